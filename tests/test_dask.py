"""Tiled detection on a local Dask cluster: the same detections as in one process and
as the untiled run, a worker killed mid-run, failures named, a scheduler that is not
there.

The floor: three small rooms side by side (``synth.building``), 8.1 m long, cut by
4 m tiles into three tiles whose windows (core + 2.5 m) each hold one to three rooms;
the border at x = 4 m runs through the middle room's table.
"""

from __future__ import annotations

import contextlib
import json
import os
import threading
import time

import numpy as np
import pytest

from ontodetect import InvalidParameterError, detect_tiled, read_cloud, write_cloud
from ontodetect._executor import DaskExecutor, UnitsFailedError, open_executor
from ontodetect.config import Config
from ontodetect.pipeline import detect
from ontodetect.synth.building import building_floor

pytestmark = pytest.mark.slow

#: One pass per tile: the vote's three passes would triple the time and test nothing more.
CONFIG = Config().replace(detect={"votes": 1})
TILE = 4.0
#: Tiled and untiled runs segment different neighbourhoods (and the tiled one uses the
#: floor found on the whole floor's subsample, not each window's own): an object may
#: gain or lose a few boundary points. The same object: same label, point IoU at least
#: this, box centres this close (m).
SAME_OBJECT_IOU = 0.9
SAME_CENTRE = 0.05


@pytest.fixture(scope="module")
def floor_file(tmp_path_factory):
    cloud = building_floor(["tiny"] * 3, points_per_room=20_000, seed=1)
    return write_cloud(tmp_path_factory.mktemp("floor") / "floor.ply", cloud)


@pytest.fixture(scope="module")
def in_process(floor_file):
    """The tiled run in this process."""
    return detect_tiled(floor_file, tile=TILE, config=CONFIG)


@pytest.fixture(scope="module")
def cluster():
    with open_executor(workers=2) as executor:
        yield executor


def _doc(result) -> dict:
    """The result without what depends on where and when it ran."""
    doc = result.to_dict()
    doc.pop("timings")
    doc["tiling"].pop("workers")
    for t in doc["tiling"]["tiles"]:
        for key in ("seconds", "peak_rss", "worker"):
            t.pop(key)
    return doc


def _iou(a, b) -> float:
    return len(np.intersect1d(a, b)) / len(np.union1d(a, b))


def test_a_cluster_finds_what_one_process_and_the_untiled_run_find(floor_file, in_process, cluster):
    here = in_process
    there = detect_tiled(floor_file, tile=TILE, config=CONFIG, executor=cluster)
    assert cluster.workers == 2 and there.workers == 2
    assert [t.name for t in there.tiles] == ["tile_0_0", "tile_0_1", "tile_0_2"]
    assert len({t.worker for t in there.tiles}) == 2  # both workers took tiles
    assert _doc(there) == _doc(here)  # exactly the same, wherever the tiles ran

    whole = detect(read_cloud(floor_file), config=CONFIG, jobs=1)
    assert len(whole.detections) == len(there.detections) >= 5
    unmatched = list(there.detections)
    for d in whole.detections:
        match = next(
            e
            for e in unmatched
            if e.label == d.label and _iou(d.point_indices, e.point_indices) >= SAME_OBJECT_IOU
        )
        assert np.linalg.norm(match.center - d.center) < SAME_CENTRE
        unmatched.remove(match)
    assert not unmatched
    # An object on a border: the table of the middle room straddles x = 4 m.
    assert any(
        d.label == "table" and d.center[0] - d.size[0] / 2 < TILE < d.center[0] + d.size[0] / 2
        for d in there.detections
    )


def _kill_a_busy_worker(client, done: threading.Event, killed: list) -> None:
    """Once a worker is running a tile, end its process (as a crash or an OOM kill would)."""
    while not done.is_set():
        busy = [w for w, keys in client.processing().items() if keys]
        if busy:
            with contextlib.suppress(Exception):  # the worker dies before it answers
                client.run(os._exit, 1, workers=busy[:1], wait=False)
            killed.append(busy[0])
            return
        time.sleep(0.05)


def test_a_worker_killed_mid_run_costs_no_tile(floor_file, in_process):
    with open_executor(workers=2) as cluster:
        done, killed = threading.Event(), []
        killer = threading.Thread(target=_kill_a_busy_worker, args=(cluster.client, done, killed))
        killer.start()
        try:
            result = detect_tiled(floor_file, tile=TILE, config=CONFIG, executor=cluster)
        finally:
            done.set()
            killer.join()
    assert killed, "no worker was busy to be killed"
    assert [t.name for t in result.tiles] == ["tile_0_0", "tile_0_1", "tile_0_2"]
    assert _doc(result) == _doc(in_process)


def _flaky(x: int) -> int:
    if x == 2:
        raise RuntimeError("disk full")
    return x + 1


def test_a_unit_that_keeps_failing_is_named_after_its_retries(cluster):
    with pytest.raises(UnitsFailedError, match=r"1 units failed: scan_c: RuntimeError: disk full"):
        cluster.map(_flaky, [0, 1, 2], names=["scan_a", "scan_b", "scan_c"], retries=2)
    assert cluster.map(_flaky, [0, 1], names=["a", "b"]) == [1, 2]


def test_eval_over_the_cluster_gives_the_in_process_evaluation(tmp_path, cluster):
    from ontodetect.evaluation import evaluate_dataset
    from ontodetect.synth import synthesize_many

    synthesize_many(2, "tiny", "rgbd", 3, out_dir=tmp_path / "set", points=8000)
    opts = {"config": CONFIG}
    one = evaluate_dataset(tmp_path / "set", detect_options=opts).to_dict()
    two = evaluate_dataset(tmp_path / "set", detect_options=opts, executor=cluster).to_dict()
    assert two["jobs"] == 2
    one, two = _untimed(one), _untimed(two)
    # json: NaN (AP of a class without ground truth) compares equal to itself there
    assert json.dumps(one, sort_keys=True) == json.dumps(two, sort_keys=True)


def _untimed(doc):
    """``doc`` without times and the worker count, at any depth."""
    if isinstance(doc, dict):
        return {k: _untimed(v) for k, v in doc.items() if k not in _TIMED}
    if isinstance(doc, list):
        return [_untimed(v) for v in doc]
    return doc


_TIMED = {"seconds", "load_seconds", "timings", "scene_seconds", "jobs"}


def test_a_scheduler_that_does_not_answer_is_named():
    with pytest.raises(InvalidParameterError, match=r"'scheduler' parameter must be the address"):
        open_executor("tcp://127.0.0.1:9", timeout=1.0)


def test_the_executor_is_a_dask_client(cluster):
    assert isinstance(cluster, DaskExecutor) and cluster.address.startswith("tcp://")
