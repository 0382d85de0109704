"""Geometry that several stages share: transforms and the sign rule, the levelled frame,
upright boxes, point-set
overlap, shape checks for point arrays, and plain JSON values.

- :func:`yaw_pose`, :func:`canonical_sign`: rigid transforms and the one sign rule.
- :class:`LevelFrame`, :func:`level_transform`, :func:`rotation_between`: the levelled frame.
- :func:`box_corners`, :func:`box_footprint`, :func:`footprint_gap`: upright boxes.
- :func:`point_overlap`: point IoU and intersections between sets of point rows.
- :func:`as_points`: the (n, 3) check at a stage's boundary.
- :func:`jsonable`: plain JSON values, optionally rounded.
- :class:`Mesh`: a triangle mesh with named parts, built by the simulator and the CAD models.
"""

from __future__ import annotations

from ._box import box_corners, box_footprint, footprint_gap
from ._frame import LevelFrame, level_transform, rotation_between, unit_direction
from ._json import jsonable
from ._mesh import Mesh
from ._overlap import point_overlap
from ._points import as_points
from ._transforms import SIGN_TIE_ORDER, SIGN_TIE_TOLERANCE, canonical_sign, yaw_pose

__all__ = [
    "SIGN_TIE_ORDER",
    "SIGN_TIE_TOLERANCE",
    "LevelFrame",
    "Mesh",
    "as_points",
    "box_corners",
    "box_footprint",
    "canonical_sign",
    "footprint_gap",
    "jsonable",
    "level_transform",
    "point_overlap",
    "rotation_between",
    "unit_direction",
    "yaw_pose",
]
