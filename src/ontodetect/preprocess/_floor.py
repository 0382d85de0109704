"""A floor that is not flat: height map of the floor under a levelled scan.

Reconstructions drift: a SLAM map of a room can have its floor bent by 20 cm from
one corner to the other (measured on real ScanNet rooms), so "height above the
floor" from a single plane puts seats on one side of the room 20 cm lower than on
the other. The map follows the lowest horizontal surface of each tile of the
floor, smoothed and filled, and heights above the floor subtract it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._gravity import CellPlanes

__all__ = ["FloorMap", "floor_height_map"]

#: Horizontal cells: normal within this angle (deg) of vertical.
HORIZONTAL_TOLERANCE = 10.0
#: Within a tile, the floor is the horizontal cells up to this (m) above the lowest ones.
FLOOR_LAYER = 0.06
#: Fewest horizontal cells in a tile for its own floor estimate.
MIN_TILE_CELLS = 3
#: A tile whose floor differs from the median of its 3x3 neighbourhood by more than this
#: (m) takes the median instead.
OUTLIER_STEP = 0.04
#: Low percentile of a tile's horizontal cell heights taken as its lowest (robust to noise).
LOW_PERCENTILE = 5.0


@dataclass(frozen=True)
class FloorMap:
    """Floor height on a grid of square tiles in the levelled frame.

    Attributes
    ----------
    origin : (2,) float
        x, y of the centre of tile (0, 0).
    tile : float
        Tile edge (m).
    heights : (nx, ny) float
        Floor height at each tile centre.
    """

    origin: NDArray[np.float64]
    tile: float
    heights: NDArray[np.float64]

    def height(self, xy: ArrayLike) -> NDArray[np.float64]:
        """(k,) floor height under points ``xy`` (k, 2), bilinear between tile centres.

        Examples
        --------
        >>> import numpy as np
        >>> m = FloorMap(np.zeros(2), 1.0, np.array([[0.0, 0.0], [0.2, 0.2]]))
        >>> m.height([[0.5, 0.3], [5.0, 0.0]]).round(3).tolist()
        [0.1, 0.2]
        """
        from scipy import ndimage  # heavy: imported when used (start-up)

        p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        coords = ((p - self.origin) / self.tile).T
        return ndimage.map_coordinates(self.heights, coords, order=1, mode="nearest")

    @property
    def warp(self) -> float:
        """Largest minus smallest floor height (m)."""
        return float(np.ptp(self.heights)) if self.heights.size else 0.0

    def to_dict(self) -> dict:
        return {
            "origin": self.origin.tolist(),
            "tile": self.tile,
            "heights": np.round(self.heights, 4).tolist(),
        }


def floor_height_map(
    cells: CellPlanes, *, tile: float = 0.5, max_warp: float = 0.3, anchored: bool = False
) -> FloorMap:
    """Estimate the floor height under every tile of a levelled scene.

    Parameters
    ----------
    cells : CellPlanes
        Plane fits of the levelled scene (floor near z = 0).
    tile : float
        Tile edge (m).
    max_warp : float
        Only horizontal surfaces within this height (m) of z = 0 can be floor.

    Returns
    -------
    FloorMap
        Tiles without floor of their own take the value of the nearest tile with
        one; a tile that disagrees with the median of its 3x3 neighbours takes
        that median (a low platform taken for floor).

    Examples
    --------
    >>> import numpy as np
    >>> from ontodetect.preprocess import cell_planes
    >>> xy = np.random.default_rng(0).random((20000, 2)) * 4
    >>> fm = floor_height_map(cell_planes(np.c_[xy, 0.05 * xy[:, 0]], 0.1), tile=0.5)
    >>> round(float(fm.height([[3.0, 2.0]])[0]), 2)
    0.15
    """
    from scipy import ndimage  # heavy: imported when used (start-up)

    ok = cells.planar & (np.abs(cells.normals[:, 2]) > np.cos(np.radians(HORIZONTAL_TOLERANCE)))
    ok &= np.abs(cells.centers[:, 2]) <= max_warp
    ctr = cells.centers
    lo = ctr[:, :2].min(axis=0) if len(ctr) else np.zeros(2)
    if anchored:  # tiles laid from the frame's origin (prepare.frame: canonical)
        lo = np.floor(lo / tile) * tile
    hi = ctr[:, :2].max(axis=0) if len(ctr) else np.zeros(2)
    shape = tuple(int(v) for v in np.floor((hi - lo) / tile).astype(np.int64) + 1)
    origin = lo + tile / 2
    heights = np.full(shape, np.nan)
    if ok.sum() >= MIN_TILE_CELLS:
        t = np.floor((ctr[ok, :2] - lo) / tile).astype(np.int64)
        flat = t[:, 0] * shape[1] + t[:, 1]
        z = ctr[ok, 2]
        order = np.lexsort((z, flat))
        flat, z = flat[order], z[order]
        starts = np.flatnonzero(np.r_[True, np.diff(flat) > 0])
        ends = np.r_[starts[1:], len(flat)]
        for s, e in zip(starts, ends, strict=True):
            if e - s < MIN_TILE_CELLS:
                continue
            zz = z[s:e]
            low = np.percentile(zz, LOW_PERCENTILE)
            heights.flat[flat[s]] = float(np.median(zz[zz <= low + FLOOR_LAYER]))
    known = np.isfinite(heights)
    if not known.any():
        return FloorMap(origin, float(tile), np.zeros(shape))
    # Median over 3x3 tiles of the known values, then nearest known value for the rest.
    padded = np.pad(heights, 1, constant_values=np.nan)
    stack = np.stack(
        [padded[i : i + shape[0], j : j + shape[1]] for i in range(3) for j in range(3)]
    )
    counts = np.isfinite(stack).sum(axis=0)
    with np.errstate(all="ignore"):
        med = np.where(counts > 0, np.nanmedian(np.where(counts > 0, stack, 0.0), axis=0), np.nan)
    # Keep a tile's own value unless it disagrees with its neighbours (a low platform):
    # the median alone would flatten a floor that bends towards the walls.
    med = np.where(known & (np.abs(heights - med) > OUTLIER_STEP), med, heights)
    _, idx = ndimage.distance_transform_edt(~np.isfinite(med), return_indices=True)
    filled = med[tuple(idx)]
    return FloorMap(origin, float(tile), filled)
