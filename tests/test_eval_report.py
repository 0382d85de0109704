"""The evaluation report: files, tables with the numbers, literature figures."""

from __future__ import annotations

import json

import pytest

from ontodetect import WriteError
from ontodetect.evaluation import (
    Instance,
    SceneOutcome,
    SceneSource,
    literature_comparisons,
    markdown_report,
    summarize_outcomes,
    write_report,
)

CLASSES = ["chair", "sofa", "table"]


def inst(i, label, a, b, score=1.0, center=(0.0, 0.0, 0.0)):
    return Instance.make(i, label, range(a, b), score, center)


def outcome(name, preds, gts, seconds, points=1000, error=None):
    source = SceneSource(name, f"/data/{name}_vert.npy", "scannet-votenet", name[:9])
    return SceneOutcome(name, source, tuple(preds), tuple(gts), points, seconds, 0.1, {}, error)


@pytest.fixture
def evaluation():
    """Chairs: 2 of 3 found plus one false alarm; a table found as a sofa; one scene failed."""
    a = outcome(
        "scene0000_00",
        [
            inst(1, "chair", 0, 10, 0.9),
            inst(2, "chair", 10, 20, 0.8),
            inst(3, "chair", 500, 510, 0.7),
        ],
        [inst(1, "chair", 0, 10), inst(2, "chair", 10, 20), inst(3, "chair", 20, 30)],
        1.25,
    )
    b = outcome(
        "scene0001_00", [inst(1, "sofa", 100, 200, 0.6)], [inst(7, "table", 100, 200)], 2.75
    )
    bad = outcome("scene0002_00", [], [], 0.0, error="x.npy: no such file")
    return summarize_outcomes([a, b, bad], CLASSES, dataset="/data/dev", jobs=2, seconds=5.0)


def test_metrics_of_the_hand_made_evaluation(evaluation):
    ev = evaluation.primary
    chair = ev.per_class["chair"]
    assert (chair.num_gt, chair.num_pred, chair.tp) == (3, 3, 2)
    assert ev.per_class["sofa"].fp == 1 and ev.per_class["table"].fn == 1
    assert [s.name for s in evaluation.failed] == ["scene0002_00"]
    assert evaluation.scene_seconds()["mean"] == pytest.approx(2.0)


def test_report_files_exist_and_hold_the_numbers(evaluation, tmp_path):
    files = write_report(evaluation, tmp_path / "report")
    for path in (files.markdown, files.json, files.pr_curves, files.confusion):
        assert path.is_file() and path.stat().st_size > 0
    for png in (files.pr_curves, files.confusion):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Atomic writes leave no temporary files behind.
    assert sorted(p.name for p in (tmp_path / "report").iterdir()) == [
        "confusion.png",
        "pr_curves.png",
        "report.json",
        "report.md",
    ]

    md = files.markdown.read_text(encoding="utf-8")
    # chair: GT 3, det 3, TP 2, FP 1, FN 1, P = R = F1 = 66.7 %
    assert "| chair | 3 | 3 | 2 | 1 | 1 | 66.7 | 66.7 | 66.7 |" in md
    assert "| **overall** | 4 | 4 | 2 | 2 | 2 | 50.0 | 50.0 | 50.0 |" in md
    # Confusion: the table was detected as a sofa; the third chair missed; one false alarm.
    assert "| table | 0 | 1 | 0 | 0 |" in md
    assert "| chair | 2 | 0 | 0 | 1 |" in md
    assert "| false alarm | 1 | 0 | 0 |  |" in md
    assert "| scene0001_00 | 1,000 | 2.75 | 0/0/0 | 0/1/0 | 1/0/0 |" in md
    assert "mean 2.00 s" in md and "2 worker processes" in md
    assert "| scene0002_00 | x.npy: no such file |" in md
    assert "Measured on other datasets" in md
    for figure in (
        "90.1 | 68.2",
        "81.0 | 53.1",
        "79.1 | 83.9",
        "80.5 | 72.6",
        "76.4 | 62.1",
        "57.8 | 53.6",
    ):
        assert figure in md

    doc = json.loads(files.json.read_text(encoding="utf-8"))
    assert doc["format"] == "ontodetect.evaluation/1"
    assert set(doc["evaluations"]) == {"iou@0.25", "iou@0.5", "distance"}
    chair = doc["evaluations"]["iou@0.25"]["per_class"]["chair"]
    assert chair["tp"] == 2 and chair["precision"] == pytest.approx(2 / 3)
    assert doc["evaluations"]["iou@0.25"]["per_class"]["sofa"]["ap"] is None  # no ground truth
    assert doc["curves"]["iou@0.25"]["chair"]["recall"] == [0.3333, 0.6667, 0.6667]
    assert [s["scene"] for s in doc["scenes"]] == ["scene0000_00", "scene0001_00"]
    assert doc["failed"][0]["error"] == "x.npy: no such file"
    assert doc["literature"]["comparisons"][0]["results"][0]["precision"] == 0.901


def test_the_literature_figures_are_the_thesis_tables():
    got = {
        (c["source"], r["method"]): (r["precision"], r["recall"])
        for c in literature_comparisons()
        for r in c["results"]
    }
    assert got == {
        ("Thesis Table 4.14", "Probabilistic ontology (thesis)"): (0.901, 0.682),
        ("Thesis Table 4.14", "Günther et al."): (0.810, 0.531),
        ("Thesis Table 4.15", "Probabilistic ontology (thesis)"): (0.791, 0.839),
        ("Thesis Table 4.15", "Koppula et al."): (0.805, 0.726),
        ("Thesis Table 4.16", "Probabilistic ontology (thesis)"): (0.764, 0.621),
        ("Thesis Table 4.16", "Koppula et al."): (0.578, 0.536),
    }


def test_this_run_is_set_apart_from_the_literature(evaluation):
    md = markdown_report(evaluation)
    tail = md[md.index("## Comparison with the literature") :]
    assert "**this run**: dev (2 scenes) | ontodetect, point IoU ≥ 0.25 | 50.0 | 50.0" in tail


def test_an_unwritable_report_folder_is_a_write_error(evaluation, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(WriteError, match="report folder"):
        write_report(evaluation, blocker / "report")
