"""Which way is up: the one heuristic that ``detect --up auto`` (preparation) and
``ontodetect info`` share.

Indoors, gravity shows in the geometry: the floor, the ceiling and the tops of tables and
seats are perpendicular to it and walls are parallel to it. Planes fitted on a coarse grid
give a Manhattan frame, and of its six signed axes the one that puts a floor at the bottom
of the scan and furniture tops above it is up (:func:`estimate_up`); the cloud's kind gives
the hint (:func:`up_hint`: ``-y`` for a camera frame, ``z`` otherwise). Which axis a run
uses when none is given is :func:`default_up`: ``auto`` for an organized or single-view
cloud, ``z`` for anything else. NumPy alone, below the configuration and the preparation
stage, so that ``info`` starts quickly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._units import estimate_spacing, guess_units
from .cloud import PointCloud, pixel_grid, point_cloud, sensor_position
from .errors import InvalidParameterError
from .geometry import unit_direction

__all__ = [
    "AUTO_FRAME",
    "AXES",
    "CAMERA_MAX_TILT",
    "CELL_PER_SPACING",
    "CellPlanes",
    "UpGuess",
    "as_direction",
    "cell_index",
    "cell_planes",
    "default_up",
    "estimate_up",
    "grouped_covariance",
    "guess_up",
    "inferred_view",
    "is_single_view",
    "looks_like_one_view",
    "manhattan_axes",
    "surface_spacing",
    "up_hint",
    "view_grid",
    "view_up",
]

#: Named up directions accepted by :func:`estimate_up` and ``prepare(up=...)``.
AXES: dict[str, tuple[float, float, float]] = {
    "x": (1.0, 0.0, 0.0),
    "-x": (-1.0, 0.0, 0.0),
    "y": (0.0, 1.0, 0.0),
    "-y": (0.0, -1.0, 0.0),
    "z": (0.0, 0.0, 1.0),
    "-z": (0.0, 0.0, -1.0),
}
#: A cell is planar when its smallest eigenvalue is below this share of the eigenvalue sum.
PLANAR_RATIO = 0.05
#: Fewest points in a cell for its plane fit to count.
MIN_CELL_POINTS = 5
#: Normals within this angle (deg) of a direction support it.
AXIS_TOLERANCE = 10.0
#: At most this many cell normals are tried as candidate directions, each counted against
#: at most ``SUPPORT_SAMPLE`` normals.
MAX_CANDIDATES = 500
SUPPORT_SAMPLE = 3000
#: Largest angle (deg) between a camera frame's -y axis and up that ``up="auto"`` considers.
CAMERA_MAX_TILT = 60.0
#: The ``prepare.up`` value (the default) that means ``auto`` for an organized or
#: single-view cloud and ``z`` for any other.
AUTO_FRAME = "auto-frame"
#: Voxel centres sampled to estimate the sampling spacing.
SPACING_SAMPLE = 20_000
#: Cells of the coarse plane fits hold about this many sampling spacings a side, so that
#: sparse scans still get a few points per cell.
CELL_PER_SPACING = 5.0
#: Cell (m) on which the surface per voxel is measured, and how many planar cells that takes.
SURFACE_CELL = 0.2
MIN_SURFACE_CELLS = 20
#: Planar cells this full (percentile of voxel counts) count as completely covered; edge
#: cells of a surface are partly empty.
FULL_CELL_PERCENTILE = 90.0
#: A full cell holds at least this many voxels, or the cells double (up to
#: ``MAX_SURFACE_CELL``): a cell counts as planar from ``MIN_CELL_POINTS`` voxels, so when a
#: full cell holds few more, the emptier full cells drop out of the count and the spacing
#: comes out too small. A Poisson count of mean 16 falls under 5 in one cell of 2,500; of
#: mean 8, in one of ten; of mean 4 (points 10 cm apart), in most. The largest cell is
#: about the size of a room's smaller flat surfaces (a table top, a wall between windows),
#: which must still make whole planar cells.
MIN_FULL_CELL = 16.0
MAX_SURFACE_CELL = 0.8
#: What :func:`guess_up` assumes of preparation when not told (``prepare.voxel_size`` and
#: ``prepare.structure_cell``; tests/test_units.py keeps them equal to the configuration's).
VOXEL_SIZE = 0.02
STRUCTURE_CELL = 0.1
#: Bonus of the given up hint when choosing among the axes of the Manhattan frame.
HINT_WEIGHT = 1.0
#: Heights (m) above a candidate floor where furniture tops and seats are.
FURNITURE_BAND = (0.3, 1.2)


@dataclass(frozen=True)
class CellPlanes:
    """A plane fitted in every occupied cell of a coarse grid.

    Attributes
    ----------
    centers : (g, 3) float
        Mean of the points in each cell.
    normals : (g, 3) float
        Unit normal of each cell's best-fit plane (sign arbitrary).
    counts : (g,) int
        Points per cell.
    planar : (g,) bool
        Cells holding a plane (enough points, flat enough).
    cell : float
        Cell edge.
    """

    centers: NDArray[np.float64]
    normals: NDArray[np.float64]
    counts: NDArray[np.int64]
    planar: NDArray[np.bool_]
    cell: float


def as_direction(up: str | ArrayLike) -> NDArray[np.float64]:
    """A unit vector from an axis name (``"z"``, ``"-y"``...) or a 3-vector."""
    if isinstance(up, str):
        if up not in AXES:
            raise InvalidParameterError("up", "one of " + ", ".join(map(repr, AXES)), up)
        return np.array(AXES[up])
    return unit_direction(up)


def cell_index(
    points: ArrayLike, cell: float, *, anchored: bool = False
) -> tuple[NDArray[np.int64], int]:
    """Cell of every point on a grid of edge ``cell`` from the points' minimum corner (or,
    ``anchored``, from the frame's origin: cells ``[k·cell, (k+1)·cell)``, the same for
    the points moved by whole cells or turned by a quarter about the origin), and the
    number of occupied cells; cells are numbered in increasing (x, y, z) order, as
    :func:`ontodetect.preprocess.voxelize` numbers its voxels.

    Examples
    --------
    >>> groups, n = cell_index([[0.0, 0, 0], [0.05, 0, 0], [0.0, 0.3, 0]], 0.1)
    >>> groups.tolist(), n
    ([0, 0, 1], 2)
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if not cell > 0:
        raise InvalidParameterError("cell", "a number > 0", cell)
    if len(pts) == 0:
        return np.zeros(0, dtype=np.int64), 0
    if anchored:
        keys = np.floor(pts / cell).astype(np.int64)
        keys -= keys.min(axis=0)
    else:
        keys = np.floor((pts - pts.min(axis=0)) / cell).astype(np.int64)
    code = np.ravel_multi_index(keys.T, keys.max(axis=0) + 1)
    _, inverse = np.unique(code, return_inverse=True)
    inverse = inverse.reshape(-1).astype(np.int64)
    return inverse, int(inverse.max()) + 1


def cell_planes(points: ArrayLike, cell: float = 0.1, *, anchored: bool = False) -> CellPlanes:
    """Fit a plane in every cell of a grid of edge ``cell``.

    Examples
    --------
    >>> import numpy as np
    >>> xy = np.random.default_rng(0).random((2000, 2))
    >>> c = cell_planes(np.c_[xy, 0.5 * np.ones(2000)], 0.1)
    >>> bool(c.planar.all()), np.abs(c.normals[:, 2]).min() > 0.99
    (True, np.True_)
    """
    pts = np.asarray(points, dtype=np.float64)
    groups, num = cell_index(pts, cell, anchored=anchored)
    means, cov, counts = grouped_covariance(pts, groups, num)
    evals, evecs = np.linalg.eigh(cov)
    normals = evecs[:, :, 0]
    total = evals.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        flat = evals[:, 0] <= PLANAR_RATIO * total
    planar = (counts >= MIN_CELL_POINTS) & flat & (total > 0)
    return CellPlanes(means, normals, counts.astype(np.int64), planar, float(cell))


def _support(
    normals: NDArray[np.float64], candidates: NDArray[np.float64], tolerance_deg: float
) -> NDArray[np.int64]:
    # Counting on an even thinning of the normals ranks candidates the same way.
    normals = normals[:: max(1, len(normals) // SUPPORT_SAMPLE)]
    cos_tol = np.cos(np.radians(tolerance_deg))
    out = np.zeros(len(candidates), dtype=np.int64)
    step = max(1, 20_000_000 // max(len(normals), 1))  # bound the (candidates, normals) block
    for s in range(0, len(candidates), step):
        out[s : s + step] = (np.abs(candidates[s : s + step] @ normals.T) > cos_tol).sum(axis=1)
    return out


def _refine(
    normals: NDArray[np.float64], axis: NDArray[np.float64], tolerance_deg: float
) -> NDArray[np.float64]:
    """Mean of the normals within the tolerance of ``axis`` (signs aligned), normalised."""
    for _ in range(3):
        d = normals @ axis
        near = np.abs(d) > np.cos(np.radians(tolerance_deg))
        if not near.any():
            break
        mean = (normals[near] * np.sign(d[near])[:, None]).sum(axis=0)
        axis = mean / np.linalg.norm(mean)
    return axis


def _candidates(normals: NDArray[np.float64]) -> NDArray[np.float64]:
    step = max(1, len(normals) // MAX_CANDIDATES)
    return normals[::step]  # deterministic thinning


def manhattan_axes(normals: ArrayLike) -> NDArray[np.float64]:
    """Three orthogonal directions that most plane normals follow (a Manhattan frame).

    Parameters
    ----------
    normals : (g, 3) float
        Unit normals of planar patches.

    Returns
    -------
    (3, 3) float
        Rows are the axes, the best supported first.

    Examples
    --------
    >>> import numpy as np
    >>> n = np.repeat(np.eye(3), [50, 30, 20], axis=0)
    >>> np.abs(manhattan_axes(n)).round(3).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    """
    nrm = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    if len(nrm) == 0:
        return np.eye(3)
    cand = _candidates(nrm)
    a1 = _refine(nrm, cand[int(np.argmax(_support(nrm, cand, AXIS_TOLERANCE)))], AXIS_TOLERANCE)
    perp = np.abs(cand @ a1) < np.sin(np.radians(AXIS_TOLERANCE))
    if perp.any():
        c2 = cand[perp]
        a2 = c2[int(np.argmax(_support(nrm, c2, AXIS_TOLERANCE)))]
    else:
        a2 = np.eye(3)[int(np.argmin(np.abs(a1)))]
    a2 = a2 - (a2 @ a1) * a1
    a2 = _refine(nrm, a2 / np.linalg.norm(a2), AXIS_TOLERANCE)
    a2 = a2 - (a2 @ a1) * a1
    a2 /= np.linalg.norm(a2)
    a3 = np.cross(a1, a2)
    return np.stack([a1, a2, a3])


def _floor_score(
    cells: CellPlanes, heights_all: NDArray[np.float64], up: NDArray[np.float64]
) -> float:
    """How much the geometry looks like a room with ``up`` as its up direction.

    Horizontal area near the lowest large level (the floor) plus horizontal area at
    furniture height above it, in units of cell area; zero when most points would
    lie below the floor.
    """
    nrm = cells.normals[cells.planar]
    ctr = cells.centers[cells.planar]
    horiz = np.abs(nrm @ up) > np.cos(np.radians(AXIS_TOLERANCE))
    if horiz.sum() == 0:
        return 0.0
    h = ctr[horiz] @ up
    lo = float(np.percentile(heights_all, 1.0))
    near_floor = np.abs(h - lo) < 2 * cells.cell
    floor_level = float(np.median(h[near_floor])) if near_floor.any() else lo
    furniture = (h - floor_level > FURNITURE_BAND[0]) & (h - floor_level < FURNITURE_BAND[1])
    median = float(np.median(heights_all))
    top = float(np.percentile(heights_all, 99.0))
    # Furniture stands on the floor: most points are in the lower part of the room.
    lower_half = 1.0 if median - lo <= top - median else 0.5
    return (float(near_floor.sum()) + float(furniture.sum())) * lower_half


def estimate_up(
    points: ArrayLike,
    *,
    hint: str | ArrayLike | None = "z",
    cell: float = 0.1,
    max_angle: float | None = None,
) -> tuple[NDArray[np.float64], float]:
    """Estimate the up direction of an indoor scan from its planes.

    The normals of planar cells give a Manhattan frame (floor/ceiling normal and
    two wall directions). Each of its six signed axes is scored by the horizontal
    area it would put on a floor at the bottom of the scan and at furniture height
    above it; the given ``hint`` (the axis the data's convention suggests: ``z``
    for lidar and most maps, ``-y`` for camera frames) adds a bonus.

    Parameters
    ----------
    points : (n, 3) float
    hint : str or (3,) float or None
        Direction expected to be up.
    cell : float
        Cell edge (m) of the plane fits.
    max_angle : float, optional
        Only axes within this angle (deg) of ``hint`` are considered: a camera
        frame is pitched and rolled, but not upside down.

    Returns
    -------
    up : (3,) float
        Unit vector in the input frame.
    confidence : float
        Share of the best score among the six signed axes (1 = unambiguous).
    """
    pts = np.asarray(points, dtype=np.float64)
    cells = cell_planes(pts, cell)
    if cells.planar.sum() < 3:
        fallback = as_direction(hint if hint is not None else "z")
        return fallback, 0.0
    axes = manhattan_axes(cells.normals[cells.planar])
    hint_vec = None if hint is None else as_direction(hint)
    sample = pts[:: max(1, len(pts) // 200_000)]
    signed = np.concatenate([axes, -axes])
    scores = np.array([_floor_score(cells, sample @ u, u) for u in signed])
    if hint_vec is not None:
        bonus = np.clip(signed @ hint_vec, 0.0, None) ** 2
        scores = scores * (1.0 + HINT_WEIGHT * bonus)
        if max_angle is not None:
            allowed = signed @ hint_vec >= np.cos(np.radians(max_angle))
            if not allowed.any():
                return hint_vec, 0.0
            scores = np.where(allowed, scores, 0.0)
    best = int(np.argmax(scores))
    total = float(scores.sum())
    return signed[best], (float(scores[best]) / total if total > 0 else 0.0)


def grouped_covariance(
    points: NDArray[np.float64], groups: NDArray[np.int64], num_groups: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:
    """Mean and covariance of the points of every group, in one pass of sums.

    Parameters
    ----------
    points : (n, 3) float
    groups : (n,) int
        Group of every point, in ``0..num_groups-1``.
    num_groups : int

    Returns
    -------
    means : (g, 3) float
    covariances : (g, 3, 3) float
    counts : (g,) int
    """
    counts = np.bincount(groups, minlength=num_groups)
    safe = np.maximum(counts, 1)[:, None]
    means = np.stack([np.bincount(groups, points[:, a], num_groups) for a in range(3)], 1)
    means /= safe
    # Centre on the group mean before the products: sums of raw squares lose precision
    # far from the origin.
    d = points - means[groups]
    cov = np.empty((num_groups, 3, 3))
    for a in range(3):
        for b in range(a, 3):
            v = np.bincount(groups, d[:, a] * d[:, b], num_groups) / safe[:, 0]
            cov[:, a, b] = v
            cov[:, b, a] = v
    return means, cov, counts


def surface_spacing(centers: ArrayLike, voxel_size: float, *, index: str = "kdtree") -> float:
    """Side of the square of surface one voxel stands for (m): the scene's sampling spacing.

    On well-covered planar patches of a coarse grid, ``cell² / voxels per cell``
    is the surface per voxel. Nearest-neighbour distances underestimate it on
    unevenly sampled scans (mesh vertices crowd at edges and leave flat parts
    bare), and it is what turns surfaces (m²) into voxel counts. Never less than
    the voxel size; the median nearest-neighbour distance when too few planar
    cells exist (found with ``index``, as :func:`~ontodetect._units.estimate_spacing`).

    Examples
    --------
    >>> import numpy as np
    >>> g = np.stack(np.meshgrid(np.arange(100), np.arange(100), [0]), -1).reshape(-1, 3)
    >>> s = surface_spacing(g * 0.04, 0.02)  # a grid of 4 cm: about 4 cm
    >>> bool(0.035 < s < 0.045)
    True
    """
    c = np.asarray(centers, dtype=np.float64)
    if len(c) < 2:
        return float(voxel_size)
    est = None
    cell = SURFACE_CELL
    while cell <= MAX_SURFACE_CELL:
        cells = cell_planes(c, cell)
        counts = cells.counts[cells.planar]
        if len(counts) < MIN_SURFACE_CELLS:
            break
        full = float(np.percentile(counts, FULL_CELL_PERCENTILE))
        est = cell / np.sqrt(full)
        if full >= MIN_FULL_CELL:
            break
        cell *= 2.0
    if est is None:
        sample = c[:: max(1, len(c) // SPACING_SAMPLE)]
        est = estimate_spacing(c, sample=len(sample), index=index)
    return float(max(voxel_size, est))


class _Clock:
    """Seconds spent in each step, for people tuning parameters on big scans."""


def up_hint(cloud: PointCloud) -> tuple[str, float | None]:
    """The axis :func:`estimate_up` prefers for ``cloud`` and the largest tilt (deg) it
    allows from it: ``-y`` within :data:`CAMERA_MAX_TILT` for an organized cloud in its
    camera's coordinates, ``z`` within that tilt for a view placed in a map (its
    sensor's position given there, z up like any map), ``z`` and any direction otherwise.

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> frame = point_cloud([[0.0, 0, 1]]).with_meta(organized=True, width=1, height=2)
    >>> up_hint(frame), up_hint(frame.with_meta(organized=False, sensor_position=[0, 0, 1]))
    (('-y', 60.0), ('z', 60.0))
    """
    # An organized cloud (width x height) is a camera frame: y down, z forward, and a
    # camera is pitched or rolled but not turned on its side.
    meta = cloud.meta
    height = meta.get("height")
    # A view found from its points (``view_up``, :func:`view_up`): its own axes' up.
    if meta.get("view_up") in AXES:
        return str(meta["view_up"]), CAMERA_MAX_TILT
    in_world = meta.get("sensor_position") is not None and not meta.get("organized")
    if in_world:
        return "z", CAMERA_MAX_TILT  # one view, placed upright in its map
    if isinstance(height, (int, np.integer)) and height > 1:
        return "-y", CAMERA_MAX_TILT
    return "z", None


def is_single_view(cloud: PointCloud) -> bool:
    """Whether ``cloud`` is one view of one sensor: organized (a PCD, PLY or depth frame of
    ``meta["height"] > 1`` rows) or with the sensor's position (``sensor_position``, a
    frame's viewpoint).

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> is_single_view(point_cloud([[0.0, 0, 1]]).with_meta(organized=True, width=1, height=2))
    True
    >>> is_single_view(point_cloud([[0.0, 0, 1]]))
    False
    """
    height = cloud.meta.get("height")
    if isinstance(height, (int, np.integer)) and not isinstance(height, bool) and height > 1:
        return True
    try:
        return sensor_position(cloud) is not None
    except InvalidParameterError:
        return False


#: :func:`looks_like_one_view`: fewest points to judge by; nearest range (m) of the closest
#: 1 % (a depth camera sees nothing nearer than 0.2-0.5 m; a room scanned around its
#: origin has points there); widest cone (deg) about the mean direction holding 99.5 % of
#: the points (a camera's field of view is 60-90 deg across, a room around its origin
#: 180 and more).
VIEW_MIN_POINTS = 1000
#: ... and most points judged (an even stride of the rest): a frame is a few hundred
#: thousand points, and a large scan must not pay for the test in time or memory.
VIEW_SAMPLE = 200_000
VIEW_MIN_RANGE = 0.2
VIEW_MAX_CONE = 75.0
#: ... and the median range at most this (m): depth cameras (structured light, stereo,
#: time of flight) work to 5-10 m; a scan far from the origin fills a narrow cone too.
VIEW_MAX_RANGE = 10.0
#: ... the angular cells (gnomonic, about nine points in a full one) in which one surface
#: per sight line is looked for: their ranges within this share of the nearest ...
VIEW_SPREAD = 0.15
#: ... in at least this share of the cells holding two points or more. One view is a depth
#: image, one surface per sight line (0.94-0.99 on the simulated frames from their sensor,
#: 0.99 on a Kinect frame); a scan fused from many views holds what lies behind what (0.15-0.2
#: of the cells on the simulated fused rooms seen from their origin, 0.5-0.85 on frames seen
#: from elsewhere than their sensor).
VIEW_SHARE = 0.9


def looks_like_one_view(xyz: ArrayLike, eye: ArrayLike = (0.0, 0.0, 0.0)) -> bool:
    """Whether points look like one view of a depth sensor standing at ``eye``: all of them
    in a cone from it, none very near it nor most of them far (a depth camera's range),
    and one surface per sight line (a depth image),
    which a scan fused from many views is not (what stands in front of a wall, and the wall
    behind it, on one sight line).

    A depth camera's frame stored without its pixel grid or its viewpoint has its sensor
    at the origin: SUN RGB-D's frames as VoteNet stores them (upright, z up), or a PLY in
    the camera's own axes.

    Examples
    --------
    >>> gen = np.random.default_rng(0)
    >>> wall = np.c_[gen.uniform(-1, 1, 4000), gen.uniform(-1, 1, 4000), np.full(4000, 3.0)]
    >>> box = np.c_[gen.uniform(-0.3, 0.3, (2000, 2)), np.full(2000, 2.0)]
    >>> looks_like_one_view(np.r_[wall[np.abs(wall[:, :2]).max(1) > 0.45], box])
    True
    >>> looks_like_one_view(np.r_[wall, box])  # the wall also behind the box: fused
    False
    """
    pts = np.asarray(xyz)
    pts = pts[:: max(1, -(-len(pts) // VIEW_SAMPLE))]
    p = np.asarray(pts, dtype=np.float64) - np.asarray(eye, dtype=np.float64)
    r = np.sqrt(np.einsum("ij,ij->i", p, p))
    keep = np.isfinite(r) & (r > 0)
    p, r = p[keep], r[keep]
    if len(r) < VIEW_MIN_POINTS or float(np.quantile(r, 0.01)) < VIEW_MIN_RANGE:
        return False
    if float(np.median(r)) > VIEW_MAX_RANGE:
        return False
    d = p / r[:, None]
    m = _mean_direction(d)
    if not m.any():
        return False
    cos = d @ m
    if float(np.degrees(np.arccos(np.clip(np.quantile(cos, 0.005), -1, 1)))) > VIEW_MAX_CONE:
        return False
    u, v = _image_plane(d, m, cos)
    cell = 3.0 * float(np.sqrt(np.ptp(u) * np.ptp(v) / len(u)))
    if not cell > 0.0:
        return False
    keys = np.unique(
        np.c_[np.floor(u / cell), np.floor(v / cell)].astype(np.int64),
        axis=0,
        return_inverse=True,
    )[1].reshape(-1)
    order = np.argsort(keys, kind="stable")
    k, rr = keys[order], r[order]
    starts = np.flatnonzero(np.r_[True, k[1:] != k[:-1]])
    counts = np.diff(np.r_[starts, len(k)])
    near = np.minimum.reduceat(rr, starts)
    far = np.maximum.reduceat(rr, starts)
    multi = counts >= 2
    if not multi.any():
        return False
    return float(np.mean((far - near)[multi] <= VIEW_SPREAD * near[multi])) >= VIEW_SHARE


def inferred_view(cloud: PointCloud) -> PointCloud | None:
    """``cloud`` taken as a depth frame seen from the origin when it has no sensor position
    and no pixel grid but looks like one view (:func:`looks_like_one_view`): its points'
    pixel grid (:func:`view_grid`, field ``pixel``), the sensor at the origin and the
    view's up axis (:func:`view_up`) in ``meta``; None for any other cloud. What
    ``detect`` does with such a cloud (``detect.infer_view``), and what ``info`` says of it.

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> inferred_view(point_cloud([[0.0, 0, 1], [1, 0, 1]])) is None  # too few to tell
    True
    """
    if sensor_position(cloud) is not None or pixel_grid(cloud) is not None:
        return None
    if not looks_like_one_view(cloud.xyz):
        return None
    pixels, width, height = view_grid(cloud.xyz)
    return cloud.replace(fields={**cloud.fields, "pixel": pixels}).with_meta(
        sensor_position=[0.0, 0.0, 0.0],
        width=width,
        height=height,
        view_up=view_up(cloud.xyz[:: max(1, len(cloud) // 100_000)]),
    )


def view_up(xyz: ArrayLike, eye: ArrayLike = (0.0, 0.0, 0.0)) -> str:
    """The axis a view from ``eye`` stored as bare points has for up: ``z`` when its mean
    sight line is within :data:`CAMERA_MAX_TILT` of level about it (a view placed upright,
    as SUN RGB-D's frames in VoteNet's upright axes), else ``-y``, a camera's own axes
    (y down, z forward: the sight lines run along z).

    Examples
    --------
    >>> view_up([[0.3, 3.0, -1.0], [-0.3, 3.0, -0.5]])  # looking along y, a little down
    'z'
    >>> view_up([[0.3, 0.5, 3.0], [-0.3, 0.2, 3.0]])  # looking along z: a camera's axes
    '-y'
    """
    p = np.asarray(xyz, dtype=np.float64) - np.asarray(eye, dtype=np.float64)
    r = np.sqrt(np.einsum("ij,ij->i", p, p))
    m = _mean_direction(p[r > 0] / r[r > 0, None])
    return "z" if abs(float(m[2])) <= np.sin(np.radians(CAMERA_MAX_TILT)) else "-y"


#: :func:`view_grid`: pixel side as a share of the points' mean angular spacing.
VIEW_PIXEL = 0.7


def _mean_direction(d: NDArray[np.float64]) -> NDArray[np.float64]:
    """The unit mean of unit sight lines ``d`` (n, 3); zero when they cancel out."""
    m = d.mean(axis=0)
    return m / max(float(np.linalg.norm(m)), 1e-12)


def _image_plane(
    d: NDArray[np.float64], m: NDArray[np.float64], cos: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Gnomonic image coordinates (u, v) of sight lines ``d`` on the plane across their
    mean direction ``m`` (``cos``: each one's cosine to it)."""
    e1 = np.cross(m, [0.0, 0.0, 1.0] if abs(m[2]) < 0.9 else [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(m, e1)
    return (d @ e1) / cos, (d @ e2) / cos


def view_grid(
    xyz: ArrayLike, eye: ArrayLike = (0.0, 0.0, 0.0)
) -> tuple[NDArray[np.int64], int, int]:
    """A pixel grid for one view stored as bare points (:func:`looks_like_one_view`): the
    points' sight lines from ``eye`` on an image plane across their mean direction, in
    pixels of :data:`VIEW_PIXEL` times their mean angular spacing. Returns each point's
    pixel (row-major) and the image's width and height, as
    :func:`ontodetect.cloud.pixel_grid` gives them for a camera's own frame.

    Examples
    --------
    >>> gen = np.random.default_rng(0)
    >>> pts = np.c_[gen.uniform(-1, 1, (900, 2)), np.full(900, 2.0)]
    >>> pixels, width, height = view_grid(pts)
    >>> 30 < width < 45 and 30 < height < 45, int(pixels.max()) < width * height
    (True, True)
    """
    p = np.asarray(xyz, dtype=np.float64) - np.asarray(eye, dtype=np.float64)
    r = np.sqrt(np.einsum("ij,ij->i", p, p))
    d = p / np.where(r > 0, r, 1.0)[:, None]
    m = _mean_direction(d)
    u, v = _image_plane(d, m, np.maximum(d @ m, 1e-6))
    side = VIEW_PIXEL * float(np.sqrt(np.ptp(u) * np.ptp(v) / max(len(u), 1)))
    if not side > 0.0:
        return np.zeros(len(p), dtype=np.int64), 1, 1
    col = np.floor((u - u.min()) / side).astype(np.int64)
    row = np.floor((v - v.min()) / side).astype(np.int64)
    width, height = int(col.max()) + 1, int(row.max()) + 1
    return row * width + col, width, height


def default_up(cloud: PointCloud, choice: str | ArrayLike | None = AUTO_FRAME) -> str | ArrayLike:
    """The up axis a run uses: ``choice``, where :data:`AUTO_FRAME` (the default) becomes
    ``"auto"`` for an organized or single-view cloud (:func:`is_single_view`) and ``"z"``
    for any other (a fused room scan keeps its axes, and its results do not change).

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> default_up(point_cloud([[0.0, 0, 1]])), default_up(point_cloud([[0.0, 0, 1]]), "-y")
    ('z', '-y')
    """
    if choice is None or (isinstance(choice, str) and choice == AUTO_FRAME):
        return "auto" if is_single_view(cloud) else "z"
    return choice


@dataclass(frozen=True)
class UpGuess:
    """What :func:`guess_up` found.

    Attributes
    ----------
    direction : (3,) float
        Unit up vector in the cloud's frame.
    axis : str
        The signed axis nearest to it (``"z"``, ``"-y"``...).
    angle : float
        Angle (deg) between ``direction`` and ``axis``.
    confidence : float
        Share of the best score among the six signed axes (1 when the axis is given).
    choice : str
        How it was chosen: ``"auto"`` (estimated) or the given axis.
    single_view : bool
        Whether the cloud is organized or single-view (then ``auto`` is the default).
    """

    direction: NDArray[np.float64]
    axis: str
    angle: float
    confidence: float
    choice: str
    single_view: bool


def guess_up(
    cloud: PointCloud | ArrayLike,
    up: str | ArrayLike | None = AUTO_FRAME,
    *,
    voxel_size: float = VOXEL_SIZE,
    structure_cell: float = STRUCTURE_CELL,
) -> UpGuess:
    """The up direction ``detect`` would use on ``cloud`` (``up`` as ``detect --up``).

    The same steps as preparation (:func:`ontodetect.preprocess.find_ground`) take before
    the floor: :func:`default_up`, the units guess's scale, the voxel grid average, the
    cell size from the sampling spacing and :func:`estimate_up` with :func:`up_hint`; only
    the removal of outliers is left out, so a very noisy scan may get a slightly different
    tilt, seldom another axis. NumPy alone (``ontodetect info``'s guess).

    Parameters
    ----------
    cloud : PointCloud or (n, 3) float
    up : str or (3,) float or None
        As ``prepare.up``: an axis, a vector, ``"auto"``, or :data:`AUTO_FRAME`.
    voxel_size, structure_cell : float
        ``prepare.voxel_size`` and ``prepare.structure_cell``.

    Returns
    -------
    UpGuess

    Examples
    --------
    >>> import numpy as np
    >>> from ontodetect import point_cloud
    >>> rng = np.random.default_rng(0)
    >>> floor = np.c_[rng.random((4000, 2)) * 4, np.zeros(4000)]
    >>> table = np.c_[rng.random((1000, 2)) + 1, np.full(1000, 0.75)]
    >>> wall = np.c_[rng.random(2000) * 4, np.full(2000, 4.0), rng.random(2000) * 2.5]
    >>> xyz = np.vstack([floor, table, wall])[:, [0, 2, 1]] * [1, -1, 1]  # a camera's y down
    >>> frame = point_cloud(xyz).with_meta(organized=True, width=100, height=70)
    >>> g = guess_up(frame)  # an organized frame: auto by default
    >>> g.axis, g.choice, g.single_view
    ('-y', 'auto', True)
    >>> guess_up(xyz).axis  # not a frame: z unless told
    'z'
    """
    if not isinstance(cloud, PointCloud):
        cloud = point_cloud(cloud)
    single = is_single_view(cloud)
    choice = default_up(cloud, up)
    if isinstance(choice, str) and choice == "auto":
        xyz = cloud.xyz[np.isfinite(cloud.xyz).all(axis=1)]
        units = guess_units(xyz)
        scale = {"millimetres": 1e-3, "centimetres": 1e-2}.get(units, 1.0)
        scaled = xyz * scale if scale != 1.0 else xyz
        groups, num = cell_index(scaled, voxel_size)
        centers = grouped_covariance(scaled, groups, num)[0] if num else scaled
        spacing = surface_spacing(centers, voxel_size, index="grid")
        cell = max(structure_cell, CELL_PER_SPACING * spacing)
        hint, max_angle = up_hint(cloud)
        direction, confidence = estimate_up(centers, hint=hint, cell=cell, max_angle=max_angle)
        label = "auto"
    else:
        direction, confidence = as_direction(choice), 1.0
        label = choice if isinstance(choice, str) else "given"
    names = list(AXES)
    cosines = np.array([direction @ np.array(AXES[n]) for n in names])
    best = int(np.argmax(cosines))
    angle = float(np.degrees(np.arccos(np.clip(cosines[best], -1.0, 1.0))))
    return UpGuess(direction, names[best], angle, float(confidence), label, single)
