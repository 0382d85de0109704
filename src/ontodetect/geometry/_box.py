"""Upright (oriented about the vertical) boxes and their footprints."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["box_corners", "box_footprint"]


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
