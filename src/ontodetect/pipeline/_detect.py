"""The whole method in one call: read → prepare → segment → score → label (→ vote).

:func:`detect` takes a :class:`~ontodetect.cloud.PointCloud` and returns a
:class:`~ontodetect.pipeline.Result` holding the detections (in the input file's frame
and units, with the input file's point rows), every cluster's scores for ``--explain``,
and the intermediate results.
"""

from __future__ import annotations

import multiprocessing
import threading
import time
import warnings
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._parallel import cpu_count, fork_context
from .._progress import progress, use_reporter
from ..cloud import DataWarning, PointCloud, as_position, pixel_grid, sensor_position
from ..config import Config
from ..errors import InvalidParameterError
from ..labeling import LabelChoice, label_clusters
from ..ontology import ClusterScores, Ontology, builtin_ontology, class_priors, score_cluster
from ..preprocess import Ground, find_ground, smooth_depth
from ..segment import Segmentation, segment
from ..segment._measure import describe_clusters
from ._result import Detection, Result, _detection
from ._vote import PassCluster, _vote, vote_turns

__all__ = ["detect"]


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
