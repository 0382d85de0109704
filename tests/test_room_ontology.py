"""The ontology of a whole room on generated scenes: what only looks like a seat is not a
chair (a WC, a washbasin with a backsplash, a nightstand with a lamp), and easy chairs
(a club armchair, a curved shell chair) are."""

import numpy as np
import pytest

from ontodetect import detect
from ontodetect.config import Config
from ontodetect.synth.furniture import make_furniture
from ontodetect.synth.rooms import object_scene

#: Every class reported, one pass (the vote only steadies what one pass finds).
CONFIG = Config().with_overrides(["detect.classes=all", "detect.votes=1"])


def _built(kind, seed):
    """A kind built with this seed; basins always with a backsplash."""
    if kind.startswith("sink"):
        return make_furniture(kind, seed, backsplash=True)
    return kind


def _detections_on(kinds, seed):
    items = [
        tuple(_built(k, seed) for k in g) if isinstance(g, tuple) else _built(g, seed)
        for g in kinds
    ]
    cloud, scene = object_scene(items, points=40_000, seed=seed)
    result = detect(cloud, config=CONFIG, room=None, seed=seed)
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
