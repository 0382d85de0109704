"""Matching detections to ground-truth instances (docs/evaluation.md, "How a detection is scored").

A detection is a true positive when its point set overlaps an unmatched
ground-truth instance of the same class with IoU >= the threshold; detections
are taken greedily by descending score. The distance criterion of Günther et
al. (centre within 15 cm for chairs, 45 cm for tables) is offered beside it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..config import SHARE, check_param
from ..errors import InvalidParameterError
from ..geometry import point_overlap

__all__ = [
    "DISTANCE_THRESHOLDS",
    "Instance",
    "MatchResult",
    "instances_from_labels",
    "match_instances",
    "overlap_matrix",
]

#: Günther et al.: a detection counts when its centre is this close to the object's (m).
DISTANCE_THRESHOLDS: dict[str, float] = {"chair": 0.15, "table": 0.45, "sofa": 0.45}
#: Distance threshold for classes the table above does not list (m).
DEFAULT_DISTANCE = 0.3


@dataclass(frozen=True)
class Instance:
    """One object: a ground-truth instance or a detection.

    Attributes
    ----------
    id : int
        Instance id (ground truth) or detection id.
    label : str
        Class name (``chair``, ``sofa``, ``table``...).
    points : (k,) int
        Indices of its points in the input file, sorted and unique.
    score : float
        Detection score (1 for ground truth).
    center : (3,) float or None
        Centre, for the distance criterion.
    """

    id: int
    label: str
    points: NDArray[np.int64]
    score: float = 1.0
    center: NDArray[np.float64] | None = None

    @classmethod
    def make(
        cls,
        id: int,
        label: str,
        points: ArrayLike,
        score: float = 1.0,
        center: ArrayLike | None = None,
    ) -> Instance:
        pts = np.unique(np.asarray(points, dtype=np.int64))
        c = None if center is None else np.asarray(center, dtype=np.float64)
        return cls(int(id), str(label), pts, float(score), c)


def instances_from_labels(
    instance: ArrayLike,
    class_id: ArrayLike,
    class_names: Mapping[int, str],
    *,
    xyz: ArrayLike | None = None,
    index: ArrayLike | None = None,
) -> list[Instance]:
    """Ground-truth instances from per-point instance and class ids.

    Parameters
    ----------
    instance : (n,) int
        Instance id per point, 0 for none.
    class_id : (n,) int
        Class id per point.
    class_names : mapping of int to str
        Which class ids are evaluated and under which name (e.g. NYU40 5 -> chair,
        7 and 14 -> table). Instances of other classes are left out.
    xyz : (n, 3) float, optional
        Points, for the instance centres (centre of the bounding box).
    index : (n,) int, optional
        Row of each point in the input file (``PointCloud.index``); default 0..n-1.
    """
    inst = np.asarray(instance).astype(np.int64, copy=False)
    cls = np.asarray(class_id).astype(np.int64, copy=False)
    if inst.shape != cls.shape or inst.ndim != 1:
        raise InvalidParameterError("instance", f"the shape of class_id {cls.shape}", inst.shape)
    rows = np.arange(len(inst)) if index is None else np.asarray(index, dtype=np.int64)
    pts = None if xyz is None else np.asarray(xyz, dtype=np.float64)
    out = []
    order = np.argsort(inst, kind="stable")
    ids, starts = np.unique(inst[order], return_index=True)
    bounds = [*starts[1:], len(order)]
    for iid, a, b in zip(ids, starts, bounds):
        if iid <= 0:
            continue
        members = order[a:b]
        # An instance's class is the most common class id among its points.
        values, counts = np.unique(cls[members], return_counts=True)
        cid = int(values[np.argmax(counts)])
        if cid not in class_names:
            continue
        center = None
        if pts is not None:
            p = pts[members]
            center = (p.min(axis=0) + p.max(axis=0)) / 2
        out.append(Instance.make(int(iid), class_names[cid], rows[members], 1.0, center))
    return out


def overlap_matrix(
    preds: Sequence[Instance], gts: Sequence[Instance]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """(p, g) IoU and intersection counts between every detection and ground-truth instance
    (:func:`ontodetect.geometry.point_overlap` of their points)."""
    return point_overlap([p.points for p in preds], [g.points for g in gts])


@dataclass(frozen=True)
class MatchResult:
    """How detections and ground truth were paired.

    Attributes
    ----------
    pred_match : (p,) int
        Index of the ground-truth instance each detection matched, -1 for none.
    gt_match : (g,) int
        Index of the detection each ground-truth instance matched, -1 for none.
    pred_iou : (p,) float
        IoU with the matched instance (or the best same-class overlap when unmatched).
    """

    pred_match: NDArray[np.int64]
    gt_match: NDArray[np.int64]
    pred_iou: NDArray[np.float64]
    criterion: str
    extra: dict = field(default_factory=dict)

    @property
    def true_positives(self) -> NDArray[np.bool_]:
        return self.pred_match >= 0


def match_instances(
    preds: Sequence[Instance],
    gts: Sequence[Instance],
    *,
    criterion: str = "iou",
    iou_threshold: float = 0.25,
    distance_thresholds: Mapping[str, float] | None = None,
    class_agnostic: bool = False,
) -> MatchResult:
    """Match detections to ground truth greedily by descending score.

    Parameters
    ----------
    preds, gts : sequences of Instance
        Detections and ground-truth instances.
    criterion : {"iou", "distance"}
        Point-set IoU >= ``iou_threshold`` (docs/evaluation.md), or centre distance within
        the class's threshold (Günther et al.).
    class_agnostic : bool
        Match regardless of class (for the confusion matrix).

    Examples
    --------
    >>> gt = [Instance.make(1, "chair", range(0, 10))]
    >>> det = [Instance.make(1, "chair", range(5, 15), 0.9),
    ...        Instance.make(2, "chair", range(0, 10), 0.5)]
    >>> match_instances(det, gt).pred_match.tolist()  # IoU 5/15 >= 0.25; the higher score first
    [0, -1]
    """
    if criterion not in ("iou", "distance"):
        raise InvalidParameterError("criterion", "'iou' or 'distance'", criterion)
    check_param("iou_threshold", SHARE, iou_threshold)
    thresholds = {**DISTANCE_THRESHOLDS, **(distance_thresholds or {})}
    iou, _ = overlap_matrix(preds, gts)
    pred_match = np.full(len(preds), -1, dtype=np.int64)
    gt_match = np.full(len(gts), -1, dtype=np.int64)
    pred_iou = np.zeros(len(preds))
    order = sorted(range(len(preds)), key=lambda i: (-preds[i].score, i))
    for i in order:
        p = preds[i]
        same = np.array([class_agnostic or g.label == p.label for g in gts], dtype=bool)
        free = gt_match < 0
        if criterion == "iou":
            cand = np.where(same & free, iou[i], -1.0)
            if len(cand) and same.any():
                pred_iou[i] = float(np.max(np.where(same, iou[i], 0.0)))
            if len(cand) == 0 or cand.max() < iou_threshold - 1e-12:
                continue
            k = int(np.argmax(cand))
            pred_iou[i] = float(iou[i, k])
        else:
            if p.center is None:
                raise InvalidParameterError(
                    "preds",
                    "instances with centres for the distance criterion",
                    f"detection {p.id} without one",
                )
            dist = np.array(
                [
                    np.inf
                    if g.center is None or not (s and f)
                    else float(np.linalg.norm((g.center - p.center)[:2]))
                    for g, s, f in zip(gts, same, free)
                ]
            )
            limit = thresholds.get(p.label, DEFAULT_DISTANCE)
            if len(dist) == 0 or dist.min() > limit:
                continue
            k = int(np.argmin(dist))
            pred_iou[i] = float(iou[i, k])
        pred_match[i] = k
        gt_match[k] = i
    return MatchResult(pred_match, gt_match, pred_iou, criterion)
