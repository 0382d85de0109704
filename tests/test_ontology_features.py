"""The feature registry: features found by name, one call to add one."""

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect.errors import InvalidOntologyError
from ontodetect.ontology import (
    CLUSTER_FEATURES,
    PART_FEATURES,
    RELATION_FEATURES,
    Feature,
    builtin_ontology,
    feature_registry,
    parse_ontology,
    register_feature,
    score_class,
    sigma_floor,
)
from ontodetect.ontology._features import FEATURES
from test_ontology import P, R, cluster


@pytest.fixture
def slope():
    """A part feature registered for one test and removed after it."""
    f = register_feature(
        Feature("slope", "part", "Or", "tilt again (degrees)", 1.5, plane=lambda p: p.tilt)
    )
    yield f
    del FEATURES["part"]["slope"]


def test_every_scope_lists_its_features():
    assert set(PART_FEATURES) == set(feature_registry("part"))
    assert PART_FEATURES["tilt"] == "Or" and PART_FEATURES["open_below"] == "Pr"
    assert "gap" in RELATION_FEATURES and "rise" in CLUSTER_FEATURES
    assert feature_registry()["cluster"]["height"].log_factor is not None
    assert feature_registry("part")["open_below"].scene


def test_sigma_floors_are_those_calibration_used():
    """The absolute floors calibration kept beside it (evaluation._calibrate.ABS_SIGMA_FLOOR
    on 2026-11-24) are the registry's, with those of the features added since (``wall_gap``:
    the voxel's 2 cm; ``span``: a share, as ``fill``), and only these features have one."""
    floors = {
        "tilt": 1.0,
        "angle": 2.0,
        "height": 0.02,
        "top": 0.02,
        "bottom": 0.02,
        "gap": 0.02,
        "distance": 0.01,
        "length": 0.03,
        "width": 0.03,
        "breadth": 0.03,
        "area": 0.01,
        "spread": 1.0,
        "fill": 0.03,
        "open_below": 0.03,
        "seen_below": 0.03,
        "covered": 0.03,
        "sunk": 0.03,
        "runs_on": 0.03,
        "behind": 0.02,
        "over": 0.02,
        "aside": 0.02,
        "across": 1.0,
        "span": 0.03,
        "overlap": 0.03,
        "rise": 0.02,
        "planes": 0.5,
        "wall_gap": 0.02,
    }
    for name, floor in floors.items():
        assert sigma_floor(name) == floor, name
    names = {n for table in FEATURES.values() for n in table}
    assert {n for n in names if sigma_floor(n) > 0} == set(floors)
    assert sigma_floor("density") == sigma_floor("points") == sigma_floor("nothing") == 0.0


def test_a_registered_feature_is_accepted_by_the_schema_and_scored(slope):
    text = """
format: ontodetect.ontology/1
classes:
  plank:
    parts:
      board: {slope: {max: 5}}
"""
    plank = parse_ontology(text)["plank"]
    flat = score_class(plank, cluster([P(0.0, 0.5, 1.0, 0.3)], length=1.0))
    steep = score_class(plank, cluster([P(40.0, 0.5, 1.0, 0.3)], length=1.0))
    (cv,) = [c for c in flat.constraints if c.feature == "slope"]
    assert cv.group == "Or" and cv.value == 0.0 and cv.factor == 1.0
    assert steep.log_likelihood < flat.log_likelihood - 1.0
    assert sigma_floor("slope") == 1.5


def test_an_unregistered_feature_is_an_error_naming_the_key():
    with pytest.raises(InvalidOntologyError, match=r"classes\.plank\.parts\.board\.slope"):
        parse_ontology(
            "format: ontodetect.ontology/1\nclasses:\n  plank:\n"
            "    parts:\n      board: {slope: {max: 5}}\n",
            "plank.yaml",
        )


def test_a_scene_feature_reads_the_description_and_costs_nothing_when_absent():
    register_feature(Feature("wet", "part", "De", "share wet", scene=True))
    try:
        o = parse_ontology(
            "format: ontodetect.ontology/1\nclasses:\n  dry:\n"
            "    parts:\n      top: {wet: {max: 0.1}}\n"
        )
        desc = cluster([P(0.0, 0.7, 1.0, 0.6)], length=1.0)
        unknown = score_class(o["dry"], desc)
        wet = score_class(o["dry"], replace(desc, scene={"wet": [0.9]}))
        assert unknown.assignment["top"] == 0 and unknown.factors["top"]["De"] == 1.0
        assert wet.log_likelihood < unknown.log_likelihood - 1.0
    finally:
        del FEATURES["part"]["wet"]


def test_a_part_rise_is_measured_from_the_plane_the_part_takes():
    """``rise`` of a part is the cluster's height above the plane it takes: a seat under an
    armchair's arms has them rising above it, the arms' tops have nothing above them."""
    o = parse_ontology(
        "format: ontodetect.ontology/1\nclasses:\n  box:\n"
        "    parts:\n      top: {tilt: {max: 5}, rise: {max: 0.06, soft: 0.05}}\n"
    )
    seat, arms = P(0.0, 0.42, 0.55, 0.5), P(0.0, 0.62, 0.85, 0.2, cy=0.3)
    desc = cluster([seat, arms], length=0.9)
    assert FEATURES["part"]["rise"].in_cluster(desc, 0) == pytest.approx(0.2)
    assert FEATURES["part"]["rise"].in_cluster(desc, 1) == 0.0
    best = score_class(o["box"], desc)
    assert best.assignment["top"] == 1
    only_seat = score_class(o["box"], replace(desc, planes=[seat, arms][:1], height=0.64))
    assert only_seat.assignment["top"] is None  # a seat with arms above it is no top


@dataclass(frozen=True)
class Facing(P):  # an upright plane facing +y, as `behind` and `aside` read it
    normal: tuple = (0.0, 1.0, 0.0)


def test_behind_measures_along_a_backrest_s_outward_normal():
    """An armrest in front of the backrest is negative, a cistern top behind it positive; a
    level plane has no front and back."""

    back = Facing(85.0, 0.7, 0.45, 0.4, cy=0.2)
    arm, cistern = P(0.0, 0.62, 0.6, 0.15, cy=-0.1), P(0.0, 0.76, 0.36, 0.2, cy=0.3)
    desc = cluster([back, arm, cistern], length=0.8)
    behind = FEATURES["relation"]["behind"].relation
    assert behind(desc, 0, 1) == pytest.approx(-0.3)
    assert behind(desc, 0, 2) == pytest.approx(0.1)
    level = cluster([Facing(0.0, 0.5, 0.4, 0.4, normal=(0.0, 0.0, 1.0)), arm], length=0.5)
    assert behind(level, 0, 1) == 0.0


def test_aside_measures_across_the_upright_plane_whichever_comes_first():
    """A backrest centred behind its seat is 0 aside; a headboard's end beside a
    nightstand's top is its offset along the headboard; two level planes have no upright."""

    seat = P(0.0, 0.45, 0.45, 0.42, cx=0.3, cy=0.0)
    back = Facing(85.0, 0.7, 0.45, 0.4, cx=0.3, cy=0.22)
    headboard_end = Facing(87.0, 0.6, 0.3, 0.3, cx=0.65, cy=0.22)
    desc = cluster([seat, back, headboard_end], length=0.8)
    aside = FEATURES["relation"]["aside"].relation
    assert aside(desc, 0, 1) == pytest.approx(0.0)
    assert aside(desc, 1, 0) == pytest.approx(0.0)
    assert aside(desc, 0, 2) == pytest.approx(0.35)
    assert aside(desc, 2, 0) == pytest.approx(0.35)
    level = cluster([seat, P(0.0, 0.7, 0.3, 0.3, cx=1.0)], length=1.0)
    assert aside(level, 0, 1) == 0.0


@dataclass(frozen=True)
class Axed(P):  # a plane with its normal and its in-plane axes, as `across` reads them
    normal: tuple = (0.0, 0.0, 1.0)
    axes: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))


def test_across_is_the_angle_between_a_seat_s_long_axis_and_the_back_s_run():
    """A sofa's back runs along its seat (0); a bed's headboard stands across its
    mattress's end (90); a square cushion, or planes given without axes, are not measured."""
    seat = Axed(1.0, 0.42, 1.8, 0.6)  # long along x
    back = Axed(80.0, 0.7, 1.8, 0.4, cy=0.35, normal=(0.0, 0.98, 0.17))  # runs along x
    board = Axed(88.0, 0.8, 1.4, 0.5, cx=1.0, normal=(1.0, 0.0, 0.0))  # runs along y
    desc = cluster([seat, back, board], length=2.0)
    across = FEATURES["relation"]["across"].relation
    assert across(desc, 0, 1) == pytest.approx(0.0, abs=1e-6)
    assert across(desc, 1, 0) == pytest.approx(0.0, abs=1e-6)
    assert across(desc, 0, 2) == pytest.approx(90.0)
    turned = Axed(1.0, 0.42, 1.8, 0.6, axes=((0.6, 0.8, 0.0), (-0.8, 0.6, 0.0)))
    assert across(cluster([turned, board], length=2.0), 0, 1) == pytest.approx(36.87, abs=0.01)
    assert math.isnan(across(cluster([P(0.0, 0.5, 1.0, 0.3), board], length=1.0), 0, 1))
    cushion = Axed(1.0, 0.42, 0.62, 0.58)  # about square: no long axis to measure along
    assert math.isnan(across(cluster([cushion, board], length=1.0), 0, 1))


def test_a_cabinet_s_front_runs_along_its_top_not_across_its_end():
    """A long top on a closed panel along it is a sideboard; the same top on a panel
    across its end is a desk on panel legs, which the built-in cabinet costs."""
    top = Axed(1.0, 0.74, 1.2, 0.6)  # 1.2 m along x, 0.6 m deep
    along = Axed(89.0, 0.37, 1.2, 0.72, cy=0.3, normal=(0.0, 1.0, 0.0))  # a front, along x
    end = Axed(89.0, 0.37, 0.6, 0.72, cx=0.6, normal=(1.0, 0.0, 0.0))  # an end panel, along y
    cabinet = builtin_ontology()["cabinet"]
    touching = {(0, 1): R(angle=88.0, distance=0.01)}
    sideboard = score_class(cabinet, cluster([top, along], touching, length=1.2, breadth=0.6))
    desk = score_class(cabinet, cluster([top, end], touching, length=1.2, breadth=0.6))
    assert sideboard.assignment == {"top": 0, "front": 1}
    assert desk.likelihood < 0.2 * sideboard.likelihood


#: A 1.2 x 0.6 m desk or sideboard top at 0.74 m, a front spanning it, and a drawer
#: pedestal's front along it, 0.42 m wide and taller than wide.
DESK_TOP = Axed(1.0, 0.74, 1.2, 0.6)
SIDEBOARD_FRONT = Axed(89.0, 0.37, 1.2, 0.72, cy=0.3, normal=(0.0, 1.0, 0.0),
                       axes=((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)))  # fmt: skip
PEDESTAL_FRONT = Axed(89.0, 0.37, 0.72, 0.42, cx=0.39, cy=0.3, normal=(0.0, 1.0, 0.0),
                      axes=((0.0, 0.0, 1.0), (1.0, 0.0, 0.0)))  # fmt: skip


def test_span_is_the_share_of_a_top_a_front_spans_along_its_run():
    """A sideboard's front spans its top (1); a desk's drawer pedestal, 0.42 m of a 1.2 m
    top along it, a third; a turned top is measured along the front's run; two level or two
    upright planes, or planes without axes, are not measured."""
    top, front, pedestal = DESK_TOP, SIDEBOARD_FRONT, PEDESTAL_FRONT
    span = FEATURES["relation"]["span"].relation
    assert span(cluster([top, front], length=1.2), 0, 1) == pytest.approx(1.0)
    assert span(cluster([top, front], length=1.2), 1, 0) == pytest.approx(1.0)
    assert span(cluster([top, pedestal], length=1.2), 0, 1) == pytest.approx(0.35)
    # a top turned by 90 degrees shows its 0.6 m depth along the front's run
    turned = Axed(1.0, 0.74, 1.2, 0.6, axes=((0.0, 1.0, 0.0), (-1.0, 0.0, 0.0)))
    assert span(cluster([turned, front], length=1.2), 0, 1) == pytest.approx(2.0)
    assert math.isnan(span(cluster([top, Axed(2.0, 0.4, 1.0, 0.5)], length=1.2), 0, 1))
    assert math.isnan(span(cluster([front, pedestal], length=1.2), 0, 1))
    assert math.isnan(span(cluster([P(0.0, 0.74, 1.2, 0.6), front], length=1.2), 0, 1))


def test_a_desk_on_a_drawer_pedestal_is_no_cabinet():
    """The built-in cabinet's front spans its top (catalogue carcasses); a pedestal's
    front along a desk's top, a third of it, costs the cabinet reading, and the table's
    reading of the desk wins."""
    onto = builtin_ontology()
    cabinet = onto["cabinet"]
    touching = {(0, 1): R(angle=88.0, distance=0.01)}
    sideboard = score_class(
        cabinet, cluster([DESK_TOP, SIDEBOARD_FRONT], touching, length=1.2, breadth=0.6)
    )
    desk_cluster = cluster([DESK_TOP, PEDESTAL_FRONT], touching, length=1.2, breadth=0.6)
    desk = score_class(cabinet, desk_cluster)
    assert sideboard.assignment == {"top": 0, "front": 1}
    assert desk.likelihood < 0.4 * sideboard.likelihood
    assert score_class(onto["table"], desk_cluster).likelihood > desk.likelihood


def test_a_chair_s_back_rises_above_its_arms():
    """Armrests stand 20-25 cm over the seat and the back 36 cm and more: a level board
    as high as the top of the panel behind it (a hutch's shelf over its back panel, a
    cabinet's top over its front) is no armrest."""

    seat = P(1.0, 0.42, 0.5, 0.48)
    back = Facing(80.0, 0.58, 0.5, 0.3, cy=0.26)  # up to 0.73 m
    arm = P(0.0, 0.6, 0.6, 0.12, cx=0.3)
    board = P(0.0, 0.71, 0.6, 0.12, cx=0.3)  # as high as the back's top
    near = {
        (0, 1): R(angle=80.0, distance=0.02),
        (0, 2): R(angle=1.0, distance=0.05),
        (1, 2): R(angle=80.0, distance=0.03),
    }
    over = FEATURES["relation"]["over"].relation
    assert over(cluster([seat, back, arm], length=0.8), 1, 2) == pytest.approx(0.62 - 0.73)
    assert over(cluster([seat, back, board], length=0.8), 1, 2) == pytest.approx(0.0)
    chair = builtin_ontology()["chair"]
    armchair = score_class(chair, cluster([seat, back, arm], near, length=0.8))
    boarded = score_class(chair, cluster([seat, back, board], near, length=0.8))
    assert armchair.assignment["arm"] == 2
    assert boarded.assignment["arm"] is None and boarded.assignment["other_arm"] is None
    assert boarded.likelihood < 0.8 * armchair.likelihood


def test_registering_twice_or_without_a_measure_is_refused():
    with pytest.raises(ValueError, match="registered"):
        register_feature(Feature("tilt", "part", "Or", "again", plane=lambda p: 0.0))
    with pytest.raises(ValueError, match="needs a measure"):
        Feature("x", "cluster", "cluster", "nothing")
    with pytest.raises(ValueError, match="scope"):
        Feature("x", "room", "cluster", "nothing", cluster=lambda d: 0.0)
    two = cluster([P(0.0, 0.5, 1.0, 0.3), P(90.0, 0.8, 1.0, 0.3)], length=1.0)
    assert math.isinf(FEATURES["relation"]["distance"].relation(two, 0, 1))  # no relation
    assert np.isfinite(sigma_floor("tilt"))


@settings(max_examples=300, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.floats(-1e6, 50, allow_nan=False),
            st.just(-math.inf),
            st.sampled_from([-3.5, 0.0, 2.25]),  # ties of the largest term
        ),
        min_size=1,
        max_size=20,
    )
)
def test_the_censored_measures_sum_is_scipys_to_the_last_bit(values):
    """``_logsumexp`` is ``scipy.special.logsumexp`` without its dispatch: the same value,
    bit for bit, including ties of the largest term and terms of -inf."""
    from scipy.special import logsumexp

    from ontodetect.ontology._features import _logsumexp

    a = np.asarray(values, dtype=np.float64)
    with np.errstate(all="ignore"):
        expected = float(logsumexp(a))
    got = _logsumexp(a)
    assert got == expected or (math.isnan(got) and math.isnan(expected))
