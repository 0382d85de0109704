"""Matching and metrics on hand-made cases."""

import numpy as np
import pytest

from ontodetect.errors import InvalidParameterError
from ontodetect.evaluation import (
    NYU40_CLASSES,
    Instance,
    SceneResult,
    average_precision,
    evaluate_scenes,
    instances_from_labels,
    match_instances,
    overlap_matrix,
)


def inst(i, label, a, b, score=1.0, center=None):
    return Instance.make(i, label, range(a, b), score, center)


def test_iou_exactly_at_the_threshold_counts():
    gt = [inst(1, "chair", 0, 100)]
    # 25 shared points, union 100: IoU exactly 0.25
    det = [inst(1, "chair", 0, 25, 0.9)]
    assert overlap_matrix(det, gt)[0][0, 0] == pytest.approx(0.25)
    assert match_instances(det, gt).pred_match.tolist() == [0]
    just_below = [inst(1, "chair", 0, 24, 0.9)]
    assert match_instances(just_below, gt).pred_match.tolist() == [-1]


def test_duplicates_only_one_true_positive_greedy_by_score():
    gt = [inst(1, "chair", 0, 100)]
    det = [inst(1, "chair", 0, 90, 0.4), inst(2, "chair", 0, 60, 0.8)]
    m = match_instances(det, gt)
    assert m.pred_match.tolist() == [-1, 0]  # the higher score takes the instance
    assert m.gt_match.tolist() == [1]


def test_class_mismatch_is_not_a_match_but_shows_in_the_confusion():
    gt = [inst(1, "chair", 0, 100)]
    det = [inst(1, "table", 0, 100, 0.9)]
    assert match_instances(det, gt).pred_match.tolist() == [-1]
    ev = evaluate_scenes([SceneResult("s", det, gt)])
    labels = ev.confusion_labels
    assert ev.confusion[labels.index("chair"), ev.classes.index("table")] == 1
    assert ev.per_class["chair"].fn == 1 and ev.per_class["table"].fp == 1


def test_metrics_against_hand_computation():
    gts = [inst(1, "chair", 0, 100), inst(2, "chair", 100, 200), inst(3, "table", 200, 400)]
    preds = [
        inst(1, "chair", 0, 80, 0.9),
        inst(2, "chair", 300, 320, 0.8),
        inst(3, "chair", 100, 190, 0.7),
        inst(4, "table", 200, 400, 0.6),
    ]
    ev = evaluate_scenes([SceneResult("s", preds, gts)])
    chair = ev.per_class["chair"]
    assert (chair.tp, chair.fp, chair.fn) == (2, 1, 0)
    assert chair.precision == pytest.approx(2 / 3)
    assert chair.recall == pytest.approx(1.0)
    assert chair.f1 == pytest.approx(2 * (2 / 3) / (2 / 3 + 1))
    # PR points: (1, .5), (.5, .5), (2/3, 1): interpolated AP = .5*1 + .5*(2/3)
    assert chair.ap == pytest.approx(0.5 + 0.5 * 2 / 3)
    assert ev.overall.tp == 3 and ev.overall.num_gt == 3 and ev.overall.num_pred == 4
    assert ev.confusion[ev.confusion_labels.index("false alarm"), 0] == 1


def test_average_precision_edge_cases():
    assert average_precision(np.array([]), np.array([], bool), 3) == 0.0
    assert np.isnan(average_precision(np.array([0.5]), np.array([False]), 0))
    assert average_precision(np.array([0.9, 0.1]), np.array([True, True]), 2) == 1.0


def test_distance_criterion_of_gunther():
    gt = [inst(1, "chair", 0, 10, center=[0, 0, 0.4]), inst(2, "table", 10, 20, center=[2, 0, 0.7])]
    det = [
        inst(1, "chair", 50, 60, 0.9, center=[0.1, 0.1, 0.5]),
        inst(2, "table", 60, 70, 0.9, center=[2.5, 0, 0.7]),
    ]
    m = match_instances(det, gt, criterion="distance")
    assert m.pred_match.tolist() == [0, -1]  # 14 cm chair ok, 50 cm table too far
    with pytest.raises(InvalidParameterError, match="criterion"):
        match_instances(det, gt, criterion="centre")


def test_instances_from_labels_maps_nyu40_and_file_rows():
    inst_ids = np.array([0, 1, 1, 2, 2, 2, 3, 3])
    cls = np.array([0, 5, 5, 14, 14, 14, 3, 3])
    xyz = np.arange(24, dtype=float).reshape(8, 3)
    got = instances_from_labels(inst_ids, cls, NYU40_CLASSES, xyz=xyz, index=np.arange(8) + 10)
    assert [(g.id, g.label, g.points.tolist()) for g in got] == [
        (1, "chair", [11, 12]),
        (2, "table", [13, 14, 15]),
    ]
    assert got[0].center.tolist() == pytest.approx([4.5, 5.5, 6.5])
