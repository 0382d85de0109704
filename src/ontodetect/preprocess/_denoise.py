"""Outlier removal (thesis §3.3 filtering, Alg. 1 step 1), scaled to millions of points.

Neighbourhood statistics on raw points cost a k-d tree over every point; on a
10-million-point scan that is minutes and gigabytes. Here they run on the voxel
grid average (one point per occupied voxel), and every point inherits the verdict
of its voxel: an isolated speck of noise is an isolated voxel, while a dense
surface stays dense whatever the sensor's resolution.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..config import POSITIVE, Interval, OneOf, check_param
from ..geometry import as_points
from ._voxel import voxelize

__all__ = [
    "denoise",
    "far_outlier_mask",
    "radius_outlier_mask",
    "statistical_outlier_mask",
]

DENOISE_METHODS = ("statistical", "radius", "both", "none")
#: Statistical outlier removal never drops a point whose mean neighbour distance is within
#: this multiple of the median: on a clean, regular grid the standard deviation is tiny and
#: the plain rule would shave the edges off every surface.
SOR_MEDIAN_FLOOR = 2.0
#: Percentiles of the far-outlier box come from at most about this many points.
PERCENTILE_SAMPLE = 200_000


def statistical_outlier_mask(
    points: ArrayLike, neighbors: int = 8, std_ratio: float = 3.0
) -> NDArray[np.bool_]:
    """Keep points whose mean distance to their neighbours is not unusually large.

    A point is an outlier when its mean distance to its ``neighbors`` nearest
    neighbours exceeds the mean of that statistic over all points by more than
    ``std_ratio`` standard deviations (PCL's StatisticalOutlierRemoval), and is
    more than twice its median (so that clean surfaces keep their edges).

    Parameters
    ----------
    points : (n, 3) float
    neighbors : int
        Neighbours per point, >= 1.
    std_ratio : float
        Cut-off in standard deviations, > 0.

    Returns
    -------
    (n,) bool
        True for points to keep.

    Examples
    --------
    >>> import numpy as np
    >>> g = np.stack(np.meshgrid(np.arange(10), np.arange(10), [0]), -1).reshape(-1, 3) * 0.02
    >>> pts = np.vstack([g, [[5.0, 5.0, 5.0]]])
    >>> keep = statistical_outlier_mask(pts, 4, 2.0)
    >>> bool(keep[-1]), int(keep.sum())
    (False, 100)
    """
    from scipy.spatial import cKDTree  # heavy: imported when used (start-up)

    pts = as_points(points)
    check_param("neighbors", Interval(1, math.inf, "left", integer=True), neighbors)
    check_param("std_ratio", POSITIVE, std_ratio)
    n = len(pts)
    k = min(int(neighbors), n - 1)
    if k < 1:
        return np.ones(n, dtype=bool)
    dist, _ = cKDTree(pts).query(pts, k=k + 1, workers=-1)
    mean = dist[:, 1:].mean(axis=1)
    cut = max(mean.mean() + std_ratio * mean.std(), SOR_MEDIAN_FLOOR * float(np.median(mean)))
    return mean <= cut


def radius_outlier_mask(
    points: ArrayLike, radius: float, min_neighbors: int = 2
) -> NDArray[np.bool_]:
    """Keep points with at least ``min_neighbors`` other points within ``radius``.

    Examples
    --------
    >>> radius_outlier_mask([[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0], [1, 1, 1]], 0.05).tolist()
    [True, True, True, False]
    """
    from scipy.spatial import cKDTree  # heavy: imported when used (start-up)

    pts = as_points(points)
    check_param("radius", POSITIVE, radius)
    if len(pts) == 0:
        return np.ones(0, dtype=bool)
    counts = cKDTree(pts).query_ball_point(pts, radius, return_length=True, workers=-1)
    return (np.asarray(counts) - 1) >= int(min_neighbors)


def far_outlier_mask(
    points: ArrayLike, percentile: float = 0.5, margin: float = 1.0
) -> NDArray[np.bool_]:
    """Keep points inside the box of the central percentiles, grown by ``margin``.

    Measurement errors of range sensors (reflections, mixed pixels at depth
    edges) put a few points metres away from the scene; they stretch every
    bounding box and grid. The box spans the ``percentile``-th to the
    ``100 - percentile``-th percentile on each axis.

    Examples
    --------
    >>> import numpy as np
    >>> pts = np.vstack([np.random.default_rng(0).random((1000, 3)), [[50.0, 0, 0]]])
    >>> bool(far_outlier_mask(pts, 0.5, 1.0)[-1])
    False
    """
    pts = as_points(points)
    check_param("percentile", Interval(0.0, 50.0, "left"), percentile)
    if len(pts) == 0:
        return np.ones(0, dtype=bool)
    # Percentiles of an even thinning are as good and cost a fraction on big clouds.
    sample = pts[:: max(1, len(pts) // PERCENTILE_SAMPLE)]
    lo, hi = np.percentile(sample, [percentile, 100.0 - percentile], axis=0)
    return np.all((pts >= lo - margin) & (pts <= hi + margin), axis=1)


def denoise(
    points: ArrayLike,
    *,
    voxel_size: float = 0.02,
    method: str = "statistical",
    neighbors: int = 8,
    std_ratio: float = 3.0,
    radius: float = 0.1,
    min_neighbors: int = 2,
    far_percentile: float = 0.5,
    far_margin: float = 1.0,
    anchored: bool = False,
) -> NDArray[np.bool_]:
    """Points to keep after far-outlier removal and outlier removal on the voxel grid
    (laid from the frame's origin when ``anchored``, see :func:`voxelize`).

    Parameters
    ----------
    points : (n, 3) float
    voxel_size : float
        Grid on which neighbourhood statistics are computed.
    method : {"statistical", "radius", "both", "none"}
        Which neighbourhood test to apply (far outliers are always removed
        unless ``far_margin`` is infinite).
    neighbors, std_ratio : int, float
        Statistical outlier removal parameters (on voxels).
    radius, min_neighbors : float, int
        Radius outlier removal parameters (occupied voxels within ``radius``).
    far_percentile, far_margin : float
        See :func:`far_outlier_mask`.

    Returns
    -------
    (n,) bool
        True for points to keep.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> plane = np.c_[rng.random((5000, 2)), np.zeros(5000)]
    >>> pts = np.vstack([plane, [[0.5, 0.5, 0.4]]])
    >>> keep = denoise(pts, voxel_size=0.02)
    >>> bool(keep[-1]), int(keep[:-1].sum())
    (False, 5000)
    """
    pts = as_points(points)
    check_param("method", OneOf(DENOISE_METHODS), method)
    keep = (
        far_outlier_mask(pts, far_percentile, far_margin)
        if np.isfinite(far_margin)
        else np.ones(len(pts), dtype=bool)
    )
    if method == "none" or not keep.any():
        return keep
    grid = voxelize(pts, voxel_size, mask=keep, anchored=anchored)
    good = np.ones(len(grid), dtype=bool)
    if method in ("statistical", "both"):
        good &= statistical_outlier_mask(grid.centers, neighbors, std_ratio)
    if method in ("radius", "both"):
        good &= radius_outlier_mask(grid.centers, radius, min_neighbors)
    keep[keep] = good[grid.point_to_voxel[keep]]
    return keep
