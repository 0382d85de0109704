"""Measured constraint values of ground-truth objects (the samples the fit uses)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InvalidParameterError, OntoDetectError
from ..evaluation._dataset import (
    _class_id_lists,
    _class_ids,
    read_scene_cloud,
)
from ..evaluation._match import Instance, instances_from_labels, overlap_matrix
from ..io._layouts import SceneSource
from ..ontology import score_class
from ..segment import segment
from ..segment._measure import describe_clusters
from ._settings import MIN_CLUSTER_IOU, ConstraintPath


def constraint_values(cls: Any, score: Any) -> dict[ConstraintPath, float]:
    """The measured value of every constraint of a :class:`~ontodetect.ontology.ClassScore`.

    Parameters
    ----------
    cls : ObjectClass
        The class scored.
    score : ClassScore
        ``score_class(cls, description)``: its constraints hold the values of the best
        assignment (parts without a plane and relations involving them have none).

    Returns
    -------
    dict
        Constraint path -> finite value.
    """
    parts = {p.name for p in cls.parts}
    used: set[tuple[int, str]] = set()
    out: dict[ConstraintPath, float] = {}
    for cv in score.constraints:
        if cv.gaussian is None or cv.value is None or not math.isfinite(cv.value):
            continue
        path: ConstraintPath | None = None
        if cv.part == "cluster":
            path = (cls.name, "cluster", cv.feature)
        elif cv.part in parts:
            path = (cls.name, "parts", cv.part, cv.feature)
        else:
            for i, rel in enumerate(cls.relations):
                if (
                    f"{rel.a}~{rel.b}" == cv.part
                    and cv.feature in rel.constraints
                    and (i, cv.feature) not in used
                ):
                    used.add((i, cv.feature))
                    path = (cls.name, "relations", i, cv.feature)
                    break
        if path is not None:
            out[path] = float(cv.value)
    return out


@dataclass(frozen=True)
class ValidationScene:
    """What re-detecting a calibration scene with another ontology needs.

    Segmentation does not depend on the ontology, so a scene is segmented once and its
    clusters are scored and labelled again for every candidate ontology.

    Attributes
    ----------
    name : str
    descriptions : tuple of ClusterDescription
        One per cluster.
    centers : (k, 3) float
        Cluster box centres (for the labelling's context term).
    members : tuple of (m,) int arrays
        Each cluster's points as rows of the input file.
    gts : tuple of Instance
        Ground truth of the reported classes, as rows of the input file.
    """

    name: str
    descriptions: tuple[Any, ...]
    centers: np.ndarray
    members: tuple[np.ndarray, ...]
    gts: tuple[Instance, ...]


@dataclass(frozen=True)
class SceneSamples:
    """Constraint values measured in one calibration scene.

    Attributes
    ----------
    name : str
    values : dict
        Constraint path -> list of values (one per object that calibrated it).
    used, skipped : dict of str to int
        Objects per class that gave values, and that had no cluster with point IoU
        >= :data:`MIN_CLUSTER_IOU`.
    error : str or None
    scene : ValidationScene or None
        The scene's clusters and ground truth, when asked for (``keep_clusters``).
    """

    name: str
    values: dict[ConstraintPath, list[float]] = field(default_factory=dict)
    used: dict[str, int] = field(default_factory=dict)
    skipped: dict[str, int] = field(default_factory=dict)
    error: str | None = None
    scene: ValidationScene | None = None


def best_kind(ontology: Any, names: Sequence[str], description: Any) -> tuple[Any, Any]:
    """Of the classes ``names`` (kinds of one ground-truth class, such as a table and a side
    table), the one whose likelihood on the cluster ``description`` is highest, with its
    :class:`ontodetect.ontology.ClassScore`; the first of equals."""

    if not names:
        raise InvalidParameterError("names", "at least one class name", names)
    scored = [(ontology[n], score_class(ontology[n], description)) for n in names]
    return max(scored, key=lambda t: t[1].log_likelihood)


def collect_scene_samples(
    source: SceneSource,
    ontology: Any,
    *,
    class_ids: Mapping[int, str] | None = None,
    segment_options: Mapping[str, Any] | None = None,
    min_iou: float = MIN_CLUSTER_IOU,
    keep_clusters: bool = False,
) -> SceneSamples:
    """Measure every constraint on the ground-truth objects of one scene.

    Parameters
    ----------
    source : SceneSource
    ontology : Ontology
        The classes whose constraints are measured.
    class_ids : mapping of int to str, optional
        Ground-truth class id -> ontology class name; from the classes' ``matches`` by
        default (including classes that are not reported, such as stools). Where several
        classes match one ground truth (a table and a side table), each object is measured
        against the one whose likelihood on its cluster is highest.
    segment_options : mapping, optional
        ``config``, ``seed``, ``up``, ``scale`` of :func:`ontodetect.segment.segment`.
    min_iou : float
        Least point IoU between an object and its cluster.
    keep_clusters : bool
        Also return the clusters and the reported classes' ground truth
        (:class:`ValidationScene`) for the nested check of :func:`select_groups`.
    """

    opts = dict(segment_options or {})
    ids = _class_ids(ontology, reported_only=False, attr="name") if class_ids is None else class_ids
    # Classes that match the same ground truth (a table and a side table) are kinds of it:
    # each object is measured against the kind that explains its cluster best.
    kinds: dict[str, list[str]] = {}
    for names in _class_id_lists(ontology, reported_only=False, attr="name").values():
        group = kinds.setdefault(names[0], [])
        group.extend(n for n in names if n not in group)
    try:
        cloud = read_scene_cloud(source)
        gts = instances_from_labels(cloud.fields["instance"], cloud.fields["class_id"], ids)
        if not gts and not keep_clusters:
            return SceneSamples(source.name)
        seg = segment(
            cloud,
            opts.get("config"),
            seed=opts.get("seed", 0),
            up=opts.get("up"),
            scale=opts.get("scale"),
        )
    except OntoDetectError as exc:
        return SceneSamples(source.name, error=str(exc))
    clusters = [Instance.make(k, "cluster", c.point_indices) for k, c in enumerate(seg)]
    iou, _ = overlap_matrix(clusters, gts)
    values: dict[ConstraintPath, list[float]] = {}
    used: dict[str, int] = {}
    skipped: dict[str, int] = {}
    # Described as detect describes them, with what stands beside each cluster.
    descriptions = describe_clusters(seg)
    for g, gt in enumerate(gts):
        if not clusters or iou[:, g].max() < min_iou:
            skipped[gt.label] = skipped.get(gt.label, 0) + 1
            continue
        k = int(np.argmax(iou[:, g]))
        cls, score = best_kind(ontology, kinds.get(gt.label, [gt.label]), descriptions[k])
        for path, v in constraint_values(cls, score).items():
            values.setdefault(path, []).append(v)
        used[cls.name] = used.get(cls.name, 0) + 1
    scene = None
    if keep_clusters:
        # The same ground truth and point rows as evaluate_scene uses for detections.
        reported = _class_ids(ontology, reported_only=True, attr="label")
        eval_gts = instances_from_labels(
            cloud.fields["instance"],
            cloud.fields["class_id"],
            reported,
            xyz=cloud.xyz,
            index=cloud.index,
        )
        centers = np.array([c.box.center for c in seg]) if len(seg) else np.zeros((0, 3))
        scene = ValidationScene(
            source.name,
            tuple(descriptions),
            np.asarray(centers, dtype=np.float64),
            tuple(np.sort(cloud.index[c.point_indices]) for c in seg),
            tuple(eval_gts),
        )
    return SceneSamples(source.name, values, used, skipped, scene=scene)


# -- fitting -------------------------------------------------------------------------------
