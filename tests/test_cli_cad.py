"""``ontodetect cad fit`` and ``ontodetect cad models`` run in-process."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import trimesh
import yaml

from ontodetect import point_cloud, read_cloud, write_cloud
from ontodetect.cad import builtin_library
from ontodetect.cad._models import sample_surface, visible_shell
from ontodetect.cli import main
from ontodetect.geometry._mesh import Mesh
from ontodetect.io._detections import read_detections, write_detections
from ontodetect.synth.furniture import make_furniture, place


@pytest.fixture
def stored(tmp_path):
    """A scan in millimetres (floor at z = -500 mm) with a chair and a table, and a
    detections.json for it written by hand."""
    rng = np.random.default_rng(5)
    floor = np.c_[rng.random((3000, 2)) * 4.0, np.zeros(3000)]
    parts, boxes = [floor], []
    for kind, x, y, yaw in (("chair-4leg", 1.0, 1.0, 0.5), ("table-dining", 2.6, 2.0, 1.2)):
        obj = place(make_furniture(kind, 3), x, y, yaw)
        pts = sample_surface(visible_shell(Mesh(obj.vertices, obj.triangles)), 0.015, rng=1)
        parts.append(pts)
        b = obj.box
        boxes.append((b.center, b.size, b.yaw))
    xyz = np.vstack(parts)
    rows = np.cumsum([0] + [len(p) for p in parts])
    colors = np.full((len(xyz), 3), 90, np.uint8)
    colors[rows[1] : rows[2]] = (150, 60, 30)
    scan = tmp_path / "scan.ply"
    write_cloud(scan, point_cloud(xyz * 1000.0 - [0, 0, 500], colors))
    dets = []
    for k, (label, score) in enumerate((("chair", 0.7), ("table", 0.1))):
        center, size, yaw = boxes[k]
        dets.append(
            {
                "id": k + 1,
                "label": label,
                "score": score,
                "box": {
                    "center": [float(c * 1000) for c in center[:2]]
                    + [float(center[2] * 1000 - 500)],
                    "size": [float(s * 1000) for s in size],
                    "yaw": float(yaw),
                },
                "point_indices": list(range(rows[k + 1], rows[k + 2])),
                "parts": [],
            }
        )
    doc = {
        "format": "ontodetect.detections/1",
        "source": "scan.ply",
        "num_points": len(xyz),
        "frame": {"up": [0, 0, 1], "ground_z": -500.0, "scale": 0.001},
        "detections": dets,
    }
    det_dir = tmp_path / "det"
    det_dir.mkdir()
    write_detections(det_dir / "detections.json", doc)
    return scan, det_dir


def test_cad_fit_writes_detections_and_object_map(stored, tmp_path, capsys):
    scan, det_dir = stored
    out = tmp_path / "out"
    code = main(["cad", "fit", str(det_dir), str(scan), "-o", str(out), "--spacing", "0.03"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "chair-4leg" in captured.out or "chair" in captured.out
    doc = read_detections(out / "detections.json")
    chair, table = doc["detections"]
    assert chair["cad"]["blank"] is False and chair["cad"]["model"].startswith("chair")
    # The pose is in the input's frame and units: the chair stands on the floor at z = -500 mm,
    # at (1000, 1000) mm, facing yaw 0.5.
    pose = np.asarray(chair["cad"]["pose"])
    assert pose[2, 3] == pytest.approx(-500.0, abs=1e-6)
    assert math.hypot(pose[0, 3] - 1000.0, pose[1, 3] - 1000.0) < 40.0
    assert math.atan2(pose[1, 0], pose[0, 0]) == pytest.approx(0.5, abs=math.radians(5))
    assert chair["cad"]["color"] == [150, 60, 30]
    # The table scored below --min-score: its detection box stands in.
    assert table["cad"]["model"] == "box" and table["cad"]["blank"] is True
    assert "below min_score" in table["cad"]["reason"]
    assert read_cloud(out / "object_map.ply").fields["object"].max() == 2
    assert len(trimesh.load(out / "object_map.glb").geometry) == 2
    assert (out / "object_map_mesh.ply").is_file()


def test_cad_fit_into_the_detections_folder_keeps_its_files(stored, tmp_path, capsys):
    import shutil

    from ontodetect.io._atomic import staged_folder

    scan, det_dir = stored
    out = tmp_path / "run"
    with staged_folder(out) as stage:  # a detect run's folder: its files and their marker
        shutil.copy(det_dir / "detections.json", stage / "detections.json")
        (stage / "labelled.ply").write_text("the detect run's cloud")
    code = main(["cad", "fit", str(out), str(scan), "-o", str(out), "--spacing", "0.05"])
    assert code == 0, capsys.readouterr().err
    assert (out / "labelled.ply").read_text() == "the detect run's cloud"
    assert "cad" in read_detections(out / "detections.json")["detections"][0]
    assert (out / "object_map.ply").is_file()


def test_cad_fit_options(stored, tmp_path, capsys):
    scan, det_dir = stored
    out = tmp_path / "out"
    code = main(
        [
            "-q",
            "cad",
            "fit",
            str(det_dir / "detections.json"),
            str(scan),
            "-o",
            str(out),
            "--min-score",
            "0",
            "--no-scale",
            "--no-glb",
            "--kernel",
            "cauchy",
        ]
    )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert captured.out == ""
    doc = json.loads((out / "detections.json").read_text())
    assert all(d["cad"]["scale"] == [1.0, 1.0, 1.0] for d in doc["detections"])
    assert doc["detections"][1]["cad"]["model"].startswith("table")
    assert not (out / "object_map.glb").exists()


def test_cad_fit_with_user_models(stored, tmp_path, capsys):
    scan, det_dir = stored
    chair = builtin_library()["chair-4leg"]
    trimesh.Trimesh(chair.full.vertices * 100.0, chair.full.triangles).export(tmp_path / "mine.obj")
    manifest = tmp_path / "models.yaml"
    manifest.write_text(
        yaml.safe_dump(
            {
                "models": [
                    {
                        "name": "my-chair",
                        "label": "chair",
                        "full": "mine.obj",
                        "units": "cm",
                        "seat_height": 0.46,
                    }
                ]
            }
        )
    )
    code = main(
        [
            "cad",
            "fit",
            str(det_dir),
            str(scan),
            "-o",
            str(tmp_path / "out"),
            "--models",
            str(manifest),
            "--models-only",
        ]
    )
    assert code == 0, capsys.readouterr().err
    doc = read_detections(tmp_path / "out")
    assert doc["detections"][0]["cad"]["model"] == "my-chair"
    assert "no model for label 'table'" not in json.dumps(doc)  # the table is blank by score


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["cad", "fit", "{tmp}/none", "{scan}", "-o", "{tmp}/o"], "no such file"),
        (["cad", "fit", "{det}", "{tmp}/none.ply", "-o", "{tmp}/o"], "none.ply"),
        (["cad", "fit", "{det}", "{small}", "-o", "{tmp}/o"], "'cloud' parameter"),
        (["cad", "fit", "{det}", "{scan}", "-o", "{tmp}/o", "--models-only"], "--models-only"),
        (["cad", "fit", "{det}", "{scan}", "-o", "{tmp}/o", "--kernel", "x"], "'kernel'"),
        (["cad", "fit", "{det}", "{scan}", "-o", "{tmp}/o", "--min-score", "3"], "'min_score'"),
        (["cad", "models", "--models", "{tmp}/none.yaml"], "none.yaml: no such file"),
    ],
)
def test_cad_errors_are_one_line(stored, tmp_path, capsys, args, message):
    scan, det_dir = stored
    small = tmp_path / "small.ply"
    write_cloud(small, point_cloud(np.zeros((10, 3))))
    argv = [a.format(tmp=tmp_path, scan=scan, det=det_dir, small=small) for a in args]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("error:") and message in err
    assert "Traceback" not in err


def test_cad_models_lists_and_draws(tmp_path, capsys):
    png = tmp_path / "models.png"
    code = main(["cad", "models", "--picture", str(png)])
    out = capsys.readouterr().out
    assert code == 0
    for name in builtin_library():
        assert name in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cad_without_subcommand_shows_help(capsys):
    code = main(["cad"])
    captured = capsys.readouterr()
    assert code in (0, 2)
    assert "fit" in captured.out + captured.err
