"""End to end: simulate a scene, run ``ontodetect detect`` in-process, check every output."""

import json

import numpy as np
import pytest

from ontodetect.cli import main
from ontodetect.io import read_cloud
from ontodetect.synth import synthesize, write_synth


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    out = tmp_path_factory.mktemp("scene")
    write_synth(synthesize("dining_room", "rgbd", seed=5, points=60_000), out)
    return out


def test_detect_writes_the_contract(scene, tmp_path, capsys):
    out = tmp_path / "result"
    assert main(["detect", str(scene / "cloud.ply"), "-o", str(out), "--room", "dining_room"]) == 0
    doc = json.loads((out / "detections.json").read_text())
    cloud = read_cloud(scene / "cloud.ply")
    assert doc["format"] == "ontodetect.detections/1"
    assert doc["source"].endswith("cloud.ply")
    assert doc["num_points"] == len(cloud)
    assert doc["frame"]["up"] == pytest.approx([0, 0, 1], abs=1e-6)
    # A simulated RGB-D walk fused on a grid: millimetres of scatter, not a centimetre.
    assert 0.001 < doc["frame"]["floor_scatter"] < 0.0087
    assert doc["detections"], "a dining room has chairs and a table"
    ids = [d["id"] for d in doc["detections"]]
    assert ids == list(range(1, len(ids) + 1))
    scores = [d["score"] for d in doc["detections"]]
    assert scores == sorted(scores, reverse=True)
    claimed = np.zeros(len(cloud), dtype=int)
    truth = cloud.fields["class_id"]
    for d in doc["detections"]:
        assert d["label"] in {"chair", "sofa", "table"}
        assert set(d["probabilities"]) >= {"chair", "sofa", "table"}
        assert d["score"] == pytest.approx(d["probabilities"][d["label"]], abs=1e-3)
        assert min(d["costs"], key=d["costs"].get) == d["label"] or d["costs"][d["label"]] <= 1
        box = d["box"]
        assert len(box["center"]) == 3 and len(box["size"]) == 3 and isinstance(box["yaw"], float)
        pts = np.asarray(d["point_indices"])
        assert pts.size and pts.min() >= 0 and pts.max() < len(cloud)
        claimed[pts] += 1
        # the box holds its points (upright box, yaw about z)
        c, s = np.cos(box["yaw"]), np.sin(box["yaw"])
        rel = cloud.xyz[pts] - box["center"]
        local = np.c_[c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1], rel[:, 2]]
        assert np.all(np.abs(local) <= np.asarray(box["size"]) / 2 + 0.05)
        for part in d["parts"]:
            assert {"name", "normal", "centroid", "extent", "height", "num_points"} <= set(part)
    assert claimed.max() <= 1, "two detections never claim the same point"
    chairs = [d for d in doc["detections"] if d["label"] == "chair"]
    assert chairs, "at least one chair found"
    best = max(chairs, key=lambda d: d["score"])
    assert np.mean(truth[best["point_indices"]] == 5) > 0.5
    labelled = read_cloud(out / "labelled.ply")
    assert len(labelled) == len(cloud)
    assert set(np.unique(labelled.fields["scalar_instance"])) <= {0, *ids}
    # the input's own ground-truth `instance` field is kept as it was
    assert np.array_equal(labelled.fields["instance"], cloud.fields["instance"])
    assert (out / "boxes.txt").read_text().count("\n") == len(ids) + 1
    assert (out / "detections.png").read_bytes()[:4] == b"\x89PNG"
    printed = capsys.readouterr().out
    assert "chair" in printed


def test_detect_explain_prints_constraints(scene, tmp_path, capsys):
    code = main(
        ["detect", str(scene / "cloud.ply"), "-o", str(tmp_path), "--explain", "--no-picture"]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "P_obj|ont" in text and "cost U" in text and "seat" in text
    # The vote: what each pass made of a detection's points.
    assert "first pass: chair" in text and "pass turned +0.7°: " in text
    assert "pass turned -0.7°: " in text and "point IoU" in text
    assert not (tmp_path / "detections.png").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--room", "spaceship"], "'room'"),
        (["--set", "cluster.radius=-1"], "cluster.radius"),
        (["--threshold", "2"], "'detect.threshold'"),
        (["--votes", "0"], "'detect.votes'"),
        (["--viewpoint", "1,2"], "'--viewpoint'"),
        (["--viewpoint", "1,up,2"], "'--viewpoint'"),
        (["--labelled-format", "obj"], "'labelled_format'"),
        (["--export", "boxes,kitti"], "'exports'"),
        (["--explain", "chair,chiar"], "'--explain'"),
        (["--explain", "--min-points", "-3"], "'--min-points'"),
    ],
)
def test_detect_bad_parameters_exit_2_with_one_line(scene, tmp_path, capsys, args, message):
    code = main(["detect", str(scene / "cloud.ply"), "-o", str(tmp_path / "o"), *args])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert message in err and err.startswith("error:")
    assert "Traceback" not in err
    assert not (tmp_path / "o").exists()  # refused before any work


def test_detect_missing_input(tmp_path, capsys):
    assert main(["detect", str(tmp_path / "nope.ply"), "-o", str(tmp_path / "o")]) == 2
    assert "nope.ply: no such file" in capsys.readouterr().err


def test_detect_with_cad_adds_poses_and_the_object_map(scene, tmp_path, capsys):
    out = tmp_path / "cad"
    assert main(["detect", str(scene / "cloud.ply"), "-o", str(out), "--cad", "--no-picture"]) == 0
    # The last line names every file written, each with its folder.
    wrote = " ".join(capsys.readouterr().out.split()).split("wrote ")[-1]
    object_map = ("object_map.ply", "object_map.glb", "object_map_mesh.ply")
    assert wrote.split(", ") == [
        str(out / name) for name in ("detections.json", "labelled.ply", "boxes.txt", *object_map)
    ]
    assert all((out / name).is_file() for name in object_map)
    doc = json.loads((out / "detections.json").read_text())
    assert doc["detections"]
    for d in doc["detections"]:
        pose = np.asarray(d["cad"]["pose"])
        assert pose.shape == (4, 4)
        # upright: the model's z axis stays the world's z axis
        assert np.allclose(pose[:3, 2], [0, 0, 1], atol=1e-6)
        assert d["cad"]["rms"] >= 0
    assert (out / "object_map.ply").exists() and (out / "object_map.glb").exists()


def test_detect_writes_laz_and_scannet_exports(scene, tmp_path):
    laspy = pytest.importorskip("laspy")
    out = tmp_path / "laz"
    args = ["-q", "detect", str(scene / "cloud.ply"), "-o", str(out), "--no-picture"]
    assert main([*args, "--labelled-format", "laz", "--export", "boxes,scannet"]) == 0
    doc = json.loads((out / "detections.json").read_text())
    las = laspy.read(out / "labelled.laz")
    codes = set(np.unique(np.asarray(las.classification)).tolist())
    assert codes <= {1, *range(64, 64 + len(doc["classes"]))} and max(codes) >= 64
    summary = (out / "scannet" / "cloud.txt").read_text().splitlines()
    assert len(summary) == len(doc["detections"])
    assert not (out / "labelled.ply").exists()


def test_detect_json_on_stdout_and_no_wrapping_in_a_pipe(scene, tmp_path):
    import subprocess
    import sys

    out = tmp_path / ("a-very-long-folder-name-" * 5) / "result"
    base = [sys.executable, "-m", "ontodetect", "detect", str(scene / "cloud.ply"), "-o", str(out)]
    proc = subprocess.run(
        [*base, "--json", "--no-picture", "--votes", "1"],
        capture_output=True,
        text=True,
        check=True,
    )
    doc = json.loads(proc.stdout)
    assert doc["format"] == "ontodetect.detections/1" and doc["detections"]
    assert str(out / "labelled.ply") in doc["files"] and str(out / "boxes.txt") in doc["files"]
    proc = subprocess.run(
        [*base, "--no-picture", "--votes", "1", "-v"], capture_output=True, text=True, check=True
    )
    wrote = [line for line in proc.stdout.splitlines() if line.startswith("wrote ")]
    assert len(wrote) == 1 and str(out / "detections.json") in wrote[0], proc.stdout
    assert "\x1b[" not in proc.stdout


def test_explain_filtered_by_class_and_size_and_as_json(scene, tmp_path, capsys):
    args = ["detect", str(scene / "cloud.ply"), "-o", str(tmp_path), "--no-picture"]
    assert main([*args, "--votes", "1", "--json", "--explain", "--min-points", "0"]) == 0
    every = json.loads(capsys.readouterr().out)["explain"]
    assert main([*args, "--votes", "1", "--json", "--explain", "chair", "--min-points", "50"]) == 0
    doc = json.loads(capsys.readouterr().out)
    chairs = doc["explain"]
    assert chairs and len(chairs) < len(every)
    for row in chairs:
        assert row["num_points"] >= 50
        best = next(c["class"] for c in row["classes"] if c["class"] != "none")
        assert row["label"] == "chair" or best == "chair"
    kept = {row["cluster"] for row in chairs}
    assert {d["cluster"] for d in doc["detections"] if d["label"] == "chair"} <= kept
    # printed, the filter keeps the tables short
    assert main([*args, "--votes", "1", "--explain", "chair,table", "-q"]) == 0
    text = capsys.readouterr().out
    assert "constraints of chair" in text and "constraints of sofa" not in text
    # A class named is shown on every cluster kept, however unlikely there: why a chair
    # is not a WC.
    assert main([*args, "--votes", "1", "--json", "--explain", "chair,toilet"]) == 0
    rows = json.loads(capsys.readouterr().out)["explain"]
    assert rows
    for row in rows:
        toilet = [c for c in row["classes"] if c["class"] == "toilet"]
        assert len(toilet) == 1 and toilet[0]["named"] and toilet[0]["constraints"]
        assert not any(
            c.get("named") for c in row["classes"] if c["class"] not in {"chair", "toilet"}
        )
    assert main([*args, "--votes", "1", "--explain", "chair,toilet", "-q"]) == 0
    text = capsys.readouterr().out
    assert text.count("constraints of toilet") == len(rows)


def test_detect_many_scans_from_a_folder_a_glob_and_paths(scene, tmp_path, capsys):
    import shutil

    scans = tmp_path / "scans"
    scans.mkdir()
    for name in ("a", "b"):
        shutil.copy(scene / "cloud.ply", scans / f"{name}.ply")
    (scans / "notes.txt.md").write_text("not a scan")
    opts = ["--no-picture", "--votes", "1", "--json", "-q"]
    assert main(["detect", str(scans), "-o", str(tmp_path / "o1"), "--jobs", "2", *opts]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["input"] for r in rows] == [str(scans / "a.ply"), str(scans / "b.ply")]
    assert rows[0]["objects"] == rows[1]["objects"] > 0
    one = json.loads((tmp_path / "o1" / "a" / "detections.json").read_text())
    two = json.loads((tmp_path / "o1" / "b" / "detections.json").read_text())
    assert [d["point_indices"] for d in one["detections"]] == [
        d["point_indices"] for d in two["detections"]
    ]
    pattern = str(scans / "*.ply")
    assert main(["detect", pattern, str(scans / "a.ply"), "-o", str(tmp_path / "o2"), *opts]) == 0
    assert len(json.loads(capsys.readouterr().out)) == 2  # a.ply once
    assert main(["detect", str(scans / "*.pcd"), "-o", str(tmp_path / "o3"), *opts]) == 2
    assert "no readable scan matches" in capsys.readouterr().err


def test_a_batch_with_a_scan_that_fails_exits_2_and_keeps_the_others(scene, tmp_path, capsys):
    import shutil

    scans = tmp_path / "scans"
    scans.mkdir()
    shutil.copy(scene / "cloud.ply", scans / "good.ply")
    (scans / "empty.ply").write_bytes(b"")
    out = tmp_path / "out"
    opts = ["--no-picture", "--votes", "1", "--json", "-q"]
    assert (
        main(["detect", str(scans / "empty.ply"), str(scans / "good.ply"), "-o", str(out), *opts])
        == 2
    )
    rows = {r["input"]: r for r in json.loads(capsys.readouterr().out)}
    assert "error" in rows[str(scans / "empty.ply")]
    assert rows[str(scans / "good.ply")]["objects"] > 0
    assert (out / "good" / "detections.json").is_file()
    assert not (out / "empty").exists()
