"""Rigid transforms and the one sign rule for normals and axes, shared by every stage."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["SIGN_TIE_ORDER", "SIGN_TIE_TOLERANCE", "canonical_sign", "yaw_pose"]

#: Two components of a unit vector whose magnitudes differ by at most this much are a tie.
#: A fitted plane at 45 degrees between two axes has components equal in exact arithmetic
#: that differ in their last bits from one BLAS build to the next (about 1e-16); real
#: differences between measured directions are many orders larger.
SIGN_TIE_TOLERANCE = 1e-9
#: Axis order that breaks a tie: z first (a horizontal plane's normal points up), then y, then x.
SIGN_TIE_ORDER = (2, 1, 0)


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


def canonical_sign(vector: NDArray[np.float64], tol: float = SIGN_TIE_TOLERANCE) -> float:
    """+1.0 or -1.0: the factor that makes ``vector``'s deciding component positive.

    The deciding component is the largest in magnitude; components within ``tol`` of the
    largest are tied, and the tie goes to the first of z, y, x. This is the one rule by
    which normals and axes are oriented, so that an exact tie does not depend on the last
    bit a linear-algebra library returns. A zero vector gives +1.0.

    Parameters
    ----------
    vector : (3,) float
        A direction, usually of unit length.
    tol : float
        Largest difference of magnitudes that still counts as a tie.

    Examples
    --------
    >>> canonical_sign(np.array([0.1, -0.9, 0.2]))
    -1.0
    >>> canonical_sign(np.array([1.0, -2.0, 2.0]) / 3)  # |y| == |z|: z decides
    1.0
    >>> canonical_sign(np.array([-0.6, 0.0, 0.6]))
    1.0
    """
    v = np.asarray(vector, dtype=np.float64)
    mag = np.abs(v)
    top = float(mag.max()) if v.size else 0.0
    for axis in SIGN_TIE_ORDER:
        if mag[axis] >= top - tol:
            return -1.0 if v[axis] < 0 else 1.0
    return 1.0  # unreachable: the largest component is always within tol of itself
