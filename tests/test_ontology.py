"""Ontology scoring on hand-made clusters with known answers."""

import math
import re
from dataclasses import dataclass, replace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ontodetect.errors import InvalidOntologyError, InvalidParameterError
from ontodetect.ontology import (
    NONE,
    ClusterDescription,
    Gaussian,
    builtin_ontology,
    class_priors,
    cluster_log_factor,
    continuations,
    missing_factor,
    parse_ontology,
    room_distribution,
    score_class,
    score_cluster,
)


@dataclass(frozen=True)
class P:  # the plane features the scoring reads
    tilt: float
    height: float
    length: float
    width: float
    cx: float = 0.0
    cy: float = 0.0
    fill: float = 0.9
    thickness: float = 0.02

    @property
    def centroid(self):
        return np.array([self.cx, self.cy, self.height])

    @property
    def area(self):
        return self.fill * self.length * self.width

    @property
    def z_min(self):
        return self.height - (self.width / 2 if self.tilt > 45 else self.thickness)

    @property
    def z_max(self):
        return self.height + (self.width / 2 if self.tilt > 45 else self.thickness)

    density = 2500.0
    num_points = 500
    normal = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class R:
    angle: float
    distance: float
    xy_overlap: float = 0.0


def cluster(planes, relations=None, *, length, breadth=None, height=None):
    top = max(p.z_max for p in planes)
    return ClusterDescription(
        planes=planes,
        relations=relations or {},
        length=length,
        breadth=breadth or length * 0.9,
        height=height or top,
        bottom=0.0,
    )


def chair():
    seat = P(tilt=2, height=0.46, length=0.45, width=0.42)
    back = P(tilt=85, height=0.72, length=0.44, width=0.4, cy=0.2)
    return cluster([seat, back], {(0, 1): R(angle=87, distance=0.02)}, length=0.55)


def stool():
    return cluster([P(tilt=1, height=0.62, length=0.35, width=0.33)], length=0.38)


def side_table():
    return cluster([P(tilt=1, height=0.6, length=0.55, width=0.5)], length=0.58)


def ottoman():
    return cluster([P(tilt=2, height=0.42, length=0.6, width=0.48)], length=0.62)


def bench():
    return cluster([P(tilt=1, height=0.45, length=1.4, width=0.38)], length=1.45, breadth=0.4)


def high_table():
    return cluster([P(tilt=1, height=0.74, length=1.4, width=0.8)], length=1.45)


def sofa():
    seat = P(tilt=3, height=0.42, length=1.9, width=0.6)
    back = P(tilt=75, height=0.7, length=1.9, width=0.35, cy=0.35)
    return cluster([seat, back], {(0, 1): R(angle=78, distance=0.05)}, length=2.1, breadth=0.9)


@pytest.mark.parametrize(
    ("make", "expected"),
    [
        (chair, "chair"),
        (stool, "stool"),
        (high_table, "table"),
        (sofa, "sofa"),
        (side_table, "side_table"),
        (ottoman, "ottoman"),
        (bench, "bench"),
    ],
)
def test_hand_made_clusters_get_their_class(make, expected):
    scores = score_cluster(make(), builtin_ontology())
    assert scores.best == expected
    assert scores.probabilities[expected] > 0.5
    assert math.isclose(sum(scores.probabilities.values()), 1.0)


def test_stool_is_not_a_chair_and_table_is_not_a_chair():
    o = builtin_ontology()
    assert score_cluster(stool(), o).probabilities["chair"] < 0.2
    assert score_cluster(high_table(), o).probabilities["chair"] < 0.05


def test_small_tops_by_height_and_size():
    """A bare top 55 cm across at 60 cm is a side table (reported as "table"), a 35 cm one a
    stool; a 60 cm seat at 42 cm is an ottoman; none of them a chair."""
    o = builtin_ontology()
    assert o["side_table"].label == "table" and o["side_table"].detect
    assert not o["ottoman"].detect and not o["stool"].detect
    for make in (side_table, stool, ottoman):
        assert score_cluster(make(), o).probabilities["chair"] < 0.15
    lower = score_cluster(cluster([P(tilt=1, height=0.45, length=0.55, width=0.5)], length=0.58), o)
    assert lower.probabilities["side_table"] < 0.1  # below a side table's height


def test_ottoman_stands_on_the_floor_and_bench_seats_several():
    """An ottoman's sides reach the floor: the same 60 cm seat floating at 42 cm with nothing
    seen below it (a chair whose legs and backrest went unseen) is no ottoman. A bench seats
    two or more: a 1.4 m seat is one, a 60 cm seat fits it ten times worse."""
    o = builtin_ontology()
    standing = score_cluster(ottoman(), o).probabilities
    floating = score_cluster(replace(ottoman(), bottom=0.37), o).probabilities
    assert standing["ottoman"] > 0.5
    assert floating["ottoman"] < 0.01
    assert floating["chair"] > 2 * standing["chair"]
    short = cluster([P(tilt=1, height=0.45, length=0.6, width=0.38)], length=0.63, breadth=0.4)
    assert score_cluster(bench(), o).probabilities["bench"] > 0.5
    bench_likelihood = score_cluster(bench(), o).classes["bench"].likelihood
    assert score_cluster(short, o).classes["bench"].likelihood < 0.1 * bench_likelihood


def test_a_table_top_is_open_below_and_a_box_is_not():
    """The floor seen under a top (``open_below``) keeps a table; a top under which it was
    never seen (a cabinet, a bed) is no table top; not measured costs nothing."""
    from ontodetect.ontology import part_values

    o = builtin_ontology()
    top = high_table()
    assert np.isnan(part_values(top, "open_below")).all()
    unknown = score_class(o["table"], top)
    opened = score_class(o["table"], replace(top, open_below=[0.9]))
    closed = score_class(o["table"], replace(top, open_below=[0.0]))
    assert opened.log_likelihood == pytest.approx(unknown.log_likelihood)
    # As the top the plane would cost exp(-6.1): it is likelier a missing top (0.02).
    assert closed.log_likelihood < unknown.log_likelihood - 3.5
    assert closed.assignment["top"] is None and unknown.assignment["top"] == 0
    (cv,) = [c for c in unknown.constraints if c.feature == "open_below"]
    assert cv.value is None and cv.factor == 1.0
    half = score_class(o["table"], replace(top, open_below=[0.25]))  # one sigma short
    (cv,) = [c for c in half.constraints if c.feature == "open_below"]
    assert cv.value == 0.25 and cv.factor == pytest.approx(math.exp(-0.5))
    assert score_cluster(replace(top, open_below=[0.0]), o).probabilities["table"] < 0.15
    assert score_cluster(replace(top, open_below=[0.9]), o).probabilities["table"] > 0.5


def test_label_probability_sums_the_classes_written_under_a_label():
    from ontodetect.labeling import label_probability

    o = builtin_ontology()
    p = {"table": 0.3, "side_table": 0.25, "chair": 0.1, "cabinet": 0.2, "none": 0.15}
    assert label_probability(p, o, "table") == pytest.approx(0.55)
    assert label_probability(p, o, "chair") == pytest.approx(0.1)
    assert label_probability(p, o, "cabinet") == pytest.approx(0.2)
    assert label_probability(p, o, "sofa") == 0.0


def test_chair_assignment_and_factors():
    s = score_class(builtin_ontology()["chair"], chair())
    assert s.assignment == {"seat": 0, "backrest": 1, "apron": None, "arm": None, "other_arm": None}
    # every factor of P_def is the product of its constraints' Gaussians
    seat = {c.feature: c for c in s.constraints if c.part == "seat"}
    g = builtin_ontology()["chair"].part("seat").constraints["height"]
    assert seat["height"].factor == pytest.approx(math.exp(-0.5 * ((0.46 - 0.55) / 0.2) ** 2))
    assert seat["height"].gaussian == g
    he = math.prod(c.factor for c in s.constraints if c.part == "seat" and c.group == "He")
    assert s.factors["seat"]["He"] == pytest.approx(he)
    total = math.prod(f["def"] for f in s.factors.values())
    assert math.log(total) == pytest.approx(s.log_likelihood)


def test_a_cluster_narrower_than_a_seat_is_a_poor_chair():
    # A chair's footprint spans at least its seat's width (EN 1335-1 / EN 12520: 400 mm and
    # more); a lamp or a strip of curtain seen as a "backrest" with its seat hidden is
    # narrower. A whole chair and one seen in part (0.35 m) pay nothing for their length.
    chair_class = builtin_ontology()["chair"]

    def length_factor(length):
        s = score_class(chair_class, replace(chair(), length=length, breadth=0.45))
        (c,) = [c for c in s.constraints if c.part == "cluster" and c.feature == "length"]
        return c.factor

    assert length_factor(0.55) == pytest.approx(1.0)
    assert length_factor(0.35) == pytest.approx(1.0)
    assert length_factor(0.15) == pytest.approx(math.exp(-0.5))  # one sigma short
    assert length_factor(0.15) < 0.7 * length_factor(0.45)


@dataclass(frozen=True)
class Facing(P):  # an upright plane facing along +y (a backrest behind its seat)
    @property
    def normal(self):
        t = math.radians(self.tilt)
        return np.array([0.0, math.sin(t), math.cos(t)])


@pytest.mark.parametrize("name", ["chair", "easy_chair"])
def test_a_chairs_backrest_is_centred_on_its_seat(name):
    # A chair is symmetric about the vertical plane through the middle of its seat and back
    # (EN 1335-1, EN 1728): its back's centroid lies over the seat's middle, within half a
    # seat's width for a back seen in part. A lamp standing at the side of a bedside
    # table's top, taken as a backrest, does not.
    cls = builtin_ontology()[name]
    seat = P(tilt=2, height=0.42, length=0.5, width=0.5)

    def scored(offset):
        back = Facing(tilt=80, height=0.72, length=0.45, width=0.4, cx=offset, cy=0.25)
        desc = cluster([seat, back], {(0, 1): R(angle=80, distance=0.02)}, length=0.7)
        s = score_class(cls, desc)
        aside = [c for c in s.constraints if c.part == "seat~backrest" and c.feature == "aside"]
        return s, aside

    for offset in (0.0, 0.2):  # centred, or a back seen in part: the rule costs nothing
        s, (c,) = scored(offset)
        assert s.assignment["backrest"] == 1
        assert (c.value, c.factor) == (pytest.approx(offset), 1.0)
    centred = scored(0.0)[0].log_likelihood
    assert scored(0.2)[0].log_likelihood == pytest.approx(centred)
    # 0.4 m aside it is no backrest: the chair's back is then missing, and costs as much.
    lamp, _ = scored(0.4)
    assert lamp.assignment["backrest"] is None
    assert lamp.log_likelihood <= centred + math.log(0.2)


def test_height_cut_at_the_search_volume_counts_as_at_least_that_tall():
    # Seat and backrest planes on a cluster that reaches the altitude cut-off: a cabinet
    # or a shelf cut at 1.4 m, whose true top is higher; chairs are never that tall.
    o = builtin_ontology()
    seen = chair()
    tall = ClusterDescription(
        planes=seen.planes,
        relations=seen.relations,
        length=0.55,
        breadth=0.5,
        height=1.38,
        bottom=0.0,
    )
    cut = ClusterDescription(
        planes=seen.planes,
        relations=seen.relations,
        length=0.55,
        breadth=0.5,
        height=1.38,
        bottom=0.0,
        ceiling=1.4,
    )
    assert not tall.cut and cut.cut and not chair().cut
    g = o["chair"].cluster.constraints["height"]
    factor = {
        c.feature: c.factor for c in score_class(o["chair"], cut).constraints if c.part == "cluster"
    }["height"]
    assert factor == pytest.approx(np.mean(g(np.linspace(1.38, 1.98, 13))))
    assert factor < 0.3 < g(1.38)
    gap = score_class(o["chair"], tall).log_likelihood - score_class(o["chair"], cut).log_likelihood
    assert gap == pytest.approx(math.log(g(1.38) / factor))
    assert (
        score_cluster(cut, o).probabilities["chair"] < score_cluster(tall, o).probabilities["chair"]
    )
    # A class that may be taller than what is seen keeps its factor.
    table = o["table"].cluster.constraints["height"]
    assert cluster_log_factor(table, cut, "height") == pytest.approx(
        math.log(np.mean(table(np.linspace(1.38, 1.98, 13))))
    )


def test_occluded_backrest_is_penalised_not_fatal():
    seat_only = cluster([P(tilt=2, height=0.46, length=0.45, width=0.42)], length=0.5, height=0.95)
    s = score_class(builtin_ontology()["chair"], seat_only)
    assert s.assignment["backrest"] is None
    assert s.factors["backrest"]["missing"] == pytest.approx(0.12)
    assert s.likelihood > 0.01


def test_pieces_of_one_top_are_explained_together():
    o = builtin_ontology()
    whole = high_table()
    half = P(tilt=1, height=0.74, length=0.7, width=0.8)
    split = cluster(
        [half, P(tilt=1, height=0.75, length=0.7, width=0.8, cx=0.7)],
        {(0, 1): R(angle=0.5, distance=0.01)},
        length=1.45,
    )
    assert continuations(split) == [frozenset({1}), frozenset({0})]
    # A step in height or a gap between them: two surfaces.
    apart = cluster(split.planes, {(0, 1): R(angle=0.5, distance=0.3)}, length=1.45)
    assert continuations(apart) == [frozenset(), frozenset()]
    t_split = score_class(o["table"], split)
    assert t_split.assignment["top"] in (0, 1)
    assert not any(c.feature == "extra_plane" for c in t_split.constraints)
    assert score_class(o["table"], apart).log_likelihood < t_split.log_likelihood
    assert score_cluster(split, o).best == score_cluster(whole, o).best == "table"


@dataclass(frozen=True)
class Leaning(P):  # a plane leaning back about the x axis, its normal tilted by ``tilt``
    @property
    def normal(self):
        t = math.radians(self.tilt)
        return np.array([0.0, -math.sin(t), math.cos(t)])


def test_pieces_of_one_backrest_are_explained_together():
    seat = P(tilt=2, height=0.46, length=0.45, width=0.42)
    left = Leaning(tilt=75, height=0.8, length=0.22, width=0.4, cx=-0.12, cy=0.2)
    right = Leaning(tilt=75, height=0.8, length=0.22, width=0.4, cx=0.12, cy=0.2)
    behind = Leaning(tilt=75, height=0.8, length=0.22, width=0.4, cx=0.12, cy=0.35)
    rel = R(angle=87, distance=0.02)
    one = cluster(
        [seat, left, right], {(0, 1): rel, (0, 2): rel, (1, 2): R(0.0, 0.01)}, length=0.55
    )
    two = cluster(
        [seat, left, behind], {(0, 1): rel, (0, 2): rel, (1, 2): R(0.0, 0.01)}, length=0.55
    )
    assert continuations(one)[1] == frozenset({2})
    assert continuations(two)[1] == frozenset()  # parallel, but 14 cm behind: another surface
    chair = builtin_ontology()["chair"]
    assert score_class(chair, one).log_likelihood > score_class(chair, two).log_likelihood


def test_a_second_large_surface_costs_a_table_more_than_clutter():
    o = builtin_ontology()
    table = o["table"]
    assert table.extra_surface == pytest.approx(0.5)
    top = P(tilt=1, height=0.72, length=1.6, width=0.8)
    seat = P(tilt=2, height=0.42, length=1.5, width=0.6, cy=0.7)  # a sofa seat beside it
    book = P(tilt=2, height=0.76, length=0.3, width=0.22)  # clutter on the top
    with_seat = score_class(table, cluster([top, seat], length=1.7))
    with_book = score_class(table, cluster([top, book], length=1.7))
    extra = {c.feature: c.factor for c in with_seat.constraints if c.part == "cluster"}
    assert extra["extra_plane"] == pytest.approx(0.5)
    assert with_book.likelihood > with_seat.likelihood
    text = (
        "format: ontodetect.ontology/1\nclasses:\n  thing:\n    extra_surface: 0\n"
        "    parts: {top: {tilt: {max: 5}}}\n"
    )
    with pytest.raises(InvalidOntologyError, match=r"extra_surface"):
        parse_ontology(text, "x.yaml")


def backrest_behind_desk(*, bottom=0.5, shelter=0.74):
    """Only the upper backrest of a chair pushed under a desk: a lifted reclined plane."""
    back = P(tilt=70, height=0.75, length=0.42, width=0.5)
    return ClusterDescription(
        planes=[back],
        relations={},
        length=0.44,
        breadth=0.24,
        height=0.98,
        bottom=bottom,
        shelter=shelter,
    )


def test_seat_hidden_behind_a_desk_counts_as_occluded():
    o = builtin_ontology()
    chair_class = o["chair"]
    seat = chair_class.part("seat")
    assert seat.occluded == pytest.approx(0.15)
    assert missing_factor(seat, backrest_behind_desk()) == pytest.approx(0.15)
    # What shows may begin at the seat's rear edge: a seat at EN 1335-1's lowest, 0.42 m,
    # or at Table 4.1's lowest, 0.35 m (a dining chair's), behind a desk is hidden too;
    # 0.34 m is more than SHELTERED_MARGIN under the centre of the seat's range (0.55 m),
    # where a seat would have been seen.
    assert missing_factor(seat, backrest_behind_desk(bottom=0.42)) == pytest.approx(0.15)
    assert missing_factor(seat, backrest_behind_desk(bottom=0.36)) == pytest.approx(0.15)
    # Standing on the floor, with nothing beside it, or seen from far above where a
    # seat could be: a missing seat is simply missing.
    for desc in (
        backrest_behind_desk(bottom=0.34),
        backrest_behind_desk(bottom=0.03),
        backrest_behind_desk(shelter=-math.inf),
        backrest_behind_desk(shelter=0.3),
        backrest_behind_desk(bottom=0.9),
    ):
        assert missing_factor(seat, desc) == pytest.approx(seat.missing)
    # What shows ending in a level board (a hutch's shelf over its back panel, a cabinet's
    # top over its front) hides nothing under it: a small level plate (a back's top rail)
    # or a board well under the top does not count.
    back = backrest_behind_desk().planes[0]
    for board, hidden in (
        (P(tilt=1, height=0.97, length=0.6, width=0.3), False),
        (P(tilt=1, height=0.97, length=0.3, width=0.06), True),
        (P(tilt=1, height=0.62, length=0.6, width=0.3), True),
    ):
        desc = replace(backrest_behind_desk(), planes=[back, board])
        assert missing_factor(seat, desc) == pytest.approx(0.15 if hidden else seat.missing)
    hidden = score_cluster(backrest_behind_desk(), o)
    alone = score_cluster(backrest_behind_desk(shelter=-math.inf), o)
    assert hidden.best == "chair" and hidden.probabilities["chair"] > 0.5
    assert alone.best == NONE
    s = score_class(chair_class, backrest_behind_desk())
    assert s.assignment["seat"] is None and s.factors["seat"]["missing"] == pytest.approx(0.15)


def test_occluded_without_a_height_constraint_and_invalid_values(tmp_path):
    text = (
        "format: ontodetect.ontology/1\nclasses:\n  thing:\n    parts:\n"
        "      foot: {occluded: 0.4, tilt: {max: 5}}\n      side: {tilt: {min: 80}}\n"
    )
    o = parse_ontology(text, "x.yaml")
    foot, side = o["thing"].part("foot"), o["thing"].part("side")
    assert side.occluded is None
    lifted = backrest_behind_desk()
    assert missing_factor(foot, lifted) == pytest.approx(0.4)
    assert missing_factor(side, lifted) == pytest.approx(side.missing)
    f = tmp_path / "bad.yaml"
    f.write_text(text.replace("occluded: 0.4", "occluded: 1.5"))
    from ontodetect.ontology import read_ontology_file

    with pytest.raises(InvalidOntologyError, match=r"\[classes.thing.parts.foot.occluded\]"):
        read_ontology_file(f)


def test_each_factor_follows_its_gaussian():
    text = """
format: ontodetect.ontology/1
classes:
  thing:
    parts:
      top: {height: {mean: 0.7, sigma: 0.1}, tilt: {max: 5, soft: 2}, fill: {min: 0.5, soft: 0.1}}
"""
    o = parse_ontology(text)
    for h, tilt, fill in [(0.7, 0, 1.0), (0.8, 0, 1.0), (0.7, 9, 1.0), (0.7, 0, 0.3)]:
        d = cluster([P(tilt=tilt, height=h, length=1, width=1, fill=fill)], length=1)
        f = score_class(o["thing"], d).factors["top"]
        assert f["He"] == pytest.approx(math.exp(-0.5 * ((h - 0.7) / 0.1) ** 2))
        assert f["Or"] == pytest.approx(math.exp(-0.5 * (max(tilt - 5, 0) / 2) ** 2))
        assert f["De"] == pytest.approx(math.exp(-0.5 * (min(fill - 0.5, 0) / 0.1) ** 2), rel=1e-6)


def test_gaussian_forms():
    g = Gaussian.from_range(0.35, 0.75)
    assert float(g(0.55)) == 1.0
    assert float(g(0.75)) == pytest.approx(math.exp(-0.5))
    assert float(Gaussian.at_least(0.3, 0.1)(0.2)) == pytest.approx(math.exp(-0.5))
    assert float(Gaussian.at_most(6, 2)(2)) == 1.0


def test_environment_prior_follows_eq_3_10():
    o = builtin_ontology()
    assert class_priors(o, "living_room")["chair"] == pytest.approx(0.987)
    mixed = class_priors(o, {"office": 1, "corridor": 1})["chair"]
    assert mixed == pytest.approx((0.58 + 0.05) / 2)
    assert class_priors(o)["chair"] == 1.0
    assert class_priors(o, "office")["table"] == pytest.approx(0.9)  # places205.yaml tables
    assert class_priors(o, "bathroom")["toilet"] == pytest.approx(0.9)
    assert sum(room_distribution("office_scenes").values()) == pytest.approx(1.0)
    with pytest.raises(InvalidParameterError, match="'room'"):
        room_distribution("spaceship")


def test_prior_lowers_posterior_in_unlikely_rooms():
    o = builtin_ontology()
    p_living = score_cluster(chair(), o, class_priors(o, "living_room")).probabilities["chair"]
    p_corr = score_cluster(chair(), o, class_priors(o, "corridor")).probabilities["chair"]
    assert p_corr < p_living


@pytest.mark.parametrize(
    ("body", "line", "key"),
    [
        (
            "  chair:\n    parts:\n      seat: {height: [0.7, 0.3]}\n",
            5,
            "classes.chair.parts.seat.height",
        ),
        (
            "  chair:\n    parts:\n      seat: {colour: [1, 2]}\n",
            5,
            "classes.chair.parts.seat.colour",
        ),
        ("  chair:\n    parts:\n      seat: {tilt: 3}\n", 5, "classes.chair.parts.seat.tilt"),
        (
            "  chair:\n    parts: {seat: {}}\n    relations:\n      - {between: [seat, back]}\n",
            6,
            "classes.chair.relations[0].between[1]",
        ),
        ("  chair:\n    partz: {}\n", 4, "classes.chair.partz"),
    ],
)
def test_ontology_errors_name_file_line_and_key(tmp_path, body, line, key):
    f = tmp_path / "my.yaml"
    f.write_text("format: ontodetect.ontology/1\nclasses:\n" + body)
    from ontodetect.ontology import read_ontology_file

    with pytest.raises(InvalidOntologyError) as exc:
        read_ontology_file(f)
    msg = str(exc.value)
    assert msg.startswith(f"{f}:{line} [{key}]"), msg


def test_bad_yaml_and_wrong_format(tmp_path):
    with pytest.raises(InvalidOntologyError, match="not valid YAML"):
        parse_ontology("classes: [", "x.yaml")
    with pytest.raises(InvalidOntologyError, match="expected format"):
        parse_ontology("classes: {}", "x.yaml")


@pytest.mark.parametrize(
    "name", ["furniture.yaml", "literature.yaml", "places205.yaml", "sh3d_classes.yaml"]
)
def test_shipped_files_read_the_same_with_libyaml(name):
    """The built-in ontology is read with libyaml's parser: every shipped file gives it
    the same values, and every key the same line, as the pure-Python one."""
    from importlib import resources

    from ontodetect.io._yaml import CSafeYamlLoader
    from ontodetect.ontology._schema import _load_yaml

    if CSafeYamlLoader is None:
        pytest.skip("PyYAML without libyaml")
    text = resources.files("ontodetect").joinpath("data", name).read_text("utf-8")
    slow, slow_lines = _load_yaml(text, name)
    fast, fast_lines = _load_yaml(text, name, CSafeYamlLoader)
    assert repr(fast) == repr(slow)
    assert fast_lines.at == slow_lines.at


def test_the_builtin_ontology_is_the_file_parsed_as_any_other():
    from importlib import resources

    from ontodetect.ontology import builtin_ontology

    text = resources.files("ontodetect").joinpath("data/furniture.yaml").read_text("utf-8")
    assert builtin_ontology() == parse_ontology(text, "builtin:furniture.yaml")


@pytest.mark.parametrize(
    "text, problem",
    [
        ("a: &x [1]\nb: *x\n", "aliases (*x) are not allowed"),
        ("[1]: 2\n", "a key must be a plain name or number"),
        ("a: " + "[" * 70 + "]" * 70 + "\n", "nested more than 64 levels deep"),
    ],
)
def test_the_libyaml_reader_refuses_what_the_python_one_does(text, problem):
    from ontodetect.io._yaml import CSafeYamlLoader, YamlError

    if CSafeYamlLoader is None:
        pytest.skip("PyYAML without libyaml")
    loader = CSafeYamlLoader(text)
    with pytest.raises(YamlError, match=re.escape(problem)):
        loader.get_single_data()
    loader.dispose()


def test_none_takes_mass_when_nothing_fits():
    wall = cluster([P(tilt=90, height=1.2, length=3.0, width=2.4)], length=3.0, height=2.4)
    assert score_cluster(wall, builtin_ontology()).best == NONE


def test_plateau_constraint_is_flat_inside_with_soft_tails():
    o = parse_ontology("""
format: ontodetect.ontology/1
classes:
  t:
    parts:
      top: {length: {min: 0.5, max: 3.0, soft: 0.25}}
""")
    g = o["t"].part("top").constraints["length"]
    assert float(g(0.5)) == 1.0 and float(g(2.0)) == 1.0 and float(g(3.0)) == 1.0
    assert float(g(0.25)) == pytest.approx(math.exp(-0.5))
    assert float(g(3.5)) == pytest.approx(math.exp(-2.0))
    with pytest.raises(InvalidOntologyError, match="min < max"):
        parse_ontology(
            "format: ontodetect.ontology/1\nclasses:\n  t:\n    parts:\n"
            "      top: {length: {min: 3, max: 1}}\n"
        )


def test_plateau_tails_can_have_their_own_softness():
    o = parse_ontology("""
format: ontodetect.ontology/1
classes:
  t:
    parts:
      back: {tilt: {min: 65, max: 85, soft: [12, 2.5]}}
""")
    g = o["t"].part("back").constraints["tilt"]
    assert float(g(65)) == 1.0 and float(g(85)) == 1.0
    assert float(g(53)) == pytest.approx(math.exp(-0.5))
    assert float(g(90)) == pytest.approx(math.exp(-2.0))
    assert g.describe() == "in [65, 85] (soft 12, 2.5)"
    for soft, match in (("[12]", "below, above"), ("[12, 0]", "> 0"), ("[12, x]", "number")):
        with pytest.raises(InvalidOntologyError, match=match):
            parse_ontology(
                "format: ontodetect.ontology/1\nclasses:\n  t:\n    parts:\n"
                f"      back: {{tilt: {{min: 65, max: 85, soft: {soft}}}}}\n"
            )


@given(
    st.floats(-5, 5),
    st.floats(0.1, 5),
    st.floats(0.01, 3),
    st.floats(-20, 20),
)
def test_a_plateau_with_one_softness_scores_as_before(low, width, soft, x):
    # The same softness given once or for both tails is the same constraint.
    one = Gaussian.plateau(low, low + width, soft)
    two = Gaussian.plateau(low, low + width, soft, soft)
    assert float(one.log(x)) == float(two.log(x))


NEAR = """
format: ontodetect.ontology/1
classes:
  bed: {parts: {mattress: {tilt: {max: 6}, height: [0.3, 0.65]}}, cluster: {length: [1.8, 2.3]}}
  stand:
    parts: {top: {tilt: {max: 5}, height: [0.4, 0.72]}}
    cluster: {length: {max: 0.7}}
    near: [{class: %s, distance: {max: 0.3, soft: 0.2}, missing: 0.2}]
"""


def _box(x, size):
    from types import SimpleNamespace

    return SimpleNamespace(center=(x, 0.0, 0.3), size=size, yaw=0.0)


def test_near_scores_a_stand_by_the_bed_beside_it():
    from ontodetect.ontology import score_near

    onto = parse_ontology(NEAR % "bed")
    bed = score_cluster(cluster([P(tilt=1, height=0.5, length=2.0, width=1.4)], length=2.05), onto)
    stand = score_cluster(
        cluster([P(tilt=1, height=0.55, length=0.45, width=0.4)], length=0.5), onto
    )
    beside = score_near(
        [bed, stand], [_box(0, (2.05, 1.4, 0.5)), _box(1.35, (0.5, 0.4, 0.6))], onto
    )
    alone = score_near([bed, stand], [_box(0, (2.05, 1.4, 0.5)), _box(4.0, (0.5, 0.4, 0.6))], onto)
    # The class "bed" has no rule: its likelihood is the same, wherever the stand is.
    assert beside[0].classes["bed"].log_likelihood == bed.classes["bed"].log_likelihood
    near_bed = beside[1].classes["stand"].log_likelihood
    assert math.exp(alone[1].classes["stand"].log_likelihood - near_bed) == pytest.approx(
        0.2 / bed.probabilities["bed"], rel=1e-6
    )
    (rule,) = [c for c in alone[1].classes["stand"].constraints if c.part == "near bed"]
    assert rule.value is None and rule.factor == pytest.approx(0.2)
    # A scene's order does not change what each cluster scores.
    swapped = score_near(
        [stand, bed], [_box(1.35, (0.5, 0.4, 0.6)), _box(0, (2.05, 1.4, 0.5))], onto
    )
    assert swapped[0].probabilities == pytest.approx(beside[1].probabilities)


def test_near_names_an_unknown_class_and_needs_a_distance():
    from ontodetect.ontology import score_near

    onto = parse_ontology(NEAR % "bde")
    s = score_cluster(cluster([P(tilt=1, height=0.55, length=0.45, width=0.4)], length=0.5), onto)
    with pytest.raises(InvalidOntologyError, match=r"\[classes.stand.near\].*'bde'"):
        score_near([s], [_box(0, (0.5, 0.4, 0.6))], onto)
    text = NEAR.replace("distance: {max: 0.3, soft: 0.2}, ", "") % "bed"
    with pytest.raises(InvalidOntologyError, match=r"\[classes.stand.near.0\].*distance"):
        parse_ontology(text)


@pytest.mark.parametrize(
    ("feature", "allowed", "refused"),
    [
        # Under a seat are the sitter's legs and the chair's legs or column: a lower board
        # seen inside the seat's outline (a nightstand's or a desk compartment's shelf) takes
        # the chair away; the edge of a cross rail costs it nothing.
        ("seen_below", 0.3, 0.7),
        # A seat ends where its chair ends: what goes on level from it into the next cluster
        # for a place's width or a footstool's costs nothing; for what seats two, it is the
        # rest of a bench or a sofa, and the piece is no chair.
        ("runs_on", 0.75, 1.5),
    ],
)
def test_what_a_chair_s_seat_cannot_have(feature, allowed, refused):
    """A seat scene feature at 0 or within its bound leaves the chair as it is; past it,
    the chair is gone."""
    o = builtin_ontology()
    free = score_cluster(replace(chair(), scene={feature: [0.0, math.nan]}), o)
    fine = score_cluster(replace(chair(), scene={feature: [allowed, math.nan]}), o)
    past = score_cluster(replace(chair(), scene={feature: [refused, math.nan]}), o)
    assert free.best == fine.best == "chair"
    assert fine.probabilities["chair"] == pytest.approx(free.probabilities["chair"])
    assert past.probabilities["chair"] < 0.1 * free.probabilities["chair"]


def _bath_or_bed(seen_below, wall=True):
    """A 1.7 x 0.75 m top at 0.54 m, a lower level plane inside it at 0.17 m (a bath's
    floor, 0.37 of the top's outline) and, built in, the tiled wall behind it to 1.4 m."""
    rim = P(tilt=0, height=0.54, length=1.7, width=0.72, fill=0.7)
    floor = P(tilt=0, height=0.17, length=1.3, width=0.5, fill=0.8)
    side = P(tilt=85, height=0.35, length=1.5, width=0.35, cy=0.3)
    planes = [rim, floor, side]
    rels = {
        (0, 1): R(angle=0, distance=0.3, xy_overlap=1.0),
        (0, 2): R(angle=85, distance=0.02),
        (1, 2): R(angle=85, distance=0.05),
    }
    if wall:
        planes.append(P(tilt=90, height=0.8, length=1.8, width=1.1, cy=-0.4))
    desc = cluster(planes, rels, length=1.8, breadth=0.85, height=1.4 if wall else None)
    return replace(desc, scene={"seen_below": [seen_below, 0.0, math.nan] + [math.nan] * wall})


def test_a_bath_built_in_against_its_wall_is_a_bath_and_no_bed():
    """A bath's cluster takes the wall, taps or screen above it (its height has no upper
    bound), and a bed's mattress hides the frame under it (``seen_below`` at most 0.1, as a
    closed top): the tub's floor seen inside the rim is no bed's."""
    o = builtin_ontology()
    bath = score_cluster(_bath_or_bed(0.37), o)
    assert bath.best == "bathtub"
    assert bath.probabilities["bed"] < 0.5 * bath.probabilities["bathtub"]
    # The same top with nothing lower seen inside it is as much a bed as ever.
    closed = score_cluster(_bath_or_bed(0.0), o)
    assert closed.classes["bed"].log_likelihood > bath.classes["bed"].log_likelihood + 1.0
