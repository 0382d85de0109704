"""Sensor artefacts: counts, labels kept aligned, known angles and offsets, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from ontodetect import point_cloud
from ontodetect.errors import InvalidParameterError
from ontodetect.synth.artefacts import (
    duplicate_floor_layer,
    punch_holes,
    scannet_sampling,
    tilt,
)

FLOOR, CHAIR = 2, 5


def small_room(rng: np.random.Generator):
    """A 2 x 2 m floor on a 5 cm grid (1600 points) and a 40 cm cube of chair points above it.

    Every point carries its row as the field ``row``, so alignment after an artefact is
    checked by ``fields["row"] == index``.
    """
    g = np.arange(0.0, 2.0, 0.05)
    xy = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    floor = np.c_[xy, np.zeros(len(xy))]
    chair = rng.uniform([0.8, 0.8, 0.4], [1.2, 1.2, 0.8], size=(400, 3))
    xyz = np.concatenate([floor, chair])
    n = len(xyz)
    cls = np.r_[np.full(len(floor), FLOOR), np.full(len(chair), CHAIR)]
    inst = np.r_[np.full(len(floor), 1), np.full(len(chair), 7)]
    rgb = rng.integers(0, 256, size=(n, 3), dtype=np.uint8)
    fields = {"class_id": cls, "instance": inst, "row": np.arange(n)}
    return point_cloud(xyz, rgb, fields=fields)


def aligned(cloud) -> bool:
    return bool(np.array_equal(cloud.fields["row"], cloud.index))


def test_scannet_sampling_keeps_exactly_the_asked_rows_in_random_order(rng):
    room = small_room(rng)
    out = scannet_sampling(room, 3, points=500)
    assert len(out) == 500
    assert len(np.unique(out.index)) == 500
    assert aligned(out)
    np.testing.assert_array_equal(out.xyz, room.xyz[out.index])
    np.testing.assert_array_equal(out.rgb, room.rgb[out.index])
    assert not np.all(np.diff(out.index) > 0)  # random order, as VoteNet's files
    assert out.meta["artefacts"] == [{"name": "scannet_sampling", "points": 500, "of": 2000}]
    again = scannet_sampling(room, 3, points=500)
    np.testing.assert_array_equal(again.index, out.index)
    assert not np.array_equal(scannet_sampling(room, 4, points=500).index, out.index)


def test_scannet_sampling_of_a_small_cloud_keeps_every_point(rng):
    room = small_room(rng)
    out = scannet_sampling(room, 0, points=10_000)
    assert sorted(out.index.tolist()) == list(range(len(room)))


def test_duplicate_floor_layer_adds_a_shifted_labelled_floor_patch(rng):
    room = small_room(rng)
    out = duplicate_floor_layer(room, 5, share=0.25, offset=(0.02, 0.10), max_tilt_deg=0.0)
    added = out.xyz[len(room) :]
    assert len(added) == 400  # a quarter of the 1600 floor points
    np.testing.assert_array_equal(out.xyz[: len(room)], room.xyz)
    assert np.all(out.fields["class_id"][len(room) :] == FLOOR)
    assert np.all(out.fields["instance"][len(room) :] == 1)
    # The copy is one flat layer 2-10 cm off the floor (no tilt asked for).
    z = np.unique(added[:, 2].round(9))
    assert len(z) == 1 and 0.02 <= abs(z[0]) <= 0.10
    entry = out.meta["artefacts"][-1]
    assert entry["name"] == "duplicate_floor_layer" and entry["points"] == 400
    assert entry["offset"] == pytest.approx(z[0], abs=1e-4)
    # Each copy keeps its source point's colour and xy; new rows follow the input's.
    src = out.fields["row"][len(room) :]
    np.testing.assert_allclose(added[:, :2], room.xyz[src, :2])
    np.testing.assert_array_equal(out.rgb[len(room) :], room.rgb[src])
    assert out.index[len(room) :].tolist() == list(range(len(room), len(room) + 400))
    # A patch: the copied points are the floor points nearest its centre.
    centre = added[:, :2].mean(axis=0)
    assert np.ptp(added[:, 0]) < 2.0 and np.ptp(added[:, 1]) < 2.0
    assert np.linalg.norm(centre - [1.0, 1.0]) < 1.5
    again = duplicate_floor_layer(room, 5, share=0.25, offset=(0.02, 0.10), max_tilt_deg=0.0)
    np.testing.assert_array_equal(again.xyz, out.xyz)


def test_duplicate_floor_layer_tilts_the_copy_by_at_most_the_limit(rng):
    room = small_room(rng)
    out = duplicate_floor_layer(room, 1, share=1.0, offset=0.05, max_tilt_deg=1.0)
    added = out.xyz[len(room) :]
    centred = added - added.mean(axis=0)
    normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
    angle = np.degrees(np.arccos(abs(normal[2])))
    assert angle == pytest.approx(out.meta["artefacts"][-1]["tilt_deg"], abs=1e-3)
    assert 0.0 < angle <= 1.0
    assert abs(added[:, 2].mean()) == pytest.approx(0.05, abs=1e-9)


def test_duplicate_floor_layer_needs_labels_and_a_floor(rng):
    room = small_room(rng)
    with pytest.raises(InvalidParameterError, match="class_id"):
        duplicate_floor_layer(point_cloud(room.xyz), 0)
    with pytest.raises(InvalidParameterError, match="floor points"):
        duplicate_floor_layer(room, 0, floor_class=99)


def test_punch_holes_removes_exactly_the_points_inside_the_discs(rng):
    room = small_room(rng)
    out = punch_holes(room, 11, count=3, radius=(0.2, 0.3))
    holes = out.meta["artefacts"][-1]["holes"]
    assert len(holes) == 3
    inside = np.zeros(len(room), dtype=bool)
    for h in holes:
        assert 0.2 <= h["radius"] <= 0.3
        d = np.linalg.norm(room.xyz - h["center"], axis=1)
        inside |= d <= h["radius"]
    kept = np.zeros(len(room), dtype=bool)
    kept[out.index] = True
    assert not np.any(kept & inside)
    assert kept.sum() + out.meta["artefacts"][-1]["removed"] == len(room)
    assert out.meta["artefacts"][-1]["removed"] > 0
    assert aligned(out)
    assert np.all(np.diff(out.index) > 0)  # order kept
    np.testing.assert_array_equal(
        punch_holes(room, 11, count=3, radius=(0.2, 0.3)).index, out.index
    )


def test_punch_holes_with_no_holes_changes_nothing(rng):
    room = small_room(rng)
    out = punch_holes(room, 0, count=0)
    np.testing.assert_array_equal(out.xyz, room.xyz)


@pytest.mark.parametrize("degrees", [2.0, 4.5])
def test_tilt_angle_is_recovered_from_the_floor(rng, degrees):
    room = small_room(rng)
    out = tilt(room, 2, degrees=degrees)
    floor = out.xyz[out.fields["class_id"] == FLOOR]
    normal = np.linalg.svd(floor - floor.mean(axis=0), full_matrices=False)[2][-1]
    assert np.degrees(np.arccos(abs(normal[2]))) == pytest.approx(degrees, abs=1e-6)
    entry = out.meta["artefacts"][-1]
    assert entry["degrees"] == degrees and entry["axis"][2] == 0.0
    # A rigid turn: distances between points are kept, labels stay with their points.
    np.testing.assert_allclose(
        np.linalg.norm(out.xyz[1:] - out.xyz[:-1], axis=1),
        np.linalg.norm(room.xyz[1:] - room.xyz[:-1], axis=1),
    )
    assert aligned(out)
    np.testing.assert_array_equal(tilt(room, 2, degrees=degrees).xyz, out.xyz)


def test_tilt_draws_the_angle_from_a_range(rng):
    room = small_room(rng)
    angles = [tilt(room, s).meta["artefacts"][-1]["degrees"] for s in range(5)]
    assert all(2.0 <= a <= 5.0 for a in angles) and len(set(angles)) == 5


def test_artefacts_chain_and_record_in_order(rng):
    room = small_room(rng)
    out = tilt(punch_holes(duplicate_floor_layer(room, 0), 1), 2)
    assert [a["name"] for a in out.meta["artefacts"]] == [
        "duplicate_floor_layer",
        "punch_holes",
        "tilt",
    ]
    assert aligned(out.select(out.index < len(room)))


@pytest.mark.parametrize(
    ("fn", "kwargs", "match"),
    [
        (scannet_sampling, {"points": 0}, "'points'"),
        (duplicate_floor_layer, {"share": 0.0}, "'share'"),
        (duplicate_floor_layer, {"offset": (0.1, 0.02)}, "low <= high"),
        (duplicate_floor_layer, {"max_tilt_deg": -1.0}, "'max_tilt_deg'"),
        (punch_holes, {"radius": -0.1}, "'radius'"),
        (punch_holes, {"count": 1.5}, "'count'"),
        (tilt, {"degrees": 120.0}, "'degrees'"),
        (tilt, {"degrees": "steep"}, "'degrees'"),
    ],
)
def test_bad_parameters_are_named(rng, fn, kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        fn(small_room(rng), 0, **kwargs)
