"""Scanning chosen objects in a corner of an empty room: labelled clouds for other tests."""

from __future__ import annotations

import numpy as np
import pytest

from ontodetect import InvalidParameterError
from ontodetect.synth.furniture import make_furniture
from ontodetect.synth.rooms import object_scene
from ontodetect.synth.scene import CLASS_IDS


@pytest.fixture(scope="module")
def bathroom_corner():
    return object_scene(
        ["toilet", "sink-pedestal", ("nightstand", "lamp-table")], room=(3.5, 3.0), points=8000
    )


def test_objects_stand_side_by_side_against_the_wall(bathroom_corner):
    _, scene = bathroom_corner
    assert scene.room_type == "objects"
    structure = [o.class_name for o in scene.objects if o.is_structure]
    assert sorted(structure) == ["ceiling", "floor", "wall", "wall", "wall", "wall"]
    objs = [o for o in scene.objects if not o.is_structure]
    assert [o.class_name for o in objs] == ["toilet", "sink", "cabinet", "lamp"]
    assert [o.instance_id for o in scene.objects] == list(range(1, len(scene.objects) + 1))
    toilet, sink, stand, lamp = objs
    for obj in (toilet, sink, stand):
        assert obj.vertices[:, 1].min() == pytest.approx(0.0, abs=1e-9)  # back to the wall
    assert toilet.vertices[:, 0].max() < sink.vertices[:, 0].min()  # apart along the wall
    assert lamp.vertices[:, 2].min() == pytest.approx(stand.extra["support_z"])


def test_the_cloud_is_labelled_with_every_object(bathroom_corner):
    cloud, scene = bathroom_corner
    assert 0 < len(cloud) <= 8000
    ids = cloud.fields["instance"]
    classes = cloud.fields["class_id"]
    for obj in scene.objects:
        if obj.class_name == "ceiling":
            continue
        mine = ids == obj.instance_id
        assert mine.any(), obj.kind
        assert np.all(classes[mine] == CLASS_IDS[obj.class_name])
    lamp = scene.objects[-1]
    pts = cloud.xyz[ids == lamp.instance_id]
    assert lamp.box.contains(pts, margin=0.01).all()


def test_same_seed_same_cloud_and_built_objects_are_taken_as_they_are():
    chair = make_furniture("chair-club", 4)
    a, sa = object_scene([chair, "tv-stand"], points=2000, seed=3)
    b, _ = object_scene([chair, "tv-stand"], points=2000, seed=3)
    assert np.array_equal(a.xyz, b.xyz)
    assert np.array_equal(a.fields["instance"], b.fields["instance"])
    placed = sa.objects[6]
    assert placed.kind == "chair-club"
    assert placed.dimensions == chair.dimensions
    assert np.array_equal(chair.pose, np.eye(4))  # the input is not modified


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"objects": ["bathtub", "bathtub"], "room": (2.5, 2.5)}, "'objects'"),
        ({"objects": [42]}, "'objects'"),
        ({"objects": ["lamp-table"], "room": (1.0, 3.0)}, "'room'"),
        ({"objects": ["lamp-table"], "seed": -1}, "'seed'"),
        ({"objects": ["lamp-table"], "sensor": "sonar"}, "'sensor'"),
    ],
)
def test_bad_arguments_are_named(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        object_scene(**kwargs)
