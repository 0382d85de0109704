"""What :func:`~ontodetect.pipeline.detect` returns: :class:`Detection` and :class:`Result`,
and how a cluster of the segmentation becomes a detection in the input file's frame.

:meth:`Result.to_dict` is the ``detections.json`` document (docs/detections-format.md);
its format tag is :data:`ontodetect.io.DETECTIONS_FORMAT`, defined once in ``io``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..cad import cad_dict
from ..cloud import PointCloud
from ..errors import InvalidParameterError
from ..io._detections import DETECTIONS_FORMAT
from ..labeling import LabelChoice, label_clusters, label_probability
from ..ontology import ClusterScores, Ontology
from ..segment import Cluster, Segmentation

__all__ = ["DETECTIONS_FORMAT", "Detection", "Result", "with_cad"]


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
    candidates : list
        With ``detect.proposals: recognition``, every candidate object scored
        (``pipeline._recognize.Candidate``); empty with the vote.
    environment : dict
        Where the environment prior came from (``source``: ``scan``, ``images``,
        ``scan+images``, ``given`` or ``none``) and the P_N used (``rooms``).
    ballots : dict of int to list
        With the vote, for each cluster some pass found an object in: what every pass
        made of its points (``pipeline._vote.Ballot``, the first pass first); empty
        with one pass.
    """

    cloud: PointCloud
    detections: list[Detection]
    segmentation: Segmentation
    scores: list[ClusterScores]
    choices: list[LabelChoice]
    ontology: Ontology
    priors: dict[str, float]
    timings: dict[str, float] = field(default_factory=dict)
    candidates: list[Any] = field(default_factory=list)
    environment: dict[str, Any] = field(default_factory=dict)
    ballots: dict[int, list[Any]] = field(default_factory=dict)

    @property
    def frame(self) -> dict[str, Any]:
        prep = self.segmentation.prepared
        scatter = prep.info.get("floor_scatter")
        return {
            "up": [round(float(v), 6) for v in prep.up],
            "ground_z": round(float(prep.floor_z), 6),
            "scale": round(float(prep.scale), 9),
            "floor_scatter": None if scatter is None else round(float(scatter), 5),
        }

    def to_dict(self) -> dict[str, Any]:
        """The ``detections.json`` document (docs/detections-format.md)."""
        return {
            "format": DETECTIONS_FORMAT,
            "source": str(self.cloud.meta.get("source", "")),
            "num_points": int(self.cloud.index.max() + 1) if len(self.cloud) else 0,
            "frame": self.frame,
            "detections": [d.to_dict() for d in self.detections],
            "priors": {k: round(v, 4) for k, v in self.priors.items()},
            **({"environment": _environment_doc(self.environment)} if self.environment else {}),
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


def _environment_doc(environment: Mapping[str, Any]) -> dict[str, Any]:
    """``detections.json``'s ``environment``: the source and P_N, most likely first."""
    out = {k: v for k, v in environment.items() if k != "rooms"}
    rooms = environment.get("rooms")
    if rooms:
        ranked = sorted(rooms.items(), key=lambda kv: (-kv[1], kv[0]))
        out["rooms"] = {k: round(float(v), 4) for k, v in ranked}
    return out


def with_cad(result: Result, fits: Sequence[Any]) -> Result:
    """The result with each detection's ``cad`` entry filled from its CAD fit (same order)."""
    if len(fits) != len(result.detections):
        raise InvalidParameterError(
            "fits", f"one fit per detection ({len(result.detections)})", len(fits)
        )
    detections = [dataclasses.replace(d, cad=cad_dict(f)) for d, f in zip(result.detections, fits)]
    return dataclasses.replace(result, detections=detections)


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
        plane = cluster.scored_planes[k]
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


def label_and_detect(
    cloud: PointCloud,
    seg: Segmentation,
    scores: Sequence[ClusterScores],
    ontology: Ontology,
    settings: Any,
    *,
    found: bool = True,
) -> tuple[list[LabelChoice], list[Detection]]:
    """One label per cluster by the energy (``settings``: ``config.detect``), and a
    :class:`Detection` (numbered 0, in cluster order) per labelled cluster when ``found``."""
    centers = np.array([c.box.center for c in seg]) if len(seg) else np.zeros((0, 3))
    choices = label_clusters(
        scores,
        [c.planes for c in seg],
        ontology,
        beta=settings.beta,
        threshold=settings.threshold,
        centers=centers,
        context=settings.context,
        explain_away=settings.explain_away,
    )
    detections = [
        _detection(
            cloud, seg, k, scores[k], choice.label, choice.extra["class"], choice.costs, ontology
        )
        for k, choice in enumerate(choices)
        if found and choice.label is not None
    ]
    return choices, detections


def numbered_result(
    cloud: PointCloud,
    found: list[Detection],
    **parts: Any,
) -> Result:
    """The :class:`Result` of ``found``, best score first, numbered from 1 (``parts``: the
    other fields of :class:`Result`)."""
    found = sorted(found, key=lambda d: (-d.score, d.cluster))
    detections = [Detection(**{**d.__dict__, "id": i + 1}) for i, d in enumerate(found)]
    return Result(cloud=cloud, detections=detections, **parts)
