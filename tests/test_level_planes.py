"""Level layers (``planes.level_first``): a gently curved seat is found as a level plane
before MSAC can cut it with a slanted plane through seat and backrest."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect.errors import InvalidParameterError
from ontodetect.segment.planes import LEVEL_MIN_WIDTH, extract_planes, level_layers

THRESHOLD = 0.01


def _grid(xs, ys):
    x, y = np.meshgrid(xs, ys)
    return x.ravel(), y.ravel()


def _cushioned_chair(sag=0.025, spacing=0.02):
    """A 0.45 m seat whose cushion sags ``sag`` at its middle (a paraboloid, its rim at
    0.46 m) and a backrest reclined by 15°, on a grid of ``spacing``: (points, seat rows)."""
    x, y = _grid(np.arange(0, 0.45, spacing), np.arange(0, 0.45, spacing))
    r2 = ((x - 0.225) ** 2 + (y - 0.225) ** 2) / 0.225**2
    seat = np.column_stack([x, y, 0.46 - sag * np.clip(1 - r2, 0, 1)])
    u, v = _grid(np.arange(0, 0.45, spacing), np.arange(0, 0.45, spacing))
    lean = math.radians(15)
    back = np.column_stack([u, 0.46 + v * math.sin(lean), 0.48 + v * math.cos(lean)])
    return np.vstack([seat, back]), np.arange(len(seat))


def test_level_layers_are_the_densest_bands_without_overlap():
    z = np.r_[np.full(30, 0.45), np.full(20, 0.75), np.full(5, 0.9), [0.1, 0.46, 0.76, 1.0]]
    pts = np.column_stack([np.zeros_like(z), np.zeros_like(z), z])
    layers = level_layers(pts, threshold=0.01, min_inliers=10)
    assert [len(b) for b in layers] == [31, 21]  # each band takes the stray point in it
    assert np.allclose(pts[layers[0], 2].mean(), 0.45, atol=0.01)
    assert np.allclose(pts[layers[1], 2].mean(), 0.75, atol=0.02)
    assert level_layers(pts, threshold=0.01, min_inliers=100) == []
    with pytest.raises(InvalidParameterError, match="threshold"):
        level_layers(pts, threshold=0.0)


@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=20, deadline=None)
def test_level_layers_do_not_depend_on_the_order_of_the_points(seed):
    pts, _ = _cushioned_chair()
    perm = np.random.default_rng(seed).permutation(len(pts))
    here = [set(b.tolist()) for b in level_layers(pts, threshold=THRESHOLD, min_inliers=20)]
    there = [
        {int(perm[i]) for i in b}
        for b in level_layers(pts[perm], threshold=THRESHOLD, min_inliers=20)
    ]
    assert here == there


def test_a_sagging_seat_is_found_level_before_the_rest():
    """The cushion sags 2.5 cm, more than the inlier distance: its rim and most of its
    surface lie in one band; the level plane comes first and holds most of the seat, and
    the backrest is still found after it."""
    pts, seat = _cushioned_chair()
    runs = [
        extract_planes(
            pts, threshold=THRESHOLD, min_points=20, min_extent=0.25, rng=seed, level_first=True
        )
        for seed in range(4)
    ]
    first = runs[0][0]
    assert first.tilt < 5 and first.height == pytest.approx(0.455, abs=0.01)
    assert np.isin(first.inliers, seat).all()
    assert len(first.inliers) >= 0.7 * len(seat)
    # No random draw finds it: every seed gives the same seat, point for point.
    assert all(np.array_equal(run[0].inliers, first.inliers) for run in runs)
    for planes in runs:
        assert any(60 < p.tilt < 85 and p.length > 0.4 for p in planes[1:])  # the backrest


def test_a_band_across_a_slanted_surface_is_no_level_plane():
    """A 30° ramp holds a band of points at every height, but a band is a strip narrower
    than a seat: no level plane is taken from it."""
    x, y = _grid(np.arange(0, 0.6, 0.01), np.arange(0, 0.6, 0.01))
    ramp = np.column_stack([x, y, 0.3 + y * math.tan(math.radians(30))])
    planes = extract_planes(
        ramp, threshold=THRESHOLD, min_points=20, min_extent=0.25, rng=0, level_first=True
    )
    assert planes and all(p.tilt > 20 for p in planes)
    assert 2 * THRESHOLD / math.tan(math.radians(30)) < LEVEL_MIN_WIDTH
