"""SUN RGB-D frames as VoteNet stores them: ``<id>_pc.npz`` (array ``pc``, colours 0..1) and
``<id>_bbox.npy`` (centre, half sizes, heading, class index), read as a labelled scan and
evaluated as a dataset layout."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect.cli import main
from ontodetect.cloud import DataWarning
from ontodetect.errors import CorruptFileError, ReadError
from ontodetect.evaluation import discover_scenes, evaluate_dataset, load_scene
from ontodetect.geometry import box_corners
from ontodetect.io import detect_format, expand_inputs, read_cloud
from ontodetect.io._sunrgbd import SUNRGBD_CLASSES, boxes_to_labels, read_sunrgbd_votenet

CHAIR, TABLE = 3, 1  # VoteNet's class indices


def _votenet_corners(center, half, heading):
    """VoteNet's ``my_compute_box_3d``: the corners are rotz(-heading) of the local ones."""
    lx, ly, lz = half
    local = np.array(
        [
            [sx * lx, sy * ly, sz * lz]
            for sz in (1, -1)
            for sx, sy in ((-1, 1), (1, 1), (1, -1), (-1, -1))
        ]
    )
    c, s = math.cos(-heading), math.sin(-heading)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    return local @ rot.T + np.asarray(center)


def _write_frame(folder, name, pc, boxes):
    folder.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(folder / f"{name}_pc.npz", pc=np.asarray(pc, np.float32))
    np.save(folder / f"{name}_bbox.npy", np.asarray(boxes, np.float64).reshape(-1, 8))
    return folder / f"{name}_pc.npz"


def test_an_npz_with_votenets_pc_array_reads_as_points_and_colours(tmp_path):
    pc = np.array([[0.0, 1.0, 0.2, 1.0, 0.5, 0.0], [0.1, 1.2, 0.3, 0.0, 0.0, 1.0]], np.float32)
    np.savez_compressed(tmp_path / "000007_pc.npz", pc=pc)
    cloud = read_cloud(tmp_path / "000007_pc.npz")
    assert np.allclose(cloud.xyz, pc[:, :3])
    assert cloud.rgb.tolist() == [[255, 128, 0], [0, 0, 255]]


@settings(max_examples=60, deadline=None)
@given(
    heading=st.floats(-math.pi, math.pi),
    center=st.tuples(*[st.floats(-3, 3)] * 3),
    half=st.tuples(*[st.floats(0.1, 1.0)] * 3),
)
def test_a_point_is_in_a_box_exactly_when_inside_votenets_corners(heading, center, half):
    corners = _votenet_corners(center, half, heading)
    c = np.asarray(center)
    inside = c + 0.98 * (corners - c)  # just within each corner
    outside = c + 1.03 * (corners - c)  # just beyond it
    boxes = np.array([[*center, *half, heading, CHAIR]])
    instance, class_id = boxes_to_labels(np.vstack([inside, outside]), boxes)
    assert instance.tolist() == [1] * 8 + [0] * 8
    assert class_id.tolist() == [5] * 8 + [0] * 8  # chair is NYU40 5
    # The box stored in meta (full size, yaw = -heading) has the same corners.
    ours = box_corners(center, 2 * np.asarray(half), -heading)
    dist = np.linalg.norm(ours[:, None] - corners[None], axis=2)
    assert dist.min(axis=1).max() < 1e-9


def test_a_point_in_two_boxes_takes_the_smaller():
    table = [0, 0, 0.375, 0.6, 0.4, 0.375, 0.0, TABLE]
    chair = [0.5, 0, 0.45, 0.25, 0.25, 0.45, 0.0, CHAIR]  # pushed under the table's edge
    pts = np.array([[0.0, 0.0, 0.74], [0.5, 0.0, 0.3], [0.45, 0.0, 0.74], [2.0, 0.0, 0.3]])
    instance, class_id = boxes_to_labels(pts, np.array([table, chair]))
    assert instance.tolist() == [1, 2, 2, 0]
    assert class_id.tolist() == [7, 5, 5, 0]


def test_the_reader_labels_points_and_keeps_the_oriented_boxes(tmp_path):
    boxes = [[0, 2, 0.45, 0.3, 0.25, 0.45, 0.5, CHAIR], [1, 3, 0.4, 0.5, 0.4, 0.4, 0.0, 5]]
    pc = [[0, 2, 0.45, 0.2, 0.2, 0.2], [1, 3, 0.4, 0.2, 0.2, 0.2], [3, 3, 0.4, 0.2, 0.2, 0.2]]
    path = _write_frame(tmp_path, "000001", pc, boxes)
    cloud = read_cloud(path, format="sunrgbd-votenet")
    assert cloud.fields["instance"].tolist() == [1, 2, 0]
    assert cloud.fields["class_id"].tolist() == [5, 14, 0]  # a desk is NYU40's desk
    assert cloud.meta["instance_labels"] == {1: "chair", 2: "desk"}
    first = cloud.meta["boxes"][0]
    assert first["class_id"] == 5
    assert first["box"]["size"] == pytest.approx([0.6, 0.5, 0.9])
    assert first["box"]["yaw"] == pytest.approx(-0.5)
    # evaluated as ScanNet is: desks count as tables, boxes turned into BoxInstances
    scene = load_scene(discover_scenes(path)[0])
    assert sorted(g.label for g in scene.gts) == ["chair", "table"]
    assert sorted(b.label for b in scene.gt_boxes) == ["chair", "table"]


@pytest.mark.parametrize(
    ("boxes", "message"),
    [
        (np.zeros((2, 7)), "should be a (K, 8) array"),
        (np.array([[0, 0, 0, 1, 1, 1, 0, 12.0]]), "class indices 0..9"),
        (np.array([[0, 0, 0, 1, -1, 1, 0, 3.0]]), "half sizes"),
        (np.array([[0, 0, np.nan, 1, 1, 1, 0, 3.0]]), "NaN"),
    ],
)
def test_a_damaged_box_file_is_refused_naming_it(tmp_path, boxes, message):
    np.savez_compressed(tmp_path / "000002_pc.npz", pc=np.zeros((3, 6), np.float32))
    np.save(tmp_path / "000002_bbox.npy", boxes)
    with pytest.raises(CorruptFileError, match=r"000002_bbox\.npy") as err:
        read_cloud(tmp_path / "000002_pc.npz", format="sunrgbd-votenet")
    assert message in str(err.value) and "\n" not in str(err.value)


def test_a_frame_without_boxes_reads_as_points_but_is_no_labelled_scene(tmp_path):
    np.savez_compressed(tmp_path / "000003_pc.npz", pc=np.zeros((3, 6), np.float32))
    with pytest.raises(ReadError, match=r"000003_bbox\.npy: missing: its boxes label"):
        read_cloud(tmp_path / "000003_pc.npz", format="sunrgbd-votenet")
    # labels=None labels the points when the box file is there (read_points' choice)
    assert dict(read_sunrgbd_votenet(tmp_path / "000003_pc.npz", labels=None).fields) == {}
    assert len(read_cloud(tmp_path / "000003_pc.npz")) == 3
    with pytest.raises(ReadError, match="holds no scene"):
        discover_scenes(tmp_path)


def test_discovery_finds_the_labelled_frames_and_skips_their_siblings(tmp_path):
    for name in ("000010", "000002"):
        _write_frame(tmp_path / "val", name, np.zeros((4, 6)), np.zeros((0, 8)))
    np.savez_compressed(tmp_path / "val" / "000002_votes.npz", point_votes=np.zeros((4, 10)))
    np.savez_compressed(tmp_path / "val" / "000099_pc.npz", pc=np.zeros((4, 6)))  # no boxes
    found = discover_scenes(tmp_path)
    assert [(s.name, s.format, s.group) for s in found] == [
        ("val/000002", "sunrgbd-votenet", "val/000002"),
        ("val/000010", "sunrgbd-votenet", "val/000010"),
    ]
    assert [s.name for s in discover_scenes(tmp_path, format="sunrgbd")] == [
        "val/000002",
        "val/000010",
    ]
    one = discover_scenes(tmp_path / "val" / "000010_bbox.npy")
    assert [(s.name, s.path) for s in one] == [("000010", str(tmp_path / "val" / "000010_pc.npz"))]
    assert detect_format(tmp_path / "val" / "000010_bbox.npy") == "sunrgbd-votenet"
    # a folder of frames given to ``detect`` is its frames, not their box and vote files
    scans = [p.name for p in expand_inputs([tmp_path / "val"])]
    assert scans == ["000002_pc.npz", "000010_pc.npz", "000099_pc.npz"]


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    """Two simulated single frames of the tiny room stored as VoteNet stores SUN RGB-D's:
    upright, the camera at the origin, colours 0..1, and boxes drawn 3 cm around each
    object (as annotators draw them around what the depth shows, noise and all)."""
    from ontodetect.cloud import sensor_position
    from ontodetect.synth import load_synth, synthesize, write_synth

    root = tmp_path_factory.mktemp("sunrgbd")
    index = {name: k for k, (name, _) in enumerate(SUNRGBD_CLASSES)}
    for seed in (2, 3):
        folder = write_synth(synthesize("tiny", "rgbd-frame", seed, points=20_000), root / "s")
        cloud, objects, _ = load_synth(folder)
        eye = np.asarray(sensor_position(cloud))
        boxes = [
            [
                *(np.asarray(o["box"]["center"]) - eye),
                *(np.asarray(o["box"]["size"]) / 2 + 0.03),
                -o["box"]["yaw"],
                index[o["class"]],
            ]
            for o in objects
            if o["class"] in index
        ]
        pc = np.c_[cloud.xyz - eye, cloud.rgb / 255.0]
        _write_frame(root / "frames", f"{seed:06d}", pc, boxes)
    return root / "frames"


def test_a_folder_of_frames_is_evaluated_as_a_dataset(frames):
    with pytest.warns(DataWarning) as caught:
        ev = evaluate_dataset(frames, jobs=1, detect_options={"seed": 0})
    assert any("one view seen from the origin" in str(w.message) for w in caught)
    at25 = ev.evaluations["iou@0.25"].per_class
    assert at25["chair"].num_gt == 2 and at25["table"].num_gt == 2
    assert at25["table"].tp == 2  # both tables found: the frames were read as views
    assert set(ev.box_ap) >= {"aligned@0.25", "oriented@0.25"}


@pytest.mark.filterwarnings("ignore::ontodetect.cloud.DataWarning")  # the frames' own
def test_eval_on_the_command_line_names_the_layout(frames, tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["eval", str(frames), "-f", "sunrgbd", "-o", str(out), "--votes", "1"]) == 0
    assert "2 scenes" in capsys.readouterr().out
    doc = json.loads((out / "report.json").read_text(encoding="utf-8"))
    assert [s["scene"] for s in doc["scenes"]] == ["000002", "000003"]


def test_labels_when_present_reads_the_boxes_of_a_frame_that_has_them(tmp_path):
    np.savez_compressed(tmp_path / "000004_pc.npz", pc=np.array([[0, 2, 0.4, 0.5, 0.5, 0.5]]))
    np.save(tmp_path / "000004_bbox.npy", np.array([[0, 2, 0.4, 0.3, 0.3, 0.45, 0.0, 3]]))
    cloud = read_sunrgbd_votenet(tmp_path / "000004_pc.npz", labels=None)
    assert cloud.fields["class_id"].tolist() == [5]
