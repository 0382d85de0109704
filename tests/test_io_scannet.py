"""ScanNet, release layout and VoteNet layout: generated scans with known labels."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from ontodetect import CorruptFileError, ReadError, read_cloud
from ontodetect.io import detect_format
from ontodetect.io._labels import read_scannet_label_map
from ontodetect.io._scannet import read_scannet, read_scannet_votenet

SCENE = "scene0042_00"
# Vertex -> segment, and the objects of the aggregation (objectId, label, segments).
SEGMENTS = [100, 100, 205, 205, 310, 310, 400, 400, 777, 777]
GROUPS = [
    (0, "chair", [100]),
    (1, "couch", [205]),
    (2, "coffee table", [310, 999]),  # segment 999 covers no vertex
    (5, "mystery thing", [400]),  # not in the label table
]
EXPECTED_INSTANCE = [1, 1, 2, 2, 3, 3, 6, 6, 0, 0]
EXPECTED_CLASS = [5, 5, 6, 6, 7, 7, 0, 0, 0, 0]
LABEL_TABLE = (
    "id\traw_category\tcategory\tcount\tnyu40id\tnyu40class\n"
    "1\tchair\tchair\t4646\t5\tchair\n"
    "2\tcouch\tcouch\t502\t6\tsofa\n"
    "3\tcoffee table\tcoffee table\t258\t7\ttable\n"
    "4\tunlabelled thing\tthing\t3\t\t\n"
)


def write_mesh_ply(path, xyz, rgb):
    """A binary mesh PLY laid out like ScanNet's ``*_vh_clean_2.ply``."""
    n = len(xyz)
    faces = np.array([[i, (i + 1) % n, (i + 2) % n] for i in range(n)], dtype="<i4")
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment VCGLIB generated\n"
        f"element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    vertex = np.zeros(n, dtype=[("xyz", "<f4", 3), ("rgba", "u1", 4)])
    vertex["xyz"] = xyz
    vertex["rgba"][:, :3] = rgb
    vertex["rgba"][:, 3] = 255
    face_bytes = b"".join(struct.pack("<B3i", 3, *f) for f in faces.tolist())
    path.write_bytes(header.encode() + vertex.tobytes() + face_bytes)
    return path


def make_release_scan(root, *, aggregation_name=f"{SCENE}.aggregation.json", table=True):
    folder = root / SCENE
    folder.mkdir(parents=True)
    n = len(SEGMENTS)
    xyz = np.column_stack([np.arange(n), np.zeros(n), np.full(n, 0.5)]).astype(np.float32)
    rgb = np.column_stack([np.arange(n) * 20, np.full(n, 7), np.full(n, 9)])
    write_mesh_ply(folder / f"{SCENE}_vh_clean_2.ply", xyz, rgb)
    (folder / f"{SCENE}_vh_clean_2.0.010000.segs.json").write_text(
        json.dumps({"params": {}, "sceneId": SCENE, "segIndices": SEGMENTS})
    )
    groups = [
        {"id": oid, "objectId": oid, "segments": segs, "label": label}
        for oid, label, segs in GROUPS
    ]
    (folder / aggregation_name).write_text(
        json.dumps(
            {
                "sceneId": f"scannet.{SCENE}",
                "appId": "Aggregator.v2",
                "segGroups": groups,
                "segmentsFile": f"scannet.{SCENE}_vh_clean_2.0.010000.segs.json",
            }
        )
    )
    if table:
        (root / "scannetv2-labels.combined.tsv").write_text(LABEL_TABLE)
    return folder


# -- release layout ---------------------------------------------------------------
def test_release_layout(tmp_path):
    folder = make_release_scan(tmp_path)
    c = read_scannet(folder)
    assert c.fields["instance"].tolist() == EXPECTED_INSTANCE
    assert c.fields["class_id"].tolist() == EXPECTED_CLASS
    assert c.fields["instance"].dtype == np.int32 and c.fields["class_id"].dtype == np.int32
    assert "alpha" not in c.fields
    assert c.rgb[:, 0].tolist() == [i * 20 for i in range(10)]
    np.testing.assert_array_equal(c.xyz[:, 0], np.arange(10))
    assert c.meta["scene_id"] == SCENE
    assert c.meta["instance_labels"] == {
        1: "chair",
        2: "couch",
        3: "coffee table",
        6: "mystery thing",
    }
    assert c.meta["instance_class_ids"] == {1: 5, 2: 6, 3: 7, 6: 0}
    assert c.meta["unmapped_labels"] == ["mystery thing"]
    same = read_scannet(folder / f"{SCENE}_vh_clean_2.ply")
    np.testing.assert_array_equal(same.fields["instance"], c.fields["instance"])


def test_release_layout_through_the_registry(tmp_path):
    folder = make_release_scan(tmp_path)
    assert detect_format(folder) == "scannet"
    assert detect_format(folder / f"{SCENE}_vh_clean_2.ply") == "scannet"
    c = read_cloud(folder)
    assert c.meta["format"] == "scannet" and c.fields["class_id"].tolist() == EXPECTED_CLASS


def test_vh_clean_aggregation_name(tmp_path):
    folder = make_release_scan(tmp_path, aggregation_name=f"{SCENE}_vh_clean.aggregation.json")
    assert read_scannet(folder).fields["instance"].tolist() == EXPECTED_INSTANCE


def test_label_map_option(tmp_path):
    folder = make_release_scan(tmp_path, table=False)
    with pytest.raises(ReadError, match=r"scannetv2-labels\.combined\.tsv: missing.*label_map="):
        read_scannet(folder)
    table = tmp_path / "elsewhere.tsv"
    table.write_text(LABEL_TABLE)
    assert read_scannet(folder, label_map=table).fields["class_id"].tolist() == EXPECTED_CLASS


def test_missing_segments_file(tmp_path):
    folder = make_release_scan(tmp_path)
    (folder / f"{SCENE}_vh_clean_2.0.010000.segs.json").unlink()
    with pytest.raises(ReadError, match=rf"{SCENE}_vh_clean_2\.0\.010000\.segs\.json: missing"):
        read_scannet(folder)


def test_missing_aggregation(tmp_path):
    folder = make_release_scan(tmp_path)
    (folder / f"{SCENE}.aggregation.json").unlink()
    with pytest.raises(ReadError, match=rf"{SCENE}\.aggregation\.json: missing.*_vh_clean\."):
        read_scannet(folder)


def test_segments_disagree_with_mesh(tmp_path):
    folder = make_release_scan(tmp_path)
    (folder / f"{SCENE}_vh_clean_2.0.010000.segs.json").write_text(
        json.dumps({"segIndices": SEGMENTS[:-1]})
    )
    with pytest.raises(
        CorruptFileError,
        match=rf"segs\.json: has 9 segment indices but "
        rf"{SCENE}_vh_clean_2\.ply has 10 vertices",
    ):
        read_scannet(folder)


@pytest.mark.parametrize(
    ("content", "match"),
    [
        ('{"segGroups": [', "is not valid JSON"),
        ('{"segGroups": 3}', "'segGroups' list"),
        (
            '{"segGroups": [{"objectId": "a", "label": "chair", "segments": []}]}',
            "integer objectId",
        ),
        ('{"segGroups": [{"objectId": 1, "label": "chair", "segments": ["x"]}]}', "segments"),
    ],
)
def test_damaged_aggregation(tmp_path, content, match):
    folder = make_release_scan(tmp_path)
    (folder / f"{SCENE}.aggregation.json").write_text(content)
    with pytest.raises(CorruptFileError, match=rf"aggregation\.json: .*{match}"):
        read_scannet(folder)


def test_axis_alignment(tmp_path):
    folder = make_release_scan(tmp_path)
    with pytest.raises(ReadError, match=rf"{SCENE}\.txt: missing"):
        read_scannet(folder, align=True)
    # A quarter turn about z and a shift, as in ScanNet's metadata files.
    m = [0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1]
    (folder / f"{SCENE}.txt").write_text(
        "colorHeight = 968\naxisAlignment = " + " ".join(map(str, m)) + "\nnumDepthFrames = 1\n"
    )
    c = read_scannet(folder, align=True)
    np.testing.assert_allclose(c.xyz[2], [1, 4, 3.5])  # (2, 0, 0.5) -> (-0 + 1, 2 + 2, 3.5)
    assert c.meta["axis_alignment"][0] == [0, -1, 0, 1]


def test_label_table_reader(tmp_path):
    f = tmp_path / "t.tsv"
    f.write_text(LABEL_TABLE)
    assert read_scannet_label_map(f) == {"chair": 5, "couch": 6, "coffee table": 7}
    f.write_text("id\traw_category\n1\tchair\n")
    with pytest.raises(CorruptFileError, match="no column 'nyu40id'"):
        read_scannet_label_map(f)
    f.write_text("raw_category\tnyu40id\nchair\tfive\n")
    with pytest.raises(CorruptFileError, match="line 2: nyu40id should be an integer"):
        read_scannet_label_map(f)


# -- VoteNet layout -----------------------------------------------------------------
def make_votenet_scan(folder, n=6, boxes=True):
    folder.mkdir(parents=True, exist_ok=True)
    vert = np.zeros((n, 6), np.float32)
    vert[:, 0] = np.arange(n)
    vert[:, 3:6] = [[10, 20, 30]] * n
    np.save(folder / f"{SCENE}_vert.npy", vert)
    np.save(folder / f"{SCENE}_sem_label.npy", np.array([5, 5, 5, 7, 7, 0][:n], np.uint32))
    np.save(folder / f"{SCENE}_ins_label.npy", np.array([1, 1, 1, 2, 2, 0][:n], np.uint32))
    if boxes:
        np.save(folder / f"{SCENE}_bbox.npy", np.array([[1, 0, 0, 3, 1, 1, 5]], np.float64))
    return folder / f"{SCENE}_vert.npy"


def test_votenet_layout(tmp_path):
    f = make_votenet_scan(tmp_path)
    c = read_scannet_votenet(f)
    assert c.fields["class_id"].tolist() == [5, 5, 5, 7, 7, 0]
    assert c.fields["instance"].tolist() == [1, 1, 1, 2, 2, 0]
    assert c.fields["class_id"].dtype == np.int32 and c.fields["instance"].dtype == np.int32
    assert c.rgb.tolist() == [[10, 20, 30]] * 6
    assert c.meta["instance_class_ids"] == {1: 5, 2: 7}
    assert c.meta["instance_labels"] == {1: "chair", 2: "table"}
    assert c.meta["boxes"] == [[1, 0, 0, 3, 1, 1, 5]]
    assert c.meta["scene_id"] == SCENE


def test_votenet_from_a_label_file_and_the_registry(tmp_path):
    make_votenet_scan(tmp_path, boxes=False)
    label = tmp_path / f"{SCENE}_ins_label.npy"
    assert detect_format(label) == "scannet-votenet"
    c = read_cloud(label)
    assert c.meta["format"] == "scannet-votenet" and "boxes" not in c.meta
    assert c.fields["instance"].tolist() == [1, 1, 1, 2, 2, 0]


def test_votenet_points_only(tmp_path):
    f = make_votenet_scan(tmp_path)
    (tmp_path / f"{SCENE}_ins_label.npy").unlink()
    with pytest.raises(ReadError, match=r"_ins_label\.npy: missing: it holds the scan's labels"):
        read_scannet_votenet(f)
    assert dict(read_scannet_votenet(f, labels=False).fields) == {}


@pytest.mark.parametrize("missing", [None, "_sem_label.npy", "_ins_label.npy"])
def test_votenet_labels_when_present(tmp_path, missing):
    """``labels=None`` reads the labels when both label files are there, else the points."""
    f = make_votenet_scan(tmp_path)
    if missing is not None:
        (tmp_path / f"{SCENE}{missing}").unlink()
    fields = set(read_scannet_votenet(f, labels=None).fields)
    assert fields == (set() if missing else {"class_id", "instance"})


def test_votenet_lengths_disagree(tmp_path):
    f = make_votenet_scan(tmp_path)
    np.save(tmp_path / f"{SCENE}_sem_label.npy", np.zeros(5, np.uint32))
    with pytest.raises(
        CorruptFileError,
        match=rf"{SCENE}_sem_label\.npy: has 5 labels but "
        rf"{SCENE}_vert\.npy has 6 points.*{SCENE}_sem_label\.npy and "
        rf"{SCENE}_vert\.npy",
    ):
        read_scannet_votenet(f)


def test_votenet_damaged_arrays(tmp_path):
    f = make_votenet_scan(tmp_path)
    data = f.read_bytes()
    f.write_bytes(data[:-10])
    with pytest.raises(CorruptFileError, match=r"_vert\.npy: truncated"):
        read_scannet_votenet(f)
    np.save(f, np.zeros((4, 2), np.float32))
    with pytest.raises(CorruptFileError, match=r"should be an \(n, 6\) array"):
        read_scannet_votenet(f)
    np.save(f, np.zeros((0, 6), np.float32))
    with pytest.raises(CorruptFileError, match="contains no points"):
        read_scannet_votenet(f)
    f.write_bytes(b"\x93NUMPY garbage")
    with pytest.raises(CorruptFileError, match=r"not a valid \.npy file"):
        read_scannet_votenet(f)
