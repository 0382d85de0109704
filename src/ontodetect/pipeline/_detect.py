"""The whole method in one call: read → prepare → segment → score → label (→ vote).

:func:`detect` takes a :class:`~ontodetect.cloud.PointCloud` and returns a
:class:`~ontodetect.pipeline.Result` holding the detections (in the input file's frame
and units, with the input file's point rows), every cluster's scores for ``--explain``,
and the intermediate results.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import threading
import time
import warnings
from collections.abc import Mapping, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._parallel import cpu_count, fork_context, one_blas_thread
from .._progress import progress, use_reporter
from .._rules import SEED
from .._up import inferred_view
from ..cloud import DataWarning, PointCloud, as_position, pixel_grid, sensor_position
from ..config import COUNT, Config, Nullable, check_param
from ..errors import InvalidParameterError
from ..io._budget import check_extent
from ..labeling import LabelChoice
from ..ontology import (
    ClusterScores,
    Ontology,
    builtin_ontology,
    class_priors,
    relative_priors,
    room_area_likelihood,
    room_distribution,
    rooms_from_objects,
    score_cluster,
    score_near,
    with_priors,
)
from ..preprocess import Ground, GroundPlane, find_ground, floor_area, smooth_depth
from ..segment import Segmentation, segment
from ..segment._measure import describe_clusters
from ._recognize import recognize
from ._result import Detection, Result, label_and_detect, numbered_result
from ._vote import PassCluster, _vote, vote_turns

__all__ = ["detect"]


#: One pass: its clusters, their scores and labels, its detections and its timings.
_Pass = tuple[
    Segmentation, list[ClusterScores], list[LabelChoice], list[Detection], dict[str, float]
]


@dataclass(frozen=True)
class _PassInputs:
    """What every pass shares besides the scan and its configuration."""

    ontology: Ontology
    priors: Mapping[str, float]
    seed: int
    viewpoint: NDArray[np.float64] | None = None
    ground: Ground | None = None


@one_blas_thread
def detect(
    cloud: PointCloud,
    *,
    config: Config | None = None,
    ontology: Ontology | None = None,
    room: str | Mapping[str, float] | None = "auto",
    indoor: float | None = None,
    jobs: int | None = None,
    seed: int = 0,
    viewpoint: Sequence[float] | None = None,
    scene_rooms: Mapping[str, float] | None = None,
    plane: GroundPlane | None = None,
) -> Result:
    """Find the objects an ontology describes in a point cloud.

    Parameters
    ----------
    cloud : PointCloud
        The scan (any units and up direction the preparation can handle).
    config : Config, optional
        Parameters of every stage (defaults: Table 4.1): among them the decision
        threshold, the energy's β, the likelihood of "none", the seat-near-table term
        and the vote (``detect.*``), the up axis and the scale factor (``prepare.up``,
        ``prepare.scale``). Change single values with :meth:`Config.replace` or
        :meth:`Config.with_overrides`, e.g.
        ``Config().with_overrides(["detect.votes=1", "prepare.up=auto"])``.
    ontology : Ontology, optional
        Classes to look for; the built-in furniture ontology by default.
    room : str, mapping or None
        The environment prior P_N (Eq. 3.10): a room category (``"office"``), a
        distribution over categories, ``"auto"`` (the default) to estimate it from the
        scan itself — a first labelling with every class competing says what the room
        holds (:func:`ontodetect.ontology.rooms_from_objects`), and the labelling runs
        again with the classes the room makes unlikely explained away
        (:func:`ontodetect.ontology.relative_priors`) — or None for no prior.
    scene_rooms : mapping, optional
        P_N from photographs of the scene (:func:`ontodetect.environment.predict_environment`).
        With ``room="auto"`` it is combined with the scan's estimate
        (:func:`ontodetect.environment.combine_room_priors`); alone (``room=None``) it is
        the P_N of Eq. 3.10.
    indoor : float, optional
        P(indoor) for the indoor/outdoor prior (Eq. 3.5).
    jobs : int, optional
        Worker processes (forked) for the passes after the first (``detect.votes``),
        while this process makes the first; 1: all in this process; 0: one per usable
        CPU, as for :func:`ontodetect.evaluation.evaluate_dataset`. By default one per
        CPU where the platform can fork, if this process runs no other thread (a number
        given here forks anyway). The result does not depend on it.
    seed : int
        Seed of every random step.
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
    seed = check_param("seed", SEED, seed)
    # A point kilometres away would stretch every grid and fit downstream: refused here.
    check_extent(cloud.meta.get("source") or "<cloud>", cloud.xyz)
    config = config or Config()
    d = config.detect
    if viewpoint is not None:
        cloud = cloud.with_meta(sensor_position=as_position(viewpoint).tolist())
    eye = sensor_position(cloud)
    frame = inferred_view(cloud) if d.infer_view and eye is None else None
    if frame is not None:
        warnings.warn(
            f"{cloud.meta.get('source') or 'the cloud'}: one view seen from the origin (all of "
            "it in a cone from there, one surface per sight line): taken as a depth frame "
            "with its sensor there (--viewpoint X,Y,Z to place it elsewhere, --set "
            "detect.infer_view=false to keep it a scan)",
            DataWarning,
            stacklevel=2,
        )
        cloud = frame
        eye = sensor_position(cloud)
    elif eye is not None and pixel_grid(cloud) is None:
        warnings.warn(
            "a viewpoint but no pixel grid: if this is a depth camera's frame, its "
            "depth steps stay unsmoothed and read as flat parts (give the organized "
            "frame, such as its PCD)",
            DataWarning,
            stacklevel=2,
        )
    ontology = (ontology or builtin_ontology()).reporting(config.detect.classes)
    auto = isinstance(room, str) and room == "auto"
    if auto and indoor is not None:  # P(indoor) given: Eq. 3.5 instead of an estimate
        auto, room = False, None
    if scene_rooms is not None and not auto:
        if room is not None:
            raise InvalidParameterError("scene_rooms", "not combined with a room given", room)
        room = scene_rooms
    priors = class_priors(ontology, None if auto else room, indoor)
    environment = _environment_given(room, indoor, scene_rooms, auto)
    if d.proposals == "recognition":
        return _recognition_result(cloud, config, ontology, priors, seed, eye, plane)
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
    ground = find_ground(scan, config, plane=plane) if turned or plane is not None else None
    shared = _PassInputs(ontology, priors, seed, eye, ground)
    before = time.perf_counter() - t0
    with _OtherPasses(scan, shared, turned, workers, wait=auto) as others:
        first = None
        if auto:
            first, priors, environment = _room_pass(scan, config, shared, scene_rooms)
            shared = dataclasses.replace(shared, priors=priors)
            others.send_priors(priors)
        seg, scores, choices, found, timings = _one_pass(scan, config, shared, first=first)
        passes = others.results()
    timings["segment"] += before
    ballots = {}
    if turned:
        turns = vote_turns(len(turned) + 1, d.vote_turn)
        found, choices, ballots = _vote(
            cloud, seg, scores, choices, found, passes, ontology, turns, d.vote_abstain
        )
        timings["votes"] = time.perf_counter() - t0 - sum(timings.values())
    return numbered_result(
        cloud,
        found,
        segmentation=seg,
        scores=scores,
        choices=choices,
        ontology=ontology,
        priors=priors,
        timings=timings,
        environment=environment,
        ballots=ballots,
    )


def _room_shape(
    seg: Segmentation, cloud: PointCloud, eye: NDArray[np.float64] | None
) -> tuple[dict[str, float] | None, dict[str, Any]]:
    """The likelihood of each room category from the floor area a pass's scene covers
    (``detect.room_shape``), and what ``detections.json`` records of it."""
    area = floor_area(seg.prepared.voxels.centers)
    whole = eye is None and pixel_grid(cloud) is None  # a fused scan, not one view
    if area <= 0:
        return None, {}
    return room_area_likelihood(area, whole_room=whole), {
        "floor_area": round(area, 2),
        "whole_room": whole,
    }


def _environment_given(
    room: str | Mapping[str, float] | None,
    indoor: float | None,
    scene_rooms: Mapping[str, float] | None,
    auto: bool,
) -> dict[str, Any]:
    """Where P_N comes from when the scan does not estimate it (``detections.json``)."""
    if auto:
        return {"source": "scan"}
    if scene_rooms is not None:
        return {"source": "images", "rooms": room_distribution(scene_rooms)}
    if room is not None:
        return {"source": "given", "rooms": room_distribution(room)}
    if indoor is not None:
        return {"source": "given", "indoor": indoor}
    return {"source": "none"}


def _found_objects(
    choices: Sequence[LabelChoice], scores: Sequence[ClusterScores], ontology: Ontology
) -> list[dict[str, float]]:
    """What a labelling found, every class competing: for each labelled cluster, the
    classes of the label it was given (a table or a side table, a sink or a basin: one
    thing described two ways) and their probabilities. (Not the whole posterior: a dozen
    chairs that each look a little like a WC are a dozen chairs, not a bathroom.)"""
    out = []
    for choice, score in zip(choices, scores):
        name = choice.extra.get("class")
        if name is None:
            continue
        label = ontology[name].label if name in ontology else name
        out.append(
            {
                c: float(p)
                for c, p in score.probabilities.items()
                if c == name or (c in ontology and ontology[c].label == label)
            }
        )
    return out


def _recognition_result(
    cloud: PointCloud,
    config: Config,
    ontology: Ontology,
    priors: Mapping[str, float],
    seed: int,
    eye: NDArray[np.float64] | None,
    plane: GroundPlane | None = None,
) -> Result:
    """:func:`detect` with ``detect.proposals: recognition`` (:func:`recognize`)."""
    t0 = time.perf_counter()
    scan = smooth_depth(cloud) if config.prepare.depth_smoothing else cloud
    ground = None if plane is None else find_ground(scan, config, plane=plane)
    before = time.perf_counter() - t0
    seg, scores, choices, found, timings, candidates = recognize(
        scan, config, ontology, priors, seed=seed, viewpoint=eye, ground=ground
    )
    timings["segment"] += before
    return numbered_result(
        cloud,
        found,
        segmentation=seg,
        scores=scores,
        choices=choices,
        ontology=ontology,
        priors=dict(priors),
        timings=timings,
        candidates=candidates,
    )


def _vote_workers(jobs: int | None, passes: int) -> int:
    """Worker processes for ``passes`` extra passes (0: make them in this process)."""
    jobs = check_param("jobs", Nullable(COUNT), jobs)
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


def _room_pass(
    scan: PointCloud,
    config: Config,
    shared: _PassInputs,
    scene_rooms: Mapping[str, float] | None,
) -> tuple[_Pass, dict[str, float], dict[str, Any]]:
    """A first labelling, every class competing and no prior, says what the room holds:
    the pass, the class priors relative to the room it gives (and to photographs, when
    given) and the ``environment`` entry of the result."""
    first = _one_pass(scan, config, shared)
    shape, area_seen = (
        _room_shape(first[0], scan, shared.viewpoint) if config.detect.room_shape else (None, {})
    )
    found = _found_objects(first[2], first[1], shared.ontology)
    rooms = rooms_from_objects(found, shared.ontology, shape=shape)
    if scene_rooms is not None:
        from ..environment import combine_room_priors  # lazy: only with photographs

        rooms = combine_room_priors(rooms, scene_rooms)
    environment = {
        "source": "scan+images" if scene_rooms else "scan",
        "rooms": rooms,
        **area_seen,
    }
    return first, relative_priors(shared.ontology, rooms), environment


class _OtherPasses:
    """The passes after the first (``turned``: the configuration of each), in forked
    workers that start at once (``workers`` > 0) or in this process when their results
    are asked for.

    With ``wait``, the class priors come from the first labelling of this process
    (:meth:`send_priors`): the workers segment and score meanwhile and wait for them
    before labelling (the likelihoods do not depend on the priors, only the posterior
    does, as in :func:`ontodetect.ontology.with_priors`), so the passes end as if they
    had known the priors from the start.
    """

    def __init__(
        self,
        scan: PointCloud,
        shared: _PassInputs,
        turned: Sequence[Config],
        workers: int,
        *,
        wait: bool,
    ) -> None:
        self._scan, self._shared, self._turned = scan, shared, list(turned)
        self._workers, self._wait = workers, wait
        self._pool: ProcessPoolExecutor | None = None
        self._inbox: Any = None
        self._futures: list[Future[list[PassCluster]]] = []
        self._owed = 0

    def __enter__(self) -> _OtherPasses:
        if self._workers and self._turned:
            context = fork_context()
            self._inbox = context.SimpleQueue() if self._wait else None
            self._pool = ProcessPoolExecutor(
                max_workers=self._workers,
                mp_context=context,
                # Inherited at the fork, never pickled: the scan can be large.
                initializer=_start_vote_worker,
                initargs=(self._scan, self._shared, self._inbox),
            )
            self._futures = [self._pool.submit(_worker_pass, c) for c in self._turned]
            self._owed = len(self._futures) if self._wait else 0
        return self

    def send_priors(self, priors: Mapping[str, float]) -> None:
        """The class priors of every pass, once this process knows them."""
        self._shared = dataclasses.replace(self._shared, priors=priors)
        for _ in range(self._owed):
            self._inbox.put(dict(priors))
        self._owed = 0

    def results(self) -> list[list[PassCluster]]:
        """Every cluster of every pass, in the order of ``turned``."""
        if self._pool is not None:
            return [f.result() for f in self._futures]
        return [_pass_clusters(self._scan, c, self._shared) for c in self._turned]

    def __exit__(self, *exc: object) -> None:
        for _ in range(self._owed):  # no priors will come (this process failed): stop
            self._inbox.put(None)
        self._owed = 0
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)


#: What a vote worker keeps from the process that forked it (:func:`_start_vote_worker`).
_worker_state: dict[str, Any] = {}


def _start_vote_worker(scan: PointCloud, shared: _PassInputs, inbox: Any) -> None:
    """Keep, in a forked worker, the scan, what every pass shares and where the class
    priors arrive when the parent estimates them (``inbox``; None when they are known)."""
    _worker_state.update(scan=scan, shared=shared, inbox=inbox)


def _worker_pass(config: Config) -> list[PassCluster]:
    """One pass in a vote worker; with an inbox, scored under the first pass's priors,
    then labelled under those the parent sends (None: it failed; the pass is dropped)."""
    scan, shared, inbox = (_worker_state[k] for k in ("scan", "shared", "inbox"))
    if inbox is None:
        return _pass_clusters(scan, config, shared)
    with use_reporter(None):  # a forked worker must not draw the parent's progress bars
        unlabelled = _one_pass(scan, config, shared, found=False, label=False)
    priors = inbox.get()
    if priors is None:
        return []
    return _pass_clusters(scan, config, dataclasses.replace(shared, priors=priors), unlabelled)


def _pass_clusters(
    cloud: PointCloud, config: Config, shared: _PassInputs, first: _Pass | None = None
) -> list[PassCluster]:
    """Every cluster of one pass, as the vote needs it (a unit of work for a worker);
    ``first`` as for :func:`_one_pass`."""
    with use_reporter(None):  # a forked worker must not draw the parent's progress bars
        seg, scores, choices, _, _ = _one_pass(cloud, config, shared, found=False, first=first)
    return [
        (np.sort(cloud.index[c.point_indices]), dict(s.probabilities), ch.label)
        for c, s, ch in zip(seg, scores, choices)
    ]


def _one_pass(
    cloud: PointCloud,
    config: Config,
    shared: _PassInputs,
    *,
    found: bool = True,
    first: _Pass | None = None,
    label: bool = True,
) -> _Pass:
    """Segment, score and label once; detections (when ``found``) numbered 0, in cluster
    order. With ``first`` (this pass made with other priors), its clusters and their
    likelihoods are kept and only the priors change. Without ``label``, no labels nor
    detections (empty lists): the pass is to be labelled under other priors."""
    d, ontology = config.detect, shared.ontology
    if first is not None:
        seg, scores, _, _, timings = first
        t0 = time.perf_counter()
        scores = [with_priors(s, shared.priors, none_likelihood=d.none_likelihood) for s in scores]
        timings = {**timings, "score": timings["score"] + time.perf_counter() - t0}
    else:
        timings = {}
        t0 = time.perf_counter()
        seg = segment(cloud, config, seed=shared.seed, ground=shared.ground, ontology=ontology)
        timings["segment"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        scores = []
        with progress("Scoring clusters", total=len(seg)) as advance:
            for desc in describe_clusters(seg, shared.viewpoint):
                scores.append(
                    score_cluster(desc, ontology, shared.priors, none_likelihood=d.none_likelihood)
                )
                advance(1)
        # What stands beside each cluster (a nightstand by a bed), once all are scored.
        scores = score_near(
            scores, [c.box for c in seg], ontology, none_likelihood=d.none_likelihood
        )
        timings["score"] = time.perf_counter() - t0

    if not label:
        return seg, scores, [], [], timings
    t0 = time.perf_counter()
    choices, detections = label_and_detect(cloud, seg, scores, ontology, d, found=found)
    timings["label"] = time.perf_counter() - t0
    return seg, scores, choices, detections, timings
