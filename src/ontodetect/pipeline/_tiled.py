"""Detection in a cloud too large for one process: tiles on the floor plane, one
:func:`detect` per tile, detections merged across tile borders.

1. **Survey** (:func:`~ontodetect.io._windows.survey_cloud`): one pass over the file, a
   chunk at a time, gives its size, its bounds and an even subsample; the floor, the up
   direction and the units are found once on the subsample
   (:class:`~ontodetect.preprocess.GroundPlane`) and shared with every tile.
2. **Tiles** (:func:`plan_tiles`): the floor plane is cut into square *cores* of edge
   ``tile`` (the outer ones open to infinity, so every point lies in exactly one core);
   a tile's *window* is its core grown by ``overlap`` on every side.
3. **Detect** (:func:`detect_tile`, a unit of work): a worker reads only its window's
   points (:func:`~ontodetect.io._windows.read_window`), runs :func:`detect` with the
   shared floor, and keeps the detections whose box centre lies in its core. An object
   whose centre lies in a core lies wholly inside that tile's window when the overlap is
   at least half its length (:func:`minimum_overlap`), with room to spare for what is
   around it (the wall behind, the table beside), so each tile sees its own objects as an
   untiled run would.
4. **Merge** (:func:`merge_tiles`): an object seen by two tiles whose centres fell on
   either side of a border (segmentation in two windows differs in small details) is
   reported once: of two detections that share more than :data:`MERGE_OVERLAP` of the
   smaller one's points, the higher score stays.

Detections index the rows of the input file, as :func:`detect`'s do. The tiles run
through an :class:`~ontodetect._executor.Executor`: in this process, or as tasks of a
Dask cluster whose workers read the file from storage they all see.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import os
import resource
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._executor import DEFAULT_RETRIES, Executor, InProcess
from .._rules import COUNT, POSITIVE, Interval, Nullable, check_param
from ..cloud import PointCloud
from ..config import Config
from ..errors import InvalidParameterError
from ..io._detections import DETECTIONS_FORMAT
from ..io._windows import WINDOW_CHUNK_POINTS, Window, read_window, survey_cloud
from ..ontology import Ontology, builtin_ontology
from ..preprocess import GroundPlane, find_ground
from ._detect import detect
from ._result import Detection

__all__ = [
    "CONTEXT_MARGIN",
    "DEFAULT_OVERLAP",
    "DEFAULT_TILE",
    "MERGE_OVERLAP",
    "MIN_TILE_POINTS",
    "SAMPLE_POINTS",
    "Tile",
    "TileOutcome",
    "TileTask",
    "TiledResult",
    "detect_tile",
    "detect_tiled",
    "floor_axes",
    "largest_object",
    "merge_tiles",
    "minimum_overlap",
    "plan_tiles",
]

#: Edge of a tile's core (m).
DEFAULT_TILE = 10.0
#: Overlap (m) of a tile's window beyond its core on every side, unless the ontology
#: allows objects so large that :func:`minimum_overlap` asks for more.
DEFAULT_OVERLAP = 2.5
#: Room (m) beyond half the largest object: the surroundings segmentation looks at.
CONTEXT_MARGIN = 0.5
#: Two detections sharing more than this share of the smaller one's points are one object.
MERGE_OVERLAP = 0.5
#: Points of the subsample the shared floor, up direction and units are found on.
SAMPLE_POINTS = 2_000_000
#: A window with fewer points holds no object worth a detection run.
MIN_TILE_POINTS = 100
#: A whole number >= 1.
AT_LEAST_ONE = Interval(1, math.inf, "left", integer=True)


# -- tiles ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class Tile:
    """A core of the floor plane and the window around it (input units).

    Attributes
    ----------
    name : str
        ``tile_<row>_<column>``.
    lo, hi : (2,) float
        The core on the floor axes (``-inf``/``inf`` on the outer sides).
    overlap : float
        How far the window reaches beyond the core.
    """

    name: str
    lo: tuple[float, float]
    hi: tuple[float, float]
    overlap: float

    def window(self, axes: NDArray[np.float64]) -> Window:
        """The points this tile reads."""
        lo = np.asarray(self.lo) - self.overlap
        hi = np.asarray(self.hi) + self.overlap
        return Window(np.asarray(axes, dtype=np.float64), lo, hi)

    def in_core(self, uv: NDArray[np.float64]) -> NDArray[np.bool_]:
        """(n,) bool: which floor-plane coordinates (n, 2) lie in the core."""
        uv = np.atleast_2d(uv)
        return np.all((uv >= np.asarray(self.lo)) & (uv < np.asarray(self.hi)), axis=1)


def plan_tiles(lo: Sequence[float], hi: Sequence[float], tile: float, overlap: float) -> list[Tile]:
    """Square cores of edge ``tile`` covering the box ``lo``–``hi`` of the floor plane.

    The grid starts at ``lo``; the outer cores reach to infinity, so that every point
    of the plane (and every detection's centre) lies in exactly one core.

    Examples
    --------
    >>> [t.name for t in plan_tiles([0, 0], [25, 8], 10.0, 2.5)]
    ['tile_0_0', 'tile_0_1', 'tile_0_2']
    >>> plan_tiles([0, 0], [25, 8], 10.0, 2.5)[1].lo, plan_tiles([0, 0], [25, 8], 10.0, 2.5)[1].hi
    ((10.0, -inf), (20.0, inf))
    """
    check_param("tile", POSITIVE, tile)
    lo_a, hi_a = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    counts = [max(1, math.ceil((b - a) / tile - 1e-9)) for a, b in zip(lo_a, hi_a)]

    def edges(axis: int) -> list[tuple[float, float]]:
        n = counts[axis]
        cuts = [float(lo_a[axis] + k * tile) for k in range(1, n)]
        bounds = [-math.inf, *cuts, math.inf]
        return list(itertools.pairwise(bounds))

    tiles = []
    for r, (v0, v1) in enumerate(edges(1)):
        for c, (u0, u1) in enumerate(edges(0)):
            tiles.append(Tile(f"tile_{r}_{c}", (u0, v0), (u1, v1), float(overlap)))
    return tiles


def floor_axes(up: Sequence[float]) -> NDArray[np.float64]:
    """(2, 3) float: two orthonormal directions of the plane perpendicular to ``up``
    (x and y themselves when up is z).

    Examples
    --------
    >>> floor_axes([0, 0, 1]).tolist()
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    u = np.asarray(up, dtype=np.float64)
    u = u / np.linalg.norm(u)
    ref = np.eye(3)[int(np.argmin(np.abs(u)))] if abs(u[2]) < 0.9 else np.array([1.0, 0, 0])
    e1 = ref - (ref @ u) * u
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    axes = np.array([e1, e2])
    axes[np.abs(axes) < 1e-15] = 0.0
    return axes


def largest_object(ontology: Ontology | None = None, config: Config | None = None) -> float:
    """The longest object (m) the ontology's length constraints (of a class or of a part)
    and the configuration's cluster length (``cluster.length``, Table 4.1) allow.

    A plateau counts its upper end, a one-sided maximum its bound, a Gaussian its mean
    plus two σ; lower bounds do not limit length.

    Examples
    --------
    >>> largest_object()
    4.0
    """
    ontology = ontology or builtin_ontology()
    config = config or Config()
    longest = float(config.cluster.length[1])
    for cls in ontology.classes:
        rules = [cls.cluster.constraints] + [getattr(p, "constraints", {}) for p in cls.parts]
        for rule in rules:
            g = rule.get("length")
            if g is None:
                continue
            if g.side == "plateau" and g.upper is not None:
                longest = max(longest, float(g.upper))
            elif g.side == "max":
                longest = max(longest, float(g.mean))
            elif g.side == "both":
                longest = max(longest, float(g.mean + 2 * g.sigma))
    return longest


def minimum_overlap(ontology: Ontology | None = None, config: Config | None = None) -> float:
    """The least overlap (m) that keeps every object whose centre lies in a core wholly
    inside its tile's window: half the :func:`largest_object` plus
    :data:`CONTEXT_MARGIN`. 2.5 m for the built-in ontology (its tables reach 4 m)."""
    return largest_object(ontology, config) / 2 + CONTEXT_MARGIN


# -- one tile -----------------------------------------------------------------------------
@dataclass(frozen=True)
class TileTask:
    """A unit of work: which points to read and how to detect in them.

    Attributes
    ----------
    tile : Tile
    axes : (2, 3) float
        The floor plane's axes (:func:`floor_axes` of the shared up direction).
    plane : GroundPlane
        The floor, up direction and units shared by every tile.
    source : str or PointCloud
        A path every worker can read (the points are read there), or, for a cloud given
        in memory, the window's points themselves.
    format : str or None
        The file's format when it cannot be told from its name.
    options : dict
        Keyword arguments of :func:`detect` (``config``, ``ontology``, ``seed``...).
    chunk_points : int
        Rows read at a time.
    chunk_bounds : (k, 2, 3) float, optional
        Every chunk's box (:func:`~ontodetect.io._windows.survey_cloud`): chunks that miss
        the window are not read.
    """

    tile: Tile
    axes: NDArray[np.float64]
    plane: GroundPlane
    source: str | PointCloud
    format: str | None = None
    options: Mapping[str, Any] = field(default_factory=dict)
    chunk_points: int = WINDOW_CHUNK_POINTS
    chunk_bounds: NDArray[np.float64] | None = None


@dataclass(frozen=True)
class TileOutcome:
    """What one tile found: its detections (those centred in its core) and its costs.

    Attributes
    ----------
    name : str
    points : int
        Points in the window.
    found : int
        Detections in the whole window.
    detections : list of Detection
        Those whose centre lies in the core (rows of the input file).
    seconds : float
        Reading and detection.
    peak_rss : int
        Peak resident memory (bytes) of the process that ran it, so far.
    worker : str
        Host and process id.
    """

    name: str
    points: int
    found: int
    detections: list[Detection]
    seconds: float
    peak_rss: int
    worker: str

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "points": self.points,
            "found": self.found,
            "kept": len(self.detections),
            "seconds": round(self.seconds, 3),
            "peak_rss": self.peak_rss,
            "worker": self.worker,
        }


def _peak_rss() -> int:
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(peak if sys.platform == "darwin" else peak * 1024)  # KiB on Linux


def detect_tile(task: TileTask) -> TileOutcome:
    """Read one tile's window, detect in it with the shared floor, keep what is centred
    in its core (the function every worker runs)."""
    t0 = time.perf_counter()
    window = task.tile.window(task.axes)
    if isinstance(task.source, PointCloud):
        cloud = task.source
    else:
        cloud = read_window(task.source, window, format=task.format, chunk_points=task.chunk_points)
    kept: list[Detection] = []
    found = 0
    points = 0 if cloud is None else len(cloud)
    if cloud is not None and points >= MIN_TILE_POINTS:
        result = detect(cloud, plane=task.plane, **dict(task.options))
        found = len(result.detections)
        if found:
            centres = np.array([d.center for d in result.detections]) @ task.axes.T
            inside = task.tile.in_core(centres)
            kept = [d for d, ok in zip(result.detections, inside) if ok]
    return TileOutcome(
        task.tile.name,
        points,
        found,
        kept,
        time.perf_counter() - t0,
        _peak_rss(),
        f"{os.uname().nodename}:{os.getpid()}",
    )


# -- merging ------------------------------------------------------------------------------
def _shared(a: NDArray[np.int64], b: NDArray[np.int64]) -> int:
    return len(np.intersect1d(a, b, assume_unique=True))


def merge_tiles(outcomes: Sequence[TileOutcome]) -> tuple[list[Detection], list[str], int]:
    """Every tile's detections, each object once, numbered by decreasing score.

    Of two detections (of any classes, from different tiles) sharing more than
    :data:`MERGE_OVERLAP` of the smaller one's points, the one with the higher score stays
    (ties: the earlier tile).

    Returns
    -------
    detections : list of Detection
        Numbered 1, 2, ... by decreasing score.
    tiles : list of str
        The tile each detection came from.
    merged : int
        Duplicates dropped.
    """
    pool = [(d, t, k) for t, o in enumerate(outcomes) for k, d in enumerate(o.detections)]
    pool.sort(key=lambda e: (-e[0].score, e[1], e[2]))
    kept: list[tuple[Detection, int]] = []
    merged = 0
    for d, t, _ in pool:
        half = np.asarray(d.size) / 2
        duplicate = False
        for e, s in kept:
            if s == t:
                continue
            # Far apart boxes share no point: only near ones are compared.
            if np.any(np.abs(np.asarray(d.center) - e.center) > half + np.asarray(e.size) / 2):
                continue
            small = min(len(d.point_indices), len(e.point_indices))
            if small and _shared(d.point_indices, e.point_indices) > MERGE_OVERLAP * small:
                duplicate = True
                break
        if duplicate:
            merged += 1
            continue
        kept.append((d, t))
    detections = [dataclasses.replace(d, id=i + 1) for i, (d, _) in enumerate(kept)]
    return detections, [outcomes[t].name for _, t in kept], merged


# -- the whole cloud ----------------------------------------------------------------------
@dataclass
class TiledResult:
    """What :func:`detect_tiled` found.

    Attributes
    ----------
    source : str
        The input (a path, or the cloud's ``meta["source"]``).
    num_points : int
        Rows of the input.
    plane : GroundPlane
        The floor every tile shared.
    detections : list of Detection
        Every object once, rows of the input file, numbered by decreasing score.
    detection_tiles : list of str
        The tile each detection came from.
    tiles : list of TileOutcome
        Per tile: points, detections, time, worker memory.
    merged : int
        Detections dropped as duplicates of another tile's.
    class_names : list of str
        Labels of the ontology used.
    timings : dict of str to float
        Seconds of the survey, the tiles (wall time) and the merge.
    workers : int
        Tiles that could run at the same time.
    """

    source: str
    num_points: int
    plane: GroundPlane
    detections: list[Detection]
    detection_tiles: list[str]
    tiles: list[TileOutcome]
    merged: int
    class_names: list[str]
    timings: dict[str, float] = field(default_factory=dict)
    workers: int = 1
    tile_size: float = DEFAULT_TILE
    overlap: float = DEFAULT_OVERLAP

    @property
    def frame(self) -> dict[str, Any]:
        return {
            "up": [round(float(v), 6) for v in self.plane.up],
            "ground_z": round(float(self.plane.height), 6),
            "scale": round(float(self.plane.scale), 9),
        }

    @property
    def peak_rss(self) -> int:
        """The largest peak resident memory (bytes) of any process that ran a tile."""
        return max((t.peak_rss for t in self.tiles), default=0)

    def to_dict(self) -> dict[str, Any]:
        """The ``detections.json`` document, with ``tiling`` (tiles, overlap, workers) and
        each detection's ``tile``."""
        detections = []
        for d, name in zip(self.detections, self.detection_tiles):
            doc = d.to_dict()
            doc["tile"] = name
            detections.append(doc)
        return {
            "format": DETECTIONS_FORMAT,
            "source": self.source,
            "num_points": self.num_points,
            "frame": self.frame,
            "detections": detections,
            "classes": list(self.class_names),
            "tiling": {
                "tile": self.tile_size,
                "overlap": self.overlap,
                "workers": self.workers,
                "merged": self.merged,
                "tiles": [t.to_dict() for t in self.tiles],
            },
            "timings": {k: round(v, 4) for k, v in self.timings.items()},
        }


def _check_overlap(overlap: float | None, ontology: Ontology, config: Config) -> float:
    least = minimum_overlap(ontology, config)
    if overlap is None:
        return max(DEFAULT_OVERLAP, least)
    check_param("overlap", POSITIVE, overlap)
    if overlap < least - 1e-9:
        raise InvalidParameterError(
            "overlap",
            f"at least {least:g} m (half the longest object the ontology allows, "
            f"{largest_object(ontology, config):g} m, plus {CONTEXT_MARGIN:g} m)",
            overlap,
        )
    return float(overlap)


def detect_tiled(
    source: PointCloud | str | os.PathLike[str],
    *,
    tile: float = DEFAULT_TILE,
    overlap: float | None = None,
    executor: Executor | None = None,
    format: str | None = None,
    config: Config | None = None,
    ontology: Ontology | None = None,
    room: str | Mapping[str, float] | None = None,
    indoor: float | None = None,
    seed: int = 0,
    jobs: int | None = None,
    sample_points: int = SAMPLE_POINTS,
    chunk_points: int = WINDOW_CHUNK_POINTS,
    retries: int = DEFAULT_RETRIES,
) -> TiledResult:
    """Find objects in a cloud of any size, tile by tile (a building floor, a site).

    Parameters
    ----------
    source : PointCloud or path
        A file (binary PLY and LAS/LAZ are read a window at a time; other formats whole),
        on storage every worker of ``executor`` can read at the same path; or a cloud
        in memory (its windows then travel to the workers).
    tile : float
        Edge (m) of a tile's core on the floor plane.
    overlap : float, optional
        How far (m) each tile reads beyond its core; at least :func:`minimum_overlap`
        (default: :data:`DEFAULT_OVERLAP`, or that minimum when larger).
    executor : Executor, optional
        Where the tiles run (:func:`ontodetect._executor.open_executor`); in this
        process by default.
    format : str, optional
        The file's format, when its name does not tell.
    config, ontology, room, indoor, seed
        As for :func:`detect`, for every tile.
    jobs : int, optional
        :func:`detect`'s worker processes for the passes of a vote, in each tile (tiles on
        a cluster run their passes in their own worker).
    sample_points : int
        Size of the subsample the shared floor, up direction and units are found on.
    chunk_points : int
        Rows read at a time.
    retries : int
        Times a tile that failed runs again on a cluster.

    Returns
    -------
    TiledResult

    Raises
    ------
    ontodetect._executor.UnitsFailedError
        Tiles still failed after their retries; the message names them.

    Examples
    --------
    >>> from ontodetect.synth.building import building_floor
    >>> floor = building_floor(["tiny", "tiny"], points_per_room=20000, seed=3)
    >>> result = detect_tiled(floor, tile=3.0)
    >>> len(result.tiles), sorted({d.label for d in result.detections})
    (2, ['chair', 'table'])
    """
    t0 = time.perf_counter()
    config = config or Config()
    ontology = ontology or builtin_ontology()
    tile = check_param("tile", POSITIVE, tile)
    overlap_m = _check_overlap(overlap, ontology, config)
    check_param("sample_points", AT_LEAST_ONE, sample_points)
    jobs = check_param("jobs", Nullable(COUNT), jobs)
    executor = executor if executor is not None else InProcess()
    if not isinstance(executor, Executor):
        raise InvalidParameterError(
            "executor", "an ontodetect Executor (see open_executor)", type(executor).__name__
        )

    in_memory = isinstance(source, PointCloud)
    if in_memory:
        cloud = source
        if len(cloud) == 0:
            raise InvalidParameterError("source", "a cloud with at least one point", "0 points")
        step = max(1, -(-len(cloud) // sample_points))
        sample = cloud.select(np.arange(0, len(cloud), step))
        lo, hi = cloud.xyz.min(axis=0), cloud.xyz.max(axis=0)
        num_points = int(cloud.index.max()) + 1
        bounds = None
        name = str(cloud.meta.get("source", ""))
    else:
        path = Path(source)
        survey = survey_cloud(
            path, format=format, sample_points=sample_points, chunk_points=chunk_points
        )
        sample, lo, hi = survey.sample, survey.lo, survey.hi
        num_points, name = survey.num_points, str(path)
        bounds = survey.chunk_bounds
    plane = GroundPlane.from_ground(find_ground(sample, config))
    axes = floor_axes(plane.up)
    corners = np.array(np.meshgrid(*zip(lo, hi), indexing="ij")).reshape(3, -1).T @ axes.T
    # Tile sizes are metres; the cloud is in its own units (k_s converts to metres).
    tiles = plan_tiles(
        corners.min(axis=0), corners.max(axis=0), tile / plane.scale, overlap_m / plane.scale
    )
    survey_seconds = time.perf_counter() - t0

    options: dict[str, Any] = {
        "config": config,
        "ontology": ontology,
        "room": room,
        "indoor": indoor,
        "seed": seed,
    }
    if jobs is not None or not isinstance(executor, InProcess):
        options["jobs"] = 1 if jobs is None else jobs
    tasks = []
    for t in tiles:
        where: str | PointCloud = name
        if in_memory:
            inside = np.flatnonzero(t.window(axes).contains(cloud.xyz))
            if not len(inside):
                continue
            where = cloud.select(inside)
        elif bounds is not None and t.window(axes).misses(bounds).all():
            continue  # no chunk of the file reaches this tile
        tasks.append(TileTask(t, axes, plane, where, format, options, chunk_points, bounds))
    t1 = time.perf_counter()
    outcomes = executor.map(
        detect_tile,
        tasks,
        names=[t.tile.name for t in tasks],
        description="Tiles",
        retries=retries,
    )
    t2 = time.perf_counter()
    detections, origin, merged = merge_tiles(outcomes)
    return TiledResult(
        name,
        num_points,
        plane,
        detections,
        origin,
        list(outcomes),
        merged,
        sorted({c.label for c in ontology.classes}),
        {"survey": survey_seconds, "tiles": t2 - t1, "merge": time.perf_counter() - t2},
        executor.workers,
        float(tile),
        overlap_m,
    )
