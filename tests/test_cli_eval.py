"""``ontodetect eval`` and ``ontodetect calibrate`` in-process on a generated dataset."""

from __future__ import annotations

import json

import pytest
import yaml

from ontodetect.cli import main
from ontodetect.ontology import parse_ontology


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    """Two simulated tiny rooms (a chair, a table and a stool each) in the synthetic layout."""
    from ontodetect.synth import synthesize, write_synth

    root = tmp_path_factory.mktemp("synth")
    for k, seed in enumerate((1, 2)):
        write_synth(synthesize("tiny", "rgbd", seed=seed, points=15_000), root / f"scene_{k:04d}")
    return root


def test_eval_writes_the_report_and_scores_stored_detections_alike(dataset, tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["eval", str(dataset), "-o", str(out), "--save-detections"]) == 0
    printed = capsys.readouterr().out
    assert "2 scenes" in printed and "overall" in printed and "report.md" in printed
    for name in ("report.md", "report.json", "pr_curves.png", "confusion.png"):
        assert (out / name).is_file()
    doc = json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert [s["scene"] for s in doc["scenes"]] == ["scene_0000", "scene_0001"]
    at25 = doc["evaluations"]["iou@0.25"]
    assert at25["per_class"]["chair"]["num_gt"] == 2 and at25["per_class"]["table"]["num_gt"] == 2
    assert all(s["seconds"] > 0 for s in doc["scenes"])
    assert (out / "detections" / "scene_0001" / "detections.json").is_file()

    again = tmp_path / "again"
    args = ["eval", str(dataset), "-o", str(again), "--detections", str(out / "detections")]
    assert main(args) == 0
    stored = json.loads((again / "report.json").read_text(encoding="utf-8"))
    for key, ev in doc["evaluations"].items():
        for part in ("per_class", "overall", "confusion"):
            assert stored["evaluations"][key][part] == ev[part]
    assert stored["options"] == {"detections": str(out / "detections")}


def test_eval_turns_each_scene_and_reports_every_turn_and_the_pool(dataset, tmp_path, capsys):
    out = tmp_path / "turned"
    assert main(["eval", str(dataset), "-o", str(out), "--turns", "0,90", "--votes", "1"]) == 0
    printed = capsys.readouterr().out
    assert "2 scenes, 4 runs" in printed and "90°: chair P" in printed
    doc = json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert [s["scene"] for s in doc["scenes"]] == [
        "scene_0000@0deg",
        "scene_0000@90deg",
        "scene_0001@0deg",
        "scene_0001@90deg",
    ]
    assert doc["options"]["turns"] == [0.0, 90.0]
    pooled = doc["evaluations"]["iou@0.25"]["per_class"]["chair"]
    by_turn = {k: v["per_class"]["chair"] for k, v in doc["by_variant"].items()}
    assert list(by_turn) == ["0°", "90°"] and pooled["num_gt"] == 4
    assert pooled["tp"] == sum(m["tp"] for m in by_turn.values())
    text = (out / "report.md").read_text(encoding="utf-8")
    assert "## By run" in text and "| 90° |" in text and "| **pooled** |" in text
    for bad in (["--turns", "0,x"], ["--seeds", "1,1"], ["--seeds", "0", "--detections", "d"]):
        assert main(["eval", str(dataset), *bad]) == 2
        err = capsys.readouterr().err
        assert err.startswith("error:") and err.count("\n") == 1


def test_eval_errors_are_one_line_and_status_2(tmp_path, capsys):
    assert main(["eval", str(tmp_path / "missing")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and "missing" in err and "Traceback" not in err
    (tmp_path / "empty").mkdir()
    assert main(["eval", str(tmp_path / "empty"), "--format", "s3dis"]) == 2
    assert "'s3dis' layout" in capsys.readouterr().err
    assert main(["eval", str(tmp_path / "empty"), "--save-detections"]) == 2


def test_calibrate_writes_a_valid_ontology_and_states_the_split(dataset, tmp_path, capsys):
    out, report = tmp_path / "mine.yaml", tmp_path / "calibration.json"
    args = [
        "calibrate",
        str(dataset),
        "-o",
        str(out),
        "--split",
        "0.5",
        "--seed",
        "4",
        "--report",
        str(report),
    ]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "split seed 4" in printed and "held-out scenes" in printed
    onto = parse_ontology(out.read_text(encoding="utf-8"))
    assert {"chair", "sofa", "table"} <= set(onto.names)
    assert yaml.safe_load(out.read_text(encoding="utf-8"))["format"] == "ontodetect.ontology/1"
    doc = json.loads(report.read_text(encoding="utf-8"))
    assert len(doc["split"]["calibration"]) == 1 and len(doc["split"]["held_out"]) == 1
    assert {r["class"] for r in doc["held_out"]} == {"chair", "sofa", "table", "overall"}
    assert main(["calibrate", str(dataset), "-o", str(out), "--split", "2"]) == 2
    assert "'split' parameter" in capsys.readouterr().err


def test_eval_json_on_stdout_has_box_ap_and_global_flags_after_the_command(dataset, tmp_path):
    import subprocess
    import sys

    out = tmp_path / "report"
    assert main(["eval", str(dataset), "-o", str(out), "--save-detections", "-q"]) == 0
    # a real pipe: one JSON document, no table, no colour codes
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "ontodetect",
            "eval",
            str(dataset),
            "--json",
            "--detections",
            str(out / "detections"),
            "-q",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    assert "\x1b[" not in proc.stdout
    doc = json.loads(proc.stdout)
    assert set(doc["box_ap"]) == {"aligned@0.25", "aligned@0.5", "oriented@0.25", "oriented@0.5"}
    # the simulator's objects.json carries the boxes: two chairs, two tables
    assert doc["box_ap"]["aligned@0.25"]["chair"] is not None
    assert doc["evaluations"]["iou@0.25"]["per_class"]["chair"]["num_gt"] == 2
