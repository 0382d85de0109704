"""Evaluation against ground truth: matching, precision/recall/F1, AP and confusion matrices.

A detection is a true positive when its points overlap an unmatched ground-truth
instance of the same class with IoU >= 0.25 (0.5 is reported too), matched
greedily by descending score (DESIGN.md). NYU40 ids map to classes as ScanNet
uses them: chair 5, sofa 6, table 7 and desk 14 (counted as table).
"""

from __future__ import annotations

from ._match import (
    DISTANCE_THRESHOLDS,
    Instance,
    MatchResult,
    instances_from_labels,
    match_instances,
    overlap_matrix,
)
from ._metrics import (
    ClassMetrics,
    Evaluation,
    SceneResult,
    average_precision,
    evaluate_scenes,
    precision_recall_curve,
)

__all__ = [
    "DISTANCE_THRESHOLDS",
    "NYU40_CLASSES",
    "ClassMetrics",
    "Evaluation",
    "Instance",
    "MatchResult",
    "SceneResult",
    "average_precision",
    "evaluate_scenes",
    "instances_from_labels",
    "match_instances",
    "overlap_matrix",
    "precision_recall_curve",
]

#: NYU40 class id -> evaluated class (desks count as tables).
NYU40_CLASSES: dict[int, str] = {5: "chair", 6: "sofa", 7: "table", 14: "table"}
