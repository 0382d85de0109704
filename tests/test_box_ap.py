"""Box AP at 3D IoU 0.25 / 0.5, axis-aligned and oriented, on hand-made boxes."""

import json
import math

import numpy as np
import pytest

from ontodetect import point_cloud
from ontodetect.evaluation import (
    BoxInstance,
    box_average_precision,
    box_iou,
    boxes_from_instances,
    evaluate_dataset,
    scene_boxes,
    write_report,
)
from ontodetect.evaluation._match import Instance
from ontodetect.io import write_detections

CLASS_IDS = {5: "chair", 7: "table", 14: "table"}


def box(label="chair", center=(0, 0, 0.5), size=(1, 1, 1), yaw=0.0, score=1.0):
    return BoxInstance.make(label, center, size, yaw, score)


@pytest.mark.parametrize("oriented", [False, True])
@pytest.mark.parametrize(
    ("other", "expected"),
    [
        (box(), 1.0),
        (box(center=(0.5, 0, 0.5)), 1 / 3),  # half overlap in x: 0.5 / 1.5
        (box(center=(0, 0, 1.0)), 1 / 3),  # half overlap in height
        (box(center=(3, 0, 0.5)), 0.0),
        (box(size=(2, 1, 1)), 0.5),  # inside a box twice as long
        (box(center=(0.5, 0.5, 0.5)), 1 / 7),  # a quarter of the footprint
    ],
)
def test_iou_of_hand_made_boxes(other, expected, oriented):
    assert box_iou(box(), other, oriented=oriented) == pytest.approx(expected)
    assert box_iou(other, box(), oriented=oriented) == pytest.approx(expected)


def test_oriented_and_axis_aligned_iou_differ_for_turned_boxes():
    turned = box(yaw=math.pi / 4)
    # octagon 2(sqrt2 - 1) over 2 - octagon
    octagon = 2 * (math.sqrt(2) - 1)
    assert box_iou(box(), turned, oriented=True) == pytest.approx(octagon / (2 - octagon))
    # the envelope of the turned box is sqrt2 x sqrt2: IoU 1 / 2
    assert box_iou(box(), turned) == pytest.approx(0.5)
    # a long box turned a quarter turn is the same box for both (length and width swap)
    a, b = box(size=(2, 1, 1)), box(size=(1, 2, 1), yaw=math.pi / 2)
    assert box_iou(a, b, oriented=True) == pytest.approx(1.0)
    assert box_iou(a, b) == pytest.approx(1.0)


def test_ap_of_a_hand_made_ranking():
    gt1 = [box(center=(0, 0, 0.5)), box(center=(5, 0, 0.5)), box("table", center=(9, 9, 0.4))]
    gt2 = [box(center=(0, 0, 0.5))]
    preds1 = [
        box(center=(0.1, 0, 0.5), score=0.9),  # TP
        box(center=(0.0, 0, 0.5), score=0.8),  # duplicate: FP
        box(center=(5.59, 0, 0.5), score=0.7),  # IoU 0.41 / 1.59: TP at 0.25 only
    ]
    preds2 = [box(center=(20, 0, 0.5), score=0.95)]  # FP ranked first
    scenes = [(preds1, gt1), (preds2, gt2)]
    at25 = box_average_precision(scenes, ["chair", "table"], iou_threshold=0.25)
    # by score: FP, TP, FP, TP; 3 ground truth -> precision 1/2 at recall 1/3, 1/2 at 2/3
    assert at25["chair"] == pytest.approx(0.5 * 1 / 3 + 0.5 * 1 / 3)
    assert at25["table"] == 0.0  # ground truth, no detection
    assert at25["mean"] == pytest.approx(at25["chair"] / 2)
    at50 = box_average_precision(scenes, ["chair"], iou_threshold=0.5)
    assert at50["chair"] == pytest.approx(0.5 * 1 / 3)
    # a detection in one scene never matches the ground truth of another
    swapped = box_average_precision([(preds2, gt1), (preds1, gt2)], ["chair"])
    assert swapped["chair"] == pytest.approx(0.5 * 1 / 3)
    assert math.isnan(box_average_precision([([], [])], ["sofa"])["sofa"])


def test_ground_truth_boxes_from_both_layouts():
    votenet = [[1, 2, 0.5, 0.4, 0.5, 1.0, 5], [0, 0, 0, 1, 1, 1, 2], [3, 3, 0.4, 2, 1, 0.8, 14]]
    got = boxes_from_instances(votenet, CLASS_IDS)
    assert [b.label for b in got] == ["chair", "table"]
    assert got[0].center.tolist() == [1, 2, 0.5] and got[0].yaw == 0.0
    synth = [
        {"class_id": 7, "box": {"center": [1, 1, 0.4], "size": [1.2, 0.8, 0.75], "yaw": 0.3}},
        {"class_id": 1, "box": {"center": [0, 0, 1], "size": [5, 0.1, 2], "yaw": 0.0}},
    ]
    [table] = boxes_from_instances(synth, CLASS_IDS)
    assert (table.label, table.yaw, table.size.tolist()) == ("table", 0.3, [1.2, 0.8, 0.75])


def test_scene_boxes_turn_with_the_scan_or_come_from_the_points():
    xyz = np.array([[0, 0, 0], [2, 1, 1], [5, 5, 5.0]])
    cloud = point_cloud(xyz, meta={"boxes": [[1, 0, 0.5, 2, 1, 1, 5]]})
    [b] = scene_boxes(cloud, [], CLASS_IDS, turn=90)
    assert b.center == pytest.approx([0, 1, 0.5], abs=1e-12)
    assert b.yaw == pytest.approx(math.pi / 2)
    plain = point_cloud(xyz)
    [g] = scene_boxes(plain, [Instance.make(1, "chair", [0, 1])], CLASS_IDS)
    assert g.center.tolist() == [1, 0.5, 0.5] and g.size.tolist() == [2, 1, 1]


def test_eval_reports_box_ap_from_the_datasets_boxes(tmp_path):
    root = tmp_path / "dev"
    root.mkdir()
    n = 40
    xyz = np.column_stack([np.arange(n, dtype=float), np.zeros(n), np.full(n, 0.5)])
    vert = np.column_stack([xyz, np.full((n, 3), 128)]).astype(np.float32)
    np.save(root / "scene0000_00_vert.npy", vert)
    np.save(root / "scene0000_00_sem_label.npy", np.array([5] * 10 + [2] * 30, np.uint32))
    np.save(root / "scene0000_00_ins_label.npy", np.array([1] * 10 + [0] * 30, np.uint32))
    np.save(root / "scene0000_00_bbox.npy", np.array([[4.5, 0, 0.5, 9, 1, 1, 5]]))
    dets = tmp_path / "dets" / "scene0000_00"
    dets.mkdir(parents=True)
    doc = {
        "format": "ontodetect.detections/1",
        "source": "x",
        "num_points": n,
        "frame": {"up": [0, 0, 1], "ground_z": 0.0, "scale": 1.0},
        "detections": [
            {
                "id": 1,
                "label": "chair",
                "score": 0.9,
                # 3 of 9 m long: IoU 1/3 -> a hit at 0.25, a miss at 0.5
                "box": {"center": [1.5, 0, 0.5], "size": [3, 1, 1], "yaw": 0.0},
                "point_indices": list(range(10)),
            }
        ],
    }
    write_detections(dets / "detections.json", doc)
    ev = evaluate_dataset(root, detections_dir=tmp_path / "dets")
    assert ev.box_ap["aligned@0.25"]["chair"] == pytest.approx(1.0)
    assert ev.box_ap["oriented@0.25"]["chair"] == pytest.approx(1.0)
    assert ev.box_ap["aligned@0.5"]["chair"] == 0.0
    assert math.isnan(ev.box_ap["aligned@0.25"]["sofa"])
    files = write_report(ev, tmp_path / "report")
    assert "## Box AP" in files.markdown.read_text()
    saved = json.loads(files.json.read_text())
    assert saved["box_ap"]["aligned@0.25"] == {
        "chair": 1.0,
        "sofa": None,
        "table": None,
        "mean": 1.0,
    }
