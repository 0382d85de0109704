"""Gravity and ground: which way is up, where the floor is, and the levelling transform.

Indoors, gravity shows in the geometry: the floor, the ceiling and the tops of
tables and seats are perpendicular to it, walls are parallel to it, and the floor
is the lowest large plane with everything above it. Normals are estimated on a
coarse grid (one plane fit per cell, from grouped sums: no neighbour search), so
all of this costs two passes over the points. The up direction itself
(:func:`estimate_up`, :func:`cell_planes`, :func:`manhattan_axes`) lives in
``ontodetect._up``, which ``ontodetect info`` shares; this module re-exports it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._up import (
    AXES,
    AXIS_TOLERANCE,
    CellPlanes,
    _candidates,
    _refine,
    _support,
    as_direction,
    cell_planes,
    estimate_up,
    manhattan_axes,
)
from ..cloud import DataWarning
from ..geometry import level_transform, rotation_between, unit_direction

__all__ = [
    "AXES",
    "AXIS_TOLERANCE",
    "CellPlanes",
    "FloorFit",
    "as_direction",
    "cell_planes",
    "estimate_up",
    "find_floor",
    "level_transform",
    "manhattan_axes",
    "rotation_between",
]

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
#: A SLAM map that closed a loop late keeps a drifted copy of part of the floor 2-10 cm off
#: it. Points down to this depth (m) below a floor may be such a copy (a thin sheet, at
#: least the floor's smallest area) rather than a sign that the level is no floor: less than
#: a stair's riser (0.19-0.2 m in building codes, e.g. DIN 18065), and no seat or table top
#: is that low (seats from 35 cm, Table 4.1).
DUPLICATE_FLOOR_DEPTH = 0.15


@dataclass(frozen=True)
class FloorFit:
    """The floor plane ``normal · x = offset``; ``area`` is the horizontal surface found on it."""

    normal: NDArray[np.float64]
    offset: float
    area: float
    found: bool


def find_floor(
    points: ArrayLike,
    up: ArrayLike,
    *,
    cell: float = 0.1,
    min_area: float = 0.5,
    tolerance: float = FLOOR_TOLERANCE,
    cells: CellPlanes | None = None,
    refine: bool = True,
    layers: bool = True,
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
    layers : bool
        Allow a drifted copy of the floor below it (a thin sheet of at least
        ``min_area`` at most :data:`DUPLICATE_FLOOR_DEPTH` down) in the points below.

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
        fit, members = _lowest_level(
            pts, normal, capped, ctr[cap], cnt[cap], cells.cell, min_area, layers
        )
        if fit is not None and refine:
            # Cell normals of a noisy sensor scatter by several degrees; a plane through
            # the centres of the floor's cells is much steadier.
            better = _plane_normal(ctr[cap][members], cnt[cap][members], normal)
            if better @ u > np.cos(np.radians(tolerance)):
                refit, _ = _lowest_level(
                    pts, better, capped, ctr[cap], cnt[cap], cells.cell, min_area, layers
                )
                fit = refit if refit is not None else fit
    if fit is not None:
        return fit
    warnings.warn(
        f"no floor found (no horizontal surface of {min_area:g} m² or more with the scene "
        f"above it); the floor is put at the lowest points along up {_axis_name(u)}. If "
        "that is not the scan's up, let detect estimate it (--up auto, up='auto') or "
        "name it (--up -y, ...)",
        DataWarning,
        stacklevel=2,
    )
    heights = pts @ u
    offset = float(np.percentile(heights, FALLBACK_PERCENTILE)) if len(pts) else 0.0
    return FloorFit(u, offset, 0.0, False)


def _axis_name(u: NDArray[np.float64]) -> str:
    """The named axis ``u`` is, or its rounded components."""
    for name, axis in AXES.items():
        if np.allclose(u, axis, atol=1e-9):
            return name
    return "(" + ", ".join(f"{v:.2f}" for v in u) + ")"


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


def _lowest_level(pts, normal, normals, centers, counts, cell, min_area, layers=False):
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
    sample = pts[:: max(1, len(pts) // 200_000)]
    heights = sample @ normal
    bottom = float(np.percentile(heights, FALLBACK_PERCENTILE))
    for b in np.flatnonzero(smooth >= min_area):
        sel = np.abs(bins - b) <= half
        level = float(np.average(h[sel], weights=counts[horiz][sel]))
        if level - bottom > FLOOR_SEARCH:
            break  # higher levels are furniture or shelves, not a floor
        below = heights < level - 2 * LEVEL_BIN
        if np.mean(below) <= MAX_BELOW_FLOOR or (
            layers and _drifted_copy(sample, heights, below, level, normal, cell, min_area)
        ):
            members = horiz & (np.abs(h_all - level) <= (half + 1) * LEVEL_BIN)
            return FloorFit(normal, level, float(smooth[b]), True), members
    return None, None


def _drifted_copy(sample, heights, below, level, normal, cell, min_area) -> bool:
    """Whether the points below a level are a drifted copy of the floor: within
    :data:`DUPLICATE_FLOOR_DEPTH` of it, one thin layer, at least ``min_area`` across."""
    if np.mean(heights < level - DUPLICATE_FLOOR_DEPTH) > MAX_BELOW_FLOOR:
        return False
    lo, hi = np.percentile(heights[below], [5, 95])
    if hi - lo > LEVEL_WINDOW:
        return False
    flat = sample[below] - np.outer(heights[below], normal)
    keys = np.unique(np.floor(flat / cell).astype(np.int64), axis=0)
    return len(keys) * cell**2 >= min_area
