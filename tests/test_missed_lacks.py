"""What a missed object's reading as its class lacked: the first pass's clusters, per label,
and the benchmark's tally of the objects lost to the scoring."""

from __future__ import annotations

import numpy as np
import pytest
from benchmarks import _generalization as G
from benchmarks import bench_generalization as B

from ontodetect import point_cloud
from ontodetect.config import Config
from ontodetect.evaluation import Instance, first_pass_clusters, first_pass_lacks
from ontodetect.pipeline import detect
from test_segmentation import rect, slab


def inst(i, label, pts):
    return Instance.make(i, label, list(pts))


def chair_without_seat(rng, x0, y0):
    """Four legs to 0.42 m and a backrest from 0.45 to 0.9 m: a chair whose seat was
    never scanned, standing on the floor (so nothing can have hidden it)."""
    legs = [
        slab(rng, (x, y, 0), (x + 0.03, y + 0.03, 0.42))
        for x in (x0, x0 + 0.41)
        for y in (y0, y0 + 0.41)
    ]
    back = slab(rng, (x0, y0, 0.45), (x0 + 0.44, y0 + 0.03, 0.9))
    return np.vstack([*legs, back])


@pytest.fixture(scope="module")
def seatless_result():
    rng = np.random.default_rng(3)
    floor = rect(rng, (-1, -1, 0), (3.0, 0, 0), (0, 3.0, 0), 0.03)
    chair = chair_without_seat(rng, 0.3, 0.3)
    pts = np.vstack([floor, chair])
    cfg = Config().with_overrides(["detect.votes=1"])
    result = detect(point_cloud(pts), config=cfg, seed=0, jobs=1)
    return result, np.arange(len(floor), len(pts))


def test_a_chair_seen_without_its_seat_lacks_the_seat(seatless_result):
    result, rows = seatless_result
    clusters = first_pass_clusters(result)
    lacks = first_pass_lacks(result)
    assert len(lacks) == len(clusters) == len(result.scores)
    held = [np.isin(c.points, rows).sum() for c in clusters]
    k = int(np.argmax(held))
    assert held[k] > 0.8 * len(rows)
    assert lacks[k]["chair"] == "seat.missing"
    # every reported label is read, each as one of the ontology's parts or the cluster
    labels = {c.label for c in result.ontology.classes}
    assert set(lacks[k]) == labels
    assert all(v == "" or "." in v for v in lacks[k].values())


def test_only_objects_lost_to_the_scoring_say_what_they_lacked():
    gts = [
        inst(1, "chair", range(0, 10)),  # its cluster, read as a table
        inst(2, "chair", range(10, 20)),  # its cluster, read as a chair, lost in the vote
        inst(3, "chair", range(30, 40)),  # merged into a desk's cluster
    ]
    clusters = [inst(0, "table", range(0, 10)), inst(1, "chair", range(10, 20)),
                inst(2, "table", range(30, 90))]  # fmt: skip
    lacks = [{"chair": "seat.missing"}, {"chair": "cluster.breadth"}, {"chair": "seat.height"}]
    got = G.missed_causes([], gts, clusters, lacks=lacks)
    assert [(m["cause"], m["lacks"]) for m in got] == [
        ("scored", "seat.missing"),
        ("vote", ""),
        ("merged", ""),
    ]
    # without the clusters' readings nothing is claimed
    assert {m["lacks"] for m in G.missed_causes([], gts, clusters)} == {""}


def test_the_summary_counts_what_the_scored_misses_lacked():
    missed = {
        key: [
            {"label": "chair", "kind": "chair-dining", "cause": "scored", "lacks": "seat.missing"},
            {"label": "chair", "kind": "chair-office", "cause": "scored", "lacks": "seat.missing"},
            {
                "label": "chair",
                "kind": "chair-office",
                "cause": "scored",
                "lacks": "cluster.breadth",
            },
            {"label": "chair", "kind": "chair-office", "cause": "merged", "lacks": ""},
            {"label": "table", "kind": "desk", "cause": "split"},  # written before ``lacks``
        ]
        for key in B.THRESHOLDS
    }
    summary = B.missed_summary(missed)
    chair = summary["iou@0.25"]["chair"]
    assert chair["lacks"] == {"seat.missing": 2, "cluster.breadth": 1}
    assert list(chair["lacks"]) == ["seat.missing", "cluster.breadth"]  # commonest first
    assert summary["iou@0.25"]["table"]["lacks"] == {}
    from rich.console import Console

    console = Console(width=200, record=True)
    console.print(B.lacks_table("what they lacked", summary))
    text = console.export_text()
    assert "seat.missing 2, cluster.breadth 1" in text
