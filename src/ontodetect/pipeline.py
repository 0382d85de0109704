"""The whole method in one call: read → prepare → segment → score → label (→ fit CAD).

:func:`detect` takes a :class:`~ontodetect.cloud.PointCloud` and returns a
:class:`Result` holding the detections (in the input file's frame and units, with
the input file's point rows), every cluster's scores for ``--explain``, and the
intermediate results. :meth:`Result.to_dict` is the ``detections.json`` contract
of DESIGN.md.
"""

from __future__ import annotations

import dataclasses
import math
import multiprocessing
import threading
import time
import warnings
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._parallel import cpu_count, fork_context
from ._progress import progress, use_reporter
from .cloud import DataWarning, PointCloud, as_position, pixel_grid, sensor_position
from .config import Config
from .errors import InvalidParameterError
from .evaluation._match import Instance, overlap_matrix
from .labeling import LabelChoice, label_clusters, label_probability
from .ontology import (
    ClusterDescription,
    ClusterScores,
    Ontology,
    builtin_ontology,
    class_priors,
    score_cluster,
)
from .ontology._score import HORIZONTAL_TILT
from .preprocess import Ground, find_ground, smooth_depth
from .preprocess._structure import FLOOR
from .render import box_corners
from .segment import Cluster, Segmentation, segment

__all__ = [
    "Detection",
    "Result",
    "class_for_label",
    "describe_cluster",
    "describe_clusters",
    "detect",
    "hidden_heights",
    "majority_labels",
    "open_below",
    "pass_probabilities",
    "shelter_heights",
    "vote_turns",
    "with_cad",
]

#: Format tag of detections.json.
DETECTIONS_FORMAT = "ontodetect.detections/1"


@dataclass(frozen=True)
class Detection:
    """One detected object, in the input file's frame and units.

    Attributes
    ----------
    id : int
        1, 2, ... in order of decreasing score.
    label : str
        The label of the winning class (its name unless the ontology gives a ``label``).
    score : float
        P_obj|ont of the label: ``probabilities`` of the classes written under it,
        summed (:func:`ontodetect.labeling.label_probability`); with one class per
        label, that class's.
    probabilities, costs : mapping of str to float
        P_obj|ont and energy U of every class. With ``detect.votes`` > 1 the
        probabilities are means over the passes (:func:`pass_probabilities`); the
        costs are those of the first pass, whose clusters the detections keep.
    center, size : (3,) float
        Upright box centre and size (length, breadth, height).
    yaw : float
        Angle of the box's length axis about ``frame.up`` (radians).
    point_indices : (k,) int
        Rows of the input file that belong to the object.
    parts : list of dict
        The planes assigned to the label's parts.
    cluster : int
        Index of the cluster in the segmentation.
    cad : dict, optional
        The fitted CAD model (see :func:`with_cad`).
    votes : int, optional
        Passes that found the object when ``detect.votes`` > 1.
    """

    id: int
    label: str
    score: float
    probabilities: Mapping[str, float]
    costs: Mapping[str, float]
    center: NDArray[np.float64]
    size: NDArray[np.float64]
    yaw: float
    point_indices: NDArray[np.int64]
    parts: list[dict[str, Any]]
    cluster: int
    cad: dict[str, Any] | None = None
    votes: int | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "id": self.id,
            "label": self.label,
            "score": round(self.score, 4),
            "probabilities": {k: round(v, 4) for k, v in self.probabilities.items()},
            "costs": {k: round(v, 4) for k, v in self.costs.items()},
            "box": {
                "center": [round(float(v), 4) for v in self.center],
                "size": [round(float(v), 4) for v in self.size],
                "yaw": round(self.yaw, 4),
            },
            "point_indices": [int(i) for i in self.point_indices],
            "parts": self.parts,
            "cluster": self.cluster,
        }
        if self.cad is not None:
            out["cad"] = self.cad
        if self.votes is not None:
            out["votes"] = self.votes
        return out


@dataclass
class Result:
    """What :func:`detect` found, and how.

    Attributes
    ----------
    cloud : PointCloud
        The input.
    detections : list of Detection
    segmentation : Segmentation
        Clusters with their planes (levelled frame).
    scores : list of ClusterScores
        One per cluster: every class's probability and factors.
    choices : list of LabelChoice
        One per cluster: the label (or none) and the costs.
    ontology : Ontology
    priors : dict of str to float
        P_obj per class.
    timings : dict of str to float
        Seconds per stage.
    """

    cloud: PointCloud
    detections: list[Detection]
    segmentation: Segmentation
    scores: list[ClusterScores]
    choices: list[LabelChoice]
    ontology: Ontology
    priors: dict[str, float]
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def frame(self) -> dict[str, Any]:
        prep = self.segmentation.prepared
        return {
            "up": [round(float(v), 6) for v in prep.up],
            "ground_z": round(float(prep.floor_z), 6),
            "scale": round(float(prep.scale), 9),
        }

    def to_dict(self) -> dict[str, Any]:
        """The ``detections.json`` document (DESIGN.md contract)."""
        return {
            "format": DETECTIONS_FORMAT,
            "source": str(self.cloud.meta.get("source", "")),
            "num_points": int(self.cloud.index.max() + 1) if len(self.cloud) else 0,
            "frame": self.frame,
            "detections": [d.to_dict() for d in self.detections],
            "priors": {k: round(v, 4) for k, v in self.priors.items()},
            "timings": {k: round(v, 4) for k, v in self.timings.items()},
        }

    def point_labels(self) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
        """Per point of :attr:`cloud`: class index into :attr:`class_names` (-1 none) and
        detection id (0 none)."""
        n = len(self.cloud)
        label = np.full(n, -1, dtype=np.int32)
        instance = np.zeros(n, dtype=np.int32)
        names = self.class_names
        for d in self.detections:
            members = self.segmentation[d.cluster].point_indices
            label[members] = names.index(d.label)
            instance[members] = d.id
        return label, instance

    @property
    def class_names(self) -> list[str]:
        return sorted({c.label for c in self.ontology.classes})


def with_cad(result: Result, fits: Sequence[Any]) -> Result:
    """The result with each detection's ``cad`` entry filled from its CAD fit (same order)."""
    from .cad import cad_dict

    if len(fits) != len(result.detections):
        raise InvalidParameterError(
            "fits", f"one fit per detection ({len(result.detections)})", len(fits)
        )
    detections = [dataclasses.replace(d, cad=cad_dict(f)) for d, f in zip(result.detections, fits)]
    return dataclasses.replace(result, detections=detections)


def describe_cluster(
    cluster: Cluster,
    shelter: float = -math.inf,
    ceiling: float = math.inf,
    hidden_below: float = -math.inf,
    open_below: Sequence[float] | None = None,
) -> ClusterDescription:
    """What the ontology scoring needs to know about a cluster (``shelter``: see
    :func:`shelter_heights`; ``ceiling``: the top of the search volume;
    ``hidden_below``: see :func:`hidden_heights`; ``open_below``: see
    :func:`open_below`)."""
    return ClusterDescription(
        planes=cluster.planes,
        relations=cluster.relations_by_pair,
        length=cluster.length,
        breadth=cluster.breadth,
        height=cluster.height,
        bottom=cluster.bottom,
        shelter=shelter,
        ceiling=ceiling,
        hidden_below=hidden_below,
        open_below=open_below,
    )


def describe_clusters(
    seg: Segmentation, viewpoint: Sequence[float] | None = None
) -> list[ClusterDescription]:
    """:func:`describe_cluster` for every cluster, with what stands beside it and the
    altitude cut-off of the search.

    ``viewpoint`` is the sensor's position in the input frame when the scan is one view
    (:func:`ontodetect.cloud.sensor_position`); then a cluster may also hide what
    stands behind it (:func:`hidden_heights`), and whether the floor shows under a top
    (:func:`open_below`) is not measured, since the top itself hides most of it.
    """
    ceiling = float(seg.config.prepare.altitude_cutoff)
    hidden = np.full(len(seg), -math.inf)
    if viewpoint is not None and len(seg):
        eye = seg.prepared.level(np.asarray(viewpoint, dtype=np.float64))[0]
        hidden = hidden_heights(
            np.array([c.height for c in seg], dtype=np.float64),
            np.array([c.box.center[:2] for c in seg], dtype=np.float64),
            eye,
        )
    # From one view the floor under a top is hidden by the top itself: not measured there.
    below = open_below(seg) if viewpoint is None else [None] * len(seg)
    return [
        describe_cluster(c, float(h), ceiling, float(b), o)
        for c, h, b, o in zip(seg, shelter_heights(seg), hidden, below)
    ]


#: Cell of the horizontal grid on which :func:`open_below` compares a plane's footprint
#: with the floor seen (m).
FLOOR_CELL = 0.1
#: Under a lower plane (m above the floor) the floor is seldom seen from eye height, so
#: :func:`open_below` does not measure it: a coffee table looks closed below.
OPEN_BELOW_HEIGHT = 0.55
#: Rings of cells left out at the rim of a footprint, where the floor beyond the edge
#: and the foot of the sides show (fewer when nothing would be left).
OPEN_BELOW_RIM = 2


def _cell_keys(xy: NDArray[np.float64]) -> NDArray[np.int64]:
    """One integer per ``FLOOR_CELL`` cell of the points ``xy``."""
    ij = np.floor(xy / FLOOR_CELL).astype(np.int64)
    return (ij[:, 0] << 32) + (ij[:, 1] + (1 << 31))  # a step in j is a step of 1


def open_below(seg: Segmentation) -> list[list[float]]:
    """Per cluster and plane, the share of a horizontal plane's footprint under which the
    floor was seen (0..1); NaN for tilted planes and planes lower than
    ``OPEN_BELOW_HEIGHT``, and for all when no floor was found.

    A top on legs or a pedestal leaves the floor under it open to the sensor; a cabinet,
    a bed, a box or an upholstered seat hides it. The footprint is the plane's cells on a
    ``FLOOR_CELL`` grid less ``OPEN_BELOW_RIM`` rings of cells at its rim (where the
    floor beyond the edge and the foot of a box's sides show), fewer when nothing would
    be left; the floor is the voxels the preparation labelled floor.
    """
    prep = seg.prepared
    floor = prep.voxels.centers[prep.structure_label == FLOOR]
    out: list[list[float]] = []
    if not prep.floor_found or not len(floor):
        return [[math.nan] * len(c.planes) for c in seg]
    seen = np.unique(_cell_keys(floor[:, :2]))
    for c in seg:
        values = []
        centers = np.asarray(c.centers)
        for plane in c.planes:
            if float(plane.tilt) > HORIZONTAL_TILT or float(plane.height) < OPEN_BELOW_HEIGHT:
                values.append(math.nan)
                continue
            use = np.unique(_cell_keys(centers[plane.inliers, :2]))
            for _ in range(OPEN_BELOW_RIM):
                inner = use
                for step in ((1 << 32), -(1 << 32), 1, -1):
                    inner = inner[np.isin(inner + step, use)]
                if not len(inner):
                    break
                use = inner
            values.append(float(np.isin(use, seen).mean()))
        out.append(values)
    return out


#: What a cluster hides behind it must lie in its shadow for at least this far (m),
#: about the depth of a seat behind its backrest.
SELF_SHADOW = 0.3
#: The sensor must stand at least this far (m, horizontally) from the cluster's centre.
SELF_SHADOW_DISTANCE = 0.5


def hidden_heights(tops: NDArray, centers: NDArray, eye: Sequence[float]) -> NDArray:
    """(clusters,) height under which each cluster hides what stands behind it.

    Seen over an object's top at height ``top`` from an eye at height ``eye_z`` and
    horizontal distance ``d``, the sight line comes down to height ``h`` only
    ``(top − h) · d / (eye_z − top)`` beyond the object. Whatever stands behind it
    lower than ``top − SELF_SHADOW · (eye_z − top) / d`` is out of sight for at least
    ``SELF_SHADOW``: that height is returned (the top itself when the eye is not
    above it), and ``-inf`` when the eye stands closer than ``SELF_SHADOW_DISTANCE``.

    Parameters
    ----------
    tops : (k,) float
        Top of each cluster above the floor (levelled frame).
    centers : (k, 2) float
        Horizontal centre of each cluster (levelled frame).
    eye : (3,) float
        The sensor's position in the levelled frame.

    Examples
    --------
    >>> import numpy as np
    >>> tops, centers = np.array([0.9, 0.9, 1.6]), np.array([[2.0, 0], [0.3, 0], [2.0, 0]])
    >>> hidden_heights(tops, centers, [0.0, 0.0, 1.5]).round(3).tolist()
    [0.81, -inf, 1.6]
    """
    tops = np.asarray(tops, dtype=np.float64)
    eye = np.asarray(eye, dtype=np.float64)
    d = np.linalg.norm(np.asarray(centers, dtype=np.float64).reshape(-1, 2) - eye[:2], axis=1)
    above = np.maximum(eye[2] - tops, 0.0)
    hidden = tops - SELF_SHADOW * above / np.maximum(d, 1e-9)
    return np.where(d >= SELF_SHADOW_DISTANCE, hidden, -math.inf)


#: Horizontal planes of at least this area (m²) can hide ...
SHELTER_AREA = 0.1
#: ... what stands within this horizontal gap of their cluster's box (m).
SHELTER_GAP = 0.4


def _footprint(box: Any) -> NDArray:
    """(2, 2) min and max corner of the xy rectangle around an upright box."""
    xy = box_corners(box.center, box.size, box.yaw)[:4, :2]
    return np.stack([xy.min(axis=0), xy.max(axis=0)])


def shelter_heights(seg: Segmentation) -> NDArray:
    """(clusters,) height of the highest large horizontal surface beside each cluster.

    For every cluster, the highest horizontal plane (a desk or table top) of any other
    cluster whose footprint comes within ``SHELTER_GAP`` of its own; ``-inf`` when there
    is none. A chair pushed under a desk shows only its backrest above the desk's top:
    this is what tells the scoring its seat may be hidden rather than absent.
    """
    n = len(seg)
    tops = np.full(n, -math.inf)
    boxes = np.zeros((n, 2, 2))
    for k, c in enumerate(seg):
        flat = [
            float(p.height)
            for p in c.planes
            if float(p.tilt) < HORIZONTAL_TILT and float(p.area) >= SHELTER_AREA
        ]
        tops[k] = max(flat, default=-math.inf)
        boxes[k] = _footprint(c.box)
    if n == 0:
        return tops
    gap = np.maximum(boxes[None, :, 0] - boxes[:, None, 1], boxes[:, None, 0] - boxes[None, :, 1])
    near = np.all(gap <= SHELTER_GAP, axis=2)
    np.fill_diagonal(near, False)
    return np.where(near, tops[None, :], -math.inf).max(axis=1)


def _to_input_frame(seg: Segmentation, cluster: Cluster) -> tuple[NDArray, NDArray, float]:
    prep = seg.prepared
    box = cluster.box
    center = prep.from_level(np.asarray(box.center, dtype=np.float64)[None])[0]
    rot = prep.to_level[:3, :3] / prep.scale
    direction = rot.T @ np.array([math.cos(box.yaw), math.sin(box.yaw), 0.0])
    yaw = math.atan2(direction[1], direction[0])
    return center, np.asarray(box.size, dtype=np.float64) / prep.scale, yaw


def _parts(
    seg: Segmentation, cluster: Cluster, assignment: Mapping[str, int | None]
) -> list[dict[str, Any]]:
    prep = seg.prepared
    rot = prep.to_level[:3, :3] / prep.scale
    counts = prep.counts
    out = []
    for name, k in assignment.items():
        if k is None:
            continue
        plane = cluster.planes[k]
        normal = rot.T @ np.asarray(plane.normal, dtype=np.float64)
        centroid = prep.from_level(np.asarray(plane.centroid, dtype=np.float64)[None])[0]
        voxels = cluster.voxels[np.asarray(plane.inliers)]
        out.append(
            {
                "name": name,
                "normal": [round(float(v), 4) for v in normal],
                "centroid": [round(float(v), 4) for v in centroid],
                "extent": [
                    round(float(plane.length) / prep.scale, 4),
                    round(float(plane.width) / prep.scale, 4),
                ],
                "height": round(float(plane.height) / prep.scale, 4),
                "tilt": round(float(plane.tilt), 2),
                "num_points": int(counts[voxels].sum()),
            }
        )
    return out


def detect(
    cloud: PointCloud,
    *,
    config: Config | None = None,
    ontology: Ontology | None = None,
    room: str | Mapping[str, float] | None = None,
    indoor: float | None = None,
    threshold: float | None = None,
    beta: float | None = None,
    none_likelihood: float | None = None,
    context: float | None = None,
    votes: int | None = None,
    jobs: int | None = None,
    seed: int = 0,
    up: str | Sequence[float] | None = None,
    scale: float | None = None,
    viewpoint: Sequence[float] | None = None,
) -> Result:
    """Find the objects an ontology describes in a point cloud.

    Parameters
    ----------
    cloud : PointCloud
        The scan (any units and up direction the preparation can handle).
    config : Config, optional
        Parameters of every stage (defaults: Table 4.1).
    ontology : Ontology, optional
        Classes to look for; the built-in furniture ontology by default.
    room : str or mapping, optional
        Room category or distribution for the environment prior (Eq. 3.10).
    indoor : float, optional
        P(indoor) for the indoor/outdoor prior (Eq. 3.5).
    threshold, beta, none_likelihood, context : float, optional
        Override ``config.detect``: decision threshold on P_obj|ont (Table 4.1:
        15 %), weight β of the class probability in the energy (γ = 1 − β),
        likelihood of "none of the classes", strength of the seat-near-table term.
    votes : int, optional
        Override ``config.detect.votes``: passes over the scan, each turned by
        ``detect.vote_turn`` degrees more about the vertical; a detection stays when
        more than half of them find it (:func:`majority_labels`). Clouds of more than
        ``detect.vote_max_points`` points get one pass.
    jobs : int, optional
        Worker processes (forked) for the passes after the first, while this process
        makes the first; 1: all in this process; 0: one per usable CPU, as for
        :func:`ontodetect.evaluation.evaluate_dataset`. By default one per CPU where the
        platform can fork, if this process runs no other thread (a number given here
        forks anyway). The result does not depend on it.
    seed : int
        Seed of every random step.
    up, scale :
        Passed to the preparation (up direction, scale factor k_s).
    viewpoint : (3,) float, optional
        Where the sensor stood, in the cloud's frame and units, when the cloud is one
        view (a single camera frame): a part the object itself hides from there, such
        as a seat behind its backrest, counts as occluded rather than absent. By
        default :func:`ontodetect.cloud.sensor_position` (an organized cloud's
        viewpoint); none for a fused scan.

    Returns
    -------
    Result

    Examples
    --------
    >>> from ontodetect.synth import synthesize
    >>> result = detect(synthesize("tiny", seed=1).cloud)
    >>> sorted(d.label for d in result.detections)
    ['chair', 'table']
    """
    if not isinstance(cloud, PointCloud):
        raise InvalidParameterError("cloud", "a PointCloud", type(cloud).__name__)
    config = config or Config()
    d = config.detect
    threshold = d.threshold if threshold is None else threshold
    beta = d.beta if beta is None else beta
    none_likelihood = d.none_likelihood if none_likelihood is None else none_likelihood
    context = d.context if context is None else context
    if votes is not None:
        config = config.replace(detect={"votes": votes})  # checked like the file's value
        d = config.detect
    if not 0.0 < none_likelihood <= 1.0:
        raise InvalidParameterError("none_likelihood", "a number in (0, 1]", none_likelihood)
    if viewpoint is not None:
        cloud = cloud.with_meta(sensor_position=as_position(viewpoint).tolist())
    viewpoint = sensor_position(cloud)
    if viewpoint is not None and pixel_grid(cloud) is None:
        warnings.warn(
            "a viewpoint but no pixel grid: if this is a depth camera's frame, its "
            "depth steps stay unsmoothed and read as flat parts (give the organized "
            "frame, such as its PCD)",
            DataWarning,
            stacklevel=2,
        )
    ontology = ontology or builtin_ontology()
    priors = class_priors(ontology, room, indoor)
    opts = {
        "ontology": ontology,
        "priors": priors,
        "threshold": threshold,
        "beta": beta,
        "none_likelihood": none_likelihood,
        "context": context,
        "seed": seed,
        "up": up,
        "scale": scale,
        "viewpoint": viewpoint,
    }
    passes = d.votes if len(cloud) <= d.vote_max_points else 1
    turned = [
        config.replace(prepare={"turn": (config.prepare.turn + t + 180.0) % 360.0 - 180.0})
        for t in vote_turns(passes, d.vote_turn)
    ]
    workers = _vote_workers(jobs, len(turned))
    t0 = time.perf_counter()
    # A frame's depth steps, its scale, voxels, up direction and floor do not depend on the
    # pass's turn: find them once for all passes (counted in "segment", where preparation
    # would have found them).
    scan = smooth_depth(cloud) if config.prepare.depth_smoothing else cloud
    if turned:
        opts["ground"] = find_ground(scan, config, scale=scale, up=up)
    shared = time.perf_counter() - t0
    if workers:
        with ProcessPoolExecutor(max_workers=workers, mp_context=fork_context()) as pool:
            futures = [pool.submit(_pass_clusters, scan, c, opts) for c in turned]
            seg, scores, choices, found, timings = _one_pass(scan, config, **opts)
            others = [f.result() for f in futures]
    else:
        seg, scores, choices, found, timings = _one_pass(scan, config, **opts)
        others = [_pass_clusters(scan, c, opts) for c in turned]
    timings["segment"] += shared
    if turned:
        found, choices = _vote(cloud, seg, scores, choices, found, others, ontology)
        timings["votes"] = time.perf_counter() - t0 - sum(timings.values())
    found.sort(key=lambda d: (-d.score, d.cluster))
    detections = [Detection(**{**d.__dict__, "id": i + 1}) for i, d in enumerate(found)]
    return Result(
        cloud=cloud,
        detections=detections,
        segmentation=seg,
        scores=scores,
        choices=choices,
        ontology=ontology,
        priors=priors,
        timings=timings,
    )


def vote_turns(votes: int, step: float) -> list[float]:
    """Turns (deg) of the passes after the first: +step, -step, +2 step, -2 step...

    >>> vote_turns(5, 0.7)
    [0.7, -0.7, 1.4, -1.4]
    """
    return [step * ((i + 1) // 2) * (1 if i % 2 else -1) for i in range(1, votes)]


def _vote_workers(jobs: int | None, passes: int) -> int:
    """Worker processes for ``passes`` extra passes (0: make them in this process)."""
    if jobs is not None and (isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 0):
        raise InvalidParameterError("jobs", "a non-negative integer or None", jobs)
    if not passes or fork_context() is None or multiprocessing.current_process().daemon:
        return 0  # a daemonic worker (multiprocessing.Pool) may not have children
    if jobs is None:
        # Forking copies only the calling thread: with other threads about (a GUI, a
        # robot's node), whatever they hold stays held in the copy. Then, unless the
        # caller asks for workers, the passes run here.
        if threading.active_count() > 1:
            return 0
        jobs = 0
    jobs = jobs or cpu_count()
    return min(passes, jobs) if jobs > 1 else 0


#: What the vote needs of a cluster of another pass: its sorted input rows, its
#: P_obj|ont by class (with "none") and its label (None when it is no object).
PassCluster = tuple[NDArray[np.int64], dict[str, float], str | None]


def _pass_clusters(cloud: PointCloud, config: Config, opts: Mapping[str, Any]) -> list[PassCluster]:
    """Every cluster of one pass, as the vote needs it (a unit of work for a worker)."""
    with use_reporter(None):  # a forked worker must not draw the parent's progress bars
        seg, scores, choices, _, _ = _one_pass(cloud, config, found=False, **opts)
    return [
        (np.sort(cloud.index[c.point_indices]), dict(s.probabilities), ch.label)
        for c, s, ch in zip(seg, scores, choices)
    ]


def _one_pass(
    cloud: PointCloud,
    config: Config,
    *,
    ontology: Ontology,
    priors: Mapping[str, float],
    threshold: float,
    beta: float,
    none_likelihood: float,
    context: float,
    seed: int,
    up: Any,
    scale: Any,
    viewpoint: NDArray[np.float64] | None = None,
    found: bool = True,
    ground: Ground | None = None,
) -> tuple[Segmentation, list[ClusterScores], list[LabelChoice], list[Detection], dict[str, float]]:
    """Segment, score and label once; detections (when ``found``) numbered 0, in cluster
    order."""
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    seg = segment(cloud, config, seed=seed, up=up, scale=scale, ground=ground)
    timings["segment"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    scores: list[ClusterScores] = []
    with progress("Scoring clusters", total=len(seg)) as advance:
        for desc in describe_clusters(seg, viewpoint):
            scores.append(score_cluster(desc, ontology, priors, none_likelihood=none_likelihood))
            advance(1)
    timings["score"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    centers = np.array([c.box.center for c in seg]) if len(seg) else np.zeros((0, 3))
    choices = label_clusters(
        scores,
        [c.planes for c in seg],
        ontology,
        beta=beta,
        threshold=threshold,
        centers=centers,
        context=context,
    )
    timings["label"] = time.perf_counter() - t0
    detections = [
        _detection(
            cloud, seg, k, scores[k], choice.label, choice.extra["class"], choice.costs, ontology
        )
        for k, choice in enumerate(choices)
        if found and choice.label is not None
    ]
    return seg, scores, choices, detections, timings


def _detection(
    cloud: PointCloud,
    seg: Segmentation,
    k: int,
    scores: ClusterScores,
    label: str,
    cls_name: str,
    costs: Mapping[str, float],
    ontology: Ontology,
    votes: int | None = None,
    probabilities: Mapping[str, float] | None = None,
) -> Detection:
    """Cluster ``k`` as a detection; its probabilities are the cluster's unless given."""
    c = seg[k]
    if probabilities is None:
        probabilities = scores.probabilities
    center, size, yaw = _to_input_frame(seg, c)
    return Detection(
        id=0,
        label=label,
        score=label_probability(probabilities, ontology, label),
        probabilities={n: float(p) for n, p in probabilities.items() if n != "none"},
        costs=dict(costs),
        center=center,
        size=size,
        yaw=yaw,
        point_indices=np.sort(cloud.index[c.point_indices]),
        parts=_parts(seg, c, scores.classes[cls_name].assignment),
        cluster=k,
        votes=votes,
    )


#: A detection of another pass backs a cluster of the first when their points overlap
#: at least this much (IoU), with the same label.
VOTE_IOU = 0.5


def majority_labels(
    clusters: Sequence[NDArray[np.int64]],
    first: Mapping[int, str],
    others: Sequence[Sequence[tuple[str, NDArray[np.int64]]]],
) -> dict[int, tuple[str, int]]:
    """The labels a majority of passes gives the clusters of the first pass.

    Parameters
    ----------
    clusters : sequence of (k,) int
        Sorted point rows of each cluster of the first pass.
    first : mapping of int to str
        The first pass's labels, by cluster.
    others : sequence of sequences of (label, rows)
        The detections of every other pass (sorted rows).

    Returns
    -------
    dict of int to (label, passes)
        For each cluster that more than half of all passes label alike (a pass counts
        when one of its detections of the label covers the cluster with point IoU ≥
        ``VOTE_IOU``): the label and how many passes found it.

    Examples
    --------
    >>> a, b = np.arange(0, 10), np.arange(20, 30)
    >>> majority_labels([a, b], {0: "chair"}, [[("chair", a), ("table", b)], [("table", b[1:])]])
    {0: ('chair', 2), 1: ('table', 2)}
    """
    need = (len(others) + 1) // 2 + 1
    backing: list[dict[str, int]] = [
        {first[k]: 1} if k in first else {} for k in range(len(clusters))
    ]
    dets = [
        Instance.make(i, label, rows)
        for i, (label, rows) in enumerate(d for run in others for d in run)
    ]
    iou, _ = overlap_matrix(dets, [Instance.make(k, "", rows) for k, rows in enumerate(clusters)])
    run_of = np.repeat(np.arange(len(others)), [len(run) for run in others])
    for r in range(len(others)):
        found = {
            (int(k), dets[i].label)
            for i in np.flatnonzero(run_of == r)
            for k in np.flatnonzero(iou[i] >= VOTE_IOU)
        }
        for k, label in found:
            backing[k][label] = backing[k].get(label, 0) + 1
    out: dict[int, tuple[str, int]] = {}
    for k, votes in enumerate(backing):
        winners = sorted(((n, label) for label, n in votes.items() if n >= need), reverse=True)
        if winners:
            out[k] = (winners[0][1], winners[0][0])
    return out


def pass_probabilities(
    clusters: Sequence[NDArray[np.int64]],
    first: Sequence[Mapping[str, float]],
    others: Sequence[Sequence[tuple[NDArray[np.int64], Mapping[str, float]]]],
) -> list[dict[str, float]]:
    """P_obj|ont of clusters of the first pass, averaged over all the passes.

    Parameters
    ----------
    clusters : sequence of (k,) int
        Sorted point rows of the clusters of the first pass to average.
    first : sequence of mappings of str to float
        Their probabilities in the first pass (by class, with ``"none"``).
    others : sequence of sequences of (rows, probabilities)
        Every cluster of every other pass.

    Returns
    -------
    list of dict
        For each cluster, the mean over the passes of the probabilities of the cluster
        of that pass that covers it with point IoU ≥ ``VOTE_IOU``; a pass with no such
        cluster saw no object there and counts as ``{"none": 1}``.

    Examples
    --------
    >>> a, b = np.arange(0, 10), np.arange(20, 30)
    >>> p = pass_probabilities([a], [{"chair": 0.1, "none": 0.9}],
    ...                        [[(a[1:], {"chair": 0.7, "none": 0.3})], [(b, {"chair": 1.0})]])
    >>> {k: round(v, 3) for k, v in p[0].items()}
    {'chair': 0.267, 'none': 0.733}
    """
    sums = [dict(p) for p in first]
    if clusters:
        mine = [Instance.make(k, "", rows) for k, rows in enumerate(clusters)]
        for run in others:
            theirs = [Instance.make(j, "", rows) for j, (rows, _) in enumerate(run)]
            iou = overlap_matrix(mine, theirs)[0] if theirs else np.zeros((len(mine), 0))
            for k, total in enumerate(sums):
                j = int(np.argmax(iou[k])) if iou.shape[1] else -1
                seen = run[j][1] if j >= 0 and iou[k, j] >= VOTE_IOU else {"none": 1.0}
                for name, p in seen.items():
                    total[name] = total.get(name, 0.0) + float(p)
    n = len(others) + 1
    return [{name: total / n for name, total in s.items()} for s in sums]


def class_for_label(ontology: Ontology, label: str, costs: Mapping[str, float]) -> str:
    """The reported class written under ``label`` that costs least in ``costs`` (the
    energy's U per class; ties go to the name first in order): the class a cluster the
    first pass left out is reported as when the other passes found it a ``label``."""
    names = [o.name for o in ontology.classes if o.label == label and o.detect]
    if not names:
        raise InvalidParameterError("label", "the label of a reported class", label)
    return min(names, key=lambda n: (costs.get(n, math.inf), n))


def _vote(
    cloud: PointCloud,
    seg: Segmentation,
    scores: list[ClusterScores],
    choices: list[LabelChoice],
    found: list[Detection],
    others: list[list[PassCluster]],
    ontology: Ontology,
) -> tuple[list[Detection], list[LabelChoice]]:
    """Keep what a majority of the passes found (:func:`majority_labels`), on the first
    pass's clusters: a detection only the first pass made goes, and one the first pass
    missed but most of the others made comes back on the first pass's cluster. What is
    kept carries the probabilities averaged over the passes (:func:`pass_probabilities`)."""
    first = {d.cluster: d for d in found}
    rows = [np.sort(cloud.index[c.point_indices]) for c in seg]
    kept = majority_labels(
        rows,
        {k: d.label for k, d in first.items()},
        [[(label, r) for r, _, label in run if label is not None] for run in others],
    )
    passes = len(others) + 1
    choices = list(choices)
    out: list[Detection] = []
    for k in first:
        if k not in kept:
            choices[k] = LabelChoice(
                None,
                choices[k].costs,
                f"found by fewer than half of {passes} passes",
                {"class": choices[k].extra["class"]},
            )
    ks = sorted(kept)
    means = pass_probabilities(
        [rows[k] for k in ks],
        [scores[k].probabilities for k in ks],
        [[(r, p) for r, p, _ in run] for run in others],
    )
    for k, mean in zip(ks, means):
        label, n = kept[k]
        probabilities = {name: p for name, p in mean.items() if name != "none"}
        if k in first and first[k].label == label:
            out.append(
                dataclasses.replace(
                    first[k],
                    votes=n,
                    probabilities=probabilities,
                    score=label_probability(probabilities, ontology, label),
                )
            )
            continue
        cls_name = class_for_label(ontology, label, choices[k].costs)
        choices[k] = LabelChoice(label, choices[k].costs, "", {"class": cls_name})
        out.append(
            _detection(
                cloud,
                seg,
                k,
                scores[k],
                label,
                cls_name,
                choices[k].costs,
                ontology,
                votes=n,
                probabilities=mean,
            )
        )
    return out, choices
