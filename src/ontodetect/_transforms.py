"""Shim: rigid transforms and the sign rule live in :mod:`ontodetect.geometry`.

Kept while segment/planes.py, cad/_icp.py and synth/scene.py import from here.
"""

from __future__ import annotations

from .geometry._transforms import SIGN_TIE_ORDER, SIGN_TIE_TOLERANCE, canonical_sign, yaw_pose

__all__ = ["SIGN_TIE_ORDER", "SIGN_TIE_TOLERANCE", "canonical_sign", "yaw_pose"]
