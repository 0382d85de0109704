"""One depth frame stored as bare points (SUN RGB-D's frames as VoteNet stores them, a PLY
written from a camera): its sensor at the origin, one surface per sight line. ``detect``
takes such a cloud as the frame it is (``detect.infer_view``), with a pixel grid made
from its sight lines; a scan fused from many views is never taken for one."""

import warnings

import numpy as np
import pytest

from ontodetect import DataWarning, point_cloud
from ontodetect._up import looks_like_one_view, view_grid
from ontodetect.config import Config
from ontodetect.pipeline import detect
from ontodetect.synth import synthesize


def _ray_cast(width=160, height=120, fov=(60.0, 45.0)):
    """A camera at the origin, 1.3 m above the floor, looking along +y (z up) at a wall
    4 m away with a box 2 m wide and 1 m tall in front of it: the first surface on every sight line,
    and, apart, the parts of the floor and wall the box hides."""
    az = np.radians(np.linspace(-fov[0] / 2, fov[0] / 2, width))
    el = np.radians(np.linspace(-fov[1] / 2, fov[1] / 2, height))
    a, e = np.meshgrid(az, el)
    d = np.stack([np.sin(a) * np.cos(e), np.cos(a) * np.cos(e), np.sin(e)], -1).reshape(-1, 3)
    hits = []
    t_wall = 4.0 / d[:, 1]
    t_floor = np.where(d[:, 2] < 0, -1.3 / np.minimum(d[:, 2], -1e-9), np.inf)
    t_box = 2.0 / d[:, 1]  # the box's front face, y = 2, |x| < 1, z in [-1.3, -0.3]
    p_box = d * t_box[:, None]
    on_box = (np.abs(p_box[:, 0]) < 1.0) & (p_box[:, 2] < -0.3)
    t = np.minimum(t_wall, t_floor)
    hidden = on_box & (t_box < t)
    first = np.where(hidden, t_box, t)
    hits = d * first[:, None]
    behind = d[hidden] * t[hidden, None]
    rng = np.random.default_rng(0)
    return hits + rng.normal(0, 0.003, hits.shape), behind


def test_a_depth_image_is_one_view_and_what_lies_behind_it_is_not():
    view, behind = _ray_cast()
    assert looks_like_one_view(view)
    assert not looks_like_one_view(np.r_[view, behind])  # the wall behind the box too
    assert not looks_like_one_view(view + [0.0, 0.0, 400.0e3])  # far away: no camera's range
    assert not looks_like_one_view(view[:500])  # too few points to judge


def test_a_fused_room_is_never_one_view():
    cloud = synthesize("tiny", seed=1).cloud
    for shift in ([0, 0, 0], -np.asarray(cloud.xyz).mean(axis=0), [0, 0, -1.3]):
        assert not looks_like_one_view(np.asarray(cloud.xyz) + shift)


def test_the_grid_of_a_view_has_about_a_point_a_pixel():
    view, _ = _ray_cast()
    pixels, width, height = view_grid(view)
    assert pixels.min() >= 0 and pixels.max() < width * height
    # Pixels of 0.7 times the sight lines' spacing: most points have one of their own.
    assert len(np.unique(pixels)) > 0.8 * len(view)


def test_detect_takes_a_bare_frame_as_one_and_says_so():
    view, _ = _ray_cast()
    cloud = point_cloud(view)
    with pytest.warns(DataWarning, match="one view seen from the origin"):
        detect(cloud, config=Config().with_overrides(["detect.votes=1"]), jobs=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DataWarning)
        try:
            detect(
                cloud,
                config=Config().with_overrides(["detect.votes=1", "detect.infer_view=false"]),
                jobs=1,
            )
        except DataWarning as w:
            assert "one view" not in str(w)


def test_a_bare_frame_in_a_cameras_own_axes_finds_its_floor():
    """The same view in a camera's axes (x right, y down, z forward): its sight lines run
    along z, so up is sought near -y, and the floor 1.3 m below the camera is found."""
    view, _ = _ray_cast()
    camera = np.c_[view[:, 0], -view[:, 2], view[:, 1]]  # z up, y forward -> y down, z forward
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = detect(
            point_cloud(camera), config=Config().with_overrides(["detect.votes=1"]), jobs=1
        )
    assert not any("no floor found" in str(w.message) for w in caught)
    up = np.asarray(result.frame["up"], dtype=float)
    assert up @ [0.0, -1.0, 0.0] > 0.99


def test_info_says_what_detect_does_with_a_bare_frame():
    """``info`` guesses up as ``detect`` will: on the view taken as a frame."""
    from ontodetect.summary import describe_cloud

    view, _ = _ray_cast()
    camera = np.c_[view[:, 0], -view[:, 2], view[:, 1]]
    summary = describe_cloud(point_cloud(camera))
    assert summary.up_default == "auto" and summary.up_axis == "-y"
    fused = describe_cloud(synthesize("tiny", seed=1).cloud)
    assert fused.up_default == "z"
