"""Ground-constrained ICP: x, y and yaw of an upright model standing on the floor.

Furniture stands upright on the floor (thesis §3.7): in the levelled frame (z
up, floor at z = 0) a model's pose has three free parameters, the position
(x, y) on the floor and the yaw about z; its height is fixed by floor contact
and roll and pitch are zero. The thesis ran a 6-DoF ICP and kept the yaw of the
resulting rotation. Here the constraint is part of the problem: every ICP step
solves in closed form for (x, y, yaw) only (:func:`yaw_procrustes`, a 2D
weighted Procrustes on the horizontal coordinates of the correspondences), so
a model can never tilt or leave the floor, and no degree of freedom is spent
on explaining noise with a tilt. Correspondences are still found in 3D, so the
vertical structure (seat height, table top) decides which points match.

Each iteration:

1. the data points are moved into the model's frame with the current pose
   (one k-d tree of the model serves every object and every pose);
2. each point's nearest model point is its correspondence (scipy ``cKDTree``);
3. robust weights (:func:`robust_weights`: Tukey, Huber or Cauchy) make
   clutter and other objects' points count little or nothing;
4. :func:`yaw_procrustes` gives the (x, y, yaw) that minimizes the weighted sum
   of squared horizontal distances, exactly.

:func:`ground_icp` runs several starting poses at once (a batch of
hypotheses shares every tree query), which is how :mod:`ontodetect.cad._fit`
tries several yaws and models within a few milliseconds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..geometry import yaw_pose as pose_matrix

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

__all__ = [
    "KERNELS",
    "GroundIcpResult",
    "ground_icp",
    "pose_matrix",
    "robust_weights",
    "yaw_procrustes",
]

#: Robust kernels of :func:`robust_weights`; ``"l2"`` is plain least squares.
KERNELS = ("tukey", "huber", "cauchy", "l2")
#: Kernel width from the residuals: Tukey's biweight at 95 % efficiency is 4.685 σ, with σ
#: estimated robustly as 1.4826 × the median residual.
TUKEY_C = 4.685
MAD_TO_SIGMA = 1.4826
#: Bounds of the automatic kernel width (m): no narrower than the mismatch between a
#: generic model and a real object, no wider than a piece of furniture.
MIN_KERNEL = 0.02
MAX_KERNEL = 0.30
#: Stop when the pose moves less than this between iterations (m and rad): half a millimetre
#: and 0.03°, far below what a generic model can resolve.
TOLERANCE = 5e-4
#: Default inlier distance (m) of the match statistics: a data point within this of the
#: model counts as matched.
INLIER_DISTANCE = 0.03
#: A step that keeps the direction of the previous one (cosine above this) is lengthened
#: this many times.
ACCEL_COS = 0.9
ACCELERATION = 2.0
#: Model points looked at to measure its reach (any few hundred give it to a few per cent).
REACH_SAMPLE = 500
#: Total weight below which a hypothesis has nothing to align and keeps its pose.
MIN_WEIGHT = 1e-9


def yaw_procrustes(
    source: ArrayLike, target: ArrayLike, weights: ArrayLike | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Closed-form (x, y, yaw) that best maps source points onto their targets.

    Minimizes ``Σ w_i ‖R(yaw) s_i + t − q_i‖²`` over the horizontal coordinates,
    where ``R(yaw)`` turns about z. With weighted centroids ``s̄``, ``q̄`` and
    centred points, ``A = Σ w (q·s)`` and ``B = Σ w (q × s)_z``, the optimum is
    ``yaw = atan2(B, A)`` and ``t = q̄ − R s̄``. Leading dimensions are batches.

    Parameters
    ----------
    source, target : (..., n, 2) or (..., n, 3) float
        Corresponding points (only x and y are used).
    weights : (..., n) float, optional
        Non-negative weights; all 1 by default. A batch whose weights sum to
        zero gets yaw 0 and the translation between the plain centroids.

    Returns
    -------
    yaw : (...) float
    translation : (..., 2) float

    Examples
    --------
    >>> s = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 2.0]])
    >>> c, si = np.cos(0.3), np.sin(0.3)
    >>> q = s @ np.array([[c, -si], [si, c]]).T + [0.5, -1.0]
    >>> yaw, t = yaw_procrustes(s, q)
    >>> round(float(yaw), 12), t.round(12).tolist()
    (0.3, [0.5, -1.0])
    """
    s = np.asarray(source, dtype=np.float64)[..., :2]
    q = np.asarray(target, dtype=np.float64)[..., :2]
    if s.shape != q.shape or s.ndim < 2:
        raise InvalidParameterError(
            "target", f"an array of the shape of source {s.shape}", f"shape {q.shape}"
        )
    w = np.ones(s.shape[:-1]) if weights is None else np.asarray(weights, dtype=np.float64)
    if w.shape != s.shape[:-1]:
        raise InvalidParameterError("weights", f"an array of shape {s.shape[:-1]}", w.shape)
    total = w.sum(axis=-1)
    empty = total <= MIN_WEIGHT
    if np.any(empty):
        w = np.where(empty[..., None], 1.0, w)
        total = w.sum(axis=-1)
    s_mean = np.einsum("...n,...nk->...k", w, s) / total[..., None]
    q_mean = np.einsum("...n,...nk->...k", w, q) / total[..., None]
    sc = s - s_mean[..., None, :]
    qc = q - q_mean[..., None, :]
    a = np.einsum("...n,...n->...", w, qc[..., 0] * sc[..., 0] + qc[..., 1] * sc[..., 1])
    b = np.einsum("...n,...n->...", w, qc[..., 1] * sc[..., 0] - qc[..., 0] * sc[..., 1])
    yaw = np.arctan2(b, a)
    yaw = np.where(empty, 0.0, yaw)
    c, si = np.cos(yaw), np.sin(yaw)
    rotated = np.stack(
        [c * s_mean[..., 0] - si * s_mean[..., 1], si * s_mean[..., 0] + c * s_mean[..., 1]],
        axis=-1,
    )
    return yaw, q_mean - rotated


def robust_weights(
    residuals: ArrayLike, kernel: str = "tukey", scale: float | ArrayLike = 0.05
) -> NDArray[np.float64]:
    """Weights of an iteratively reweighted least-squares step for residual distances.

    Parameters
    ----------
    residuals : (..., n) float
        Distances (m), >= 0; ``inf`` for points without a correspondence.
    kernel : {"tukey", "huber", "cauchy", "l2"}
        Tukey's biweight ``(1 − (r/c)²)²`` (0 beyond c), Huber ``min(1, c/r)``,
        Cauchy ``1 / (1 + (r/c)²)``, or plain least squares (1).
    scale : float or (...) float
        The kernel width c (m), per batch when an array.

    Examples
    --------
    >>> robust_weights([0.0, 0.05, 0.2], "tukey", 0.1).round(4).tolist()
    [1.0, 0.5625, 0.0]
    >>> robust_weights([0.0, 0.2], "huber", 0.1).tolist()
    [1.0, 0.5]
    """
    r = np.asarray(residuals, dtype=np.float64)
    c = np.asarray(scale, dtype=np.float64)
    if np.any(~(c > 0)):
        raise InvalidParameterError("scale", "a float in the range (0, inf)", scale)
    if c.ndim:
        c = c[..., None]
    u = r / c
    finite = np.isfinite(u)
    if kernel == "tukey":
        w = np.where(u < 1.0, (1.0 - np.minimum(u, 1.0) ** 2) ** 2, 0.0)
    elif kernel == "huber":
        with np.errstate(divide="ignore"):
            w = np.where(u <= 1.0, 1.0, 1.0 / np.where(finite, u, 1.0))
    elif kernel == "cauchy":
        w = 1.0 / (1.0 + np.where(finite, u, 0.0) ** 2)
    elif kernel == "l2":
        w = np.ones_like(u)
    else:
        raise InvalidParameterError("kernel", "one of " + ", ".join(map(repr, KERNELS)), kernel)
    return np.where(finite, w, 0.0)


@dataclass(frozen=True)
class GroundIcpResult:
    """Poses found by :func:`ground_icp`, one per starting pose.

    Attributes
    ----------
    x, y, yaw : (h,) float
        Model origin on the floor and rotation about z (levelled frame).
    z : float
        Height of the model's origin (floor contact), unchanged by the fit.
    rms : (h,) float
        Root mean square distance of the matched data points (those within
        ``inlier_distance`` of the model).
    inlier_fraction : (h,) float
        Share of the data points within ``inlier_distance`` of the model.
    cost : (h,) float
        Mean truncated squared distance ``mean(min(r, d)²) / d²`` in [0, 1]: low
        when many points match closely; it ranks hypotheses.
    iterations : (h,) int
    converged : (h,) bool
    residuals : (h, n) float
        Distance of every data point to the model at the final pose.
    """

    x: NDArray[np.float64]
    y: NDArray[np.float64]
    yaw: NDArray[np.float64]
    z: float
    rms: NDArray[np.float64]
    inlier_fraction: NDArray[np.float64]
    cost: NDArray[np.float64]
    iterations: NDArray[np.int64]
    converged: NDArray[np.bool_]
    residuals: NDArray[np.float64]

    def __len__(self) -> int:
        return len(self.x)

    @property
    def best(self) -> int:
        """Index of the hypothesis with the lowest cost."""
        return int(np.argmin(self.cost))

    def pose(self, k: int | None = None) -> NDArray[np.float64]:
        """4x4 model -> levelled transform of hypothesis ``k`` (the best by default)."""
        k = self.best if k is None else k
        return pose_matrix(self.x[k], self.y[k], self.yaw[k], self.z)


def _correspond(
    data: NDArray[np.float64],
    model: NDArray[np.float64],
    tree: cKDTree,
    x: NDArray[np.float64],
    y: NDArray[np.float64],
    yaw: NDArray[np.float64],
    z: float,
    scale: NDArray[np.float64],
    max_distance: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Nearest (scaled) model point of every data point under every pose.

    Returns the (h, n, 3) correspondences in the scaled model frame and the (h, n)
    distances (inf where nothing lies within ``max_distance``).
    """
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    dx = data[None, :, 0] - x[:, None]
    dy = data[None, :, 1] - y[:, None]
    local = np.empty((len(x), len(data), 3))
    local[..., 0] = c * dx + s * dy
    local[..., 1] = -s * dx + c * dy
    local[..., 2] = data[None, :, 2] - z
    # The tree holds the unscaled model: search there with the data unscaled, which is
    # the nearest neighbour of the scaled model for a uniform scale and close to it for
    # the mild anisotropic ones fitting uses, and saves a tree per object.
    _, idx = tree.query(
        (local / scale).reshape(-1, 3), k=1, distance_upper_bound=max_distance / float(scale.min())
    )
    idx = idx.reshape(len(x), len(data))
    found = idx < len(model)
    matched = model[np.where(found, idx, 0)] * scale
    dist = np.linalg.norm(matched - local, axis=-1)
    dist[~found] = np.inf
    return matched, dist


def _kernel_width(dist: NDArray[np.float64], kernel_scale: float | None) -> NDArray[np.float64]:
    """Kernel width per hypothesis: fixed, or Tukey's c from the median matched distance."""
    if kernel_scale is not None:
        return np.full(len(dist), float(kernel_scale))
    ordered = np.sort(dist, axis=1)  # inf (no correspondence) sorts last
    found = np.isfinite(ordered).sum(axis=1)
    med = ordered[np.arange(len(dist)), np.maximum(found - 1, 0) // 2]
    med = np.where(found > 0, med, MAX_KERNEL)
    return np.clip(TUKEY_C * MAD_TO_SIGMA * med, MIN_KERNEL, MAX_KERNEL)


def ground_icp(
    data: ArrayLike,
    model: ArrayLike,
    starts: ArrayLike,
    *,
    tree: cKDTree | None = None,
    scale: ArrayLike = (1.0, 1.0, 1.0),
    z: float = 0.0,
    kernel: str = "tukey",
    kernel_scale: float | None = None,
    max_iterations: int = 30,
    max_distance: float = MAX_KERNEL,
    inlier_distance: float = INLIER_DISTANCE,
    tolerance: float = TOLERANCE,
) -> GroundIcpResult:
    """Fit an upright model to points by (x, y, yaw) only, from one or several starting poses.

    Parameters
    ----------
    data : (n, 3) float
        The object's points in the levelled frame (z up, floor at z = 0).
    model : (m, 3) float
        The model's points in its canonical frame (origin on the floor).
    starts : (3,) or (h, 3) float
        Starting poses (x, y, yaw), each fitted independently.
    tree : scipy.spatial.cKDTree, optional
        A tree of ``model`` (built when not given; pass a cached one).
    scale : (3,) float
        Factors applied to the model along its own x, y, z before the pose.
    z : float
        Height of the model's origin: 0 stands it on the floor. Never changed.
    kernel : {"tukey", "huber", "cauchy", "l2"}
        Robust kernel (:func:`robust_weights`).
    kernel_scale : float, optional
        Fixed kernel width (m); by default it follows the residuals (Tukey's
        4.685 σ with σ = 1.4826 × median residual), between 2 and 30 cm.
    max_iterations : int
    max_distance : float
        Data points farther than this (m) from the model have no correspondence.
    inlier_distance : float
        Distance (m) within which a point counts as matched in the statistics.
    tolerance : float
        Stop when no pose moves by more than this (m, rad).

    Returns
    -------
    GroundIcpResult

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> model = np.c_[rng.random((400, 2)) * [0.8, 0.4], np.full(400, 0.45)]
    >>> model = np.vstack([model, np.c_[rng.random((300, 1)) * 0.8, np.zeros(300),
    ...                    0.45 + rng.random(300) * 0.4]])
    >>> c, s = np.cos(0.2), np.sin(0.2)
    >>> data = model @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + [1.0, 2.0, 0.0]
    >>> fit = ground_icp(data, model, [0.9, 2.1, 0.0])
    >>> np.round([fit.x[0], fit.y[0], fit.yaw[0]], 3).tolist()
    [1.0, 2.0, 0.2]
    """
    d = np.asarray(data, dtype=np.float64)
    m = np.asarray(model, dtype=np.float64)
    for name, a in (("data", d), ("model", m)):
        if a.ndim != 2 or a.shape[1] != 3 or len(a) == 0:
            raise InvalidParameterError(
                name, "a non-empty array of shape (n, 3)", f"shape {a.shape}"
            )
    st = np.atleast_2d(np.asarray(starts, dtype=np.float64))
    if st.ndim != 2 or st.shape[1] != 3 or len(st) == 0:
        raise InvalidParameterError(
            "starts", "an array of shape (3,) or (h, 3)", f"shape {np.shape(starts)}"
        )
    sc = np.asarray(scale, dtype=np.float64).reshape(-1)
    if sc.shape != (3,) or not np.all(np.isfinite(sc) & (sc > 0)):
        raise InvalidParameterError("scale", "three positive factors", scale)
    if kernel not in KERNELS:
        raise InvalidParameterError("kernel", "one of " + ", ".join(map(repr, KERNELS)), kernel)
    if (
        isinstance(max_iterations, bool)
        or not isinstance(max_iterations, (int, np.integer))
        or max_iterations < 0
    ):
        raise InvalidParameterError("max_iterations", "an integer >= 0", max_iterations)
    for name, v in (("max_distance", max_distance), ("inlier_distance", inlier_distance)):
        if not (isinstance(v, (int, float)) and v > 0):
            raise InvalidParameterError(name, "a float in the range (0, inf)", v)
    if kernel_scale is not None and not (
        isinstance(kernel_scale, (int, float)) and kernel_scale > 0
    ):
        raise InvalidParameterError(
            "kernel_scale", "a float in the range (0, inf) or None", kernel_scale
        )
    if tree is None:
        from scipy.spatial import cKDTree  # lazy: scipy.spatial off the import path

        tree = cKDTree(m)
    z = float(z)
    x, y, yaw = st[:, 0].copy(), st[:, 1].copy(), st[:, 2].copy()
    h = len(st)
    iterations = np.zeros(h, dtype=np.int64)
    converged = np.zeros(h, dtype=bool)
    active = np.arange(h)
    # Radius (m) that turns a yaw step into a comparable displacement: the model's reach.
    sample = m[:: max(1, len(m) // REACH_SAMPLE)]
    reach = float(np.max(np.hypot(sample[:, 0] * sc[0], sample[:, 1] * sc[1])))
    previous = np.zeros((h, 3))
    for _ in range(max_iterations):
        if len(active) == 0:
            break
        matched, dist = _correspond(
            d, m, tree, x[active], y[active], yaw[active], z, sc, max_distance
        )
        w = robust_weights(dist, kernel, _kernel_width(dist, kernel_scale))
        new_yaw, t = yaw_procrustes(
            matched[..., :2], np.broadcast_to(d[:, :2], matched[..., :2].shape), w
        )
        # A hypothesis with nothing within reach keeps its pose and stops.
        lost = w.sum(axis=1) <= MIN_WEIGHT
        step = np.c_[
            t[:, 0] - x[active], t[:, 1] - y[active], np.angle(np.exp(1j * (new_yaw - yaw[active])))
        ]
        step[lost] = 0.0
        turn, move = np.abs(step[:, 2]), np.hypot(step[:, 0], step[:, 1])
        # Point-to-point ICP creeps along surfaces with steps that keep their direction;
        # such a step is lengthened (Besl & McKay 1992, accelerated ICP).
        v = step * [1.0, 1.0, reach]
        u = previous[active] * [1.0, 1.0, reach]
        norms = np.linalg.norm(v, axis=1) * np.linalg.norm(u, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            steady = np.where(norms > 0, np.einsum("ij,ij->i", v, u) / norms, 0.0) > ACCEL_COS
        step[steady] *= ACCELERATION
        previous[active] = step
        x[active] += step[:, 0]
        y[active] += step[:, 1]
        yaw[active] += step[:, 2]
        iterations[active] += 1
        done = lost | ((turn < tolerance) & (move < tolerance))
        converged[active[done & ~lost]] = True
        active = active[~done]
    yaw = np.angle(np.exp(1j * yaw))
    _, dist = _correspond(d, m, tree, x, y, yaw, z, sc, max_distance)
    inlier = dist <= inlier_distance
    count = inlier.sum(axis=1)
    sq = np.where(inlier, dist, 0.0) ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.where(count > 0, np.sqrt(sq.sum(axis=1) / np.maximum(count, 1)), np.inf)
    truncated = np.minimum(np.where(np.isfinite(dist), dist, inlier_distance), inlier_distance)
    cost = np.mean(truncated**2, axis=1) / inlier_distance**2
    return GroundIcpResult(
        x=x,
        y=y,
        yaw=yaw,
        z=z,
        rms=rms,
        inlier_fraction=count / len(d),
        cost=cost,
        iterations=iterations,
        converged=converged,
        residuals=dist,
    )
