"""The room's shape as evidence about P_N: the floor area a scan covers
(``preprocess.floor_area``) and how likely each category makes it
(``ontology.room_area_likelihood``), whole room or one view."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect import detect
from ontodetect.config import Config
from ontodetect.errors import InvalidParameterError
from ontodetect.ontology import (
    builtin_ontology,
    room_area_likelihood,
    room_categories,
    rooms_from_objects,
)
from ontodetect.ontology._places import places_data
from ontodetect.preprocess import floor_area
from ontodetect.synth import synthesize


def _room_points(length, width, *, step=0.05, height=2.5, seed=0):
    """A levelled empty room: floor, four walls up to ``height``, points ``step`` apart."""
    rng = np.random.default_rng(seed)
    xs, ys = np.arange(0, length, step), np.arange(0, width, step)
    zs = np.arange(0, height, step)
    floor = np.array(np.meshgrid(xs, ys)).reshape(2, -1).T
    parts = [np.c_[floor, np.zeros(len(floor))]]
    for x in (0.0, length):
        parts.append(np.array([(x, y, z) for y in ys for z in zs]))
    for y in (0.0, width):
        parts.append(np.array([(x, y, z) for x in xs for z in zs]))
    pts = np.concatenate(parts)
    return pts + rng.normal(0, 0.003, pts.shape)


def test_floor_area_of_an_empty_room():
    area = floor_area(_room_points(4.0, 3.0))
    # Cells the walls fall in count too: at most one cell's band around the room.
    assert 12.0 <= area <= (4.0 + 0.2) * (3.0 + 0.2)


def test_floor_hidden_under_furniture_and_small_holes_count():
    pts = _room_points(4.0, 3.0)
    # A 1.5 x 0.8 m bed hides the floor under it, and the scan has a 15 cm hole.
    under_bed = (pts[:, 2] < 0.01) & (pts[:, 0] > 1.0) & (pts[:, 0] < 2.5) & (pts[:, 1] < 0.8)
    hole = (pts[:, 2] < 0.01) & (np.hypot(pts[:, 0] - 3.0, pts[:, 1] - 2.0) < 0.15)
    bed = np.array(
        [(x, y, 0.5) for x in np.arange(1.0, 2.5, 0.05) for y in np.arange(0, 0.8, 0.05)]
    )
    cut = np.concatenate([pts[~(under_bed | hole)], bed])
    assert floor_area(cut) == pytest.approx(floor_area(pts), rel=0.02)


def test_points_above_two_metres_do_not_widen_the_floor():
    pts = _room_points(3.0, 2.0)
    lamp = np.array([(x, 5.0, 2.4) for x in np.arange(0, 3, 0.05)])  # out over a corridor
    assert floor_area(np.concatenate([pts, lamp])) == floor_area(pts)
    assert floor_area(np.zeros((0, 3))) == 0.0


@settings(max_examples=20, deadline=None)
@given(
    st.floats(1.5, 8.0),
    st.floats(1.5, 6.0),
    st.floats(-math.pi, math.pi),
    st.floats(-1e3, 1e3),
)
def test_floor_area_is_the_rectangle_whatever_its_turn_and_place(length, width, turn, shift):
    pts = _room_points(length, width, step=0.04)
    c, s = math.cos(turn), math.sin(turn)
    moved = pts @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]]) + [shift, -shift, 0]
    area = floor_area(moved)
    # The grid's cells along the edges: at most a cell's band around the perimeter.
    assert abs(area - length * width) <= 2 * (length + width) * 0.1 + 0.05


def test_areas_cover_every_category_with_a_median_below_its_95th_percentile():
    areas = places_data()["areas"]
    assert set(areas) == set(room_categories())
    assert all(0 < a["median"] < a["p95"] for a in areas.values())


def test_a_whole_room_scan_bounds_the_room_from_above():
    """A fused scan covers at least its room: 6 m² is no classroom, 60 m² (a flat, an
    open-plan floor) may hold any room up to that size."""
    small, large = room_area_likelihood(6.0), room_area_likelihood(60.0)
    assert set(small) == set(room_categories()) and max(small.values()) == 1.0
    assert small["bathroom"] > 0.5 and small["classroom"] < 1e-6
    assert min(large["bathroom"], large["living_room"], large["classroom"]) > 0.3
    assert large["airport_terminal"] < 0.01


def test_one_view_rules_out_small_rooms_only():
    """A frame sees a share of the floor: 6 m² may be a corner of a classroom, 60 m² is
    no bathroom."""
    small = room_area_likelihood(6.0, whole_room=False)
    large = room_area_likelihood(60.0, whole_room=False)
    assert small["classroom"] > 0.05
    assert large["bathroom"] < 1e-3 * large["classroom"]


@settings(max_examples=30, deadline=None)
@given(st.floats(1.0, 100.0), st.floats(1.01, 2.5))
def test_a_larger_view_never_favours_the_smaller_room(area, factor):
    """Seeing more floor moves belief from bathrooms towards classrooms, never back (up to
    250 m²: far beyond both, a whole-room log-normal's wider tail wins, and neither
    category is likely then)."""
    for whole in (True, False):
        a = room_area_likelihood(area, whole_room=whole)
        b = room_area_likelihood(area * factor, whole_room=whole)
        ratio_a = a["classroom"] / max(a["bathroom"], 1e-300)
        ratio_b = b["classroom"] / max(b["bathroom"], 1e-300)
        assert ratio_b >= ratio_a * (1 - 1e-9)


def test_area_must_be_positive():
    with pytest.raises(InvalidParameterError, match="area"):
        room_area_likelihood(0.0)


def test_shape_is_one_more_factor_of_the_room_estimate():
    onto = builtin_ontology()
    found = [{"toilet": 0.5}]
    alone = rooms_from_objects(found, onto)
    small = rooms_from_objects(found, onto, shape=room_area_likelihood(5.0))
    assert small["bathroom"] > alone["bathroom"]
    # A large scan says little about the rooms it may hold.
    large = rooms_from_objects(found, onto, shape=room_area_likelihood(80.0))
    assert large["bathroom"] == pytest.approx(alone["bathroom"], rel=0.3)
    # One view of 58 m² with nothing found: the large rooms, no bathroom.
    only = rooms_from_objects([], onto, shape=room_area_likelihood(58.0, whole_room=False))
    assert only["bathroom"] < 1e-3 < only["classroom"]


def test_the_room_shape_is_off_by_default():
    assert Config().detect.room_shape is False


@pytest.mark.slow
def test_detect_records_the_floor_area_it_used():
    """A bathroom walked around with an RGB-D camera: its floor area is measured, and with
    its WC and basin it makes the room a bathroom."""
    scan = synthesize("bathroom", "rgbd", seed=0, points=40_000)
    config = Config().with_overrides(["detect.votes=1", "detect.room_shape=true"])
    result = detect(scan.cloud, config=config, seed=0)
    env = result.environment
    assert env["source"] == "scan" and env["whole_room"] is True
    length, width = scan.scene.size[:2]
    assert env["floor_area"] == pytest.approx(length * width, rel=0.25)
    assert max(env["rooms"], key=env["rooms"].get) == "bathroom"


def test_a_found_object_is_evidence_by_every_class_of_its_label():
    """A basin and a sink are one thing described two ways (both labelled sink), as are a
    table and a side table: the room estimate weighs the label, not the class the labelling
    happened to pick, so a second class of a label cannot dilute its evidence."""
    from ontodetect.labeling import LabelChoice
    from ontodetect.ontology import ClusterScores, builtin_ontology, rooms_from_objects
    from ontodetect.pipeline._detect import _found_objects

    onto = builtin_ontology()

    def scored(name, probs):
        choice = LabelChoice(onto[name].label, {}, extra={"class": name})
        return choice, ClusterScores({}, probs, name)

    sink = scored("basin", {"basin": 0.5, "sink": 0.3, "table": 0.1, "none": 0.1})
    table = scored("table", {"table": 0.5, "side_table": 0.3, "chair": 0.1, "none": 0.1})
    unlabelled = (LabelChoice(None, {}), ClusterScores({}, {"none": 1.0}, "none"))
    found = _found_objects(*zip(sink, table, unlabelled, strict=True), onto)
    assert found == [{"basin": 0.5, "sink": 0.3}, {"table": 0.5, "side_table": 0.3}]
    both = rooms_from_objects(found[:1], onto)["bathroom"]
    assert both > rooms_from_objects([{"basin": 0.5}], onto)["bathroom"]
