"""Evaluation against ground truth: matching, precision/recall/F1, AP and confusion matrices.

A detection is a true positive when its points overlap an unmatched ground-truth
instance of the same class with IoU >= 0.25 (0.5 is reported too), matched
greedily by descending score (docs/evaluation.md). NYU40 ids map to classes as ScanNet
uses them: chair 5, sofa 6, table 7 and desk 14 (counted as table).

- matching and metrics: :func:`match_instances`, :func:`evaluate_scenes`;
- datasets: :func:`discover_scenes`, :func:`evaluate_scene` (one unit of work),
  :func:`evaluate_dataset` (the map over scenes and the merge);
- reports: :func:`write_report` (report.md, report.json, pr_curves.png, confusion.png).

Calibration, which uses these, is its own stage: :mod:`ontodetect.calibrate`.
"""

from __future__ import annotations

from ._boxes import (
    BOX_IOU_THRESHOLDS,
    BoxInstance,
    box_average_precision,
    box_iou,
    boxes_from_instances,
)
from ._dataset import (
    CRITERIA,
    DATASET_FORMATS,
    DatasetEvaluation,
    LoadedScene,
    SceneError,
    SceneOutcome,
    SceneSource,
    discover_scenes,
    evaluate_dataset,
    evaluate_scene,
    evaluation_classes,
    first_pass_clusters,
    first_pass_lacks,
    load_scene,
    map_scenes,
    read_scene_detections,
    scene_boxes,
    scene_group,
    summarize_outcomes,
    turn_cloud,
    variant_name,
)
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
from ._report import ReportFiles, literature_comparisons, markdown_report, write_report

__all__ = [
    "BOX_IOU_THRESHOLDS",
    "CRITERIA",
    "DATASET_FORMATS",
    "DISTANCE_THRESHOLDS",
    "NYU40_CLASSES",
    "BoxInstance",
    "ClassMetrics",
    "DatasetEvaluation",
    "Evaluation",
    "Instance",
    "LoadedScene",
    "MatchResult",
    "ReportFiles",
    "SceneError",
    "SceneOutcome",
    "SceneResult",
    "SceneSource",
    "average_precision",
    "box_average_precision",
    "box_iou",
    "boxes_from_instances",
    "discover_scenes",
    "evaluate_dataset",
    "evaluate_scene",
    "evaluate_scenes",
    "evaluation_classes",
    "first_pass_clusters",
    "first_pass_lacks",
    "instances_from_labels",
    "literature_comparisons",
    "load_scene",
    "map_scenes",
    "markdown_report",
    "match_instances",
    "overlap_matrix",
    "precision_recall_curve",
    "read_scene_detections",
    "scene_boxes",
    "scene_group",
    "summarize_outcomes",
    "turn_cloud",
    "variant_name",
    "write_report",
]

#: NYU40 class id -> evaluated class (desks count as tables).
NYU40_CLASSES: dict[int, str] = {5: "chair", 6: "sofa", 7: "table", 14: "table"}
