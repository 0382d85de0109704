"""Ground-constrained ICP: closed-form (x, y, yaw) steps, robust weights, known transforms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from ontodetect.cad import (
    builtin_library,
    ground_icp,
    pose_matrix,
    robust_weights,
    yaw_procrustes,
)
from ontodetect.errors import InvalidParameterError


def rot_z(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def place(points: np.ndarray, x: float, y: float, yaw: float, z: float = 0.0) -> np.ndarray:
    return points @ rot_z(yaw).T + [x, y, z]


@pytest.fixture(scope="module")
def chair() -> np.ndarray:
    """The thin profile of the generic four-legged chair on a 1 cm grid."""
    return np.array(builtin_library()["chair-4leg"].points(0.01))


# -- the closed-form step ---------------------------------------------------------------


def test_procrustes_is_exact_on_noise_free_correspondences(rng):
    src = rng.normal(size=(50, 3))
    for yaw in (-3.0, -0.4, 0.0, 1.2, math.pi - 1e-3):
        dst = place(src, 2.5, -1.25, yaw)
        got_yaw, t = yaw_procrustes(src, dst)
        assert got_yaw == pytest.approx(yaw, abs=1e-12)
        np.testing.assert_allclose(t, [2.5, -1.25], atol=1e-12)


def test_procrustes_ignores_zero_weight_pairs_and_batches(rng):
    src = rng.normal(size=(3, 40, 2))
    yaws = np.array([0.3, -1.0, 2.0])
    dst = np.stack(
        [place(np.c_[s, np.zeros(40)], 1.0, k, a)[:, :2] for k, (s, a) in enumerate(zip(src, yaws))]
    )
    dst[:, :5] += 10.0  # corrupted pairs...
    w = np.ones((3, 40))
    w[:, :5] = 0.0  # ...that weigh nothing
    got, t = yaw_procrustes(src, dst, w)
    np.testing.assert_allclose(got, yaws, atol=1e-12)
    np.testing.assert_allclose(t, [[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]], atol=1e-12)


def test_procrustes_uses_only_horizontal_coordinates(rng):
    src = rng.normal(size=(30, 3))
    dst = place(src, 0.5, 0.5, 0.7)
    dst[:, 2] = rng.normal(size=30)  # vertical disagreement does not matter
    yaw, _ = yaw_procrustes(src, dst)
    assert yaw == pytest.approx(0.7, abs=1e-12)


def test_procrustes_without_weight_falls_back_to_centroids():
    yaw, t = yaw_procrustes([[0.0, 0.0], [1.0, 0.0]], [[5.0, 5.0], [6.0, 5.0]], [0.0, 0.0])
    assert yaw == 0.0
    np.testing.assert_allclose(t, [5.0, 5.0])


def test_procrustes_checks_shapes():
    with pytest.raises(InvalidParameterError, match="'target'"):
        yaw_procrustes(np.zeros((4, 2)), np.zeros((5, 2)))
    with pytest.raises(InvalidParameterError, match="'weights'"):
        yaw_procrustes(np.zeros((4, 2)), np.zeros((4, 2)), np.ones(3))


# -- robust weights ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kernel", "expected"),
    [
        ("tukey", [1.0, 0.5625, 0.0, 0.0]),
        ("huber", [1.0, 1.0, 0.5, 0.0]),
        ("cauchy", [1.0, 0.8, 0.2, 0.0]),
        ("l2", [1.0, 1.0, 1.0, 0.0]),
    ],
)
def test_robust_weights_by_hand(kernel, expected):
    r = np.array([0.0, 0.05, 0.2, np.inf])
    np.testing.assert_allclose(robust_weights(r, kernel, 0.1), expected)


def test_robust_weights_per_batch_scale():
    w = robust_weights(np.array([[0.05, 0.05], [0.05, 0.05]]), "tukey", np.array([0.1, 0.05]))
    np.testing.assert_allclose(w, [[0.5625, 0.5625], [0.0, 0.0]])


@pytest.mark.parametrize(
    ("kernel", "scale", "match"),
    [("bisquare", 0.1, "'kernel'"), ("tukey", 0.0, "'scale'"), ("huber", -1.0, "'scale'")],
)
def test_robust_weights_rejects_bad_parameters(kernel, scale, match):
    with pytest.raises(InvalidParameterError, match=match):
        robust_weights([0.1], kernel, scale)


# -- the ICP ------------------------------------------------------------------------------


def test_recovers_a_known_pose(chair, rng):
    data = place(chair, 1.7, -0.6, 2.1)
    data = data[rng.random(len(data)) < 0.3]
    data = data + rng.normal(0, 0.002, data.shape)
    fit = ground_icp(data, chair, [1.62, -0.53, 2.1 + math.radians(12)])
    assert fit.converged[0]
    assert fit.x[0] == pytest.approx(1.7, abs=2e-3)
    assert fit.y[0] == pytest.approx(-0.6, abs=2e-3)
    assert fit.yaw[0] == pytest.approx(2.1, abs=math.radians(0.2))
    assert fit.inlier_fraction[0] > 0.99
    assert fit.rms[0] < 0.005


def test_recovers_a_pose_for_a_scaled_model(chair, rng):
    scale = np.array([1.15, 0.9, 1.05])
    data = place(chair * scale, -2.0, 3.0, -0.8)
    data = data[rng.random(len(data)) < 0.3]
    fit = ground_icp(data, chair, [-2.05, 3.04, -0.7], scale=scale)
    assert (fit.x[0], fit.y[0]) == pytest.approx((-2.0, 3.0), abs=3e-3)
    assert fit.yaw[0] == pytest.approx(-0.8, abs=math.radians(0.3))


def test_several_starts_are_independent_hypotheses(chair, rng):
    data = place(chair[::3], 0.4, 0.2, 0.5)
    starts = np.array([[0.35, 0.25, 0.4], [0.4, 0.2, 0.5 + math.pi], [0.45, 0.1, 0.6]])
    batch = ground_icp(data, chair, starts)
    for k, s in enumerate(starts):
        single = ground_icp(data, chair, s)
        assert batch.x[k] == pytest.approx(single.x[0], abs=1e-9)
        assert batch.yaw[k] == pytest.approx(single.yaw[0], abs=1e-9)
    # The backwards start explains the chair worse and is not the best.
    assert batch.best != 1
    assert batch.cost[1] > batch.cost[batch.best]


def test_robust_to_outliers(chair, rng):
    clean = place(chair[::2], 3.0, 1.0, -1.0)
    n_out = int(0.4 * len(clean))
    lo, hi = clean.min(axis=0) - 0.3, clean.max(axis=0) + 0.3
    uniform = lo + rng.random((n_out, 3)) * (hi - lo)
    blob = rng.normal([3.45, 1.0, 0.6], 0.04, (n_out // 2, 3))  # clutter beside the chair
    data = np.vstack([clean, uniform, blob])
    is_outlier = np.r_[np.zeros(len(clean), bool), np.ones(n_out + len(blob), bool)]
    fit = ground_icp(data, chair, [2.95, 1.05, -1.1])
    assert (fit.x[0], fit.y[0]) == pytest.approx((3.0, 1.0), abs=5e-3)
    assert fit.yaw[0] == pytest.approx(-1.0, abs=math.radians(0.5))
    inlier = fit.residuals[0] <= 0.03
    assert inlier[~is_outlier].mean() > 0.99
    # The outliers kept are those that happen to lie on the chair's surfaces.
    truth = cKDTree(place(chair, 3.0, 1.0, -1.0))
    on_chair = truth.query(data[is_outlier])[0] <= 0.03
    assert np.mean(inlier[is_outlier] == on_chair) > 0.98
    assert inlier[is_outlier].mean() < 0.15


@pytest.mark.parametrize("kernel", ["tukey", "huber", "cauchy"])
def test_every_kernel_converges(chair, kernel):
    data = place(chair[::4], 0.0, 0.0, 0.3)
    fit = ground_icp(data, chair, [0.03, -0.03, 0.2], kernel=kernel)
    assert fit.yaw[0] == pytest.approx(0.3, abs=math.radians(0.5))


def test_never_tilts_or_lifts(chair, rng):
    # Data tilted by 10 degrees and lifted by 5 cm: a 6-DoF ICP would follow; this one
    # keeps the model upright on the floor, exactly.
    c, s = math.cos(0.17), math.sin(0.17)
    tilt = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    data = place(chair[::3] @ tilt.T, 1.0, 2.0, 0.4, z=0.05)
    fit = ground_icp(data, chair, [1.0, 2.0, 0.4], z=0.0)
    T = fit.pose()
    assert T[2].tolist() == [0.0, 0.0, 1.0, 0.0]
    assert T[:3, 2].tolist() == [0.0, 0.0, 1.0]
    moved = chair @ T[:3, :3].T + T[:3, 3]
    assert np.array_equal(moved[:, 2], chair[:, 2])


@given(
    x=st.floats(-5, 5),
    y=st.floats(-5, 5),
    yaw=st.floats(-4, 4),
    z=st.floats(-0.5, 0.5),
    seed=st.integers(0, 2**16),
)
def test_pose_keeps_height_and_zero_roll_pitch(x, y, yaw, z, seed):
    gen = np.random.default_rng(seed)
    model = gen.random((60, 3))
    data = gen.random((40, 3)) * 2.0
    fit = ground_icp(data, model, [x, y, yaw], z=z, max_iterations=3)
    T = fit.pose(0)
    assert fit.z == z
    assert T[2, :3].tolist() == [0.0, 0.0, 1.0] and T[2, 3] == z
    assert T[0, 2] == 0.0 and T[1, 2] == 0.0


def test_pose_matrix():
    T = pose_matrix(1.0, 2.0, math.pi / 2, 0.5)
    np.testing.assert_allclose(T @ [1.0, 0.0, 0.0, 1.0], [1.0, 3.0, 0.5, 1.0], atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"data": np.zeros((0, 3))}, "'data'"),
        ({"model": np.zeros((5, 2))}, "'model'"),
        ({"starts": [0.0, 0.0]}, "'starts'"),
        ({"scale": (1.0, 0.0, 1.0)}, "'scale'"),
        ({"kernel": "bisquare"}, "'kernel'"),
        ({"max_iterations": -1}, "'max_iterations'"),
        ({"inlier_distance": 0.0}, "'inlier_distance'"),
        ({"kernel_scale": -0.1}, "'kernel_scale'"),
    ],
)
def test_ground_icp_rejects_bad_parameters(kwargs, match):
    args = {"data": np.ones((5, 3)), "model": np.ones((5, 3)), "starts": [0.0, 0.0, 0.0]}
    args.update(kwargs)
    with pytest.raises(InvalidParameterError, match=match):
        ground_icp(**args)


def test_input_not_modified(chair):
    data = place(chair[::5], 0.1, 0.1, 0.1)
    before = data.copy(), chair.copy()
    ground_icp(data, chair, [0.0, 0.0, 0.0])
    assert np.array_equal(data, before[0]) and np.array_equal(chair, before[1])
