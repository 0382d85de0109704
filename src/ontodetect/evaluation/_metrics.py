"""Precision, recall, F1, average precision and the confusion matrix over many scenes."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._match import Instance, match_instances

__all__ = [
    "ClassMetrics",
    "Evaluation",
    "SceneResult",
    "average_precision",
    "evaluate_scenes",
    "precision_recall_curve",
]

MISSED = "missed"
FALSE_ALARM = "false alarm"


def _ratio(a: float, b: float) -> float:
    return float(a) / float(b) if b else 0.0


def precision_recall_curve(
    scores: NDArray[np.float64], is_tp: NDArray[np.bool_], num_gt: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Precision and recall after each detection, by descending score.

    Returns
    -------
    precision, recall, thresholds : (k,) float
    """
    scores = np.asarray(scores, dtype=np.float64)
    order = np.argsort(-scores, kind="stable")
    tp = np.cumsum(np.asarray(is_tp, dtype=bool)[order])
    fp = np.cumsum(~np.asarray(is_tp, dtype=bool)[order])
    precision = tp / np.maximum(tp + fp, 1)
    recall = tp / num_gt if num_gt else np.zeros_like(precision)
    return precision, recall, scores[order]


def average_precision(scores: NDArray[np.float64], is_tp: NDArray[np.bool_], num_gt: int) -> float:
    """Area under the interpolated precision–recall curve (all-point, as PASCAL VOC 2010+).

    Examples
    --------
    >>> import numpy as np
    >>> average_precision(np.array([0.9, 0.8, 0.7]), np.array([True, False, True]), 2)
    0.8333333333333333
    """
    if num_gt == 0:
        return float("nan")
    precision, recall, _ = precision_recall_curve(scores, is_tp, num_gt)
    if len(precision) == 0:
        return 0.0
    r = np.concatenate([[0.0], recall, [recall[-1]]])
    p = np.concatenate([[0.0], precision, [0.0]])
    p = np.maximum.accumulate(p[::-1])[::-1]  # interpolate: best precision at >= recall
    steps = np.nonzero(r[1:] != r[:-1])[0]
    return float(np.sum((r[steps + 1] - r[steps]) * p[steps + 1]))


@dataclass(frozen=True)
class ClassMetrics:
    """Counts and rates for one class (or "overall")."""

    label: str
    num_gt: int
    num_pred: int
    tp: int
    fp: int
    fn: int
    precision: float
    recall: float
    f1: float
    ap: float

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class SceneResult:
    """One scene's detections and ground truth, with how they matched."""

    name: str
    preds: Sequence[Instance]
    gts: Sequence[Instance]
    seconds: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Evaluation:
    """Everything a report shows."""

    classes: list[str]
    criterion: str
    iou_threshold: float
    per_class: dict[str, ClassMetrics]
    overall: ClassMetrics
    confusion_labels: list[str]  # rows: ground truth + "false alarm"; cols: predicted + "missed"
    confusion: NDArray[np.int64]
    per_scene: list[dict[str, Any]]
    curves: dict[str, tuple[NDArray[np.float64], NDArray[np.float64]]]

    def to_dict(self) -> dict[str, Any]:
        return {
            "criterion": self.criterion,
            "iou_threshold": self.iou_threshold,
            "classes": self.classes,
            "per_class": {k: v.to_dict() for k, v in self.per_class.items()},
            "overall": self.overall.to_dict(),
            "confusion": {
                "labels": self.confusion_labels,
                "rows": "ground truth (+ false alarm)",
                "cols": "predicted (+ missed)",
                "matrix": self.confusion.tolist(),
            },
            "per_scene": self.per_scene,
        }


def _metrics(label: str, num_gt: int, scores: list[float], tps: list[bool]) -> ClassMetrics:
    tp = int(sum(tps))
    fp = len(tps) - tp
    fn = num_gt - tp
    p = _ratio(tp, tp + fp)
    r = _ratio(tp, num_gt)
    f1 = _ratio(2 * p * r, p + r)
    ap = average_precision(np.asarray(scores), np.asarray(tps, dtype=bool), num_gt)
    return ClassMetrics(label, num_gt, len(tps), tp, fp, fn, p, r, f1, ap)


def evaluate_scenes(
    scenes: Sequence[SceneResult],
    classes: Sequence[str] = ("chair", "sofa", "table"),
    *,
    criterion: str = "iou",
    iou_threshold: float = 0.25,
) -> Evaluation:
    """Match every scene and aggregate per class and overall.

    Detections and instances of classes outside ``classes`` are ignored.
    """
    classes = list(classes)
    scores: dict[str, list[float]] = {c: [] for c in classes}
    tps: dict[str, list[bool]] = {c: [] for c in classes}
    num_gt = dict.fromkeys(classes, 0)
    labels = [*classes, FALSE_ALARM]
    cols = [*classes, MISSED]
    confusion = np.zeros((len(labels), len(cols)), dtype=np.int64)
    per_scene = []
    for scene in scenes:
        preds = [p for p in scene.preds if p.label in classes]
        gts = [g for g in scene.gts if g.label in classes]
        m = match_instances(preds, gts, criterion=criterion, iou_threshold=iou_threshold)
        row: dict[str, Any] = {"scene": scene.name, "seconds": round(scene.seconds, 3)}
        for c in classes:
            idx = [i for i, p in enumerate(preds) if p.label == c]
            scores[c] += [preds[i].score for i in idx]
            tps[c] += [bool(m.pred_match[i] >= 0) for i in idx]
            n_gt = sum(g.label == c for g in gts)
            num_gt[c] += n_gt
            n_tp = sum(bool(m.pred_match[i] >= 0) for i in idx)
            row[c] = {"gt": n_gt, "pred": len(idx), "tp": n_tp}
        per_scene.append(row)
        # Confusion: class-agnostic matching at the same criterion.
        ma = match_instances(
            preds, gts, criterion=criterion, iou_threshold=iou_threshold, class_agnostic=True
        )
        for i, k in enumerate(ma.pred_match):
            r = classes.index(gts[k].label) if k >= 0 else len(classes)
            confusion[r, classes.index(preds[i].label)] += 1
        for k, i in enumerate(ma.gt_match):
            if i < 0:
                confusion[classes.index(gts[k].label), len(classes)] += 1
    per_class = {c: _metrics(c, num_gt[c], scores[c], tps[c]) for c in classes}
    all_scores = [s for c in classes for s in scores[c]]
    all_tps = [t for c in classes for t in tps[c]]
    overall = _metrics("overall", sum(num_gt.values()), all_scores, all_tps)
    curves = {}
    for c in classes:
        p, r, _ = precision_recall_curve(np.asarray(scores[c]), np.asarray(tps[c], bool), num_gt[c])
        curves[c] = (p, r)
    return Evaluation(
        classes, criterion, iou_threshold, per_class, overall, labels, confusion, per_scene, curves
    )
