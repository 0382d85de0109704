"""Gravity and ground: which way is up, where the floor is, and the levelling transform.

Indoors, gravity shows in the geometry: the floor, the ceiling and the tops of
tables and seats are perpendicular to it, walls are parallel to it, and the floor
is the lowest large plane with everything above it. Normals are estimated on a
coarse grid (one plane fit per cell, from grouped sums: no neighbour search), so
all of this costs two passes over the points.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..cloud import DataWarning
from ..errors import InvalidParameterError
from ..geometry import level_transform, rotation_between, unit_direction
from ._voxel import grouped_covariance, voxelize

__all__ = [
    "AXES",
    "CellPlanes",
    "FloorFit",
    "cell_planes",
    "estimate_up",
    "find_floor",
    "level_transform",
    "manhattan_axes",
    "rotation_between",
]

#: Named up directions accepted by :func:`estimate_up` and ``prepare(up=...)``.
AXES: dict[str, tuple[float, float, float]] = {
    "x": (1.0, 0.0, 0.0),
    "-x": (-1.0, 0.0, 0.0),
    "y": (0.0, 1.0, 0.0),
    "-y": (0.0, -1.0, 0.0),
    "z": (0.0, 0.0, 1.0),
    "-z": (0.0, 0.0, -1.0),
}
#: A cell is planar when its smallest eigenvalue is below this share of the eigenvalue sum.
PLANAR_RATIO = 0.05
#: Fewest points in a cell for its plane fit to count.
MIN_CELL_POINTS = 5
#: Normals within this angle (deg) of a direction support it.
AXIS_TOLERANCE = 10.0
#: At most this many cell normals are tried as candidate directions, each counted against
#: at most ``SUPPORT_SAMPLE`` normals.
MAX_CANDIDATES = 500
SUPPORT_SAMPLE = 3000
#: The floor normal may differ from the given or estimated up axis by up to this (deg):
#: scans drift, and a SLAM map is rarely exactly levelled.
FLOOR_TOLERANCE = 15.0
#: Cells whose normal is within this angle (deg) of the floor normal are horizontal.
HORIZONTAL_TOLERANCE = 6.0
#: Bin width (m) of the height histogram of horizontal cells.
LEVEL_BIN = 0.02
#: Width (m) of a level: a floor seen by a noisy sensor spreads over several bins.
LEVEL_WINDOW = 0.08
#: Cells whose normal is within this angle (deg) of the floor normal count for a level.
LEVEL_TOLERANCE = 12.0
#: Candidate floors are sought up to this height (m) above the lowest points; higher
#: levels are furniture.
FLOOR_SEARCH = 0.6
#: Share of the points allowed below a floor (noise, reflections, a hole in the floor).
MAX_BELOW_FLOOR = 0.05
#: Without a floor, the floor is put at this percentile of heights.
FALLBACK_PERCENTILE = 0.5
#: Bonus of the given up hint when choosing among the axes of the Manhattan frame.
HINT_WEIGHT = 1.0
#: Heights (m) above a candidate floor where furniture tops and seats are.
FURNITURE_BAND = (0.3, 1.2)


@dataclass(frozen=True)
class CellPlanes:
    """A plane fitted in every occupied cell of a coarse grid.

    Attributes
    ----------
    centers : (g, 3) float
        Mean of the points in each cell.
    normals : (g, 3) float
        Unit normal of each cell's best-fit plane (sign arbitrary).
    counts : (g,) int
        Points per cell.
    planar : (g,) bool
        Cells holding a plane (enough points, flat enough).
    cell : float
        Cell edge.
    """

    centers: NDArray[np.float64]
    normals: NDArray[np.float64]
    counts: NDArray[np.int64]
    planar: NDArray[np.bool_]
    cell: float


@dataclass(frozen=True)
class FloorFit:
    """The floor plane ``normal · x = offset``; ``area`` is the horizontal surface found on it."""

    normal: NDArray[np.float64]
    offset: float
    area: float
    found: bool


def as_direction(up: str | ArrayLike) -> NDArray[np.float64]:
    """A unit vector from an axis name (``"z"``, ``"-y"``...) or a 3-vector."""
    if isinstance(up, str):
        if up not in AXES:
            raise InvalidParameterError("up", "one of " + ", ".join(map(repr, AXES)), up)
        return np.array(AXES[up])
    return unit_direction(up)


def cell_planes(points: ArrayLike, cell: float = 0.1) -> CellPlanes:
    """Fit a plane in every cell of a grid of edge ``cell``.

    Examples
    --------
    >>> import numpy as np
    >>> xy = np.random.default_rng(0).random((2000, 2))
    >>> c = cell_planes(np.c_[xy, 0.5 * np.ones(2000)], 0.1)
    >>> bool(c.planar.all()), np.abs(c.normals[:, 2]).min() > 0.99
    (True, np.True_)
    """
    pts = np.asarray(points, dtype=np.float64)
    grid = voxelize(pts, cell)
    means, cov, counts = grouped_covariance(pts, grid.point_to_voxel, len(grid))
    evals, evecs = np.linalg.eigh(cov)
    normals = evecs[:, :, 0]
    total = evals.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        flat = evals[:, 0] <= PLANAR_RATIO * total
    planar = (counts >= MIN_CELL_POINTS) & flat & (total > 0)
    return CellPlanes(means, normals, counts.astype(np.int64), planar, float(cell))


def _support(
    normals: NDArray[np.float64], candidates: NDArray[np.float64], tolerance_deg: float
) -> NDArray[np.int64]:
    # Counting on an even thinning of the normals ranks candidates the same way.
    normals = normals[:: max(1, len(normals) // SUPPORT_SAMPLE)]
    cos_tol = np.cos(np.radians(tolerance_deg))
    out = np.zeros(len(candidates), dtype=np.int64)
    step = max(1, 20_000_000 // max(len(normals), 1))  # bound the (candidates, normals) block
    for s in range(0, len(candidates), step):
        out[s : s + step] = (np.abs(candidates[s : s + step] @ normals.T) > cos_tol).sum(axis=1)
    return out


def _refine(
    normals: NDArray[np.float64], axis: NDArray[np.float64], tolerance_deg: float
) -> NDArray[np.float64]:
    """Mean of the normals within the tolerance of ``axis`` (signs aligned), normalised."""
    for _ in range(3):
        d = normals @ axis
        near = np.abs(d) > np.cos(np.radians(tolerance_deg))
        if not near.any():
            break
        mean = (normals[near] * np.sign(d[near])[:, None]).sum(axis=0)
        axis = mean / np.linalg.norm(mean)
    return axis


def _candidates(normals: NDArray[np.float64]) -> NDArray[np.float64]:
    step = max(1, len(normals) // MAX_CANDIDATES)
    return normals[::step]  # deterministic thinning


def manhattan_axes(normals: ArrayLike) -> NDArray[np.float64]:
    """Three orthogonal directions that most plane normals follow (a Manhattan frame).

    Parameters
    ----------
    normals : (g, 3) float
        Unit normals of planar patches.

    Returns
    -------
    (3, 3) float
        Rows are the axes, the best supported first.

    Examples
    --------
    >>> import numpy as np
    >>> n = np.repeat(np.eye(3), [50, 30, 20], axis=0)
    >>> np.abs(manhattan_axes(n)).round(3).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    """
    nrm = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    if len(nrm) == 0:
        return np.eye(3)
    cand = _candidates(nrm)
    a1 = _refine(nrm, cand[int(np.argmax(_support(nrm, cand, AXIS_TOLERANCE)))], AXIS_TOLERANCE)
    perp = np.abs(cand @ a1) < np.sin(np.radians(AXIS_TOLERANCE))
    if perp.any():
        c2 = cand[perp]
        a2 = c2[int(np.argmax(_support(nrm, c2, AXIS_TOLERANCE)))]
    else:
        a2 = np.eye(3)[int(np.argmin(np.abs(a1)))]
    a2 = a2 - (a2 @ a1) * a1
    a2 = _refine(nrm, a2 / np.linalg.norm(a2), AXIS_TOLERANCE)
    a2 = a2 - (a2 @ a1) * a1
    a2 /= np.linalg.norm(a2)
    a3 = np.cross(a1, a2)
    return np.stack([a1, a2, a3])


def _floor_score(
    cells: CellPlanes, heights_all: NDArray[np.float64], up: NDArray[np.float64]
) -> float:
    """How much the geometry looks like a room with ``up`` as its up direction.

    Horizontal area near the lowest large level (the floor) plus horizontal area at
    furniture height above it, in units of cell area; zero when most points would
    lie below the floor.
    """
    nrm = cells.normals[cells.planar]
    ctr = cells.centers[cells.planar]
    horiz = np.abs(nrm @ up) > np.cos(np.radians(AXIS_TOLERANCE))
    if horiz.sum() == 0:
        return 0.0
    h = ctr[horiz] @ up
    lo = float(np.percentile(heights_all, 1.0))
    near_floor = np.abs(h - lo) < 2 * cells.cell
    floor_level = float(np.median(h[near_floor])) if near_floor.any() else lo
    furniture = (h - floor_level > FURNITURE_BAND[0]) & (h - floor_level < FURNITURE_BAND[1])
    median = float(np.median(heights_all))
    top = float(np.percentile(heights_all, 99.0))
    # Furniture stands on the floor: most points are in the lower part of the room.
    lower_half = 1.0 if median - lo <= top - median else 0.5
    return (float(near_floor.sum()) + float(furniture.sum())) * lower_half


def estimate_up(
    points: ArrayLike,
    *,
    hint: str | ArrayLike | None = "z",
    cell: float = 0.1,
    max_angle: float | None = None,
) -> tuple[NDArray[np.float64], float]:
    """Estimate the up direction of an indoor scan from its planes.

    The normals of planar cells give a Manhattan frame (floor/ceiling normal and
    two wall directions). Each of its six signed axes is scored by the horizontal
    area it would put on a floor at the bottom of the scan and at furniture height
    above it; the given ``hint`` (the axis the data's convention suggests: ``z``
    for lidar and most maps, ``-y`` for camera frames) adds a bonus.

    Parameters
    ----------
    points : (n, 3) float
    hint : str or (3,) float or None
        Direction expected to be up.
    cell : float
        Cell edge (m) of the plane fits.
    max_angle : float, optional
        Only axes within this angle (deg) of ``hint`` are considered: a camera
        frame is pitched and rolled, but not upside down.

    Returns
    -------
    up : (3,) float
        Unit vector in the input frame.
    confidence : float
        Share of the best score among the six signed axes (1 = unambiguous).
    """
    pts = np.asarray(points, dtype=np.float64)
    cells = cell_planes(pts, cell)
    if cells.planar.sum() < 3:
        fallback = as_direction(hint if hint is not None else "z")
        return fallback, 0.0
    axes = manhattan_axes(cells.normals[cells.planar])
    hint_vec = None if hint is None else as_direction(hint)
    sample = pts[:: max(1, len(pts) // 200_000)]
    signed = np.concatenate([axes, -axes])
    scores = np.array([_floor_score(cells, sample @ u, u) for u in signed])
    if hint_vec is not None:
        bonus = np.clip(signed @ hint_vec, 0.0, None) ** 2
        scores = scores * (1.0 + HINT_WEIGHT * bonus)
        if max_angle is not None:
            allowed = signed @ hint_vec >= np.cos(np.radians(max_angle))
            if not allowed.any():
                return hint_vec, 0.0
            scores = np.where(allowed, scores, 0.0)
    best = int(np.argmax(scores))
    total = float(scores.sum())
    return signed[best], (float(scores[best]) / total if total > 0 else 0.0)


def find_floor(
    points: ArrayLike,
    up: ArrayLike,
    *,
    cell: float = 0.1,
    min_area: float = 0.5,
    tolerance: float = FLOOR_TOLERANCE,
    cells: CellPlanes | None = None,
    refine: bool = True,
) -> FloorFit:
    """Find the floor: the lowest large plane roughly perpendicular to ``up``.

    The floor normal is refined from the horizontal cells (so a scan that drifted
    a few degrees is levelled on its floor), and the floor is the lowest height
    at which at least ``min_area`` of horizontal surface lies, with nearly all
    points above it. Without such a plane the floor is put at the lowest points
    along ``up`` and a :class:`~ontodetect.DataWarning` says so.

    Parameters
    ----------
    points : (n, 3) float
    up : (3,) float
        Approximate up direction.
    cell : float
        Cell edge (m) of the plane fits.
    min_area : float
        Smallest floor surface (m²).
    tolerance : float
        Largest angle (deg) between ``up`` and the floor normal.
    cells : CellPlanes, optional
        Plane fits already computed with :func:`cell_planes`.
    refine : bool
        Take the floor's own normal as up (True) or keep ``up`` and only find the
        floor height along it.

    Returns
    -------
    FloorFit
        ``normal`` points up; ``found`` is False for the fallback.
    """
    pts = np.asarray(points, dtype=np.float64)
    u = unit_direction(up)
    cells = cells if cells is not None else cell_planes(pts, cell)
    nrm = cells.normals[cells.planar]
    ctr = cells.centers[cells.planar]
    cnt = cells.counts[cells.planar]
    d = nrm @ u
    cap = np.abs(d) > np.cos(np.radians(tolerance))
    normal = u
    fit: FloorFit | None = None
    if cap.sum() >= 3:
        capped = nrm[cap] * np.sign(d[cap])[:, None]
        if refine:
            cand = _candidates(capped)
            best = cand[int(np.argmax(_support(capped, cand, HORIZONTAL_TOLERANCE / 2)))]
            normal = _refine(capped, best, HORIZONTAL_TOLERANCE / 2)
        fit, members = _lowest_level(pts, normal, capped, ctr[cap], cnt[cap], cells.cell, min_area)
        if fit is not None and refine:
            # Cell normals of a noisy sensor scatter by several degrees; a plane through
            # the centres of the floor's cells is much steadier.
            better = _plane_normal(ctr[cap][members], cnt[cap][members], normal)
            if better @ u > np.cos(np.radians(tolerance)):
                refit, _ = _lowest_level(
                    pts, better, capped, ctr[cap], cnt[cap], cells.cell, min_area
                )
                fit = refit if refit is not None else fit
    if fit is not None:
        return fit
    warnings.warn(
        f"no floor found (no horizontal surface of {min_area:g} m² or more with the scene "
        "above it); the floor is put at the lowest points",
        DataWarning,
        stacklevel=2,
    )
    heights = pts @ u
    offset = float(np.percentile(heights, FALLBACK_PERCENTILE)) if len(pts) else 0.0
    return FloorFit(u, offset, 0.0, False)


def window_sum(values: NDArray[np.float64], half: int) -> NDArray[np.float64]:
    """Sum over ``values[i - half : i + half + 1]``, same length as ``values``.

    Examples
    --------
    >>> window_sum(np.array([1.0, 2.0, 3.0]), 1).tolist()
    [3.0, 6.0, 5.0]
    """
    padded = np.pad(np.asarray(values, dtype=np.float64), half)
    return np.convolve(padded, np.ones(2 * half + 1), mode="valid")


def _plane_normal(centers, weights, near):
    mu = np.average(centers, axis=0, weights=weights)
    d = centers - mu
    cov = (d * weights[:, None]).T @ d
    n = np.linalg.eigh(cov)[1][:, 0]
    return n if n @ near >= 0 else -n


def _lowest_level(pts, normal, normals, centers, counts, cell, min_area):
    """The lowest level along ``normal`` holding ``min_area`` of horizontal cells."""
    horiz = normals @ normal > np.cos(np.radians(LEVEL_TOLERANCE))
    if not horiz.any():
        return None, None
    h_all = centers @ normal
    h = h_all[horiz]
    lo = float(h.min())
    span = float(h.max()) - lo
    nbins = max(1, int(np.ceil(span / LEVEL_BIN)) + 1)
    bins = np.minimum(((h - lo) / LEVEL_BIN).astype(np.int64), nbins - 1)
    area = np.bincount(bins, minlength=nbins) * cell**2
    # A floor seen by a noisy sensor, or not perfectly flat, spreads over several bins.
    half = round(LEVEL_WINDOW / LEVEL_BIN / 2)
    smooth = window_sum(area, half)
    heights = pts[:: max(1, len(pts) // 200_000)] @ normal
    bottom = float(np.percentile(heights, FALLBACK_PERCENTILE))
    for b in np.flatnonzero(smooth >= min_area):
        sel = np.abs(bins - b) <= half
        level = float(np.average(h[sel], weights=counts[horiz][sel]))
        if level - bottom > FLOOR_SEARCH:
            break  # higher levels are furniture or shelves, not a floor
        if np.mean(heights < level - 2 * LEVEL_BIN) <= MAX_BELOW_FLOOR:
            members = horiz & (np.abs(h_all - level) <= (half + 1) * LEVEL_BIN)
            return FloorFit(normal, level, float(smooth[b]), True), members
    return None, None
