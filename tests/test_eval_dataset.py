"""Dataset discovery and loading in every layout, and dataset evaluation on stored detections."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest

from ontodetect import InvalidParameterError, ReadError, point_cloud, write_cloud
from ontodetect.cloud import sensor_position
from ontodetect.config import Config
from ontodetect.evaluation import (
    NYU40_CLASSES,
    SceneError,
    SceneSource,
    discover_scenes,
    evaluate_dataset,
    evaluate_scene,
    evaluation_classes,
    load_scene,
    map_scenes,
    markdown_report,
    read_scene_detections,
    scene_group,
)
from ontodetect.evaluation._dataset import turn_cloud
from ontodetect.io._detections import write_detections
from ontodetect.ontology import parse_ontology

#: Detection options of one pass per scan (faster; the vote is tested in test_pipeline.py).
ONE_PASS = {"config": Config().replace(detect={"votes": 1})}

LABEL_TABLE = (
    "id\traw_category\tcategory\tcount\tnyu40id\tnyu40class\n"
    "1\tchair\tchair\t10\t5\tchair\n"
    "2\tdesk\tdesk\t10\t14\tdesk\n"
    "3\tfloor\tfloor\t10\t2\tfloor\n"
)


# -- generated datasets --------------------------------------------------------------------
def votenet_scene(folder, scene, sem, ins, xyz=None):
    """One VoteNet scan: points on a line (x = row) unless given."""
    n = len(sem)
    if xyz is None:
        xyz = np.column_stack([np.arange(n), np.zeros(n), np.full(n, 0.5)])
    vert = np.column_stack([xyz, np.full((n, 3), 128)]).astype(np.float32)
    np.save(folder / f"{scene}_vert.npy", vert)
    np.save(folder / f"{scene}_sem_label.npy", np.asarray(sem, dtype=np.uint32))
    np.save(folder / f"{scene}_ins_label.npy", np.asarray(ins, dtype=np.uint32))


# Rows 0-9 a chair (instance 1), 10-29 a desk (instance 2, a table), 30-39 floor.
SEM = [5] * 10 + [14] * 20 + [2] * 10
INS = [1] * 10 + [2] * 20 + [0] * 10


def make_votenet(root, scenes=("scene0000_00", "scene0000_01", "scene0002_00")):
    root.mkdir(parents=True, exist_ok=True)
    for s in scenes:
        votenet_scene(root, s, SEM, INS)
    (root / "scannetv2-labels.combined.tsv").write_text(LABEL_TABLE)
    return root


def release_scan(folder, scene, groups):
    """A ScanNet release scan: 6 vertices, segments 10/20/30, objects over segments."""
    folder.mkdir(parents=True)
    xyz = np.column_stack([np.arange(6.0), np.zeros(6), np.full(6, 0.4)])
    write_cloud(folder / f"{scene}_vh_clean_2.ply", point_cloud(xyz))
    (folder / f"{scene}_vh_clean_2.0.010000.segs.json").write_text(
        json.dumps({"segIndices": [10, 10, 20, 20, 30, 30]})
    )
    seg_groups = [
        {"objectId": oid, "label": label, "segments": segs} for oid, label, segs in groups
    ]
    (folder / f"{scene}.aggregation.json").write_text(json.dumps({"segGroups": seg_groups}))


def s3dis_room(folder, objects):
    ann = folder / "Annotations"
    ann.mkdir(parents=True)
    for k, (name, rows) in enumerate(objects):
        pts = np.column_stack([np.arange(rows) + 10 * k, np.zeros(rows), np.full(rows, 0.5)])
        body = "\n".join(" ".join(f"{v:g}" for v in [*p, 100, 100, 100]) for p in pts)
        (ann / f"{name}.txt").write_text(body + "\n")


def synth_scene(folder, instance, class_id):
    """A folder in the project's own synthetic layout, written by hand."""
    folder.mkdir(parents=True)
    n = len(instance)
    xyz = np.column_stack([np.arange(n, dtype=float), np.zeros(n), np.full(n, 0.5)])
    fields = {
        "instance": np.asarray(instance, np.int32),
        "class_id": np.asarray(class_id, np.int32),
    }
    write_cloud(folder / "cloud.ply", point_cloud(xyz, fields=fields))
    (folder / "objects.json").write_text(json.dumps({"format": "x", "objects": []}))
    (folder / "scene.json").write_text(json.dumps({"format": "ontodetect.synth/1"}))


def detections_doc(num_points, dets):
    return {
        "format": "ontodetect.detections/1",
        "source": "test",
        "num_points": num_points,
        "frame": {"up": [0, 0, 1], "ground_z": 0.0, "scale": 1.0},
        "detections": [
            {
                "id": i + 1,
                "label": label,
                "score": score,
                "box": {"center": list(center), "size": [1, 1, 1], "yaw": 0.0},
                "point_indices": list(points),
            }
            for i, (label, score, points, center) in enumerate(dets)
        ],
    }


# -- discovery -----------------------------------------------------------------------------
def test_votenet_folder_gives_one_scene_per_scan_with_rooms_grouped(tmp_path):
    root = make_votenet(tmp_path / "dev", ("scene0010_00", "scene0002_01", "scene0002_00"))
    (root / "notes.txt").write_text("not a scene")
    scenes = discover_scenes(root)
    assert [s.name for s in scenes] == ["scene0002_00", "scene0002_01", "scene0010_00"]
    assert {s.format for s in scenes} == {"scannet-votenet"}
    assert [s.group for s in scenes] == ["scene0002", "scene0002", "scene0010"]
    assert scenes[0].path.endswith("scene0002_00_vert.npy")


def test_a_scene_file_is_one_scene(tmp_path):
    root = make_votenet(tmp_path / "dev")
    (only,) = discover_scenes(root / "scene0002_00_sem_label.npy")
    assert only.name == "scene0002_00" and only.path.endswith("scene0002_00_vert.npy")


def test_natural_order_and_group_names():
    assert scene_group("scene0000_02") == "scene0000"
    assert scene_group("val/scene0011_01") == "val/scene0011"
    assert scene_group("Area_1/office_1") == "Area_1/office_1"


def test_scannet_release_scan_and_folder_of_scans(tmp_path):
    scans = tmp_path / "scans"
    release_scan(scans / "scene0001_00", "scene0001_00", [(0, "chair", [10]), (1, "desk", [20])])
    release_scan(scans / "scene0001_01", "scene0001_01", [(0, "chair", [30])])
    (scans / "scannetv2-labels.combined.tsv").write_text(LABEL_TABLE)
    scenes = discover_scenes(scans)
    assert [(s.name, s.format, s.group) for s in scenes] == [
        ("scene0001_00", "scannet", "scene0001"),
        ("scene0001_01", "scannet", "scene0001"),
    ]
    (one,) = discover_scenes(scans / "scene0001_00")
    assert one.name == "scene0001_00"
    loaded = load_scene(one)
    assert [(g.label, g.points.tolist()) for g in loaded.gts] == [
        ("chair", [0, 1]),
        ("table", [2, 3]),  # a desk counts as a table
    ]
    assert loaded.num_points == 6


def test_s3dis_area_and_dataset_of_areas(tmp_path):
    root = tmp_path / "s3dis"
    s3dis_room(root / "Area_1" / "office_10", [("chair_1", 4), ("floor_1", 3)])
    s3dis_room(root / "Area_1" / "office_2", [("table_1", 5), ("sofa_1", 2)])
    s3dis_room(root / "Area_2" / "hallway_1", [("wall_1", 3)])
    names = [s.name for s in discover_scenes(root)]
    assert names == ["Area_1/office_2", "Area_1/office_10", "Area_2/hallway_1"]
    area = discover_scenes(root / "Area_1")
    assert [s.name for s in area] == ["office_2", "office_10"]
    assert {s.format for s in area} == {"s3dis"}
    loaded = load_scene(area[0])
    assert sorted((g.label, len(g.points)) for g in loaded.gts) == [("sofa", 2), ("table", 5)]


def test_synthetic_dataset_and_single_synthetic_scene(tmp_path):
    root = tmp_path / "synth"
    for k in range(2):
        synth_scene(root / f"scene_{k:04d}", [0, 1, 1, 2, 2, 2], [2, 5, 5, 101, 101, 101])
    scenes = discover_scenes(root)
    assert [(s.name, s.format) for s in scenes] == [
        ("scene_0000", "ontodetect"),
        ("scene_0001", "ontodetect"),
    ]
    assert scenes[0].group != scenes[1].group
    (single,) = discover_scenes(root / "scene_0001")
    assert single.name == "scene_0001"
    (via_file,) = discover_scenes(root / "scene_0001" / "cloud.ply")
    assert via_file == single
    loaded = load_scene(single)
    # The stool (simulator id 101) is not evaluated: the built-in stool class is not reported.
    assert [(g.label, g.points.tolist()) for g in loaded.gts] == [("chair", [1, 2])]


def test_explicit_format_empty_folder_and_bad_names(tmp_path):
    root = make_votenet(tmp_path / "dev")
    assert len(discover_scenes(root, format="votenet")) == 3  # an alias
    with pytest.raises(ReadError, match="'s3dis' layout"):
        discover_scenes(root, format="s3dis")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ReadError, match="holds no scene"):
        discover_scenes(tmp_path / "empty")
    with pytest.raises(ReadError, match="no such"):
        discover_scenes(tmp_path / "missing")
    with pytest.raises(InvalidParameterError, match="'format' parameter"):
        discover_scenes(root, format="kitti")


def test_evaluated_classes_follow_the_ontology():
    assert evaluation_classes() == NYU40_CLASSES
    onto = parse_ontology(
        "format: ontodetect.ontology/1\n"
        "classes:\n"
        "  bed: {matches: [bed], parts: {top: {height: [0.3, 0.7]}}}\n"
        "  stool: {detect: false, matches: [stool], parts: {seat: {height: [0.4, 0.8]}}}\n"
        "  seat: {label: chair, matches: [chair, Night_Stand], parts: {s: {height: [0.4, 1]}}}\n"
    )
    assert evaluation_classes(onto) == {4: "bed", 5: "chair", 32: "chair"}


# -- evaluation on stored detections ---------------------------------------------------------
@pytest.fixture
def dataset(tmp_path):
    """Two scans with one chair (rows 0-9) and one table (rows 10-29) each, and detections."""
    root = make_votenet(tmp_path / "dev", ("scene0000_00", "scene0001_00"))
    dets = tmp_path / "dets"
    for scene, found in {
        # a perfect chair, a table that overlaps the floor only (false alarm)
        "scene0000_00": [
            ("chair", 0.9, range(10), (4.5, 0, 0.5)),
            ("table", 0.8, range(30, 40), (34.5, 0, 0.5)),
        ],
        # a chair at IoU 4/13 (>= 0.25, < 0.5) whose centre is 0.3 m off; the table found
        "scene0001_00": [
            ("chair", 0.7, range(6, 13), (4.8, 0, 0.5)),
            ("table", 0.6, range(10, 30), (19.5, 0, 0.5)),
        ],
    }.items():
        (dets / scene).mkdir(parents=True)
        write_detections(dets / scene / "detections.json", detections_doc(40, found))
    return root, dets


def test_stored_detections_are_scored_at_every_criterion(dataset):
    root, dets = dataset
    ev = evaluate_dataset(root, detections_dir=dets)
    assert [s.name for s in ev.scenes] == ["scene0000_00", "scene0001_00"]
    at25, at50, dist = (ev.evaluations[k] for k in ("iou@0.25", "iou@0.5", "distance"))
    assert (at25.per_class["chair"].tp, at25.per_class["chair"].fp) == (2, 0)
    assert (at25.per_class["table"].tp, at25.per_class["table"].fp) == (1, 1)
    assert at25.overall.precision == pytest.approx(3 / 4)
    assert at25.overall.recall == pytest.approx(3 / 4)
    assert at50.per_class["chair"].tp == 1  # IoU 4/13 < 0.5
    assert dist.per_class["chair"].tp == 1  # centre 30 cm away > 15 cm
    assert ev.options == {"detections": str(dets)}
    assert all(s.seconds == 0.0 and s.num_points == 40 for s in ev.scenes)


def test_detections_of_another_scan_are_refused_naming_the_scene(dataset, tmp_path):
    root, dets = dataset
    write_detections(dets / "scene0001_00" / "detections.json", detections_doc(41, []))
    with pytest.raises(SceneError, match=r"scene0001_00.*num_points is 41.*40 points"):
        evaluate_dataset(root, detections_dir=dets)
    ev = evaluate_dataset(root, detections_dir=dets, on_error="skip")
    assert [s.name for s in ev.scenes] == ["scene0000_00"]
    assert [s.name for s in ev.failed] == ["scene0001_00"]
    with pytest.raises(ReadError, match=r"detections\.json"):
        read_scene_detections(tmp_path / "nowhere", "scene0000_00")


def test_a_missing_detections_file_names_the_file(dataset):
    root, dets = dataset
    (dets / "scene0000_00" / "detections.json").unlink()
    with pytest.raises(SceneError, match=r"scene0000_00.*detections\.json: no such file"):
        evaluate_dataset(root, detections_dir=dets)


def test_worker_processes_give_the_same_evaluation(dataset):
    root, dets = dataset
    one = evaluate_dataset(root, detections_dir=dets, jobs=1).to_dict()
    two = evaluate_dataset(root, detections_dir=dets, jobs=2).to_dict()
    for doc in (one, two):
        doc.pop("seconds"), doc.pop("jobs"), doc.pop("scene_seconds")
        for s in doc["scenes"]:
            s.pop("load_seconds")
    # json: NaN (AP of a class without ground truth) compares equal to itself there
    assert json.dumps(one, sort_keys=True) == json.dumps(two, sort_keys=True)


def test_a_scene_is_a_picklable_unit_of_work(dataset):
    root, dets = dataset
    source = discover_scenes(root)[1]
    assert pickle.loads(pickle.dumps(source)) == source
    outcome = evaluate_scene(source, detections_dir=dets)
    back = pickle.loads(pickle.dumps(outcome))
    assert back.name == "scene0001_00" and len(back.preds) == 2 and len(back.gts) == 2
    bad = evaluate_scene(SceneSource("x", str(root / "x_vert.npy"), "scannet-votenet", "x"))
    assert not bad.ok and "x_vert.npy" in bad.error
    assert map_scenes(abs, [-3, 1, -2], jobs=1) == [3, 1, 2]
    assert map_scenes(abs, [-3, 1, -2], jobs=0) == [3, 1, 2]  # one per usable CPU
    with pytest.raises(InvalidParameterError, match="'jobs' parameter"):
        map_scenes(abs, [1], jobs=-1)
    with pytest.raises(InvalidParameterError, match="detect_options"):
        evaluate_dataset(root, detect_options={"colour": 1})


# -- turned and reseeded runs ----------------------------------------------------------------
def test_a_turned_scene_keeps_its_ground_truth_by_row_with_turned_centres(tmp_path):
    root = make_votenet(tmp_path / "dev", ("scene0000_00",))
    source = discover_scenes(root)[0]
    plain, turned = load_scene(source), load_scene(source, turn=90.0)
    assert [g.points.tolist() for g in turned.gts] == [g.points.tolist() for g in plain.gts]
    # the chair spans x = 0..9 on y = 0: its box centre (4.5, 0) turns to (0, 4.5)
    chair = next(g for g in turned.gts if g.label == "chair")
    assert np.allclose(chair.center, [0.0, 4.5, 0.5], atol=1e-5)
    assert np.allclose(turned.cloud.xyz[:, 1], plain.cloud.xyz[:, 0], atol=1e-5)


def test_a_turned_single_view_turns_its_sensor_too():
    frame = point_cloud([[2.0, 0.0, 0.5]]).with_meta(sensor_position=[1.0, 0.0, 1.5])
    turned = turn_cloud(frame, 90.0)
    assert np.allclose(turned.xyz, [[0.0, 2.0, 0.5]])
    assert np.allclose(sensor_position(turned), [0.0, 1.0, 1.5])


@pytest.mark.filterwarnings("ignore:no floor found")  # a line of points: nothing to find
def test_runs_per_turn_and_seed_are_named_pooled_and_reported_per_turn(tmp_path):
    root = make_votenet(tmp_path / "dev", ("scene0000_00", "scene0001_00"))
    ev = evaluate_dataset(
        root,
        turns=[0, 90],
        seeds=[0, 1],
        detect_options=ONE_PASS,
    )
    assert [s.name for s in ev.scenes[:4]] == [
        "scene0000_00@0deg-seed0",
        "scene0000_00@0deg-seed1",
        "scene0000_00@90deg-seed0",
        "scene0000_00@90deg-seed1",
    ]
    assert [(s.turn, s.seed) for s in ev.scenes[:2]] == [(0.0, 0), (0.0, 1)]
    assert list(ev.by_variant) == ["0°", "90°"]
    # every run sees the whole ground truth: 2 scenes x 4 runs, one chair and one table each
    assert ev.primary.per_class["chair"].num_gt == 8
    assert all(e.per_class["table"].num_gt == 4 for e in ev.by_variant.values())
    doc = ev.to_dict()
    assert doc["options"]["turns"] == [0.0, 90.0] and doc["options"]["seeds"] == [0, 1]
    assert "seed" not in doc["options"] and doc["scenes"][2]["turn"] == 90.0
    assert set(doc["by_variant"]) == {"0°", "90°"}
    # the report sums the four runs of a scene in one row; report.json keeps every run
    rows = markdown_report(ev).split("## Per scene")[1].split("\n## ")[0]
    scene_rows = [line for line in rows.splitlines() if line.startswith("| scene0")]
    assert [line.split(" | ")[:2] for line in scene_rows] == [
        ["| scene0000_00", "4"],
        ["| scene0001_00", "4"],
    ]
    # one chair and one table per run: 4 of each over the runs of a scene
    assert all(
        line.split(" | ")[4] == "4/0/0" and line.endswith("| 4/0/0 |") for line in scene_rows
    )
    assert len(doc["scenes"]) == 8

    seeded = evaluate_dataset(root, seeds=[3, 4], detect_options=ONE_PASS)
    assert [s.name for s in seeded.scenes[:2]] == ["scene0000_00@seed3", "scene0000_00@seed4"]
    assert list(seeded.by_variant) == ["seed 3", "seed 4"]
    assert evaluate_dataset(root, detect_options=ONE_PASS).by_variant == {}


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"turns": []}, "turns"),
        ({"turns": [0, 0]}, "turns"),
        ({"turns": [float("nan")]}, "turns"),
        ({"turns": ["90"]}, "turns"),
        ({"seeds": [-1]}, "seeds"),
        ({"seeds": [1.5]}, "seeds"),
        ({"seeds": [True]}, "seeds"),
    ],
)
def test_bad_turns_and_seeds_name_the_parameter(tmp_path, kwargs, name):
    root = make_votenet(tmp_path / "dev", ("scene0000_00",))
    with pytest.raises(InvalidParameterError, match=f"'{name}' parameter"):
        evaluate_dataset(root, **kwargs)


def test_stored_detections_cannot_be_turned(dataset):
    root, dets = dataset
    with pytest.raises(InvalidParameterError, match=r"'turns' parameter.*stored detections"):
        evaluate_dataset(root, detections_dir=dets, turns=[90])
    with pytest.raises(InvalidParameterError, match="'seeds' parameter"):
        evaluate_dataset(root, detections_dir=dets, seeds=[0, 1])
    with pytest.raises(InvalidParameterError, match="'turn' parameter"):
        evaluate_scene(discover_scenes(root)[0], detections_dir=dets, turn=90.0)
    with pytest.raises(InvalidParameterError, match="'turn' parameter"):
        evaluate_scene(discover_scenes(root)[0], turn=float("inf"))
