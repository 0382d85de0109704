"""Tiles on the floor plane, windowed reads, the merge across tile borders, and the
executor in this process (the Dask cluster's tests are in test_dask.py)."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from ontodetect import InvalidParameterError, point_cloud, read_cloud, write_cloud
from ontodetect._executor import InProcess, UnitsFailedError, open_executor, scheduler_address
from ontodetect.errors import ReadError
from ontodetect.io._windows import Window, iter_chunks, read_window, survey_cloud
from ontodetect.pipeline import Detection
from ontodetect.pipeline._tiled import (
    DEFAULT_OVERLAP,
    Tile,
    TileOutcome,
    floor_axes,
    merge_tiles,
    minimum_overlap,
    plan_tiles,
)

XY = Window(np.eye(3)[:2], np.array([1.0, -np.inf]), np.array([2.0, 0.5]))


@pytest.fixture
def cloud(rng):
    xyz = rng.random((5000, 3)) * [4.0, 1.0, 2.0]
    rgb = rng.integers(0, 256, (5000, 3), dtype=np.uint8)
    return point_cloud(xyz, rgb=rgb)


# -- tiles ----------------------------------------------------------------------------------
def test_every_point_of_the_plane_lies_in_exactly_one_core(rng):
    tiles = plan_tiles([0.0, 0.0], [25.0, 12.0], 10.0, 2.5)
    assert [t.name for t in tiles] == [f"tile_{r}_{c}" for r in range(2) for c in range(3)]
    uv = rng.uniform(-50, 50, (2000, 2))
    uv[:10] = [[10.0, 10.0]] * 10  # on a border: the core above and to the right takes it
    owners = np.array([t.in_core(uv) for t in tiles])
    assert (owners.sum(axis=0) == 1).all()
    assert tiles[4].in_core(uv[:1]).all()  # tile_1_1: [10, 20) x [10, inf)


def test_a_window_is_the_core_grown_by_the_overlap():
    tile = Tile("tile_0_1", (10.0, -math.inf), (20.0, math.inf), 2.5)
    w = tile.window(floor_axes([0, 0, 1]))
    inside = w.contains([[7.6, 0, 0], [7.4, 0, 0], [22.4, 5, 9], [22.6, 0, 0]])
    assert inside.tolist() == [True, False, True, False]


def test_floor_axes_are_orthonormal_and_perpendicular_to_up():
    for up in ([0, 0, 1], [0, -1, 0], [1, 2, 3]):
        axes = floor_axes(up)
        u = np.asarray(up, float) / np.linalg.norm(up)
        np.testing.assert_allclose(axes @ axes.T, np.eye(2), atol=1e-12)
        np.testing.assert_allclose(axes @ u, 0, atol=1e-12)


def test_the_overlap_holds_the_longest_object_the_ontology_allows():
    assert minimum_overlap() == pytest.approx(DEFAULT_OVERLAP)  # tables up to 4 m
    with pytest.raises(InvalidParameterError, match=r"'overlap' parameter must be at least 2\.5"):
        from ontodetect import detect_tiled

        detect_tiled(point_cloud(np.zeros((3, 3))), overlap=1.0)
    with pytest.raises(InvalidParameterError, match="'tile' parameter"):
        plan_tiles([0, 0], [1, 1], 0.0, 2.5)


# -- windowed reads -------------------------------------------------------------------------
@pytest.mark.parametrize("suffix", [".ply", ".laz", ".npz"])
def test_a_window_holds_the_files_points_in_it_with_their_rows(tmp_path, cloud, suffix):
    path = write_cloud(tmp_path / f"c{suffix}", cloud)
    whole = read_cloud(path)
    got = read_window(path, XY, chunk_points=700)
    want = np.flatnonzero(XY.contains(whole.xyz))
    assert got.index.tolist() == want.tolist()
    np.testing.assert_array_equal(got.xyz, whole.xyz[want])
    np.testing.assert_array_equal(got.rgb, whole.rgb[want])


def test_chunks_cover_the_file_in_order(tmp_path, cloud):
    path = write_cloud(tmp_path / "c.ply", cloud)
    chunks = list(iter_chunks(path, chunk_points=1200))
    assert [c.start for c in chunks] == [0, 1200, 2400, 3600, 4800]
    np.testing.assert_array_equal(np.vstack([c.xyz for c in chunks]), read_cloud(path).xyz)


def test_a_survey_bounds_counts_and_subsamples_in_one_pass(tmp_path, cloud):
    path = write_cloud(tmp_path / "c.laz", cloud)
    survey = survey_cloud(path, sample_points=1000, chunk_points=333)
    whole = read_cloud(path)
    assert survey.num_points == 5000 and survey.step == 5
    assert survey.sample.index.tolist() == list(range(0, 5000, 5))
    np.testing.assert_array_equal(survey.sample.xyz, whole.xyz[::5])
    np.testing.assert_array_equal(survey.lo, whole.xyz.min(axis=0))
    np.testing.assert_array_equal(survey.hi, whole.xyz.max(axis=0))


@pytest.mark.parametrize("suffix", [".ply", ".laz"])
def test_a_window_steps_over_the_chunks_that_miss_it(tmp_path, cloud, suffix):
    # Rows sorted along x, as a file written room by room is: chunks are narrow in x.
    path = write_cloud(tmp_path / f"c{suffix}", cloud.select(np.argsort(cloud.xyz[:, 0])))
    survey = survey_cloud(path, chunk_points=500)
    assert survey.chunk_bounds.shape == (10, 2, 3)
    misses = XY.misses(survey.chunk_bounds)
    assert 4 <= misses.sum() < 10  # x in [1, 2) is a quarter of [0, 4)
    starts = [c.start for c in iter_chunks(path, chunk_points=500, skip=lambda k: misses[k])]
    assert starts == [500 * k for k in np.flatnonzero(~misses)]
    fast = read_window(path, XY, chunk_points=500, chunk_bounds=survey.chunk_bounds)
    slow = read_window(path, XY, chunk_points=500)
    assert fast.index.tolist() == slow.index.tolist()
    np.testing.assert_array_equal(fast.xyz, slow.xyz)


def test_a_window_of_nothing_and_a_truncated_file(tmp_path, cloud):
    path = write_cloud(tmp_path / "c.ply", cloud)
    far = Window(np.eye(3)[:2], np.array([50.0, 50.0]), np.array([60.0, 60.0]))
    assert read_window(path, far) is None
    data = path.read_bytes()
    (tmp_path / "cut.ply").write_bytes(data[: len(data) - 100])
    with pytest.raises(ReadError, match=r"cut\.ply.*truncated"):
        read_window(tmp_path / "cut.ply", XY)


# -- the merge ------------------------------------------------------------------------------
def _det(label, score, rows, center=(0.0, 0.0, 0.5), size=(1.0, 1.0, 1.0)) -> Detection:
    return Detection(
        id=0,
        label=label,
        score=score,
        probabilities={label: score},
        costs={},
        center=np.asarray(center, float),
        size=np.asarray(size, float),
        yaw=0.0,
        point_indices=np.asarray(rows, dtype=np.int64),
        parts=[],
        cluster=0,
    )


def _outcome(name, *dets) -> TileOutcome:
    return TileOutcome(name, 100, len(dets), list(dets), 0.0, 0, "here")


def test_an_object_seen_by_two_tiles_is_reported_once():
    a = _outcome("tile_0_0", _det("chair", 0.8, range(0, 100)), _det("table", 0.9, range(500, 600)))
    # The same chair from the neighbour, its centre just across the border, a few
    # points more; and a chair of its own.
    b = _outcome(
        "tile_0_1",
        _det("chair", 0.7, range(0, 104), center=(0.05, 0, 0.5)),
        _det("chair", 0.6, range(200, 300), center=(3.0, 0, 0.5)),
    )
    detections, tiles, merged = merge_tiles([a, b])
    assert merged == 1
    assert [(d.id, d.label, d.score) for d in detections] == [
        (1, "table", 0.9),
        (2, "chair", 0.8),
        (3, "chair", 0.6),
    ]
    assert tiles == ["tile_0_0", "tile_0_0", "tile_0_1"]


def test_objects_sharing_few_points_or_one_tile_are_kept():
    # Two objects of one tile that share points are the tile's own choice to make.
    a = _outcome("tile_0_0", _det("chair", 0.8, range(0, 100)), _det("sofa", 0.5, range(30, 130)))
    b = _outcome("tile_0_1", _det("chair", 0.7, range(90, 250)))  # 10 and 40 of 100 shared
    detections, _, merged = merge_tiles([a, b])
    assert merged == 0 and len(detections) == 3


# -- the executor in this process -----------------------------------------------------------
def _fail_on(bad: int, x: int) -> int:
    if x == bad:
        raise ReadError(f"scan{x}.ply", "truncated")
    return x * x


def test_the_in_process_executor_maps_in_order_and_names_a_failed_unit():
    ex = open_executor()
    assert isinstance(ex, InProcess) and ex.workers == 1
    assert ex.map(abs, [-3, 1, -2]) == [3, 1, 2]
    with pytest.raises(UnitsFailedError, match=r"1 units failed: b: scan1.ply: truncated") as err:
        ex.map(functools.partial(_fail_on, 1), [0, 1, 2], names=["a", "b", "c"])
    assert err.value.failures == [("b", "scan1.ply: truncated")]


@pytest.mark.parametrize("address", ["10.0.0.5:8786", "tcp://host", "http://h:1", "tcp://h:0"])
def test_a_malformed_scheduler_address_is_refused(address):
    with pytest.raises(InvalidParameterError, match="'scheduler' parameter must be a Dask"):
        scheduler_address(address)


def test_the_scheduler_address_comes_from_the_dask_variable(monkeypatch):
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "tcp://10.1.2.3:8786")
    assert scheduler_address() == "tcp://10.1.2.3:8786"
    assert scheduler_address("tcp://other:1") == "tcp://other:1"
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "nonsense")
    with pytest.raises(InvalidParameterError, match=r"DASK_SCHEDULER_ADDRESS"):
        scheduler_address()
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS")
    assert scheduler_address() is None
