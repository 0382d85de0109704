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
#: Walls rise above furniture: their top must be at least this high (m), or, with
#: ``low_scan_walls``, reach to within a cell of the scan's top where the scan stops lower
#: (a sensor that sees a small room only to 1.4 m sees its walls that far and no farther).
MIN_WALL_TOP = 1.5
#: The scan's top: this quantile of the voxels' heights (a shower head or a shelf seen
#: higher than the rest does not raise it).
SCAN_TOP = 0.99
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
    min_top: float = MIN_WALL_TOP,
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
            min_top=min_top,
        )
    return walls


def _wall_segments(ctr, nrm, sample, cell, *, min_length, min_height, band, min_top):
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
        tall = tall_ok and height >= min_height and zz.max() + cell / 2 >= min_top
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


# -- the room shell where no wall plane shows: glazed and curtained walls ----------------
#: Columns (m, a square of the horizontal grid) in which tall surfaces are sought: about
#: one fold of a curtain (folds every 12-20 cm) and the width of a glazing mullion.
SHELL_COLUMN = 0.1
#: Height bins (m) of a column.
SHELL_BIN = 0.1
#: A tall surface starts near the floor: below the lowest seat (Table 4.1: seats from 35 cm),
#: so that what it is cannot be furniture seen above a seat; floor-length curtains end 1-2 cm
#: above the floor and glazing frames 5-10 cm.
SHELL_FOOT = 0.3
#: ... and reaches this height (m). Glazing and curtains rise to door-head height (doors of
#: 2.0-2.1 m, e.g. DIN 18101's 2.01 m; curtain rails hang above the window head), but a scan
#: made with a hand-held camera often stops lower (the tops of ScanNet walls at 1.6-1.8 m in
#: some rooms; simulated scans see curtains up to 1.5-1.8 m). So the test is the altitude
#: cut-off of Table 4.1 (1.4 m: no seat or table is higher) and one bin: what reaches from
#: below a seat to above it is no object looked for (high-backed chairs stop at 1.3 m).
SHELL_HEAD = 1.5
#: Share of the height bins from the foot to the head that must hold points: gaps are allowed
#: (what stands in front of a curtain hides part of it; glass returns almost nothing).
SHELL_FILL = 0.5
#: Columns within this distance (m) of a line belong to it: curtain folds are 3-10 cm deep.
SHELL_BAND = 0.1
#: Thickness (m) of the slices across a wall in which its tall surface is traced: a few
#: voxels.
SHELL_SLICE = 0.05
#: Largest gap (m) between tall columns along one wall: a glazing pane between two mullions
#: (curtain-wall modules and panes are 1.2-1.8 m wide) or a window between two curtains.
SHELL_GAP = 2.0
#: Fewest tall columns, and shortest run (m), of a glazed or curtained wall: one curtain
#: gathered at the side of a window is 0.3-0.6 m wide.
SHELL_MIN_COLUMNS = 3
SHELL_MIN_LENGTH = 0.3
#: At the room's boundary: no more than MAX_BEHIND_WALL of the scene within the run's span
#: lies farther than this (m) behind it. Curtain rails stand 5-15 cm off the wall and folds
#: add up to 10 cm; a wall behind a curtain is nearer than this.
SHELL_DEPTH = 0.3
#: Between tall columns, voxels up to this height (m) on the line are wall too: the bottom
#: frame of glazing and skirting boards (6-15 cm), which would join everything along it.
SHELL_SKIRT = 0.15


def _tall(keys: NDArray[np.int64], z: NDArray[np.float64]) -> tuple:
    """Which cells hold a tall surface: (cell of every point, cell keys, tall per cell).
    ``keys`` (n, 2) int are the points' cells, ``z`` (n,) their heights."""
    cells, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    nbins = round(SHELL_HEAD / SHELL_BIN)
    zb = np.floor(z / SHELL_BIN).astype(np.int64)
    low = np.zeros(len(cells), dtype=bool)
    high = np.zeros(len(cells), dtype=bool)
    low[inverse[z < SHELL_FOOT]] = True
    high[inverse[z >= SHELL_HEAD]] = True
    inside = (zb >= 0) & (zb < nbins)
    occupied = np.zeros((len(cells), nbins), dtype=bool)
    occupied[inverse[inside], zb[inside]] = True
    return inverse, cells, low & high & (occupied.mean(axis=1) >= SHELL_FILL)


def _tall_columns(c: NDArray[np.float64], free: NDArray[np.bool_]) -> tuple:
    """Columns of the horizontal grid holding a tall surface: (column of every voxel, -1
    when not free; ids of the tall columns; their centres (k, 2))."""
    idx = np.flatnonzero(free & (c[:, 2] >= 0.0))
    col = np.full(len(c), -1, dtype=np.int64)
    if len(idx) == 0:
        return col, np.zeros(0, dtype=np.int64), np.zeros((0, 2))
    keys = np.floor(c[idx, :2] / SHELL_COLUMN).astype(np.int64)
    inverse, cells, tall = _tall(keys, c[idx, 2])
    col[idx] = inverse
    ids = np.flatnonzero(tall)
    return col, ids, (cells[ids] + 0.5) * SHELL_COLUMN


def _shell_walls(
    c: NDArray[np.float64], labels: NDArray[np.int8], sample: NDArray[np.float64]
) -> list[StructurePlane]:
    """Glazed and curtained walls: tall surfaces (from near the floor to door-head height,
    gaps allowed) in lines at the room's boundary. Their voxels, and those of the glazing's
    bottom frame between them, are labelled wall in ``labels`` (modified)."""
    from scipy import ndimage  # heavy: imported when used (start-up)

    _, ids, xy = _tall_columns(c, labels == NONE)
    planes: list[StructurePlane] = []
    if len(ids) < SHELL_MIN_COLUMNS:
        return planes
    az = np.radians(np.arange(0.0, 180.0, AZIMUTH_BIN))
    dirs = np.stack([np.cos(az), np.sin(az)], axis=1)
    centre = xy.mean(axis=0)
    rho = (xy - centre) @ dirs.T  # (k, azimuths)
    r_lo = float(rho.min())
    r_bins = int(np.ceil((float(rho.max()) - r_lo) / SHELL_COLUMN)) + 1
    free = np.ones(len(ids), dtype=bool)
    for _ in range(MAX_WALLS):
        if free.sum() < SHELL_MIN_COLUMNS:
            break
        ri = ((rho[free] - r_lo) / SHELL_COLUMN).astype(np.int64)
        hist = np.zeros((len(az), r_bins))
        np.add.at(hist, (np.broadcast_to(np.arange(len(az)), ri.shape), ri), 1.0)
        smooth = ndimage.convolve1d(hist, np.ones(2), axis=1, mode="constant")
        a, r = np.unravel_index(int(np.argmax(smooth)), smooth.shape)
        if smooth[a, r] < SHELL_MIN_COLUMNS:
            break
        on_line = free & (np.abs(rho[:, a] - (r_lo + r * SHELL_COLUMN)) <= SHELL_BAND)
        if on_line.sum() < SHELL_MIN_COLUMNS:
            break
        free &= ~on_line
        planes += _shell_runs(c, labels, xy[on_line], dirs[a], sample)
    return planes


def _shell_runs(c, labels, xy, n2, sample) -> list[StructurePlane]:
    """Runs of the tall columns at ``xy`` (k, 2) on one line split at gaps; those at the room's
    boundary become walls."""
    along = np.array([-n2[1], n2[0]])
    t = xy @ along
    order = np.argsort(t)
    out = []
    for run in np.split(order, np.flatnonzero(np.diff(t[order]) > SHELL_GAP) + 1):
        tt = np.sort(t[run])
        t0, t1 = tt[0] - SHELL_COLUMN / 2, tt[-1] + SHELL_COLUMN / 2
        if len(run) < SHELL_MIN_COLUMNS or t1 - t0 < SHELL_MIN_LENGTH:
            continue
        n = np.array([n2[0], n2[1], 0.0])
        t_dir = np.array([along[0], along[1], 0.0])
        off = float(np.median(xy[run] @ n2))
        ts = sample @ t_dir
        span = (ts >= t0) & (ts <= t1)
        d = sample[span] @ n - off
        if np.count_nonzero(d > 0) < np.count_nonzero(d < 0):
            n, off, d = -n, -off, -d
            t_dir = -t_dir
            t0, t1, tt = -t1, -t0, np.sort(-tt)
        if np.count_nonzero(d < -SHELL_DEPTH) > MAX_BEHIND_WALL * max(len(d), 1):
            continue
        # The tall surface itself, traced on cells thin across the line (a chair's back a
        # few centimetres in front of a curtain is no part of it), and low voxels between
        # the surface and the boundary behind it along the whole run (the glazing's bottom
        # frame, skirting), which would join everything standing along it.
        tv = c @ t_dir
        dv = c @ n - off
        cand = np.flatnonzero(
            (labels == NONE)
            & (tv >= t0)
            & (tv <= t1)
            & (dv >= -SHELL_DEPTH)
            & (dv <= SHELL_BAND + SHELL_COLUMN / 2)
            & (c[:, 2] >= 0.0)
        )
        keys = np.stack(
            [np.floor(tv[cand] / SHELL_COLUMN), np.floor(dv[cand] / SHELL_SLICE)], axis=1
        ).astype(np.int64)
        inverse, _, tall = _tall(keys, c[cand, 2])
        on = tall[inverse]
        front = float(dv[cand[on]].max()) if on.any() else 0.0
        take = cand[on | ((c[cand, 2] <= SHELL_SKIRT) & (dv[cand] <= front))]
        if not on.any():
            continue
        labels[take] = WALL
        p = c[take]
        ext = np.stack([p.min(0), p.max(0)])
        area = float(len(run)) * SHELL_COLUMN * SHELL_HEAD
        out.append(StructurePlane("wall", n, off, ext, area))
    return out


def _xy_cells(
    xy: NDArray[np.float64], cell: float, margin: int
) -> tuple[NDArray[np.int64], tuple[int, int]]:
    """Cells of a horizontal grid of edge ``cell`` laid from the frame's origin, numbered
    so that ``margin`` empty cells border them: the cell of every point (n, 2) and the
    shape of the grid."""
    ij = np.floor(xy / cell).astype(np.int64)
    ij -= ij.min(axis=0) - margin
    return ij, (int(ij[:, 0].max()) + margin + 1, int(ij[:, 1].max()) + margin + 1)


# -- a drifted second floor layer ---------------------------------------------------------
#: A horizontal sheet at most this high (m) above the floor is floor: a SLAM map that closed
#: a loop late keeps a copy of part of the floor 2-10 cm above or below it. Nothing looked
#: for has a horizontal surface that low (seats from 35 cm, Table 4.1; the lowest coffee
#: tables about 30 cm), and a step up is at most a stair's riser (0.19-0.2 m in building
#: codes, e.g. DIN 18065): a surface that low is walked on.
FLOOR_LAYER_TOP = 0.15
#: Largest height spread (m) of a sheet within one cell: a tilted copy (up to 1-2 degrees)
#: and sensor noise, not the side of an object.
FLOOR_LAYER_THICKNESS = 0.04
#: Cells (m) of the grid the sheet is traced on.
FLOOR_LAYER_CELL = 0.1


def _floor_layers(
    c: NDArray[np.float64], labels: NDArray[np.int8], *, band: float, min_area: float
) -> float:
    """Label as floor the voxels of large thin horizontal sheets just above the floor (a
    drifted copy of it); ``labels`` is modified. Returns the sheets' area (m²)."""
    from scipy import ndimage  # heavy: imported when used (start-up)

    z = c[:, 2]
    idx = np.flatnonzero((labels == NONE) & (z >= band) & (z <= FLOOR_LAYER_TOP))
    if len(idx) == 0:
        return 0.0
    ij, shape = _xy_cells(c[idx, :2], FLOOR_LAYER_CELL, 1)
    flat = np.ravel_multi_index((ij[:, 0], ij[:, 1]), shape)
    size = shape[0] * shape[1]
    zi = z[idx]
    lo = np.full(size, np.inf)
    hi = np.full(size, -np.inf)
    np.minimum.at(lo, flat, zi)
    np.maximum.at(hi, flat, zi)
    total = np.bincount(flat, weights=zi, minlength=size)
    count = np.bincount(flat, minlength=size)
    sheet = ((count > 0) & (hi - lo <= FLOOR_LAYER_THICKNESS)).reshape(shape)
    # A sheet is large in every direction: the lower edge of a sofa's side or a plinth
    # makes a strip one or two cells wide, which opening removes.
    square = np.ones((3, 3), dtype=bool)
    sheet = ndimage.binary_opening(sheet, square)
    comp, k = ndimage.label(sheet, square)
    if k == 0:
        return 0.0
    area = np.bincount(comp.ravel(), minlength=k + 1) * FLOOR_LAYER_CELL**2
    keep = area >= min_area
    keep[0] = False
    layer = keep[comp]
    if not layer.any():
        return 0.0
    with np.errstate(invalid="ignore", divide="ignore"):
        height = np.where(layer.ravel(), total / np.maximum(count, 1), np.nan).reshape(shape)
    # Cells beside the sheet (a chair leg stands on it) take the nearest sheet height and
    # give up only their voxels on it.
    _, near = ndimage.distance_transform_edt(~layer, return_indices=True)
    height = height[tuple(near)]
    reach = ndimage.binary_dilation(layer, square).ravel()
    on = reach[flat] & (np.abs(zi - height.ravel()[flat]) <= FLOOR_LAYER_THICKNESS / 2)
    on |= layer.ravel()[flat]
    labels[idx[on]] = FLOOR
    return float(area[keep].sum())


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
    shell_walls: bool = False,
    floor_layers: bool = True,
    low_scan_walls: bool = False,
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
    shell_walls : bool
        Also find glazed and curtained walls: tall surfaces from near the floor to door-head
        height and more, gaps allowed, in lines at the room's boundary.
    floor_layers : bool
        Also take as floor large thin horizontal sheets just above it (a drifted copy of
        the floor in a SLAM map).
    low_scan_walls : bool
        In a scan that stops lower than a wall's least top (its ``SCAN_TOP`` height
        quantile below ``MIN_WALL_TOP`` and a cell), a wall need only reach to within a
        cell of the scan's top, and be as tall as it can be from near the floor.

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
    if floor_layers:
        _floor_layers(c, labels, band=floor_band, min_area=min_floor_area)
    sample = c[:: max(1, len(c) // 100_000)]
    # With low_scan_walls, where the scan stops lower than a wall's least top, a wall
    # reaches to the scan's top and is as tall as it can be from near the floor.
    min_top = MIN_WALL_TOP
    if low_scan_walls:
        min_top = min(min_top, float(np.quantile(c[:, 2], SCAN_TOP)) - cells.cell)
    walls = _walls(
        cells,
        sample,
        min_length=min_wall_length,
        min_height=min(min_wall_height, min_top - cells.cell),
        band=wall_band,
        min_top=min_top,
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
    if shell_walls:
        planes += _shell_walls(c, labels, sample)
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
    ij, shape = _xy_cells(pts, cell, AREA_CLOSING + 1)
    grid = np.zeros(shape, dtype=bool)
    grid[ij[:, 0], ij[:, 1]] = True
    grid = ndimage.binary_closing(grid, np.ones((3, 3), dtype=bool), iterations=AREA_CLOSING)
    grid = ndimage.binary_fill_holes(grid)
    return float(np.count_nonzero(grid)) * cell * cell
