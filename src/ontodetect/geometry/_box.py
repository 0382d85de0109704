"""Upright (oriented about the vertical) boxes and their footprints."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["box_corners", "box_footprint", "footprint_gap"]


def box_corners(center: Sequence[float], size: Sequence[float], yaw: float) -> NDArray[np.float64]:
    """(8, 3) corners of an upright box: bottom four counter-clockwise, then the top four.

    Examples
    --------
    >>> box_corners([0, 0, 0.5], [2, 1, 1], 0.0)[0].tolist()
    [-1.0, -0.5, 0.0]
    """
    c = np.asarray(center, dtype=np.float64)
    lx, ly, lz = np.asarray(size, dtype=np.float64) / 2
    local = np.array([[-lx, -ly], [lx, -ly], [lx, ly], [-lx, ly]])
    cs, sn = np.cos(yaw), np.sin(yaw)
    xy = local @ np.array([[cs, sn], [-sn, cs]]) + c[:2]
    bottom = np.c_[xy, np.full(4, c[2] - lz)]
    top = np.c_[xy, np.full(4, c[2] + lz)]
    return np.vstack([bottom, top])


def box_footprint(
    center: Sequence[float], size: Sequence[float], yaw: float
) -> NDArray[np.float64]:
    """(4, 2) corners of an upright box's footprint, counter-clockwise.

    Examples
    --------
    >>> box_footprint([0, 0, 0.5], [2, 1, 1], 0.0).tolist()[0]
    [-1.0, -0.5]
    """
    return box_corners(center, size, yaw)[:4, :2]


def footprint_gap(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """Horizontal gap (m) between two convex footprints (``(k, 2)`` corners in order, as
    :func:`box_footprint` gives them): 0 when they touch or overlap, else the shortest
    distance between their outlines.

    Examples
    --------
    >>> bed = box_footprint([0, 0, 0.3], [2.0, 1.0, 0.6], 0.0)
    >>> stand = box_footprint([0.8, 0.85, 0.3], [0.4, 0.4, 0.6], 0.0)
    >>> round(footprint_gap(bed, stand), 3)
    0.15
    >>> footprint_gap(bed, box_footprint([0.9, 0.4, 0.3], [0.4, 0.4, 0.6], 0.0))
    0.0
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if not _separated(a, b):
        return 0.0
    return min(_to_edges(a, b), _to_edges(b, a))


def _separated(a: NDArray[np.float64], b: NDArray[np.float64]) -> bool:
    """Whether an edge normal of either convex polygon separates the two (separating axes:
    none does when they overlap or touch)."""
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.c_[-edges[:, 1], edges[:, 0]]
        pa, pb = a @ normals.T, b @ normals.T
        if np.any((pa.max(axis=0) < pb.min(axis=0)) | (pb.max(axis=0) < pa.min(axis=0))):
            return True
    return False


def _to_edges(points: NDArray[np.float64], poly: NDArray[np.float64]) -> float:
    """Shortest distance from any of ``points`` to the outline of ``poly``."""
    step = np.roll(poly, -1, axis=0) - poly
    rel = points[:, None, :] - poly[None]
    t = np.clip((rel * step).sum(-1) / np.maximum((step * step).sum(-1), 1e-18), 0.0, 1.0)
    return float(np.linalg.norm(rel - t[..., None] * step, axis=-1).min())
