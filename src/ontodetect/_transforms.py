"""Rigid transforms shared by the preparation, the simulator and the CAD fit."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["yaw_pose"]


def yaw_pose(x: float, y: float, yaw: float, z: float = 0.0) -> NDArray[np.float64]:
    """4x4 rigid transform: rotation by ``yaw`` (radians) about z, then translation (x, y, z).

    Examples
    --------
    >>> T = yaw_pose(1.0, 2.0, np.pi / 2)
    >>> np.round(T @ [1, 0, 0, 1], 6).tolist()
    [1.0, 3.0, 0.0, 1.0]
    >>> T.round(6)[:3, 3].tolist()
    [1.0, 2.0, 0.0]
    """
    c, s = np.cos(yaw), np.sin(yaw)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:3, 3] = [x, y, z]
    return T
