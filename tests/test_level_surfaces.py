"""Lying surfaces (issue 21, beds found whole): level planes of a cluster that meet, their
centroids a pillow's step apart at most, are one surface (``segment.planes.level_surfaces``),
which the scoring's parts may take as a plane (``planes.level_surfaces``)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _clusters import describe_points
from ontodetect.config import Config
from ontodetect.ontology import builtin_ontology
from ontodetect.ontology._score import score_class
from ontodetect.segment.planes import (
    LEVEL_STEP,
    Patch,
    extract_planes,
    level_surfaces,
    plane_relations,
)


def _sheet(x0, x1, y0, y1, z, per, gen):
    return np.c_[gen.uniform(x0, x1, per), gen.uniform(y0, y1, per), np.full(per, z)]


def _bed(seed=0):
    """A made double bed 2.0 x 1.4 m: the duvet at 0.50 m over 1.5 m of it, the pillows
    6 cm proud of it at the head, a headboard to 1.0 m behind them (EN 1725 / catalogue)."""
    gen = np.random.default_rng(seed)
    duvet = _sheet(0.0, 1.5, 0.0, 1.4, 0.50, 4000, gen)
    pillows = _sheet(1.5, 1.95, 0.05, 1.35, 0.56, 1200, gen)
    y = gen.uniform(0.0, 1.4, 1500)
    z = gen.uniform(0.3, 1.0, 1500)
    head = np.c_[np.full(1500, 2.0), y, z]
    return np.vstack([duvet, pillows, head])


def _planes(pts, threshold=0.01):
    return extract_planes(pts, threshold=threshold, max_planes=6, min_points=40, rng=0)


def _description(pts, surfaces_on):
    planes = _planes(pts)
    rels = plane_relations(pts, planes)
    surfaces = level_surfaces(pts, planes, rels, rng=0) if surfaces_on else []
    return planes, surfaces, describe_points(pts, [*planes, *surfaces])


def test_a_made_bed_is_one_lying_surface_measured_whole():
    pts = _bed()
    planes, surfaces, _ = _description(pts, surfaces_on=True)
    level = [p for p in planes if p.tilt < 5.0]
    assert len(level) == 2  # MSAC: the duvet, the pillows
    assert max(p.length for p in level) < 1.6  # neither is a mattress's length
    (surface,) = surfaces
    assert isinstance(surface, Patch)
    assert sorted(surface.members) == sorted(planes.index(p) for p in level)
    assert surface.length == pytest.approx(1.95, abs=0.08)
    assert surface.width == pytest.approx(1.4, abs=0.08)
    assert surface.height == pytest.approx(0.515, abs=0.02)
    assert surface.tilt < 2.0
    assert surface.num_points == sum(p.num_points for p in level)


def test_the_bed_takes_its_whole_surface_and_scores_as_a_bed():
    onto = builtin_ontology()
    bed, sofa = onto["bed"], onto["sofa"]
    _, _, pieces = _description(_bed(), surfaces_on=False)
    planes, (_,), whole = _description(_bed(), surfaces_on=True)
    before, after = score_class(bed, pieces), score_class(bed, whole)
    assert after.assignment["mattress"] == len(planes)  # the surface, not a piece
    assert after.log_likelihood > before.log_likelihood + 0.5
    # It is no sofa's seat for all that: the bed gains more than the sofa does.
    gain_sofa = score_class(sofa, whole).log_likelihood - score_class(sofa, pieces).log_likelihood
    assert after.log_likelihood - before.log_likelihood > gain_sofa
    slow = score_class(bed, whole, search_exhaustively=True)
    assert slow.assignment == after.assignment


def test_only_a_part_that_says_lying_takes_a_lying_surface():
    onto = builtin_ontology()
    planes, _, whole = _description(_bed(), surfaces_on=True)
    assert onto["bed"].parts[0].lying
    for name in ("sofa", "table", "chair", "cabinet"):
        cls = onto[name]
        assert not any(part.lying for part in cls.parts)
        # The surface is no candidate for them: the same score as without it.
        _, _, pieces = _description(_bed(), surfaces_on=False)
        with_surface, without = score_class(cls, whole), score_class(cls, pieces)
        assert len(planes) not in with_surface.assignment.values()
        assert with_surface.log_likelihood == pytest.approx(without.log_likelihood)


def test_lying_must_be_true_or_false():
    from ontodetect.errors import InvalidOntologyError
    from ontodetect.ontology import parse_ontology

    text = "format: ontodetect.ontology/1\nclasses:\n  bed:\n    parts:\n      top: {lying: 1}\n"
    with pytest.raises(InvalidOntologyError, match="lying"):
        parse_ontology(text, "bed.yaml")
    ok = text.replace("lying: 1", "lying: true, height: [0.3, 0.6]")
    assert parse_ontology(ok, "bed.yaml")["bed"].parts[0].lying


def test_a_seat_its_arms_and_a_top_above_it_never_join():
    gen = np.random.default_rng(3)
    seat = _sheet(0.0, 0.45, 0.0, 0.45, 0.45, 900, gen)
    arm = _sheet(0.0, 0.45, 0.46, 0.56, 0.66, 300, gen)  # 21 cm above (EN 1335-1)
    top = _sheet(-0.2, 1.0, 0.6, 1.4, 0.74, 2000, gen)  # a desk's top beside it
    pts = np.vstack([seat, arm, top])
    planes = _planes(pts, threshold=0.004)
    assert len(planes) == 3
    assert level_surfaces(pts, planes, plane_relations(pts, planes)) == []


def test_a_backrest_never_joins_the_seat():
    gen = np.random.default_rng(4)
    seat = _sheet(0.0, 0.45, 0.0, 0.45, 0.45, 900, gen)
    back = np.c_[np.full(600, 0.46), gen.uniform(0, 0.45, 600), gen.uniform(0.47, 0.9, 600)]
    pts = np.vstack([seat, back])
    planes = _planes(pts, threshold=0.004)
    assert level_surfaces(pts, planes, plane_relations(pts, planes)) == []


@settings(max_examples=20, deadline=None)
@given(
    step=st.floats(0.02, 0.12),
    turn=st.floats(-math.pi, math.pi),
    shift=st.tuples(st.floats(-50, 50), st.floats(-50, 50)),
    seed=st.integers(0, 1000),
)
def test_two_cushions_join_up_to_a_pillows_step_however_placed(step, turn, shift, seed):
    gen = np.random.default_rng(seed)
    left = _sheet(0.0, 0.6, 0.0, 0.6, 0.45, 1000, gen)
    right = _sheet(0.62, 1.2, 0.0, 0.6, 0.45 + step, 1000, gen)
    pts = np.vstack([left, right])
    c, s = math.cos(turn), math.sin(turn)
    pts[:, :2] = pts[:, :2] @ np.array([[c, s], [-s, c]]) + np.asarray(shift)
    planes = _planes(pts, threshold=0.004)
    level = [k for k, p in enumerate(planes) if p.tilt <= 10.0]
    surfaces = level_surfaces(pts, planes, plane_relations(pts, planes), rng=0)
    if step <= LEVEL_STEP - 0.005:
        (surface,) = surfaces
        assert list(surface.members) == level
        assert surface.length == pytest.approx(1.2, abs=0.05)
    elif step > LEVEL_STEP + 0.005:
        assert all(s.length < 0.7 for s in surfaces)  # no surface spans both cushions


def test_parameters_are_checked():
    pts = _bed()
    planes = _planes(pts)
    rels = plane_relations(pts, planes)
    with pytest.raises(ValueError, match="max_tilt"):
        level_surfaces(pts, planes, rels, max_tilt=0.0)
    with pytest.raises(ValueError, match="max_step"):
        level_surfaces(pts, planes, rels, max_step=-0.1)


def test_the_option_offers_surfaces_to_the_scoring_only():
    from ontodetect.segment import segment
    from ontodetect.synth import synthesize

    cloud = synthesize("living_room", "rgbd", seed=1, points=50_000).cloud
    off = segment(cloud, Config().with_overrides(["planes.level_surfaces=false"]), seed=0)
    on = segment(cloud, Config(), seed=0, ontology=builtin_ontology())  # on by default
    assert [len(c.voxels) for c in on] == [len(c.voxels) for c in off]
    assert all(len(a.planes) == len(b.planes) for a, b in zip(on, off))
    assert all(c.patches == [] for c in off)
    with_surfaces = [c for c in on if c.patches]
    assert with_surfaces
    for c in with_surfaces:
        assert all(p.kind == "lying" for p in c.patches)
        assert all(p.tilt <= 10.0 and len(p.members) >= 2 for p in c.patches)
        n = len(c.scored_planes)
        assert len(c.scored_relations) == n * (n - 1) // 2
