"""The VoteNet layouts on the command line, on one simulated room written in both:

- a scan whose label files are missing (a ScanNet test scan, a SUN RGB-D frame without
  boxes) is read for its points by the commands that need only them (info, detect,
  segment, cad fit); eval, which needs the labels, names the missing file;
- every command that reads one cloud per input takes ``--format``'s other names of the
  layouts (``sunrgbd``, ``votenet``), and refuses the same names with the same line.

Known answers: the room's points are the same in every layout, so detections and clusters
are those of the labelled ScanNet scan.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ontodetect.cli import main
from ontodetect.io import read_cloud
from ontodetect.synth import synthesize

SCENE = "scene0002_00"
FRAME = "000002"


def _one_line(capsys, status: int) -> str:
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert status == 2 and len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.fixture(scope="module")
def room():
    return synthesize("tiny", seed=1).cloud


@pytest.fixture(scope="module")
def scans(room, tmp_path_factory):
    """The room as a labelled ScanNet scan (``labelled/``), the same scan with only its
    points and boxes (``bare/``), and as a SUN RGB-D frame without boxes (``frame/``)."""
    root = tmp_path_factory.mktemp("scans")
    vert = np.c_[room.xyz, room.rgb].astype(np.float32)  # colours 0..255
    for name in ("labelled", "bare", "frame"):
        (root / name).mkdir()
    for name in ("labelled", "bare"):
        np.save(root / name / f"{SCENE}_vert.npy", vert)
        np.save(root / name / f"{SCENE}_bbox.npy", np.array([[1, 1, 0.4, 0.5, 0.5, 0.8, 5]]))
    np.save(root / "labelled" / f"{SCENE}_sem_label.npy", room.fields["class_id"].astype(np.uint32))
    np.save(root / "labelled" / f"{SCENE}_ins_label.npy", room.fields["instance"].astype(np.uint32))
    pc = np.c_[room.xyz, room.rgb / 255.0].astype(np.float32)  # colours 0..1
    np.savez(root / "frame" / f"{FRAME}_pc.npz", pc=pc)
    return root


def _detect(path, out, *extra):
    return main(["-q", "detect", str(path), "-o", str(out), "--votes", "1", "--no-picture", *extra])


def _detections(out):
    return json.loads((out / "detections.json").read_text())


@pytest.fixture(scope="module")
def labelled_detections(scans, tmp_path_factory):
    out = tmp_path_factory.mktemp("labelled") / "out"
    assert _detect(scans / "labelled" / f"{SCENE}_vert.npy", out) == 0
    doc = _detections(out)
    assert doc["detections"], "the tiny room has furniture"
    return doc


# ------------------------------------------------------------------------------------------
# A scan without its label files


def test_info_reads_a_scan_without_label_files_for_its_points(room, scans, capsys):
    assert main(["info", str(scans / "bare" / f"{SCENE}_vert.npy")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert f"points           {len(room):,}" in lines
    assert "fields           xyz, rgb" in lines
    assert "boxes            1 (1 chair [5]; --json lists them)" in lines
    # With its label files, the same scan shows their fields.
    assert main(["info", str(scans / "labelled" / f"{SCENE}_vert.npy")]) == 0
    assert "fields           xyz, rgb, class_id, instance" in capsys.readouterr().out


def test_detect_reads_a_scan_without_label_files_for_its_points(
    room, scans, labelled_detections, tmp_path, capsys
):
    out = tmp_path / "out"
    assert _detect(scans / "bare" / f"{SCENE}_vert.npy", out) == 0
    assert "labels=False" not in capsys.readouterr().err
    doc = _detections(out)
    assert doc["num_points"] == len(room)
    assert doc["detections"] == labelled_detections["detections"]


def test_a_batch_and_tiles_read_a_scan_without_label_files_too(scans, tmp_path, capsys):
    bare = scans / "bare" / f"{SCENE}_vert.npy"
    labelled = scans / "labelled" / f"{SCENE}_vert.npy"
    out = tmp_path / "batch"
    assert main(["-q", "detect", str(bare), str(labelled), "-o", str(out), "--votes", "1"]) == 0
    same = [(out / name / "detections.json").read_bytes() for name in (SCENE, f"{SCENE}_2")]
    assert same[0].replace(b"bare", b"labelled") == same[1]
    tiles = tmp_path / "tiles"
    args = ["-q", "detect", str(bare), "-o", str(tiles), "--tile", "4", "--set", "detect.votes=1"]
    assert main(args) == 0
    assert (tiles / "detections.json").is_file()


def test_a_frame_without_boxes_is_read_for_its_points(room, scans, capsys):
    frame = scans / "frame" / f"{FRAME}_pc.npz"
    assert main(["info", "-f", "sunrgbd", str(frame)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "format           sunrgbd-votenet" in lines
    assert f"points           {len(room):,}" in lines
    assert not any(line.startswith("boxes") for line in lines)


def test_eval_still_needs_the_labels_and_names_the_missing_file(scans, capsys):
    line = _one_line(capsys, main(["eval", str(scans / "bare")]))
    assert f"{SCENE}_sem_label.npy: missing: it holds the scan's labels" in line


# ------------------------------------------------------------------------------------------
# --format's other names of the layouts


def test_detect_takes_sunrgbd_and_votenet(scans, labelled_detections, tmp_path):
    assert _detect(scans / "frame" / f"{FRAME}_pc.npz", tmp_path / "s", "-f", "sunrgbd") == 0
    assert _detections(tmp_path / "s")["detections"] == labelled_detections["detections"]
    assert _detect(scans / "bare" / f"{SCENE}_vert.npy", tmp_path / "v", "-f", "VoteNet") == 0
    assert _detections(tmp_path / "v")["detections"] == labelled_detections["detections"]


def test_segment_takes_sunrgbd_and_votenet(room, scans, tmp_path):
    planes = {}
    for name, path in (
        ("sunrgbd", scans / "frame" / f"{FRAME}_pc.npz"),
        ("votenet", scans / "bare" / f"{SCENE}_vert.npy"),
    ):
        out = tmp_path / name
        assert main(["-q", "segment", str(path), "-o", str(out), "-f", name]) == 0
        assert len(read_cloud(out / "segments.ply")) == len(room)
        doc = json.loads((out / "planes.json").read_text())
        doc.pop("source")  # the one difference: the file read
        planes[name] = doc
    assert planes["sunrgbd"] == planes["votenet"]


def test_cad_fit_takes_sunrgbd(scans, labelled_detections, tmp_path):
    frame = scans / "frame" / f"{FRAME}_pc.npz"
    det = tmp_path / "det"
    assert _detect(frame, det, "-f", "sunrgbd") == 0
    out = tmp_path / "cad"
    assert main(["-q", "cad", "fit", str(det), str(frame), "-o", str(out), "-f", "sunrgbd"]) == 0
    doc = _detections(out)
    assert len(doc["detections"]) == len(labelled_detections["detections"])
    assert all("cad" in d for d in doc["detections"])


@pytest.mark.parametrize(
    ("command", "args"),
    [
        ("detect", ["detect", "{scan}", "-o", "{out}"]),
        ("segment", ["segment", "{scan}", "-o", "{out}"]),
        ("cad fit", ["cad", "fit", "{scan}", "{scan}", "-o", "{out}"]),
        ("info", ["info", "{scan}"]),
    ],
)
def test_a_dataset_layout_is_refused_by_every_one_cloud_command_alike(
    scans, tmp_path, capsys, command, args
):
    scan, out = scans / "bare" / f"{SCENE}_vert.npy", tmp_path / "out"
    argv = [a.format(scan=scan, out=out) for a in args] + ["-f", "synth"]
    line = _one_line(capsys, main(argv))
    assert line.startswith("error: The '--format' parameter must be one of ply, pcd, ")
    assert f"sunrgbd-votenet, s3dis ({command} reads one cloud or scan); " in line
    assert line.endswith(
        "'synth' is a dataset layout: 'ontodetect eval -f synth' reads it. Got 'synth' instead."
    )
    assert not out.exists()  # refused before any work
