"""Segmentation by recognition (issue 20, opt-in): over-segmentation, candidates, the exact
selection, and generated scenes where the right candidate must exist and be chosen."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from ontodetect.config import Config
from ontodetect.errors import OntoDetectError
from ontodetect.geometry import _mesh as M
from ontodetect.labeling import conflicts, select_candidates
from ontodetect.ontology import builtin_ontology, class_priors
from ontodetect.outputs import explain
from ontodetect.pipeline import detect
from ontodetect.pipeline._recognize import candidate_gain, explain_candidates, recognize
from ontodetect.segment import (
    GENERATORS,
    cut_shares,
    felzenszwalb,
    oversegment,
    propose,
    radius_graph,
    segment,
)
from ontodetect.synth import synthesize
from ontodetect.synth.furniture import make_furniture, place
from ontodetect.synth.scene import OrientedBox, SceneObject
from test_synth_sensors import box_room


# -- the selection ---------------------------------------------------------------------------
def _brute_force(gains, pairs, bonus=()):
    """The best total gain, plus the bonuses of the chosen pairs, over every consistent
    subset (the empty one included)."""
    n, best = len(gains), 0.0
    clash = {tuple(p) for p in np.asarray(pairs).tolist()}
    for r in range(1, n + 1):
        for subset in itertools.combinations(range(n), r):
            if any((a, b) in clash for a, b in itertools.combinations(subset, 2)):
                continue
            pick = set(subset)
            extra = sum(v for i, j, v in bonus if int(i) in pick and int(j) in pick)
            best = max(best, sum(gains[k] for k in subset) + extra)
    return best


def _random_candidates(rng, most):
    """Between 3 and ``most`` candidates: runs of 2 to 14 ids starting below 40."""
    members = []
    for _ in range(int(rng.integers(3, most + 1))):
        lo = int(rng.integers(0, 40))
        members.append(np.arange(lo, lo + int(rng.integers(2, 15))))
    return members


@pytest.mark.parametrize("seed", range(12))
def test_the_selection_is_exact_on_small_candidate_sets(seed):
    rng = np.random.default_rng(seed)
    members = _random_candidates(rng, 10)
    n = len(members)
    gains = rng.normal(0.5, 1.0, n)
    pairs = conflicts(members, share=0.1)
    chosen, how = select_candidates(gains, pairs)
    assert how in ("milp", "none")
    picked = np.flatnonzero(chosen)
    assert not any(chosen[a] and chosen[b] for a, b in pairs)
    assert (gains[picked] > 0).all()
    assert gains[picked].sum() == pytest.approx(_brute_force(gains, pairs), abs=1e-9)
    # greedy with suppression is consistent, never better than exact
    greedy, how = select_candidates(gains, pairs, max_exact=0)
    assert how == "greedy" and not any(greedy[a] and greedy[b] for a, b in pairs)
    assert gains[greedy].sum() <= gains[picked].sum() + 1e-9


def test_the_selection_prefers_two_disjoint_candidates_to_their_union():
    members = [np.arange(0, 20), np.arange(0, 10), np.arange(10, 20)]
    chosen, _ = select_candidates([2.0, 1.5, 1.5], conflicts(members))
    assert chosen.tolist() == [False, True, True]
    chosen, _ = select_candidates([3.5, 1.5, 1.5], conflicts(members))
    assert chosen.tolist() == [True, False, False]


@pytest.mark.parametrize("seed", range(12))
def test_the_selection_with_pair_bonuses_is_exact(seed):
    rng = np.random.default_rng(100 + seed)
    members = _random_candidates(rng, 9)
    n = len(members)
    gains = rng.normal(0.0, 1.0, n)
    pairs = conflicts(members, share=0.1)
    clash = {tuple(p) for p in pairs.tolist()}
    bonus = [
        [i, j, float(rng.uniform(0.0, 1.5))]
        for i, j in itertools.combinations(range(n), 2)
        if (i, j) not in clash and rng.random() < 0.5
    ]
    chosen, how = select_candidates(
        gains, pairs, bonus=np.array(bonus).reshape(-1, 3), eligible=np.ones(n, bool)
    )
    assert how == "milp"
    assert not any(chosen[a] and chosen[b] for a, b in pairs)
    pick = set(np.flatnonzero(chosen).tolist())
    total = gains[chosen].sum() + sum(v for i, j, v in bonus if i in pick and j in pick)
    assert total == pytest.approx(_brute_force(gains, pairs, bonus), abs=1e-9)


def test_touching_candidates_get_back_what_they_lost_where_they_meet():
    # Two chairs that touch, each cut where it meets the other, and both as one piece: on
    # their own the pair wins; with what they lost where they meet given back, the two do.
    members = [np.arange(0, 20), np.arange(0, 10), np.arange(10, 20)]
    gains = [1.0, 0.4, 0.4]
    chosen, _ = select_candidates(gains, conflicts(members))
    assert chosen.tolist() == [True, False, False]
    chosen, _ = select_candidates(
        gains, conflicts(members), bonus=[[1, 2, 0.5]], eligible=[True] * 3
    )
    assert chosen.tolist() == [False, True, True]


def test_cut_shares_of_a_whole_object_and_of_its_pieces():
    # Two boxes of voxels 1 m apart: each whole box is cut from nothing, its halves are
    # cut from each other, and the contact says how much of each half meets the other.
    g = np.mgrid[0:6, 0:4, 0:4].reshape(3, -1).T * 0.02
    centers = np.vstack([g, g + [1.0, 0.0, 0.0]])
    objects = np.arange(len(centers))
    box = np.arange(len(g))
    left, right = box[g[:, 0] < 0.05], box[g[:, 0] > 0.05]
    graph = radius_graph(centers, 0.021)
    cut, contact = cut_shares(objects, graph, [box, box + len(g), left, right])
    assert cut[0] == 0.0 and cut[1] == 0.0
    assert 0.0 < cut[2] < 0.5 and cut[3] == pytest.approx(cut[2])
    assert contact[2, 3] == pytest.approx(cut[2]) and contact[3, 2] == pytest.approx(cut[3])
    assert contact[0, 1] == 0.0  # 1 m apart: no edge between them
    # structure (not an object voxel) is not in the graph: resting on it cuts nothing
    objects = np.setdiff1d(objects, left)
    cut, _ = cut_shares(objects, radius_graph(centers[objects], 0.021), [right])
    assert cut[0] == 0.0


def test_conflicts_allow_a_small_shared_share():
    a, b = np.arange(100), np.arange(95, 200)
    assert conflicts([a, b], share=0.1).tolist() == []
    assert conflicts([a, b], share=0.01).tolist() == [[0, 1]]


def test_nothing_is_chosen_without_a_positive_gain():
    chosen, how = select_candidates([-1.0, 0.0], np.zeros((0, 2)))
    assert chosen.tolist() == [False, False] and how == "none"


# -- over-segmentation -----------------------------------------------------------------------
def test_felzenszwalb_cuts_at_a_heavy_edge():
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4]])
    weights = np.array([0.0, 0.0, 9.0, 0.0])
    assert felzenszwalb(5, edges, weights, scale=1.0, min_size=1).tolist() == [0, 0, 0, 1, 1]


def test_oversegment_separates_a_seat_from_its_backrest():
    g = np.arange(0.0, 0.5, 0.02)
    seat = np.array([[x, y, 0.45] for x in g for y in g])
    back = np.array([[x, 0.5, z] for x in g for z in np.arange(0.47, 0.95, 0.02)])
    segs = oversegment(np.vstack([seat, back]), None, 0.05)
    a, b = segs.labels[: len(seat)], segs.labels[len(seat) :]
    assert len(np.intersect1d(np.unique(a), np.unique(b))) == 0
    assert len(segs) >= 2 and segs.counts.sum() == len(seat) + len(back)


def test_generators_are_registered_by_name():
    assert {"clusters", "parts", "merge", "density"} <= set(GENERATORS)


# -- configuration ----------------------------------------------------------------------------
def test_proposals_default_to_the_vote_and_reject_unknown_values():
    assert Config().detect.proposals == "vote"
    assert Config().with_overrides(["detect.proposals=recognition"]).detect.proposals == (
        "recognition"
    )
    with pytest.raises(OntoDetectError, match="proposals"):
        Config().with_overrides(["detect.proposals=magic"])


def test_candidate_gain_is_the_log_odds_of_the_best_label():
    onto = builtin_ontology()
    assert candidate_gain({"chair": 0.1, "none": 0.9}, onto, 0.15) == (None, 0.0)
    label, gain = candidate_gain({"table": 0.3, "side_table": 0.3, "none": 0.4}, onto, 0.15)
    assert label == "table" and gain == pytest.approx(np.log(0.6 / 0.4))


# -- generated scenes ---------------------------------------------------------------------------
def _obj(kind, iid, x, y, yaw=0.0, seed=4):
    return dataclasses.replace(place(make_furniture(kind, seed), x, y, yaw), instance_id=iid)


def _mesh_obj(iid, cls, mesh, color):
    lo, hi = mesh.bounds
    t = len(mesh.triangles)
    return SceneObject(
        iid,
        cls,
        cls,
        mesh.vertices,
        np.asarray(mesh.triangles, np.int32),
        np.zeros(t, np.int32),
        ["body"],
        np.tile(np.asarray(color, np.uint8), (t, 1)),
        np.eye(4),
        {"width": float(hi[0] - lo[0]), "depth": float(hi[1] - lo[1]), "height": float(hi[2])},
        OrientedBox(tuple((lo + hi) / 2), tuple(hi - lo), 0.0),
    )


def _scene(name):
    chair = _obj("chair-4leg", 8, 2.0, 1.5)
    if name == "two chairs touching":
        return [_obj("chair-4leg", 8, 1.75, 1.5), _obj("chair-4leg", 9, 2.25, 1.5, seed=5)], 8
    if name == "a chair pushed under a desk":
        return [_obj("desk-panel", 7, 2.0, 2.3), _obj("chair-office", 8, 2.0, 1.95)], 8
    if name == "a cushion on a seat":
        seat = chair.dimensions["seat_height"]
        cushion = M.cushion((0.36, 0.3, 0.1), softness=0.3).translated((2.0, 1.5, seat + 0.06))
        return [chair, _mesh_obj(9, "pillow", cushion, (180, 40, 40))], 8
    if name == "a chair beside a curtain":
        x = np.linspace(0.5, 3.5, 120)
        y = 3.4 + 0.03 * np.sin(2 * np.pi * x / 0.15)
        grid = np.stack(
            [np.stack([x, y, np.zeros_like(x)], 1), np.stack([x, y, np.full_like(x, 2.4)], 1)],
            axis=1,
        )
        curtain = _mesh_obj(9, "curtain", M.thick_surface(grid, 0.008), (200, 190, 160))
        return [_obj("chair-4leg", 8, 2.0, 3.0, yaw=np.pi), curtain], 8
    raise KeyError(name)


SCENES = [
    "two chairs touching",
    "a chair pushed under a desk",
    "a cushion on a seat",
    "a chair beside a curtain",
]


@pytest.mark.slow
@pytest.mark.parametrize("name", SCENES)
def test_the_right_candidate_exists_in_generated_scenes(name):
    furniture, target = _scene(name)
    scan = synthesize(box_room(furniture, size=(4.0, 3.5, 2.6)), sensor="tls", seed=0).cloud
    inst = scan.fields["instance"]
    cfg = Config()
    today = segment(scan, cfg, seed=0)
    voxels, _, _ = propose(today.prepared, today)
    p2v = today.prepared.point_to_voxel
    mine = inst == target

    def iou(vox):
        pts = np.isin(p2v, vox)
        return (pts & mine).sum() / (pts | mine).sum()

    best = max(iou(v) for v in voxels)
    assert best >= 0.5, f"{name}: best candidate IoU {best:.2f}"


@pytest.mark.slow
@pytest.mark.parametrize("name", SCENES)
def test_the_right_candidate_is_selected_in_generated_scenes(name):
    furniture, target = _scene(name)
    scan = synthesize(box_room(furniture, size=(4.0, 3.5, 2.6)), sensor="tls", seed=0).cloud
    inst = scan.fields["instance"]
    onto = builtin_ontology()
    seg, _, _, found, _, cands = recognize(
        scan, Config(), onto, class_priors(onto), seed=0, viewpoint=None, ground=None
    )
    mine = np.flatnonzero(inst == target)
    hits = [
        d
        for d in found
        if d.label == "chair"
        and len(np.intersect1d(d.point_indices, scan.index[mine]))
        / len(np.union1d(d.point_indices, scan.index[mine]))
        >= 0.5
    ]
    assert hits, f"{name}: {[(d.label, len(d.point_indices)) for d in found]}"
    chosen = [k for k, c in enumerate(cands) if c.chosen]
    assert len(chosen) == len(seg)
    assert explain_candidates(cands, chosen)[0].startswith("candidate")


def test_recognition_finds_the_tiny_room():
    result = detect(
        synthesize("tiny", seed=1).cloud,
        config=Config().with_overrides(["detect.proposals=recognition"]),
        jobs=1,
    )
    assert sorted(d.label for d in result.detections) == ["chair", "table"]
    assert "select" in result.timings
    rows = explain(result)
    assert all("beat" in row for row in rows) and any(row["beat"] for row in rows)
    assert all(0.0 <= b["cut"] <= 1.0 for row in rows for b in row["beat"])
    assert sum(c.chosen for c in result.candidates) == len(result.segmentation)
