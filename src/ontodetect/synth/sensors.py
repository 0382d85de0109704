"""Virtual sensors: ray-cast a simulated :class:`~ontodetect.synth.scene.Scene` into points.

Every sensor casts rays against ``scene.combined_mesh()`` with Open3D's
``RaycastingScene`` and returns a :class:`SensorOutput`: a
:class:`~ontodetect.cloud.PointCloud` whose points carry the ``instance`` and
``class_id`` of the triangle they hit, and the sensor's poses, intrinsics and
parameters. Points exist only where the sensor saw a surface, so occlusion and
self-occlusion come for free. Colours are the material colour with simple
shading (light from the ceiling and from the sensor) and seeded noise.

Four sensors:

- :func:`scan_rgbd_trajectory`: a Kinect-like RGB-D camera walked around the
  room, frames fused in the world frame (what RGB-D SLAM produces);
- :func:`scan_rgbd_frame`: one organized frame in the camera frame (x right,
  y down, z forward), the way single Kinect frames come;
- :func:`scan_tls`: a terrestrial laser scanner on a tripod at a few stations;
- :func:`scan_monocular_slam`: a semi-dense monocular SLAM map (LSD-SLAM /
  ORB-SLAM style), at an unknown global scale, with the odometry distance that
  recovers the scale (thesis §3.2: ``k_s = D_e / D_s``).

Every random step draws from ``np.random.default_rng(rng)``: the same scene,
parameters and seed give the same points.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._progress import progress
from ..cloud import PointCloud, point_cloud
from ..errors import InvalidParameterError
from .scene import Scene

__all__ = [
    "SENSORS",
    "RGBDSensor",
    "SensorOutput",
    "camera_trajectory",
    "scan_monocular_slam",
    "scan_rgbd_frame",
    "scan_rgbd_trajectory",
    "scan_tls",
    "tls_stations",
]

#: Sensor names, as ``synthesize(sensor=...)`` and ``ontodetect synth --sensor`` take them.
SENSORS: tuple[str, ...] = ("rgbd", "rgbd-frame", "tls", "monocular")

# -- Kinect v1 constants ---------------------------------------------------------------
# Axial noise sigma(z) = a + b z^2 (metres). Nguyen, Izadi & Lovell (2012), "Modeling
# Kinect sensor noise for improved 3D reconstruction and tracking", fit
# sigma_z = 0.0012 + 0.0019 (z - 0.4)^2 for incidence below 60 degrees; Khoshelham &
# Elberink (2012), "Accuracy and resolution of Kinect depth data for indoor mapping
# applications", report the same quadratic growth (a few mm at 1 m, ~4 cm at 5 m).
# Dropping the 0.4 m offset keeps the form a + b z^2 and errs on the noisy side.
KINECT_NOISE: tuple[float, float] = (0.0012, 0.0019)
#: Kinect v1 disparity is measured in 1/8 pixel steps (Khoshelham & Elberink 2012).
KINECT_DISPARITY_STEP_PX = 0.125
#: Distance between the Kinect v1 infrared projector and camera (metres).
KINECT_BASELINE = 0.075
#: Beyond this angle between ray and surface normal the projected pattern is lost.
KINECT_MAX_INCIDENCE_DEG = 75.0

# -- shading ---------------------------------------------------------------------------
AMBIENT = 0.45  # share of the material colour lit by ambient light
CEILING_LIGHT = 0.30  # Lambertian term for light from straight above
HEAD_LIGHT = 0.35  # Lambertian term for light from the sensor
COLOR_NOISE = 3.0  # std of the per-channel sensor noise, in 0..255 units

# -- geometry tolerances -----------------------------------------------------------------
#: Projector rays that stop this fraction short of the point are shadowed by something else.
SHADOW_TOLERANCE = 1e-3
#: A depth jump larger than this fraction of the depth per pixel of stride is an edge.
EDGE_JUMP_PER_PIXEL = 0.04
#: Neighbouring surfaces whose normals differ by more than this form a crease (an edge).
CREASE_ANGLE_DEG = 30.0
#: Material colours further apart than this (0..255, Euclidean) form a visible edge.
COLOR_EDGE = 30.0
#: Parts that rays pass through (window panes).
TRANSPARENT_PARTS = frozenset({"glass"})
#: Rays per Open3D call: bounds memory for multi-million point scans.
CHUNK_RAYS = 1_000_000

# -- trajectories ----------------------------------------------------------------------
CAMERA_HEIGHT = (1.2, 1.7)  # hand-held or robot-mounted camera, metres
WALL_CLEARANCE = 0.6  # camera loop keeps this far from the walls
MIN_LOOP_RADIUS = 0.25
LOOK_HEIGHT = 0.5  # cameras aim at furniture height
POSITION_JITTER = 0.05
TARGET_JITTER = 0.25
CORNER_LOOK_EVERY = 4  # every 4th frame looks along a wall into a corner
INNER_LOOP_SHARE = 0.4  # share of the frames on the inner loop, looking out at the walls
INNER_LOOP_SCALE = 0.35  # size of the inner loop relative to the outer one
OUTWARD_LOOK = 2.0  # the inner loop aims this far ahead (metres), at furniture height
VIEW_PROBE_STRIDE = 16  # choosing a single frame's view: one probe ray per 16 x 16 pixels
VIEW_MIN_PIXELS = 3  # probe pixels that make a piece of furniture count as seen
FURNITURE_CLEARANCE = 0.15  # sensors are never placed closer than this to an object box
FREE_GRID = 0.1  # resolution of the search for free floor, metres
#: Per-frame drift: rotation std (radians) per metre of translation std.
DRIFT_ANGLE_PER_METRE = 0.5

# -- laser scanner ---------------------------------------------------------------------
TRIPOD_HEIGHT = 1.5
TLS_ELEVATION = (-60.0, 90.0)  # typical phase-shift scanner field of view, degrees
TLS_MAX_INCIDENCE_DEG = 85.0
TLS_INTENSITY_NOISE = 0.01
_LUMA = np.array([0.299, 0.587, 0.114])  # ITU-R BT.601 luminance of an RGB colour

# -- monocular SLAM ----------------------------------------------------------------------
#: Unknown map scale drawn log-uniformly in this range when not given.
SLAM_SCALE_RANGE = (0.2, 5.0)
#: Share of edge pixels a semi-dense tracker keeps (the rest lack a stable gradient).
SLAM_EDGE_KEEP = 0.8
#: Relative error of wheel odometry over the trajectory (D_e).
ODOMETRY_NOISE = 0.01


@dataclass(frozen=True, eq=False)
class SensorOutput:
    """What a virtual sensor returns.

    Attributes
    ----------
    cloud : PointCloud
        The points, with fields ``instance`` (int32, 0 = no object, e.g. an
        outlier) and ``class_id`` (int32, see :data:`~ontodetect.synth.scene.CLASS_IDS`),
        ``intensity`` (float32, 0..1) for the laser scanner, and normals facing
        the sensor when asked for.
    sensor : str
        One of :data:`SENSORS`.
    frame : str
        Frame of ``cloud``: ``"world"`` (metres, z up, floor at 0), ``"camera"``
        (x right, y down, z forward; world = ``poses[0]`` applied to it) or
        ``"map"`` (world multiplied by ``scale``).
    parameters : dict
        Every parameter of the sensor, JSON-serializable, to reproduce the scan.
    poses : (m, 4, 4) float
        True sensor-to-world transforms, one per frame or station.
    estimated_poses : (m, 4, 4) float
        The poses the points were fused with (``poses`` plus drift).
    triangle : (n,) int32
        Triangle of ``scene.combined_mesh()`` each point comes from (-1 for outliers).
    intrinsics : dict or None
        Camera ``width``, ``height``, ``fx``, ``fy``, ``cx``, ``cy``, ``stride``.
    scale : float
        Map units per metre (1 except for monocular SLAM).
    odometry_distance : float or None
        D_e: length of the trajectory according to odometry (metres).
    slam_distance : float or None
        D_s: length of the trajectory in map units.
    """

    cloud: PointCloud
    sensor: str
    frame: str
    parameters: dict[str, Any]
    poses: NDArray[np.float64]
    estimated_poses: NDArray[np.float64]
    triangle: NDArray[np.int32]
    intrinsics: dict[str, Any] | None = None
    scale: float = 1.0
    odometry_distance: float | None = None
    slam_distance: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def scale_factor(self) -> float | None:
        """k_s = D_e / D_s: multiply the map by it to get metres (thesis §3.2)."""
        if self.odometry_distance is None or not self.slam_distance:
            return None
        return self.odometry_distance / self.slam_distance

    def organized_cloud(self, *, fields: bool = True) -> PointCloud:
        """The single frame as its full ``width x height`` grid, NaN where nothing returned.

        This is the layout of an organized PCD file (row-major pixels) and is
        meant for writing one; the NaN rows break the usual promise of finite
        points, so other stages should take :attr:`cloud` instead.

        Parameters
        ----------
        fields : bool
            Keep the per-point fields (zero where nothing returned).

        Returns
        -------
        PointCloud
            ``width * height`` points in the camera frame; ``index`` is ``arange``.
        """
        width, height = self.cloud.meta.get("width"), self.cloud.meta.get("height")
        if not self.cloud.meta.get("organized") or width is None or height is None:
            raise InvalidParameterError(
                "sensor", "a single-frame sensor ('rgbd-frame')", self.sensor
            )
        n = int(width) * int(height)
        xyz = np.full((n, 3), np.nan)
        xyz[self.cloud.index] = self.cloud.xyz
        rgb = None
        if self.cloud.rgb is not None:
            rgb = np.zeros((n, 3), np.uint8)
            rgb[self.cloud.index] = self.cloud.rgb
        normals = None
        if self.cloud.normals is not None:
            normals = np.full((n, 3), np.nan)
            normals[self.cloud.index] = self.cloud.normals
        grid_fields = {}
        for name, values in self.cloud.fields.items() if fields else ():
            full = np.zeros((n, *values.shape[1:]), values.dtype)
            full[self.cloud.index] = values
            grid_fields[name] = full
        arrays = [xyz, rgb, normals, *grid_fields.values()]
        index = np.arange(n, dtype=np.int64)
        for a in [*arrays, index]:
            if a is not None:
                a.flags.writeable = False
        # Built directly: point_cloud() would drop the NaN rows that make the grid.
        return PointCloud(
            xyz,
            rgb,
            normals,
            MappingProxyType(grid_fields),
            index,
            MappingProxyType(dict(self.cloud.meta)),
        )

    def world_cloud(self) -> PointCloud:
        """The cloud in the world frame (camera frames moved by their pose, with the
        camera's position as ``meta["sensor_position"]``; maps keep scale)."""
        if self.frame != "camera":
            return self.cloud
        xyz = _transform(self.estimated_poses[0], self.cloud.xyz)
        normals = self.cloud.normals
        if normals is not None:
            normals = normals @ self.estimated_poses[0][:3, :3].T
        # The camera now stands at the pose's origin (ontodetect.cloud.sensor_position).
        eye = self.estimated_poses[0][:3, 3].tolist()
        return self.cloud.replace(xyz=xyz, normals=normals).with_meta(sensor_position=eye)


# ----------------------------------------------------------------------------------------
# parameter checks
# ----------------------------------------------------------------------------------------
def _check_number(
    name: str,
    value: Any,
    *,
    low: float = 0.0,
    high: float = np.inf,
    low_open: bool = False,
    integer: bool = False,
) -> Any:
    """``value`` as int/float if it is a number in the range, else InvalidParameterError."""
    kinds = (int, np.integer) if integer else (int, float, np.integer, np.floating)
    ok = isinstance(value, kinds) and not isinstance(value, bool)
    if ok:
        v = float(value)
        ok = bool(np.isfinite(v) and (v > low if low_open else v >= low) and v <= high)
    if not ok:
        kind = "an integer" if integer else "a number"
        lo = "(" if low_open else "["
        hi = "]" if np.isfinite(high) else ")"
        raise InvalidParameterError(name, f"{kind} in the range {lo}{low:g}, {high:g}{hi}", value)
    return int(value) if integer else float(value)


def _check_pair(name: str, value: Any, *, low: float = 0.0) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise InvalidParameterError(name, "a pair of numbers", value) from None
    if not (np.isfinite(a) and np.isfinite(b)) or a < low or b < low:
        raise InvalidParameterError(name, f"a pair of finite numbers >= {low}", value)
    return a, b


def _check_scene(scene: Any) -> Scene:
    if not isinstance(scene, Scene):
        raise InvalidParameterError("scene", "a Scene", type(scene).__name__)
    return scene


# ----------------------------------------------------------------------------------------
# ray casting
# ----------------------------------------------------------------------------------------
class _Raycaster:
    """The scene's triangles in an Open3D ray-casting scene, with per-triangle labels."""

    def __init__(self, scene: Scene) -> None:
        import open3d as o3d

        self._o3c = o3d.core
        vertices, triangles, instance, color = scene.combined_mesh()
        if len(triangles) == 0:
            raise InvalidParameterError(
                "scene", "a scene with at least one triangle", "a scene without triangles"
            )
        self.instance = np.asarray(instance, np.int32)
        self.color = np.asarray(color, np.uint8)
        class_of = {obj.instance_id: obj.class_id for obj in scene.objects}
        lookup = np.zeros(int(self.instance.max()) + 1, np.int32)
        for iid, cid in class_of.items():
            lookup[iid] = cid
        self.class_id = lookup[self.instance]
        v = np.asarray(vertices, np.float64)
        t = np.asarray(triangles, np.int64)
        n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
        length = np.linalg.norm(n, axis=1, keepdims=True)
        self.normal = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
        # Clear glass returns no depth to a structured-light camera and lets a laser
        # through: rays pass such parts and hit whatever lies behind them.
        solid = np.concatenate(
            [
                ~np.isin(
                    np.asarray(obj.part_names, dtype=object)[obj.triangle_part]
                    if len(obj.triangles)
                    else np.zeros(0, object),
                    list(TRANSPARENT_PARTS),
                )
                for obj in scene.objects
            ]
        )
        #: Triangle of the combined mesh for each triangle of the ray-casting scene.
        self._solid = np.flatnonzero(solid)
        self._scene = o3d.t.geometry.RaycastingScene()
        if len(self._solid):
            self._scene.add_triangles(
                o3d.core.Tensor(v.astype(np.float32)),
                o3d.core.Tensor(t[self._solid].astype(np.uint32)),
            )

    def cast(
        self, origins: NDArray[np.float64], directions: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """Hit parameter ``t`` (units of the direction's length; inf = miss), triangle (-1)."""
        rays = np.empty((len(directions), 6), np.float32)
        rays[:, :3] = origins
        rays[:, 3:] = directions
        out = self._scene.cast_rays(self._o3c.Tensor(rays))
        t_hit = out["t_hit"].numpy().astype(np.float64)
        prim = out["primitive_ids"].numpy().astype(np.int64)
        miss = ~np.isfinite(t_hit)
        tri = self._solid[np.where(miss, 0, prim)] if len(self._solid) else prim
        tri[miss] = -1
        return t_hit, tri


def _transform(T: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
    return points @ T[:3, :3].T + T[:3, 3]


def _shade(
    base: NDArray[np.uint8],
    normal: NDArray[np.float64],
    to_sensor: NDArray[np.float64],
    rng: np.random.Generator,
    color_noise: float,
) -> NDArray[np.uint8]:
    """Material colour lit from the ceiling and from the sensor, plus sensor noise.

    ``normal`` must face the sensor and ``to_sensor`` be unit vectors.
    """
    lit = (
        AMBIENT
        + CEILING_LIGHT * np.clip(normal[:, 2], 0.0, 1.0)
        + HEAD_LIGHT * np.clip(np.einsum("ij,ij->i", normal, to_sensor), 0.0, 1.0)
    )
    rgb = base.astype(np.float64) * lit[:, None]
    if color_noise > 0:
        rgb += rng.normal(0.0, color_noise, rgb.shape)
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8)


def _facing(
    normal: NDArray[np.float64], direction: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Normals flipped towards the sensor, and the cosine of the incidence angle."""
    cos = np.einsum("ij,ij->i", normal, direction)
    flipped = np.where(cos[:, None] > 0, -normal, normal)
    return flipped, np.abs(cos)


def _rotation(rotvec: NDArray[np.float64]) -> NDArray[np.float64]:
    """(m, 3) rotation vectors -> (m, 3, 3) matrices (Rodrigues)."""
    theta = np.linalg.norm(rotvec, axis=1)
    k = np.divide(rotvec, theta[:, None], out=np.zeros_like(rotvec), where=theta[:, None] > 0)
    K = np.zeros((len(k), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    K -= K.transpose(0, 2, 1)
    s, c = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
    return np.eye(3) + s * K + (1 - c) * (K @ K)


def _drifted(
    poses: NDArray[np.float64], drift: float, rng: np.random.Generator
) -> NDArray[np.float64]:
    """Poses with an accumulated random-walk error, as registration drift produces."""
    if drift <= 0 or len(poses) < 2:
        return poses.copy()
    m = len(poses)
    steps = np.zeros((m, 4, 4))
    steps[:] = np.eye(4)
    steps[1:, :3, :3] = _rotation(rng.normal(0.0, drift * DRIFT_ANGLE_PER_METRE, (m - 1, 3)))
    steps[1:, :3, 3] = rng.normal(0.0, drift, (m - 1, 3))
    error = np.eye(4)
    out = np.empty_like(poses)
    for k in range(m):
        error = error @ steps[k]
        out[k] = error @ poses[k]
    return out


def _path_length(poses: NDArray[np.float64]) -> float:
    return float(np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1).sum())


# ----------------------------------------------------------------------------------------
# where sensors stand
# ----------------------------------------------------------------------------------------
def _furniture_boxes(scene: Scene) -> list[Any]:
    return [obj.box for obj in scene.objects if not obj.is_structure]


def _occupied(boxes: list[Any], xy: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Which positions stand on the footprint of a piece of furniture (plus clearance)."""
    inside = np.zeros(len(xy), bool)
    for box in boxes:
        # Test at the box's own mid-height: a person or a tripod cannot stand on furniture.
        pts = np.column_stack([xy, np.full(len(xy), box.center[2])])
        inside |= box.contains(pts, FURNITURE_CLEARANCE)
    return inside


def _snap_free(scene: Scene, xy: NDArray[np.float64]) -> NDArray[np.float64]:
    """Positions kept inside the room; those on furniture moved to the nearest free spot."""
    room = np.asarray(scene.size[:2], np.float64)
    xy = np.clip(
        xy, FURNITURE_CLEARANCE, np.maximum(room - FURNITURE_CLEARANCE, FURNITURE_CLEARANCE)
    )
    boxes = _furniture_boxes(scene)
    blocked = _occupied(boxes, xy)
    if not blocked.any():
        return xy
    gx = np.arange(FURNITURE_CLEARANCE, room[0] - FURNITURE_CLEARANCE + 1e-9, FREE_GRID)
    gy = np.arange(FURNITURE_CLEARANCE, room[1] - FURNITURE_CLEARANCE + 1e-9, FREE_GRID)
    cells = np.stack(np.meshgrid(gx, gy, indexing="ij"), -1).reshape(-1, 2)
    free = cells[~_occupied(boxes, cells)]
    if len(free) == 0:  # wall-to-wall furniture: nowhere better to go
        return xy
    d2 = ((xy[blocked, None, :] - free[None]) ** 2).sum(-1)
    xy[blocked] = free[np.argmin(d2, axis=1)]
    return xy


def _frame_pose(
    scene: Scene, caster: _Raycaster | None, cam: RGBDSensor, rng: np.random.Generator
) -> NDArray[np.float64]:
    """(1, 4, 4): the best view for a single frame.

    Cameras stand near the four corners and the middles of the four walls
    (jittered by ``rng``), looking at the furniture; a coarse probe render keeps
    the one that sees the most pieces of furniture, then the most furniture pixels,
    among those whose projector (``cam.baseline`` to the right) the camera can see.
    """
    room = np.asarray(scene.size[:2], np.float64)
    lo = np.minimum(WALL_CLEARANCE, room / 4)
    hi, mid = room - lo, room / 2
    xy = np.array(
        [
            [lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]],
            [mid[0], lo[1]], [hi[0], mid[1]], [mid[0], hi[1]], [lo[0], mid[1]],
        ]
    )  # fmt: skip
    xy = _snap_free(scene, xy + rng.normal(0.0, POSITION_JITTER, xy.shape))
    z = rng.uniform(*CAMERA_HEIGHT, len(xy))
    boxes = _furniture_boxes(scene)
    aim = np.mean([b.center[:2] for b in boxes], axis=0) if boxes else mid
    target = np.column_stack(
        [aim + rng.normal(0.0, TARGET_JITTER, xy.shape), np.full(len(xy), LOOK_HEIGHT)]
    )
    near = np.linalg.norm(target[:, :2] - xy, axis=1) < 2 * FURNITURE_CLEARANCE
    target[near, :2] = xy[near] + [1.0, 0.0]
    poses = _look_at(np.column_stack([xy, z]), target)
    if caster is None or not boxes:
        return poses[:1]
    probe = RGBDSensor(
        width=cam.width, height=cam.height, fx=cam.fx, fy=cam.fy, cx=cam.cx, cy=cam.cy,
        min_range=cam.min_range, max_range=cam.max_range, noise=(0.0, 0.0),
        disparity_step=0.0, baseline=0.0, edge_dropout=0.0, color_noise=0.0,
        stride=VIEW_PROBE_STRIDE,
    )  # fmt: skip
    # Every random draw of the probe has probability 0 or std 0: any generator will do,
    # and the caller's stream stays untouched.
    r = probe.render(caster, poses, np.random.default_rng(0), shade=False)
    furniture = np.zeros(int(caster.instance.max()) + 1, bool)
    furniture[[o.instance_id for o in scene.objects if not o.is_structure]] = True
    inst = caster.instance[r["triangle"]].astype(np.int64)
    mine = furniture[inst]
    frame = r["frame"][mine].astype(np.int64)
    pixels = np.bincount(frame, minlength=len(poses))
    pair, count = np.unique(frame * len(furniture) + inst[mine], return_counts=True)
    seen = np.bincount(pair[count >= VIEW_MIN_PIXELS] // len(furniture), minlength=len(poses))
    if cam.baseline > 0:
        # A structured-light camera measures only what its projector lights: with the
        # projector on the far side of a door leaf beside the camera, the frame is empty.
        reach, _ = caster.cast(poses[:, :3, 3], poses[:, :3, 0] * cam.baseline)
        blocked = reach <= 1.0
        seen[blocked], pixels[blocked] = -1, -1
    best = np.lexsort((pixels, seen))[-1]
    return poses[best : best + 1]


def _look_at(position: NDArray[np.float64], target: NDArray[np.float64]) -> NDArray[np.float64]:
    """(m, 4, 4) camera-to-world poses: camera x right, y down, z toward the target."""
    forward = target - position
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(forward, up)
    norm = np.linalg.norm(right, axis=1, keepdims=True)
    # Looking straight down or up: any horizontal right vector will do.
    right = np.where(norm > 1e-6, right / np.maximum(norm, 1e-12), [1.0, 0.0, 0.0])
    down = np.cross(forward, right)
    T = np.zeros((len(position), 4, 4))
    T[:, :3, 0], T[:, :3, 1], T[:, :3, 2], T[:, :3, 3] = right, down, forward, position
    T[:, 3, 3] = 1.0
    return T


def camera_trajectory(
    scene: Scene,
    num_frames: int,
    *,
    height: tuple[float, float] = CAMERA_HEIGHT,
    rng: int | np.random.Generator | None = None,
) -> NDArray[np.float64]:
    """Camera poses walking around the room: a loop looking in, then one looking out.

    Like someone scanning a room, the camera first walks an ellipse
    ``WALL_CLEARANCE`` away from the walls looking in at the furniture (every
    ``CORNER_LOOK_EVERY``-th frame along the wall into the next corner), then a
    smaller loop around the middle of the room looking out at the walls and at
    what stands against them (a share ``INNER_LOOP_SHARE`` of the frames). The
    height goes up and down within ``height``; cameras aim at furniture height.
    Positions on the footprint of a piece of furniture move to the nearest free
    floor.

    Parameters
    ----------
    scene : Scene
    num_frames : int
        Number of poses.
    height : (2,) float
        Lowest and highest camera height (metres).
    rng : int or Generator, optional
        Seed for the jitter of positions and aims.

    Returns
    -------
    (num_frames, 4, 4) float
        Camera-to-world transforms; camera frame x right, y down, z forward.

    Examples
    --------
    >>> from ontodetect.synth.scene import Scene
    >>> poses = camera_trajectory(Scene("office", (4.0, 3.0, 2.6), [], 0), 8, rng=0)
    >>> poses.shape, bool(poses[:, 2, 3].min() >= 1.2)
    ((8, 4, 4), True)
    """
    scene = _check_scene(scene)
    num_frames = _check_number("num_frames", num_frames, low=1, integer=True)
    lo, hi = _check_pair("height", height)
    rng = np.random.default_rng(rng)
    room = np.asarray(scene.size[:2], np.float64)
    centre = room / 2
    boxes = _furniture_boxes(scene)
    aim = np.mean([b.center[:2] for b in boxes], axis=0) if boxes else centre
    semi = np.maximum(room / 2 - WALL_CLEARANCE, MIN_LOOP_RADIUS)
    semi = np.minimum(semi, room / 2 - FURNITURE_CLEARANCE)
    n_in = round(num_frames * INNER_LOOP_SHARE) if num_frames >= CORNER_LOOK_EVERY else 0
    n_out = num_frames - n_in
    start = rng.uniform(0, 2 * np.pi)
    theta = start + 2 * np.pi * np.concatenate(
        [np.arange(n_out) / max(n_out, 1), np.arange(n_in) / max(n_in, 1)]
    )
    inner = np.arange(num_frames) >= n_out
    radius = np.where(inner[:, None], INNER_LOOP_SCALE * semi, semi)
    direction = np.column_stack([np.cos(theta), np.sin(theta)])
    xy = centre + radius * direction + rng.normal(0.0, POSITION_JITTER, (num_frames, 2))
    phase = rng.uniform(0, 2 * np.pi)
    z = (lo + hi) / 2 + (hi - lo) / 2 * np.sin(2 * theta + phase)
    xy = _snap_free(scene, xy)

    target = np.empty((num_frames, 3))
    target[:, :2] = aim + rng.normal(0.0, TARGET_JITTER, (num_frames, 2))
    target[:, 2] = LOOK_HEIGHT
    corners = np.array([[0, 0], [room[0], 0], [room[0], room[1]], [0, room[1]]], np.float64)
    corner_angle = np.arctan2(corners[:, 1] - centre[1], corners[:, 0] - centre[0])
    ahead = (corner_angle[None, :] - theta[:, None]) % (2 * np.pi)
    next_corner = corners[np.argmin(ahead, axis=1)]
    corner_frames = (np.arange(num_frames) % CORNER_LOOK_EVERY == CORNER_LOOK_EVERY - 1) & ~inner
    target[corner_frames, :2] = next_corner[corner_frames]
    # The inner loop looks outwards, at the walls and what stands against them.
    target[inner, :2] = np.clip(xy[inner] + OUTWARD_LOOK * direction[inner], 0.0, room)
    position = np.column_stack([xy, z])
    # A target right under the camera gives a useless view: look at the room centre instead.
    near = np.linalg.norm(target[:, :2] - xy, axis=1) < 2 * FURNITURE_CLEARANCE
    target[near, :2] = centre
    near = np.linalg.norm(target[:, :2] - xy, axis=1) < 2 * FURNITURE_CLEARANCE
    target[near, :2] = xy[near] + [1.0, 0.0]
    return _look_at(position, target)


def tls_stations(
    scene: Scene,
    stations: int,
    *,
    height: float = TRIPOD_HEIGHT,
    rng: int | np.random.Generator | None = None,
) -> NDArray[np.float64]:
    """Scanner stations: one near the room centre, the others spread around it.

    Returns
    -------
    (stations, 4, 4) float
        Scanner-to-world transforms (scanner axes parallel to the world's).

    Examples
    --------
    >>> from ontodetect.synth.scene import Scene
    >>> tls_stations(Scene("office", (4.0, 3.0, 2.6), [], 0), 3, rng=0)[:, 2, 3].tolist()
    [1.5, 1.5, 1.5]
    """
    scene = _check_scene(scene)
    stations = _check_number("stations", stations, low=1, integer=True)
    rng = np.random.default_rng(rng)
    room = np.asarray(scene.size[:2], np.float64)
    centre = room / 2
    angle = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(stations - 1) / max(stations - 1, 1)
    spread = np.maximum(room / 2 - WALL_CLEARANCE, MIN_LOOP_RADIUS) * 0.7
    xy = np.vstack([centre, centre + spread * np.column_stack([np.cos(angle), np.sin(angle)])])
    xy += rng.normal(0.0, POSITION_JITTER, xy.shape)
    z = np.full(stations, float(height))
    xy = _snap_free(scene, xy)
    T = np.zeros((stations, 4, 4))
    T[:] = np.eye(4)
    T[:, :2, 3], T[:, 2, 3] = xy, z
    return T


# ----------------------------------------------------------------------------------------
# RGB-D camera
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class RGBDSensor:
    """A structured-light RGB-D camera (Kinect v1 defaults).

    Parameters
    ----------
    width, height : int
        Image size in pixels.
    fx, fy : float
        Focal lengths in pixels; the principal point is the image centre
        unless ``cx``, ``cy`` are given.
    min_range, max_range : float
        Depths (metres along the optical axis) outside which nothing is returned.
    noise : (2,) float
        ``(a, b)`` of the axial noise std ``sigma(z) = a + b z**2`` (metres),
        quantization included. See :data:`KINECT_NOISE` for the sources.
    disparity_step : float
        Disparity quantization in pixels: depths come in steps of
        ``disparity_step * z**2 / (fx * baseline)`` (none when either is 0).
    baseline : float
        Projector-camera distance (metres); the projector sits on the camera's
        +x side, so background just left of an object edge is in the projector's
        shadow and returns nothing (0 disables the shadows).
    max_incidence_deg : float
        No return where the ray meets the surface at a larger angle to its normal.
    edge_dropout : float
        Probability that a pixel at a depth discontinuity returns nothing.
    dropout : float
        Probability that any other pixel returns nothing (speckle).
    stride : int
        Cast one ray every ``stride`` pixels in both directions.
    color_noise : float
        Std of the colour noise per channel (0..255 units).
    """

    width: int = 640
    height: int = 480
    fx: float = 525.0
    fy: float = 525.0
    cx: float | None = None
    cy: float | None = None
    min_range: float = 0.5
    max_range: float = 4.5
    noise: tuple[float, float] = KINECT_NOISE
    disparity_step: float = KINECT_DISPARITY_STEP_PX
    baseline: float = KINECT_BASELINE
    max_incidence_deg: float = KINECT_MAX_INCIDENCE_DEG
    edge_dropout: float = 0.5
    dropout: float = 0.0
    stride: int = 1
    color_noise: float = COLOR_NOISE

    def __post_init__(self) -> None:
        check = object.__setattr__
        check(self, "width", _check_number("width", self.width, low=1, integer=True))
        check(self, "height", _check_number("height", self.height, low=1, integer=True))
        check(self, "fx", _check_number("fx", self.fx, low_open=True))
        check(self, "fy", _check_number("fy", self.fy, low_open=True))
        cx = (self.width - 1) / 2 if self.cx is None else _check_number("cx", self.cx, low=-np.inf)
        cy = (self.height - 1) / 2 if self.cy is None else _check_number("cy", self.cy, low=-np.inf)
        check(self, "cx", float(cx))
        check(self, "cy", float(cy))
        check(self, "min_range", _check_number("min_range", self.min_range))
        check(
            self,
            "max_range",
            _check_number("max_range", self.max_range, low=self.min_range, low_open=True),
        )
        check(self, "noise", _check_pair("noise", self.noise))
        check(self, "disparity_step", _check_number("disparity_step", self.disparity_step))
        check(self, "baseline", _check_number("baseline", self.baseline))
        check(
            self,
            "max_incidence_deg",
            _check_number("max_incidence_deg", self.max_incidence_deg, high=90),
        )
        check(self, "edge_dropout", _check_number("edge_dropout", self.edge_dropout, high=1))
        check(self, "dropout", _check_number("dropout", self.dropout, high=1))
        check(self, "stride", _check_number("stride", self.stride, low=1, integer=True))
        check(self, "color_noise", _check_number("color_noise", self.color_noise))

    # -- derived quantities ----------------------------------------------------------
    def sigma(self, depth: ArrayLike) -> NDArray[np.float64]:
        """Axial noise std (metres) at the given depths: ``a + b z**2``.

        Examples
        --------
        >>> float(RGBDSensor().sigma(2.0))
        0.0088
        """
        a, b = self.noise
        z = np.asarray(depth, np.float64)
        return a + b * z**2

    def quantum(self, depth: ArrayLike) -> NDArray[np.float64]:
        """Depth quantization step (metres) at the given depths (0 when disabled)."""
        z = np.asarray(depth, np.float64)
        if self.disparity_step <= 0 or self.baseline <= 0:
            return np.zeros_like(z)
        return self.disparity_step * z**2 / (self.fx * self.baseline)

    @property
    def grid(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Pixel columns and rows that get a ray."""
        return (
            np.arange(0, self.width, self.stride, dtype=np.float64),
            np.arange(0, self.height, self.stride, dtype=np.float64),
        )

    def intrinsics(self) -> dict[str, Any]:
        u, v = self.grid
        return {
            "width": self.width,
            "height": self.height,
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            "stride": self.stride,
            "grid_width": len(u),
            "grid_height": len(v),
        }

    def parameters(self) -> dict[str, Any]:
        params = asdict(self)
        params["noise"] = list(self.noise)
        return params

    # -- rendering -------------------------------------------------------------------
    def render(
        self,
        caster: _Raycaster,
        poses: NDArray[np.float64],
        rng: np.random.Generator,
        *,
        shade: bool = True,
    ) -> dict[str, NDArray[Any]]:
        """Depth images of a batch of poses, returns per valid pixel (camera frame).

        Returns a dict of flat arrays over the returned pixels: ``frame``,
        ``pixel`` (row-major in the ray grid), ``camera`` (n, 3) points in the
        camera frame (noisy, quantized), ``triangle``, ``normal`` (world,
        facing the camera), ``rgb`` (only if ``shade``; otherwise ``to_camera``,
        the unit vectors from the points to the camera, for shading later).
        """
        u, v = self.grid
        gw, gh = len(u), len(v)
        uu, vv = np.meshgrid(u, v)
        dirs_cam = np.column_stack(
            [
                ((uu - self.cx) / self.fx).ravel(),
                ((vv - self.cy) / self.fy).ravel(),
                np.ones(gw * gh),
            ]
        )
        frames_per_chunk = max(1, CHUNK_RAYS // (gw * gh))
        parts: list[dict[str, NDArray[Any]]] = []
        with progress("Ray casting RGB-D frames", total=len(poses)) as advance:
            for start in range(0, len(poses), frames_per_chunk):
                chunk = poses[start : start + frames_per_chunk]
                parts.append(
                    self._render_chunk(caster, chunk, start, dirs_cam, (gh, gw), rng, shade)
                )
                advance(len(chunk))
        return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}

    def _render_chunk(
        self,
        caster: _Raycaster,
        poses: NDArray[np.float64],
        first: int,
        dirs_cam: NDArray[np.float64],
        shape: tuple[int, int],
        rng: np.random.Generator,
        shade: bool,
    ) -> dict[str, NDArray[Any]]:
        m, k = len(poses), len(dirs_cam)
        R, t = poses[:, :3, :3], poses[:, :3, 3]
        dirs = (dirs_cam[None] @ R.transpose(0, 2, 1)).reshape(-1, 3)
        origins = np.repeat(t, k, axis=0)
        # Directions keep a unit z in the camera frame, so the hit parameter is the depth.
        depth, tri = caster.cast(origins, dirs)
        valid = (tri >= 0) & (depth >= self.min_range) & (depth <= self.max_range)
        idx = np.flatnonzero(valid)
        unit = dirs[idx] / np.linalg.norm(dirs_cam, axis=1)[idx % k, None]
        normal, cos_inc = _facing(caster.normal[tri[idx]], unit)
        seen = cos_inc >= np.cos(np.radians(self.max_incidence_deg))

        if self.baseline > 0 and seen.any():
            # Structured light: a point is measured only if the projector also sees it.
            sub = idx[seen]
            hit = origins[sub] + depth[sub, None] * dirs[sub]
            projector = t + R[:, :, 0] * self.baseline
            proj = projector[sub // k]
            t_proj, _ = caster.cast(proj, hit - proj)
            seen[np.flatnonzero(seen)[t_proj < 1.0 - SHADOW_TOLERANCE]] = False
        valid[idx[~seen]] = False

        # Depth discontinuities: drivers drop the mixed pixels along object edges.
        img = np.where(valid, depth, np.inf).reshape(m, *shape)
        jump = np.zeros_like(img)
        for axis in (1, 2):
            with np.errstate(invalid="ignore"):  # inf - inf next to pixels without return
                diff = np.abs(np.diff(img, axis=axis))
            diff[~np.isfinite(diff)] = 0.0
            lo = [slice(None)] * 3
            hi = [slice(None)] * 3
            lo[axis], hi[axis] = slice(None, -1), slice(1, None)
            jump[tuple(lo)] = np.maximum(jump[tuple(lo)], diff)
            jump[tuple(hi)] = np.maximum(jump[tuple(hi)], diff)
        edge = (jump.ravel() > EDGE_JUMP_PER_PIXEL * self.stride * depth)[idx]
        draw = rng.random(len(idx))
        keep = seen & np.where(edge, draw >= self.edge_dropout, draw >= self.dropout)
        idx, unit, normal = idx[keep], unit[keep], normal[keep]

        z = depth[idx]
        sigma = self.sigma(z)
        quantum = self.quantum(z)
        # The noise model gives the total std; the quantization's share (q^2/12) comes off
        # the Gaussian part so that the sum matches it.
        gauss = np.sqrt(np.maximum(sigma**2 - quantum**2 / 12.0, 0.0))
        z_noisy = z + rng.normal(0.0, 1.0, len(z)) * gauss
        if self.disparity_step > 0 and self.baseline > 0:
            step = self.disparity_step / (self.fx * self.baseline)  # inverse-depth step, 1/m
            z_noisy = 1.0 / (np.maximum(np.rint(1.0 / z_noisy / step), 1.0) * step)
        pixel = idx % k
        frame = idx // k
        camera = dirs_cam[pixel] * z_noisy[:, None]
        out = {
            "frame": (frame + first).astype(np.int32),
            "pixel": pixel.astype(np.int64),
            "camera": camera,
            "triangle": tri[idx].astype(np.int32),
            "normal": normal,
        }
        if shade:
            out["rgb"] = _shade(caster.color[tri[idx]], normal, -unit, rng, self.color_noise)
        else:
            out["to_camera"] = -unit
        return out


def _labelled_cloud(
    caster: _Raycaster,
    xyz: NDArray[np.float64],
    rgb: NDArray[np.uint8],
    triangle: NDArray[np.int32],
    *,
    normals: NDArray[np.float64] | None = None,
    extra: dict[str, NDArray[Any]] | None = None,
    index: ArrayLike | None = None,
    meta: dict[str, Any] | None = None,
) -> PointCloud:
    hit = triangle >= 0
    tri = np.maximum(triangle, 0)
    fields = {
        "instance": np.where(hit, caster.instance[tri], 0).astype(np.int32),
        "class_id": np.where(hit, caster.class_id[tri], 0).astype(np.int32),
    }
    fields.update(extra or {})
    return point_cloud(xyz, rgb, normals, fields, index, meta, on_nonfinite="raise", copy=False)


def _voxel_fuse(
    xyz: NDArray[np.float64],
    rgb: NDArray[np.uint8],
    triangle: NDArray[np.int32],
    instance: NDArray[np.int32],
    normals: NDArray[np.float64] | None,
    voxel: float,
) -> tuple[Any, ...]:
    """Grid-average fusion: one point per occupied voxel, labelled by majority."""
    cell = np.floor((xyz - xyz.min(axis=0)) / voxel).astype(np.int64)
    dims = cell.max(axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    _, inv, counts = np.unique(key, return_inverse=True, return_counts=True)
    nvox = len(counts)
    mean = np.column_stack([np.bincount(inv, xyz[:, j], nvox) for j in range(3)]) / counts[:, None]
    col = (
        np.column_stack([np.bincount(inv, rgb[:, j].astype(np.float64), nvox) for j in range(3)])
        / counts[:, None]
    )
    # Majority instance per voxel; ties go to the lower instance id, deterministically.
    pair = inv.astype(np.int64) * (int(instance.max()) + 1) + instance
    upair, first, pcount = np.unique(pair, return_index=True, return_counts=True)
    pvox = upair // (int(instance.max()) + 1)
    order = np.lexsort((-pcount, pvox))
    winner = order[np.r_[True, pvox[order][1:] != pvox[order][:-1]]]
    rep = first[winner]  # one representative input point per voxel
    nrm = None
    if normals is not None:
        nsum = np.column_stack([np.bincount(inv, normals[:, j], nvox) for j in range(3)])
        length = np.linalg.norm(nsum, axis=1, keepdims=True)
        nrm = np.divide(nsum, length, out=normals[rep].copy(), where=length > 0)
    return mean, np.clip(np.rint(col), 0, 255).astype(np.uint8), triangle[rep], nrm


def scan_rgbd_trajectory(
    scene: Scene,
    *,
    num_frames: int = 24,
    poses: ArrayLike | None = None,
    drift: float = 0.0,
    voxel: float | None = None,
    normals: bool = False,
    rng: int | np.random.Generator | None = None,
    **sensor: Any,
) -> SensorOutput:
    """Walk an RGB-D camera around the room and fuse its frames in the world frame.

    Parameters
    ----------
    scene : Scene
    num_frames : int
        Frames on the :func:`camera_trajectory` (ignored when ``poses`` is given).
    poses : (m, 4, 4) float, optional
        Camera-to-world poses to use instead of the default loop.
    drift : float
        Std (metres) of the per-frame random-walk error of the fused poses
        (rotation std ``drift * DRIFT_ANGLE_PER_METRE`` radians): registration
        drift. 0 fuses with the true poses.
    voxel : float, optional
        Average the fused points on a grid of this size (metres) to keep the
        cloud small; labels go to the majority in each voxel.
    normals : bool
        Attach the true surface normals, facing the camera.
    rng : int or Generator, optional
        Seed for the trajectory, noise, dropouts and colours.
    **sensor
        :class:`RGBDSensor` parameters (``width``, ``height``, ``fx``, ``fy``,
        ``min_range``, ``max_range``, ``noise``, ``disparity_step``,
        ``baseline``, ``max_incidence_deg``, ``edge_dropout``, ``dropout``,
        ``stride`` (default 4 here), ``color_noise``).

    Returns
    -------
    SensorOutput
        ``frame == "world"``; fields ``instance``, ``class_id``, ``frame``
        (index of the frame that saw the point; absent after voxel fusion).

    Examples
    --------
    >>> from ontodetect.synth.scene import Scene
    >>> out = scan_rgbd_trajectory(Scene("office", (4.0, 3.0, 2.6), [], 0), num_frames=2,
    ...                            rng=0)  # an empty scene: nothing to see
    >>> len(out.cloud)
    0
    """
    scene = _check_scene(scene)
    sensor.setdefault("stride", 4)
    cam = _make_sensor(sensor)
    drift = _check_number("drift", drift)
    if voxel is not None:
        voxel = _check_number("voxel", voxel, low_open=True)
    rng = np.random.default_rng(rng)
    if poses is None:
        true_poses = camera_trajectory(scene, num_frames, rng=rng)
    else:
        true_poses = _check_poses(poses)
    est = _drifted(true_poses, drift, rng)
    caster = _caster(scene)
    params = {
        "num_frames": len(true_poses),
        "drift": drift,
        "voxel": voxel,
        "normals": bool(normals),
        **cam.parameters(),
    }
    if caster is None:
        return _empty_output("rgbd", "world", params, true_poses, est, cam.intrinsics())
    r = cam.render(caster, true_poses, rng)
    xyz = np.einsum("nij,nj->ni", est[r["frame"], :3, :3], r["camera"]) + est[r["frame"], :3, 3]
    nrm = None
    if normals:
        # Normals were computed in the world of the true poses; carry them into the fused frame.
        nrm = np.einsum(
            "nij,njk,nk->ni",
            est[r["frame"], :3, :3],
            true_poses[r["frame"], :3, :3].transpose(0, 2, 1),
            r["normal"],
        )
    extra: dict[str, NDArray[Any]] = {"frame": r["frame"]}
    rgb, tri = r["rgb"], r["triangle"]
    if voxel is not None and len(xyz):
        inst = caster.instance[tri]
        xyz, rgb, tri, nrm = _voxel_fuse(xyz, rgb, tri, inst, nrm, voxel)
        extra = {}
    cloud = _labelled_cloud(
        caster, xyz, rgb, tri, normals=nrm, extra=extra, meta={"sensor": "rgbd"}
    )
    return SensorOutput(
        cloud, "rgbd", "world", params, true_poses, est, tri, intrinsics=cam.intrinsics()
    )


def scan_rgbd_frame(
    scene: Scene,
    *,
    pose: ArrayLike | None = None,
    normals: bool = False,
    rng: int | np.random.Generator | None = None,
    **sensor: Any,
) -> SensorOutput:
    """One RGB-D frame in the camera frame, organized like a Kinect frame.

    Parameters
    ----------
    scene : Scene
    pose : (4, 4) float, optional
        Camera-to-world transform; by default, of cameras standing near the
        corners and the middles of the walls looking at the furniture, the one
        that sees the most of it.
    normals : bool
        Attach surface normals (camera frame, facing the camera).
    rng : int or Generator, optional
    **sensor
        :class:`RGBDSensor` parameters (``stride`` defaults to 1: the full image).

    Returns
    -------
    SensorOutput
        ``frame == "camera"`` (x right, y down, z forward). The cloud holds the
        pixels that returned a depth; ``cloud.index`` is each point's row-major
        pixel in the ``meta["width"] x meta["height"]`` grid (``organized``
        True), so the full organized frame has NaN everywhere else.

    Examples
    --------
    >>> import numpy as np
    >>> from ontodetect.synth.scene import Scene
    >>> out = scan_rgbd_frame(Scene("office", (4.0, 3.0, 2.6), [], 0), pose=np.eye(4), stride=8)
    >>> out.cloud.meta["width"], out.cloud.meta["height"], len(out.cloud)
    (80, 60, 0)
    """
    scene = _check_scene(scene)
    cam = _make_sensor(sensor)
    rng = np.random.default_rng(rng)
    caster = _caster(scene)
    if pose is None:
        true_pose = _frame_pose(scene, caster, cam, rng)
    else:
        true_pose = _check_poses(np.asarray(pose, np.float64)[None], name="pose")
    intr = cam.intrinsics()
    meta = {
        "sensor": "rgbd-frame",
        "width": intr["grid_width"],
        "height": intr["grid_height"],
        "organized": True,
        "viewpoint": [0, 0, 0, 1, 0, 0, 0],
    }
    params = {"normals": bool(normals), **cam.parameters()}
    if caster is None:
        return _empty_output("rgbd-frame", "camera", params, true_pose, true_pose, intr, meta)
    r = cam.render(caster, true_pose, rng)
    nrm = r["normal"] @ true_pose[0, :3, :3] if normals else None
    cloud = _labelled_cloud(
        caster, r["camera"], r["rgb"], r["triangle"], normals=nrm, index=r["pixel"], meta=meta
    )
    return SensorOutput(
        cloud,
        "rgbd-frame",
        "camera",
        params,
        true_pose,
        true_pose.copy(),
        r["triangle"],
        intrinsics=intr,
    )


# ----------------------------------------------------------------------------------------
# terrestrial laser scanner
# ----------------------------------------------------------------------------------------
def scan_tls(
    scene: Scene,
    *,
    stations: int | ArrayLike = 3,
    h_res_deg: float = 0.4,
    v_res_deg: float = 0.4,
    noise_sigma: float = 0.002,
    min_range: float = 0.6,
    max_range: float = 50.0,
    max_incidence_deg: float = TLS_MAX_INCIDENCE_DEG,
    elevation: tuple[float, float] = TLS_ELEVATION,
    color_noise: float = COLOR_NOISE,
    normals: bool = False,
    rng: int | np.random.Generator | None = None,
) -> SensorOutput:
    """A terrestrial laser scanner on a tripod, scanning a full turn at a few stations.

    Each station casts one ray per ``h_res_deg`` of azimuth and ``v_res_deg``
    of elevation within ``elevation``; ranges get Gaussian noise along the ray
    (phase-shift scanners quote a few millimetres). Work is done in chunks of
    :data:`CHUNK_RAYS` rays, so ten million points fit in memory, with a
    progress bar when a reporter is installed.

    Parameters
    ----------
    scene : Scene
    stations : int or (m, 4, 4) float
        Number of stations placed by :func:`tls_stations`, or their poses.
    h_res_deg, v_res_deg : float
        Angular steps (degrees). 0.4 gives about 340,000 rays per station, 0.1 about
        5.4 million (what it takes for ten million points from a few stations).
    noise_sigma : float
        Range noise std (metres).
    min_range, max_range : float
        Ranges outside which nothing is returned (metres).
    max_incidence_deg : float
        No return at more grazing angles.
    elevation : (2,) float
        Lowest and highest elevation (degrees).
    color_noise : float
        Std of the colour noise per channel.
    normals : bool
        Attach the true surface normals, facing the station.
    rng : int or Generator, optional

    Returns
    -------
    SensorOutput
        ``frame == "world"``; fields ``instance``, ``class_id``,
        ``intensity`` (float32, 0..1: reflectance times the cosine of the
        incidence angle) and ``station``.

    Examples
    --------
    >>> from ontodetect.synth.scene import Scene
    >>> out = scan_tls(Scene("office", (4.0, 3.0, 2.6), [], 0), stations=1, h_res_deg=10,
    ...                v_res_deg=10, rng=0)
    >>> out.poses.shape
    (1, 4, 4)
    """
    scene = _check_scene(scene)
    h_res = _check_number("h_res_deg", h_res_deg, low_open=True, high=90)
    v_res = _check_number("v_res_deg", v_res_deg, low_open=True, high=90)
    noise_sigma = _check_number("noise_sigma", noise_sigma)
    min_range = _check_number("min_range", min_range)
    max_range = _check_number("max_range", max_range, low=min_range, low_open=True)
    max_inc = _check_number("max_incidence_deg", max_incidence_deg, high=90)
    el_lo, el_hi = _check_pair("elevation", elevation, low=-90)
    if el_hi > 90 or el_lo >= el_hi:
        raise InvalidParameterError(
            "elevation", "(low, high) degrees with -90 <= low < high <= 90", elevation
        )
    color_noise = _check_number("color_noise", color_noise)
    rng = np.random.default_rng(rng)
    if np.ndim(stations) == 0:
        poses = tls_stations(scene, stations, rng=rng)
    else:
        poses = _check_poses(stations, name="stations")

    azimuth = np.radians(np.arange(0.0, 360.0, h_res))
    elev = np.radians(np.arange(el_lo, el_hi + 1e-9, v_res))
    el_grid, az_grid = np.meshgrid(elev, azimuth, indexing="ij")  # scanline by scanline
    dirs_local = np.column_stack(
        [
            (np.cos(el_grid) * np.cos(az_grid)).ravel(),
            (np.cos(el_grid) * np.sin(az_grid)).ravel(),
            np.sin(el_grid).ravel(),
        ]
    )
    params = {
        "stations": len(poses),
        "h_res_deg": h_res,
        "v_res_deg": v_res,
        "noise_sigma": noise_sigma,
        "min_range": min_range,
        "max_range": max_range,
        "max_incidence_deg": max_inc,
        "elevation": [el_lo, el_hi],
        "color_noise": color_noise,
        "normals": bool(normals),
    }
    caster = _caster(scene)
    if caster is None:
        return _empty_output("tls", "world", params, poses, poses.copy(), None)

    k = len(dirs_local)
    parts: list[dict[str, NDArray[Any]]] = []
    cos_max = np.cos(np.radians(max_inc))
    with progress("Laser scanning", total=k * len(poses)) as advance:
        for s, pose in enumerate(poses):
            dirs_all = dirs_local @ pose[:3, :3].T
            for start in range(0, k, CHUNK_RAYS):
                dirs = dirs_all[start : start + CHUNK_RAYS]
                origin = np.broadcast_to(pose[:3, 3], dirs.shape)
                rng_t, tri = caster.cast(origin, dirs)
                idx = np.flatnonzero((tri >= 0) & (rng_t >= min_range) & (rng_t <= max_range))
                d = dirs[idx]
                normal, cos_inc = _facing(caster.normal[tri[idx]], d)
                seen = cos_inc >= cos_max
                idx, d, normal, cos_inc = idx[seen], d[seen], normal[seen], cos_inc[seen]
                r = rng_t[idx] + rng.normal(0.0, noise_sigma, len(idx))
                t_idx = tri[idx]
                base = caster.color[t_idx]
                reflectance = 0.1 + 0.8 * (base @ _LUMA) / 255
                intensity = reflectance * cos_inc + rng.normal(0.0, TLS_INTENSITY_NOISE, len(idx))
                part = {
                    "xyz": pose[:3, 3] + d * r[:, None],
                    "rgb": _shade(base, normal, -d, rng, color_noise),
                    "triangle": t_idx.astype(np.int32),
                    "intensity": np.clip(intensity, 0, 1).astype(np.float32),
                    "station": np.full(len(idx), s, np.int32),
                }
                if normals:
                    part["normal"] = normal
                parts.append(part)
                advance(len(dirs))
    cat = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
    cloud = _labelled_cloud(
        caster,
        cat["xyz"],
        cat["rgb"],
        cat["triangle"],
        normals=cat.get("normal"),
        extra={"intensity": cat["intensity"], "station": cat["station"]},
        meta={"sensor": "tls"},
    )
    return SensorOutput(cloud, "tls", "world", params, poses, poses.copy(), cat["triangle"])


# ----------------------------------------------------------------------------------------
# monocular SLAM
# ----------------------------------------------------------------------------------------
#: Camera settings the monocular SLAM simulation accepts.
MONOCULAR_CAMERA_OPTIONS = frozenset(
    {"width", "height", "fx", "fy", "cx", "cy", "min_range", "max_range", "stride", "color_noise"}
)


def scan_monocular_slam(
    scene: Scene,
    *,
    num_frames: int = 30,
    scale: float | None = None,
    noise: float = 0.005,
    outlier_ratio: float = 0.03,
    texture: float = 0.05,
    drift: float = 0.0,
    odometry_noise: float = ODOMETRY_NOISE,
    poses: ArrayLike | None = None,
    rng: int | np.random.Generator | None = None,
    **camera: Any,
) -> SensorOutput:
    """A semi-dense monocular SLAM map (LSD-SLAM / ORB-SLAM style) at an unknown scale.

    Semi-dense trackers keep pixels with a strong image gradient, so points
    concentrate on edges: object silhouettes, depth discontinuities, creases
    and colour boundaries (each kept with probability ``SLAM_EDGE_KEEP``);
    elsewhere a surface yields points only through its texture (probability
    ``texture``). Depth is estimated by small-baseline stereo, so the error is
    Gaussian in inverse depth: depth std ``noise * z**2``. A fraction
    ``outlier_ratio`` of the points get a wrong depth along their ray (uniform
    in inverse depth between ``min_range`` and ``max_range``): they are
    labelled instance 0, class 0. Finally everything is multiplied by the
    unknown map scale ``s``.

    The robot's wheel odometry measures the trajectory's length ``D_e``
    (metres, relative error ``odometry_noise``) while the map gives ``D_s``
    (map units), so ``k_s = D_e / D_s`` recovers the scale (thesis §3.2).

    Parameters
    ----------
    scene : Scene
    num_frames : int
        Keyframes on the :func:`camera_trajectory`.
    scale : float, optional
        Map units per metre; drawn log-uniformly in ``SLAM_SCALE_RANGE`` when None.
    noise : float
        Inverse-depth noise std (1/m).
    outlier_ratio : float
        Share of points with a wrong depth.
    texture : float
        Probability that a pixel off any edge yields a point.
    drift : float
        Per-keyframe random-walk pose error (metres), as in :func:`scan_rgbd_trajectory`.
    odometry_noise : float
        Relative std of the odometry distance.
    poses : (m, 4, 4) float, optional
        Camera-to-world poses to use instead of the default loop.
    rng : int or Generator, optional
    **camera
        :class:`RGBDSensor` image parameters: ``width``, ``height``, ``fx``, ``fy``,
        ``min_range`` (default 0.3), ``max_range`` (default 6), ``stride``
        (default 2), ``color_noise``.

    Returns
    -------
    SensorOutput
        ``frame == "map"`` (world times ``scale``), with ``odometry_distance``
        (D_e), ``slam_distance`` (D_s) and ``scale_factor`` (k_s).

    Examples
    --------
    >>> from ontodetect.synth.scene import Scene
    >>> out = scan_monocular_slam(Scene("office", (4.0, 3.0, 2.6), [], 0), num_frames=3,
    ...                           scale=2.0, rng=0)
    >>> round(out.scale_factor * out.scale, 1)
    1.0
    """
    scene = _check_scene(scene)
    allowed = MONOCULAR_CAMERA_OPTIONS
    unknown = sorted(set(camera) - allowed)
    if unknown:
        raise InvalidParameterError(unknown[0], f"one of {sorted(allowed)}", camera[unknown[0]])
    camera.setdefault("min_range", 0.3)
    camera.setdefault("max_range", 6.0)
    camera.setdefault("stride", 2)
    # The geometry of what the camera sees, without the RGB-D sensor's depth artefacts.
    cam = RGBDSensor(
        **camera,
        noise=(0.0, 0.0),
        disparity_step=0.0,
        baseline=0.0,
        max_incidence_deg=90.0,
        edge_dropout=0.0,
        dropout=0.0,
    )
    noise = _check_number("noise", noise)
    outlier_ratio = _check_number("outlier_ratio", outlier_ratio, high=1)
    texture = _check_number("texture", texture, high=1)
    drift = _check_number("drift", drift)
    odometry_noise = _check_number("odometry_noise", odometry_noise)
    rng = np.random.default_rng(rng)
    if scale is None:
        lo, hi = np.log(SLAM_SCALE_RANGE)
        scale = float(np.exp(rng.uniform(lo, hi)))
    scale = _check_number("scale", scale, low_open=True)
    true_poses = (
        camera_trajectory(scene, num_frames, rng=rng) if poses is None else _check_poses(poses)
    )
    est = _drifted(true_poses, drift, rng)
    length = _path_length(true_poses)
    d_e = length * (1.0 + rng.normal(0.0, odometry_noise))
    d_s = scale * _path_length(est)
    params = {
        "num_frames": len(true_poses),
        "scale": scale,
        "noise": noise,
        "outlier_ratio": outlier_ratio,
        "texture": texture,
        "drift": drift,
        "odometry_noise": odometry_noise,
        **{k: v for k, v in cam.parameters().items() if k in allowed},
    }
    caster = _caster(scene)
    if caster is None:
        return _empty_output(
            "monocular",
            "map",
            params,
            true_poses,
            est,
            cam.intrinsics(),
            scale=scale,
            d_e=d_e,
            d_s=d_s,
        )
    u, v = cam.grid
    gw, gh = len(u), len(v)
    r = cam.render(caster, true_poses, rng, shade=False)
    frame, pixel, tri = r["frame"], r["pixel"], r["triangle"]

    # Edge pixels, from images of instance, depth, normal and material colour.
    m = len(true_poses)
    flat = frame.astype(np.int64) * (gw * gh) + pixel
    inst_img = np.full(m * gw * gh, -1, np.int64)
    inst_img[flat] = caster.instance[tri]
    depth_img = np.full(m * gw * gh, np.inf)
    depth_img[flat] = r["camera"][:, 2]
    normal_img = np.zeros((m * gw * gh, 3))
    normal_img[flat] = r["normal"]
    color_img = np.zeros((m * gw * gh, 3))
    color_img[flat] = caster.color[tri]
    shape = (m, gh, gw)
    edge = np.zeros(shape, bool)
    cos_crease = np.cos(np.radians(CREASE_ANGLE_DEG))
    inst_img, depth_img = inst_img.reshape(shape), depth_img.reshape(shape)
    normal_img, color_img = normal_img.reshape(*shape, 3), color_img.reshape(*shape, 3)
    for axis in (1, 2):
        a = [slice(None)] * 3
        b = [slice(None)] * 3
        a[axis], b[axis] = slice(None, -1), slice(1, None)
        a, b = tuple(a), tuple(b)
        za, zb = depth_img[a], depth_img[b]
        with np.errstate(invalid="ignore"):
            jump = np.abs(za - zb) > EDGE_JUMP_PER_PIXEL * cam.stride * np.minimum(za, zb)
        diff = (
            (inst_img[a] != inst_img[b])
            | jump
            | (np.einsum("...i,...i->...", normal_img[a], normal_img[b]) < cos_crease)
            | (np.linalg.norm(color_img[a] - color_img[b], axis=-1) > COLOR_EDGE)
        )
        edge[a] |= diff
        edge[b] |= diff
    on_edge = edge.ravel()[flat]
    keep = rng.random(len(flat)) < np.where(on_edge, SLAM_EDGE_KEEP, texture)

    z = r["camera"][keep, 2]
    dirs_cam = r["camera"][keep] / z[:, None]
    inv = 1.0 / z + rng.normal(0.0, noise, len(z))
    outlier = rng.random(len(z)) < outlier_ratio
    inv[outlier] = rng.uniform(
        1.0 / cam.max_range, 1.0 / max(cam.min_range, 1e-3), int(outlier.sum())
    )
    # Inverse depths at or below zero are points at infinity, which trackers discard.
    good = inv > 1.0 / (2 * cam.max_range)
    fr = frame[keep][good]
    cam_pts = dirs_cam[good] / inv[good, None]
    xyz = np.einsum("nij,nj->ni", est[fr, :3, :3], cam_pts) + est[fr, :3, 3]
    tri_kept = np.where(outlier[good], -1, tri[keep][good]).astype(np.int32)
    sel = np.flatnonzero(keep)[good]
    rgb = _shade(
        caster.color[tri[sel]], r["normal"][sel], r["to_camera"][sel], rng, cam.color_noise
    )
    cloud = _labelled_cloud(
        caster, xyz * scale, rgb, tri_kept, extra={"frame": fr}, meta={"sensor": "monocular"}
    )
    return SensorOutput(
        cloud,
        "monocular",
        "map",
        params,
        true_poses,
        est,
        tri_kept,
        intrinsics=cam.intrinsics(),
        scale=scale,
        odometry_distance=d_e,
        slam_distance=d_s,
    )


# ----------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------
def _caster(scene: Scene) -> _Raycaster | None:
    """A ray caster, or None for a scene without triangles (every ray misses)."""
    if not any(len(obj.triangles) for obj in scene.objects):
        return None
    return _Raycaster(scene)


def _make_sensor(options: dict[str, Any]) -> RGBDSensor:
    allowed = set(RGBDSensor.__dataclass_fields__)
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise InvalidParameterError(unknown[0], f"one of {sorted(allowed)}", options[unknown[0]])
    return RGBDSensor(**options)


def _check_poses(poses: ArrayLike, name: str = "poses") -> NDArray[np.float64]:
    arr = np.asarray(poses, np.float64)
    if arr.ndim != 3 or arr.shape[1:] != (4, 4) or len(arr) == 0:
        raise InvalidParameterError(
            name, "an array of shape (m, 4, 4), m >= 1", f"shape {arr.shape}"
        )
    R = arr[:, :3, :3]
    if not np.all(np.isfinite(arr)) or not np.allclose(
        R @ R.transpose(0, 2, 1), np.eye(3), atol=1e-6
    ):
        raise InvalidParameterError(name, "rigid transforms (orthonormal rotation)", "other")
    return arr.copy()


def _empty_output(
    sensor: str,
    frame: str,
    params: dict[str, Any],
    poses: NDArray[np.float64],
    est: NDArray[np.float64],
    intrinsics: dict[str, Any] | None,
    meta: dict[str, Any] | None = None,
    *,
    scale: float = 1.0,
    d_e: float | None = None,
    d_s: float | None = None,
) -> SensorOutput:
    fields = {"instance": np.zeros(0, np.int32), "class_id": np.zeros(0, np.int32)}
    cloud = point_cloud(
        np.zeros((0, 3)),
        np.zeros((0, 3), np.uint8),
        None,
        fields,
        meta={"sensor": sensor, **(meta or {})},
    )
    return SensorOutput(
        cloud,
        sensor,
        frame,
        params,
        poses,
        est,
        np.zeros(0, np.int32),
        intrinsics=intrinsics,
        scale=scale,
        odometry_distance=d_e,
        slam_distance=d_s,
    )
