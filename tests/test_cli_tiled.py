"""``ontodetect detect --tile``: one large scan tile by tile, in this process; the
cluster options' errors (the cluster runs themselves are in test_dask.py)."""

import json

import pytest

from ontodetect.cli import main
from ontodetect.io import write_cloud
from ontodetect.synth.building import building_floor


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    cloud = building_floor(["tiny"] * 2, points_per_room=15_000, seed=1)
    return write_cloud(tmp_path_factory.mktemp("floor") / "floor.laz", cloud)


def test_detect_by_tiles_writes_the_contract_and_the_tiles(floor, tmp_path, capsys):
    out = tmp_path / "out"
    args = ["detect", str(floor), "-o", str(out), "--tile", "3", "--set", "detect.votes=1"]
    assert main([*args, "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    doc = json.loads((out / "detections.json").read_text())
    assert doc["num_points"] == 30_000 and doc["source"].endswith("floor.laz")
    assert [t["name"] for t in doc["tiling"]["tiles"]] == ["tile_0_0", "tile_0_1"]
    assert doc["tiling"]["overlap"] == 2.5 and doc["tiling"]["workers"] == 1
    assert sorted({d["label"] for d in doc["detections"]}) == ["chair", "table"]
    assert all(d["tile"] in ("tile_0_0", "tile_0_1") for d in doc["detections"])
    assert [d["id"] for d in doc["detections"]] == list(range(1, len(doc["detections"]) + 1))
    assert (out / "boxes.txt").exists() and printed["files"][0].endswith("detections.json")
    # What differs from run to run is in timings.json, not in the contract.
    assert not {"seconds", "peak_rss", "worker"} & set(doc["tiling"]["tiles"][0])
    runs = json.loads((out / "timings.json").read_text())["tile_runs"]
    assert [t["name"] for t in runs] == ["tile_0_0", "tile_0_1"] and runs[0]["peak_rss"] > 0
    again = tmp_path / "again"
    assert main([*args[:3], str(again), *args[4:], "-q"]) == 0
    assert (again / "detections.json").read_bytes() == (out / "detections.json").read_bytes()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--tile", "3", "--scheduler", "localhost:8786"], "'--scheduler' parameter must be"),
        (["--tile", "3", "--overlap", "1"], "'overlap' parameter must be at least 2.5"),
        (["--overlap", "3"], "--overlap"),
        (["--tile", "3", "--workers", "2", "--scheduler", "tcp://h:1"], "'--workers'"),
    ],
)
def test_bad_tiling_and_cluster_options_end_in_one_line(floor, tmp_path, capsys, extra, message):
    assert main(["detect", str(floor), "-o", str(tmp_path / "o"), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
