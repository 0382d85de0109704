"""Clustering primitives on voxel centres: DBSCAN, Euclidean, region growing, graphs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
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


def upholstered_sofa(rng, x0=0.0, y0=0.0, length=1.9, arm_height=0.6):
    """Seat cushions at 42 cm, a 45 cm thick back with a flat top at 75 cm, two arms."""
    arm, depth, back = 0.2, 1.0, 0.45
    seat = _box_faces(rng, (x0 + arm, y0, 0.1), (x0 + length - arm, y0 + depth - back, 0.42))
    backrest = _box_faces(rng, (x0, y0 + depth - back, 0.1), (x0 + length, y0 + depth, 0.75))
    arms = [
        _box_faces(rng, (x, y0, 0.1), (x + arm, y0 + depth - back, arm_height))
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


def _best_share(rng, sofa, *others):
    from ontodetect.segment import segment

    floor = np.c_[rng.uniform(-1.5, 3.5, (20000, 2)), np.zeros(20000)]
    pts = np.vstack([floor, sofa, *others])
    seg = segment(pts, fit_planes=False, seed=0)
    labels = seg.labels_per_point()
    start = len(floor)
    mine = labels[start : start + len(sofa)]
    counts = np.bincount(mine[mine >= 0])
    best = int(counts.argmax())
    return seg, labels, best, counts[best] / len(sofa)


def test_arms_as_high_as_the_back_join_the_seat(rng):
    # The flat tops of the arms and of the back touch: one U-shaped part, as deep as
    # the sofa but nowhere wider than an arm or the back.
    sofa = upholstered_sofa(rng, arm_height=0.75)
    seg, _, best, share = _best_share(rng, sofa)
    assert share >= 0.8
    assert [p.kind for p in seg[best].parts] == ["seat"]


def framed_sofa(rng, length=1.2, depth=0.75, seat=0.35, top=0.68):
    """A sofa with thin arms and back (no flat top on them) and a seat at ``seat`` m."""
    t = 0.05
    parts = [
        _box_faces(rng, (t, 0.0, seat - 0.05), (length - t, depth - t, seat)),
        _box_faces(rng, (0.0, depth - t, 0.05), (length, depth, top)),
        _box_faces(rng, (0.0, 0.0, 0.05), (t, depth - t, top - 0.1)),
        _box_faces(rng, (length - t, 0.0, 0.05), (length, depth - t, top - 0.1)),
    ]
    return np.vstack(parts)


def test_a_sofa_seen_in_part_is_one_cluster_and_the_console_behind_it_is_not(rng):
    # A sparse scan sees the seat as a dense patch at its front only: the back and the
    # far arm lie beyond a seat's reach from that patch, yet within reach of the seat
    # as scanned. A console table standing against the back stays apart.
    sofa = framed_sofa(rng)
    on_seat = (np.abs(sofa[:, 2] - 0.35) < 0.01) & (sofa[:, 0] > 0.05) & (sofa[:, 0] < 1.15)
    far = on_seat & ((sofa[:, 1] > 0.35) | (sofa[:, 0] > 0.7))
    sofa = sofa[~(far & (rng.random(len(sofa)) < 0.97))]
    console = np.vstack(
        [
            _box_faces(rng, (0.1, 0.78, 0.82), (1.1, 1.13, 0.85)),
            *(
                _box_faces(rng, (x, y, 0.0), (x + 0.04, y + 0.04, 0.82))
                for x in (0.12, 1.04)
                for y in (0.8, 1.07)
            ),
        ]
    )
    _, labels, best, share = _best_share(rng, sofa, console)
    assert share >= 0.8
    assert np.mean(labels[-len(console) :] == best) < 0.2


def test_width_is_the_widest_disc_not_the_box():
    from ontodetect.segment._parts import _width

    cell = 0.03
    g = np.stack(np.meshgrid(np.arange(0, 1.8, cell), np.arange(0, 0.9, cell)), -1).reshape(-1, 2)
    assert _width(g, cell) == pytest.approx(0.9, abs=0.1)
    # The tops of a back and two arms: a U as deep as the sofa, 25 cm wide everywhere.
    u = g[(g[:, 1] > 0.65) | (g[:, 0] < 0.25) | (g[:, 0] > 1.55)]
    assert _width(u, cell) == pytest.approx(0.25, abs=0.07)
    # A sparse top is as wide as its short side once its gaps are closed.
    holes = g[np.random.default_rng(0).random(len(g)) < 0.5]
    assert _width(holes, cell) == pytest.approx(0.9, abs=0.15)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 40),
    st.integers(0, 2**32 - 1),
    st.floats(0.0, 1.0),
)
def test_nearest_tops_equals_the_all_pairs_definition(n, seed, share):
    """The blocked search over the clusters with a top gives what comparing every pair
    gives (the highest top of another footprint within SHELTER_GAP)."""
    from ontodetect.segment import _measure

    rng = np.random.default_rng(seed)
    lo = rng.uniform(0, 5, (n, 2))
    boxes = np.stack([lo, lo + rng.uniform(0.05, 1.5, (n, 2))], axis=1)
    tops = np.where(rng.random(n) < share, rng.uniform(0.3, 1.2, n), -np.inf)
    gap = np.maximum(boxes[None, :, 0] - boxes[:, None, 1], boxes[:, None, 0] - boxes[None, :, 1])
    near = np.all(gap <= _measure.SHELTER_GAP, axis=2)
    np.fill_diagonal(near, False)
    expected = np.where(near, tops[None, :], -np.inf).max(axis=1) if n else np.zeros(0)
    old_block = _measure.SHELTER_BLOCK
    try:
        _measure.SHELTER_BLOCK = 7  # several blocks even for small n
        got = _measure.nearest_tops(boxes, tops)
    finally:
        _measure.SHELTER_BLOCK = old_block
    np.testing.assert_array_equal(got, expected)
