"""A scan prepared with its walls along the axes (``prepare.walls_to_axes``): the same scan
turned by any angle about the vertical, moved or shuffled is the same input to the last
bit, so it gives the same detections, reported in its own axes."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _turns import assert_turned_with_the_scan
from ontodetect import detect
from ontodetect.config import Config
from ontodetect.evaluation._dataset import turn_cloud
from ontodetect.preprocess import prepare, turn_about_z, wall_yaw
from ontodetect.synth import synthesize

WALLS = Config().with_overrides(["prepare.walls_to_axes=true"])
#: One pass: the vote's passes turn the levelled scan, after the walls' turn.
ONE_PASS = WALLS.with_overrides(["detect.votes=1"])


def _room(seed: int, n: int = 1500) -> tuple[np.ndarray, float]:
    """Two walls at a right angle, a floor and a lump of clutter, turned by a random yaw
    (returned, in degrees)."""
    gen = np.random.default_rng(seed)
    wall = np.c_[gen.uniform(0, 5, n), np.zeros(n), gen.uniform(0, 2.5, n)]
    side = np.c_[np.zeros(n), gen.uniform(0, 4, n), gen.uniform(0, 2.5, n)]
    floor = np.c_[gen.uniform(0, 5, (n, 2)) * [1.0, 0.8], np.zeros(n)]
    clutter = gen.normal([2.0, 2.0, 0.5], 0.3, (n // 3, 3))
    pts = np.vstack([wall, side, floor, clutter]) + gen.normal(0.0, 0.003, (3 * n + n // 3, 3))
    yaw = gen.uniform(-math.pi, math.pi)
    return turn_about_z(pts, yaw), math.degrees(yaw)


def _mod90(degrees: float) -> float:
    return (degrees + 45.0) % 90.0 - 45.0


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000), st.floats(-180.0, 180.0), st.floats(-100.0, 100.0))
def test_the_walls_direction_turns_with_the_scan_to_the_rounding_error(seed, degrees, dx):
    pts, _ = _room(seed)
    turned = turn_about_z(pts, math.radians(degrees)) + [dx, -dx, 0.5]
    a, b = math.degrees(wall_yaw(pts)), math.degrees(wall_yaw(turned))
    assert abs(_mod90(b - a - degrees)) < 1e-8
    # A shuffle sums the same moments in another order.
    order = np.random.default_rng(seed).permutation(len(pts))
    assert abs(_mod90(math.degrees(wall_yaw(pts[order])) - a)) < 1e-8


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_walls_direction_is_the_walls_own(seed):
    pts, truth = _room(seed)
    yaw = math.degrees(wall_yaw(pts))
    assert -45.0 < yaw <= 45.0
    assert abs(_mod90(yaw - truth)) < 0.2  # clutter and corners bend it a little
    assert wall_yaw(np.zeros((5, 3))) == 0.0  # too few points: no direction


@pytest.mark.parametrize("degrees", [23.7, -131.0])
def test_a_turned_moved_and_shuffled_scan_is_the_same_input_to_the_last_bit(degrees):
    cloud = synthesize("tiny", seed=2).cloud
    base = prepare(cloud, WALLS)
    turned = turn_cloud(cloud, degrees)
    moved = turned.replace(xyz=turned.xyz + [1000.25, -37.5, 0.0])
    order = np.random.default_rng(0).permutation(len(cloud))
    assert np.array_equal(prepare(turned, WALLS).cloud.xyz, base.cloud.xyz)
    # Shuffled: the same horizontal coordinates; the floor the heights are levelled on is
    # fitted by sums taken in another order (within a femtometre).
    shuffled = prepare(turned.select(order), WALLS).cloud.xyz[np.argsort(order)]
    assert np.array_equal(shuffled[:, :2], base.cloud.xyz[:, :2])
    assert np.abs(shuffled[:, 2] - base.cloud.xyz[:, 2]).max() <= 1e-12
    # A move rounds the input itself (1e-13 m at a kilometre): read to the nanometre, all
    # but a few horizontal coordinates come back to the bit and those within the
    # nanometre; the heights, levelled on a floor fitted to those, within a picometre.
    far = prepare(moved.select(order), WALLS).cloud.xyz[np.argsort(order)]
    assert np.abs(far[:, :2] - base.cloud.xyz[:, :2]).max() <= 1.5e-9
    assert np.mean(far[:, :2] == base.cloud.xyz[:, :2]) > 0.999
    assert np.abs(far[:, 2] - base.cloud.xyz[:, 2]).max() <= 1e-12
    plain = [prepare(c).cloud.xyz for c in (cloud, turned)]
    assert not np.allclose(plain[0], plain[1])  # without: the turn stays in the levelled frame


def test_the_levelling_transform_maps_the_input_and_the_floor_stays_in_the_input_frame():
    cloud = synthesize("tiny", seed=2).cloud
    turned = turn_cloud(cloud, 31.0)
    turned = turned.replace(xyz=turned.xyz + [250.0, 4.0, 0.3])
    scene = prepare(turned, WALLS)
    assert scene.info["walls_yaw"] != 0.0
    T = scene.to_level
    inputs = turned.xyz[scene.inliers]
    levelled = inputs @ T[:3, :3].T + T[:3, 3]
    flat = scene.floor_map is None
    assert np.allclose(levelled[:, :2], scene.cloud.xyz[scene.inliers, :2], atol=1e-6)
    if flat:
        assert np.allclose(levelled, scene.cloud.xyz[scene.inliers], atol=1e-6)
    # The floor in the input frame: up is z, the floor at the input's own height (0.3 m).
    assert np.allclose(scene.up, [0.0, 0.0, 1.0], atol=1e-3)
    centre = turned.xyz.mean(axis=0)
    assert scene.up @ centre - scene.floor_z == pytest.approx(centre[2] - 0.3, abs=0.01)


@pytest.mark.slow
def test_a_room_turned_by_any_angle_gives_the_same_detections_in_its_own_axes():
    cloud = synthesize("office", seed=1).cloud
    base = detect(cloud, config=ONE_PASS, seed=0, jobs=1)
    assert base.detections
    for degrees in (17.0, 218.5):
        turned = detect(turn_cloud(cloud, degrees), config=ONE_PASS, seed=0, jobs=1)
        assert_turned_with_the_scan(base, turned, degrees)


def test_a_depth_frame_and_a_given_up_axis_keep_their_axes():
    frame = synthesize("tiny", seed=0, sensor="rgbd-frame").cloud
    assert np.array_equal(prepare(frame, WALLS).to_level, prepare(frame).to_level)
    cloud = synthesize("tiny", seed=2).cloud
    other_up = WALLS.with_overrides(["prepare.up=y"])
    scene = prepare(cloud.replace(xyz=cloud.xyz[:, [0, 2, 1]]), other_up)
    assert "walls_yaw" not in scene.info


def test_the_picture_keeps_the_files_heading():
    from ontodetect.outputs import _picture_frame

    cloud = synthesize("tiny", seed=2).cloud
    turned = turn_cloud(cloud, 40.0)
    result = detect(turned, config=ONE_PASS, seed=0, jobs=1)
    prepared = result.segmentation.prepared
    assert prepared.info["walls_yaw"] != 0.0
    xyz, boxes = _picture_frame(result)
    # Drawn in the input's horizontal axes (the levelled frame differs by a tilt and a shift).
    inputs = turned.xyz[prepared.inliers]
    drawn = xyz[prepared.inliers]
    assert np.allclose(
        drawn[:, :2] - drawn[:, :2].mean(0), inputs[:, :2] - inputs[:, :2].mean(0), atol=1e-6
    )
    for box, d in zip(boxes, result.detections):
        assert np.allclose(
            box.center[:2] - drawn[:, :2].mean(0), d.center[:2] - inputs[:, :2].mean(0), atol=1e-6
        )
        turn = (box.yaw - d.yaw) % math.pi
        assert min(turn, math.pi - turn) < 1e-6
    plain = detect(turned, config=Config().with_overrides(["detect.votes=1"]), seed=0, jobs=1)
    assert "walls_yaw" not in plain.segmentation.prepared.info
