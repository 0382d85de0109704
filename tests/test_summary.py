import numpy as np
import pytest

from ontodetect import point_cloud
from ontodetect.summary import describe_cloud, estimate_spacing, guess_units, guess_up


def _room(rng, up_axis=2, sign=1, scale=1.0, n=20000):
    """Floor, a table top and two walls: a crude room with a known up axis."""
    floor = np.c_[rng.uniform(0, 5, n), rng.uniform(0, 4, n), np.zeros(n)]
    table = np.c_[rng.uniform(1, 2, n // 4), rng.uniform(1, 2, n // 4), np.full(n // 4, 0.74)]
    wall = np.c_[np.zeros(n // 2), rng.uniform(0, 4, n // 2), rng.uniform(0, 2.6, n // 2)]
    pts = np.concatenate([floor, table, wall]) + rng.normal(0, 0.003, (n + n // 4 + n // 2, 3))
    if sign < 0:
        pts[:, 2] = 2.6 - pts[:, 2]
    order = [0, 1, 2]
    order[up_axis], order[2] = order[2], order[up_axis]
    return pts[:, order] * scale


@pytest.mark.parametrize(
    ("axis", "sign", "expected"), [(2, 1, "z"), (1, 1, "y"), (0, 1, "x"), (2, -1, "-z")]
)
def test_up_axis_guess(rng, axis, sign, expected):
    up = guess_up(_room(rng, axis, sign), "auto")
    assert up.axis == expected and up.choice == "auto"
    assert up.angle < 2.0 and up.confidence > 0.4


def test_units_guess(rng):
    assert guess_units(_room(rng)) == "metres"
    assert guess_units(_room(rng, scale=1000.0)) == "millimetres"


def test_spacing_of_a_grid():
    g = np.stack(np.meshgrid(np.arange(50), np.arange(50), [0]), -1).reshape(-1, 3) * 0.01
    assert estimate_spacing(g) == pytest.approx(0.01)


def test_describe_cloud(rng):
    cloud = point_cloud(_room(rng), fields={"label": np.zeros(35000, np.int32)})
    s = describe_cloud(cloud)
    assert s.num_points == 35000
    assert s.fields == ["label"]
    assert s.up_axis == "z" and s.up_default == "z"
    assert s.extent[0] == pytest.approx(5.0, abs=0.05)
    d = s.to_dict()
    assert d["units"] == "metres"


def test_describe_cloud_tells_a_single_view_from_a_fused_scan(rng):
    fused = describe_cloud(point_cloud(_room(rng)))
    assert fused.sensor is None and fused.to_dict()["sensor"] is None
    xyz = rng.random((6, 3)) + [0.0, 0.0, 1.0]
    frame = point_cloud(xyz, index=[0, 1, 2, 4, 5, 7]).with_meta(
        organized=True, width=4, height=2, viewpoint=[0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]
    )
    assert describe_cloud(frame).sensor == [0.5, 0.0, 0.0]
    assert describe_cloud(frame).up_default == "auto" and fused.up_default == "z"
    # an unorganized cloud's VIEWPOINT (a PCD default) says nothing about one view
    assert describe_cloud(frame.with_meta(organized=False)).sensor is None
