"""``ontodetect info`` run in-process on generated scans: the formats ``--format`` takes,
and what it prints of a labelled scan's boxes."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

from ontodetect.cli import main

#: NYU40 class ids of the fake ScanNet boxes, and how many boxes of each.
BOX_CLASSES = {3: 12, 5: 10, 7: 8}  # cabinet, chair, table


@pytest.fixture
def votenet_scan(tmp_path):
    """A fake ScanNet scan in VoteNet's layout: 100 points, 30 boxes of known classes."""
    rng = np.random.default_rng(7)
    vert = np.c_[rng.random((100, 3)) * 4, rng.integers(0, 256, (100, 3))].astype(np.float32)
    np.save(tmp_path / "scene0001_00_vert.npy", vert)
    np.save(tmp_path / "scene0001_00_sem_label.npy", np.full(100, 5, np.uint32))
    np.save(tmp_path / "scene0001_00_ins_label.npy", np.arange(100, dtype=np.uint32) % 3)
    ids = np.repeat(list(BOX_CLASSES), list(BOX_CLASSES.values()))
    boxes = np.c_[rng.random((30, 3)) * 4, rng.random((30, 3)) + 0.2, rng.permutation(ids)]
    np.save(tmp_path / "scene0001_00_bbox.npy", boxes.astype(np.float32))
    return tmp_path / "scene0001_00_vert.npy"


@pytest.fixture
def sunrgbd_frame(tmp_path):
    """One SUN RGB-D frame in VoteNet's layout: a chair box and a table box."""
    rng = np.random.default_rng(3)
    folder = tmp_path / "frames"
    folder.mkdir()
    pc = np.c_[rng.random((200, 3)) * [2, 2, 1] + [0, 1, 0], rng.random((200, 3))]
    np.savez_compressed(folder / "000001_pc.npz", pc=pc)
    boxes = [[0.5, 1.5, 0.4, 0.3, 0.3, 0.4, 0.0, 3], [1.5, 2.5, 0.4, 0.5, 0.4, 0.4, 0.0, 1]]
    np.save(folder / "000001_bbox.npy", np.array(boxes))
    return folder / "000001_pc.npz"


def test_a_votenet_scan_shows_its_boxes_in_one_line(votenet_scan, capsys):
    assert main(["info", str(votenet_scan)]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    boxes = [line for line in lines if line.startswith("boxes")]
    assert boxes == [
        "boxes            30 (12 cabinet [3], 10 chair [5], 8 table [7]; --json lists them)"
    ]
    assert len(lines) < 20
    # Not a terminal: no line is padded with blanks.
    assert all(line == line.rstrip() for line in lines)
    assert max(len(line) for line in lines) < 120


def test_json_keeps_every_box(votenet_scan, capsys):
    assert main(["info", str(votenet_scan), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["extra"]["boxes"]) == 30
    assert sorted(b[6] for b in doc["extra"]["boxes"]) == sorted(
        np.repeat(list(BOX_CLASSES), list(BOX_CLASSES.values())).tolist()
    )


@pytest.mark.parametrize("name", ["sunrgbd", "sunrgbd-votenet", "SUNRGBD"])
def test_format_takes_the_layout_names_eval_takes(sunrgbd_frame, capsys, name):
    assert main(["info", "--format", name, str(sunrgbd_frame)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "format           sunrgbd-votenet" in lines
    assert "boxes            2 (1 chair [5], 1 table [7]; --json lists them)" in lines


def _one_error(capsys, status):
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert status == 2 and len(lines) == 1, err
    return lines[0]


def test_a_dataset_folder_of_frames_points_to_eval(sunrgbd_frame, capsys):
    folder = sunrgbd_frame.parent
    line = _one_error(capsys, main(["info", "-f", "sunrgbd", str(folder)]))
    assert line == (
        f"error: {folder}: is a folder, but info reads one scan of the 'sunrgbd-votenet' "
        "layout (a *_pc.npz file); 'ontodetect eval -f sunrgbd' reads a dataset folder"
    )


@pytest.mark.parametrize(
    ("name", "layout"), [("synth", True), ("ontodetect", True), ("potree", False)]
)
def test_a_format_info_does_not_read_names_the_option_and_its_formats(
    sunrgbd_frame, capsys, name, layout
):
    line = _one_error(capsys, main(["info", "--format", name, str(sunrgbd_frame)]))
    assert line.startswith("error: The '--format' parameter must be one of ply, pcd, ")
    assert "sunrgbd-votenet" in line and "(info reads one cloud or scan)" in line
    assert line.endswith(f"Got {name!r} instead.")
    assert (f"'ontodetect eval -f {name}' reads it" in line) == layout


def test_a_terminal_gets_the_table(votenet_scan, monkeypatch):
    from rich.console import Console

    from ontodetect.cli import info as info_module

    screen = Console(
        file=io.StringIO(),
        force_terminal=True,
        color_system=None,
        width=200,
        markup=False,
        highlight=False,
    )
    monkeypatch.setattr(info_module, "console", screen)
    assert main(["info", str(votenet_scan)]) == 0
    lines = screen.file.getvalue().splitlines()
    assert lines[0].strip() == str(votenet_scan)  # the title
    row = next(line for line in lines if "boxes" in line)
    assert "30 (12 cabinet [3], 10 chair [5], 8 table [7]" in row
    assert len(lines) < 25


def test_a_list_field_is_printed_as_comma_separated_values(tmp_path, capsys):
    f = tmp_path / "p.txt"
    f.write_text("x y z intensity\n0 0 0 1\n1 0 0 2\n0 1 0 3\n0 0 1 4\n")
    assert main(["info", str(f)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "columns          x, y, z, intensity" in lines
    assert "delimiter        whitespace" in lines
    # --json keeps the list.
    assert main(["info", str(f), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["extra"]["columns"] == ["x", "y", "z", "intensity"]


@pytest.mark.parametrize(
    ("value", "line"),
    [
        (["x", "y", "z"], "x, y, z"),
        ([0.1, 2.0, 1e-7], "0.1, 2, 1e-07"),
        ([[1.0, 0.0, 0.0], [0.0, 1.0, 0.5]], "[1, 0, 0], [0, 1, 0.5]"),
        ({"width": 640, "height": 480}, "width: 640, height: 480"),
        ([{"class_id": 3, "box": {"size": [1.0, 2.0]}}], "{class_id: 3, box: {size: [1, 2]}}"),
        ("whitespace", "whitespace"),
        (True, "True"),
        ([], ""),
        (
            [f"s{k}" for k in range(14)],
            "s0, s1, s2, s3, s4, s5, s6, s7, s8, s9, s10, s11, ... (14 in all; --json lists them)",
        ),
    ],
)
def test_value_line_prints_lists_and_mappings_plainly(value, line):
    from ontodetect.cli.info import value_line

    assert value_line(value) == line
