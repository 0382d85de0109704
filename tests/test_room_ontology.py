"""The ontology of a whole room on generated scenes: what only looks like a seat is not a
chair (a WC, a washbasin with a backsplash, a nightstand with a lamp), and easy chairs
(a club armchair, a curved shell chair) are."""

from pathlib import Path

import numpy as np
import pytest

from ontodetect import detect
from ontodetect.config import Config
from ontodetect.ontology import Ontology, load_ontology
from ontodetect.outputs import explain
from ontodetect.synth.furniture import make_furniture
from ontodetect.synth.rooms import object_scene

#: The example ontology of bedrooms (a nightstand by a bed), loaded over the built-in one.
BEDROOM = Path(__file__).resolve().parents[1] / "docs" / "examples" / "bedroom.yaml"
#: Every class reported, one pass (the vote only steadies what one pass finds).
CONFIG = Config().with_overrides(["detect.classes=all", "detect.votes=1"])


def _built(kind, seed):
    """A kind built with this seed; basins always with a backsplash."""
    if kind.startswith("sink"):
        return make_furniture(kind, seed, backsplash=True)
    return kind


def _detections_on(kinds, seed, ontology=None):
    items = [
        tuple(_built(k, seed) for k in g) if isinstance(g, tuple) else _built(g, seed)
        for g in kinds
    ]
    cloud, scene = object_scene(items, points=40_000, seed=seed)
    result = detect(cloud, config=CONFIG, ontology=ontology, room=None, seed=seed)
    return cloud, scene, result


def _covering(cloud, result, instance):
    """Labels of the detections whose points are mostly this instance's (IoU >= 0.25)."""
    inst = np.asarray(cloud.fields["instance"])
    truth = set(np.flatnonzero(inst == instance).tolist())
    labels = []
    for d in result.detections:
        pts = set(np.asarray(result.segmentation[d.cluster].point_indices).tolist())
        if len(pts & truth) / max(1, len(pts | truth)) >= 0.25:
            labels.append(d.label)
    return labels


def _instance(scene, kind):
    return next(o.instance_id for o in scene.objects if o.kind == kind)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize(
    ("kinds", "kind"),
    [
        (["toilet"], "toilet"),
        (["sink-vanity"], "sink-vanity"),
        (["sink-pedestal"], "sink-pedestal"),
        ([("nightstand", "lamp-table")], "nightstand"),
    ],
)
def test_what_only_looks_like_a_seat_is_not_a_chair(kinds, kind, seed):
    cloud, scene, result = _detections_on(kinds, seed)
    assert "chair" not in _covering(cloud, result, _instance(scene, kind))


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("kind", ["chair-club", "chair-shell-curved"])
def test_easy_chairs_are_chairs(kind, seed):
    cloud, scene, result = _detections_on([kind], seed)
    assert _covering(cloud, result, _instance(scene, kind)) == ["chair"]


def _without_easy_chair():
    """The built-in ontology with the chair alone: no easy chair beside it."""
    onto = load_ontology()
    chair_alone = tuple(c for c in onto.classes if c.name != "easy_chair")
    return Ontology(chair_alone, onto.source, onto.seeds)


@pytest.mark.slow
@pytest.mark.parametrize(("kind", "seed"), [("chair-wingback", 3), ("chair-club", 5)])
def test_the_easy_chair_takes_armchairs_the_chair_alone_misses(kind, seed):
    # The chair alone reads these as a sofa and a table (an easy chair's cushion sits where
    # a sofa's does, and its back and arms are larger planes than a chair's); with the easy
    # chair, a variant of the chair, they are chairs.
    cloud, scene, result = _detections_on([kind], seed, _without_easy_chair())
    assert "chair" not in _covering(cloud, result, _instance(scene, kind))
    cloud, scene, result = _detections_on([kind], seed)
    assert _covering(cloud, result, _instance(scene, kind)) == ["chair"]
    (found,) = [d for d in result.detections if d.label == "chair"]
    p = found.probabilities  # one description of the chair counts, never both
    assert min(p["chair"], p["easy_chair"]) == 0.0 < max(p["chair"], p["easy_chair"])
    # --explain shows the class the labelling chose, even when it is not the most probable.
    (row,) = [r for r in explain(result, top=1) if r["cluster"] == found.cluster]
    assert row["class"] in ("chair", "easy_chair")
    assert row["class"] in [c["class"] for c in row["classes"]]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("kind", ["sink-wall-hung", "sink-pedestal"])
def test_a_basin_is_a_sink_by_its_sunk_bowl(kind, seed):
    # The bowl is curved: MSAC fits its rim and seldom a plane in it, so the sink class,
    # which asks for one, lost these to a chair (wall-hung, seed 1) and a stool (pedestal,
    # seed 1). The basin class knows the bowl by what is sunk under the rim.
    cloud, scene, result = _detections_on([kind], seed)
    labels = _covering(cloud, result, _instance(scene, kind))
    assert labels and set(labels) == {"sink"}, labels


def test_classes_all_reports_the_competing_classes():
    cloud, _, result = _detections_on(["toilet", "sink-pedestal"], 0)
    found = {d.label for d in result.detections}
    assert found & {"toilet", "sink"}, found
    default = detect(cloud, config=Config().with_overrides(["detect.votes=1"]), room=None)
    assert {d.label for d in default.detections} <= {"chair", "sofa", "table"}


def test_cli_classes_all_and_a_bad_class_name(tmp_path, capsys):
    import json

    from ontodetect.cli import main
    from ontodetect.io import write_cloud

    cloud, _ = object_scene(
        ["toilet", make_furniture("sink-pedestal", 0, backsplash=True)], points=30_000, seed=0
    )
    path = tmp_path / "wc.ply"
    write_cloud(path, cloud)
    args = ["-q", "detect", str(path), "--votes", "1", "--no-picture", "--json"]
    assert main([*args, "-o", str(tmp_path / "all"), "--classes", "all"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert {d["label"] for d in doc["detections"]} & {"toilet", "sink"}
    assert doc["environment"]["source"] == "scan"
    assert main([*args, "-o", str(tmp_path / "bad"), "--classes", "chair,spaceship"]) == 2
    err = capsys.readouterr().err
    assert "detect.classes" in err and "spaceship" in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
@pytest.mark.parametrize(
    "seed",
    [
        0,
        pytest.param(
            1,
            marks=pytest.mark.xfail(
                reason="segmentation: this double bed's pillows and headboard come apart "
                "from its mattress (three clusters), none of them a whole bed",
                strict=True,
            ),
        ),
        2,
    ],
)
def test_a_nightstand_by_a_bed_is_a_nightstand_and_the_bed_a_bed(seed):
    # The example bedroom ontology over the built-in one: a bed with its head to the wall
    # and a nightstand with a lamp beside its head. The bed's headboard runs across the
    # mattress's end (no sofa's back), and the box beside it is a nightstand because the
    # bed is there (`near`: the factor comes from the bed, not from `missing`).
    onto = load_ontology(BEDROOM)
    items = ["bed", ("nightstand", "lamp-table")]
    cloud, scene = object_scene(items, room=(4.0, 3.2), points=50_000, seed=seed)
    result = detect(cloud, config=CONFIG, ontology=onto, room=None, seed=seed)
    assert _covering(cloud, result, _instance(scene, "bed")) == ["bed"]
    assert _covering(cloud, result, _instance(scene, "nightstand")) == ["nightstand"]
    (stand,) = [result.scores[d.cluster] for d in result.detections if d.label == "nightstand"]
    (rule,) = [c for c in stand.classes["nightstand"].constraints if c.part == "near bed"]
    assert rule.value is not None and rule.value < 0.3  # the bed gave the factor


@pytest.mark.slow
def test_a_bed_under_its_duvet_is_a_bed_with_the_example_only():
    # This generated bed's mattress shows flat over 1.35 m only (pillows at its head, a
    # duvet over its foot): the built-in bed asks for 1.7 m of it (the whole EN 1334
    # mattress) and the top is read as a table; the example's bed asks for what shows.
    cloud, scene = object_scene(["bed"], room=(4.0, 3.2), points=40_000, seed=6)
    bed = _instance(scene, "bed")
    built_in = detect(cloud, config=CONFIG, room=None, seed=6)
    example = detect(cloud, config=CONFIG, ontology=load_ontology(BEDROOM), room=None, seed=6)
    assert _covering(cloud, built_in, bed) == ["table"]
    assert _covering(cloud, example, bed) == ["bed"]
    (found,) = [d for d in example.detections if d.label == "bed"]
    mattress = example.scores[found.cluster].classes["bed"].assignment["mattress"]
    plane = example.segmentation[found.cluster].scored_planes[mattress]
    assert 1.1 < plane.length < 1.6


def test_the_example_bedroom_ontology_loads_over_the_built_in_one():
    onto = load_ontology(BEDROOM)
    assert [r.target for r in onto["nightstand"].near] == ["bed"]
    assert {p.name for p in onto["bed"].parts} == {"mattress", "headboard"}
    assert "chair" in onto and not onto["nightstand"].detect
