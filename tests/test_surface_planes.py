"""Planes from the surface's own normals (``planes.hypotheses: surface``): MSAC's cost, no
random draw, so the same surface gives the same planes whatever the seed, and a surface
moved by a fraction of a millimetre gives the same planes moved with it."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect.preprocess import graph_normals
from ontodetect.segment import radius_graph
from ontodetect.segment.planes import extract_planes, local_plane


def _chair(seed=0, noise=0.002):
    """A seat (0.45 x 0.45 m at 0.46 m) and a backrest above its back edge."""
    gen = np.random.default_rng(seed)
    seat = np.column_stack([gen.uniform(0, 0.45, (900, 2)), np.full(900, 0.46)])
    back = np.column_stack(
        [gen.uniform(0, 0.45, 700), np.full(700, 0.45), gen.uniform(0.5, 0.95, 700)]
    )
    pts = np.vstack([seat, back])
    return pts + gen.normal(0, noise, pts.shape)


def _surface(pts, radius=0.04):
    return graph_normals(pts, radius_graph(pts, radius))


def _planes(pts, rng):
    normals, variation = _surface(pts)
    return extract_planes(pts, normals=normals, variation=variation, min_points=50, rng=rng)


def test_seat_and_backrest_are_found_whatever_the_seed():
    pts = _chair()
    runs = [_planes(pts, seed) for seed in (0, 1, 7)]
    first = [(round(p.tilt), round(p.height, 2), p.num_points) for p in runs[0]]
    assert [f[:2] for f in first] == [(0, 0.46), (90, 0.72)]
    for other in runs[1:]:
        assert [(round(p.tilt), round(p.height, 2), p.num_points) for p in other] == first
        for a, b in zip(runs[0], other):
            assert np.array_equal(a.inliers, b.inliers)


def test_a_jitter_below_a_millimetre_keeps_the_planes():
    pts = _chair(seed=3)
    moved = pts + np.random.default_rng(9).normal(0, 0.0003, pts.shape)
    a, b = _planes(pts, 0), _planes(moved, 0)
    assert len(a) == len(b)
    for p, q in zip(a, b):
        shared = np.intersect1d(p.inliers, q.inliers).size
        assert shared >= 0.97 * max(p.num_points, q.num_points)
        assert math.degrees(math.acos(min(1.0, abs(float(p.normal @ q.normal))))) < 0.2


@settings(max_examples=25, deadline=None)
@given(
    st.floats(0.0, 80.0),
    st.floats(-math.pi, math.pi),
    st.floats(-2.0, 2.0),
    st.integers(0, 2**16),
)
def test_any_plane_is_recovered_among_outliers(tilt, azimuth, offset, seed):
    gen = np.random.default_rng(seed)
    t, a = math.radians(tilt), azimuth
    normal = np.array([math.sin(t) * math.cos(a), math.sin(t) * math.sin(a), math.cos(t)])
    u = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    st_ = gen.uniform(-0.5, 0.5, (600, 2))
    plane = st_[:, :1] * u + st_[:, 1:] * v - offset * normal
    plane += gen.normal(0, 0.002, plane.shape)
    clutter = gen.uniform(-1, 1, (150, 3)) - offset * normal
    pts = np.vstack([plane, clutter])
    normals, variation = _surface(pts, 0.08)
    found = local_plane(pts, normals, variation, threshold=0.01, min_inliers=50)
    assert found
    angle = math.degrees(math.acos(min(1.0, abs(float(found.model.normal @ normal)))))
    assert angle < 0.5
    assert np.isin(np.arange(600), found.inliers).mean() > 0.95
