"""Structural planes of a levelled room: floor, walls and ceiling.

They are kept apart from object clustering (a chair against a wall must not merge
with it) but stay available to later stages, for relations such as "against a
wall". The input is in the levelled frame: z up, floor at z = 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._gravity import CellPlanes, window_sum

__all__ = ["STRUCTURE_LABELS", "StructurePlane", "find_structure", "floor_area"]

#: Label of each voxel in ``PreparedScene.structure_label``.
STRUCTURE_LABELS = {0: "none", 1: "floor", 2: "wall", 3: "ceiling"}
NONE, FLOOR, WALL, CEILING = 0, 1, 2, 3

#: Cells whose normal is within this angle (deg) of horizontal are vertical planes.
VERTICAL_TOLERANCE = 10.0
#: Cells whose normal is within this angle (deg) of vertical are horizontal planes.
HORIZONTAL_TOLERANCE = 6.0
#: Wall search: histogram bins of azimuth (deg) and offset (m).
AZIMUTH_BIN = 2.0
OFFSET_BIN = 0.05
#: Bin width (m) of the height histogram of ceiling cells.
CEILING_BIN = 0.04
#: Azimuth bins on each side of the 0/180 degree cut that vote twice.
WRAP_BINS = 3
#: Cells within these of a wall candidate belong to it.
AZIMUTH_TOLERANCE = 5.0
#: A wall is split where its cells leave a gap longer than this (m) (doors are narrower
#: than this only when closed: an open door leaves a hole the wall must not bridge).
WALL_GAP = 0.6
#: Share of the scene allowed behind a wall (through open doors and windows).
MAX_BEHIND_WALL = 0.1
#: Walls rise above furniture: their top must be at least this high (m).
MIN_WALL_TOP = 1.5
#: A wall seen only up to furniture height (scans that stop at 1 m) must be at least this
#: tall (m) and have at most this share of the scene behind it.
LOW_WALL_HEIGHT = 0.6
LOW_WALL_MAX_BEHIND = 0.005
#: At most this many walls are looked for.
MAX_WALLS = 24
#: Voxels beyond a wall's ends by up to this (m) still belong to it.
WALL_END_MARGIN = 0.05


@dataclass(frozen=True)
class StructurePlane:
    """A floor, wall or ceiling plane in the levelled frame: ``normal · x = offset``.

    Attributes
    ----------
    kind : str
        "floor", "wall" or "ceiling".
    normal : (3,) float
        Unit normal; walls point into the room, floor up, ceiling down.
    offset : float
    extent : (2, 3) float
        Box of the cells that support the plane (min and max corner).
    area : float
        Supporting surface (m²), from the cells.
    """

    kind: str
    normal: NDArray[np.float64]
    offset: float
    extent: NDArray[np.float64]
    area: float

    def distance(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """(n,) signed distance of points to the plane (positive on the room side)."""
        return np.asarray(points, dtype=np.float64) @ self.normal - self.offset

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "normal": [float(v) for v in self.normal],
            "offset": float(self.offset),
            "extent": self.extent.tolist(),
            "area": float(self.area),
        }


def _levels(heights: NDArray[np.float64], cell: float, bin_width: float) -> tuple:
    lo = float(heights.min())
    nb = int(np.ceil((float(heights.max()) - lo) / bin_width)) + 1
    b = np.minimum(((heights - lo) / bin_width).astype(np.int64), nb - 1)
    area = window_sum(np.bincount(b, minlength=nb) * cell**2, 1)
    return lo, b, area


def _ceiling(cells: CellPlanes, min_height: float, min_area: float) -> StructurePlane | None:
    nrm, ctr = cells.normals[cells.planar], cells.centers[cells.planar]
    horiz = np.abs(nrm[:, 2]) > np.cos(np.radians(HORIZONTAL_TOLERANCE))
    high = horiz & (ctr[:, 2] > min_height)
    if not high.any():
        return None
    h = ctr[high, 2]
    _, b, area = _levels(h, cells.cell, CEILING_BIN)
    good = np.flatnonzero(area >= min_area)
    if len(good) == 0:
        return None
    top = good[-1]
    sel = np.abs(b - top) <= 1
    level = float(np.median(h[sel]))
    pts = ctr[high][sel]
    ext = np.stack([pts.min(0), pts.max(0)])
    return StructurePlane("ceiling", np.array([0.0, 0.0, -1.0]), -level, ext, float(area[top]))


def _walls(
    cells: CellPlanes,
    sample: NDArray[np.float64],
    *,
    min_length: float,
    min_height: float,
    band: float,
) -> list[StructurePlane]:
    from scipy import ndimage  # heavy: imported when used (start-up)

    nrm, ctr = cells.normals[cells.planar], cells.centers[cells.planar]
    vert = np.abs(nrm[:, 2]) < np.sin(np.radians(VERTICAL_TOLERANCE))
    nrm, ctr = nrm[vert], ctr[vert]
    if len(nrm) == 0:
        return []
    # Azimuth in [0, 180): a wall and its back face share a bin.
    az = np.degrees(np.arctan2(nrm[:, 1], nrm[:, 0])) % 180.0
    rad = np.radians(az)
    n2 = np.stack([np.cos(rad), np.sin(rad)], axis=1)
    # Offsets from the middle of the cells, not from the origin of the input frame: a
    # cell's normal is a degree or two off its wall's, which moves its offset in
    # proportion to its distance from the reference point.
    xy = ctr[:, :2] - ctr[:, :2].mean(axis=0)
    off = (xy * n2).sum(axis=1)
    free = np.ones(len(nrm), dtype=bool)
    walls: list[StructurePlane] = []
    # Azimuth wraps at 0/180 degrees, where a wall's offset changes sign: cells near the
    # cut vote a second time on the other side, so that no wall is split in two.
    wrap = AZIMUTH_BIN * WRAP_BINS
    low_side, high_side = az < wrap, az > 180.0 - wrap
    vote_cell = np.concatenate(
        [np.arange(len(az)), np.flatnonzero(low_side), np.flatnonzero(high_side)]
    )
    vote_az = np.concatenate([az, az[low_side] + 180.0, az[high_side] - 180.0]) + wrap
    vote_off = np.concatenate([off, -off[low_side], -off[high_side]])
    a_bins = int(np.ceil((180.0 + 2 * wrap) / AZIMUTH_BIN))
    o_lo = float(vote_off.min())
    o_bins = int(np.ceil((float(vote_off.max()) - o_lo) / OFFSET_BIN)) + 1
    min_cells = max(3, int(min_length * min_height / cells.cell**2 * 0.25))
    for _ in range(MAX_WALLS * 3):
        if len(walls) >= MAX_WALLS or free.sum() < min_cells:
            break
        use = free[vote_cell]
        ai = np.minimum((vote_az[use] / AZIMUTH_BIN).astype(np.int64), a_bins - 1)
        oi = ((vote_off[use] - o_lo) / OFFSET_BIN).astype(np.int64)
        hist = np.zeros((a_bins, o_bins))
        np.add.at(hist, (ai, oi), 1.0)
        # Neighbouring bins share the votes of one wall.
        smooth = ndimage.convolve(hist, np.ones((3, 3)), mode="constant")
        best = np.unravel_index(int(np.argmax(smooth)), smooth.shape)
        if smooth[best] < min_cells:
            break
        a0 = (best[0] + 0.5) * AZIMUTH_BIN - wrap
        o0 = o_lo + (best[1] + 0.5) * OFFSET_BIN
        if not 0.0 <= a0 < 180.0:
            a0, o0 = a0 % 180.0, -o0
        daz = np.abs((az - a0 + 90.0) % 180.0 - 90.0)
        # Offsets of cells on the other side of the 0/180 cut have the other sign.
        flip = np.abs(az - a0) > 90.0
        o_adj = np.where(flip, -off, off)
        member = free & (daz < AZIMUTH_TOLERANCE) & (np.abs(o_adj - o0) < OFFSET_BIN * 1.5)
        if member.sum() < 3:
            break  # the peak was made of cells already taken: nothing left to find
        free &= ~member
        walls += _wall_segments(
            ctr[member],
            nrm[member],
            sample,
            cells.cell,
            min_length=min_length,
            min_height=min_height,
            band=band,
        )
    return walls


def _wall_segments(ctr, nrm, sample, cell, *, min_length, min_height, band):
    sign = np.sign(nrm @ nrm[0])
    n = (nrm * sign[:, None]).mean(axis=0)
    n[2] = 0.0
    n /= np.linalg.norm(n)
    offset = float(np.median(ctr @ n))
    # Point the normal into the room: most of the scene lies in front of a wall.
    in_front = np.mean(sample @ n - offset > 0)
    if in_front < 0.5:
        n, offset, in_front = -n, -offset, 1.0 - in_front
    dist = sample @ n - offset
    on_plane = np.mean(np.abs(dist) <= band)
    tall_ok = 1.0 - in_front <= MAX_BEHIND_WALL + on_plane
    t_dir = np.array([-n[1], n[0], 0.0])
    t = ctr @ t_dir
    t_sample = sample @ t_dir
    order = np.argsort(t)
    ts = t[order]
    cuts = np.flatnonzero(np.diff(ts) > WALL_GAP) + 1
    out = []
    for seg in np.split(order, cuts):
        tt = t[seg]
        zz = ctr[seg, 2]
        length = float(tt.max() - tt.min()) + cell
        height = float(zz.max() - zz.min()) + cell
        if length < min_length:
            continue
        tall = tall_ok and height >= min_height and zz.max() + cell / 2 >= MIN_WALL_TOP
        if not tall:
            # A wall scanned only part of the way up: nothing may lie behind it, or it
            # is the back of a sofa or a cabinet standing against the real wall.
            span = (t_sample >= tt.min() - cell) & (t_sample <= tt.max() + cell)
            behind = np.count_nonzero(span & (dist < -band)) / max(len(sample), 1)
            if height < LOW_WALL_HEIGHT or behind > LOW_WALL_MAX_BEHIND:
                continue
        pts = ctr[seg]
        ext = np.stack([pts.min(0) - cell / 2, pts.max(0) + cell / 2])
        out.append(StructurePlane("wall", n.copy(), offset, ext, float(len(seg)) * cell**2))
    return out


def find_structure(
    centers: NDArray[np.float64],
    cells: CellPlanes,
    *,
    floor_band: float = 0.03,
    ceiling_above: float = 1.4,
    min_floor_area: float = 0.5,
    min_wall_length: float = 1.0,
    min_wall_height: float = 1.2,
    wall_band: float = 0.04,
    floor_area: float = 0.0,
) -> tuple[NDArray[np.int8], list[StructurePlane]]:
    """Label voxels as floor, wall, ceiling or none in a levelled scene.

    Parameters
    ----------
    centers : (m, 3) float
        Voxel centres, levelled (z up, floor at 0).
    cells : CellPlanes
        Coarse plane fits of the same scene (see ``cell_planes``).
    floor_band : float
        Voxels lower than this (m) are floor.
    ceiling_above : float
        Ceilings are sought above this height (m).
    min_floor_area : float
        Smallest ceiling surface (m²).
    min_wall_length, min_wall_height : float
        Smallest wall (m).
    wall_band : float
        Voxels within this distance (m) of a wall are wall.
    floor_area : float
        Floor surface found when levelling (m²), recorded on the floor plane.

    Returns
    -------
    labels : (m,) int8
        0 none, 1 floor, 2 wall, 3 ceiling (see ``STRUCTURE_LABELS``).
    planes : list of StructurePlane
        The floor first, then the walls, then the ceiling if found.
    """
    c = np.asarray(centers, dtype=np.float64)
    labels = np.zeros(len(c), dtype=np.int8)
    lo = c.min(axis=0) if len(c) else np.zeros(3)
    hi = c.max(axis=0) if len(c) else np.zeros(3)
    floor_ext = np.array([[lo[0], lo[1], 0.0], [hi[0], hi[1], 0.0]])
    is_floor = c[:, 2] < floor_band
    planes = [StructurePlane("floor", np.array([0.0, 0.0, 1.0]), 0.0, floor_ext, float(floor_area))]
    labels[is_floor] = FLOOR
    if len(c) == 0:
        return labels, planes
    sample = c[:: max(1, len(c) // 100_000)]
    walls = _walls(
        cells, sample, min_length=min_wall_length, min_height=min_wall_height, band=wall_band
    )
    # Cells at corners and along the floor hold two planes and are not planar: a wall's
    # cells stop about one cell short of its true ends.
    margin = WALL_END_MARGIN + cells.cell
    for w in walls:
        near = np.flatnonzero((np.abs(w.distance(c)) <= wall_band) & (labels == NONE))
        p = c[near]
        inside = np.all((p >= w.extent[0] - margin) & (p <= w.extent[1] + margin), axis=1)
        labels[near[inside]] = WALL
    planes += walls
    ceiling = _ceiling(cells, ceiling_above, min_floor_area)
    if ceiling is not None:
        labels[(c[:, 2] > -ceiling.offset - floor_band) & (labels == NONE)] = CEILING
        planes.append(ceiling)
    return labels, planes


#: Floor area of a scan: its footprint on a grid of this cell (m), ...
AREA_CELL = 0.1
#: ... of its points from the floor up to this height (m): floor, furniture and walls below
#: the height where a room's walls may lean or its ceiling fittings hang.
AREA_TOP = 2.0
#: Cells of closing: gaps up to twice this many cells (a chair's shadow on the floor, a
#: hole in the scan) count as floor.
AREA_CLOSING = 2


def floor_area(
    centers: NDArray[np.float64], *, cell: float = AREA_CELL, top: float = AREA_TOP
) -> float:
    """Area (m²) of the floor a levelled scan covers: the cells of a horizontal grid that
    its points between the floor and ``top`` fall in, with small gaps closed and holes
    filled (floor hidden under furniture counts).

    >>> xy = np.mgrid[0:3:0.05, 0:2:0.05].reshape(2, -1).T
    >>> floor = np.c_[xy, np.zeros(len(xy))]
    >>> round(floor_area(floor), 1)
    6.0
    """
    from scipy import ndimage  # lazy: only the room prior measures the floor

    z = centers[:, 2]
    pts = centers[(z > -cell) & (z < top), :2]
    if len(pts) == 0:
        return 0.0
    ij = np.floor(pts / cell).astype(np.int64)
    ij -= ij.min(axis=0) - (AREA_CLOSING + 1)
    grid = np.zeros(tuple(ij.max(axis=0) + AREA_CLOSING + 2), dtype=bool)
    grid[ij[:, 0], ij[:, 1]] = True
    grid = ndimage.binary_closing(grid, np.ones((3, 3), dtype=bool), iterations=AREA_CLOSING)
    grid = ndimage.binary_fill_holes(grid)
    return float(np.count_nonzero(grid)) * cell * cell
