"""The files of one detect run that other tools open: labelled.ply / .laz and the exports."""

import json

import numpy as np
import pytest

from ontodetect.errors import CorruptFileError, InvalidParameterError
from ontodetect.io import (
    read_box_table,
    read_cloud,
    read_scannet_instances,
    write_box_table,
    write_scannet_instances,
)
from ontodetect.outputs import (
    LAS_CLASS_BASE,
    LAS_UNCLASSIFIED,
    labelled_cloud,
    write_outputs,
)
from ontodetect.pipeline import detect
from ontodetect.render import class_color
from ontodetect.synth import synthesize, write_synth


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scene")
    write_synth(synthesize("dining_room", "rgbd", seed=5, points=30_000), folder)
    # Read back from the file: the input carries ground truth fields `class_id` and `instance`.
    res = detect(read_cloud(folder / "cloud.ply"), room="dining_room", seed=0)
    assert res.detections, "a dining room has chairs and a table"
    return res


@pytest.fixture(scope="module")
def written(result, tmp_path_factory):
    out = tmp_path_factory.mktemp("out")
    files = write_outputs(result, out, picture=False, exports=("boxes", "scannet"))
    return out, files


def _rgb255(name):
    return [round(255 * v) for v in class_color(name)]


def test_labelled_ply_keeps_input_fields_and_adds_scalar_ones(result, written):
    out, files = written
    assert files.labelled == out / "labelled.ply"
    back = read_cloud(files.labelled)
    label, instance = result.point_labels()
    assert len(back) == len(result.cloud)
    np.testing.assert_array_equal(back.fields["scalar_label"], label)
    np.testing.assert_array_equal(back.fields["scalar_instance"], instance)
    # The input's own `instance` (ground truth) is kept, not overwritten.
    np.testing.assert_array_equal(back.fields["instance"], result.cloud.fields["instance"])
    np.testing.assert_array_equal(back.fields["class_id"], result.cloud.fields["class_id"])
    np.testing.assert_array_equal(back.fields["input_red"], result.cloud.rgb[:, 0])
    for d in result.detections:
        pts = instance == d.id
        assert np.allclose(back.fields["scalar_score"][pts], d.score, atol=1e-6)
    assert np.all(back.fields["scalar_score"][instance == 0] == 0)
    comments = back.meta["comments"]
    assert "ontodetect label -1 none" in comments
    for i, name in enumerate(result.class_names):
        assert f"ontodetect label {i} {name}" in comments


def test_labelled_colours_do_not_depend_on_the_block_size(result, monkeypatch):
    # The colours are computed block by block to bound memory: any block size, the same
    # colours, block boundaries included.
    import ontodetect.outputs

    whole = labelled_cloud(result).rgb
    monkeypatch.setattr(ontodetect.outputs, "COLOR_BLOCK", 7)
    np.testing.assert_array_equal(labelled_cloud(result).rgb, whole)
    label, _ = result.point_labels()
    for i, name in enumerate(result.class_names):
        assert np.all(whole[label == i] == _rgb255(name))


def test_labelled_ply_opens_in_open3d_coloured_by_class(result, written):
    o3d = pytest.importorskip("open3d")
    out, _ = written
    pcd = o3d.io.read_point_cloud(str(out / "labelled.ply"))
    label, _ = result.point_labels()
    colours = np.round(np.asarray(pcd.colors) * 255).astype(int)
    assert len(colours) == len(label)
    for i, name in enumerate(result.class_names):
        if np.any(label == i):
            assert np.all(colours[label == i] == _rgb255(name))
    t = o3d.t.io.read_point_cloud(str(out / "labelled.ply"))
    got = t.point["scalar_label"].numpy().ravel()
    np.testing.assert_array_equal(got, label)


def test_labelled_ply_opens_in_trimesh_with_scalar_fields(result, written):
    trimesh = pytest.importorskip("trimesh")
    out, _ = written
    cloud = trimesh.load(out / "labelled.ply")
    label, instance = result.point_labels()
    attrs = cloud.metadata["_ply_raw"]["vertex"]["data"]
    np.testing.assert_array_equal(attrs["scalar_label"], label)
    np.testing.assert_array_equal(attrs["scalar_instance"], instance)
    colours = np.asarray(cloud.colors)[:, :3]
    first = result.class_names.index(result.detections[0].label)
    assert np.all(colours[label == first] == _rgb255(result.detections[0].label))


def test_our_fields_never_take_an_input_name(result):
    cloud = result.cloud.with_fields(scalar_label=np.full(len(result.cloud), 7, np.int32))
    res = type(result)(**{**result.__dict__, "cloud": cloud})
    out = labelled_cloud(res)
    assert np.all(out.fields["scalar_label"] == 7)
    np.testing.assert_array_equal(out.fields["scalar_label_1"], result.point_labels()[0])


def test_labelled_laz_reads_in_laspy_with_classification_codes(result, tmp_path):
    laspy = pytest.importorskip("laspy")
    files = write_outputs(result, tmp_path, picture=False, labelled_format="laz", exports=())
    assert files.labelled == tmp_path / "labelled.laz"
    las = laspy.read(files.labelled)
    label, instance = result.point_labels()
    expected = np.where(label >= 0, LAS_CLASS_BASE + label, LAS_UNCLASSIFIED)
    np.testing.assert_array_equal(np.asarray(las.classification), expected)
    np.testing.assert_array_equal(np.asarray(las["scalar_instance"]), instance)
    np.testing.assert_array_equal(np.asarray(las["instance"]), result.cloud.fields["instance"])
    assert np.allclose(las.x, result.cloud.xyz[:, 0], atol=1e-3)
    first = result.class_names.index(result.detections[0].label)
    red = np.asarray(las.red)[label == first] // 257
    assert np.all(red == _rgb255(result.detections[0].label)[0])


def test_bad_labelled_format_and_export_are_refused(result, tmp_path):
    with pytest.raises(InvalidParameterError, match="labelled_format"):
        write_outputs(result, tmp_path, picture=False, labelled_format="obj")
    with pytest.raises(InvalidParameterError, match="exports"):
        write_outputs(result, tmp_path, picture=False, exports=("kitti",))


def test_box_table_round_trips(written):
    out, _ = written
    doc = json.loads((out / "detections.json").read_text())
    rows = read_box_table(out / "boxes.txt")
    assert len(rows) == len(doc["detections"])
    for row, d in zip(rows, doc["detections"]):
        assert row["label"] == d["label"]
        assert row["score"] == pytest.approx(d["score"], abs=1e-4)
        assert row["center"] == pytest.approx(d["box"]["center"], abs=1e-6)
        assert row["size"] == pytest.approx(d["box"]["size"], abs=1e-6)
        assert row["yaw"] == pytest.approx(d["box"]["yaw"], abs=1e-6)
    head = (out / "boxes.txt").read_text().splitlines()[0]
    assert head == "# x y z dx dy dz yaw class score"


def test_box_table_hand_made(tmp_path):
    doc = {
        "num_points": 3,
        "detections": [
            {
                "label": "night stand",
                "score": 0.25,
                "box": {"center": [1, 2, 0.5], "size": [0.4, 0.3, 1.0], "yaw": 1.5},
                "point_indices": [0, 2],
            }
        ],
    }
    path = write_box_table(tmp_path / "b.txt", doc)
    assert path.read_text().splitlines()[1] == (
        "1.000000 2.000000 0.500000 0.400000 0.300000 1.000000 1.500000 night_stand 0.2500"
    )
    summary = write_scannet_instances(tmp_path / "sc", doc, scene="scene0000_00")
    assert summary.read_text() == "pred_mask/scene0000_00_000.txt 32 0.2500\n"
    [(label, conf, mask)] = read_scannet_instances(summary)
    assert (label, conf, mask.tolist()) == (32, 0.25, [True, False, True])


def test_scannet_instances_round_trip(written):
    out, _ = written
    doc = json.loads((out / "detections.json").read_text())
    scene = "cloud"
    summary = out / "scannet" / f"{scene}.txt"
    got = read_scannet_instances(summary)
    assert len(got) == len(doc["detections"])
    nyu = {"cabinet": 3, "bed": 4, "chair": 5, "sofa": 6, "table": 7, "desk": 14}
    for (label, conf, mask), d in zip(got, doc["detections"]):
        assert label == nyu.get(d["label"], 39)
        assert conf == pytest.approx(d["score"], abs=1e-4)
        assert mask.size == doc["num_points"]
        np.testing.assert_array_equal(np.flatnonzero(mask), np.sort(d["point_indices"]))


def test_corrupt_box_table_names_the_line(tmp_path):
    f = tmp_path / "b.txt"
    f.write_text("# x y z dx dy dz yaw class score\n1 2 3 chair\n")
    with pytest.raises(CorruptFileError, match="line 2"):
        read_box_table(f)
