"""Geometry that several stages share: transforms and the sign rule, upright boxes,
point-set overlap, shape checks for point arrays, and plain JSON values.

- :func:`yaw_pose`, :func:`canonical_sign`: rigid transforms and the one sign rule.
- :func:`box_corners`, :func:`box_footprint`: upright boxes.
- :func:`point_overlap`: point IoU and intersections between sets of point rows.
- :func:`as_points`: the (n, 3) check at a stage's boundary.
- :func:`jsonable`: plain JSON values, optionally rounded.
"""

from __future__ import annotations

from ._box import box_corners, box_footprint
from ._json import jsonable
from ._overlap import point_overlap
from ._points import as_points
from ._transforms import SIGN_TIE_ORDER, SIGN_TIE_TOLERANCE, canonical_sign, yaw_pose

__all__ = [
    "SIGN_TIE_ORDER",
    "SIGN_TIE_TOLERANCE",
    "as_points",
    "box_corners",
    "box_footprint",
    "canonical_sign",
    "jsonable",
    "point_overlap",
    "yaw_pose",
]
