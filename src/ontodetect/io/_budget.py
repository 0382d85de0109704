"""How much a reader may take: checked against what a file declares, before allocating.

A header says how many points follow and a compressed member how large it grows; both are
checked here, before a buffer of that size is asked for, so a lying or merely huge file is
one clear error instead of a ``MemoryError`` (or the machine swapping).

The budget is :func:`max_points` points and :func:`max_bytes` bytes of decoded data. Both
come from the memory available when the process starts (the pipeline holds several copies
of the cloud, about :data:`BYTES_PER_POINT` bytes a point all told) and are capped at
:data:`POINT_CAP`; the environment variables ``ONTODETECT_MAX_POINTS`` and
``ONTODETECT_MAX_BYTES`` set them explicitly.

At the other end, a scan to detect in must hold at least :data:`MIN_SCAN_POINTS` points.
"""

from __future__ import annotations

import functools
import os

import numpy as np
from numpy.typing import NDArray

from .._up import MIN_CELL_POINTS
from ..errors import ReadError

__all__ = [
    "BYTES_PER_POINT",
    "MAX_COORDINATE",
    "MAX_EXTENT",
    "MIN_SCAN_POINTS",
    "POINT_CAP",
    "check_bytes",
    "check_enough_points",
    "check_extent",
    "check_points",
    "max_bytes",
    "max_points",
]

#: Memory one input point costs through the pipeline (copies, normals, labels, voxels).
BYTES_PER_POINT = 200
#: The most points read by default, whatever the memory: a room is 1-10 million.
POINT_CAP = 100_000_000
#: Fallback when the available memory cannot be read (4 GiB).
_FALLBACK_MEMORY = 4 * 2**30


def _env_int(name: str) -> int | None:
    raw = os.environ.get(name)
    if raw is None or not raw.strip():
        return None
    try:
        value = int(raw)
    except ValueError:
        raise ReadError(
            name, f"environment variable must be a whole number > 0, got {raw!r}"
        ) from None
    if value <= 0:
        raise ReadError(
            name, f"environment variable must be a whole number > 0, got {raw!r}"
        ) from None
    return value


@functools.cache
def _available_memory() -> int:
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return _FALLBACK_MEMORY


def max_points() -> int:
    """The most points one input may declare (``ONTODETECT_MAX_POINTS`` overrides)."""
    explicit = _env_int("ONTODETECT_MAX_POINTS")
    if explicit is not None:
        return explicit
    return max(1, min(POINT_CAP, _available_memory() // BYTES_PER_POINT))


def max_bytes() -> int:
    """The most bytes of decoded data one input may take (``ONTODETECT_MAX_BYTES``
    overrides); by default half the memory available."""
    explicit = _env_int("ONTODETECT_MAX_BYTES")
    if explicit is not None:
        return explicit
    return max(1, _available_memory() // 2)


def check_points(path: os.PathLike[str] | str, count: int, what: str = "the file") -> None:
    """Refuse ``count`` declared points beyond :func:`max_points`."""
    limit = max_points()
    if count > limit:
        raise ReadError(
            path,
            f"{what} declares {count:,} points, more than the {limit:,} this machine can "
            "process (set ONTODETECT_MAX_POINTS to change the limit, or split the scan)",
        )


def check_bytes(path: os.PathLike[str] | str, size: int, what: str = "the file") -> None:
    """Refuse ``size`` declared bytes of decoded data beyond :func:`max_bytes`."""
    limit = max_bytes()
    if size > limit:
        raise ReadError(
            path,
            f"{what} declares {size:,} bytes of data, more than the {limit:,} allowed "
            "(set ONTODETECT_MAX_BYTES to change the limit)",
        )


#: Fewest points with finite coordinates a scan must hold for detection and segmentation.
#: The preparation finds the up direction, the floor and every plane from plane fits in
#: the cells of a grid, and a cell's fit counts only with ``MIN_CELL_POINTS`` points
#: (three fix a plane; the others tell a plane from noise): a scan with fewer can hold no
#: plane, so no floor and no object, and its point spacing (hence the clustering radius)
#: would rest on a handful of distances.
MIN_SCAN_POINTS = MIN_CELL_POINTS


def check_enough_points(
    path: os.PathLike[str] | str, count: int, min_points: int = MIN_SCAN_POINTS
) -> None:
    """Refuse a scan of ``count`` points with finite coordinates, fewer than ``min_points``."""
    if count < min_points:
        raise ReadError(
            path,
            f"holds only {count} point{'s' if count != 1 else ''} with finite coordinates; "
            f"at least {min_points} are needed to find planes (and so the floor and any object)",
        )


#: The widest a scan may be along any axis, in its own units: 10 km in millimetres,
#: 10,000 km in metres. Nothing indoors comes near; a point beyond is damage (or a
#: coordinate in the wrong field), and geometry that far apart overflows the fits.
MAX_EXTENT = 1e7
#: The largest absolute coordinate accepted (georeferenced scans are ~1e7 m from their
#: origin; beyond 1e9 a float64 no longer holds millimetres).
MAX_COORDINATE = 1e9


def check_extent(path: os.PathLike[str] | str, xyz: NDArray[np.floating]) -> None:
    """Refuse a cloud whose finite points span more than :data:`MAX_EXTENT` along an axis
    or lie further than :data:`MAX_COORDINATE` from the origin."""
    pts = np.asarray(xyz, dtype=np.float64)
    if pts.size == 0:
        return
    finite = np.isfinite(pts).all(axis=1)
    if not finite.any():
        return
    pts = pts[finite] if not finite.all() else pts
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    biggest = float(np.max(np.maximum(np.abs(lo), np.abs(hi))))
    if biggest > MAX_COORDINATE:
        axis = "xyz"[int(np.argmax(np.maximum(np.abs(lo), np.abs(hi))))]
        raise ReadError(
            path,
            f"a point lies at {axis} = {biggest:.3g}, beyond the {MAX_COORDINATE:.0e} a "
            "scan's coordinates may reach (a damaged or mis-scaled file)",
        )
    span = hi - lo
    if float(span.max()) > MAX_EXTENT:
        axis = "xyz"[int(np.argmax(span))]
        raise ReadError(
            path,
            f"the points span {float(span.max()):.3g} along {axis}, more than the "
            f"{MAX_EXTENT:.0e} a building can (a damaged or mis-scaled file)",
        )
