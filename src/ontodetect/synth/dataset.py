"""Simulated scans with ground truth: generate, write and read back the synthetic dataset layout.

:func:`synthesize` builds a room (:func:`~ontodetect.synth.rooms.build_room`) and
scans it with a virtual sensor (:mod:`~ontodetect.synth.sensors`);
:func:`write_synth` writes the result as a folder::

    cloud.ply      the points: x y z, red green blue, instance, class_id
                   (+ intensity for the laser scanner, + pixel for a single frame)
    objects.json   every object: class, kind, oriented box, pose, dimensions, parts,
                   how many points it got
    scene.json     room, sensor and its parameters, seed, scale, trajectory
    mesh.ply       the scene's triangles with colours, instance and part per face
    frame.pcd      single-frame sensor only: the organized frame in the camera frame

:func:`load_synth` reads a folder back and :func:`synthesize_many` writes a
dataset of numbered scenes. The same arguments give byte-identical files.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import re
from collections import Counter
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._progress import progress
from .._version import __version__
from ..cloud import PointCloud
from ..errors import CorruptFileError, InvalidParameterError, ReadError
from ..io import atomic_write, atomic_write_text, make_folder, read_cloud, write_cloud
from . import sensors as _sensors
from .rooms import ROOM_TYPES, build_room
from .scene import CLASS_IDS, OrientedBox, Scene, SceneObject
from .sensors import SENSORS, SensorOutput

__all__ = [
    "SYNTH_FORMAT",
    "SynthResult",
    "load_synth",
    "room_types",
    "sensor_options",
    "synthesize",
    "synthesize_many",
    "write_synth",
]

#: Value of the ``format`` key of scene.json; the number changes when keys change meaning.
SYNTH_FORMAT = "ontodetect.synth/1"
OBJECTS_FORMAT = "ontodetect.synth.objects/1"
#: Decimals kept for floats in the JSON files (nanometres and nanoradians).
JSON_DECIMALS = 9

# -- reaching a requested number of points ----------------------------------------------
#: Scan this much more than asked, then subsample to exactly the number asked.
POINTS_MARGIN = 1.15
#: Cameras are not subsampled below one ray per this many pixels...
MAX_STRIDE = 8
#: ...rather, fewer frames are taken, but at least this many.
MIN_FRAMES = 4
PROBE_STRIDE = 8  # RGB-D probe: one ray per 8 x 8 pixels
PROBE_RES_DEG = 2.0  # laser probe: one ray per 2 degrees
PROBE_FRAMES = 4  # monocular probe: keyframes


@dataclasses.dataclass(frozen=True, eq=False)
class SynthResult:
    """A simulated scene and what a sensor saw of it.

    Attributes
    ----------
    scene : Scene
        The room and its objects (meshes in the world frame, metres).
    output : SensorOutput
        The points (labelled per point) and the sensor's poses and parameters.
    room : str
        Room type.
    seed : int
        The seed everything was drawn from.
    clutter : float
        Clutter factor the room was built with.
    """

    scene: Scene
    output: SensorOutput
    room: str
    seed: int
    clutter: float

    @property
    def sensor(self) -> str:
        return self.output.sensor

    @property
    def cloud(self) -> PointCloud:
        """The points as the sensor returns them (see ``output.frame``), in the order
        ``cloud.ply`` stores them: ``index`` is the row in that file."""
        cloud = self.output.cloud
        return cloud if cloud.is_complete else cloud.replace(index=None)

    def objects_by_class(self, *, seen_only: bool = False) -> dict[str, int]:
        """Number of furniture objects (not floor, walls...) per class, sorted by class name."""
        seen = set(np.unique(self.cloud.fields["instance"]).tolist()) if seen_only else None
        counts = Counter(
            o.class_name
            for o in self.scene.objects
            if not o.is_structure and (seen is None or o.instance_id in seen)
        )
        return dict(sorted(counts.items()))

    def summary(self) -> str:
        """One line: room, sensor, seed, points and objects by class."""
        objs = self.objects_by_class()
        unseen = sum(objs.values()) - sum(self.objects_by_class(seen_only=True).values())
        text = ", ".join(f"{n} {c}" for c, n in objs.items()) or "no objects"
        tail = f" ({unseen} unseen)" if unseen else ""
        return (
            f"{self.room}/{self.sensor} seed {self.seed}: {len(self.cloud):,} points; {text}{tail}"
        )


def room_types() -> tuple[str, ...]:
    """The room types :func:`synthesize` accepts (those of :mod:`ontodetect.synth.rooms`)."""

    return tuple(ROOM_TYPES)


def _build_scene(room: str, seed: int, clutter: float) -> Scene:

    return build_room(room, seed, clutter=clutter)


# ----------------------------------------------------------------------------------------
# synthesize
# ----------------------------------------------------------------------------------------
_SCANNERS: dict[str, Callable[..., SensorOutput]] = {
    "rgbd": _sensors.scan_rgbd_trajectory,
    "rgbd-frame": _sensors.scan_rgbd_frame,
    "tls": _sensors.scan_tls,
    "monocular": _sensors.scan_monocular_slam,
}
_CAMERA_OPTIONS = {f.name for f in dataclasses.fields(_sensors.RGBDSensor)}
_MONOCULAR_CAMERA = _sensors.MONOCULAR_CAMERA_OPTIONS


def sensor_options(sensor: str) -> list[str]:
    """Names of the options a sensor takes (keyword arguments of :func:`synthesize`)."""
    fn = _SCANNERS[sensor]
    names = {
        p.name
        for p in inspect.signature(fn).parameters.values()
        if p.kind is inspect.Parameter.KEYWORD_ONLY
    } - {"rng"}
    if sensor in ("rgbd", "rgbd-frame"):
        names |= _CAMERA_OPTIONS
    elif sensor == "monocular":
        names |= _MONOCULAR_CAMERA
    return sorted(names)


def _streams(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """Independent generators for the sensor and for the point-count probe.

    The room builder gets ``seed`` itself; the sensor's streams are spawned
    from it so that they never repeat the room's random numbers.
    """
    main, probe = np.random.SeedSequence(seed).spawn(2)
    return np.random.default_rng(main), np.random.default_rng(probe)


def synthesize(
    room: str | Scene = "office",
    sensor: str = "rgbd",
    seed: int = 0,
    *,
    points: int | None = None,
    clutter: float = 1.0,
    **sensor_opts: Any,
) -> SynthResult:
    """Build a room and scan it with a virtual sensor.

    Parameters
    ----------
    room : str or Scene
        A room type (see :func:`room_types`: ``"office"``, ``"conference"``,
        ``"living_room"``, ``"tiny"`` ...) or a ready :class:`Scene`.
    sensor : str
        ``"rgbd"`` (camera walked around the room, frames fused),
        ``"rgbd-frame"`` (one organized camera frame), ``"tls"`` (laser
        scanner) or ``"monocular"`` (semi-dense monocular SLAM map, unknown scale).
    seed : int
        Seed of the room and of the sensor; the same seed gives the same result.
    points : int, optional
        Approximate number of points wanted. Frames, stride or angular
        resolution are chosen to scan a bit more, then points are subsampled
        at random to exactly this many (a single frame keeps its grid: its
        stride is chosen to come closest). If the scene cannot give that many
        at the finest setting, fewer come back.
    clutter : float
        Passed to the room builder (more or fewer small objects).
    **sensor_opts
        Options of the sensor function (:func:`~ontodetect.synth.sensors.scan_rgbd_trajectory`,
        :func:`~ontodetect.synth.sensors.scan_rgbd_frame`,
        :func:`~ontodetect.synth.sensors.scan_tls`,
        :func:`~ontodetect.synth.sensors.scan_monocular_slam`); see
        :func:`sensor_options`.

    Returns
    -------
    SynthResult

    Examples
    --------
    >>> from ontodetect.synth.scene import Scene
    >>> r = synthesize(Scene("office", (4.0, 3.0, 2.6), [], 0), "rgbd", seed=1)
    >>> r.summary()
    'office/rgbd seed 1: 0 points; no objects'
    """
    if sensor not in SENSORS:
        raise InvalidParameterError("sensor", f"one of {', '.join(SENSORS)}", sensor)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidParameterError("seed", "a non-negative integer", seed)
    seed = int(seed)
    if points is not None and (
        isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 1
    ):
        raise InvalidParameterError("points", "a positive integer", points)
    if (
        isinstance(clutter, bool)
        or not isinstance(clutter, (int, float))
        or not (math.isfinite(clutter) and clutter >= 0)
    ):
        raise InvalidParameterError("clutter", "a number >= 0", clutter)
    allowed = sensor_options(sensor)
    for name in sensor_opts:
        if name not in allowed:
            raise InvalidParameterError(
                name,
                f"an option of the {sensor!r} sensor ({', '.join(allowed)})",
                sensor_opts[name],
            )

    if isinstance(room, Scene):
        scene, room_name = room, room.room_type
    else:
        kinds = room_types()
        if room not in kinds:
            raise InvalidParameterError("room", f"one of {', '.join(kinds)}", room)
        scene, room_name = _build_scene(room, seed, float(clutter)), room

    rng, probe_rng = _streams(seed)
    opts = dict(sensor_opts)
    if points is not None:
        opts = _options_for_points(scene, sensor, int(points), opts, probe_rng)
    output = _SCANNERS[sensor](scene, rng=rng, **opts)
    if points is not None and sensor != "rgbd-frame" and len(output.cloud) > points:
        keep = np.sort(rng.choice(len(output.cloud), int(points), replace=False))
        output = dataclasses.replace(
            output,
            cloud=output.cloud.select(keep),
            triangle=output.triangle[keep],
            parameters={**output.parameters, "subsampled_to": int(points)},
        )
    return SynthResult(scene, output, room_name, seed, float(clutter))


def _grid_len(extent: int, stride: int) -> int:
    return -(-extent // stride)


def _options_for_points(
    scene: Scene, sensor: str, points: int, opts: dict[str, Any], rng: np.random.Generator
) -> dict[str, Any]:
    """Sensor options that give a bit more than ``points`` points (measured on a probe scan)."""
    opts = dict(opts)
    wanted = POINTS_MARGIN * points
    if sensor in ("rgbd", "rgbd-frame", "monocular"):
        cam = _sensors.RGBDSensor(**{k: v for k, v in opts.items() if k in _CAMERA_OPTIONS})
        w, h = cam.width, cam.height
    if sensor in ("rgbd", "rgbd-frame"):
        probe_opts = {**opts, "stride": PROBE_STRIDE}
        probe = _SCANNERS[sensor](scene, rng=rng, **probe_opts)
        frames = 1 if sensor == "rgbd-frame" else len(probe.poses)
        rays = frames * _grid_len(w, PROBE_STRIDE) * _grid_len(h, PROBE_STRIDE)
        per_ray = max(len(probe.cloud), 1) / rays
        if sensor == "rgbd-frame":
            if "stride" not in opts:
                strides = np.arange(1, MAX_STRIDE + 1)
                counts = per_ray * np.array([_grid_len(w, s) * _grid_len(h, s) for s in strides])
                opts["stride"] = int(strides[np.argmin(np.abs(np.log(counts / points)))])
            return opts
        rays_needed = wanted / per_ray
        fixed_frames = "num_frames" in opts or "poses" in opts
        if "stride" not in opts:
            s = int(np.sqrt(frames * w * h / rays_needed))
            opts["stride"] = int(np.clip(s, 1, MAX_STRIDE))
        if not fixed_frames:
            per_frame = _grid_len(w, opts["stride"]) * _grid_len(h, opts["stride"])
            opts["num_frames"] = max(MIN_FRAMES, math.ceil(rays_needed / per_frame))
        return opts
    if sensor == "tls":
        if "h_res_deg" in opts and "v_res_deg" in opts:
            return opts
        probe = _sensors.scan_tls(
            scene, rng=rng, **{**opts, "h_res_deg": PROBE_RES_DEG, "v_res_deg": PROBE_RES_DEG}
        )
        lo, hi = probe.parameters["elevation"]
        rays = probe.parameters["stations"] * _tls_rays(PROBE_RES_DEG, PROBE_RES_DEG, lo, hi)
        per_ray = max(len(probe.cloud), 1) / rays
        # Solve for a square angular step, then refine on the exact ray count.
        res = PROBE_RES_DEG * np.sqrt(per_ray * rays / wanted)
        while (
            res > 1e-3
            and probe.parameters["stations"] * per_ray * _tls_rays(res, res, lo, hi) < wanted
        ):
            res *= 0.98
        opts.setdefault("h_res_deg", float(res))
        opts.setdefault("v_res_deg", float(res))
        return opts
    # monocular: points grow with the number of keyframes.
    if "num_frames" in opts or "poses" in opts:
        return opts
    probe = _sensors.scan_monocular_slam(scene, rng=rng, **{**opts, "num_frames": PROBE_FRAMES})
    per_frame = max(len(probe.cloud), 1) / PROBE_FRAMES
    opts["num_frames"] = max(2, math.ceil(wanted / per_frame))
    return opts


def _tls_rays(h_res: float, v_res: float, lo: float, hi: float) -> int:
    return len(np.arange(0.0, 360.0, h_res)) * len(np.arange(lo, hi + 1e-9, v_res))


# ----------------------------------------------------------------------------------------
# writing
# ----------------------------------------------------------------------------------------
def _jsonable(value: Any) -> Any:
    """Plain JSON types; floats rounded to JSON_DECIMALS so files are stable and readable."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if not math.isfinite(v):
            return None
        v = round(v, JSON_DECIMALS)
        return 0.0 if v == 0 else v  # no "-0.0"
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, OrientedBox):
        return _jsonable(value.to_dict())
    return str(value)


_NUMBER_LIST = re.compile(r"\[\s*(-?[0-9][-+0-9.eE]*(?:,\s*-?[0-9][-+0-9.eE]*)*)\s*\]")


def _dump(path: Path, data: Any) -> None:
    text = json.dumps(_jsonable(data), indent=1)
    # Lists of numbers (vectors, matrix rows) on one line each: poses read as matrices.
    text = _NUMBER_LIST.sub(
        lambda m: "[" + ", ".join(m.group(1).split()).replace(",,", ",") + "]", text
    )
    atomic_write_text(path, text + "\n")


def _part_box(obj: SceneObject, part: int) -> dict[str, Any] | None:
    """Upright box of one part, in the object's yaw, as {center, size, yaw}."""
    tris = obj.triangles[obj.triangle_part == part]
    if len(tris) == 0:
        return None
    v = obj.vertices[np.unique(tris)]
    yaw = obj.yaw
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    local = v @ R  # world -> yaw-aligned axes (R is orthonormal)
    lo, hi = local.min(axis=0), local.max(axis=0)
    return OrientedBox(tuple(R @ ((lo + hi) / 2)), tuple(hi - lo), yaw).to_dict()


def _objects_json(result: SynthResult) -> list[dict[str, Any]]:
    scene, out = result.scene, result.output
    instance = np.asarray(out.cloud.fields["instance"])
    size = int(max([o.instance_id for o in scene.objects] + [0])) + 1
    per_instance = np.bincount(instance, minlength=size)
    # Points per part: the triangle each point came from names its object and part.
    num_triangles = sum(len(o.triangles) for o in scene.objects)
    hit = out.triangle[out.triangle >= 0]
    per_triangle = np.bincount(hit, minlength=num_triangles)
    objects = []
    offset = 0
    for obj in scene.objects:
        n = int(per_instance[obj.instance_id]) if obj.instance_id < size else 0
        mine = per_triangle[offset : offset + len(obj.triangles)]
        offset += len(obj.triangles)
        part_points = np.bincount(
            np.asarray(obj.triangle_part, np.int64), weights=mine, minlength=len(obj.part_names)
        )
        parts = {}
        for k, name in enumerate(obj.part_names):
            parts[name] = {
                "index": k,
                "triangles": int(np.count_nonzero(obj.triangle_part == k)),
                "box": _part_box(obj, k),
                "num_points": int(np.rint(part_points[k])),
            }
        entry = {
            "id": obj.instance_id,
            "class": obj.class_name,
            "class_id": obj.class_id,
            "kind": obj.kind,
            "structure": obj.is_structure,
            "box": obj.box.to_dict(),
            "pose": obj.pose,
            "dimensions": obj.dimensions,
            "parts": parts,
            "num_points": n,
            "seen": n > 0,
        }
        if obj.extra:
            entry["extra"] = obj.extra
        objects.append(entry)
    return objects


def _scene_json(result: SynthResult, files: list[str], num_points: int) -> dict[str, Any]:

    out = result.output
    data: dict[str, Any] = {
        "format": SYNTH_FORMAT,
        "version": __version__,
        "room_type": result.room,
        "size": list(result.scene.size),
        "seed": result.seed,
        "clutter": result.clutter,
        "sensor": {"name": out.sensor, "parameters": out.parameters},
        "intrinsics": out.intrinsics,
        # cloud.ply is in the world frame, or for monocular SLAM the world times ``scale``.
        "frame": "map" if out.frame == "map" else "world",
        "scale": out.scale,
        "odometry_distance": out.odometry_distance,
        "slam_distance": out.slam_distance,
        "scale_factor": out.scale_factor,
        "trajectory": out.poses,
        "num_points": num_points,
        "num_objects": len(result.scene.objects),
        "class_ids": CLASS_IDS,
        "files": files,
    }
    if not np.array_equal(out.poses, out.estimated_poses):
        data["estimated_trajectory"] = out.estimated_poses
    if result.scene.extra:
        data["scene_extra"] = result.scene.extra
    return data


def _mesh_ply_bytes(
    vertices: NDArray[np.float64],
    triangles: NDArray[np.int64],
    colors: NDArray[np.uint8],
    instance: NDArray[np.int32],
    part: NDArray[np.int64],
    comment: str,
) -> bytes:
    """A binary little-endian PLY mesh: vertex colours plus colour, instance and part per face."""
    nv, nt = len(vertices), len(triangles)
    vcol = np.zeros((nv, 3), np.uint8)
    if nt:
        # Each vertex takes the colour of the first face that uses it (deterministic).
        flat = triangles.ravel()
        used, first = np.unique(flat, return_index=True)
        vcol[used] = colors[first // 3]
    vdt = np.dtype(
        [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")]
    )
    fdt = np.dtype(
        [
            ("n", "u1"),
            ("v", "<i4", (3,)),
            ("red", "u1"),
            ("green", "u1"),
            ("blue", "u1"),
            ("instance", "<i4"),
            ("part", "<i4"),
        ]
    )
    vert = np.empty(nv, vdt)
    vert["x"], vert["y"], vert["z"] = vertices.T.astype(np.float32)
    vert["red"], vert["green"], vert["blue"] = vcol.T
    face = np.empty(nt, fdt)
    face["n"] = 3
    face["v"] = triangles
    face["red"], face["green"], face["blue"] = colors.T
    face["instance"], face["part"] = instance, part
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"comment {comment}\n"
        f"element vertex {nv}\n"
        "property float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        f"element face {nt}\n"
        "property list uchar int vertex_indices\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\n"
        "property int instance\nproperty int part\n"
        "end_header\n"
    )
    return header.encode("ascii") + vert.tobytes() + face.tobytes()


def _write_mesh(path: Path, objects: Sequence[SceneObject], comment: str) -> None:
    verts, tris, cols, inst, part = [], [], [], [], []
    offset = 0
    for obj in objects:
        verts.append(np.asarray(obj.vertices, np.float64))
        tris.append(np.asarray(obj.triangles, np.int64) + offset)
        cols.append(np.asarray(obj.triangle_color, np.uint8))
        inst.append(np.full(len(obj.triangles), obj.instance_id, np.int32))
        part.append(np.asarray(obj.triangle_part, np.int64))
        offset += len(obj.vertices)
    if not verts:
        data = _mesh_ply_bytes(
            np.zeros((0, 3)),
            np.zeros((0, 3), np.int64),
            np.zeros((0, 3), np.uint8),
            np.zeros(0, np.int32),
            np.zeros(0, np.int64),
            comment,
        )
    else:
        data = _mesh_ply_bytes(
            np.concatenate(verts),
            np.concatenate(tris),
            np.concatenate(cols),
            np.concatenate(inst),
            np.concatenate(part),
            comment,
        )
    with atomic_write(path, "wb") as fh:
        fh.write(data)


#: Per-point fields that go into cloud.ply (``frame`` and ``station`` stay in memory).
_PLY_FIELDS = ("instance", "class_id", "intensity", "pixel")


def write_synth(result: SynthResult, out_dir: str | Path, *, object_meshes: bool = False) -> Path:
    """Write a simulated scan in the synthetic dataset layout (see docs/synthetic-data.md).

    Parameters
    ----------
    result : SynthResult
        From :func:`synthesize`.
    out_dir : str or Path
        Folder to write into (created if needed); existing files of the layout
        are replaced, each atomically.
    object_meshes : bool
        Also write ``objects/<id>.ply``, one mesh per object.

    Returns
    -------
    Path
        The folder.
    """
    if not isinstance(result, SynthResult):
        raise InvalidParameterError(
            "result", "a SynthResult from synthesize()", type(result).__name__
        )
    out = make_folder(out_dir, "folder")
    sensor_out = result.output
    cloud = sensor_out.world_cloud()
    fields = {k: v for k, v in cloud.fields.items() if k in _PLY_FIELDS}
    if sensor_out.frame == "camera":
        fields["pixel"] = cloud.index.astype(np.int32)
    ply_cloud = cloud.replace(fields=fields, meta={"source": "synth"})
    files = ["cloud.ply", "objects.json", "scene.json", "mesh.ply"]
    write_cloud(out / "cloud.ply", ply_cloud, dtype="float32")
    if sensor_out.frame == "camera":
        # As depth cameras deliver frames: organized, NaN where no depth, LZF-compressed,
        # x y z rgb only (cloud.ply's ``pixel`` links the labels).
        frame = sensor_out.organized_cloud(fields=False)
        write_cloud(out / "frame.pcd", frame, data="binary_compressed")
        files.append("frame.pcd")
    comment = f"ontodetect synth {result.room} seed {result.seed}"
    _write_mesh(out / "mesh.ply", result.scene.objects, comment)
    if object_meshes:
        folder = make_folder(out / "objects", "folder")
        for obj in result.scene.objects:
            _write_mesh(
                folder / f"{obj.instance_id}.ply",
                [obj],
                f"ontodetect synth {obj.class_name} {obj.kind}",
            )
        files.append("objects/")
    _dump(out / "objects.json", {"format": OBJECTS_FORMAT, "objects": _objects_json(result)})
    _dump(out / "scene.json", _scene_json(result, files, len(ply_cloud)))
    return out


def synthesize_many(
    count: int,
    room: str | Sequence[str] = "office",
    sensor: str = "rgbd",
    seed: int = 0,
    *,
    out_dir: str | Path,
    points: int | None = None,
    clutter: float = 1.0,
    object_meshes: bool = False,
    on_scene: Callable[[int, SynthResult, Path], None] | None = None,
    **sensor_opts: Any,
) -> list[Path]:
    """Write ``count`` simulated scans into ``out_dir/scene_0000``, ``scene_0001``...

    Scene ``i`` uses seed ``seed + i`` and room type ``room`` (or
    ``room[i % len(room)]`` for a list of types). A progress bar shows when a
    reporter is installed; ``on_scene(i, result, folder)`` is called after each
    scene is written (the CLI prints its summary).

    Returns
    -------
    list of Path
        The scene folders.
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InvalidParameterError("count", "a positive integer", count)
    rooms = [room] if isinstance(room, (str, Scene)) else list(room)
    if not rooms:
        raise InvalidParameterError("room", "a room type or a non-empty list of them", room)
    names = [r for r in rooms if not isinstance(r, Scene)]
    if names:
        # Check every room type before writing anything.
        kinds = room_types()
        for name in names:
            if name not in kinds:
                raise InvalidParameterError("room", f"one of {', '.join(kinds)}", name)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidParameterError("seed", "a non-negative integer", seed)
    base = Path(out_dir)
    folders = []
    with progress("Synthesizing scenes", total=int(count)) as advance:
        for i in range(int(count)):
            result = synthesize(
                rooms[i % len(rooms)],
                sensor,
                int(seed) + i,
                points=points,
                clutter=clutter,
                **sensor_opts,
            )
            folder = write_synth(result, base / f"scene_{i:04d}", object_meshes=object_meshes)
            folders.append(folder)
            if on_scene is not None:
                on_scene(i, result, folder)
            advance(1)
    return folders


# ----------------------------------------------------------------------------------------
# reading
# ----------------------------------------------------------------------------------------
def _load_json(path: Path) -> Any:
    if not path.is_file():
        raise ReadError(path, "no such file (is the folder written by 'ontodetect synth'?)")
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise ReadError(path, f"cannot be read ({exc})") from exc
    except json.JSONDecodeError as exc:
        raise CorruptFileError(path, f"is not valid JSON (line {exc.lineno}: {exc.msg})") from exc
    except RecursionError:
        raise CorruptFileError(path, "is not valid JSON (nested too deeply)") from None


def load_synth(out_dir: str | Path) -> tuple[PointCloud, list[dict[str, Any]], dict[str, Any]]:
    """Read a folder written by :func:`write_synth`.

    Returns
    -------
    cloud : PointCloud
        cloud.ply, with fields ``instance`` and ``class_id`` (and ``intensity``,
        ``pixel`` when written); a single frame (``rgbd-frame``) carries the camera's
        position as ``meta["sensor_position"]`` and its image size as ``meta["width"]``
        and ``meta["height"]`` (see :func:`ontodetect.cloud.pixel_grid`).
    objects : list of dict
        objects.json's ``objects``: id, class, class_id, kind, structure, box,
        pose, dimensions, parts, num_points, seen.
    scene : dict
        scene.json.

    Raises
    ------
    ReadError
        A file is missing or unreadable, or is not of this layout.
    """
    folder = Path(out_dir)
    if not folder.is_dir():
        raise ReadError(folder, "no such folder")
    scene = _load_json(folder / "scene.json")
    fmt = scene.get("format") if isinstance(scene, dict) else None
    if not isinstance(fmt, str) or not fmt.startswith("ontodetect.synth/"):
        raise CorruptFileError(
            folder / "scene.json", f"'format' should be {SYNTH_FORMAT!r}, found {fmt!r}"
        )
    objects = _load_json(folder / "objects.json")
    if not isinstance(objects, dict) or not isinstance(objects.get("objects"), list):
        raise CorruptFileError(folder / "objects.json", "expected an object with an 'objects' list")
    cloud = read_cloud(folder / "cloud.ply")
    missing = [k for k in ("instance", "class_id") if k not in cloud.fields]
    if missing:
        raise CorruptFileError(
            folder / "cloud.ply", f"missing per-point field(s) {', '.join(missing)}"
        )
    fields = dict(cloud.fields)
    for k in ("instance", "class_id", "pixel"):
        if k in fields:
            fields[k] = np.asarray(fields[k]).astype(np.int32)
    cloud = cloud.replace(fields=fields)
    sensor = scene.get("sensor")
    trajectory = scene.get("trajectory")
    if isinstance(sensor, dict) and sensor.get("name") == "rgbd-frame" and trajectory:
        # One camera saw every point: detection may reason about what it could not see.
        try:
            eye = np.asarray(trajectory[0], dtype=np.float64)[:3, 3]
        except (TypeError, ValueError, IndexError) as err:
            raise CorruptFileError(
                folder / "scene.json", "'trajectory' should hold 4 x 4 camera poses"
            ) from err
        meta: dict[str, Any] = {"sensor_position": eye.tolist()}
        grid = scene.get("intrinsics") or {}
        if "pixel" in cloud.fields and "grid_width" in grid and "grid_height" in grid:
            meta.update(width=int(grid["grid_width"]), height=int(grid["grid_height"]))
        cloud = cloud.with_meta(**meta)
    return cloud, objects["objects"], scene
