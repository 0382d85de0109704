"""S3DIS rooms written in the real layout: classes, instances, the stray-character glitch."""

from __future__ import annotations

import numpy as np
import pytest

from ontodetect import CorruptFileError, DataWarning, ReadError, read_cloud
from ontodetect.io import detect_format
from ontodetect.io._labels import NYU40_NAMES, S3DIS_TO_NYU40, s3dis_class_id
from ontodetect.io._s3dis import read_s3dis

S3DIS_CLASSES = ["ceiling", "floor", "wall", "beam", "column", "window", "door", "table",
                 "chair", "sofa", "bookcase", "board", "clutter"]  # fmt: skip


def _lines(points):
    return "".join(f"{x:.3f} {y:.3f} {z:.3f} {r} {g} {b}\n" for x, y, z, r, g, b in points)


def make_room(root, objects, area="Area_1", room="office_1"):
    """``objects``: file stem -> list of (x, y, z, r, g, b); also writes ``<room>.txt``."""
    folder = root / area / room
    (folder / "Annotations").mkdir(parents=True)
    everything = []
    for stem, points in objects.items():
        (folder / "Annotations" / f"{stem}.txt").write_text(_lines(points))
        everything += points
    (folder / f"{room}.txt").write_text(_lines(everything))
    return folder


ROOM = {
    "chair_2": [(1.0, 1.0, 0.45, 200, 10, 10), (1.1, 1.0, 0.45, 200, 10, 10)],
    "chair_10": [(3.0, 1.0, 0.45, 10, 200, 10)],
    "floor_1": [(0.0, 0.0, 0.0, 90, 90, 90), (5.0, 5.0, 0.0, 90, 90, 90)],
    "table_1": [(2.0, 2.0, 0.75, 120, 80, 40)],
}


def test_room_from_annotations(tmp_path):
    folder = make_room(tmp_path, ROOM)
    c = read_s3dis(folder)
    # Files sorted by class name, then number: chair_2, chair_10, floor_1, table_1.
    assert c.fields["instance"].tolist() == [1, 1, 2, 3, 3, 4]
    assert c.fields["class_id"].tolist() == [5, 5, 5, 2, 2, 7]
    assert c.fields["class_id"].dtype == np.int32 and c.fields["instance"].dtype == np.int32
    np.testing.assert_allclose(c.xyz[2], [3.0, 1.0, 0.45])
    assert c.rgb[2].tolist() == [10, 200, 10]
    assert c.meta["room"] == "office_1"
    assert c.meta["instance_labels"] == {1: "chair", 2: "chair", 3: "floor", 4: "table"}
    assert c.meta["instance_class_ids"] == {1: 5, 2: 5, 3: 2, 4: 7}
    assert c.meta["unknown_classes"] == []


def test_registry_and_room_file(tmp_path):
    folder = make_room(tmp_path, ROOM)
    assert detect_format(folder) == "s3dis"
    c = read_cloud(folder)
    assert c.meta["format"] == "s3dis" and len(c) == 6
    assert len(read_s3dis(folder / "office_1.txt")) == 6


def test_room_file_without_labels(tmp_path):
    folder = make_room(tmp_path, ROOM)
    c = read_s3dis(folder, labels=False)
    assert len(c) == 6 and dict(c.fields) == {}
    assert c.rgb is not None


def test_stray_control_character_is_repaired(tmp_path):
    folder = make_room(tmp_path, ROOM)
    ceiling = folder / "Annotations" / "ceiling_1.txt"
    # As in Area_5/hallway_6: a control character where a separator belongs.
    ceiling.write_bytes(b"0 0 3 1 1 1\n1 0 3\x10 1 1 1\n2 0 3 1 1 1\n")
    with pytest.warns(DataWarning, match=r"ceiling_1\.txt: repaired 1 line.*line 2"):
        c = read_s3dis(folder)
    assert int((c.fields["class_id"] == 22).sum()) == 3


def test_unrepairable_line_is_skipped(tmp_path):
    folder = make_room(tmp_path, ROOM)
    ceiling = folder / "Annotations" / "ceiling_1.txt"
    ceiling.write_bytes(b"0 0 3 1 1 1\n1 0 3\x10 1 1\n2 0 3 1 1 1\n")
    with pytest.warns(DataWarning, match=r"ceiling_1\.txt: skipped 1 unreadable line.*line 2"):
        c = read_s3dis(folder)
    assert int((c.fields["class_id"] == 22).sum()) == 2


def test_unknown_class(tmp_path):
    folder = make_room(tmp_path, {**ROOM, "robot_1": [(0.0, 0.0, 1.0, 0, 0, 0)]})
    c = read_s3dis(folder)
    assert c.meta["unknown_classes"] == ["robot_1.txt"]
    assert c.fields["class_id"][c.fields["instance"] == 4].tolist() == [0]


def test_errors(tmp_path):
    empty = tmp_path / "room_a"
    (empty / "Annotations").mkdir(parents=True)
    with pytest.raises(ReadError, match=r"Annotations: holds no <class>_<k>\.txt"):
        read_s3dis(empty)
    with pytest.raises(ReadError, match=r"room_a\.txt: missing"):
        read_s3dis(empty, labels=False)
    folder = make_room(tmp_path, ROOM, room="room_b")
    (folder / "Annotations" / "door_1.txt").write_text("")
    with pytest.raises(CorruptFileError, match=r"door_1\.txt: contains no points"):
        read_s3dis(folder)
    (folder / "Annotations" / "door_1.txt").write_text("1 2\n")
    with pytest.raises(CorruptFileError, match=r"door_1\.txt: expected columns x y z r g b"):
        read_s3dis(folder)


def test_class_mapping_covers_the_thirteen_classes():
    assert set(S3DIS_CLASSES) <= set(S3DIS_TO_NYU40)
    assert all(NYU40_NAMES[i] for i in S3DIS_TO_NYU40.values())
    assert [s3dis_class_id(c) for c in ("chair", "sofa", "table", "bookcase", "wall")] == [
        5,
        6,
        7,
        10,
        1,
    ]
    assert s3dis_class_id("floor") == 2 and s3dis_class_id("ceiling") == 22
    assert s3dis_class_id("clutter") == 40
