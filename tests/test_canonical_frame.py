"""The canonical horizontal frame (``prepare.frame: canonical``): a room turned by any
angle and moved in its file meets the same voxels, so that detection does not depend on
where the scan's file put its axes."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect import detect
from ontodetect.config import Config
from ontodetect.geometry import yaw_pose
from ontodetect.preprocess import prepare
from ontodetect.preprocess._prepare import canonical_pose
from ontodetect.synth import synthesize
from test_preprocess import room

#: The canonical frame is opt-in.
CANONICAL = Config().with_overrides(["prepare.frame=canonical"])


def _turned(points, degrees, shift=(0.0, 0.0)):
    T = yaw_pose(shift[0], shift[1], math.radians(degrees))
    return points @ T[:3, :3].T + T[:3, 3]


def _groups(prepared):
    """The partition of the input points into voxels, as a set of frozensets of rows."""
    p2v = prepared.voxels.point_to_voxel
    order = np.argsort(p2v, kind="stable")
    bounds = np.flatnonzero(np.diff(p2v[order])) + 1
    return {frozenset(g.tolist()) for g in np.split(order, bounds) if p2v[g[0]] >= 0}


def test_the_walls_main_direction_becomes_x_and_the_median_the_origin():
    pts, _ = room(np.random.default_rng(0))
    turned = _turned(pts, 30.0, (5.0, -2.0))
    scene = prepare(turned, CANONICAL)
    c = scene.centers
    # The walls run along x and y again (their points have a few distinct x or y values).
    walls = c[(c[:, 2] > 1.2) & (c[:, 2] < 2.0)]
    xs = np.round(walls[:, 0], 1)
    ys = np.round(walls[:, 1], 1)
    on_axis = np.mean(np.isin(xs, [xs.min(), xs.max()]) | np.isin(ys, [ys.min(), ys.max()]))
    assert on_axis > 0.9
    assert np.abs(np.median(c[:, :2], axis=0)).max() < 0.05


def test_a_quarter_turn_and_a_move_give_the_same_voxels():
    pts, _ = room(np.random.default_rng(1), spacing=0.04)
    base = _groups(prepare(pts, CANONICAL))
    for quarter in (1, 2, 3):
        moved = _groups(prepare(_turned(pts, 90.0 * quarter, (123.4, -56.7)), CANONICAL))
        # The same grids: only a point within rounding error of a voxel's face may cross.
        assert len(base & moved) >= 0.998 * len(base), quarter


def _yaw(T):
    return math.degrees(math.atan2(T[1, 0], T[0, 0]))


@settings(max_examples=10, deadline=None)
@given(st.floats(-180.0, 180.0), st.floats(-50.0, 50.0), st.floats(-50.0, 50.0))
def test_any_turn_is_undone_to_within_a_tenth_of_a_degree(degrees, dx, dy):
    pts, _ = room(np.random.default_rng(2), spacing=0.05)
    base = prepare(pts, CANONICAL).to_level
    moved = prepare(_turned(pts, degrees, (dx, dy)), CANONICAL).to_level
    # The frames differ by the turn, up to a quarter turn (walls at right angles).
    error = (_yaw(moved) + degrees - _yaw(base) + 45.0) % 90.0 - 45.0
    assert abs(error) < 0.1


def test_the_input_frame_keeps_the_files_axes():
    pts, _ = room(np.random.default_rng(0))
    cfg = Config().with_overrides(["prepare.frame=input"])
    scene = prepare(_turned(pts, 30.0), cfg)
    assert np.allclose(scene.to_level[:2, :2], np.eye(2), atol=1e-6)


def test_canonical_pose_without_walls_follows_the_spread():
    rng = np.random.default_rng(3)
    pts = np.c_[rng.normal(0, [2.0, 0.3], (2000, 2)), rng.random(2000)]
    pts[:, :2] = _turned(np.c_[pts[:, :2], np.zeros(2000)], 40.0)[:, :2]
    T = canonical_pose(pts, np.zeros((0, 3)), np.zeros(0))
    main = T[:2, :2] @ [math.cos(math.radians(40)), math.sin(math.radians(40))]
    assert abs(abs(main[0]) - 1.0) < 1e-3


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="the voxels are the same up to a few points on voxel faces, and that is enough to "
    "move one detection downstream (clusters, planes and scores amplify it): the canonical "
    "frame is needed for stability, not enough",
)
def test_detections_of_a_turned_and_moved_room_are_the_same():
    """The property users meet: the same room, its file's axes turned by a quarter and its
    origin moved, gives the same objects on the same points (up to the few points within
    rounding error of a voxel's face)."""
    cloud = synthesize("dining_room", "rgbd", seed=11, points=40_000).cloud
    config = Config().with_overrides(["detect.votes=1", "prepare.frame=canonical"])
    T = yaw_pose(250.0, -80.0, math.pi / 2)
    moved = cloud.replace(xyz=cloud.xyz @ T[:3, :3].T + T[:3, 3])
    a = detect(cloud, config=config, seed=0)
    b = detect(moved, config=config, seed=0)
    assert a.detections and sorted(d.label for d in a.detections) == sorted(
        d.label for d in b.detections
    )
    for d in a.detections:
        p = set(np.asarray(d.point_indices).tolist())
        best = max(
            len(p & q) / len(p | q)
            for q in (set(np.asarray(e.point_indices).tolist()) for e in b.detections)
            if q
        )
        assert best >= 0.95, d.label
