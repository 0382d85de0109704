"""End to end: ``ontodetect env train``, ``env predict`` and ``detect --scene-image`` on
generated photographs and a generated scan, and their one-line errors."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from _images import TEXTURES, write_training_folder
from ontodetect.cli import main
from ontodetect.environment import combine_room_priors
from ontodetect.ontology import room_distribution
from ontodetect.ontology._environment import room_table
from ontodetect.synth import synthesize, write_synth


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """A model trained by the CLI on 4 generated images per category, and a scene folder
    of 2 new kitchen photographs."""
    root = tmp_path_factory.mktemp("env")
    images = write_training_folder(root / "images", per_category=4, seed=1)
    model = root / "rooms.npz"
    assert main(["-q", "env", "train", str(images), "-o", str(model)]) == 0
    scene = write_training_folder(root / "scene", per_category=2, seed=42, categories=["kitchen"])
    return images, model, scene / "kitchen"


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    out = tmp_path_factory.mktemp("scan")
    write_synth(synthesize("dining_room", "rgbd", seed=5, points=8_000), out)
    return out / "cloud.ply"


def test_train_prints_images_per_category_and_accuracy(tmp_path, capsys):
    images = write_training_folder(tmp_path / "images", per_category=4, seed=3)
    model = tmp_path / "m.npz"
    assert main(["env", "train", str(images), "-o", str(model)]) == 0
    out = capsys.readouterr().out
    for name in TEXTURES:
        assert name in out
    assert "cross-validated accuracy" in out and "2-fold" in out
    assert f"wrote {model}" in out
    with np.load(model, allow_pickle=False) as archive:
        assert json.loads(str(archive["header"]))["classes"] == sorted(TEXTURES)


def test_train_json_says_why_accuracy_is_missing(tmp_path, capsys):
    images = write_training_folder(tmp_path / "images", per_category=2, seed=3)
    assert main(["env", "train", str(images), "-o", str(tmp_path / "m.npz"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["images"] == {name: 2 for name in sorted(TEXTURES)}
    assert summary["cv_accuracy"] is None and "not estimated" in summary["cv_note"]


def test_predict_prints_p_n_sorted_like_tables_4_11_to_4_13(trained, capsys):
    _, model, scene = trained
    assert main(["env", "predict", str(scene), "--model", str(model)]) == 0
    out = capsys.readouterr().out
    assert "P_N from 2 images" in out
    rows = re.findall(r"([a-z_]+)\W+([0-9.]+)%", out)
    assert rows[0][0] == "kitchen" and len(rows) == len(TEXTURES)
    values = [float(v) for _, v in rows]
    assert values == sorted(values, reverse=True) and sum(values) == pytest.approx(100, abs=0.2)


def test_predict_json(trained, capsys):
    _, model, scene = trained
    assert main(["env", "predict", str(scene), "--model", str(model), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["images"]) == 2
    rooms = doc["rooms"]
    assert next(iter(rooms)) == "kitchen" and rooms["kitchen"] > 0.5
    assert sum(rooms.values()) == pytest.approx(1.0)


def test_detect_takes_the_room_prior_from_photographs(trained, scan, tmp_path, capsys):
    _, model, scene = trained
    out = tmp_path / "out"
    args = ["-q", "detect", str(scan), "-o", str(out), "--votes", "1", "--no-picture"]
    images = ["--scene-image", str(scene), "--env-model", str(model)]
    assert main([*args, *images, "--room", "none"]) == 0
    assert main(["env", "predict", str(scene), "--model", str(model), "--json"]) == 0
    rooms = json.loads(capsys.readouterr().out)["rooms"]
    seating = room_table("seating")
    expected = sum(p * seating[c] for c, p in room_distribution(rooms).items())
    doc = json.loads((out / "detections.json").read_text())
    assert doc["priors"]["chair"] == pytest.approx(expected, abs=1e-4)
    # the same as handing the distribution over with --room-probs
    probs = tmp_path / "rooms.json"
    probs.write_text(json.dumps(rooms))
    assert main([*args[:4], str(tmp_path / "o2"), *args[5:], "--room-probs", str(probs)]) == 0
    again = json.loads((tmp_path / "o2" / "detections.json").read_text())
    assert again["priors"] == doc["priors"]
    assert doc["environment"]["source"] == "images"
    # by default the photographs' P_N meets the scan's own estimate
    assert main([*args[:4], str(tmp_path / "o3"), *args[5:], *images]) == 0
    both = json.loads((tmp_path / "o3" / "detections.json").read_text())["environment"]
    assert both["source"] == "scan+images"
    assert main([*args[:4], str(tmp_path / "o4"), *args[5:]]) == 0
    scan_only = json.loads((tmp_path / "o4" / "detections.json").read_text())["environment"]
    assert scan_only["source"] == "scan"
    expected = combine_room_priors(scan_only["rooms"], room_distribution(rooms))
    assert both["rooms"] == pytest.approx({k: expected[k] for k in both["rooms"]}, abs=2e-3)


def _garbage_image(folder):
    folder.mkdir(parents=True, exist_ok=True)
    bad = folder / "photo.jpg"
    bad.write_bytes(b"\x00\x01garbage, not an image\xff" * 20)
    return bad


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("train-empty", "holds no sub-folder"),
        ("train-one-category", "one category only (office)"),
        ("train-unknown", "spaceship: not a room category or alias"),
        ("train-corrupt", "photo.jpg: not a readable image"),
        ("predict-corrupt", "photo.jpg: not a readable image"),
        ("predict-empty", "holds no image"),
        ("predict-bad-model", "bad.npz: not a readable .npz archive"),
        ("predict-missing-model", "no such model file"),
    ],
)
def test_env_errors_are_one_line_and_exit_2(trained, tmp_path, capsys, case, message):
    _, model, scene = trained
    if case.startswith("train"):
        images = tmp_path / "images"
        images.mkdir()
        if case == "train-one-category":
            write_training_folder(images, per_category=2, categories=["office"])
        elif case == "train-unknown":
            write_training_folder(images, per_category=2, categories=["office", "spaceship"])
        elif case == "train-corrupt":
            write_training_folder(images, per_category=2, categories=["office", "kitchen"])
            _garbage_image(images / "kitchen")
        argv = ["env", "train", str(images), "-o", str(tmp_path / "m.npz")]
    else:
        target, use = scene, model
        if case == "predict-corrupt":
            target = _garbage_image(tmp_path / "scene")
        elif case == "predict-empty":
            target = tmp_path / "empty"
            target.mkdir()
        elif case == "predict-bad-model":
            use = tmp_path / "bad.npz"
            use.write_bytes(b"this is not a model" * 10)
        elif case == "predict-missing-model":
            use = tmp_path / "missing.npz"
        argv = ["env", "predict", str(target), "--model", str(use)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and message in err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "m.npz").exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--scene-image", "X"], "'--scene-image' parameter must be given with --env-model"),
        (["--env-model", "M"], "'--env-model' parameter must be given with --scene-image"),
        (
            ["--scene-image", "X", "--env-model", "M", "--room", "office"],
            "not combined with --room",
        ),
    ],
)
def test_detect_scene_image_options_go_together(trained, scan, tmp_path, capsys, extra, message):
    _, model, scene = trained
    extra = [str(scene) if a == "X" else str(model) if a == "M" else a for a in extra]
    assert main(["detect", str(scan), "-o", str(tmp_path / "o"), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and message in err
    assert not (tmp_path / "o").exists()


def test_detect_with_a_corrupt_scene_image_exits_2(trained, scan, tmp_path, capsys):
    _, model, _ = trained
    bad = _garbage_image(tmp_path / "scene")
    argv = ["detect", str(scan), "-o", str(tmp_path / "o")]
    assert main([*argv, "--scene-image", str(bad), "--env-model", str(model)]) == 2
    assert "photo.jpg: not a readable image" in capsys.readouterr().err
