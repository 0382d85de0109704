"""Evaluating a whole dataset: find its scenes, detect in each, match, aggregate.

A dataset is a folder in one of five layouts (or one scene of them):

- ``ontodetect``: what ``ontodetect synth`` writes, ``scene_0000/cloud.ply`` + ``objects.json``
  + ``scene.json`` (or one such folder);
- ``scannet-votenet``: many scans side by side, ``<scene>_vert.npy`` + ``_sem_label.npy`` +
  ``_ins_label.npy``;
- ``sunrgbd-votenet``: SUN RGB-D frames side by side, ``<id>_pc.npz`` + ``_bbox.npy``
  (points labelled by the oriented boxes that hold them);
- ``scannet``: a release scan folder (``*_vh_clean_2.ply`` + aggregation + segments), or a
  folder of them;
- ``s3dis``: a room folder holding ``Annotations/``, an area of rooms, or a folder of areas.

Each scene is an independent unit of work: :func:`evaluate_scene` reads it, runs
:func:`ontodetect.pipeline.detect` (or reads stored detections) and returns a
:class:`SceneOutcome`; :func:`summarize_outcomes` merges the outcomes in scene order into a
:class:`DatasetEvaluation`. :func:`evaluate_dataset` is that map and merge, run in worker
processes with ``jobs > 1`` or on a Dask cluster (an :class:`~ontodetect._executor.Executor`:
docs/cluster.md); any other engine that maps a function over a list can run it the same way
(docs/architecture.md, "Scale").
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import math
import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from .._executor import Executor, InProcess, executor_for
from .._parallel import cpu_count
from .._progress import progress
from ..cloud import PointCloud, sensor_position
from ..config import COUNT, Config, Interval, check_param
from ..errors import (
    CorruptFileError,
    InvalidParameterError,
    OntoDetectError,
)
from ..geometry import yaw_pose
from ..io import make_folder, read_cloud
from ..io._detections import read_detections, write_detections
from ..io._labels import NYU40_NAMES
from ..io._layouts import (
    DATASET_FORMATS,
    SceneSource,
    discover_scenes,
    scene_group,
)
from ..ontology import builtin_ontology
from ..pipeline import detect
from ..synth import load_synth
from ..synth.scene import CLASS_IDS
from ._boxes import BOX_IOU_THRESHOLDS, BoxInstance, box_average_precision, boxes_from_instances
from ._match import Instance, instances_from_labels
from ._metrics import Evaluation, SceneResult, evaluate_scenes

__all__ = [
    "CRITERIA",
    "DATASET_FORMATS",
    "DatasetEvaluation",
    "LoadedScene",
    "SceneError",
    "SceneOutcome",
    "SceneSource",
    "discover_scenes",
    "evaluate_dataset",
    "evaluate_scene",
    "evaluation_classes",
    "first_pass_clusters",
    "first_pass_lacks",
    "load_scene",
    "map_scenes",
    "read_scene_detections",
    "scene_boxes",
    "scene_group",
    "summarize_outcomes",
    "turn_cloud",
    "variant_name",
]

#: Other names accepted for a layout.
#: The three ways a detection is scored: key -> (criterion, IoU threshold) (docs/evaluation.md):
#: point IoU >= 0.25 counts, 0.5 is reported too; the centre distance of Günther et al.
CRITERIA: dict[str, tuple[str, float]] = {
    "iou@0.25": ("iou", 0.25),
    "iou@0.5": ("iou", 0.5),
    "distance": ("distance", 0.25),
}
#: The criterion reports lead with.
PRIMARY = "iou@0.25"
#: Format tag of the JSON form of a dataset evaluation.
EVALUATION_FORMAT = "ontodetect.evaluation/1"


class SceneError(OntoDetectError):
    """One scene of a dataset could not be evaluated; the message names the scene."""

    def __init__(self, scene: str, problem: str) -> None:
        self.scene = scene
        self.problem = problem
        super().__init__(f"scene {scene}: {problem}")

    def __reduce__(self) -> tuple[Any, ...]:
        return (SceneError, (self.scene, self.problem))


# -- loading -------------------------------------------------------------------------------
def _class_id_lists(ontology: Any, *, reported_only: bool, attr: str) -> dict[int, list[str]]:
    """Ground-truth class id -> every class (``attr`` of it) that matches it, in file order."""
    ids = {name: cid for name, cid in CLASS_IDS.items() if cid > 0}
    ids.update({name: cid for cid, name in NYU40_NAMES.items() if cid > 0})
    out: dict[int, list[str]] = {}
    for cls in ontology.classes:
        if reported_only and not cls.detect:
            continue
        for match in cls.matches:
            cid = ids.get(match.lower().replace("_", " "), ids.get(match.lower()))
            if cid is not None:
                names = out.setdefault(cid, [])
                if getattr(cls, attr) not in names:
                    names.append(getattr(cls, attr))
    return dict(sorted(out.items()))


def _class_ids(ontology: Any, *, reported_only: bool, attr: str) -> dict[int, str]:
    """Ground-truth class id -> the first class (``attr`` of it) that matches it."""
    lists = _class_id_lists(ontology, reported_only=reported_only, attr=attr)
    return {cid: names[0] for cid, names in lists.items()}


def evaluation_classes(ontology: Any = None) -> dict[int, str]:
    """Ground-truth class id -> evaluated class, from an ontology's ``matches``.

    Ids are NYU40 (ScanNet, and S3DIS as mapped by its reader) or the simulator's
    (:data:`ontodetect.synth.CLASS_IDS`). Only classes that are reported
    (``detect: true``) are evaluated, under their ``label``.

    Examples
    --------
    >>> evaluation_classes()
    {5: 'chair', 6: 'sofa', 7: 'table', 14: 'table'}
    """
    if ontology is None:
        ontology = builtin_ontology()
    return _class_ids(ontology, reported_only=True, attr="label")


@dataclass(frozen=True)
class LoadedScene:
    """A scene read from disk: the cloud and its ground-truth instances."""

    source: SceneSource
    cloud: PointCloud
    gts: list[Instance]
    gt_boxes: list[BoxInstance] = field(default_factory=list)

    @property
    def num_points(self) -> int:
        """Rows of the input file (what detections' ``point_indices`` index)."""
        return int(self.cloud.index.max()) + 1 if len(self.cloud) else 0


def read_scene_cloud(source: SceneSource) -> PointCloud:
    """The scene's points with per-point ``instance`` and ``class_id`` fields."""
    path = Path(source.path)
    if source.format == "ontodetect":
        cloud, objects, _ = load_synth(path)
        # The objects' oriented boxes are the simulator's ground-truth boxes (box AP).
        cloud = cloud.with_meta(boxes=objects)
    else:
        cloud = read_cloud(path, format=source.format)
    missing = [k for k in ("instance", "class_id") if k not in cloud.fields]
    if missing:
        raise CorruptFileError(path, f"has no per-point {' and '.join(missing)} labels")
    return cloud


def turn_cloud(cloud: PointCloud, degrees: float) -> PointCloud:
    """``cloud`` turned by ``degrees`` about the vertical (z) axis through the origin.

    Points keep their rows (and labels): a turned scan is the same room, met by other
    voxel boundaries. The sensor of a single view (``meta["sensor_position"]``) turns too.

    Examples
    --------
    >>> from ontodetect import point_cloud
    >>> turn_cloud(point_cloud([[1.0, 0.0, 0.5]]), 90).xyz.round(6).tolist()
    [[0.0, 1.0, 0.5]]
    """
    if not degrees:
        return cloud
    rot = yaw_pose(0.0, 0.0, math.radians(degrees))[:3, :3]
    normals = None if cloud.normals is None else cloud.normals @ rot.T
    out = cloud.replace(xyz=cloud.xyz @ rot.T, normals=normals)
    eye = sensor_position(cloud)  # the sensor of a single view turns with its points
    return out if eye is None else out.with_meta(sensor_position=(rot @ eye).tolist())


def load_scene(
    source: SceneSource, class_ids: Mapping[int, str] | None = None, *, turn: float = 0.0
) -> LoadedScene:
    """Read a scene and its ground-truth instances.

    Parameters
    ----------
    source : SceneSource
        From :func:`discover_scenes`.
    class_ids : mapping of int to str, optional
        Which class ids are evaluated and under which name; :func:`evaluation_classes`
        of the built-in ontology by default.
    turn : float
        Turn the scan by this many degrees about the vertical first (:func:`turn_cloud`);
        the instances' centres are those of the turned points.

    Returns
    -------
    LoadedScene
        Instances index the rows of the input file, like detections do.
    """
    cloud = turn_cloud(read_scene_cloud(source), turn)
    class_ids = evaluation_classes() if class_ids is None else class_ids
    gts = instances_from_labels(
        cloud.fields["instance"],
        cloud.fields["class_id"],
        class_ids,
        xyz=cloud.xyz,
        index=cloud.index,
    )
    return LoadedScene(source, cloud, gts, scene_boxes(cloud, gts, class_ids, turn=turn))


def scene_boxes(
    cloud: PointCloud,
    gts: Sequence[Instance],
    class_ids: Mapping[int, str],
    *,
    turn: float = 0.0,
) -> list[BoxInstance]:
    """The ground-truth boxes of a scene, for box AP.

    The boxes the dataset carries (``meta["boxes"]``: VoteNet's ScanNet ``*_bbox.npy``,
    axis-aligned; the simulator's objects.json, oriented), turned with the scan by
    ``turn`` degrees; without them, the axis-aligned box around each instance's points.
    """
    given = cloud.meta.get("boxes")
    if given is None:
        out = []
        for g in gts:
            xyz = cloud.xyz[np.isin(cloud.index, g.points)]
            if len(xyz):
                lo, hi = xyz.min(axis=0), xyz.max(axis=0)
                out.append(BoxInstance.make(g.label, (lo + hi) / 2, hi - lo))
        return out
    boxes = boxes_from_instances(given, class_ids)
    if not turn:
        return boxes
    rot = yaw_pose(0.0, 0.0, math.radians(turn))[:3, :3]
    return [
        BoxInstance.make(b.label, rot @ b.center, b.size, b.yaw + math.radians(turn)) for b in boxes
    ]


def read_scene_detections(
    detections_dir: str | os.PathLike[str],
    scene: str,
    num_points: int | None = None,
    *,
    boxes: bool = False,
) -> list[Instance] | tuple[list[Instance], list[BoxInstance]]:
    """Stored detections of one scene, ``<detections_dir>/<scene>/detections.json``.

    Parameters
    ----------
    num_points : int, optional
        Rows of the scene's input file; a document written for another scan is refused.
    boxes : bool
        Also return the detections' boxes (for box AP).
    """
    path = Path(detections_dir) / scene / "detections.json"
    doc = read_detections(path)
    if num_points is not None and doc["num_points"] != num_points:
        raise CorruptFileError(
            path,
            f"num_points is {doc['num_points']}, but scene {scene} has {num_points} points: "
            "these detections belong to another scan",
        )
    preds = [
        Instance.make(
            d["id"], d["label"], d["point_indices"], float(d["score"]), d["box"]["center"]
        )
        for d in doc["detections"]
    ]
    if not boxes:
        return preds
    return preds, [
        BoxInstance.make(
            d["label"], d["box"]["center"], d["box"]["size"], d["box"]["yaw"], d["score"]
        )
        for d in doc["detections"]
    ]


# -- one scene -----------------------------------------------------------------------------
@dataclass(frozen=True)
class SceneOutcome:
    """What evaluating one scene gave: detections, ground truth, times, or the error.

    Attributes
    ----------
    name : str
    source : SceneSource
    preds, gts : tuple of Instance
        Detections and ground-truth instances (rows of the input file).
    num_points : int
        Rows of the input file.
    seconds : float
        Time of the detection (0 when stored detections were read).
    load_seconds : float
        Time to read the scene (and stored detections).
    timings : dict of str to float
        Seconds per pipeline stage.
    error : str or None
        Why the scene failed; the other fields are then empty.
    turn : float or None
        Degrees the scan was turned by (see :func:`evaluate_dataset`'s ``turns``).
    seed : int or None
        The seed of this run (see :func:`evaluate_dataset`'s ``seeds``).
    pred_boxes, gt_boxes : tuple of BoxInstance
        The detections' boxes and the ground-truth boxes (:func:`scene_boxes`), for box AP.
    clusters : tuple of Instance
        The first pass's clusters (rows of the input file), each with the label that pass
        gave it ("" for none), to tell where a missed object went (empty for stored
        detections).
    cluster_lacks : tuple of dict
        Per cluster of ``clusters``, what its reading as each label lacked most
        (:func:`first_pass_lacks`).
    """

    name: str
    source: SceneSource
    preds: tuple[Instance, ...] = ()
    gts: tuple[Instance, ...] = ()
    num_points: int = 0
    seconds: float = 0.0
    load_seconds: float = 0.0
    timings: dict[str, float] = field(default_factory=dict)
    error: str | None = None
    turn: float | None = None
    seed: int | None = None
    pred_boxes: tuple[BoxInstance, ...] = ()
    gt_boxes: tuple[BoxInstance, ...] = ()
    clusters: tuple[Instance, ...] = ()
    cluster_lacks: tuple[dict[str, str], ...] = ()

    @property
    def ok(self) -> bool:
        return self.error is None

    def scene_result(self) -> SceneResult:
        return SceneResult(
            self.name,
            self.preds,
            self.gts,
            self.seconds,
            {"points": self.num_points, "load_seconds": self.load_seconds},
        )

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "scene": self.name,
            "format": self.source.format,
            "points": self.num_points,
            "seconds": round(self.seconds, 3),
            "load_seconds": round(self.load_seconds, 3),
            "detections": len(self.preds),
            "ground_truth": len(self.gts),
            "timings": {k: round(v, 4) for k, v in self.timings.items()},
        }
        if self.turn is not None:
            out["turn"] = self.turn
        if self.seed is not None:
            out["seed"] = self.seed
        if self.error is not None:
            out["error"] = self.error
        return out


@functools.cache
def _detect_keys() -> tuple[str, ...]:
    return tuple(p for p in inspect.signature(detect).parameters if p != "cloud")


def _check_detect_options(options: Mapping[str, Any] | None) -> dict[str, Any]:
    opts = dict(options or {})
    for key in opts:
        if key not in _detect_keys():
            raise InvalidParameterError(
                "detect_options", f"a mapping with keys among {', '.join(_detect_keys())}", key
            )
    return opts


def evaluate_scene(
    source: SceneSource,
    detect_options: Mapping[str, Any] | None = None,
    *,
    detections_dir: str | os.PathLike[str] | None = None,
    save_dir: str | os.PathLike[str] | None = None,
    class_ids: Mapping[int, str] | None = None,
    turn: float = 0.0,
    name: str | None = None,
) -> SceneOutcome:
    """Evaluate one scene: read it, detect (or read stored detections), keep both sides.

    A unit of work with plain, picklable inputs and output, for any map engine.
    Problems a user can cause (unreadable files, bad stored detections) do not
    raise: they come back in :attr:`SceneOutcome.error`.

    Parameters
    ----------
    source : SceneSource
    detect_options : mapping, optional
        Keyword arguments of :func:`ontodetect.pipeline.detect` (``config``,
        ``ontology``, ``room``, ``threshold``, ``seed``...).
    detections_dir : path, optional
        Read ``<detections_dir>/<scene>/detections.json`` instead of detecting.
    save_dir : path, optional
        Write this scene's ``detections.json`` to ``<save_dir>/<scene>/``.
    class_ids : mapping of int to str, optional
        Evaluated classes (default: :func:`evaluation_classes` of the ontology used).
    turn : float
        Detect in the scan turned by this many degrees about the vertical
        (:func:`turn_cloud`); not with ``detections_dir`` (stored detections were made
        on the scan as it is).
    name : str, optional
        Name of the outcome and of its folder under ``save_dir`` (default: the scene's).
    """
    opts = _check_detect_options(detect_options)
    check_param("turn", Interval(), turn)  # degrees, any finite angle
    if turn and detections_dir is not None:
        raise InvalidParameterError(
            "turn", "0 when scoring stored detections (they were made on the scan as it is)", turn
        )
    name = source.name if name is None else name
    if class_ids is None:
        class_ids = evaluation_classes(opts.get("ontology"))
    t0 = time.perf_counter()
    try:
        scene = load_scene(source, class_ids, turn=turn)
        clusters: list[Instance] = []
        lacks: list[dict[str, str]] = []
        if detections_dir is not None:
            preds, pred_boxes = read_scene_detections(
                detections_dir, source.name, scene.num_points, boxes=True
            )
            load = time.perf_counter() - t0
            seconds, timings = 0.0, {}
        else:
            load = time.perf_counter() - t0
            t1 = time.perf_counter()
            result = detect(scene.cloud, **opts)
            seconds = time.perf_counter() - t1
            timings = dict(result.timings)
            preds = [
                Instance.make(d.id, d.label, d.point_indices, d.score, d.center)
                for d in result.detections
            ]
            pred_boxes = [
                BoxInstance.make(d.label, d.center, d.size, d.yaw, d.score)
                for d in result.detections
            ]
            clusters = first_pass_clusters(result)
            lacks = first_pass_lacks(result)
            if save_dir is not None:
                _save_detections(result, Path(save_dir) / name)
    except OntoDetectError as exc:
        return SceneOutcome(name, source, error=str(exc))
    return SceneOutcome(
        name,
        source,
        tuple(preds),
        tuple(scene.gts),
        scene.num_points,
        seconds,
        load,
        timings,
        pred_boxes=tuple(pred_boxes),
        gt_boxes=tuple(scene.gt_boxes),
        clusters=tuple(clusters),
        cluster_lacks=tuple(lacks),
    )


def first_pass_clusters(result: Any) -> list[Instance]:
    """The first pass's clusters as instances labelled as that pass labelled them (the
    vote may have dropped the label since: the class it had stays in ``extra``)."""
    index = np.asarray(result.cloud.index)
    onto = result.ontology
    out = []
    for k, (c, choice) in enumerate(zip(result.segmentation, result.choices)):
        name = choice.extra.get("class")
        label = onto[name].label if name is not None and name in onto else ""
        out.append(Instance.make(k, label, index[c.point_indices]))
    return out


def first_pass_lacks(result: Any) -> list[dict[str, str]]:
    """Per cluster of the first pass, per label: the factor that weighed most against the
    cluster's best reading as that label, as ``part.feature``: ``seat.missing`` when the
    seat was left without a plane (none was fitted, or every plane that could be the seat
    did worse than the part's ``missing`` factor), else the measure that cost most
    (``cluster.breadth``, ``backrest~seat.distance``...). Of the classes with one label (a
    chair and an easy chair) the likelier reading speaks. The benchmark uses it to say why
    an object whose cluster holds it was read as something else."""
    onto = result.ontology
    out = []
    for scores in result.scores:
        best: dict[str, Any] = {}
        for name, s in scores.classes.items():
            label = onto[name].label if name in onto else name
            if label not in best or s.log_likelihood > best[label].log_likelihood:
                best[label] = s
        out.append({label: _weakest(s) for label, s in sorted(best.items())})
    return out


def _weakest(score: Any) -> str:
    """``part.feature`` of the smallest factor of a class reading ("" when it has none)."""
    if not score.constraints:
        return ""
    c = min(score.constraints, key=lambda c: c.factor)
    return f"{c.part}.{c.feature}"


def variant_name(scene: str, turn: float | None = None, seed: int | None = None) -> str:
    """Name of one run of a scene turned by ``turn`` degrees with ``seed``.

    Examples
    --------
    >>> variant_name("scene0000_00", 90.0, 1), variant_name("office_2", None, 0)
    ('scene0000_00@90deg-seed1', 'office_2@seed0')
    """
    parts = ([] if turn is None else [f"{turn:g}deg"]) + ([] if seed is None else [f"seed{seed}"])
    return f"{scene}@{'-'.join(parts)}" if parts else scene


def _evaluate_variant(
    unit: tuple[SceneSource, float | None, int | None],
    detect_options: Mapping[str, Any],
    **kwargs: Any,
) -> SceneOutcome:
    """:func:`evaluate_scene` of one scene turned and seeded (a unit of work); with
    neither, the scene as it is under its own name."""
    source, turn, seed = unit
    opts = dict(detect_options) if seed is None else {**detect_options, "seed": seed}
    outcome = evaluate_scene(
        source, opts, turn=turn or 0.0, name=variant_name(source.name, turn, seed), **kwargs
    )
    return dataclasses.replace(outcome, turn=turn, seed=seed)


def _check_variants(name: str, values: Sequence[Any] | None, kind: type) -> list[Any]:
    """The turns or seeds asked for: distinct finite numbers (seeds non-negative integers)."""
    if values is None:
        return []
    items = list(values)
    ok = bool(items) and len(set(items)) == len(items)
    for v in items:
        if kind is int:
            ok &= isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= 0
        else:
            ok &= (
                isinstance(v, (int, float, np.integer, np.floating))
                and not isinstance(v, bool)
                and math.isfinite(float(v))
            )
    if not ok:
        what = (
            "distinct non-negative integers" if kind is int else "distinct finite angles in degrees"
        )
        raise InvalidParameterError(name, f"a non-empty list of {what}", values)
    return [kind(v) for v in items]


def _save_detections(result: Any, folder: Path) -> None:
    make_folder(folder)
    doc = result.to_dict()
    doc["classes"] = result.class_names
    write_detections(folder / "detections.json", doc)


# -- the map over scenes -------------------------------------------------------------------
T = TypeVar("T")
R = TypeVar("R")


def _check_jobs(jobs: int) -> int:
    return check_param("jobs", COUNT, jobs) or cpu_count()  # 0: one per CPU


def map_scenes(
    fn: Callable[[T], R],
    units: Sequence[T],
    *,
    jobs: int = 1,
    description: str = "Scenes",
    executor: Executor | None = None,
    names: Sequence[str] | None = None,
) -> list[R]:
    """``[fn(u) for u in units]``, results in order: in this process, or through
    ``executor`` (a Dask cluster: :func:`ontodetect._executor.open_executor`), or on a
    local cluster of ``jobs`` workers when ``jobs > 1``.

    ``fn`` and the units must be picklable (a module-level function or a
    :func:`functools.partial` of one). A progress bar counts finished units. A unit that
    still fails after its retries ends the map with a
    :class:`~ontodetect._executor.UnitsFailedError` naming it (``names``: what to call
    each unit; default its position).
    """
    if executor is not None:
        return executor.map(fn, units, names=names, description=description)
    jobs = _check_jobs(jobs)
    results: list[Any] = [None] * len(units)
    if jobs == 1 or len(units) <= 1:
        with progress(description, total=len(units)) as advance:
            for i, unit in enumerate(units):
                results[i] = fn(unit)
                advance(1)
        return results
    with executor_for(None, min(jobs, len(units))) as pool:
        return pool.map(fn, units, names=names, description=description)


# -- the dataset ---------------------------------------------------------------------------
@dataclass(frozen=True)
class DatasetEvaluation:
    """A dataset's evaluation at the three criteria, with every scene's outcome.

    Attributes
    ----------
    dataset : str
        The dataset path as given.
    classes : list of str
        Evaluated classes.
    evaluations : dict of str to Evaluation
        ``"iou@0.25"``, ``"iou@0.5"`` and ``"distance"`` (see :data:`CRITERIA`).
    scenes : list of SceneOutcome
        Evaluated scenes, in discovery order.
    failed : list of SceneOutcome
        Scenes that could not be evaluated (with ``error``).
    options : dict
        What produced the detections (JSON-ready).
    jobs : int
        Worker processes used.
    seconds : float
        Wall time of the whole evaluation.
    box_ap : dict of str to dict of str to float
        Box AP per class and ``"mean"`` (:func:`box_average_precision`) under the keys
        ``"aligned@0.25"``, ``"aligned@0.5"``, ``"oriented@0.25"``, ``"oriented@0.5"``,
        pooled over every scene like ``evaluations``.
    by_variant : dict of str to Evaluation
        When scans were turned or run with several seeds (:func:`evaluate_dataset`'s
        ``turns`` and ``seeds``): the evaluation at point IoU >= 0.25 of each turn
        (``"90°"``, over the seeds), or of each seed (``"seed 1"``) when none was turned;
        ``evaluations`` pools them all. Empty otherwise.
    """

    dataset: str
    classes: list[str]
    evaluations: dict[str, Evaluation]
    scenes: list[SceneOutcome]
    failed: list[SceneOutcome] = field(default_factory=list)
    options: dict[str, Any] = field(default_factory=dict)
    jobs: int = 1
    seconds: float = 0.0
    by_variant: dict[str, Evaluation] = field(default_factory=dict)
    box_ap: dict[str, dict[str, float]] = field(default_factory=dict)

    @property
    def primary(self) -> Evaluation:
        """The evaluation at point IoU >= 0.25, the main criterion (docs/evaluation.md)."""
        return self.evaluations[PRIMARY]

    def scene_seconds(self) -> dict[str, float]:
        """Mean, median and maximum detection time per scene (s)."""
        t = np.array([s.seconds for s in self.scenes], dtype=np.float64)
        if not len(t):
            return {"mean": 0.0, "median": 0.0, "max": 0.0, "total": 0.0}
        return {
            "mean": float(t.mean()),
            "median": float(np.median(t)),
            "max": float(t.max()),
            "total": float(t.sum()),
        }

    def to_dict(self) -> dict[str, Any]:
        return {
            "format": EVALUATION_FORMAT,
            "dataset": self.dataset,
            "classes": self.classes,
            "options": self.options,
            "jobs": self.jobs,
            "seconds": round(self.seconds, 3),
            "scene_seconds": {k: round(v, 3) for k, v in self.scene_seconds().items()},
            "evaluations": {k: e.to_dict() for k, e in self.evaluations.items()},
            "box_ap": {
                k: {c: (None if math.isnan(v) else round(v, 4)) for c, v in ap.items()}
                for k, ap in self.box_ap.items()
            },
            "scenes": [s.to_dict() for s in self.scenes],
            "failed": [s.to_dict() for s in self.failed],
            "by_variant": {
                k: {
                    "per_class": {c: m.to_dict() for c, m in e.per_class.items()},
                    "overall": e.overall.to_dict(),
                }
                for k, e in self.by_variant.items()
            },
        }


def summarize_outcomes(
    outcomes: Sequence[SceneOutcome],
    classes: Sequence[str],
    *,
    dataset: str = "",
    options: Mapping[str, Any] | None = None,
    jobs: int = 1,
    seconds: float = 0.0,
) -> DatasetEvaluation:
    """Merge scene outcomes (in the order given) into a :class:`DatasetEvaluation`."""
    ok = [o for o in outcomes if o.ok]
    results = [o.scene_result() for o in ok]
    evaluations = {
        key: evaluate_scenes(results, classes, criterion=crit, iou_threshold=thr)
        for key, (crit, thr) in CRITERIA.items()
    }
    groups: dict[str, list[SceneResult]] = {}
    turned = any(o.turn is not None for o in ok)
    for o, r in zip(ok, results):
        if o.turn is not None or o.seed is not None:
            key = f"{o.turn:g}°" if turned else f"seed {o.seed}"
            groups.setdefault(key, []).append(r)
    crit, thr = CRITERIA[PRIMARY]
    by_variant = {
        key: evaluate_scenes(rs, classes, criterion=crit, iou_threshold=thr)
        for key, rs in groups.items()
    }
    pairs = [(o.pred_boxes, o.gt_boxes) for o in ok]
    box_ap = {
        f"{kind}@{thr:g}": box_average_precision(
            pairs, classes, iou_threshold=thr, oriented=kind == "oriented"
        )
        for kind in ("aligned", "oriented")
        for thr in BOX_IOU_THRESHOLDS
    }
    return DatasetEvaluation(
        str(dataset),
        list(classes),
        evaluations,
        ok,
        [o for o in outcomes if not o.ok],
        dict(options or {}),
        jobs,
        seconds,
        by_variant,
        box_ap,
    )


def _jsonable_option(value: Any) -> Any:
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, Mapping):
        return {str(k): _jsonable_option(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable_option(v) for v in value]
    return str(value)


def describe_options(
    options: Mapping[str, Any], detections_dir: str | os.PathLike[str] | None = None
) -> dict[str, Any]:
    """A JSON-ready account of what produced the detections."""
    if detections_dir is not None:
        return {"detections": str(detections_dir)}
    out: dict[str, Any] = {}
    for key, value in options.items():
        if key == "config":
            default = Config().to_dict()
            changed = {
                f"{sec}.{k}": _jsonable_option(v)
                for sec, vals in value.to_dict().items()
                if isinstance(vals, dict)
                for k, v in vals.items()
                if default.get(sec, {}).get(k) != v
            }
            out["config"] = changed or "defaults"
        elif key == "ontology":
            out["ontology"] = {"source": value.source, "classes": value.names}
        else:
            out[key] = _jsonable_option(value)
    return out


def evaluate_dataset(
    path: str | os.PathLike[str],
    *,
    format: str = "auto",
    jobs: int = 1,
    detect_options: Mapping[str, Any] | None = None,
    detections_dir: str | os.PathLike[str] | None = None,
    save_detections: str | os.PathLike[str] | None = None,
    on_error: str = "raise",
    scenes: Sequence[SceneSource] | None = None,
    turns: Sequence[float] | None = None,
    seeds: Sequence[int] | None = None,
    executor: Executor | None = None,
) -> DatasetEvaluation:
    """Detect in every scene of a dataset and score against its ground truth.

    Parameters
    ----------
    path : str or PathLike
        Dataset folder or one scene (see :func:`discover_scenes`).
    format : str
        Dataset layout, or "auto".
    jobs : int
        Worker processes of a local cluster (0: one per CPU; 1: this process). Results
        do not depend on it.
    detect_options : mapping, optional
        Keyword arguments of :func:`ontodetect.pipeline.detect`.
    detections_dir : path, optional
        Score stored detections (``<dir>/<scene>/detections.json``) instead of detecting.
    save_detections : path, optional
        Also write each scene's ``detections.json`` into ``<save_detections>/<scene>/``.
    on_error : {"raise", "skip"}
        A scene that cannot be evaluated stops the run with a :class:`SceneError`, or is
        left out and listed in :attr:`DatasetEvaluation.failed`.
    scenes : sequence of SceneSource, optional
        Evaluate these instead of discovering ``path``'s scenes.
    turns : sequence of float, optional
        Detect in every scene once per turn, the scan turned by that many degrees about
        the vertical (the same room met by other voxel boundaries; the ground truth
        follows by point). On a small dataset one pass is one draw: the pooled figure
        over turns is the steadier one.
    seeds : sequence of int, optional
        Detect in every scene (and turn) once per seed, overriding ``seed`` of
        ``detect_options``. With ``turns`` or ``seeds`` each run is an outcome of its
        own, named ``<scene>@<turn>deg-seed<seed>`` (:func:`variant_name`), and
        :attr:`DatasetEvaluation.by_variant` holds the figures per turn (or seed).
    executor : Executor, optional
        Where the scenes run (:func:`ontodetect._executor.open_executor`: a local or an
        existing Dask cluster); ``jobs`` is then not used. Every worker must see
        ``path``.

    Returns
    -------
    DatasetEvaluation
        At point IoU 0.25 and 0.5 and at the distance criterion.

    Raises
    ------
    ReadError
        No scene found.
    SceneError
        A scene failed and ``on_error="raise"``.
    """
    if on_error not in ("raise", "skip"):
        raise InvalidParameterError("on_error", "'raise' or 'skip'", on_error)
    opts = _check_detect_options(detect_options)
    turn_list = _check_variants("turns", turns, float)
    seed_list = _check_variants("seeds", seeds, int)
    if (turn_list or seed_list) and detections_dir is not None:
        raise InvalidParameterError(
            "turns" if turn_list else "seeds",
            "none when scoring stored detections (they were made once, on the scans as they are)",
            turn_list or seed_list,
        )
    start = time.perf_counter()
    sources = list(scenes) if scenes is not None else discover_scenes(path, format)
    ontology = opts.get("ontology")
    class_ids = evaluation_classes(ontology)
    classes = list(dict.fromkeys(class_ids.values()))
    # Scenes in parallel already use the CPUs: the passes of a vote stay in each worker.
    workers = executor.workers if executor is not None else _check_jobs(jobs)
    # A plain run is the one variant (None, None): the scene as it is, with ``seed``.
    units = [
        (s, t, seed)
        for s in sources
        for t in (turn_list or [None])
        for seed in (seed_list or [None])
    ]
    parallel = executor is not None and not isinstance(executor, InProcess)
    per_scene = {"jobs": 1, **opts} if (parallel or workers > 1) and len(units) > 1 else opts
    work = functools.partial(
        _evaluate_variant,
        detect_options=per_scene,
        detections_dir=detections_dir,
        save_dir=save_detections,
        class_ids=class_ids,
    )
    outcomes = map_scenes(
        work,
        units,
        jobs=workers,
        description="Evaluating scenes",
        executor=executor,
        names=[variant_name(s.name, t, seed) for s, t, seed in units],
    )
    if on_error == "raise":
        for o in outcomes:
            if not o.ok:
                raise SceneError(o.name, o.error or "failed")
    options = describe_options(opts, detections_dir)
    if turn_list:
        options["turns"] = turn_list
    if seed_list:
        options.pop("seed", None)
        options["seeds"] = seed_list
    return summarize_outcomes(
        outcomes,
        classes,
        dataset=str(path),
        options=options,
        jobs=workers,
        seconds=time.perf_counter() - start,
    )
