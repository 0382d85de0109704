"""Local surface estimates on a (voxel) cloud: normals and planar smoothing."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._up import cell_index, grouped_covariance
from ..config import Interval, check_param
from ..geometry import as_points

__all__ = ["estimate_normals", "graph_normals", "smooth_surface", "surface_scatter"]

#: A neighbourhood is planar when its smallest eigenvalue is below this share of the sum.
PLANAR_RATIO = 0.05
#: Neighbourhoods are processed in blocks of this many points to bound memory.
BLOCK = 200_000
#: :func:`surface_scatter`: cell edge (m) of the local planes, and the fewest points a cell
#: needs for its plane to count. A quarter metre follows a floor's warp (reconstructions
#: bend by centimetres over metres) while holding enough points of a 50,000-point room.
SCATTER_CELL = 0.25
SCATTER_MIN_POINTS = 10
#: ... and the share of the occupied cells that must hold that many: on a surface seen too
#: sparsely, the cells that do are those where something stands on it.
SCATTER_MIN_SHARE = 0.5
#: Median absolute deviation to standard deviation, for Gaussian scatter.
MAD_TO_STD = 1.4826


def _local_frames(pts: NDArray[np.float64], neighbors: int):
    """Per point: neighbourhood mean, eigenvalues (ascending) and eigenvectors."""
    from scipy.spatial import cKDTree  # heavy: imported when used (start-up)

    n = len(pts)
    k = min(int(neighbors), n)
    tree = cKDTree(pts)
    means = np.empty((n, 3))
    evals = np.empty((n, 3))
    evecs = np.empty((n, 3, 3))
    for s in range(0, n, BLOCK):
        _, idx = tree.query(pts[s : s + BLOCK], k=k, workers=-1)
        nb = pts[idx.reshape(len(idx), -1)]
        mu = nb.mean(axis=1)
        d = nb - mu[:, None, :]
        cov = np.einsum("nki,nkj->nij", d, d) / k
        w, v = np.linalg.eigh(cov)
        means[s : s + BLOCK], evals[s : s + BLOCK], evecs[s : s + BLOCK] = mu, w, v
    return means, evals, evecs


def estimate_normals(
    points: ArrayLike, neighbors: int = 12, *, up: ArrayLike | None = (0.0, 0.0, 1.0)
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Normals and surface variation from the ``neighbors`` nearest points (Alg. 1 step 6).

    Parameters
    ----------
    points : (n, 3) float
    neighbors : int
        Neighbourhood size (the point itself included), >= 3.
    up : (3,) float or None
        Normals are flipped to have a non-negative component along ``up`` (for
        horizontal surfaces) - a consistent sign, not an inside/outside orientation.

    Returns
    -------
    normals : (n, 3) float
        Unit normals.
    variation : (n,) float
        Smallest eigenvalue over the sum (0 on a plane, 1/3 for isotropic scatter).

    Examples
    --------
    >>> import numpy as np
    >>> xy = np.random.default_rng(0).random((500, 2))
    >>> n, v = estimate_normals(np.c_[xy, np.zeros(500)], 8)
    >>> bool(np.allclose(n, [0, 0, 1])), bool(v.max() < 1e-9)
    (True, True)
    """
    pts = as_points(points)
    check_param("neighbors", Interval(3, math.inf, "left", integer=True), neighbors)
    if len(pts) < 3:
        return np.tile([0.0, 0.0, 1.0], (len(pts), 1)), np.zeros(len(pts))
    _, evals, evecs = _local_frames(pts, neighbors)
    normals = evecs[:, :, 0]
    total = evals.sum(axis=1)
    variation = np.divide(evals[:, 0], total, out=np.zeros(len(pts)), where=total > 0)
    if up is not None:
        u = np.asarray(up, dtype=np.float64)
        normals = normals * np.where(normals @ u < 0, -1.0, 1.0)[:, None]
    return normals, variation


def graph_normals(
    points: ArrayLike, graph: Any, *, up: ArrayLike | None = (0.0, 0.0, 1.0)
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Normals and surface variation from the neighbours a sparse graph already lists.

    The covariance of every neighbourhood (the point and its graph neighbours)
    comes from two sparse products, so a neighbour graph built for clustering
    gives normals at almost no extra cost.

    Parameters
    ----------
    points : (n, 3) float
    graph : sparse (n, n) matrix
        Non-zero entries mark neighbours (e.g. ``ontodetect.segment.radius_graph``).
    up : (3,) float or None
        Normals are flipped to have a non-negative component along ``up``.

    Returns
    -------
    normals : (n, 3) float
    variation : (n,) float
        As in :func:`estimate_normals`; points with fewer than two neighbours get
        the normal ``up`` and variation 1/3.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial import cKDTree
    >>> xy = np.random.default_rng(0).random((500, 2))
    >>> pts = np.c_[xy, np.zeros(500)]
    >>> g = cKDTree(pts).sparse_distance_matrix(cKDTree(pts), 0.15)
    >>> n, v = graph_normals(pts, g)
    >>> bool(np.allclose(n, [0, 0, 1])), bool(v.max() < 1e-6)
    (True, True)
    """
    from scipy import sparse

    pts = np.asarray(points, dtype=np.float64)
    m = len(pts)
    a = sparse.csr_matrix(graph, shape=(m, m), copy=True)
    a.data[:] = 1.0
    a = a + sparse.identity(m, format="csr")
    a.data[:] = 1.0  # the point itself once, even if the graph listed it
    count = np.asarray(a.sum(axis=1)).ravel()
    # Centre first (on the global mean) so the sums of squares keep their precision.
    p = pts - pts.mean(axis=0) if m else pts
    mean = (a @ p) / count[:, None]
    outer = np.einsum("ni,nj->nij", p, p).reshape(m, 9)
    second = (a @ outer).reshape(m, 3, 3) / count[:, None, None]
    cov = second - np.einsum("ni,nj->nij", mean, mean)
    evals, evecs = np.linalg.eigh(cov)
    normals = evecs[:, :, 0]
    total = evals.sum(axis=1)
    variation = np.divide(
        np.maximum(evals[:, 0], 0.0), total, out=np.full(m, 1.0 / 3.0), where=total > 0
    )
    few = count < 3
    u = np.array([0.0, 0.0, 1.0]) if up is None else np.asarray(up, dtype=np.float64)
    normals[few] = u
    variation[few] = 1.0 / 3.0
    if up is not None:
        normals = normals * np.where(normals @ u < 0, -1.0, 1.0)[:, None]
    return normals, variation


def smooth_surface(points: ArrayLike, neighbors: int = 12) -> NDArray[np.float64]:
    """Project every point on the plane of its neighbourhood where that is planar.

    A moving-least-squares projection of degree one: scatter across flat parts
    (seats, table tops, walls) shrinks, while edges, legs and clutter, whose
    neighbourhoods are not planar, are left alone (thesis §3.3: smoother surfaces
    and less scattering before plane fitting).

    Returns
    -------
    (n, 3) float
        The smoothed points.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> p = np.c_[rng.random((2000, 2)), rng.normal(0, 0.003, 2000)]
    >>> bool(smooth_surface(p, 16)[:, 2].std() < 0.5 * p[:, 2].std())
    True
    """
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < 3:
        return pts.copy()
    means, evals, evecs = _local_frames(pts, neighbors)
    normals = evecs[:, :, 0]
    total = evals.sum(axis=1)
    planar = evals[:, 0] <= PLANAR_RATIO * np.maximum(total, 1e-300)
    shift = ((pts - means) * normals).sum(axis=1)
    out = pts.copy()
    out[planar] -= shift[planar, None] * normals[planar]
    return out


def surface_scatter(
    points: ArrayLike,
    cell: float = SCATTER_CELL,
    min_points: int = SCATTER_MIN_POINTS,
    min_share: float = SCATTER_MIN_SHARE,
) -> float | None:
    """How far the points of a surface scatter about it (m): a robust standard deviation.

    The points are binned in cells of edge ``cell``; in every cell holding at least
    ``min_points`` of them a plane is fitted, and the cell's scatter is ``1.4826 ·`` the
    median absolute distance of its points to that plane (the standard deviation, for
    Gaussian noise, which a few points of clutter do not move). The surface's scatter is
    the median over the cells: cells that hold two layers (a floor registered twice, a rug,
    a step) scatter more, and may be up to half of them. On the floor of a scan it
    is the sensor's noise as the scan kept it: 1-4 mm on ScanNet's reconstructed rooms,
    about 1 cm on a depth frame seen from 2-3 m.

    Returns
    -------
    float or None
        ``None`` when fewer than ``min_share`` of the occupied cells hold ``min_points``
        points: a floor seen so sparsely (most of it at grazing angles, or hidden) that
        the cells holding enough points are those where something stands on it.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> floor = np.c_[rng.random((20000, 2)) * 4, rng.normal(0.0, 0.004, 20000)]
    >>> round(surface_scatter(floor), 3)
    0.004
    >>> surface_scatter(floor[:5]) is None
    True
    """
    pts = as_points(points, "points")
    if len(pts) < min_points:
        return None
    groups, num = cell_index(pts, cell)
    means, cov, counts = grouped_covariance(pts, groups, num)
    kept = counts >= min_points
    if not kept.any() or kept.mean() < min_share:
        return None
    normals = np.linalg.eigh(cov[kept])[1][:, :, 0]
    slot = np.full(num, -1)
    slot[kept] = np.arange(int(kept.sum()))
    rows = np.flatnonzero(kept[groups])
    cells = slot[groups[rows]]
    dist = np.abs(((pts[rows] - means[groups[rows]]) * normals[cells]).sum(axis=1))
    order = np.lexsort((dist, cells))
    starts = np.searchsorted(cells[order], np.arange(len(normals)))
    sizes = counts[kept]
    medians = 0.5 * (dist[order][starts + (sizes - 1) // 2] + dist[order][starts + sizes // 2])
    return float(MAD_TO_STD * np.median(medians))
