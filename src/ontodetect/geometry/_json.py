"""Plain JSON values from NumPy and Python ones: one helper for every document written."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["jsonable"]


def jsonable(value: Any, decimals: int | None = None) -> Any:
    """``value`` with NumPy arrays and scalars turned into lists, floats, ints and bools.

    Mappings get string keys, tuples become lists, non-finite floats ``None``. With
    ``decimals``, floats are rounded to that many decimals and ``-0.0`` becomes ``0.0``
    (files stay stable and readable); without, floats are written as they are.
    Other values pass unchanged.

    Examples
    --------
    >>> jsonable({"a": np.array([0.123456, np.inf]), 1: (np.int64(2), np.bool_(True))})
    {'a': [0.123456, None], '1': [2, True]}
    >>> jsonable([-0.00001, 1.23456], decimals=3)
    [0.0, 1.235]
    """
    if isinstance(value, dict):
        return {str(k): jsonable(v, decimals) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v, decimals) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist(), decimals)
    if isinstance(value, np.generic):
        return jsonable(value.item(), decimals)
    if isinstance(value, float):
        if not math.isfinite(value):
            return None
        if decimals is None:
            return value
        v = round(value, decimals)
        return 0.0 if v == 0 else v  # no "-0.0"
    return value
