"""The levelled frame: the map between a scan's own frame and units and the frame every
stage works in (z up, the floor at z = 0, metres), with the smallest rotations that build it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["LevelFrame", "level_transform", "rotation_between", "unit_direction"]


def unit_direction(v: ArrayLike, name: str = "up") -> NDArray[np.float64]:
    """(3,) ``v`` scaled to unit length, or an error naming ``name``.

    Examples
    --------
    >>> unit_direction([0, 0, 2]).tolist()
    [0.0, 0.0, 1.0]
    """
    a = np.asarray(v, dtype=np.float64).reshape(3)
    n = float(np.linalg.norm(a))
    if not np.isfinite(n) or n == 0:
        raise InvalidParameterError(name, "a non-zero 3-vector or an axis name", v)
    return a / n


def rotation_between(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    """The smallest rotation (3, 3) taking unit direction ``a`` onto ``b``.

    Examples
    --------
    >>> import numpy as np
    >>> R = rotation_between([0, -1, 0], [0, 0, 1])
    >>> np.round(R @ [0, -1, 0], 6).tolist()
    [0.0, 0.0, 1.0]
    """
    u, v = unit_direction(a), unit_direction(b)
    c = float(u @ v)
    w = np.cross(u, v)
    s = float(np.linalg.norm(w))
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        # Half turn about any axis perpendicular to u.
        p = np.eye(3)[int(np.argmin(np.abs(u)))]
        k = np.cross(u, p)
        k /= np.linalg.norm(k)
        return 2.0 * np.outer(k, k) - np.eye(3)
    k = w / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1 - c) * (K @ K)


def level_transform(up: ArrayLike, floor_offset: float, scale: float = 1.0) -> NDArray[np.float64]:
    """4x4 transform: scale, rotate ``up`` onto +z, and put the floor at z = 0.

    ``floor_offset`` is the floor height along ``up`` in the scaled frame.

    Examples
    --------
    >>> import numpy as np
    >>> T = level_transform([0, -1, 0], -1.5)  # a camera frame, floor 1.5 m below
    >>> np.round(T @ [0, 1.5, 2, 1], 6).tolist()  # a floor point 2 m ahead
    [0.0, 2.0, 0.0, 1.0]
    """
    R = rotation_between(up, (0.0, 0.0, 1.0))
    T = np.eye(4)
    T[:3, :3] = R * scale
    T[2, 3] = -floor_offset
    return T


@dataclass(frozen=True, eq=False)
class LevelFrame:
    """The map between the input file's frame and the levelled frame (z up, floor at 0, metres).

    Attributes
    ----------
    to_level : (4, 4) float
        Input frame -> levelled frame, including the scale k_s.
    floor_map : object with ``height(xy) -> (k,) float``, optional
        Height of a bent floor above its plane (``preprocess.FloorMap``); heights in the
        levelled frame are measured above it.

    Examples
    --------
    >>> f = LevelFrame.from_dict({"up": [0, 0, 1], "ground_z": -0.3, "scale": 1.0})
    >>> f.level([[1.0, 2.0, -0.3]]).round(6).tolist()
    [[1.0, 2.0, 0.0]]
    >>> f.from_level([[1.0, 2.0, 0.0]]).round(6).tolist()
    [[1.0, 2.0, -0.3]]
    """

    to_level: NDArray[np.float64]
    floor_map: Any = None

    @classmethod
    def identity(cls) -> LevelFrame:
        """The input is already levelled (z up, floor at 0, metres)."""
        return cls(np.eye(4))

    @classmethod
    def from_dict(cls, frame: Mapping[str, Any]) -> LevelFrame:
        """The frame of a detections.json (``{"up": [3], "ground_z": z, "scale": k}``)."""
        try:
            up = np.asarray(frame["up"], dtype=np.float64).reshape(3)
            ground = float(frame.get("ground_z", 0.0))
            scale = float(frame.get("scale", 1.0))
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidParameterError(
                "frame", "{up: [x, y, z], ground_z, scale}", dict(frame)
            ) from exc
        if not (
            np.all(np.isfinite(up))
            and np.linalg.norm(up) > 0
            and math.isfinite(ground)
            and scale > 0
            and math.isfinite(scale)
        ):
            raise InvalidParameterError(
                "frame", "a non-zero up vector, a finite ground_z and a positive scale", dict(frame)
            )
        return cls(level_transform(up / np.linalg.norm(up), ground * scale, scale))

    @property
    def scale(self) -> float:
        """k_s: levelled metres per input unit."""
        return float(np.linalg.norm(self.to_level[:3, 0]))

    @property
    def rotation(self) -> NDArray[np.float64]:
        """(3, 3) rotation input -> levelled (without the scale)."""
        return self.to_level[:3, :3] / self.scale

    @property
    def up(self) -> NDArray[np.float64]:
        """(3,) up direction in the input frame."""
        return self.rotation[2].copy()

    def level(self, points: ArrayLike) -> NDArray[np.float64]:
        """(k, 3) input-frame points in the levelled frame."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        out = pts @ self.to_level[:3, :3].T + self.to_level[:3, 3]
        if self.floor_map is not None and len(out):
            out[:, 2] -= self.floor_map.height(out[:, :2])
        return out

    def from_level(self, points: ArrayLike) -> NDArray[np.float64]:
        """(k, 3) levelled points in the input frame and units."""
        pts = np.array(points, dtype=np.float64).reshape(-1, 3)
        if self.floor_map is not None and len(pts):
            pts[:, 2] += self.floor_map.height(pts[:, :2])
        inv = np.linalg.inv(self.to_level)
        return pts @ inv[:3, :3].T + inv[:3, 3]

    def pose_to_input(self, level_pose: ArrayLike) -> NDArray[np.float64]:
        """A model -> levelled pose as model -> input frame (a bent floor lifts it locally)."""
        T = np.array(level_pose, dtype=np.float64)
        if self.floor_map is not None:
            T[2, 3] += float(self.floor_map.height(T[None, :2, 3])[0])
        return np.linalg.inv(self.to_level) @ T

    def yaw_to_level(self, yaw: float) -> float:
        """An input-frame yaw (about ``up``) in the levelled frame."""
        d = self.rotation @ np.array([math.cos(yaw), math.sin(yaw), 0.0])
        return math.atan2(d[1], d[0])
