"""Voxel grid average: one point per occupied voxel, and the map back to every input point."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._up import grouped_covariance
from ..config import POSITIVE, check_param
from ..errors import InvalidParameterError
from ..geometry import as_points

__all__ = ["VoxelGrid", "grouped_covariance", "voxel_keys", "voxelize"]

#: Voxel keys are packed into one int64 with this many bits per axis (2**21 voxels a side:
#: 40 km at 2 cm), so that grouping is a single integer sort.
KEY_BITS = 21
KEY_LIMIT = 1 << KEY_BITS
#: Grids whose keys fit in this many bits are grouped with 32-bit integers.
SMALL_KEY_BITS = 31


@dataclass(frozen=True, eq=False)
class VoxelGrid:
    """Points grouped by voxel, with the grid average of each voxel.

    Attributes
    ----------
    size : float
        Voxel edge.
    origin : (3,) float
        Corner of voxel (0, 0, 0).
    keys : (m, 3) int64
        Integer coordinates of every occupied voxel.
    centers : (m, 3) float
        Centroid of the points in each voxel (the grid average).
    colors : (m, 3) uint8 or None
        Mean colour of each voxel.
    counts : (m,) int64
        Points per voxel.
    point_to_voxel : (n,) int64
        Voxel of every input point; -1 for points left out (``mask`` was False).
    """

    size: float
    origin: NDArray[np.float64]
    keys: NDArray[np.int64]
    centers: NDArray[np.float64]
    colors: NDArray[np.uint8] | None
    counts: NDArray[np.int64]
    point_to_voxel: NDArray[np.int64]

    def __len__(self) -> int:
        return int(self.counts.shape[0])

    def subset(self, keep: ArrayLike) -> VoxelGrid:
        """The grid without the voxels where ``keep`` is False; their points map to -1.

        Examples
        --------
        >>> g = voxelize([[0, 0, 0], [1, 0, 0], [2, 0, 0]], 0.5)
        >>> g.subset([True, False, True]).point_to_voxel.tolist()
        [0, -1, 1]
        """
        mask = np.asarray(keep, dtype=bool)
        new_index = np.full(len(self) + 1, -1, dtype=np.int64)
        new_index[:-1][mask] = np.arange(int(mask.sum()))
        return VoxelGrid(
            self.size,
            self.origin,
            self.keys[mask],
            self.centers[mask],
            None if self.colors is None else self.colors[mask],
            self.counts[mask],
            new_index[self.point_to_voxel],
        )

    def points_of(self, voxels: ArrayLike) -> NDArray[np.int64]:
        """Indices of the input points that fall in the given voxels, in input order.

        Parameters
        ----------
        voxels : (k,) int or (m,) bool
            Voxel indices or a mask over the voxels.

        Examples
        --------
        >>> g = voxelize([[0.01, 0, 0], [0.5, 0, 0], [0.011, 0.001, 0]], 0.02)
        >>> g.points_of([g.point_to_voxel[0]]).tolist()
        [0, 2]
        """
        sel = np.asarray(voxels)
        mask = np.zeros(len(self) + 1, dtype=bool)  # last slot: points without a voxel
        if sel.dtype == bool:
            mask[:-1] = sel
        else:
            mask[sel.astype(np.intp, copy=False)] = True
        return np.flatnonzero(mask[self.point_to_voxel]).astype(np.int64)


def voxel_keys(points: ArrayLike, size: float, origin: ArrayLike) -> NDArray[np.int64]:
    """(n, 3) integer voxel coordinates ``floor((points - origin) / size)``."""
    pts = np.asarray(points, dtype=np.float64)
    return np.floor((pts - np.asarray(origin, dtype=np.float64)) / size).astype(np.int64)


def _pack(keys: NDArray[np.int64]) -> tuple[NDArray[np.integer], tuple[int, int, int]]:
    """One integer per (non-negative) key, and the bits of each axis.

    Room-sized grids fit in 31 bits: 32-bit integers sort about three times faster
    than 64-bit ones, and sorting is most of the cost of grouping.
    """
    bits = tuple(max(1, int(v).bit_length()) for v in keys.max(axis=0))
    if sum(bits) <= SMALL_KEY_BITS:
        k = keys.astype(np.int32)
        return (k[:, 0] << (bits[1] + bits[2])) | (k[:, 1] << bits[2]) | k[:, 2], bits
    bits = (KEY_BITS, KEY_BITS, KEY_BITS)
    return (keys[:, 0] << (2 * KEY_BITS)) | (keys[:, 1] << KEY_BITS) | keys[:, 2], bits


def _unpack(packed: NDArray[np.integer], bits: tuple[int, int, int]) -> NDArray[np.int64]:
    p = packed.astype(np.int64)
    out = np.empty((len(p), 3), dtype=np.int64)
    out[:, 0] = p >> (bits[1] + bits[2])
    out[:, 1] = (p >> bits[2]) & ((1 << bits[1]) - 1)
    out[:, 2] = p & ((1 << bits[2]) - 1)
    return out


def voxelize(
    points: ArrayLike,
    size: float,
    colors: ArrayLike | None = None,
    *,
    mask: ArrayLike | None = None,
    origin: ArrayLike | None = None,
    anchored: bool = False,
) -> VoxelGrid:
    """Group points into cubic voxels and average each voxel (thesis §3.3, Alg. 1 step 3).

    Parameters
    ----------
    points : (n, 3) float
        Coordinates.
    size : float
        Voxel edge, > 0.
    colors : (n, 3) uint8, optional
        Colours, averaged per voxel.
    mask : (n,) bool, optional
        Points to use; the others get voxel -1.
    origin : (3,) float, optional
        Corner of voxel (0, 0, 0); the minimum corner of the used points by default.
    anchored : bool
        Without ``origin``: lay the grid from the frame's origin (its corner at the
        multiple of ``size`` at or below the minimum corner), so that the same points
        moved by whole voxels, or turned by a quarter about the origin, fall in the same
        voxels (``prepare.frame: canonical``).

    Returns
    -------
    VoxelGrid
        Voxels in increasing key order (x, then y, then z), so the result does
        not depend on the order of the input points.

    Examples
    --------
    >>> g = voxelize([[0.001, 0, 0], [0.003, 0, 0], [0.05, 0, 0]], 0.02)
    >>> g.counts.tolist(), g.point_to_voxel.tolist()
    ([2, 1], [0, 0, 1])
    >>> g.centers[0].tolist()
    [0.002, 0.0, 0.0]
    """
    pts = as_points(points)
    check_param("size", POSITIVE, size)
    n = len(pts)
    use = np.ones(n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if use.shape != (n,):
        raise InvalidParameterError("mask", f"a boolean array of shape ({n},)", use.shape)
    sel = pts if mask is None else pts[use]
    if origin is None:
        org = sel.min(axis=0) if len(sel) else np.zeros(3)
        if anchored:
            org = np.floor(org / size) * size
    else:
        org = np.asarray(origin, dtype=np.float64).reshape(3)
    keys = voxel_keys(sel, size, org)
    point_to_voxel = np.full(n, -1, dtype=np.int64)
    if len(sel) == 0:
        return VoxelGrid(
            float(size),
            org,
            np.zeros((0, 3), np.int64),
            np.zeros((0, 3)),
            None if colors is None else np.zeros((0, 3), np.uint8),
            np.zeros(0, np.int64),
            point_to_voxel,
        )
    low = keys.min(axis=0)
    shifted = keys - low
    if int(shifted.max()) >= KEY_LIMIT:
        raise InvalidParameterError(
            "size",
            f"large enough for at most {KEY_LIMIT} voxels along an axis",
            f"{size} over an extent of {float(np.ptp(sel, axis=0).max()):.4g}",
        )
    packed, bits = _pack(shifted)
    unique, inverse, counts = np.unique(packed, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    m = len(unique)
    centers = np.empty((m, 3))
    for a in range(3):
        centers[:, a] = np.bincount(inverse, weights=sel[:, a], minlength=m)
    centers /= counts[:, None]
    ukeys = _unpack(unique, bits) + low
    mean_colors = None
    if colors is not None:
        col = np.asarray(colors)
        col = col if mask is None else col[use]
        mean_colors = np.empty((m, 3), dtype=np.uint8)
        for a in range(3):
            s = np.bincount(inverse, weights=col[:, a].astype(np.float64), minlength=m)
            mean_colors[:, a] = np.clip(np.rint(s / counts), 0, 255).astype(np.uint8)
    point_to_voxel[use] = inverse
    return VoxelGrid(
        float(size), org, ukeys, centers, mean_colors, counts.astype(np.int64), point_to_voxel
    )
