"""The quarter turn a scan is prepared in (``prepare.quarter_turns``): the same scan turned by
90°, 180° or 270° about the vertical is the same input to the last bit, so it gives the same
detections, reported in its own axes."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _turns import assert_turned_with_the_scan
from ontodetect import detect
from ontodetect.config import Config
from ontodetect.evaluation._dataset import turn_cloud
from ontodetect.preprocess import prepare, quarter_matrix, quarter_turns, turn_quarters
from ontodetect.preprocess._quarter import QUARTER_RATIO
from ontodetect.synth import synthesize

QUARTERS = Config().with_overrides(["prepare.quarter_turns=true"])
#: One pass: the vote's passes turn the levelled scan, after the quarter turn.
ONE_PASS = QUARTERS.with_overrides(["detect.votes=1"])


def _skewed(seed: int, n: int = 3000) -> np.ndarray:
    """A room-sized cloud longer along x than y, its mass nearer one end."""
    gen = np.random.default_rng(seed)
    return np.c_[gen.gamma(2.0, 1.0, n) * 1.5, gen.normal(0.0, 1.0, n), gen.random(n) * 2.5]


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000), st.integers(0, 3), st.floats(-50.0, 50.0), st.floats(-50.0, 50.0))
def test_a_turned_and_moved_copy_chooses_the_same_pose(seed, q, dx, dy):
    pts = _skewed(seed)
    k = quarter_turns(pts)
    moved = turn_quarters(pts, q) + [dx, dy, 0.0]
    k2 = quarter_turns(moved)
    assert k2 == (k - q) % 4
    # Turned into their poses, the two are the same points (up to the move).
    a = turn_quarters(pts, k)
    b = turn_quarters(moved, k2) - turn_quarters(np.array([[dx, dy, 0.0]]), k2)
    assert np.allclose(a, b, atol=1e-9)


def test_the_longer_side_goes_along_x_and_the_skewed_side_to_plus_x():
    pts = _skewed(0)
    assert quarter_turns(pts) == 0
    sd = turn_quarters(pts, 1)[:, :2].std(axis=0)
    assert sd[1] > QUARTER_RATIO * sd[0]  # turned: the long side runs along y
    assert quarter_turns(turn_quarters(pts, 1)) == 3
    mirrored = pts * [-1.0, 1.0, 1.0]  # the mass at the -x end: half a turn puts it at +x
    assert quarter_turns(mirrored) == 2


def test_a_symmetric_scan_keeps_its_axes():
    gen = np.random.default_rng(3)
    square = np.c_[gen.uniform(-2, 2, (4000, 2)), gen.random(4000)]
    sym = np.vstack([square, square * [-1, 1, 1], square * [1, -1, 1], square * [-1, -1, 1]])
    assert quarter_turns(sym) == 0
    assert quarter_turns(np.zeros((2, 3))) == 0


@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_quarter_turns_are_exact(k):
    pts = _skewed(1)
    assert np.array_equal(turn_quarters(turn_quarters(pts, k), 4 - k), pts)
    assert np.allclose(turn_quarters(pts, k), pts @ quarter_matrix(k).T, atol=0.0)


def test_the_levelling_transform_maps_the_input_and_the_floor_stays_in_the_input_frame():
    cloud = synthesize("tiny", seed=2).cloud
    turned = cloud.replace(xyz=turn_quarters(cloud.xyz, 1))
    scene = prepare(turned, QUARTERS)
    k = quarter_turns(turned.xyz)
    assert k != 0  # this test needs a scan that is turned
    T = scene.to_level
    inputs = turned.xyz[scene.inliers]
    levelled = inputs @ T[:3, :3].T + T[:3, 3]
    assert np.allclose(levelled, scene.cloud.xyz[scene.inliers], atol=1e-9)
    # The floor in the input frame: up is z, the floor at the input's own height.
    assert np.allclose(scene.up, [0.0, 0.0, 1.0], atol=1e-6)
    plain = prepare(turned)  # its own grids: the floor's fit may differ by a fraction of a mm
    assert scene.floor_z == pytest.approx(plain.floor_z, abs=1e-3)


def test_a_room_turned_by_quarters_gives_the_same_detections_in_its_own_axes():
    # Turned by a rotation matrix, as tools turn files: cos 90° is 6e-17, not 0.
    cloud = synthesize("office", seed=1).cloud
    base = detect(cloud, config=ONE_PASS, seed=0, jobs=1)
    assert base.detections
    for degrees in (90.0, 180.0, 270.0):
        turned = detect(turn_cloud(cloud, degrees), config=ONE_PASS, seed=0, jobs=1)
        assert_turned_with_the_scan(base, turned, degrees)


def test_a_depth_frame_keeps_its_axes():
    frame = synthesize("tiny", seed=0, sensor="rgbd-frame").cloud
    assert QUARTERS.prepare.quarter_turns
    scene = prepare(frame, QUARTERS)
    plain = prepare(frame)
    assert np.array_equal(scene.to_level, plain.to_level)


def test_the_picture_keeps_the_files_heading():
    from ontodetect.outputs import _picture_frame

    cloud = synthesize("tiny", seed=2).cloud
    turned = cloud.replace(xyz=turn_quarters(cloud.xyz, 1))
    result = detect(turned, config=ONE_PASS, seed=0, jobs=1)
    k = result.segmentation.prepared.info["quarter_turns"]
    assert k != 0  # this test needs a scan prepared in another pose than its file's
    xyz, boxes = _picture_frame(result)
    # Drawn in the input's horizontal axes (the levelled frame differs by a tilt and a shift).
    inputs = turned.xyz[result.segmentation.prepared.inliers]
    drawn = xyz[result.segmentation.prepared.inliers]
    assert np.allclose(
        drawn[:, :2] - drawn[:, :2].mean(0), inputs[:, :2] - inputs[:, :2].mean(0), atol=1e-6
    )
    for box, d in zip(boxes, result.detections):
        assert np.allclose(
            box.center[:2] - drawn[:, :2].mean(0), d.center[:2] - inputs[:, :2].mean(0), atol=1e-6
        )
    plain = detect(turned, config=Config().with_overrides(["detect.votes=1"]), seed=0, jobs=1)
    assert "quarter_turns" not in plain.segmentation.prepared.info
