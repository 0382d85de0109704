"""The generalization benchmark's pieces, on tiny hand-made data with known answers."""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
import pytest
from benchmarks import _generalization as G
from benchmarks import bench_generalization as B
from rich.console import Console

from ontodetect import point_cloud
from ontodetect.evaluation import Instance
from ontodetect.synth import load_synth


def inst(id, label, rows, score=1.0):
    return Instance.make(id, label, rows, score)


# -- stability -----------------------------------------------------------------------------
def test_reappearance_counts_same_label_overlaps_one_to_one():
    reference = [
        inst(1, "chair", range(0, 10), 0.9),  # comes back shifted by 2: IoU 8/12
        inst(2, "chair", range(10, 20), 0.8),  # comes back shifted by 5: IoU 5/15 < 0.5
        inst(3, "table", range(20, 40), 0.7),  # comes back as a sofa: not the same label
        inst(4, "sofa", range(40, 60), 0.6),  # exactly the same
        inst(5, "sofa", range(40, 60), 0.5),  # a duplicate: its twin is taken already
    ]
    other = [
        inst(1, "chair", range(2, 12), 0.9),
        inst(2, "chair", range(15, 25), 0.8),
        inst(3, "sofa", range(20, 40), 0.7),
        inst(4, "sofa", range(40, 60), 0.6),
    ]
    assert G.reappearance(reference, other) == (2, 5)
    assert G.reappearance(reference, other, iou_threshold=0.3) == (3, 5)
    assert G.reappearance([], other) == (0, 0)
    assert G.reappearance(reference, []) == (0, 5)


def test_reappearance_after_a_subsample_compares_on_the_rows_kept():
    reference = [inst(1, "chair", range(0, 10))]
    kept = np.arange(0, 100, 3)  # every third row survived
    other = [inst(1, "chair", range(0, 10, 3))]  # every kept row of the chair found again
    assert G.reappearance(reference, other) == (0, 1)  # IoU 4/10 on all rows
    assert G.reappearance(reference, other, kept=kept) == (1, 1)  # IoU 1 on the kept rows


def test_lost_references_name_the_detections_that_did_not_come_back():
    reference = [
        inst(1, "chair", range(0, 10), 0.9),  # comes back shifted by 2: IoU 8/12
        inst(2, "chair", range(10, 20), 0.8),  # comes back shifted by 5: IoU 5/15 < 0.5
        inst(3, "table", range(20, 40), 0.7),  # comes back as a sofa
    ]
    other = [inst(1, "chair", range(2, 12)), inst(2, "chair", range(15, 25))]
    other.append(inst(3, "sofa", range(20, 40)))
    assert G.lost_references(reference, other) == [1, 2]
    assert G.lost_references(reference, []) == [0, 1, 2]
    assert G.lost_references([], other) == []
    # Cut to the rows a subsample kept, the second chair overlaps its copy by 5/5.
    assert G.lost_references(reference, other, kept=np.r_[0:10, 15:20]) == [2]


def _unit(scene, transform, dets, kinds=None, kept=None):
    """A hand-made :func:`stability_unit` result."""
    return {
        "scene": scene,
        "transform": transform,
        "detections": dets,
        "kept": kept,
        "kinds": kinds,
        "seconds": 1.0,
    }


def test_stability_figures_name_each_detection_a_change_lost():
    chair, table = inst(1, "chair", range(0, 10), 0.8), inst(2, "table", range(10, 30), 0.6)
    sofa = inst(1, "sofa", range(0, 20), 0.4)
    runs = [
        _unit("a", None, [chair, table], ["chair", "false: desk (desk)"]),
        _unit("a", "turn 90°", [chair]),  # the table is lost
        _unit("a", "shuffle", [chair, table]),
        _unit("b", None, [sofa], ["sofa"]),
        _unit("b", "turn 90°", []),  # the sofa is lost
        _unit("b", "shuffle", [inst(1, "chair", range(0, 20))]),  # ... and comes back a chair
    ]
    res = B.stability_figures(["a", "b"], ["turn 90°", "shuffle"], runs)
    assert res["reappeared"] == {
        "turn 90°": {"a": [1, 2], "b": [0, 1]},
        "shuffle": {"a": [2, 2], "b": [0, 1]},
    }
    assert res["mean"] == pytest.approx((0.5 + 0 + 1 + 0) / 4) and res["worst"] == 0
    assert [(u["scene"], u["id"], u["is"], u["lost_under"]) for u in res["unsteady"]] == [
        ("b", 1, "sofa", ["turn 90°", "shuffle"]),  # the most often lost first
        ("a", 2, "false: desk (desk)", ["turn 90°"]),
    ]
    assert B.unsteady_table("t", res).row_count == 2


def test_reference_kinds_tell_true_detections_from_what_false_ones_are(tmp_path):
    from ontodetect.evaluation import SceneSource, load_scene
    from ontodetect.synth import synthesize, write_synth

    write_synth(synthesize("dining_room", "rgbd", seed=5, points=30_000), tmp_path / "room")
    source = SceneSource("room", str(tmp_path / "room"), "ontodetect", "room")
    cloud, objects, _ = load_synth(tmp_path / "room")
    rows = np.asarray(cloud.fields["instance"])
    chair = next(o for o in objects if o["class"] == "chair" and (rows == o["id"]).any())
    wall = next(o for o in objects if o["class"] == "wall" and (rows == o["id"]).any())
    dets = [
        inst(1, "chair", np.flatnonzero(rows == chair["id"]), 0.9),  # the chair itself
        inst(2, "chair", np.flatnonzero(rows == wall["id"]), 0.5),  # a wall read as a chair
        inst(3, "table", np.flatnonzero(rows == chair["id"]), 0.4),  # the chair as a table
    ]
    scan = load_scene(source).cloud
    kinds = B.reference_kinds(source, scan, dets)
    assert kinds == ["chair", "false: wall", f"false: chair ({chair['kind']})"]
    # An unlabelled scan says nothing about them.
    bare = point_cloud(cloud.xyz)
    assert B.reference_kinds(source, bare, dets) == ["?", "?", "?"]
    # The labels read from the scan in hand are those read from its files.
    rows_read, what_read = B.scene_labels(source)
    rows_held, what_held = B.scene_labels(source, scan)
    np.testing.assert_array_equal(rows_held, rows_read)
    assert what_held == what_read and what_read[chair["id"]] == ("chair", chair["kind"])


def test_stability_transforms_keep_rows_and_do_what_they_say(rng):
    xyz = rng.uniform(0, 3, size=(1000, 3))
    cloud = point_cloud(xyz, fields={"label": np.arange(1000)})
    fns = G.stability_transforms([90, 30])
    assert list(fns) == [
        "turn 90°",
        "turn 30°",
        "offset 400000 m",
        "round 1 mm",
        "jitter 0.5 mm",
        "shuffle",
        "subsample 80 %",
    ]
    out = {name: fn(cloud, np.random.default_rng(0)) for name, fn in fns.items()}
    for name, c in out.items():
        np.testing.assert_array_equal(c.fields["label"], c.index, err_msg=name)
    np.testing.assert_allclose(out["turn 90°"].xyz, np.c_[-xyz[:, 1], xyz[:, 0], xyz[:, 2]])
    np.testing.assert_allclose(out["offset 400000 m"].xyz - xyz, [[4e5, 4e5, 0]] * 1000)
    assert np.abs(out["round 1 mm"].xyz - xyz).max() <= 5e-4 + 1e-12
    np.testing.assert_allclose(out["round 1 mm"].xyz * 1000, np.round(xyz * 1000), atol=1e-9)
    assert np.std(out["jitter 0.5 mm"].xyz - xyz) == pytest.approx(5e-4, rel=0.05)
    shuffled = out["shuffle"]
    assert sorted(shuffled.index.tolist()) == list(range(1000))
    np.testing.assert_array_equal(shuffled.xyz, xyz[shuffled.index])
    sub = out["subsample 80 %"]
    assert len(sub) == 800 and len(np.unique(sub.index)) == 800
    np.testing.assert_array_equal(sub.xyz, xyz[sub.index])
    assert np.all(xyz == cloud.xyz)  # the input is not modified


# -- robustness ----------------------------------------------------------------------------
def test_robustness_changes_keep_the_labels_and_do_what_they_say(rng):
    n = 4000
    xyz = rng.uniform(0, 3, size=(n, 3))
    class_id = np.where(np.arange(n) < n // 2, G.FLOOR_CLASS, 5)  # half floor, half chair
    cloud = point_cloud(xyz, fields={"class_id": class_id, "instance": np.arange(n) % 7})
    fns = G.robustness_changes()
    assert list(fns) == [
        "noise 1 cm",
        "floor 80 % unseen",
        "points doubled",
        "half the points",
        "a quarter of the points",
        "axes turned 90°",
        "axes turned 180°",
        "axes turned 270°",
    ]
    out = {name: fn(cloud, np.random.default_rng(0)) for name, fn in fns.items()}
    noisy = out["noise 1 cm"]
    assert np.std(noisy.xyz - xyz) == pytest.approx(G.NOISE_SIGMA, rel=0.05)
    np.testing.assert_array_equal(noisy.fields["class_id"], class_id)
    unseen = out["floor 80 % unseen"]
    kept_floor = np.count_nonzero(unseen.fields["class_id"] == G.FLOOR_CLASS)
    assert kept_floor / (n // 2) == pytest.approx(1 - G.FLOOR_LOSS, abs=0.03)
    assert np.count_nonzero(unseen.fields["class_id"] == 5) == n // 2  # nothing else goes
    np.testing.assert_array_equal(unseen.xyz, xyz[unseen.index])
    doubled = out["points doubled"]
    assert len(doubled) == 2 * n
    np.testing.assert_array_equal(doubled.xyz[:n], xyz)
    assert np.std(doubled.xyz[n:] - xyz) == pytest.approx(G.DOUBLE_JITTER, rel=0.05)
    instance = cloud.fields["instance"]
    np.testing.assert_array_equal(doubled.fields["instance"], np.concatenate([instance, instance]))
    for name, share in [
        ("half the points", G.HALF_SHARE),
        ("a quarter of the points", G.QUARTER_SHARE),
    ]:
        kept = out[name]
        assert len(kept) / n == pytest.approx(share, abs=0.03)
        np.testing.assert_array_equal(kept.xyz, xyz[kept.index])  # the rows kept, as they were
        np.testing.assert_array_equal(kept.fields["class_id"], class_id[kept.index])
    # The file's axes turned by quarters, exactly: every point and label kept in its row.
    quarter = out["axes turned 90°"]
    np.testing.assert_array_equal(quarter.xyz, np.c_[-xyz[:, 1], xyz[:, 0], xyz[:, 2]])
    np.testing.assert_array_equal(quarter.fields["instance"], cloud.fields["instance"])
    np.testing.assert_array_equal(out["axes turned 180°"].xyz[:, :2], -xyz[:, :2])
    np.testing.assert_array_equal(
        out["axes turned 270°"].xyz, np.c_[xyz[:, 1], -xyz[:, 0], xyz[:, 2]]
    )
    assert np.all(xyz == cloud.xyz)  # the input is not modified


def test_a_robustness_unit_scores_the_changed_scan_against_its_own_labels(tmp_path):
    from ontodetect.evaluation import SceneSource
    from ontodetect.synth import synthesize, write_synth

    write_synth(synthesize("dining_room", "rgbd", seed=5, points=30_000), tmp_path / "room")
    source = SceneSource("room", str(tmp_path / "room"), "ontodetect", "room")
    clean = B.robustness_unit((source, "points doubled"), {"seed": 0, "room": None})
    noisy = B.robustness_unit((source, "noise 1 cm"), {"seed": 0, "room": None})
    # Doubled, every object has twice its points but is the same object.
    assert clean["counts"]["chair"][2] == noisy["counts"]["chair"][2] > 0
    assert all(tp <= min(det, gt) for tp, det, gt in noisy["counts"].values())
    # The noise is measured on the floor: the centimetre added over the simulated sensor's
    # own few millimetres (the doubled copy's 5 mm jitter adds less).
    assert noisy["floor_scatter"] == pytest.approx(G.NOISE_SIGMA, rel=0.3)
    assert clean["floor_scatter"] < noisy["floor_scatter"] - 0.002
    # Its mistakes one by one (for `compare`) add up to its counts: a false detection per
    # detection that found nothing, a missed object per object nothing found.
    for run in (clean, noisy):
        for c, (tp, det, gt) in run["counts"].items():
            assert sum(f["label"] == c for f in run["false"]) == det - tp
            assert sum(m["label"] == c for m in run["missed"]) == gt - tp
        assert all(f["scene"] == "room" for f in run["false"] + run["missed"])
        assert {m["cause"] for m in run["missed"]} <= set(G.MISSED_CAUSES)


def test_a_doubled_scans_copies_are_named_as_the_objects_they_copy(tmp_path, monkeypatch):
    # What a false detection really is, on the doubled copy, is read off the copy's own rows:
    # a point's copy is part of the same object, not "nothing" beyond the file's rows.
    from ontodetect.evaluation import SceneSource, load_scene
    from ontodetect.synth import synthesize, write_synth

    write_synth(synthesize("office", "rgbd", seed=2, points=4_000), tmp_path / "room")
    source = SceneSource("room", str(tmp_path / "room"), "ontodetect", "room")
    cloud = load_scene(source).cloud
    doubled = G.robustness_changes()["points doubled"](cloud, np.random.default_rng(0))
    rows, what = B.scene_labels(source, doubled)
    n = len(cloud)
    assert len(rows) == 2 * n
    np.testing.assert_array_equal(rows[n:], rows[:n])
    assert what == B.scene_labels(source, cloud)[1]
    seen = []
    real = B.scene_labels
    monkeypatch.setattr(B, "scene_labels", lambda s, c=None: seen.append(c) or real(s, c))
    B.robustness_unit((source, "points doubled"), {"seed": 0, "room": None})
    assert [len(c) for c in seen] == [2 * n]


# -- false detections and families ---------------------------------------------------------
def tiny_labelled_scan():
    """Rows 0-9 floor (instance 1), 10-19 wall (2), 20-29 chair (3), 30-39 sink (4),
    40-44 nothing (0)."""
    instance = np.r_[[1] * 10, [2] * 10, [3] * 10, [4] * 10, [0] * 5]
    what = {
        1: ("floor", "floor"),
        2: ("wall", "wall"),
        3: ("chair", "chair-office"),
        4: ("sink", "sink"),
    }
    gts = [inst(3, "chair", range(20, 30))]
    return instance, what, gts


def test_false_detections_are_named_by_the_object_holding_most_of_their_points():
    instance, what, gts = tiny_labelled_scan()
    dets = [
        inst(1, "chair", range(20, 30), 0.9),  # the chair: a true positive
        inst(2, "chair", [*range(30, 38), 28, 29], 0.8),  # 8 sink points, 2 chair points
        inst(3, "table", range(0, 10), 0.7),  # the floor
        inst(4, "sofa", [40, 41, 42, 43, 12], 0.6),  # 4 of nothing, 1 of wall
        inst(5, "chair", range(21, 29), 0.5),  # the chair again: a duplicate
        inst(6, "table", [10, 11, 30, 31], 0.4),  # a tie: the lower id (the wall) wins
    ]
    causes = G.false_detection_causes(dets, gts, instance, what)
    got = [(f["id"], f["label"], f["is"], f["kind"], f["instance"], f["share"]) for f in causes]
    assert got == [
        (2, "chair", "sink", "sink", 4, 0.8),
        (3, "table", "floor", "floor", 1, 1.0),
        (4, "sofa", "nothing", "nothing", 0, 0.8),
        (5, "chair", "chair", "chair-office", 3, 1.0),
        (6, "table", "wall", "wall", 2, 0.5),
    ]


def test_false_detections_at_a_stricter_overlap_include_loose_matches():
    instance, what, gts = tiny_labelled_scan()
    dets = [inst(1, "chair", range(20, 24), 0.9)]  # 4 of the chair's 10 points: IoU 0.4
    assert G.false_detection_causes(dets, gts, instance, what, iou_threshold=0.25) == []
    (f,) = G.false_detection_causes(dets, gts, instance, what, iou_threshold=0.5)
    assert (f["is"], f["kind"], f["share"]) == ("chair", "chair-office", 1.0)


def test_rows_beyond_the_labels_count_as_nothing():
    instance, what, gts = tiny_labelled_scan()
    (f,) = G.false_detection_causes([inst(1, "table", [100, 101, 0])], gts, instance, what)
    assert (f["is"], f["instance"]) == ("nothing", 0)


def test_missed_objects_are_told_apart_by_where_they_were_lost():
    gts = [
        inst(1, "chair", range(0, 10)),  # found
        inst(2, "chair", range(10, 20)),  # right cluster, labelled a table by the first pass
        inst(3, "chair", range(20, 30)),  # right cluster and label, dropped by the vote
        inst(4, "chair", range(30, 40)),  # in a desk's cluster of 60 points
        inst(5, "table", range(100, 120)),  # in pieces of 4 points
        inst(6, "sofa", range(200, 210)),  # in no cluster at all
    ]
    clusters = [
        inst(0, "chair", range(0, 10)),
        inst(1, "table", range(10, 21)),
        inst(2, "chair", range(20, 30)),
        inst(3, "table", range(30, 90)),
        *[inst(4 + k, "", range(100 + 4 * k, 104 + 4 * k)) for k in range(5)],
    ]
    preds = [inst(1, "chair", range(0, 10), 0.9), inst(2, "table", range(30, 90), 0.8)]
    got = G.missed_causes(preds, gts, clusters)
    assert [(m["id"], m["cause"], m["as"]) for m in got] == [
        (2, "scored", "table"),
        (3, "vote", "chair"),
        (4, "merged", "table"),
        (5, "split", ""),
        (6, "not clustered", ""),
    ]
    merged = got[2]
    assert merged["cover"] == 1.0 and merged["iou"] == pytest.approx(10 / 60, abs=1e-4)
    assert got[3]["cover"] == pytest.approx(0.2) and got[4]["iou"] == 0.0
    assert G.missed_causes(preds, gts[:1], clusters) == []
    assert {m["cause"] for m in got} <= set(G.MISSED_CAUSES)


def test_recall_by_group_separates_armchairs_from_office_chairs():
    gts = [
        inst(1, "chair", range(0, 10)),
        inst(2, "chair", range(10, 20)),
        inst(3, "chair", range(20, 30)),
        inst(4, "table", range(30, 50)),
    ]
    kinds = {1: "chair-office", 2: "chair-office", 3: "chair-armchair"}
    dets = [
        inst(1, "chair", range(0, 10), 0.9),
        inst(2, "sofa", range(20, 30), 0.8),  # the armchair taken for a sofa
        inst(3, "chair", range(10, 14), 0.7),  # a piece of the second office chair
    ]
    assert G.recall_by_group(dets, gts, kinds) == {
        "chair-office": [2, 2],
        "chair-armchair": [0, 1],
        "table": [0, 1],  # no kind known: grouped under its class
    }
    assert G.recall_by_group(dets, gts, kinds, iou_threshold=0.5)["chair-office"] == [1, 2]


def test_instance_names_take_the_majority_class():
    names = G.instance_names([0, 5, 5, 5, 7], [1, 5, 5, 3, 99], {5: "chair", 3: "cabinet"})
    assert names == {5: ("chair", "chair"), 7: ("class 99", "class 99")}


# -- the simulated set ---------------------------------------------------------------------
def test_simulated_set_is_fixed_and_large_enough():
    full = B.simulated_set(B.PARAMETRIC_ROOMS)
    rooms = {(s.room, s.seed) for s in full}
    fused = [s for s in full if s.variant == "fused"]
    assert len(fused) == len(rooms) >= 60
    assert {s.variant for s in full} == set(B.VARIANTS)
    assert len({s.name for s in full}) == len(full)
    assert B.simulated_set(B.PARAMETRIC_ROOMS) == full
    nine = B.simulated_set([f"type{k}" for k in range(9)])
    assert sum(s.variant == "fused" for s in nine) == 63  # 9 room types x 7 seeds
    quick = B.simulated_set(B.PARAMETRIC_ROOMS, quick=True)
    assert len(quick) == 8 and {s.variant for s in quick} == set(B.VARIANTS)


def test_a_second_simulated_set_shows_other_rooms_of_the_same_kinds():
    types = [f"type{k}" for k in range(9)]
    first, second = B.simulated_set(types), B.simulated_set(types, first_seed=7)
    assert len(second) == len(first) and not {s.name for s in first} & {s.name for s in second}
    assert {s.seed for s in second} == set(range(7, 14))
    # the same variants, each on the same room of the set as in the first one
    assert [(s.room, s.seed - 7, s.variant) for s in second] == [
        (s.room, s.seed, s.variant) for s in first
    ]
    frames = B.frames_set(types, first_seed=7)
    assert {s.seed for s in frames} == set(range(7, 14)) and len(frames) == 63
    assert B.cache_key(B.RoomSource("parametric", ("a",), ""), first) != B.cache_key(
        B.RoomSource("parametric", ("a",), ""), second
    )


def test_a_negative_first_seed_is_one_line_and_exit_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        B.main(["--real", str(tmp_path), "--sim-seeds", "-1"])
    assert stop.value.code == 2
    assert "--sim-seeds" in capsys.readouterr().err


def test_single_frames_are_every_room_type_seen_once_per_seed():
    frames = B.frames_set([f"type{k}" for k in range(9)])
    assert len(frames) == 63 and {s.variant for s in frames} == {"frame"}
    assert {(s.room, s.seed) for s in frames} == {
        (f"type{k}", s) for k in range(9) for s in range(B.FRAME_SEEDS)
    }
    # the simulated set's own frames (seed 3) are among them, under the same names
    sim = {s.name for s in B.simulated_set([f"type{k}" for k in range(9)]) if s.variant == "frame"}
    assert sim < {s.name for s in frames}
    assert B.cache_key(B.RoomSource("parametric", ("a",), ""), frames) != B.cache_key(
        B.RoomSource("parametric", ("a",), ""), B.simulated_set([f"type{k}" for k in range(9)])
    )
    assert len(B.frames_set(B.PARAMETRIC_ROOMS, quick=True)) == 2


def test_the_sparse_part_scores_the_fused_scans_with_half_and_a_quarter_of_their_points(
    monkeypatch,
):
    """(f) takes the fused scans of the simulated set alone (not their floor-layer, holes,
    tilt or frame variants) through the robustness part's two density changes, and prints
    them beside the fused scans as they are."""
    seen = {}

    def fake_robustness(scans, jobs, opts, names=None):
        seen["scans"], seen["names"] = [s.name for s in scans], list(names)
        chair = {"tp": 1, "det": 2, "gt": 3, "precision": 0.5, "recall": 0.33}
        return {
            "changes": {n: {"per_class": {"chair": chair}, "floor_scatter": None} for n in names}
        }

    monkeypatch.setattr(B, "robustness", fake_robustness)
    monkeypatch.setattr(B, "console", Console(record=True, width=200))
    scans = B.simulated_set(B.PARAMETRIC_ROOMS, quick=True)
    sources = [B.SceneSource(s.name, s.name, "ontodetect", s.room) for s in scans]
    doc = {}
    chair = {"tp": 2, "det": 2, "gt": 3, "precision": 1.0, "recall": 0.67}
    B._run_sparse(sources, {s.name: s for s in scans}, 1, {}, doc, {"chair": chair})
    assert seen["scans"] == [s.name for s in scans if s.variant == "fused"]
    assert seen["names"] == list(B.SPARSE_CHANGES) == ["half the points", "a quarter of the points"]
    assert set(B.SPARSE_CHANGES) <= set(G.robustness_changes())
    assert set(doc["sparse"]["changes"]) == set(B.SPARSE_CHANGES) and "seconds" in doc["sparse"]
    text = B.console.export_text()
    assert "as they are" in text and "2/2/3" in text and "a quarter of the points" in text


def test_the_cache_key_changes_with_the_scans():
    source = B.RoomSource("parametric", B.PARAMETRIC_ROOMS, "")
    scans = B.simulated_set(B.PARAMETRIC_ROOMS, quick=True)
    a = B.cache_key(source, scans)
    assert a == B.cache_key(source, scans)
    assert a != B.cache_key(source, scans[:-1])
    assert a["ontodetect"] and len(a["synth_sources"]) == 16


def test_without_the_furnished_rooms_the_parametric_ones_are_used_with_a_warning(monkeypatch):
    monkeypatch.setitem(sys.modules, "ontodetect.synth.furnished", None)  # import fails
    source = B.room_source()
    assert source.name == "parametric" and source.room_types == B.PARAMETRIC_ROOMS
    assert "not available" in source.note


def test_generate_scan_writes_a_scannet_like_scan_with_its_artefacts(tmp_path, monkeypatch):
    # A coarse scan keeps the test fast; the benchmark's own settings only make it denser.
    monkeypatch.setattr(B, "DENSE_SCAN", {"voxel": 0.05, "num_frames": 4, "stride": 16})
    monkeypatch.setattr(B, "POINTS", 3000)
    scan = B.SimScan("tiny", 0, "floor-layer")
    summary = B.generate_scan(("parametric", scan, str(tmp_path / scan.name)))
    cloud, objects, scene = load_synth(tmp_path / scan.name)
    assert summary["points"] == len(cloud) == min(B.POINTS, scene["num_points"])
    steps = [a["name"] for a in scene["sensor"]["parameters"]["artefacts"]]
    assert steps == ["duplicate_floor_layer", "scannet_sampling"]
    ids = {o["id"]: o for o in objects}
    for iid, cid in zip(cloud.fields["instance"][:500], cloud.fields["class_id"][:500]):
        if iid > 0:
            assert ids[int(iid)]["class_id"] == cid  # labels stayed with their points
    again = tmp_path / "again"
    B.generate_scan(("parametric", scan, str(again)))
    assert (again / "cloud.ply").read_bytes() == (tmp_path / scan.name / "cloud.ply").read_bytes()


# -- the command ---------------------------------------------------------------------------
def test_named_stability_scans_come_from_the_simulated_set_not_the_frames(tmp_path):
    source = B.RoomSource("parametric", ("office", "bedroom"), "")
    scans, frames = B.simulated_set(source.room_types), B.frames_set(source.room_types)
    for name, listed in (("sim-parametric-aaa", frames), ("sim-parametric-bbb", scans)):
        (tmp_path / name).mkdir()
        key = {"key": {"scans": [s.name for s in listed]}}
        (tmp_path / name / "manifest.json").write_text(json.dumps(key))
    args = argparse.Namespace(
        stability_scans="office-s4-fused", sim_set=None, out=tmp_path, sim_seeds=0
    )
    [picked] = B._named_scans(args, [], source)
    assert picked.path == str(tmp_path / "sim-parametric-bbb" / "office-s4-fused")


def test_a_bad_real_path_is_one_line_and_exit_2(tmp_path, capsys):
    missing = tmp_path / "nowhere"
    assert B.main(["--real", str(missing), "--out", str(tmp_path / "out")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and str(missing) in lines[0]
    empty = tmp_path / "empty"
    empty.mkdir()
    assert B.main(["--real", str(empty), "--out", str(tmp_path / "out")]) == 2
    assert str(empty) in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_figures_are_json_ready():
    a = inst(1, "chair", range(10))
    from ontodetect.evaluation import SceneResult

    figs = B.per_class([SceneResult("s", [a], [a])])
    json.dumps(figs)
    assert figs["iou@0.25"]["chair"] == {
        "gt": 1,
        "det": 1,
        "tp": 1,
        "precision": 1.0,
        "recall": 1.0,
    }
    assert figs["iou@0.5"]["overall"]["tp"] == 1


def test_the_summary_line_times_every_part_that_ran(tmp_path, monkeypatch):
    """The closing line names each measurement that ran with its seconds, the robustness
    part too, and the document is written whole."""
    from rich.console import Console

    monkeypatch.setattr(B, "console", Console(record=True, width=200))
    parts = (("real", 12.0), ("robustness", 34.0), ("simulated", 56.0), ("sparse", 78.0))
    doc = {part: {"seconds": s} for part, s in parts}
    assert B._finish(tmp_path, doc, 0.0) == 0
    line = B.console.export_text()
    assert "real 12 s, robustness 34 s, simulated 56 s, sparse 78 s" in line
    assert json.loads((tmp_path / "generalization.json").read_text())["robustness"] == {
        "seconds": 34.0
    }


def _stability_run(found, total, worst_share):
    """A hand-made :func:`stability` result of one scan and one change."""
    share = found / total
    return {
        "scans": ["room"],
        "transforms": ["turn 90°"],
        "iou": 0.5,
        "reference_detections": {"room": total},
        "reappeared": {"turn 90°": {"room": [found, total]}},
        "detections": {"turn 90°": {"room": found}},
        "per_transform": {"turn 90°": {"mean": share, "worst": worst_share}},
        "mean": share,
        "worst": worst_share,
        "detect_seconds": 2.0,
    }


def test_the_detections_lost_under_several_seeds_say_their_seed():
    lost = {"scene": "room", "id": 3, "label": "chair", "score": 0.3, "is": "chair"}
    a = {**_stability_run(9, 10, 0.9), "unsteady": [{**lost, "lost_under": ["turn 90°"]}]}
    b = {**_stability_run(6, 8, 0.75), "unsteady": [{**lost, "lost_under": ["turn 90°"] * 2}]}
    pooled = B.pooled_seeds({0: a, 1: b})
    assert [(u["seed"], len(u["lost_under"])) for u in pooled["unsteady"]] == [(1, 2), (0, 1)]
    out = Console(record=True, width=200)
    out.print(B.unsteady_table("t", pooled))
    assert "#3 chair, seed 1" in out.export_text()


def test_stability_over_several_seeds_pools_their_figures():
    runs = {0: _stability_run(9, 10, 0.9), 1: _stability_run(6, 8, 0.75)}
    pooled = B.pooled_seeds(runs)
    assert pooled["seeds"] == [0, 1]
    assert pooled["reappeared"]["turn 90°"]["room"] == [15, 18]
    assert pooled["reference_detections"] == {"room": 18}
    assert pooled["mean"] == pytest.approx((0.9 + 0.75) / 2)
    assert pooled["worst"] == 0.75 == pooled["per_transform"]["turn 90°"]["worst"]
    assert pooled["by_seed"]["1"]["mean"] == 0.75 and pooled["detect_seconds"] == 4.0
    assert pooled["unsteady"] == []  # runs written before detections were named
    # the table prints it as one run
    assert B.stability_table("t", pooled).row_count == 2


@pytest.mark.parametrize("seeds", ["a", ",", "0,x"])
def test_bad_stability_seeds_are_one_line_and_exit_2(tmp_path, capsys, seeds):
    with pytest.raises(SystemExit) as stop:
        B.main(["--real", str(tmp_path), "--stability-seeds", seeds])
    assert stop.value.code == 2
    assert "--stability-seeds" in capsys.readouterr().err
    assert not (tmp_path / "bench-output").exists()
