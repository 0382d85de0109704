"""Curved parts (issue 21): planes that meet along seams with normals turning a little from
one to the next are one surface (``segment.planes.curved_patches``), which the scoring's
parts may take as a plane (``planes.curved``)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _clusters import describe_points
from ontodetect.config import Config
from ontodetect.ontology import ClusterDescription, builtin_ontology, continuations
from ontodetect.ontology._score import score_class
from ontodetect.segment.planes import (
    PATCH_ANGLE,
    Patch,
    curved_patches,
    extract_planes,
    plane_relations,
)


def _bent(turn_deg, strips=6, strip=0.1, width=0.45, z0=0.45, per=300, seed=0):
    """A backrest bent by ``turn_deg`` at each seam between ``strips`` flat strips, rising
    from ``z0``: each strip leans back ``turn_deg`` more than the one below."""
    gen = np.random.default_rng(seed)
    pts, x, z = [], 0.0, z0
    for k in range(strips):
        a = math.radians(90.0 - turn_deg * k)  # from upright, leaning back
        u = gen.uniform(0.0, strip, per)
        pts.append(np.c_[x - u * math.cos(a), gen.uniform(0.0, width, per), z + u * math.sin(a)])
        x, z = x - strip * math.cos(a), z + strip * math.sin(a)
    return np.vstack(pts)


def _seat(z=0.45, depth=0.42, width=0.45, per=900, seed=1):
    gen = np.random.default_rng(seed)
    return np.c_[gen.uniform(0.0, depth, per), gen.uniform(0.0, width, per), np.full(per, z)]


def _patches(pts, threshold=0.004):
    planes = extract_planes(pts, threshold=threshold, max_planes=12, min_points=40, rng=0)
    return planes, curved_patches(pts, planes, plane_relations(pts, planes), rng=0)


def test_a_bent_backrest_is_one_patch_measured_whole():
    pts = _bent(12.0)
    planes, patches = _patches(pts)
    assert len(planes) >= 4  # MSAC cuts it into strips
    (patch,) = patches
    assert isinstance(patch, Patch) and len(patch.members) == len(planes)
    # The patch measures the back: about 0.6 m along its curve, 0.45 m across.
    assert patch.length == pytest.approx(0.56, abs=0.06)
    assert patch.width == pytest.approx(0.45, abs=0.05)
    assert max(p.length for p in planes) < 0.5  # no strip does
    assert patch.num_points == sum(p.num_points for p in planes)
    # The strips' normals turn by 60 deg in all; about the mean they spread by 15-25.
    assert 12.0 < patch.spread < 30.0
    assert 40.0 < patch.tilt < 80.0  # between the lowest strip's 90 and the top's 30


def test_a_seat_and_its_backrest_are_never_one_patch():
    # Upright back on the seat's rear edge, 90 deg: far more than PATCH_ANGLE.
    pts = np.vstack([_seat(), _bent(0.0, strips=4)])
    planes, patches = _patches(pts)
    assert len(planes) == 2 and patches == []


def test_flat_pieces_and_stacked_planes_are_no_patch():
    # One top cut in two by a gap: pieces of one plane (the scoring joins those already).
    gen = np.random.default_rng(2)
    top = np.c_[gen.uniform(0, 1.2, 2000), gen.uniform(0, 0.7, 2000), np.full(2000, 0.72)]
    top = top[np.abs(top[:, 0] - 0.6) > 0.02]
    planes = extract_planes(top, threshold=0.004, max_planes=4, connectivity=0.035, rng=0)
    assert len(planes) >= 2 and all(p.tilt < 1.0 for p in planes)
    assert curved_patches(top, planes, plane_relations(top, planes)) == []
    # An arm 15 cm above a seat, tilted 15 deg: within the angle, but they do not meet.
    arm = _seat(z=0.6, depth=0.5, width=0.1, per=300, seed=3)
    arm[:, 2] += np.tan(np.radians(15.0)) * arm[:, 0]
    pts = np.vstack([_seat(), arm])
    planes, patches = _patches(pts)
    assert len(planes) == 2 and patches == []


@settings(max_examples=15, deadline=None)
@given(turn=st.floats(12.0, PATCH_ANGLE - 2.0), seed=st.integers(0, 1000))
def test_any_gentle_bend_is_one_patch_whatever_the_sampling(turn, seed):
    pts = _bent(turn, strips=4, seed=seed)
    planes, patches = _patches(pts)
    if len(planes) >= 2:
        assert len(patches) == 1
        assert sorted(patches[0].members) == list(range(len(planes)))


def _chair_with_bent_back(curved):
    pts = np.vstack([_seat(), _bent(12.0, z0=0.46)])
    planes = extract_planes(pts, threshold=0.004, max_planes=12, min_points=40, rng=0)
    patches = curved_patches(pts, planes, plane_relations(pts, planes), rng=0) if curved else []
    return planes, patches, describe_points(pts, [*planes, *patches])


def test_a_chair_takes_its_bent_back_whole_and_no_strip_costs_as_clutter():
    chair = builtin_ontology()["chair"]
    planes, _, flat = _chair_with_bent_back(curved=False)
    _, patches, bent = _chair_with_bent_back(curved=True)
    (patch,) = patches
    k = len(planes)  # the patch's index among the scored planes
    # The patch continues its strips and they continue it; it conflicts with them.
    assert set(patch.members) <= continuations(bent)[k]
    assert set(patch.members) <= bent.conflicts[k]
    without = score_class(chair, flat)
    with_patch = score_class(chair, bent)
    assert with_patch.assignment["backrest"] == k
    extra = [c for c in with_patch.constraints if c.feature == "extra_plane"]
    assert extra == []  # every strip is explained by the patch
    assert with_patch.log_likelihood > without.log_likelihood
    # No other part takes a strip of the back the backrest took whole.
    taken = [v for v in with_patch.assignment.values() if v is not None]
    assert not set(taken) & set(patch.members)
    slow = score_class(chair, bent, search_exhaustively=True)
    assert slow.assignment == with_patch.assignment
    assert slow.log_likelihood == with_patch.log_likelihood


def test_the_option_offers_patches_to_the_scoring_only():
    from ontodetect.segment import segment
    from ontodetect.synth import synthesize

    cloud = synthesize("living_room", "rgbd", seed=1, points=50_000).cloud
    flat = ["planes.level_surfaces=false"]  # lying surfaces are patches too
    off = segment(cloud, Config().with_overrides(flat), seed=0, ontology=builtin_ontology())
    on = segment(cloud, Config().with_overrides([*flat, "planes.curved=true"]), seed=0)
    # Same clusters and planes; the patches come on top.
    assert [len(c.voxels) for c in on] == [len(c.voxels) for c in off]
    assert all(len(a.planes) == len(b.planes) for a, b in zip(on, off))
    assert all(c.patches == [] and c.scored_planes == c.planes for c in off)
    with_patches = [c for c in on if c.patches]
    assert with_patches
    for c in with_patches:
        n = len(c.planes) + len(c.patches)
        assert len(c.scored_planes) == n and len(c.scored_relations) == n * (n - 1) // 2
    # The pairs with a patch are measured on top of the planes' own: as if all at once.
    c = with_patches[0]
    whole = plane_relations(np.asarray(c.centers), c.scored_planes)
    assert c.scored_relations == {(r.i, r.j): r for r in whole}


# -- what holds a top up -------------------------------------------------------------------
def _panel(x0, x1, y0, y1, z0, z1, per, gen):
    """An upright rectangle from (x0, y0) to (x1, y1), z0 to z1 high."""
    t = gen.uniform(0.0, 1.0, per)
    return np.c_[x0 + t * (x1 - x0), y0 + t * (y1 - y0), gen.uniform(z0, z1, per)]


def _desk(monitor=False, open_below=True):
    gen = np.random.default_rng(5)
    top = np.c_[gen.uniform(0, 1.2, 2500), gen.uniform(0, 0.6, 2500), np.full(2500, 0.74)]
    parts = [
        top,
        _panel(0.05, 1.15, 0.55, 0.55, 0.3, 0.7, 900, gen),  # modesty panel at the back
        _panel(0.8, 0.8, 0.02, 0.58, 0.0, 0.7, 900, gen),  # pedestal's inner side
        _panel(1.15, 1.15, 0.02, 0.58, 0.0, 0.7, 900, gen),  # pedestal's outer side
    ]
    if monitor:  # rises above the top: not what holds it up
        parts.append(_panel(0.2, 0.6, 0.3, 0.3, 0.76, 1.1, 700, gen))
    pts = np.vstack(parts)
    planes = extract_planes(pts, threshold=0.005, max_planes=8, min_points=100, rng=0)
    rels = {(r.i, r.j): r for r in plane_relations(pts, planes)}
    span = pts.max(axis=0) - pts.min(axis=0)
    # The floor seen under the top (open_below) over 0.6 of its footprint: knee space.
    seen = [0.6 if p.tilt < 5 else float("nan") for p in planes]
    desc = ClusterDescription(
        planes=planes, relations=rels, length=float(span[0]), breadth=float(span[1]),
        height=float(pts[:, 2].max()), bottom=0.0, open_below=seen if open_below else None,
    )  # fmt: skip
    return planes, desc


def _desk_class(supports):
    from ontodetect.ontology import parse_ontology

    text = f"""format: ontodetect.ontology/1
classes:
  desk:
    extra_plane: 0.5
    parts:
      top:
        supports: {str(supports).lower()}
        tilt: {{max: 4, soft: 3}}
        height: [0.6, 0.9]
"""
    return parse_ontology(text, "desk.yaml")["desk"]


def test_a_top_explains_what_holds_it_up_and_not_what_stands_on_it():
    planes, desc = _desk()
    assert len(planes) == 4
    top = next(k for k, p in enumerate(planes) if p.tilt < 5)
    assert desc.below[top] == frozenset(set(range(4)) - {top})  # panel and pedestal
    held = score_class(_desk_class(True), desc)
    bare = score_class(_desk_class(False), desc)
    assert held.assignment == bare.assignment == {"top": top}
    assert not [c for c in held.constraints if c.feature == "extra_plane"]
    extra = [c for c in bare.constraints if c.feature == "extra_plane"]
    assert extra and extra[0].value == 3.0
    assert held.log_likelihood > bare.log_likelihood
    # A monitor on the top rises above it: it still costs.
    planes, desc = _desk(monitor=True)
    top = next(k for k, p in enumerate(planes) if p.tilt < 5)
    screen = next(k for k, p in enumerate(planes) if p.z_max > 1.0)
    assert screen not in desc.below[top]
    held = score_class(_desk_class(True), desc)
    (extra,) = [c for c in held.constraints if c.feature == "extra_plane"]
    assert extra.value == 1.0
    slow = score_class(_desk_class(True), desc, search_exhaustively=True)
    assert slow.assignment == held.assignment and slow.log_likelihood == held.log_likelihood


def test_only_a_top_with_the_floor_seen_under_it_is_held_up():
    # Under a closed box the sides are the box: no floor seen, nothing explained.
    from dataclasses import replace

    planes, desc = _desk()
    top = next(k for k, p in enumerate(planes) if p.tilt < 5)
    closed = replace(
        desc, open_below=[0.1 if k == top else float("nan") for k in range(4)], scene={}
    )
    unknown = replace(desc, open_below=None, scene={})  # not measured (a single view)
    assert desc.below[top] and closed.below[top] == unknown.below[top] == frozenset()
    held = score_class(_desk_class(True), closed)
    assert [c.value for c in held.constraints if c.feature == "extra_plane"] == [3.0]


def test_supports_must_be_true_or_false():
    from ontodetect.errors import InvalidOntologyError
    from ontodetect.ontology import parse_ontology

    text = (
        "format: ontodetect.ontology/1\nclasses:\n  desk:\n    parts:\n      top: {supports: 3}\n"
    )
    with pytest.raises(InvalidOntologyError, match="supports"):
        parse_ontology(text, "desk.yaml")
