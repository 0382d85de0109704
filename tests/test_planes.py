"""MSAC plane extraction and plane features: data from known planes, known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ontodetect.errors import InvalidParameterError
from ontodetect.segment.planes import (
    MsacResult,
    Plane,
    PlaneModel,
    extract_planes,
    msac,
    plane_relations,
)

THRESHOLD = 0.01
#: Noise of the generated planes (well inside the threshold: 5 sigma).
NOISE = 0.002


# -- data with known answers ------------------------------------------------------------------


def angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle between two lines (normals up to sign), degrees."""
    cos = abs(float(a @ b)) / (np.linalg.norm(a) * np.linalg.norm(b))
    return math.degrees(math.acos(min(cos, 1.0)))


def basis_of(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(normal, u)


def plane_points(
    rng: np.random.Generator,
    normal,
    offset: float,
    n: int,
    half: float = 1.0,
    noise: float = NOISE,
) -> np.ndarray:
    """n points on ``normal . x + offset = 0`` over a square patch, Gaussian noise along it."""
    normal = np.asarray(normal, dtype=float)
    normal = normal / np.linalg.norm(normal)
    u, v = basis_of(normal)
    st_ = rng.uniform(-half, half, (n, 2))
    return (
        -offset * normal
        + st_[:, :1] * u
        + st_[:, 1:] * v
        + noise * rng.standard_normal((n, 1)) * normal
    )


def with_outliers(
    rng: np.random.Generator,
    pts: np.ndarray,
    normal,
    offset: float,
    k: int,
    low: float = 5 * THRESHOLD,
    high: float = 0.3,
) -> tuple[np.ndarray, np.ndarray]:
    """Replace k random points by outliers ``low..high`` away from the plane (both sides)."""
    normal = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
    out = pts.copy()
    idx = np.sort(rng.choice(len(pts), k, replace=False))
    dist = rng.uniform(low, high, k) * rng.choice([-1.0, 1.0], k)
    # Move along the normal from the noise-free position.
    r = out[idx] @ normal + offset
    out[idx] += (dist - r)[:, None] * normal
    return out, idx


def box(rng, lo, hi, n: int, noise_axis: int | None = None) -> np.ndarray:
    """n points uniform in an axis-aligned box (a slab when one side is thin)."""
    pts = rng.uniform(lo, hi, (n, 3))
    if noise_axis is not None:
        pts[:, noise_axis] = lo[noise_axis] + NOISE * rng.standard_normal(n)
    return pts


SEAT_Z = 0.46
SEAT = (0.45, 0.42)  # x by y, metres


def chair(rng: np.random.Generator, *, noise_points: int = 60) -> tuple[np.ndarray, dict]:
    """A seat slab at 46 cm, a vertical backrest at its back edge, and scattered noise."""
    seat = box(rng, [0, 0, SEAT_Z], [SEAT[0], SEAT[1], SEAT_Z], 700, noise_axis=2)
    back = box(rng, [0, SEAT[1], SEAT_Z], [SEAT[0], SEAT[1], 0.95], 500, noise_axis=1)
    noise = rng.uniform([0, 0, 0], [SEAT[0], SEAT[1], 0.95], (noise_points, 3))
    pts = np.vstack([seat, back, noise])
    parts = {"seat": np.arange(700), "back": np.arange(700, 1200)}
    return pts, parts


# -- PlaneModel ----------------------------------------------------------------------------------


def test_plane_model_from_estimate_exact_plane(rng):
    normal = np.array([1.0, -2.0, 2.0]) / 3.0
    pts = plane_points(rng, normal, -0.7, 50, noise=0.0)
    model = PlaneModel.from_estimate(pts)
    assert model is not None
    # |n_y| == |n_z| is a tie: z decides, so the returned normal has n_z > 0 whatever
    # last bit the linear-algebra library leaves in either component.
    np.testing.assert_allclose(model.normal, normal, atol=1e-12)
    assert model.offset == pytest.approx(-0.7, abs=1e-12)
    np.testing.assert_allclose(model.residuals(pts), 0.0, atol=1e-12)
    probe = np.array([[0.0, 0.0, 0.0]])
    assert model.residuals(probe)[0] == pytest.approx(0.7)
    assert model.signed_distance(probe)[0] == pytest.approx(-0.7)
    assert model.signed_distance(probe + 1.4 * model.normal)[0] == pytest.approx(0.7)


def test_plane_model_normalises_and_validates():
    m = PlaneModel(np.array([0.0, 0.0, 2.0]), -2.0)
    np.testing.assert_array_equal(m.normal, [0.0, 0.0, 1.0])
    assert m.offset == -1.0
    assert not m.normal.flags.writeable
    with pytest.raises(InvalidParameterError, match="'normal' parameter"):
        PlaneModel(np.zeros(3), 0.0)
    with pytest.raises(InvalidParameterError, match="'normal' parameter"):
        PlaneModel(np.array([1.0, 0.0]), 0.0)
    with pytest.raises(InvalidParameterError, match="'offset' parameter"):
        PlaneModel(np.array([0.0, 0.0, 1.0]), math.nan)


@pytest.mark.parametrize(
    "points",
    [
        np.zeros((0, 3)),
        np.array([[0.0, 0, 0], [1, 0, 0]]),
        np.array([[0.0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]]),  # collinear
        np.tile([[1.0, 2.0, 3.0]], (10, 1)),  # one point, repeated
        np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, np.nan]]),
    ],
    ids=["empty", "two", "collinear", "duplicates", "nan"],
)
def test_plane_model_from_estimate_degenerate_is_none(points):
    assert PlaneModel.from_estimate(points) is None


# -- MSAC: known planes with outliers at known indices -------------------------------------------


def test_msac_recovers_plane_and_rejects_known_outliers(rng):
    normal = np.array([0.3, -0.2, 0.93])
    normal /= np.linalg.norm(normal)
    pts = plane_points(rng, normal, -1.2, 400)
    pts, outliers = with_outliers(rng, pts, normal, -1.2, 80)
    before = pts.copy()

    result = msac(pts, threshold=THRESHOLD, rng=0)

    assert result and isinstance(result, MsacResult) and result.reason == ""
    assert angle_deg(result.model.normal, normal) < 1.0
    sign = np.sign(result.model.normal @ normal)
    assert sign * result.model.offset == pytest.approx(-1.2, abs=2e-3)
    true_inliers = np.setdiff1d(np.arange(len(pts)), outliers)
    assert np.isin(true_inliers, result.inliers).mean() >= 0.95
    # Exactly the outliers were rejected (the noise is 5 sigma inside the threshold).
    np.testing.assert_array_equal(np.setdiff1d(np.arange(len(pts)), result.inliers), outliers)
    r = result.model.residuals(pts)
    assert result.cost == pytest.approx(float(np.minimum(r**2, THRESHOLD**2).sum()))
    np.testing.assert_array_equal(pts, before)  # input not modified


def test_msac_far_from_origin(rng):
    """Coordinates of a projected map (hundreds of km) keep full precision."""
    normal = np.array([0.0, 0.6, 0.8])
    pts = plane_points(rng, normal, 0.0, 300) + np.array([512_000.0, 4_200_000.0, 0.0])
    result = msac(pts, threshold=THRESHOLD, rng=1)
    assert result and angle_deg(result.model.normal, normal) < 1.0
    assert result.inliers.size == 300


def ransac_count(points: np.ndarray, model: PlaneModel, t: float) -> int:
    """Plain RANSAC's score: the number of points within the threshold."""
    return int(np.count_nonzero(model.residuals(points) <= t))


def test_msac_prefers_the_tight_plane_where_ransac_ties(rng):
    """Two planes with as many inliers each; one is tight, the other barely within t."""
    n = 150
    tight_model = PlaneModel(np.array([0.0, 0.0, 1.0]), 0.0)  # z = 0
    tight = np.column_stack([rng.uniform(0, 1, (n, 2)), 5e-4 * rng.standard_normal(n)])
    loose_model = PlaneModel(np.array([1.0, 0.0, 0.0]), -3.0)  # x = 3, away from the first
    loose = np.column_stack(
        [
            3.0 + 0.9 * THRESHOLD * np.where(np.arange(n) % 2 == 0, 1.0, -1.0),
            rng.uniform(0, 1, n),
            rng.uniform(1, 2, n),
        ]
    )
    pts = np.vstack([tight, loose])

    # Plain RANSAC cannot tell them apart ...
    assert ransac_count(pts, tight_model, THRESHOLD) == ransac_count(pts, loose_model, THRESHOLD)
    assert ransac_count(pts, tight_model, THRESHOLD) == n
    # ... MSAC's truncated quadratic cost can.
    result = msac(pts, threshold=THRESHOLD, rng=3)
    assert result
    assert angle_deg(result.model.normal, tight_model.normal) < 0.5
    np.testing.assert_array_equal(result.inliers, np.arange(n))
    assert result.cost < 0.6 * (2 * n) * THRESHOLD**2


def test_msac_stops_early_on_a_clean_plane(rng):
    pts = plane_points(rng, [0, 0, 1], 0.0, 500)
    result = msac(pts, threshold=THRESHOLD, max_trials=5000, rng=0)
    assert result and result.inliers.size == 500
    assert result.trials <= 64  # one batch: the first all-inlier sample settles it


def test_msac_sample_indices_restricts_hypotheses(rng):
    big = plane_points(rng, [0, 0, 1], 0.0, 600)
    small = plane_points(rng, [1, 0, 0], -5.0, 100)
    pts = np.vstack([big, small])
    assert angle_deg(msac(pts, threshold=THRESHOLD, rng=0).model.normal, [0, 0, 1]) < 1
    result = msac(pts, threshold=THRESHOLD, sample_indices=np.arange(600, 700), rng=0)
    assert result and angle_deg(result.model.normal, [1, 0, 0]) < 1
    np.testing.assert_array_equal(result.inliers, np.arange(600, 700))


def test_msac_large_input_uses_the_subset_and_stays_correct(rng):
    """Above the scoring subset size the answer is still the plane, with full-data cost."""
    normal = np.array([0.1, 0.95, 0.2])
    normal /= np.linalg.norm(normal)
    pts = plane_points(rng, normal, 0.4, 6000)
    pts, outliers = with_outliers(rng, pts, normal, 0.4, 3000)
    result = msac(pts, threshold=THRESHOLD, rng=5)
    assert result and angle_deg(result.model.normal, normal) < 1.0
    np.testing.assert_array_equal(np.setdiff1d(np.arange(len(pts)), result.inliers), outliers)
    r = result.model.residuals(pts)
    assert result.cost == pytest.approx(float(np.minimum(r**2, THRESHOLD**2).sum()))


# -- degenerate inputs: a falsy result with a reason, never an exception -------------------------


@pytest.mark.parametrize(
    ("points", "reason"),
    [
        (np.zeros((0, 3)), "fewer than 3 points (got 0)"),
        ([], "fewer than 3 points (got 0)"),
        ([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], "fewer than 3 points (got 2)"),
        (np.outer(np.linspace(0, 1, 20), [1.0, 2.0, 3.0]) + 5.0, "all points are collinear"),
        (np.tile([[0.3, 0.1, 0.7]], (25, 1)), "all points coincide"),
        (np.repeat([[0.0, 0, 0], [1.0, 1, 0]], 10, axis=0), "all points are collinear"),
    ],
    ids=["empty", "empty-list", "two", "collinear", "duplicates", "two-distinct"],
)
def test_msac_degenerate_inputs_fail_with_reason(points, reason):
    result = msac(points, threshold=THRESHOLD, rng=0)
    assert not result
    assert result.model is None and result.inliers.size == 0
    assert result.reason == reason
    assert result.cost == math.inf


def test_msac_degenerate_sample_indices_fail_with_reason(rng):
    pts = plane_points(rng, [0, 0, 1], 0.0, 50)
    pts[:10] = np.outer(np.arange(10), [1.0, 1.0, 0.0])  # ten points on a line
    result = msac(pts, threshold=THRESHOLD, sample_indices=np.arange(10), rng=0)
    assert not result and result.reason == "all points are collinear (of sample_indices)"
    result = msac(pts, threshold=THRESHOLD, sample_indices=[], rng=0)
    assert not result and result.reason == "fewer than 3 points to sample from (got 0)"


def test_msac_too_few_inliers_fails_with_reason(rng):
    pts = rng.uniform(0, 1, (200, 3))  # no plane holds 150 of these
    result = msac(pts, threshold=THRESHOLD, min_inliers=150, max_trials=200, rng=0)
    assert not result
    assert "fewer than min_inliers=150" in result.reason
    # Had a plane of 150 of the 200 points existed, this many samples would have found it.
    assert result.trials == math.ceil(math.log(1 - 0.999) / math.log(1 - 0.75**3))
    assert msac(pts, threshold=THRESHOLD, min_inliers=10, max_trials=200, rng=0).trials == 200


def test_extract_planes_degenerate_inputs_give_no_planes():
    line = np.outer(np.linspace(0, 1, 50), [1.0, 0.0, 0.0])
    assert extract_planes(line, min_points=3, rng=0) == []
    assert extract_planes(np.zeros((0, 3)), rng=0) == []
    assert extract_planes(np.ones((40, 3)), min_points=3, rng=0) == []


BAD_MSAC = [
    ({"threshold": 0.0}, "threshold"),
    ({"threshold": -0.01}, "threshold"),
    ({"threshold": math.nan}, "threshold"),
    ({"threshold": math.inf}, "threshold"),
    ({"threshold": "0.01"}, "threshold"),
    ({"threshold": True}, "threshold"),
    ({"confidence": 0.0}, "confidence"),
    ({"confidence": 1.0}, "confidence"),
    ({"confidence": 1.5}, "confidence"),
    ({"max_trials": 0}, "max_trials"),
    ({"max_trials": 10.5}, "max_trials"),
    ({"min_inliers": 2}, "min_inliers"),
    ({"sample_indices": [0, 1, 99]}, "sample_indices"),
    ({"sample_indices": [0.0, 1.0, 2.0]}, "sample_indices"),
]


@pytest.mark.parametrize(("kwargs", "name"), BAD_MSAC)
def test_msac_invalid_parameters_raise(rng, kwargs, name):
    pts = rng.uniform(0, 1, (10, 3))
    args = {"threshold": THRESHOLD, **kwargs}
    with pytest.raises(InvalidParameterError, match=f"The '{name}' parameter must be"):
        msac(pts, **args)


@pytest.mark.parametrize(
    ("points", "match"),
    [
        (np.zeros((5, 2)), r"must be an array of shape \(n, 3\).*shape \(5, 2\)"),
        (np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, np.inf]]), "must be finite.*1 non-finite"),
        ([["a", "b", "c"]], r"must be a numeric array"),
    ],
)
def test_invalid_points_raise(points, match):
    with pytest.raises(InvalidParameterError, match=match):
        msac(points, threshold=THRESHOLD)
    with pytest.raises(InvalidParameterError, match=match):
        extract_planes(points)


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"threshold": 0}, "threshold"),
        ({"min_points": 2}, "min_points"),
        ({"min_extent": -1.0}, "min_extent"),
        ({"max_planes": -1}, "max_planes"),
        ({"max_trials": 0}, "max_trials"),
        ({"connectivity": 0.0}, "connectivity"),
        ({"area_cell": -0.1}, "area_cell"),
        ({"floor_z": math.nan}, "floor_z"),
        ({"colors": np.zeros((3, 3))}, "colors"),
    ],
)
def test_extract_planes_invalid_parameters_raise(rng, kwargs, name):
    with pytest.raises(InvalidParameterError, match=f"The '{name}' parameter must be"):
        extract_planes(rng.uniform(0, 1, (10, 3)), **kwargs)


# -- extract_planes on a synthetic chair ---------------------------------------------------------


def test_extract_planes_finds_seat_and_backrest(rng):
    pts, parts = chair(rng)
    planes = extract_planes(pts, threshold=THRESHOLD, min_points=50, min_extent=0.2, rng=0)

    # Two planes, then nothing of 50 points is left in 60 scattered noise points.
    assert len(planes) == 2
    seat, back = planes
    assert all(isinstance(p, Plane) for p in planes)

    assert seat.is_horizontal() and seat.tilt < 1.0
    np.testing.assert_allclose(seat.normal, [0, 0, 1], atol=0.02)  # points up
    assert seat.height == pytest.approx(SEAT_Z, abs=0.005)
    assert seat.length == pytest.approx(SEAT[0], abs=0.03)
    assert seat.width == pytest.approx(SEAT[1], abs=0.03)
    assert seat.area == pytest.approx(SEAT[0] * SEAT[1], rel=0.1)
    # Inliers lie within the threshold of the fitted plane, itself within a fraction of a degree.
    assert seat.z_min >= SEAT_Z - 1.5 * THRESHOLD and seat.z_max <= SEAT_Z + 1.5 * THRESHOLD
    assert seat.rms == pytest.approx(NOISE, rel=0.25)
    assert np.isin(parts["seat"], seat.inliers).mean() >= 0.95

    assert back.is_vertical() and back.tilt > 89.0
    # A vertical plane's normal points away from the cluster: the seat is in front (-y).
    np.testing.assert_allclose(back.normal, [0, 1, 0], atol=0.02)
    assert back.height == pytest.approx((SEAT_Z + 0.95) / 2, abs=0.02)
    assert back.length == pytest.approx(0.95 - SEAT_Z, abs=0.04)  # taller than wide
    assert back.width == pytest.approx(SEAT[0], abs=0.03)
    assert back.area == pytest.approx(SEAT[0] * (0.95 - SEAT_Z), rel=0.1)
    assert np.isin(parts["back"], back.inliers).mean() >= 0.95

    for p in planes:
        assert p.length >= p.width
        assert p.num_points == p.inliers.size
        assert p.density == pytest.approx(p.num_points / p.area)
        np.testing.assert_allclose(p.axes @ p.axes.T, np.eye(2), atol=1e-12)
        np.testing.assert_allclose(np.cross(p.axes[0], p.axes[1]), p.normal, atol=1e-12)
        np.testing.assert_allclose(p.model.residuals(p.centroid[None]), 0.0, atol=1e-12)
        assert p.color_mean is None and p.color_std is None
    assert np.intersect1d(seat.inliers, back.inliers).size == 0


def test_extract_planes_stops_at_minimum_size_and_limits(rng):
    pts, _ = chair(rng)
    # The backrest (500 points) is below this size: only the seat remains.
    only_seat = extract_planes(pts, min_points=560, rng=0)
    assert [round(p.tilt) for p in only_seat] == [0]
    assert len(extract_planes(pts, min_points=50, max_planes=1, rng=0)) == 1
    assert extract_planes(pts, max_planes=0, rng=0) == []
    # No plane is 2 m long: every candidate is rejected and the search ends.
    assert extract_planes(pts, min_points=50, min_extent=2.0, rng=0) == []


def test_extract_planes_floor_z_sets_height(rng):
    pts, _ = chair(rng)
    planes = extract_planes(pts + [0, 0, 1.0], min_points=50, floor_z=1.0, rng=0)
    assert planes[0].height == pytest.approx(SEAT_Z, abs=0.005)
    assert planes[0].z_min > 1.0


# -- connectivity --------------------------------------------------------------------------------


@pytest.mark.parametrize("per_seat", [400, 3000], ids=["exact", "thinned"])
def test_connectivity_splits_coplanar_seats(rng, per_seat):
    """Two chairs side by side: their seats are coplanar but 15 cm apart."""
    left = box(rng, [0, 0, SEAT_Z], [0.45, 0.45, SEAT_Z], per_seat, noise_axis=2)
    right = box(rng, [0.6, 0, SEAT_Z], [1.05, 0.45, SEAT_Z], per_seat, noise_axis=2)
    pts = np.vstack([left, right])

    merged = extract_planes(pts, min_points=50, rng=0)
    assert len(merged) == 1 and merged[0].num_points == 2 * per_seat
    assert merged[0].length == pytest.approx(1.05, abs=0.05)

    # 7 cm: wide enough that no corner point of a random sample is cut off, narrower than the gap.
    split = extract_planes(pts, min_points=50, connectivity=0.07, rng=0)
    assert len(split) == 2
    found = sorted(tuple(p.inliers[[0, -1]]) for p in split)
    assert found == [(0, per_seat - 1), (per_seat, 2 * per_seat - 1)]
    assert all(p.num_points == per_seat for p in split)
    for p in split:
        assert p.length == pytest.approx(0.45, abs=0.03)

    # A connectivity wider than the gap keeps them together.
    assert len(extract_planes(pts, min_points=50, connectivity=0.25, rng=0)) == 1


def test_connectivity_drops_small_pieces_back_to_the_pool(rng):
    """A big patch and a small coplanar one: the small one is too small to be a plane."""
    big = box(rng, [0, 0, 0.7], [0.8, 0.6, 0.7], 800, noise_axis=2)
    small = box(rng, [1.2, 0, 0.7], [1.3, 0.1, 0.7], 20, noise_axis=2)
    planes = extract_planes(np.vstack([big, small]), min_points=30, connectivity=0.08, rng=0)
    assert len(planes) == 1
    np.testing.assert_array_equal(planes[0].inliers, np.arange(800))


# -- plane features on known data ----------------------------------------------------------------


def test_density_area_and_colour_on_a_lattice(rng):
    # A 50 x 40 lattice at 1 cm: 2000 points covering 0.5 m x 0.4 m (1 cm² each).
    gx, gy = np.meshgrid(np.arange(50) * 0.01, np.arange(40) * 0.01, indexing="ij")
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, 0.72)])
    pts[:, 2] += NOISE * rng.standard_normal(len(pts))
    colors = np.zeros((len(pts), 3), dtype=np.uint8)
    colors[: len(pts) // 2] = [200, 40, 0]
    colors[len(pts) // 2 :] = [0, 40, 100]

    (plane,) = extract_planes(pts, colors, min_points=50, rng=0)

    assert plane.num_points == 2000
    assert plane.area == pytest.approx(0.2, rel=0.05)
    assert plane.density == pytest.approx(10_000, rel=0.05)
    assert plane.length == pytest.approx(0.5, abs=0.015)
    assert plane.width == pytest.approx(0.4, abs=0.015)
    np.testing.assert_allclose(plane.color_mean, [100, 40, 50])
    np.testing.assert_allclose(plane.color_std, [100, 0, 50])
    np.testing.assert_allclose(plane.axes[0], [1, 0, 0], atol=1e-3)  # the longer side


def test_area_measures_holes_and_l_shapes(rng):
    """Occupied-cell area follows the shape, where the bounding box would not."""
    square = box(rng, [0, 0, 0], [1, 1, 0], 4000, noise_axis=2)
    l_shape = square[(square[:, 0] < 0.5) | (square[:, 1] < 0.5)]
    (plane,) = extract_planes(l_shape, min_points=50, rng=0)
    assert plane.length * plane.width == pytest.approx(1.0, rel=0.05)
    assert plane.area == pytest.approx(0.75, rel=0.08)

    # An explicit cell size gives the same answer within the border effects.
    (plane,) = extract_planes(l_shape, min_points=50, area_cell=0.05, rng=0)
    assert plane.area == pytest.approx(0.75, rel=0.08)


def test_orientation_predicates():
    def with_tilt(tilt: float) -> Plane:
        z = math.cos(math.radians(tilt))
        return Plane(
            normal=np.array([math.sqrt(1 - z * z), 0.0, z]),
            offset=0.0,
            centroid=np.zeros(3),
            inliers=np.arange(3),
            axes=np.eye(3)[:2],
            length=1.0,
            width=1.0,
            area=1.0,
            tilt=tilt,
            height=0.0,
            z_min=0.0,
            z_max=0.0,
            density=3.0,
            color_mean=None,
            color_std=None,
            num_points=3,
            rms=0.0,
        )

    assert with_tilt(5.0).is_horizontal() and not with_tilt(7.0).is_horizontal()
    assert with_tilt(7.0).is_horizontal(tolerance=10.0)
    assert with_tilt(85.0).is_vertical() and not with_tilt(80.0).is_vertical()
    assert with_tilt(80.0).is_vertical(tolerance=15.0)


# -- relations -----------------------------------------------------------------------------------


def test_relations_seat_and_backrest(rng):
    pts, _ = chair(rng)
    seat, back = extract_planes(pts, min_points=50, rng=0)
    (rel,) = plane_relations(pts, [seat, back])
    assert (rel.i, rel.j) == (0, 1)
    assert rel.angle == pytest.approx(90.0, abs=1.0)
    # They touch: the gap is the seat's inlier band plus the sampling spacing (about 1.6 cm).
    assert rel.distance < 0.03
    assert rel.vertical_gap == pytest.approx(seat.centroid[2] - back.centroid[2])
    assert rel.vertical_gap < -0.2
    # The backrest stands on the seat's back edge: above it, by the footprint rule.
    assert rel.j_above_i and not rel.i_above_j


def test_relations_above_below_and_apart(rng):
    seat = box(rng, [0, 0, SEAT_Z], [0.45, 0.45, SEAT_Z], 400, noise_axis=2)
    # A table top 29 cm higher, covering the seat's back half.
    table = box(rng, [-0.2, 0.2, 0.75], [0.8, 1.0, 0.75], 900, noise_axis=2)
    # A shelf at the table's height, 1.5 m away in x: beside, not above.
    shelf = box(rng, [2.0, 0.0, 0.8], [2.5, 0.4, 0.8], 300, noise_axis=2)
    pts = np.vstack([seat, table, shelf])
    planes = extract_planes(pts, min_points=50, rng=0)
    assert len(planes) == 3
    order = np.argsort([p.num_points for p in planes])  # shelf, seat, table
    shelf_i, seat_i, table_i = (int(k) for k in order)
    relations = {(r.i, r.j): r for r in plane_relations(pts, planes)}
    assert sorted(relations) == [(0, 1), (0, 2), (1, 2)]

    def rel(a: int, b: int):
        return relations[(min(a, b), max(a, b))]

    r = rel(table_i, seat_i)
    table_above_seat = r.i_above_j if r.i == table_i else r.j_above_i
    assert table_above_seat
    assert not (r.j_above_i if r.i == table_i else r.i_above_j)
    assert abs(r.vertical_gap) == pytest.approx(0.29, abs=0.01)
    # The closest of many noisy pairs: a few noise sigmas under the 29 cm between the planes.
    assert r.distance == pytest.approx(0.29, abs=0.02)
    assert r.angle < 1.0
    # About 25/45 of the seat's footprint lies under the table (5 cm grid cells).
    assert 0.4 < r.xy_overlap < 0.75

    r = rel(shelf_i, seat_i)
    assert r.xy_overlap == 0.0 and not r.i_above_j and not r.j_above_i
    assert r.distance == pytest.approx(np.hypot(2.0 - 0.45, 0.8 - SEAT_Z), abs=0.02)


def test_relations_since_measures_only_the_pairs_of_the_planes_added(rng):
    pts, _ = chair(rng)
    shelf = box(rng, [2.0, 0.0, 0.8], [2.5, 0.4, 0.8], 300, noise_axis=2)
    pts = np.vstack([pts, shelf])
    planes = extract_planes(pts, min_points=50, rng=0)
    assert len(planes) == 3
    every = plane_relations(pts, planes)
    added = plane_relations(pts, planes, since=2)
    assert added == [r for r in every if r.j >= 2] and len(added) == 2
    assert plane_relations(pts, planes, since=len(planes)) == []
    assert plane_relations(pts, planes, since=0) == every
    with pytest.raises(InvalidParameterError, match="'since' parameter"):
        plane_relations(pts, planes, since=-1)


def test_relations_invalid_inputs(rng):
    pts, _ = chair(rng)
    planes = extract_planes(pts, min_points=50, rng=0)
    assert plane_relations(pts, []) == []
    assert plane_relations(pts, planes[:1]) == []
    with pytest.raises(InvalidParameterError, match=r"'planes\[0\].inliers' parameter"):
        plane_relations(pts[:10], planes)
    with pytest.raises(InvalidParameterError, match="'footprint_cell' parameter"):
        plane_relations(pts, planes, footprint_cell=0)


# -- determinism ---------------------------------------------------------------------------------


def planes_equal(a: list[Plane], b: list[Plane]) -> bool:
    if len(a) != len(b):
        return False
    for p, q in zip(a, b):
        for name in Plane.__dataclass_fields__:
            x, y = getattr(p, name), getattr(q, name)
            if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
                if not np.array_equal(x, y):
                    return False
            elif x != y:
                return False
    return True


def test_same_seed_same_result(rng):
    pts, _ = chair(rng, noise_points=200)
    colors = rng.integers(0, 256, (len(pts), 3))
    before = pts.copy(), colors.copy()
    first = extract_planes(pts, colors, min_points=40, connectivity=0.05, rng=7)
    again = extract_planes(pts, colors, min_points=40, connectivity=0.05, rng=7)
    assert planes_equal(first, again)
    np.testing.assert_array_equal(pts, before[0])  # inputs not modified
    np.testing.assert_array_equal(colors, before[1])
    a = msac(pts, threshold=THRESHOLD, rng=np.random.default_rng(11))
    b = msac(pts, threshold=THRESHOLD, rng=np.random.default_rng(11))
    assert np.array_equal(a.model.normal, b.model.normal) and a.model.offset == b.model.offset
    assert np.array_equal(a.inliers, b.inliers) and (a.cost, a.trials) == (b.cost, b.trials)


def test_other_seeds_and_orders_give_the_same_planes_up_to_sampling(rng):
    """Documented: results depend on seed and point order only through the sampling."""
    pts, _ = chair(rng)
    reference = extract_planes(pts, min_points=50, rng=0)
    perm = rng.permutation(len(pts))
    for planes, back_map in [
        (extract_planes(pts, min_points=50, rng=123), np.arange(len(pts))),
        (extract_planes(pts[perm], min_points=50, rng=0), perm),
    ]:
        assert len(planes) == len(reference)
        for p, q in zip(reference, planes):
            assert angle_deg(p.normal, q.normal) < 0.5
            same = np.intersect1d(p.inliers, back_map[q.inliers]).size
            assert same >= 0.99 * max(p.num_points, q.num_points)


# -- property test -------------------------------------------------------------------------------


@given(
    polar=st.floats(0.0, math.pi),
    azimuth=st.floats(0.0, 2 * math.pi),
    offset=st.floats(-3.0, 3.0),
    noise=st.floats(0.0, THRESHOLD / 4),
    outlier_share=st.floats(0.0, 0.5),
    seed=st.integers(0, 2**32 - 1),
)
def test_msac_recovers_any_plane(polar, azimuth, offset, noise, outlier_share, seed):
    gen = np.random.default_rng(seed)
    normal = np.array(
        [
            math.sin(polar) * math.cos(azimuth),
            math.sin(polar) * math.sin(azimuth),
            math.cos(polar),
        ]
    )
    n = 300
    pts = plane_points(gen, normal, offset, n, noise=noise)
    k = int(outlier_share * n)
    outliers = np.zeros(0, dtype=int)
    if k:
        pts, outliers = with_outliers(gen, pts, normal, offset, k, low=3 * THRESHOLD)

    result = msac(pts, threshold=THRESHOLD, rng=seed)

    assert result
    assert angle_deg(result.model.normal, normal) < 1.0
    sign = np.sign(result.model.normal @ normal)
    assert sign * result.model.offset == pytest.approx(offset, abs=3e-3)
    true_inliers = np.setdiff1d(np.arange(n), outliers)
    assert np.isin(true_inliers, result.inliers).mean() >= 0.95
    assert not np.isin(outliers, result.inliers).any()
