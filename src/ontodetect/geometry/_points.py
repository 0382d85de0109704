"""Shape checks for arrays of points, done once at every stage's boundary."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = ["as_points"]


def as_points(
    a: ArrayLike,
    name: str = "points",
    *,
    n: int | None = None,
    dtype: Any = np.float64,
    copy: bool = False,
    finite: bool = False,
) -> NDArray[Any]:
    """``a`` as a contiguous (n, 3) numeric array, or an error naming ``name``.

    Parameters
    ----------
    a : (n, 3) array_like
        Points (or normals).
    name : str
        The parameter's name in the error.
    n : int, optional
        Required number of rows.
    dtype : dtype
        Of the result (float64 by default).
    copy : bool
        Always copy (otherwise only when a conversion needs one).
    finite : bool
        Also refuse NaN and infinite coordinates.

    Raises
    ------
    InvalidParameterError
        Not of shape (n, 3), not numbers, or (with ``finite``) not finite.

    Examples
    --------
    >>> as_points([[0, 1, 2]]).dtype
    dtype('float64')
    >>> as_points([1, 2, 3])
    Traceback (most recent call last):
    ...
    ontodetect.errors.InvalidParameterError: ...
    """
    arr = np.asarray(a)
    if arr.ndim != 2 or arr.shape[1] != 3 or (n is not None and arr.shape[0] != n):
        want = "(n, 3)" if n is None else f"({n}, 3)"
        raise InvalidParameterError(name, f"an array of shape {want}", f"shape {arr.shape}")
    if arr.dtype.kind not in "biuf":
        raise InvalidParameterError(name, "a numeric array", f"dtype {arr.dtype}")
    out = np.array(arr, dtype=dtype, copy=True) if copy else np.asarray(arr, dtype=dtype)
    if finite and not np.isfinite(out).all():
        bad = int(np.count_nonzero(~np.isfinite(out).all(axis=1)))
        raise InvalidParameterError(name, "finite coordinates", f"{bad} non-finite point(s)")
    return np.ascontiguousarray(out)
