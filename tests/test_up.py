"""One up-axis heuristic for ``info`` and ``detect``, and ``auto`` the default for frames."""

import numpy as np
import pytest

from ontodetect import point_cloud
from ontodetect._up import (
    AUTO_FRAME,
    STRUCTURE_CELL,
    VOXEL_SIZE,
    default_up,
    guess_up,
    is_single_view,
    up_hint,
)
from ontodetect.config import UP_CHOICES, Config
from ontodetect.preprocess import find_ground
from ontodetect.summary import describe_cloud
from ontodetect.synth import synthesize


def _room(rng, n=8000):
    """Floor, a table top and two walls, z up."""
    floor = np.c_[rng.uniform(0, 5, n), rng.uniform(0, 4, n), np.zeros(n)]
    table = np.c_[rng.uniform(1, 2, n // 4), rng.uniform(1, 2, n // 4), np.full(n // 4, 0.74)]
    wall_x = np.c_[np.zeros(n // 2), rng.uniform(0, 4, n // 2), rng.uniform(0, 2.6, n // 2)]
    wall_y = np.c_[rng.uniform(0, 5, n // 2), np.full(n // 2, 4.0), rng.uniform(0, 2.6, n // 2)]
    return np.concatenate([floor, table, wall_x, wall_y]) + rng.normal(
        0, 0.003, (2 * n + n // 4, 3)
    )


def test_the_default_is_auto_for_frames_and_z_for_fused_scans(rng):
    fused = point_cloud(_room(rng))
    organized = fused.with_meta(organized=True, width=100, height=len(fused) // 100)
    placed = fused.with_meta(sensor_position=[1.0, 1.0, 1.5])
    assert Config().prepare.up == AUTO_FRAME and AUTO_FRAME in UP_CHOICES
    assert [is_single_view(c) for c in (fused, organized, placed)] == [False, True, True]
    assert [default_up(c) for c in (fused, organized, placed)] == ["z", "auto", "auto"]
    assert default_up(organized, "z") == "z" and default_up(fused, "auto") == "auto"
    assert up_hint(organized) == ("-y", 60.0) and up_hint(placed)[0] == "z"
    assert up_hint(fused) == ("z", None)


def test_guess_up_assumes_the_configuration_s_defaults():
    cfg = Config().prepare
    assert (cfg.voxel_size, cfg.structure_cell) == (VOXEL_SIZE, STRUCTURE_CELL)


@pytest.mark.parametrize("turn", [(0, 1, 2), (0, 2, 1)])
def test_info_says_what_detect_up_auto_uses(rng, turn):
    """The same heuristic on the same input: info's axis is the axis preparation takes."""
    xyz = _room(rng)[:, list(turn)]
    cloud = point_cloud(xyz)
    ground = find_ground(cloud, Config().with_overrides(["prepare.up=auto"]))
    guess = guess_up(cloud, "auto")
    assert guess.direction @ ground.floor.normal > np.cos(np.radians(2.0))
    summary = describe_cloud(cloud)
    assert summary.up_axis == guess.axis == ("z" if turn == (0, 1, 2) else "y")
    assert summary.up_default == "z"


def test_a_camera_frame_is_estimated_by_default():
    frame = synthesize("office", "rgbd-frame", seed=1, points=20_000).cloud
    assert frame.meta.get("organized") and frame.meta.get("height", 0) > 1
    guess = guess_up(frame)
    assert guess.choice == "auto" and guess.axis == "-y" and guess.single_view
    ground = find_ground(frame)  # the configuration's default: auto-frame
    assert guess.direction @ ground.floor.normal > np.cos(np.radians(2.0))
    assert describe_cloud(frame).up_default == "auto"
