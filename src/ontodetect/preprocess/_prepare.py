"""Preparation of a whole scan: :func:`prepare`, :func:`find_ground`, the scale factor
and :class:`PreparedScene` (the levelled scan every later stage works on)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._progress import progress
from .._units import guess_units
from .._up import (
    AUTO_FRAME,
    CAMERA_MAX_TILT,
    CELL_PER_SPACING,
    FULL_CELL_PERCENTILE,
    MIN_SURFACE_CELLS,
    SPACING_SAMPLE,
    SURFACE_CELL,
    default_up,
    surface_spacing,
    up_hint,
)
from ..cloud import PointCloud, point_cloud, sensor_position
from ..config import Config
from ..errors import InvalidParameterError
from ..geometry import LevelFrame, yaw_pose
from ._denoise import denoise, far_outlier_mask
from ._depth import smooth_depth
from ._floor import FloorMap, floor_height_map
from ._gravity import (
    CellPlanes,
    FloorFit,
    as_direction,
    cell_planes,
    estimate_up,
    find_floor,
    level_transform,
)
from ._quarter import quarter_matrix, quarter_turns, turn_about_z, turn_quarters, wall_yaw
from ._structure import StructurePlane, find_structure
from ._surface import smooth_surface, surface_scatter
from ._voxel import VoxelGrid, voxelize

__all__ = [
    "AUTO_FRAME",
    "CAMERA_MAX_TILT",
    "CELL_PER_SPACING",
    "DENOISE_GRID_FACTOR",
    "FLAT_FLOOR",
    "FULL_CELL_PERCENTILE",
    "IDENTITY_TOLERANCE",
    "LEVEL_MIN_ANGLE",
    "LOCAL_ORIGIN_DISTANCE",
    "LOCAL_ORIGIN_RATIO",
    "MILLIMETRE",
    "MIN_SURFACE_CELLS",
    "SPACING_SAMPLE",
    "SURFACE_CELL",
    "Ground",
    "GroundPlane",
    "PreparedScene",
    "find_ground",
    "guess_scale",
    "local_origin",
    "prepare",
    "scale_from_travel",
    "surface_spacing",
]

#: Scale applied to clouds whose size says millimetres.
MILLIMETRE = 1e-3
#: Scale applied to clouds whose size says centimetres.
CENTIMETRE = 1e-2
#: A rotation closer to the identity than this (Frobenius norm) is no rotation: the grid
#: computed before levelling is reused.
IDENTITY_TOLERANCE = 1e-12
#: Gaussian scatter sigma keeps 75 % of a plane's points within the inlier distance t when
#: t / sigma = 1.15 (erf(1.15 / sqrt 2) = 0.75): above sigma = t / 1.15 more than a quarter
#: fall outside, and ``prepare.auto_smoothing`` projects the voxels on their planes first.
QUARTER_OUTSIDE = 1.15
#: Outliers are sought on a grid this many times coarser than the voxels: a speck of noise
#: is as isolated there, and the neighbour search costs a quarter.
DENOISE_GRID_FACTOR = 2.0
#: A floor within this angle (deg) of the given up axis is taken as level: a rotation that
#: small moves nothing by more than a few millimetres and would cost a second voxel grid.
LEVEL_MIN_ANGLE = 0.2
#: A floor height map flatter than this (m) is dropped: the floor is a plane.
FLAT_FLOOR = 0.01


def scale_from_travel(encoder_distance: float, slam_distance: float) -> float:
    """Scale ``k_s = D_e / D_s`` of a monocular SLAM map (thesis §3.2).

    Parameters
    ----------
    encoder_distance : float
        Distance travelled according to the wheel encoders (metres), ``D_e``.
    slam_distance : float
        The same distance in the SLAM map's units, ``D_s``.

    Examples
    --------
    >>> scale_from_travel(4.0, 2.0)
    2.0
    """
    for name, v in (("encoder_distance", encoder_distance), ("slam_distance", slam_distance)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not (v > 0 and np.isfinite(v)):
            raise InvalidParameterError(name, "a float in the range (0, inf)", v)
    return float(encoder_distance) / float(slam_distance)


def guess_scale(points: ArrayLike) -> float:
    """1.0 for clouds in metres, 0.01 or 0.001 for clouds whose size says centimetres or
    millimetres.

    Examples
    --------
    >>> guess_scale([[0, 0, 0], [5000.0, 4000.0, 2500.0]])
    0.001
    """
    units = guess_units(np.asarray(points, dtype=np.float64))
    return {"millimetres": MILLIMETRE, "centimetres": CENTIMETRE}.get(units, 1.0)


@dataclass(frozen=True, eq=False)
class PreparedScene:
    """A scan ready for object search: levelled, denoised, voxelized, structure found.

    Attributes
    ----------
    cloud : PointCloud
        Every input point (same order and count as the input), in the levelled
        frame: metres, z up, z = height above the floor (see ``floor_map``).
    to_level : (4, 4) float
        Input frame -> levelled frame (includes the scale); a bent floor adds a
        smooth vertical correction (``floor_map``), which :meth:`level` and
        :meth:`from_level` apply.
    scale : float
        ``k_s`` of thesis §3.2.
    up : (3,) float
        Up direction in the input frame.
    floor_z : float
        Floor height along ``up`` in the input frame and units: the floor is
        ``{x : up · x = floor_z}``.
    floor_found : bool
        False when no floor was visible and the lowest points stood in for it.
    inliers : (n,) bool
        Points kept by denoising.
    voxels : VoxelGrid
        Grid average of the inliers in the levelled frame; ``voxels.point_to_voxel``
        is -1 for outliers.
    structure_label : (m,) int8
        Per voxel: 0 none, 1 floor, 2 wall, 3 ceiling (:data:`STRUCTURE_LABELS`).
    object_mask : (m,) bool
        Voxels where objects are searched: not structure and below the cut-off.
    structure_planes : list of StructurePlane
        Floor, walls and ceiling in the levelled frame.
    spacing : float
        Sampling spacing of the voxel cloud (m): the side of the square of surface
        one voxel stands for (:func:`surface_spacing`), at least the voxel size.
    config : Config
        The configuration used.
    floor_map : FloorMap or None
        Height of a bent floor above its plane; levelled z is height above it.
    info : dict
        How the scale was chosen, confidence of the up estimate, and other facts.
    """

    cloud: PointCloud
    to_level: NDArray[np.float64]
    scale: float
    up: NDArray[np.float64]
    floor_z: float
    floor_found: bool
    inliers: NDArray[np.bool_]
    voxels: VoxelGrid
    structure_label: NDArray[np.int8]
    object_mask: NDArray[np.bool_]
    structure_planes: list[StructurePlane]
    spacing: float
    config: Config
    floor_map: FloorMap | None = None
    info: dict[str, Any] = field(default_factory=dict)

    # -- voxel arrays --------------------------------------------------------------------
    @property
    def centers(self) -> NDArray[np.float64]:
        """(m, 3) float: voxel centres (grid average) in the levelled frame."""
        return self.voxels.centers

    @property
    def colors(self) -> NDArray[np.uint8] | None:
        """(m, 3) uint8 or None: mean colour per voxel."""
        return self.voxels.colors

    @property
    def counts(self) -> NDArray[np.int64]:
        """(m,) int: input points per voxel."""
        return self.voxels.counts

    @property
    def point_to_voxel(self) -> NDArray[np.int64]:
        """(n,) int: voxel of every input point, -1 for outliers."""
        return self.voxels.point_to_voxel

    @property
    def is_structure(self) -> NDArray[np.bool_]:
        """(m,) bool: floor, wall or ceiling voxels."""
        return self.structure_label > 0

    @property
    def num_points(self) -> int:
        return len(self.cloud)

    # -- mapping back --------------------------------------------------------------------
    def points_of(self, voxels: ArrayLike) -> NDArray[np.int64]:
        """Indices of the input points in the given voxels (indices or a mask)."""
        return self.voxels.points_of(voxels)

    @property
    def frame(self) -> LevelFrame:
        """The map between the input's frame and the levelled frame."""
        return LevelFrame(self.to_level, self.floor_map)

    def from_level(self, points: ArrayLike) -> NDArray[np.float64]:
        """(k, 3) levelled coordinates back to the input frame and units."""
        return self.frame.from_level(points)

    def level(self, points: ArrayLike) -> NDArray[np.float64]:
        """(k, 3) input-frame coordinates into the levelled frame."""
        return self.frame.level(points)

    def summary(self) -> dict[str, Any]:
        """JSON-ready facts about the preparation."""
        return {
            "num_points": self.num_points,
            "num_inliers": int(self.inliers.sum()),
            "num_voxels": len(self.voxels),
            "num_object_voxels": int(self.object_mask.sum()),
            "voxel_size": self.voxels.size,
            "spacing": self.spacing,
            "scale": self.scale,
            "up": [float(v) for v in self.up],
            "floor_z": self.floor_z,
            "floor_found": self.floor_found,
            "to_level": self.to_level.tolist(),
            "structure": [p.to_dict() for p in self.structure_planes],
            **self.info,
        }


def _choose_scale(xyz, cfg, scale, travelled) -> tuple[float, str]:
    if scale is not None:
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not scale > 0:
            raise InvalidParameterError("scale", "a float in the range (0, inf)", scale)
        return float(scale), "given"
    if travelled is not None:
        try:
            d_e, d_s = travelled
        except (TypeError, ValueError):
            raise InvalidParameterError(
                "travelled", "a pair (encoder distance, SLAM distance)", travelled
            ) from None
        return scale_from_travel(d_e, d_s), "travelled"
    if cfg.scale is not None:
        return float(cfg.scale), "config"
    if cfg.guess_units and len(xyz):
        k = guess_scale(xyz)
        return k, "units" if k != 1.0 else "default"
    return 1.0, "default"


class _Clock:
    """Seconds spent in each step, for people tuning parameters on big scans."""

    def __init__(self) -> None:
        self.laps: dict[str, float] = {}
        self._t = time.perf_counter()

    def lap(self, name: str) -> None:
        now = time.perf_counter()
        self.laps[name] = round(now - self._t, 4)
        self._t = now


#: A scan whose centre lies farther than this from its origin (in its own units)...
LOCAL_ORIGIN_DISTANCE = 1000.0
#: ...and farther than this many times its own size, as in a building's map in UTM
#: coordinates (400 km away, a few metres across), is prepared in a local frame: its
#: coordinates less a whole-unit origin near its centre. Grids, neighbour searches and
#: plane fits then work on numbers of a room's size; what preparation returns is still in
#: the input frame. Scans near their origin are not touched.
LOCAL_ORIGIN_RATIO = 10.0


def local_origin(xyz: NDArray[np.float64]) -> NDArray[np.float64]:
    """(3,) float: the whole-unit origin a scan far from its own origin is prepared around.

    Zeros for a scan near its origin (see :data:`LOCAL_ORIGIN_DISTANCE`).

    Examples
    --------
    >>> import numpy as np
    >>> local_origin(np.array([[400000.2, 5e6, 1.0], [400004.9, 5e6 + 3, 2.0]])).tolist()
    [400003.0, 5000002.0, 0.0]
    >>> local_origin(np.array([[0.0, 0.0, 0.0], [5.0, 4.0, 3.0]])).tolist()
    [0.0, 0.0, 0.0]
    """
    if len(xyz) == 0:
        return np.zeros(3)
    lo, hi = xyz.min(axis=0), xyz.max(axis=0)
    centre = (lo + hi) / 2
    far = float(np.abs(centre).max())
    size = float((hi - lo).max())
    if far <= LOCAL_ORIGIN_DISTANCE or far <= LOCAL_ORIGIN_RATIO * size:
        return np.zeros(3)
    origin = np.rint(centre)
    origin[np.abs(centre) <= LOCAL_ORIGIN_RATIO * size] = 0.0
    return origin


@dataclass(frozen=True)
class Ground:
    """What preparation finds before it turns the scan (:func:`find_ground`): the scale,
    the denoised voxels in the input frame, the up direction and the floor plane.

    Attributes
    ----------
    num_points : int
        Points of the cloud it was found in.
    scale, scale_source : float, str
        ``k_s`` and how it was chosen.
    voxels : VoxelGrid
        Denoised voxels of the scaled input.
    inliers : (n,) bool
        Points that kept a voxel.
    spacing, cell : float
        Sampling spacing (:func:`surface_spacing`) and structure cell size (m).
    up_confidence : float
        Confidence of an estimated up direction (1 when given).
    cells : CellPlanes
        Plane fits of the input-frame cells.
    floor : FloorFit
        The floor plane (its normal is the up direction).
    laps : dict
        Seconds per step.
    floor_scatter : float or None
        How far the floor's voxels scatter about their local planes (m,
        :func:`~ontodetect.preprocess.surface_scatter`): the sensor's noise as the scan kept
        it, one figure for every pass of a vote. ``None`` without a floor.
    origin : (3,) float
        The local origin (:func:`local_origin`) subtracted from the input before all of
        the above, which are in that local frame; zeros for most scans.
    quarter : int
        Quarter turns about z (:func:`~ontodetect.preprocess.quarter_turns`) the input was
        turned by before the origin was subtracted (``prepare.quarter_turns``); 0 for most.
    snapped : bool
        Whether the (turned) input was rounded to :data:`SNAP` first (``prepare.quarter_turns``).
    pre, yaw, corner : (3,) float, float or None, (3,) float
        With ``prepare.walls_to_axes``: the whole-unit origin subtracted first, the walls'
        direction (:func:`~ontodetect.preprocess.wall_yaw`, radians) the input was turned
        back by before its quarter turns, and the lowest corner of the turned points then
        subtracted (``origin`` is then zero). ``yaw`` is None otherwise.
    """

    num_points: int
    scale: float
    scale_source: str
    voxels: VoxelGrid
    inliers: NDArray[np.bool_]
    spacing: float
    cell: float
    up_confidence: float
    cells: CellPlanes
    floor: FloorFit
    laps: dict[str, float] = field(default_factory=dict)
    origin: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    floor_scatter: float | None = None
    quarter: int = 0
    snapped: bool = False
    pre: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    yaw: float | None = None
    corner: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    def to_local(self, xyz: ArrayLike) -> NDArray[np.float64]:
        """Input coordinates in the local frame all of the above are in."""
        if self.yaw is not None:  # prepare.walls_to_axes, as find_ground turned them
            return _snap(_walls_frame(xyz, self.pre, self.yaw, self.quarter, self.corner))
        local = turn_quarters(xyz, self.quarter)
        if self.snapped:
            local = _snap(local)
        return local - self.origin if self.origin.any() else local

    def walls_transform(self) -> NDArray[np.float64]:
        """4x4 transform of :meth:`to_local` with ``prepare.walls_to_axes`` (without the
        rounding): the input moved by ``pre``, turned by ``-yaw`` and its quarter turns,
        then moved by ``corner``."""
        turn = _rotation(quarter_matrix(self.quarter)) @ yaw_pose(0.0, 0.0, -(self.yaw or 0.0))
        return _translation(-self.corner) @ turn @ _translation(-self.pre)

    @property
    def up(self) -> NDArray[np.float64]:
        """(3,) float: the floor's normal in the input frame (turned back by ``quarter``)."""
        normal = np.array(turn_quarters(self.floor.normal, -self.quarter))
        return turn_about_z(normal, self.yaw) if self.yaw is not None else normal


@dataclass(frozen=True)
class GroundPlane:
    """The floor of a whole scan in its input frame: found once (on a subsample) and given
    to every part of it (the tiles of a building floor), which then neither estimate their
    own up direction and floor nor guess their own units.

    Attributes
    ----------
    up : (3,) float
        Unit normal of the floor, pointing up.
    height : float
        ``up · x`` of the points on the floor (input units).
    scale : float
        ``k_s``, input units to metres.
    area : float
        Horizontal surface found on the floor (m², of the cloud it was found in).
    """

    up: NDArray[np.float64]
    height: float
    scale: float
    area: float = 0.0

    @classmethod
    def from_ground(cls, ground: Ground) -> GroundPlane:
        """The plane :func:`find_ground` found, in the input frame."""
        u = np.asarray(ground.floor.normal, dtype=np.float64)
        height = float(ground.floor.offset) / ground.scale + float(u @ ground.origin)
        return cls(ground.up, height, float(ground.scale), float(ground.floor.area))

    def to_dict(self) -> dict[str, Any]:
        return {
            "up": [float(v) for v in self.up],
            "height": self.height,
            "scale": self.scale,
            "area": self.area,
        }


def find_ground(
    cloud: PointCloud,
    config: Config | None = None,
    *,
    scale: float | None = None,
    travelled: tuple[float, float] | None = None,
    up: str | ArrayLike | None = None,
    plane: GroundPlane | None = None,
) -> Ground:
    """Scale, denoise and voxelize a scan and find its up direction and floor: the steps
    of :func:`prepare` that do not depend on ``prepare.turn`` (parameters as there; a
    frame's depth steps are expected smoothed already).

    With ``plane`` (a :class:`GroundPlane` found for a larger scan this cloud is part
    of), its up direction, floor and scale are taken as they are (``scale``, ``travelled``
    and ``up`` are then not used)."""
    cfg = (config or Config()).prepare
    xyz = cloud.xyz
    n = len(xyz)
    if n == 0:
        raise InvalidParameterError("cloud", "a cloud with at least one point", "0 points")
    up_choice = default_up(cloud, cfg.up if up is None else up)
    # A scan (no sensor, z up) is prepared in the quarter turn its own points choose, so
    # that the same scan turned by 90°, 180° or 270° is the same input to the last bit.
    quarter, snapped = 0, False
    pre, yaw, corner = np.zeros(3), None, np.zeros(3)
    own_pose = (
        plane is None
        and cfg.frame == "input"
        and isinstance(up_choice, str)
        and up_choice == "z"
        and sensor_position(cloud) is None
    )
    if cfg.walls_to_axes and own_pose:
        # Turned by its walls' direction and its quarter, moved to its lowest corner and
        # read to the nanometre: the same scan turned by any angle, or moved, is the same
        # input to the last bit (the turn is read to the rounding error, wall_yaw).
        pre = local_origin(xyz)
        local = xyz - pre if pre.any() else xyz
        yaw = wall_yaw(local)
        quarter = quarter_turns(turn_about_z(local, -yaw))
        turned = _walls_frame(xyz, pre, yaw, quarter, np.zeros(3))
        corner = turned.min(axis=0)
        xyz, snapped = _snap(turned - corner), True  # the bits Ground.to_local gives
    elif cfg.quarter_turns and own_pose:
        # Read to the nanometre, so that a file turned by a rotation matrix (whose cos 90°
        # is 6e-17, not 0) is the same input as one turned exactly.
        quarter, snapped = quarter_turns(xyz), True
        xyz = _snap(turn_quarters(xyz, quarter))
    # The canonical frame works around the scan's median from the start: the grids laid
    # from it (voxels, cells) are then the same for the scan moved or turned by a quarter.
    canonical = cfg.frame == "canonical"
    # (Zero after the walls' turn, which moved the scan to its lowest corner.)
    origin = np.median(xyz, axis=0) if canonical else local_origin(xyz)
    if origin.any():
        xyz = xyz - origin
    clock = _Clock()
    if plane is not None:
        k_s, scale_source = float(plane.scale), "plane"
    else:
        k_s, scale_source = _choose_scale(xyz, cfg, scale, travelled)
    scaled = xyz * k_s if k_s != 1.0 else xyz

    colors = cloud.rgb
    with progress("Voxelizing and denoising", total=None):
        # Far outliers first (they would stretch the grid), then neighbourhood statistics
        # on the voxel centres, on a grid twice as coarse: every point inherits its
        # voxel's verdict, so the cost does not grow with the sensor's density.
        far = (
            far_outlier_mask(scaled, cfg.far_percentile, cfg.far_margin)
            if np.isfinite(cfg.far_margin)
            else np.ones(n, dtype=bool)
        )
        if not far.any():
            raise InvalidParameterError(
                "cloud", "a cloud that keeps points after denoising", f"all {n} points removed"
            )
        grid = voxelize(scaled, cfg.voxel_size, colors, mask=far, anchored=canonical)
        keep = denoise(
            grid.centers,
            voxel_size=DENOISE_GRID_FACTOR * cfg.voxel_size,
            method=cfg.denoise,
            neighbors=cfg.sor_neighbors,
            std_ratio=cfg.sor_std_ratio,
            radius=cfg.ror_radius,
            min_neighbors=cfg.ror_min_neighbors,
            far_margin=np.inf,
            anchored=canonical,
        )
        if not keep.any():
            raise InvalidParameterError(
                "cloud", "a cloud that keeps points after denoising", f"all {n} points removed"
            )
        grid = grid.subset(keep)
    inliers = grid.point_to_voxel >= 0

    clock.lap("voxels_and_denoise")

    # -- gravity and ground ------------------------------------------------------------
    spacing = surface_spacing(grid.centers, cfg.voxel_size)
    cell = max(cfg.structure_cell, CELL_PER_SPACING * spacing)
    confidence = 1.0
    if plane is not None:
        u = as_direction(plane.up)
        cells = cell_planes(grid.centers, cell, anchored=canonical)
        offset = k_s * (float(plane.height) - float(u @ origin))
        floor = FloorFit(u, offset, float(plane.area), True)
    else:
        if isinstance(up_choice, str) and up_choice == "auto":
            hint, max_angle = up_hint(cloud)
            u, confidence = estimate_up(grid.centers, hint=hint, cell=cell, max_angle=max_angle)
        else:
            u = as_direction(up_choice)
        cells = cell_planes(grid.centers, cell, anchored=canonical)
        floor = find_floor(
            grid.centers,
            u,
            cell=cell,
            min_area=cfg.min_floor_area,
            cells=cells,
            refine=cfg.level_on_floor,
            layers=cfg.floor_layers,
        )
    if (
        plane is None
        and floor.found
        and np.degrees(np.arccos(min(1.0, abs(float(floor.normal @ u))))) < LEVEL_MIN_ANGLE
    ):
        floor = FloorFit(u, floor.offset, floor.area, floor.found)
    # The sensor's noise as the scan kept it, measured where the surface is known flat.
    floor_scatter = None
    if floor.found:
        to_level = level_transform(floor.normal, floor.offset, k_s)
        rot, shift = to_level[:3, :3] / k_s, to_level[:3, 3]
        # Heights first, then the floor's voxels alone: no levelled copy of a large scan.
        near = np.abs(grid.centers @ rot[2] + shift[2]) < cfg.floor_band
        floor_scatter = surface_scatter(grid.centers[near] @ rot.T + shift)
    clock.lap("ground")
    return Ground(
        n,
        k_s,
        scale_source,
        grid,
        inliers,
        float(spacing),
        float(cell),
        float(confidence),
        cells,
        floor,
        dict(clock.laps),
        origin,
        floor_scatter,
        quarter,
        snapped,
        pre,
        yaw,
        corner,
    )


def prepare(
    cloud: PointCloud | ArrayLike,
    config: Config | None = None,
    *,
    scale: float | None = None,
    travelled: tuple[float, float] | None = None,
    up: str | ArrayLike | None = None,
    seed: int | None = 0,
    ground: Ground | None = None,
) -> PreparedScene:
    """Scale, denoise, level, voxelize and find the structure of a scan.

    Parameters
    ----------
    cloud : PointCloud or (n, 3) float
        The scan.
    config : Config, optional
        ``config.prepare`` drives this step; defaults from Table 4.1.
    scale : float, optional
        Scale factor ``k_s``; overrides ``travelled``, the configuration and the
        units guess.
    travelled : (float, float), optional
        Distances travelled according to odometry and to the SLAM map, giving
        ``k_s = D_e / D_s``.
    up : str or (3,) float, optional
        Up direction of the input: ``"z"``, ``"-y"``..., a vector, or ``"auto"``
        to estimate it (hint: ``-y`` for organized camera frames, ``z`` otherwise).
        Defaults to ``config.prepare.up``.
    seed : int, optional
        Accepted for a uniform signature; preparation has no random step.
    ground : Ground, optional
        This cloud's :func:`find_ground` with the same configuration (``scale``,
        ``travelled`` and ``up`` are then not used): passes over one scan that differ
        only in ``prepare.turn`` share it.

    Returns
    -------
    PreparedScene

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> floor = np.c_[rng.random((4000, 2)) * 3, np.full(4000, 0.7)]
    >>> box = np.c_[rng.random((800, 2)) * 0.4 + 1, rng.random(800) * 0.5 + 0.7]
    >>> scene = prepare(np.vstack([floor, box]))
    >>> round(scene.floor_z, 3), int(scene.object_mask.sum()) > 0
    (0.7, True)
    """
    del seed  # deterministic: no random step
    config = config or Config()
    cfg = config.prepare
    if not isinstance(cloud, PointCloud):
        cloud = point_cloud(cloud)
    if cfg.depth_smoothing:
        cloud = smooth_depth(cloud)  # only a single organized frame with its sensor changes
    xyz = cloud.xyz
    n = len(xyz)
    if ground is None:
        ground = find_ground(cloud, config, scale=scale, travelled=travelled, up=up)
    elif ground.num_points != n:
        raise InvalidParameterError(
            "ground", f"the ground of this cloud ({n} points)", f"{ground.num_points} points"
        )
    origin = ground.origin
    xyz = ground.to_local(xyz)  # the local frame the ground was found in
    clock = _Clock()
    clock.laps.update(ground.laps)
    k_s, scale_source, colors = ground.scale, ground.scale_source, cloud.rgb
    grid, inliers, spacing, cell = ground.voxels, ground.inliers, ground.spacing, ground.cell
    confidence, cells, floor = ground.up_confidence, ground.cells, ground.floor
    to_level = level_transform(floor.normal, floor.offset, k_s)
    canonical = cfg.frame == "canonical"
    if canonical:
        R = to_level[:3, :3] / k_s
        planar = cells.planar
        to_level = (
            canonical_pose(
                grid.centers @ R.T + to_level[:3, 3],
                cells.normals[planar] @ R.T,
                cells.counts[planar],
            )
            @ to_level
        )
    if cfg.turn:
        to_level = yaw_pose(0.0, 0.0, math.radians(cfg.turn)) @ to_level
    R = to_level[:3, :3] / k_s
    shift = to_level[:3, 3]
    # The canonical frame lays the grids anew from its origin, even when it only moves.
    rotated = canonical or float(np.linalg.norm(R - np.eye(3))) > IDENTITY_TOLERANCE
    levelled_xyz = xyz @ to_level[:3, :3].T + shift
    # Plane fits of the levelled scene: the same cells shifted when only translated.
    if rotated:
        cells = cell_planes(grid.centers @ R.T + shift, cell, anchored=canonical)
    else:
        cells = CellPlanes(
            cells.centers + shift, cells.normals, cells.counts, cells.planar, cells.cell
        )
    floor_map = None
    if cfg.floor_tile > 0 and cfg.max_floor_warp > 0 and floor.found:
        floor_map = floor_height_map(
            cells, tile=cfg.floor_tile, max_warp=cfg.max_floor_warp, anchored=canonical
        )
        if floor_map.warp < FLAT_FLOOR:
            floor_map = None
    if floor_map is not None:
        levelled_xyz[:, 2] -= floor_map.height(levelled_xyz[:, :2])
        cc = cells.centers.copy()
        cc[:, 2] -= floor_map.height(cc[:, :2])
        cells = CellPlanes(cc, cells.normals, cells.counts, cells.planar, cells.cell)
    if rotated or floor_map is not None:
        # Voxels of the final frame, so that every point lies in the voxel it maps to.
        grid = voxelize(levelled_xyz, cfg.voxel_size, colors, mask=inliers, anchored=canonical)
    else:
        # A translation moves the grid with the points: the same voxels, shifted.
        grid = VoxelGrid(
            grid.size,
            grid.origin + shift,
            grid.keys,
            grid.centers + shift,
            grid.colors,
            grid.counts,
            grid.point_to_voxel,
        )
    floor_scatter = ground.floor_scatter
    inlier = config.planes.threshold
    smoothed = cfg.smoothing or (
        cfg.auto_smoothing
        and floor_scatter is not None
        and floor_scatter > inlier / QUARTER_OUTSIDE
    )
    if smoothed:
        grid = VoxelGrid(
            grid.size,
            grid.origin,
            grid.keys,
            smooth_surface(grid.centers),
            grid.colors,
            grid.counts,
            grid.point_to_voxel,
        )
        cells = None
    clock.lap("level")
    normals = cloud.normals
    if normals is not None:
        if ground.yaw is not None:
            normals = turn_about_z(normals, -ground.yaw)
        normals = turn_quarters(normals, ground.quarter) @ R.T
    levelled = cloud.replace(xyz=levelled_xyz, normals=normals)

    clock.lap("levelled_cloud")

    # -- structure and the search volume -------------------------------------------------
    centers = grid.centers
    if cfg.structure:
        lcells = cells if cells is not None else cell_planes(centers, cell, anchored=canonical)
        labels, planes = find_structure(
            centers,
            lcells,
            floor_band=cfg.floor_band,
            ceiling_above=cfg.altitude_cutoff,
            min_floor_area=cfg.min_floor_area,
            min_wall_length=cfg.min_wall_length,
            min_wall_height=cfg.min_wall_height,
            wall_band=cfg.wall_band,
            floor_area=floor.area,
            shell_walls=cfg.shell_walls,
            floor_layers=cfg.floor_layers,
            low_scan_walls=cfg.low_scan_walls,
        )
    else:
        labels = np.zeros(len(grid), dtype=np.int8)
        planes = []
    object_mask = (labels == 0) & (centers[:, 2] <= cfg.altitude_cutoff)
    if not cfg.structure:
        object_mask &= centers[:, 2] >= cfg.floor_band
    clock.lap("structure")
    floor_z = float(floor.offset / k_s)
    if ground.yaw is not None:
        # Back to the input frame, as find_ground turned and moved it.
        to_level = to_level @ ground.walls_transform()
        floor_z += float(floor.normal @ ground.corner) + float(ground.up @ ground.pre)
    if origin.any():
        # Back to the input frame: levelling now subtracts the local origin first.
        to_level = to_level @ _translation(-origin)
        floor_z += float(floor.normal @ origin)
    if ground.quarter and ground.yaw is None:
        # ... and turns the input by its quarter turns before that.
        to_level = to_level @ _rotation(quarter_matrix(ground.quarter))
    return PreparedScene(
        cloud=levelled,
        to_level=to_level,
        scale=k_s,
        up=ground.up,
        floor_z=floor_z,
        floor_found=floor.found,
        inliers=inliers,
        voxels=grid,
        structure_label=labels,
        object_mask=object_mask,
        structure_planes=planes,
        spacing=float(spacing),
        config=config,
        floor_map=floor_map,
        info={
            "scale_source": scale_source,
            "up_confidence": float(confidence),
            "floor_area": float(floor.area),
            "cell": float(cell),
            "floor_warp": 0.0 if floor_map is None else floor_map.warp,
            "floor_scatter": floor_scatter,
            "smoothed": smoothed,
            "timings": clock.laps,
            # prepare.quarter_turns: the quarter turns the levelled frame is turned by
            **({"quarter_turns": ground.quarter} if ground.snapped else {}),
            # prepare.walls_to_axes: the turn (radians) about z before the quarter turns
            **({"walls_yaw": ground.yaw} if ground.yaw is not None else {}),
        },
    )


#: Cells whose normal is within this angle (deg) of horizontal are walls' cells, whose
#: direction the canonical frame follows.
CANONICAL_VERTICAL = 10.0
#: Residuals (deg) within which the walls' cells refine their direction, step by step.
CANONICAL_REFINE = (5.0, 5.0, 2.0, 2.0)


def canonical_pose(
    centers: NDArray[np.float64], normals: NDArray[np.float64], weights: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The turn about the vertical and the shift in the floor plane that put a levelled
    scan in its canonical frame (``prepare.frame: canonical``): the walls' main direction
    along x, the median of its points at the origin.

    The walls' direction is the circular mean of four times the azimuths of the vertical
    cells' normals (weighted by their points), so that walls at right angles agree (a
    Manhattan room) and a turn by any angle turns it by the same angle; without walls,
    the main axis of the points' spread. The median, unlike the minimum corner, moves
    little when points are dropped or jittered. A scan turned by any angle and moved then
    meets the same grids, up to a quarter turn about the origin, which every grid laid
    from the origin (``_up.cell_index``, :func:`voxelize`) maps onto itself.

    Parameters
    ----------
    centers : (m, 3) float
        Points (or voxel centres) in the levelled frame.
    normals : (g, 3) float and weights : (g,) float
        Normals of planar cells in the levelled frame, and their weights.

    Returns
    -------
    (4, 4) float

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> pts = np.c_[rng.random((500, 2)) * [4, 2] + 10, rng.random(500)]
    >>> normals = np.array([[np.cos(0.3), np.sin(0.3), 0], [-np.sin(0.3), np.cos(0.3), 0]])
    >>> T = canonical_pose(pts, normals, np.ones(2))
    >>> bool(np.allclose(T[:3, :3] @ normals[0], [1, 0, 0]))
    True
    """
    vert = np.abs(normals[:, 2]) < np.sin(np.radians(CANONICAL_VERTICAL))
    theta = np.arctan2(normals[vert, 1], normals[vert, 0])
    w = np.asarray(weights, dtype=np.float64)[vert]
    c, s = float(w @ np.cos(4 * theta)), float(w @ np.sin(4 * theta))
    if math.hypot(c, s) > 1e-6 * max(float(w.sum()), 1e-300):
        yaw = math.atan2(s, c) / 4
        # Cells across corners and furniture pull a mean: refine on the cells near the
        # walls' direction (residuals within CANONICAL_REFINE), whose noise is symmetric.
        for tol in CANONICAL_REFINE:
            r = (theta - yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4
            near = np.abs(r) < math.radians(tol)
            if not near.any():
                break
            yaw += float(np.average(r[near], weights=w[near]))
    elif len(centers) >= 2:  # no walls: the main axis of the spread
        evals, evecs = np.linalg.eigh(np.cov(centers[:, :2].T))
        yaw = math.atan2(evecs[1, -1], evecs[0, -1]) if evals[-1] > evals[0] else 0.0
    else:
        yaw = 0.0
    T = yaw_pose(0.0, 0.0, -yaw)
    if len(centers):
        T[:2, 3] = -np.median(centers[:, :2] @ T[:2, :2].T, axis=0)
    return T


#: The quantum (input units) a scan prepared in its quarter turn is read to: far below any
#: scanner's resolution, far above the rounding error a rotation leaves in a room's
#: coordinates (1e-16 to 1e-10 of a unit).
SNAP = 1e-9


def _walls_frame(
    xyz: ArrayLike, pre: NDArray[np.float64], yaw: float, quarter: int, corner: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Input points in the frame ``prepare.walls_to_axes`` prepares a scan in (before the
    rounding): moved by ``-pre``, turned by ``-yaw`` and by ``quarter`` quarter turns, moved
    by ``-corner``; :func:`find_ground` and :meth:`Ground.to_local` both read them so."""
    local = np.asarray(xyz, dtype=np.float64)
    local = local - pre if pre.any() else local
    return turn_quarters(turn_about_z(local, -yaw), quarter) - corner


def _snap(xyz: NDArray[np.float64]) -> NDArray[np.float64]:
    """Coordinates rounded to :data:`SNAP` (symmetric: ``-x`` gives minus ``x``'s)."""
    return np.round(xyz / SNAP) * SNAP


def _rotation(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    """4x4 transform: the (3, 3) rotation ``matrix``."""
    T = np.eye(4)
    T[:3, :3] = matrix
    return T


def _translation(offset: NDArray[np.float64]) -> NDArray[np.float64]:
    """4x4 transform: translation by ``offset``."""
    T = np.eye(4)
    T[:3, 3] = offset
    return T
