"""Clustering primitives on voxel centres: DBSCAN, Euclidean, region growing, graphs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ontodetect.errors import InvalidParameterError
from ontodetect.segment import (
    core_neighbors,
    dbscan,
    effective_radius,
    euclidean_clusters,
    radius_graph,
    region_growing,
    relabel,
)

RADIUS = 0.05


def blob(rng, center, n=300, size=0.2, spacing=0.01):
    """A dense cube-ish cloud of points around ``center``."""
    g = np.arange(0, size, spacing)
    pts = np.stack(np.meshgrid(g, g, g[:5]), -1).reshape(-1, 3)
    return pts + np.asarray(center) + rng.normal(0, 0.001, pts.shape)


def test_objects_two_radii_apart_are_separated(rng):
    a = blob(rng, (0, 0, 0))
    b = blob(rng, (0.2 + 2 * RADIUS, 0, 0))  # gap of two radii between the faces
    pts = np.vstack([a, b])
    for labels in (dbscan(pts, RADIUS, 4), euclidean_clusters(pts, RADIUS)):
        assert len(set(labels[: len(a)].tolist())) == 1
        assert len(set(labels[len(a) :].tolist())) == 1
        assert labels[0] != labels[-1]


def test_touching_objects_are_merged(rng):
    a = blob(rng, (0, 0, 0))
    b = blob(rng, (0.2 + 0.5 * RADIUS, 0, 0))  # gap of half a radius
    pts = np.vstack([a, b])
    assert set(dbscan(pts, RADIUS, 4).tolist()) == {0}
    assert set(euclidean_clusters(pts, RADIUS).tolist()) == {0}


def test_dbscan_noise_and_border_points():
    line = np.c_[np.arange(10) * 0.02, np.zeros(10), np.zeros(10)]
    lonely = [[5.0, 5.0, 5.0]]
    border = [[0.18 + 0.045, 0.0, 0.0]]  # one neighbour only, next to the line's end
    labels = dbscan(np.vstack([line, lonely, border]), RADIUS, 3)
    assert labels[10] == -1  # noise
    assert labels[11] == labels[9] == 0  # border point joins its core neighbour
    assert dbscan(np.zeros((0, 3)), RADIUS, 3).shape == (0,)
    assert (dbscan(np.eye(3) * 10, RADIUS, 2) == -1).all()


def test_largest_cluster_first_and_deterministic(rng):
    small = blob(rng, (0, 0, 0), size=0.1)
    big = blob(rng, (1, 0, 0), size=0.3)
    pts = np.vstack([small, big])
    labels = euclidean_clusters(pts, RADIUS)
    assert labels[-1] == 0 and labels[0] == 1
    assert np.array_equal(labels, euclidean_clusters(pts, RADIUS))


@given(st.permutations(list(range(40))))
def test_clusters_do_not_depend_on_point_order(order):
    rng = np.random.default_rng(3)
    pts = np.vstack([rng.random((20, 3)) * 0.1, rng.random((20, 3)) * 0.1 + 1.0])
    order = np.asarray(order)
    a = euclidean_clusters(pts, RADIUS)
    b = euclidean_clusters(pts[order], RADIUS)
    # Same partition: two points share a label in one run iff they do in the other.
    same_a = a[order][:, None] == a[order][None, :]
    same_b = b[:, None] == b[None, :]
    assert np.array_equal(same_a, same_b)


def test_region_growing_splits_at_folds():
    g = np.stack(np.meshgrid(np.arange(15), np.arange(15)), -1).reshape(-1, 2) * 0.02
    seat = np.c_[g, np.zeros(len(g))]
    back = np.c_[g[:, 0], np.zeros(len(g)), g[:, 1] + 0.02]
    normals = np.repeat([[0, 0, 1], [0, 1, 0]], len(g), axis=0).astype(float)
    labels = region_growing(np.vstack([seat, back]), normals, 0.03, 15.0)
    assert len(set(labels[: len(g)].tolist())) == 1
    assert len(set(labels[len(g) :].tolist())) == 1
    assert labels[0] != labels[-1]
    with pytest.raises(InvalidParameterError, match="'normals'"):
        region_growing(seat, normals, 0.03)


def test_radius_graph_is_symmetric_with_distances(rng):
    pts = rng.random((200, 3)) * 0.3
    g = radius_graph(pts, RADIUS)
    assert (g != g.T).nnz == 0
    i, j = g.nonzero()
    d = np.linalg.norm(pts[i] - pts[j], axis=1)
    assert np.allclose(np.asarray(g[i, j]).ravel(), d)
    assert d.max() < RADIUS
    # Duplicated points keep their edge.
    assert radius_graph(np.zeros((2, 3)), RADIUS).nnz == 2
    with pytest.raises(InvalidParameterError, match="'radius'"):
        radius_graph(pts, 0.0)


def test_relabel_and_densities():
    assert relabel([3, 3, 1, -1, 1, 1]).tolist() == [1, 1, 0, -1, 0, 0]
    assert relabel([-1, -1]).tolist() == [-1, -1]
    # A flat disc of radius 5 cm sampled every 2 cm holds about 20 voxels.
    assert core_neighbors(0.05, 0.02, 1.0) == 20
    assert core_neighbors(0.05, 0.02, 0.0) == 2
    assert effective_radius(0.05, 0.01, 2.5) == 0.05
    assert effective_radius(0.05, 0.04, 2.5) == pytest.approx(0.1)


def test_input_not_modified(rng):
    pts = rng.random((100, 3))
    before = pts.copy()
    dbscan(pts, RADIUS, 2)
    euclidean_clusters(pts, RADIUS)
    assert np.array_equal(pts, before)


# -- part-driven clusters: a sofa is one object ---------------------------------------------
def _box_faces(rng, lo, hi, spacing=0.02):
    """Points on the visible faces of an axis-aligned box (all but the underside)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    ex, ey, ez = np.diag(hi - lo)
    faces = [(lo + ez, ex, ey), (lo, ex, ez), (lo + ey, ex, ez), (lo, ey, ez), (lo + ex, ey, ez)]
    out = []
    for corner, u, v in faces:
        nu = max(2, int(np.linalg.norm(u) / spacing))
        nv = max(2, int(np.linalg.norm(v) / spacing))
        s, t = np.meshgrid(np.arange(nu) / nu, np.arange(nv) / nv)
        pts = corner + s.reshape(-1, 1) * u + t.reshape(-1, 1) * v
        out.append(pts + rng.normal(0, 0.002, pts.shape))
    return np.vstack(out)


def upholstered_sofa(rng, x0=0.0, y0=0.0, length=1.9):
    """Seat cushions at 42 cm, a 45 cm thick back with a flat top at 75 cm, two arms."""
    arm, depth, back = 0.2, 1.0, 0.45
    seat = _box_faces(rng, (x0 + arm, y0, 0.1), (x0 + length - arm, y0 + depth - back, 0.42))
    backrest = _box_faces(rng, (x0, y0 + depth - back, 0.1), (x0 + length, y0 + depth, 0.75))
    arms = [
        _box_faces(rng, (x, y0, 0.1), (x + arm, y0 + depth - back, 0.6))
        for x in (x0, x0 + length - arm)
    ]
    return np.vstack([seat, backrest, *arms])


def test_a_sofa_with_a_thick_back_falls_into_one_cluster(rng):
    from ontodetect.segment import segment

    floor = np.c_[rng.uniform(-1.5, 3.5, (20000, 2)), np.zeros(20000)]
    sofa = upholstered_sofa(rng)
    seg = segment(np.vstack([floor, sofa]), fit_planes=False, seed=0)
    labels = seg.labels_per_point()[len(floor) :]
    counts = np.bincount(labels[labels >= 0])
    best = int(counts.argmax())
    assert counts[best] / len(sofa) >= 0.8
    # The back's flat top joined the seat: one part, at seat height.
    assert [p.kind for p in seg[best].parts] == ["seat"]
    assert seg[best].parts[0].height < 0.5
