"""Calibration: the split by room, the fit with its floors, the YAML kept in shape."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
import yaml

from ontodetect import InvalidParameterError
from ontodetect.calibrate import (
    FitSettings,
    calibrate_dataset,
    calibrate_ontology,
    constraint_values,
    fit_gaussian,
    split_scenes,
)
from ontodetect.calibrate._gaussian import _constraint_paths, _write_spec
from ontodetect.calibrate._run import _builtin_text
from ontodetect.evaluation import discover_scenes
from ontodetect.ontology import ClusterDescription, Gaussian, parse_ontology, score_class

SCANS = [
    "scene0000_00",
    "scene0000_01",
    "scene0000_02",
    "scene0002_00",
    "scene0002_01",
    "scene0003_00",
    "scene0005_00",
    "scene0005_01",
    "scene0007_00",
    "scene0010_00",
]

# Every constraint form the schema knows, with comments that calibration drops.
ONTOLOGY = """\
format: ontodetect.ontology/1
description: A test ontology.
classes:
  chair:
    matches: [chair]
    cluster:
      length: {max: 0.95, soft: 0.2}    # a comment
      height: {min: 0.6, max: 1.3, soft: 0.15}
    parts:
      seat:
        tilt: {max: 6}
        height: [0.35, 0.75]
        length: {range: [0.3, 0.7]}
        fill: {min: 0.45}
      backrest:
        required: false
        tilt: {min: 65, soft: 12}
        height: {mean: 0.8, sigma: 0.2}
        width: {min: 0.1, max: 0.6}
    relations:
      - between: [seat, backrest]
        angle: {min: 60, soft: 12}
        gap: {min: 0.08, soft: 0.06}
    labeling:
      plane_size: {mean: 0.45, sigma: 0.2}
"""


# -- split ---------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(8))
def test_split_keeps_rescans_of_a_room_together(seed):
    split = split_scenes(SCANS, 0.5, seed)
    cal, held = set(split.calibration), set(split.held_out)
    assert cal and held and not cal & held and cal | held == set(SCANS)
    rooms_cal = {s[:9] for s in cal}
    rooms_held = {s[:9] for s in held}
    assert not rooms_cal & rooms_held
    assert len(rooms_cal) == 3  # round(0.5 x 6 rooms)
    assert split.calibration == [s for s in SCANS if s in cal]  # order kept
    assert split_scenes(SCANS, 0.5, seed) == split  # same seed, same split


def test_split_depends_on_the_seed_and_fraction():
    splits = {tuple(split_scenes(SCANS, 0.5, s).calibration) for s in range(8)}
    assert len(splits) > 1
    assert len(split_scenes(SCANS, 0.2, 0).groups("calibration")) == 1
    assert len(split_scenes(SCANS, 0.99, 0).groups("held_out")) == 1  # at least one aside
    everything = split_scenes(SCANS, 1.0, 0)
    assert everything.calibration == SCANS and everything.held_out == []
    assert "held out" in split_scenes(SCANS, 0.5, 0).describe()


@pytest.mark.parametrize(
    ("fraction", "seed", "match"),
    [(0.0, 0, "'split'"), (1.5, 0, "'split'"), (0.5, -1, "'seed'")],
)
def test_split_rejects_bad_parameters(fraction, seed, match):
    with pytest.raises(InvalidParameterError, match=match):
        split_scenes(SCANS, fraction, seed)


def test_a_single_room_cannot_be_split():
    with pytest.raises(InvalidParameterError, match="single room"):
        split_scenes(["scene0000_00", "scene0000_01"], 0.5)
    assert split_scenes(["scene0000_00"], 1.0).held_out == []


# -- fit -----------------------------------------------------------------------------------
def test_sigma_is_the_predictive_spread_above_its_floors():
    prior = Gaussian(0.55, 0.2)
    wide = [0.3, 0.5, 0.7, 0.5]
    g = fit_gaussian(prior, wide, "height", prior_share=0.25, prior_strength=0)
    # Without a prior: the sample mean, and the std widened by the predictive 1 + 1/n.
    assert g.mean == pytest.approx(0.5)
    assert g.sigma == pytest.approx(np.std(wide) * np.sqrt(1.25))
    same = [0.46] * 5
    ml = {"prior_strength": 0}
    assert fit_gaussian(prior, same, "height", prior_share=0.25, **ml).sigma == pytest.approx(0.05)
    assert fit_gaussian(prior, same, "height", prior_share=0.5, **ml).sigma == pytest.approx(0.1)
    # The absolute floor wins over a small prior sigma: tilts are not known to 0.1 degree.
    assert fit_gaussian(Gaussian(2.0, 0.4), [2.0] * 5, "tilt", **ml).sigma == pytest.approx(1.0)
    assert (
        fit_gaussian(Gaussian(2.0, 0.4), [2.0] * 5, "unknown", prior_share=0.5, **ml).sigma == 0.2
    )


def test_few_samples_stay_near_the_prior():
    prior = Gaussian(0.55, 0.2)
    values = [0.40, 0.41, 0.42]
    few = fit_gaussian(prior, values, "height")  # 3 objects against 8
    assert abs(few.mean - 0.55) < abs(few.mean - 0.41)
    assert few.sigma > 0.15  # far from the 0.008 of the values
    many = fit_gaussian(prior, values * 30, "height")
    assert abs(many.mean - 0.41) < abs(few.mean - 0.41)
    # 90 objects of two rooms are worth 2 x ROOM_SAMPLES: still near the prior.
    rooms = fit_gaussian(prior, values * 30, "height", effective_samples=2 * 3)
    assert abs(rooms.mean - 0.55) < abs(many.mean - 0.55)
    # Data far from the prior widen sigma instead of narrowing it.
    far = fit_gaussian(Gaussian(0.55, 0.05), [0.80, 0.81, 0.82, 0.8], "height")
    assert far.sigma > 0.05


def test_too_few_values_keep_the_prior():
    prior = Gaussian(0.55, 0.2)
    assert fit_gaussian(prior, [0.4, 0.5], "height") is prior
    assert fit_gaussian(prior, [0.4, 0.5, np.nan, np.inf], "height") is prior


def test_one_sided_constraints_stay_one_sided_and_only_loosen():
    ml = {"prior_strength": 0, "quantile": 0.0}
    below = [0.3, 0.4, 0.5]
    lo = fit_gaussian(Gaussian(0.45, 0.2, "min"), below, "fill", **ml)
    assert (lo.side, lo.mean) == ("min", pytest.approx(0.2))  # 0.3 minus the gap 0.2 / 2
    inside = [0.7, 0.8, 0.9, 0.6, 0.75]
    assert fit_gaussian(Gaussian(0.45, 0.2, "min"), inside, "fill", **ml).mean == 0.45
    hi = fit_gaussian(Gaussian(3.0, 5.0, "max"), [1.0, 2.0, 3.0, 4.0, 5.0], "tilt", **ml)
    assert (hi.side, hi.mean) == ("max", pytest.approx(6.0))
    plateau = fit_gaussian(Gaussian.plateau(0.3, 0.65, 0.12), inside, "length", **ml)
    assert plateau.side == "plateau"
    assert (plateau.mean, plateau.upper) == (0.3, pytest.approx(0.9 + 0.3 / 4))
    # Tails of their own softness keep their ratio, and are written back as a pair.
    two = fit_gaussian(Gaussian.plateau(65, 85, 12, 2.5), [70.0, 80.0, 88.0, 89.0], "tilt", **ml)
    assert two.upper_sigma == pytest.approx(2.5 * two.sigma / 12)
    spec = _write_spec({"min": 65, "max": 85, "soft": [12, 2.5]}, two)
    assert isinstance(spec["soft"], list) and spec["soft"][1] < spec["soft"][0]
    # With the prior's weight the bound moves only part of the way.
    shrunk = fit_gaussian(Gaussian(0.45, 0.2, "min"), below, "fill", quantile=0.0)
    assert 0.2 < shrunk.mean < 0.45


def test_fit_settings_are_checked():
    with pytest.raises(InvalidParameterError, match="'quantile'"):
        FitSettings(quantile=0.5)
    with pytest.raises(InvalidParameterError, match="'prior_strength'"):
        FitSettings(prior_strength=-1.0)
    with pytest.raises(InvalidParameterError, match="'validate'"):
        FitSettings(validate="yes")
    with pytest.raises(InvalidParameterError, match="'min_rooms'"):
        FitSettings(min_rooms=0)


# -- the YAML ------------------------------------------------------------------------------
def _skeleton(node):
    """The structure of a YAML document with every number replaced by its type."""
    if isinstance(node, dict):
        return {k: _skeleton(v) for k, v in node.items()}
    if isinstance(node, list):
        return [_skeleton(v) for v in node]
    if isinstance(node, (int, float)) and not isinstance(node, bool):
        return "number"
    return node


def _values_for_everything(text, rng):
    onto = parse_ontology(text)
    values = {}
    for path, g in _constraint_paths(onto):
        centre = (g.mean + g.upper) / 2 if g.side == "plateau" else g.mean
        values[path] = list(rng.normal(centre, g.sigma / 3, 12))
    return onto, values


@pytest.mark.parametrize("which", ["test", "builtin"])
def test_calibration_changes_only_numbers(which, rng):
    text = ONTOLOGY if which == "test" else _builtin_text()
    onto, values = _values_for_everything(text, rng)
    new_text, fits = calibrate_ontology(text, values, comment="made by a test\nsecond line")
    assert all(f.changed for f in fits) and len(fits) == len(values)
    before, after = yaml.safe_load(text), yaml.safe_load(new_text)
    assert _skeleton(after) == _skeleton(before)
    assert after != before
    new = parse_ontology(new_text)
    assert new.names == onto.names
    for (path, g_old), (_, g_new) in zip(_constraint_paths(onto), _constraint_paths(new)):
        assert g_new.side == g_old.side, path
    assert new_text.startswith("# made by a test\n# second line\n")
    assert "a comment" not in new_text  # comments of the original are not kept


def test_forms_are_kept_key_by_key(rng):
    _, values = _values_for_everything(ONTOLOGY, rng)
    after = yaml.safe_load(calibrate_ontology(ONTOLOGY, values)[0])
    seat = after["classes"]["chair"]["parts"]["seat"]
    assert isinstance(seat["height"], list) and len(seat["height"]) == 2
    assert set(seat["length"]) == {"range"}
    assert set(seat["tilt"]) == {"max"}  # no 'soft' added where the file had none
    back = after["classes"]["chair"]["parts"]["backrest"]
    assert set(back["height"]) == {"mean", "sigma"} and set(back["width"]) == {"min", "max"}
    assert after["classes"]["chair"]["labeling"] == {"plane_size": {"mean": 0.45, "sigma": 0.2}}


def test_constraints_seen_in_one_room_keep_their_prior(rng):
    _, values = _values_for_everything(ONTOLOGY, rng)
    rooms = dict.fromkeys(values, 2)
    lonely = ("chair", "parts", "seat", "height")
    rooms[lonely] = 1
    _, fits = calibrate_ontology(ONTOLOGY, values, rooms=rooms)
    assert [f.name for f in fits if not f.changed] == ["chair.parts.seat.height"]


# -- measuring -----------------------------------------------------------------------------
def _plane(tilt, height, z_min, z_max, length, width, area, centroid):
    return SimpleNamespace(
        tilt=tilt,
        height=height,
        z_min=z_min,
        z_max=z_max,
        length=length,
        width=width,
        area=area,
        density=1000.0,
        num_points=200,
        normal=(0.0, 0.0, 1.0),
        centroid=centroid,
    )


def test_constraint_values_are_the_features_of_the_best_assignment():
    onto = parse_ontology(ONTOLOGY)
    seat = _plane(2.0, 0.46, 0.45, 0.47, 0.45, 0.42, 0.17, (0.0, 0.0, 0.46))
    back = _plane(85.0, 0.75, 0.5, 1.0, 0.45, 0.4, 0.16, (0.0, 0.2, 0.75))
    relation = SimpleNamespace(angle=83.0, distance=0.02, xy_overlap=0.1)
    desc = ClusterDescription([back, seat], {(0, 1): relation}, 0.55, 0.5, 1.0, 0.0)
    score = score_class(onto["chair"], desc)
    assert dict(score.assignment) == {"seat": 1, "backrest": 0}
    got = constraint_values(onto["chair"], score)
    assert got[("chair", "parts", "seat", "height")] == 0.46
    assert got[("chair", "parts", "seat", "fill")] == pytest.approx(0.17 / (0.45 * 0.42))
    assert got[("chair", "parts", "backrest", "tilt")] == 85.0
    assert got[("chair", "relations", 0, "angle")] == 83.0
    assert got[("chair", "relations", 0, "gap")] == pytest.approx(0.75 - 0.46)
    assert got[("chair", "cluster", "length")] == 0.55
    assert len(got) == len(_constraint_paths(onto))


def test_objects_are_measured_against_the_kind_of_their_class_that_fits():
    """The built-in table and side table both match NYU40 tables and desks: a small top
    calibrates the side table's rules, a long one the table's."""
    from ontodetect.calibrate import best_kind
    from ontodetect.evaluation._dataset import _class_id_lists, _class_ids
    from ontodetect.ontology import builtin_ontology

    onto = builtin_ontology()
    lists = _class_id_lists(onto, reported_only=False, attr="name")
    assert lists[7] == lists[14] == ["table", "side_table"]
    assert lists[5] == ["chair", "easy_chair"]
    assert _class_ids(onto, reported_only=False, attr="name")[7] == "table"
    assert _class_id_lists(onto, reported_only=True, attr="label")[7] == ["table"]

    def top(length):
        plane = _plane(1.0, 0.62, 0.61, 0.63, length, 0.5, 0.9 * length * 0.5, (0, 0, 0.62))
        return ClusterDescription([plane], {}, length + 0.03, 0.53, 0.63, 0.0)

    for length, kind in ((0.55, "side_table"), (1.4, "table")):
        cls, score = best_kind(onto, ["table", "side_table"], top(length))
        assert cls.name == kind and score.name == kind
        assert score.log_likelihood == score_class(onto[kind], top(length)).log_likelihood
    assert best_kind(onto, ["table"], top(0.55))[0].name == "table"
    with pytest.raises(InvalidParameterError, match="names"):
        best_kind(onto, [], top(0.55))


# -- the nested check ----------------------------------------------------------------------
def _chair_scene(name):
    return _chair_at(name, 0.46, back_top=1.0)


def test_a_change_that_lowers_validation_f1_is_rejected():
    from ontodetect.calibrate import select_groups

    seat_height = ("chair", "parts", "seat", "height")
    cluster_length = ("chair", "cluster", "length")
    # Seats measured at 1.5 m would make the chair of every validation room fail.
    bad = {seat_height: [1.5, 1.52, 1.48, 1.5], cluster_length: [0.5, 0.55, 0.6]}
    rooms = {r: bad for r in ("scene0001", "scene0002", "scene0003")}
    scenes = {r: [_chair_scene(r + "_00")] for r in rooms}
    settings = FitSettings(prior_strength=0.0, min_gain_rooms=2)
    accepted, decisions = select_groups(ONTOLOGY, rooms, scenes, settings=settings)
    by_name = {d.name: d for d in decisions}
    seat = by_name["chair.parts.seat"]
    assert not seat.accepted and seat.f1_after["chair"] < seat.f1_before["chair"] == 1.0
    assert ("chair", "parts", "seat") not in accepted
    # A change that does not lower F1 but shows no gain either keeps the prior by default...
    assert not by_name["chair.cluster"].accepted
    # ...and is kept when ties are accepted.
    ties = FitSettings(prior_strength=0.0, accept_ties=True, min_gain_rooms=2)
    tied, _ = select_groups(ONTOLOGY, rooms, scenes, settings=ties)
    assert ("chair", "cluster") in tied and ("chair", "parts", "seat") not in tied
    # The written file keeps the rejected group's prior.
    text, fits = calibrate_ontology(ONTOLOGY, bad, groups=accepted)
    assert yaml.safe_load(text) == yaml.safe_load(ONTOLOGY)
    assert all(not f.changed for f in fits)
    assert any("nested check" in f.note for f in fits)


def test_one_room_cannot_be_checked_so_nothing_changes():
    from ontodetect.calibrate import select_groups

    rooms = {"scene0001": {("chair", "cluster", "length"): [0.5, 0.55, 0.6]}}
    accepted, decisions = select_groups(
        ONTOLOGY, rooms, {"scene0001": [_chair_scene("scene0001_00")]}
    )
    assert accepted == set() and decisions == []


def _chair_at(name, seat_height, back_top=1.1):
    """A validation scene with one chair whose seat is at ``seat_height``; its backrest
    rises from 0.5 m to ``back_top``, the top of the chair."""
    from ontodetect.calibrate import ValidationScene
    from ontodetect.evaluation import Instance

    h, mid = seat_height, (0.5 + back_top) / 2
    seat = _plane(2.0, h, h - 0.01, h + 0.01, 0.45, 0.42, 0.17, (0.0, 0.0, h))
    back = _plane(85.0, mid, 0.5, back_top, 0.45, 0.4, 0.16, (0.0, 0.2, mid))
    relation = SimpleNamespace(angle=83.0, distance=0.02, xy_overlap=0.1)
    desc = ClusterDescription([back, seat], {(0, 1): relation}, 0.55, 0.5, back_top, 0.0)
    members = np.arange(100)
    return ValidationScene(
        name, (desc,), np.zeros((1, 3)), (members,), (Instance.make(1, "chair", members),)
    )


#: Seats measured from 0.45 to 0.9 m widen the seat height (0.55 +- 0.2) upwards: a chair
#: with its seat at 0.95 m is then found, one at 0.46 m still is.
TALL_SEATS = {("chair", "parts", "seat", "height"): [0.45, 0.6, 0.75, 0.9]}
HIGH, LOW = 0.95, 0.46


def _select(heights, **settings):
    from ontodetect.calibrate import select_groups

    rooms = {f"scene000{i}": TALL_SEATS for i in range(1, len(heights) + 1)}
    scenes = {r: [_chair_at(r + "_00", h)] for r, h in zip(rooms, heights)}
    return select_groups(
        ONTOLOGY, rooms, scenes, settings=FitSettings(prior_strength=0.0, **settings)
    )


def test_the_chairs_of_the_nested_check_behave_as_intended():
    from ontodetect.calibrate._groups import _detect_counts, _detection_params

    base = parse_ontology(ONTOLOGY)
    fitted = parse_ontology(
        calibrate_ontology(ONTOLOGY, TALL_SEATS, settings=FitSettings(prior_strength=0.0))[0]
    )
    params = _detection_params(base, {})
    found = {
        (h, which): int(_detect_counts(_chair_at("s", h), o, params, ["chair"])["chair"][0])
        for h in (HIGH, LOW)
        for which, o in (("base", base), ("fitted", fitted))
    }
    assert found == {(HIGH, "base"): 0, (HIGH, "fitted"): 1, (LOW, "base"): 1, (LOW, "fitted"): 1}


def test_a_gain_in_a_single_left_out_room_is_not_enough():
    accepted, decisions = _select([HIGH, LOW, LOW, LOW, LOW])
    assert accepted == set()
    (seat,) = decisions
    assert seat.name == "chair.parts.seat" and not seat.accepted
    assert seat.rooms_gained == ("scene0001",) and seat.rooms_lost == ()
    assert "only in scene0001" in seat.reason
    # The pooled F1 rose: the old rule would have kept it on one detection.
    assert seat.f1_after["chair"] > seat.f1_before["chair"]


def test_a_gain_in_several_left_out_rooms_is_kept():
    # The default sign test: a gain in 4 rooms and a loss in none (p = 1/16 < 0.1).
    accepted, decisions = _select([HIGH, HIGH, LOW, HIGH, HIGH])
    assert accepted == {("chair", "parts", "seat")}
    (seat,) = decisions
    assert seat.accepted and seat.rooms_gained == (
        "scene0001",
        "scene0002",
        "scene0004",
        "scene0005",
    )
    assert seat.to_dict()["rooms_gained"] == list(seat.rooms_gained)
    # Three rooms are not enough by default (p = 1/8), enough when asked for.
    accepted, (seat,) = _select([HIGH, HIGH, LOW, HIGH, LOW])
    assert accepted == set() and "needs a gain in 4 rooms" in seat.reason
    accepted, _ = _select([HIGH, HIGH, LOW, HIGH, LOW], min_gain_rooms=3)
    assert accepted == {("chair", "parts", "seat")}
    # Ties asked for: a single room's gain is enough, since no gain is.
    accepted, _ = _select([HIGH, LOW, LOW, LOW], accept_ties=True)
    assert accepted == {("chair", "parts", "seat")}


def test_a_loss_in_any_left_out_room_rejects_the_gain_of_the_others():
    from ontodetect.calibrate import select_groups

    # Seats measured around 1 m only: the fitted height finds the high chairs and loses
    # the low one.
    rooms = {
        f"scene000{i}": {("chair", "parts", "seat", "height"): [0.95, 1.0, 1.05, 1.0]}
        for i in (1, 2, 3, 4, 5)
    }
    heights = (HIGH, HIGH, LOW, HIGH, HIGH)
    scenes = {r: [_chair_at(r + "_00", h)] for r, h in zip(rooms, heights)}
    _, (seat,) = select_groups(
        ONTOLOGY, rooms, scenes, settings=FitSettings(prior_strength=0.0, min_gain_rooms=2)
    )
    assert not seat.accepted and seat.rooms_lost == ("scene0003",)
    assert seat.rooms_gained == ("scene0001", "scene0002", "scene0004", "scene0005")


def test_fewer_false_alarms_count_as_a_gain_where_f1_is_zero():
    from ontodetect.calibrate._groups import _room_sign

    assert _room_sign(np.array([0, 1, 2]), np.array([0, 2, 2])) == 1
    assert _room_sign(np.array([0, 3, 2]), np.array([0, 2, 2])) == -1
    assert _room_sign(np.array([1, 0, 1]), np.array([1, 0, 1])) == 0
    assert _room_sign(np.array([2, 1, 0]), np.array([1, 0, 1])) == 1  # F1 decides


def test_too_few_rooms_to_leave_out_validate_nothing():
    # Three calibration rooms cannot show a gain in four: nothing is even tried.
    accepted, decisions = _select([HIGH, HIGH, HIGH])
    assert accepted == set() and decisions == []
    accepted, decisions = _select([HIGH, HIGH], min_gain_rooms=3)
    assert accepted == set() and decisions == []
    with pytest.raises(InvalidParameterError, match="'min_gain_rooms'"):
        FitSettings(min_gain_rooms=0)
    assert FitSettings(min_gain_rooms=1).validation_rooms == 2
    assert FitSettings(min_gain_rooms=4).validation_rooms == 4


# -- the whole procedure on simulated rooms ------------------------------------------------
@pytest.fixture(scope="module")
def tiny_rooms(tmp_path_factory):
    from ontodetect.synth import synthesize_many

    root = tmp_path_factory.mktemp("tiny")
    synthesize_many(4, "tiny", "rgbd", seed=11, out_dir=root, points=12_000)
    return root


def test_calibration_never_reads_the_held_out_scenes(tiny_rooms, tmp_path):
    import shutil

    root = tmp_path / "rooms"
    shutil.copytree(tiny_rooms, root)
    split = split_scenes(discover_scenes(root), 0.5, seed=3)
    for scene in split.held_out:  # make every held-out scene unreadable
        (root / scene.name / "cloud.ply").write_bytes(b"ply\nbroken")
    result = calibrate_dataset(
        root, split=0.5, seed=3, evaluate=False, settings=FitSettings(min_samples=2)
    )
    assert result.failed == []
    assert [s.name for s in result.split.held_out] == [s.name for s in split.held_out]
    assert result.before is None and result.comparison() == []
    assert sum(result.used.values()) > 0
    assert parse_ontology(result.text).names == result.base.names


def test_calibration_compares_before_and_after_on_held_out_scenes(tiny_rooms):
    result = calibrate_dataset(tiny_rooms, split=0.5, seed=3, settings=FitSettings(min_samples=2))
    held = [s.name for s in result.split.held_out]
    assert [s.name for s in result.before.scenes] == held
    assert [s.name for s in result.after.scenes] == held
    rows = {r["class"]: r for r in result.comparison()}
    assert set(rows) == {"chair", "sofa", "table", "overall"}
    assert rows["overall"]["ground_truth"] == result.before.primary.overall.num_gt
    doc = result.to_dict()
    assert doc["split"]["held_out"] == held and doc["settings"]["min_samples"] == 2
    with pytest.raises(InvalidParameterError, match="detect_options"):
        calibrate_dataset(tiny_rooms, detect_options={"ontology": result.base})


def test_a_single_calibration_room_keeps_the_original_and_says_so(tiny_rooms, tmp_path, capsys):
    from ontodetect.cli import main

    out = tmp_path / "one-room.yaml"
    report = tmp_path / "report.json"
    code = main(
        [
            "calibrate",
            str(tiny_rooms),
            "-o",
            str(out),
            "--split",
            "0.25",
            "--seed",
            "3",
            "--no-evaluate",
            "--report",
            str(report),
        ]
    )
    captured = capsys.readouterr()
    assert code == 0
    err = " ".join(captured.err.split())
    assert "warning: nested check NOT POSSIBLE, only 1 calibration room(s)" in err
    assert "the file keeps the original values" in err
    assert yaml.safe_load(out.read_text()) == yaml.safe_load(_builtin_text())
    doc = json.loads(report.read_text())
    assert doc["validation_rooms"] == [] and doc["nested_check"] == []
    assert "NOT POSSIBLE" in doc["check"]
    assert "NOT POSSIBLE" in out.read_text().split("format:")[0]  # the file's header says so


def test_softness_of_a_bound_only_loosens():
    from ontodetect.calibrate import fit_gaussian
    from ontodetect.ontology import Gaussian

    prior = Gaussian(6.0, 5.0, "max")
    tight = fit_gaussian(prior, [1.0, 1.2, 0.8, 1.1, 0.9] * 4, "tilt", prior_strength=0)
    assert tight.side == "max" and tight.mean == pytest.approx(6.0)
    assert tight.sigma == pytest.approx(5.0)  # values well inside: no sharper fall-off
    wide = fit_gaussian(prior, [2.0, 9.0, 15.0, 4.0, 12.0], "tilt", prior_strength=0)
    assert wide.mean > 6.0 and wide.sigma > 5.0
