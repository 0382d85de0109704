"""Edge cases of reading and writing: scans too small to detect in, PLY in map
coordinates, organized frames whose index was rebuilt, and timings.json."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ontodetect import ReadError, point_cloud, read_cloud, write_cloud
from ontodetect.cli import main
from ontodetect.io import MIN_SCAN_POINTS, read_points, write_timings
from ontodetect.io._pcd import read_pcd, write_pcd
from ontodetect.io._ply import FLOAT32_TOLERANCE, read_ply, write_mesh_ply, write_ply
from test_reliability import one_line as _one_line


def _header(path) -> str:
    return path.read_bytes().split(b"end_header\n")[0].decode("ascii", "replace")


# ---------------------------------------------------------------------------------
# A scan with too few points to detect in
# ---------------------------------------------------------------------------------
@pytest.fixture
def tiny(tmp_path, rng):
    """A PLY file of three points: a plane, but fewer than any plane fit counts."""
    return write_cloud(tmp_path / "tiny.ply", point_cloud(rng.random((3, 3))))


def test_read_points_refuses_fewer_points_than_a_plane_fit_needs(tmp_path, tiny, rng):
    assert MIN_SCAN_POINTS == 5
    with pytest.raises(ReadError, match=r"tiny\.ply: holds only 3 points with finite coord"):
        read_points(tiny, min_points=MIN_SCAN_POINTS)
    one = write_cloud(tmp_path / "one.npy", point_cloud([[1.0, 2.0, 3.0]]))
    with pytest.raises(ReadError, match=r"one\.npy: holds only 1 point with finite coord"):
        read_points(one, min_points=MIN_SCAN_POINTS)
    # Rows with NaN coordinates do not count: 4 finite of 6.
    xyz = rng.random((6, 3))
    xyz[[1, 4], 0] = np.nan
    holes = tmp_path / "holes.npy"
    np.save(holes, xyz)
    with pytest.raises(ReadError, match="holds only 4 points"):
        read_points(holes, min_points=MIN_SCAN_POINTS, on_nonfinite="drop")
    enough = write_cloud(tmp_path / "five.ply", point_cloud(rng.random((5, 3))))
    assert len(read_points(enough, min_points=MIN_SCAN_POINTS)) == 5
    # Reading alone (info, a tile's window) still takes any non-empty cloud.
    assert len(read_points(tiny)) == len(read_cloud(tiny)) == 3


@pytest.mark.parametrize("command", [["detect"], ["segment"], ["detect", "--tile", "3"]])
def test_cli_refuses_a_tiny_scan_in_one_line(tmp_path, tiny, capsys, command):
    out = tmp_path / "out"
    status = main([command[0], str(tiny), "-o", str(out), *command[1:]])
    _one_line(capsys, status, "tiny.ply", "only 3 points", f"at least {MIN_SCAN_POINTS}")
    assert not out.exists()


def test_a_batch_names_each_tiny_scan(tmp_path, rng, capsys):
    a = write_cloud(tmp_path / "a.ply", point_cloud(rng.random((3, 3))))
    b = write_cloud(tmp_path / "b.ply", point_cloud(rng.random((4, 3))))
    status = main(["-q", "detect", str(a), str(b), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2, err
    assert "a.ply: holds only 3 points" in err and "b.ply: holds only 4 points" in err


# ---------------------------------------------------------------------------------
# Executor options given to one scan
# ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("option", "value"), [("--scheduler", "tcp://host:8786"), ("--workers", "2"), ("--jobs", "3")]
)
def test_executor_options_refused_for_one_scan(tmp_path, rng, capsys, option, value):
    scan = write_cloud(tmp_path / "scan.ply", point_cloud(rng.random((50, 3))))
    out = tmp_path / "out"
    status = main(["detect", str(scan), "-o", str(out), option, value])
    line = _one_line(capsys, status, f"'{option}'", "several scans or --tile", value)
    assert "\n" not in line
    assert not out.exists()


def test_jobs_1_is_the_default_and_accepted_for_one_scan(tiny, tmp_path, capsys):
    # The run goes on to the scan (and stops there: it is too small).
    status = main(["detect", str(tiny), "-o", str(tmp_path / "out"), "--jobs", "1"])
    _one_line(capsys, status, "tiny.ply", "only 3 points")


# ---------------------------------------------------------------------------------
# PLY in map coordinates
# ---------------------------------------------------------------------------------
@pytest.mark.parametrize("ascii", [False, True])
def test_ply_float32_keeps_utm_coordinates_within_tolerance(tmp_path, rng, ascii):
    """UTM-like coordinates: float32 steps there are 3 to 50 cm."""
    xyz = rng.random((40, 3)) * 5 + [500000.123, 5000000.456, 10.0]
    normals = rng.normal(size=(40, 3))
    cloud = point_cloud(xyz, normals=normals)
    f = write_ply(tmp_path / "utm.ply", cloud, dtype="float32", ascii=ascii)
    assert "property double x" in _header(f) and "property double nx" in _header(f)
    got = read_ply(f)
    assert np.abs(got.xyz - xyz).max() <= FLOAT32_TOLERANCE
    np.testing.assert_array_equal(got.xyz, xyz)  # in fact exactly
    np.testing.assert_array_equal(got.normals, cloud.normals)


def test_ply_float32_stays_float32_for_a_room(tmp_path, rng):
    cloud = point_cloud(rng.uniform(-4, 4, (30, 3)), normals=rng.normal(size=(30, 3)))
    f = write_ply(tmp_path / "room.ply", cloud, dtype="float32")
    head = _header(f)
    assert "property float x" in head and "property float nx" in head
    np.testing.assert_array_equal(read_ply(f).xyz, cloud.xyz.astype(np.float32))
    # Values beyond float32's range are kept too, as float64, instead of refused.
    far = write_ply(tmp_path / "far.ply", point_cloud([[1e300, 0, 0]]), dtype="float32")
    assert read_ply(far).xyz[0, 0] == 1e300


def test_mesh_float32_keeps_utm_vertices(tmp_path):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]) + [500000.123, 5000000.456, 10.0]
    f = write_mesh_ply(tmp_path / "m.ply", vertices, [[0, 1, 2]], dtype="float32")
    assert "property double x" in _header(f)
    np.testing.assert_array_equal(read_ply(f).xyz, vertices)


# ---------------------------------------------------------------------------------
# Organized frames whose index was rebuilt
# ---------------------------------------------------------------------------------
def _frame(tmp_path, rng, width=5, height=4):
    """An organized PCD frame with four pixels of no depth, read back."""
    xyz = rng.random((width * height, 3)) + [0, 0, 1]
    xyz[[0, 3, 7, 12]] = np.nan
    full = point_cloud(xyz, on_nonfinite="drop").with_meta(
        organized=True, width=width, height=height
    )
    return read_pcd(write_pcd(tmp_path / "frame.pcd", full))


def test_frame_keeps_its_pixels_through_select(tmp_path, rng):
    frame = _frame(tmp_path, rng)
    assert frame.index.tolist()[:3] == [1, 2, 4]
    kept = frame.select(np.arange(len(frame)) % 2 == 0)
    got = read_pcd(write_pcd(tmp_path / "kept.pcd", kept))
    assert got.meta["organized"] and (got.meta["width"], got.meta["height"]) == (5, 4)
    np.testing.assert_array_equal(got.index, kept.index)
    np.testing.assert_array_equal(got.xyz, kept.xyz.astype(np.float32))


def test_frame_with_a_rebuilt_index_is_not_written_to_wrong_pixels(tmp_path, rng):
    frame = _frame(tmp_path, rng)
    keep = frame.xyz[:, 0] < 0.6
    # Built again from the frame's arrays: the index starts again from 0 and no longer
    # says which pixel a point came from.
    rebuilt = point_cloud(frame.xyz[keep], meta=frame.meta)
    assert rebuilt.index.tolist() == list(range(int(keep.sum())))
    f = write_pcd(tmp_path / "rebuilt.pcd", rebuilt)
    got = read_pcd(f)
    assert not got.meta["organized"]
    assert (got.meta["width"], got.meta["height"]) == (len(rebuilt), 1)
    np.testing.assert_array_equal(got.xyz, rebuilt.xyz.astype(np.float32))
    # A rebuilt index over every pixel of the grid is still the grid.
    whole = read_pcd(write_pcd(tmp_path / "whole.pcd", point_cloud(rng.random((20, 3)))))
    full = point_cloud(whole.xyz, meta={"organized": True, "width": 5, "height": 4})
    got = read_pcd(write_pcd(tmp_path / "full.pcd", full))
    assert got.meta["organized"] and (got.meta["width"], got.meta["height"]) == (5, 4)


# ---------------------------------------------------------------------------------
# timings.json
# ---------------------------------------------------------------------------------
def test_write_timings_bytes(tmp_path):
    timings = {"voxels": 0.25, "floor": 1.5e-05, "tile_runs": [{"name": "t", "seconds": 2}]}
    f = write_timings(tmp_path / "timings.json", timings)
    assert f == tmp_path / "timings.json"
    assert f.read_bytes() == (
        b'{\n  "voxels": 0.25,\n  "floor": 1.5e-05,\n  "tile_runs": [\n    {\n'
        b'      "name": "t",\n      "seconds": 2\n    }\n  ]\n}\n'
    )
    assert write_timings(tmp_path / "empty.json", {}).read_bytes() == b"{}\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty.json", "timings.json"]


def test_segment_timings_json_layout(tmp_path, rng, capsys):
    # A 2 m floor with a box on it: enough to prepare.
    floor = np.c_[rng.random((4000, 2)) * 2, np.zeros(4000)]
    box = np.c_[rng.random((1500, 2)) * 0.4 + 0.8, np.full(1500, 0.45)]
    scan = write_cloud(tmp_path / "scan.ply", point_cloud(np.vstack([floor, box])))
    out = tmp_path / "seg"
    assert main(["-q", "segment", str(scan), "-o", str(out)]) == 0, capsys.readouterr().err
    text = (out / "timings.json").read_text(encoding="utf-8")
    assert text == json.dumps(json.loads(text), indent=2) + "\n"
