"""Issue 23: every bad input gets one clear line and exit status 2, resources are bounded
before they are taken, and the output folder of a run changes all at once.

Every case the issue lists is one test here; the hostile files are made in ``tmp_path``.
"""

from __future__ import annotations

import errno
import io
import json
import os
import struct
import warnings
import zipfile

import numpy as np
import pytest

from ontodetect.cli import main
from ontodetect.cloud import DataWarning
from ontodetect.io import read_cloud, write_cloud
from ontodetect.synth import synthesize

ONTOLOGY_HEAD = "format: ontodetect.ontology/1\nclasses:\n"


def one_line(capsys, status: int, *must: str) -> str:
    """The run failed with exit status 2 and exactly one line on stderr holding ``must``."""
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert status == 2, err
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for text in must:
        assert text in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def room(tmp_path_factory):
    """A small simulated room written as PLY (and its cloud)."""
    folder = tmp_path_factory.mktemp("room")
    cloud = synthesize("tiny", seed=1).cloud
    return write_cloud(folder / "room.ply", cloud), cloud


def _detect(room_file, out, *extra):
    return main(["-q", "detect", str(room_file), "-o", str(out), "--votes", "1", *extra])


# ------------------------------------------------------------------------------------------
# 1. One error path: markup printed verbatim, tracebacks turned into one line


def test_markup_in_a_ply_header_is_printed_verbatim(tmp_path, capsys):
    f = tmp_path / "m.ply"
    f.write_text("ply\nformat ascii 1.0\nelement vertex [/x]\nend_header\n")
    one_line(capsys, main(["info", str(f)]), "m.ply", "'[/x]'")


def test_markup_like_bold_in_a_path_does_not_vanish(tmp_path, capsys):
    f = tmp_path / "[bold]x.ply"
    f.write_text("ply\nformat ascii 1.0\nelement vertex -1\nend_header\n")
    one_line(capsys, main(["info", str(f)]), "[bold]x.ply")


def test_ontology_key_paths_are_visible(room, tmp_path, capsys):
    f = tmp_path / "o.yaml"
    f.write_text(ONTOLOGY_HEAD + "  bar_stool:\n    parts:\n      seat: {height: oops}\n")
    one_line(
        capsys,
        _detect(room[0], tmp_path / "o", "--ontology", str(f)),
        "o.yaml",
        "[classes.bar_stool.parts.seat.height]",
    )


def test_a_variant_of_no_class_is_one_line_naming_its_key(room, tmp_path, capsys):
    f = tmp_path / "v.yaml"
    f.write_text(
        ONTOLOGY_HEAD + "  armchair:\n    variant_of: chiar\n    parts:\n"
        "      seat: {height: [0.4, 0.8]}\n"
    )
    out = tmp_path / "o"
    one_line(
        capsys,
        _detect(room[0], out, "--ontology", str(f)),
        "v.yaml",
        "[classes.armchair.variant_of]",
        "'chiar'",
    )
    assert not out.exists()  # refused before anything is written


def test_pcd_with_an_empty_height_line(tmp_path, capsys):
    f = tmp_path / "h.pcd"
    f.write_text(
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT\n"
        "POINTS 1\nDATA ascii\n1 2 3\n"
    )
    one_line(capsys, main(["info", str(f)]), "h.pcd", "HEIGHT")


def _las_with_extra_bytes_type_0(path):
    import laspy

    header = laspy.LasHeader(point_format=3, version="1.4")
    header.add_extra_dim(laspy.ExtraBytesParams(name="foo", type=np.uint8))
    las = laspy.LasData(header)
    las.x = np.array([0.0, 1.0])
    las.y = np.array([0.0, 1.0])
    las.z = np.array([0.0, 1.0])
    las.write(path)
    data = bytearray(path.read_bytes())
    # The extra-bytes descriptor: 2 reserved bytes, then its data_type byte.
    at = data.index(b"foo")  # the descriptor's name field starts 4 bytes after its start
    data[at - 2] = 0
    path.write_bytes(bytes(data))


def test_las_extra_bytes_descriptor_of_type_0(tmp_path, capsys):
    f = tmp_path / "e.las"
    _las_with_extra_bytes_type_0(f)
    one_line(capsys, main(["info", str(f)]), "e.las")


@pytest.mark.skipif(os.geteuid() == 0, reason="permissions do not bind root")
def test_a_file_in_an_unreadable_folder(tmp_path, capsys):
    folder = tmp_path / "locked"
    folder.mkdir()
    (folder / "a.ply").write_text("ply\n")
    folder.chmod(0)
    try:
        one_line(capsys, main(["info", str(folder / "a.ply")]), "a.ply", "permission denied")
    finally:
        folder.chmod(0o755)


def test_a_folder_where_a_file_is_expected(tmp_path, capsys):
    # What root sees instead of an unreadable folder: a path that cannot be read as a file.
    folder = tmp_path / "x.ply"
    folder.mkdir()
    one_line(capsys, main(["info", str(folder)]), "x.ply")


@pytest.mark.parametrize("suffix", ["npy", "ply", "xyz"])
def test_a_cloud_of_nan_points_only_is_one_error_and_no_warning(tmp_path, capsys, suffix):
    f = tmp_path / f"nan.{suffix}"
    if suffix == "npy":
        np.save(f, np.full((3000, 3), np.nan))
    elif suffix == "xyz":  # a reader that leaves the check to read_cloud
        f.write_text("nan nan nan\nnan 0 0\n")
    else:
        f.write_text(
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
            "property float z\nend_header\nnan nan nan\nnan 0 0\n"
        )
    n = 3000 if suffix == "npy" else 2
    with warnings.catch_warnings():
        warnings.simplefilter("always")  # shown as a user's run shows them, not raised
        status = main(["detect", str(f), "-o", str(tmp_path / "o")])
    line = one_line(capsys, status, f"nan.{suffix}")
    of = "" if suffix == "xyz" else f" (of {n})"
    assert line == f"error: {f}: contains no points with finite coordinates{of}"
    assert not (tmp_path / "o").exists()


def test_a_cloud_with_some_finite_points_still_warns_of_the_others(tmp_path):
    f = tmp_path / "half.npy"
    np.save(f, np.array([[0.0, 0, 0], [np.nan, 0, 0], [1, 2, 3]]))
    with pytest.warns(DataWarning, match="dropped 1 of 3 points"):
        assert len(read_cloud(f)) == 2


@pytest.mark.parametrize("encoding", ["ascii", "binary_little_endian"])
def test_a_ply_whose_x_is_a_list_property(tmp_path, capsys, encoding):
    f = tmp_path / "l.ply"
    head = (
        f"ply\nformat {encoding} 1.0\nelement vertex 2\nproperty list uchar float x\n"
        "property float y\nproperty float z\nend_header\n"
    )
    if encoding == "ascii":
        body = b"1 0 0 0\n1 1 1 1\n"
    else:
        body = struct.pack("<Bfff", 1, 0, 0, 0) + struct.pack("<Bfff", 1, 1, 1, 1)
    f.write_bytes(head.encode() + body)
    line = one_line(capsys, main(["info", str(f)]), "l.ply")
    assert line == (
        f"error: {f}: element 'vertex': property 'x' is a list, which is not supported for "
        "coordinates (x, y and z must be scalar properties)"
    )


def test_an_npy_with_a_damaged_header_is_one_plain_line(tmp_path, capsys):
    f = tmp_path / "hdr.npy"
    np.save(f, np.zeros((10, 3)))
    data = bytearray(f.read_bytes())
    at = data.index(b"'descr'")
    data[at : at + 7] = b"#$%^&*("  # garbage over a key of the header's dictionary
    f.write_bytes(bytes(data))
    line = one_line(capsys, main(["info", str(f)]), "hdr.npy")
    assert line == f"error: {f}: unreadable .npy header (SyntaxError)"


@pytest.mark.parametrize(
    "args",
    [
        ["detect", "{scan}", "-o", "{out}"],
        ["segment", "{scan}", "-o", "{out}"],
        ["eval", "{folder}", "-o", "{out}"],
        ["calibrate", "{folder}", "-o", "{out}"],
    ],
    ids=["detect", "segment", "eval", "calibrate"],
)
def test_a_bad_up_axis_lists_every_value_up_takes(tmp_path, capsys, args):
    f = tmp_path / "scan.npy"
    np.save(f, np.zeros((10, 3)))
    out = tmp_path / "o"
    argv = [a.format(scan=f, folder=tmp_path, out=out) for a in args]
    # Named as the option, not as the configuration key it sets (prepare.up).
    line = one_line(capsys, main([*argv, "--up", "q"]))
    assert line == (
        "error: The '--up' parameter must be one of 'z', '-z', 'y', '-y', 'x', '-x', "
        "'auto', 'auto-frame'. Got 'q' instead."
    )
    assert not out.exists()  # refused before any work


def test_output_where_detections_json_is_a_folder(room, tmp_path, capsys):
    out = tmp_path / "out"
    (out / "detections.json").mkdir(parents=True)
    one_line(capsys, _detect(room[0], out, "--no-picture"), "detections.json")


@pytest.mark.parametrize("command", ["detect", "segment"])
def test_an_output_folder_that_is_a_file_is_refused_before_any_work(
    room, tmp_path, capsys, monkeypatch, command
):
    import ontodetect.io as io

    def no_reading(*args, **kwargs):
        raise AssertionError("the scan was read before the output folder was checked")

    monkeypatch.setattr(io, "read_cloud", no_reading)
    monkeypatch.setattr(f"ontodetect.cli.{command}.read_points", no_reading)  # its reader
    (tmp_path / "afile").write_text("")
    status = main([command, str(room[0]), "-o", str(tmp_path / "afile")])
    one_line(capsys, status, "afile", "is a file, not a folder")
    status = main([command, str(room[0]), "-o", str(tmp_path / "afile" / "below")])
    one_line(capsys, status, "below", "is a file")


@pytest.mark.parametrize(
    ("option", "value"), [("--workers", "-2"), ("--jobs", "-1"), ("--scheduler", "foo")]
)
def test_executor_options_are_checked_for_one_scan_too(room, tmp_path, capsys, option, value):
    one_line(capsys, _detect(room[0], tmp_path / "o", option, value), f"'{option}'", value)
    assert not (tmp_path / "o").exists()


def test_negative_seed(room, tmp_path, capsys):
    one_line(capsys, _detect(room[0], tmp_path / "o", "--seed", "-1"), "'seed'", "-1")


def test_deeply_nested_ontology(tmp_path, capsys):
    f = tmp_path / "deep.yaml"
    f.write_text(ONTOLOGY_HEAD + "  a: " + "[" * 5000 + "]" * 5000 + "\n")
    one_line(capsys, main(["detect", str(f), "-o", str(tmp_path), "--ontology", str(f)]), "nested")


def test_deeply_nested_configuration(room, tmp_path, capsys):
    f = tmp_path / "deep.yaml"
    f.write_text("cluster: " + "{a: " * 3000 + "1" + "}" * 3000 + "\n")
    one_line(capsys, _detect(room[0], tmp_path / "o", "--config", str(f)), "deep.yaml", "nested")


def test_yaml_key_that_is_a_list(room, tmp_path, capsys):
    f = tmp_path / "k.yaml"
    f.write_text("? [cluster, radius]\n: 1\n")
    one_line(capsys, _detect(room[0], tmp_path / "o", "--config", str(f)), "k.yaml", "key")
    g = tmp_path / "k2.yaml"
    g.write_text(ONTOLOGY_HEAD + "  ? [a, b]\n  : {}\n")
    one_line(capsys, _detect(room[0], tmp_path / "o", "--ontology", str(g)), "k2.yaml", "key")


@pytest.fixture(scope="module")
def stored(room, tmp_path_factory):
    """detections.json of the small room."""
    out = tmp_path_factory.mktemp("stored")
    assert _detect(room[0], out, "--no-picture") == 0
    return json.loads((out / "detections.json").read_text())


def test_cad_fit_on_parts_that_are_a_string(room, stored, tmp_path, capsys):
    doc = json.loads(json.dumps(stored))
    assert doc["detections"], "the small room has detections"
    doc["detections"][0]["parts"] = "x"
    f = tmp_path / "d.json"
    f.write_text(json.dumps(doc))
    one_line(
        capsys, main(["cad", "fit", str(f), str(room[0]), "-o", str(tmp_path / "o")]), "d.json"
    )


def test_cad_fit_on_a_box_of_1e30(room, stored, tmp_path, capsys):
    doc = json.loads(json.dumps(stored))
    doc["detections"][0]["box"]["size"] = [1e30, 1e30, 1e30]
    f = tmp_path / "d.json"
    f.write_text(json.dumps(doc))
    one_line(
        capsys, main(["cad", "fit", str(f), str(room[0]), "-o", str(tmp_path / "o")]), "d.json"
    )


def test_a_point_at_1e20_metres(room, tmp_path, capsys):
    cloud = room[1]
    xyz = cloud.xyz.copy()
    xyz[0] = [1e20, 0.0, 0.0]
    f = write_cloud(tmp_path / "far.ply", cloud.replace(xyz=xyz))
    out = tmp_path / "o"
    one_line(capsys, _detect(f, out), "far.ply", "1e+20")
    assert not out.exists() or not any(out.iterdir()), "nothing written"


def test_unexpected_exceptions_are_one_line_and_traceback_with_v(room, tmp_path, capsys):
    import ontodetect.pipeline._detect as d

    def boom(*a, **k):
        raise LookupError("surprise [red]x[/]")

    mp = pytest.MonkeyPatch()
    mp.setattr(d, "class_priors", boom)
    try:
        one_line(capsys, _detect(room[0], tmp_path / "o"), "room.ply", "LookupError", "[red]x[/]")
        status = main(["-v", "detect", str(room[0]), "-o", str(tmp_path / "o"), "--votes", "1"])
        assert status == 2
        assert "Traceback" in capsys.readouterr().err
    finally:
        mp.undo()


# ------------------------------------------------------------------------------------------
# 2. Budgets checked before allocating


def _npy_header(shape: str, descr: str = "<f8") -> bytes:
    head = f"{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}".encode()
    head += b" " * (63 - (len(head) + 10) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(head)) + head


def test_npz_zip_bomb_is_refused_before_decompressing(tmp_path, capsys, monkeypatch):
    # Small version of the 3.4 MB -> 3.4 GB bomb: zeros compress ~1000x, and the member's
    # header declares more than the budget, which is checked before inflating.
    monkeypatch.setenv("ONTODETECT_MAX_BYTES", str(8 * 2**20))
    rows = 1_000_000
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("xyz.npy", _npy_header(f"({rows}, 3)") + bytes(rows * 24))
    f = tmp_path / "bomb.npz"
    f.write_bytes(buf.getvalue())
    assert f.stat().st_size < 100_000
    one_line(capsys, main(["info", str(f)]), "bomb.npz", "ONTODETECT_MAX_BYTES")


def test_pcd_claiming_a_compressed_size_of_4_gb(tmp_path, capsys):
    f = tmp_path / "c.pcd"
    head = (
        b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 100\nHEIGHT 1\n"
        b"POINTS 100\nDATA binary_compressed\n"
    )
    f.write_bytes(head + struct.pack("<II", 0xFFFFFFFF, 1200) + bytes(28_000))
    one_line(capsys, main(["info", str(f)]), "c.pcd", "4294967295")


def test_npy_declaring_200_million_points(tmp_path, capsys):
    # An honest file: the header's size matches the file's (sparse, so it takes no disk).
    f = tmp_path / "big.npy"
    head = _npy_header("(200000000, 3)", "<f4")
    with open(f, "wb") as fh:
        fh.write(head)
        fh.truncate(len(head) + 200_000_000 * 12)
    one_line(capsys, main(["info", str(f)]), "big.npy", "200,000,000 points")


def test_dev_zero_as_configuration_and_as_npz(room, tmp_path, capsys):
    one_line(capsys, _detect(room[0], tmp_path / "o", "--config", "/dev/zero"), "/dev/zero")
    link = tmp_path / "zero.npz"
    link.symlink_to("/dev/zero")
    one_line(capsys, main(["info", str(link)]), "zero.npz", "not a regular file")


def test_fifo_as_input_and_ontology_does_not_block(room, tmp_path, capsys):
    fifo = tmp_path / "in.ply"
    os.mkfifo(fifo)
    one_line(capsys, main(["info", str(fifo)]), "in.ply", "FIFO")
    onto = tmp_path / "o.yaml"
    os.mkfifo(onto)
    one_line(capsys, _detect(room[0], tmp_path / "o", "--ontology", str(onto)), "o.yaml", "FIFO")


def test_yaml_alias_bomb(room, tmp_path, capsys):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, 9)]
    f = tmp_path / "bomb.yaml"
    f.write_text(ONTOLOGY_HEAD.replace("classes:\n", "") + "\n".join(lines) + "\n")
    one_line(capsys, _detect(room[0], tmp_path / "o", "--ontology", str(f)), "bomb.yaml", "alias")


# ------------------------------------------------------------------------------------------
# 4. Outputs all or nothing; detections.json byte-identical


def test_detections_json_is_byte_identical_for_the_same_input_and_seed(room, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    assert _detect(room[0], a, "--no-picture", "--seed", "3") == 0
    assert _detect(room[0], b, "--no-picture", "--seed", "3") == 0
    assert (a / "detections.json").read_bytes() == (b / "detections.json").read_bytes()
    assert "timings" not in json.loads((a / "detections.json").read_text())
    assert set(json.loads((a / "timings.json").read_text())) >= {"segment", "score", "label"}


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_a_full_disk_is_one_line_and_changes_nothing(room, tmp_path, capsys, monkeypatch):
    import ontodetect.io._atomic as atomic

    out = tmp_path / "out"
    assert _detect(room[0], out, "--no-picture") == 0
    before = _snapshot(out)
    real_fsync = os.fsync

    def full(fd):
        if os.readlink(f"/proc/self/fd/{fd}").split("/")[-1].startswith(".labelled.ply."):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", full)
    one_line(
        capsys,
        _detect(room[0], out, "--no-picture", "--seed", "2"),
        "labelled.ply",
        "No space left",
    )
    assert _snapshot(out) == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"], "no staging folder left"


def test_a_killed_run_leaves_the_old_result_and_its_leftovers_are_removed(room, tmp_path):
    out = tmp_path / "out"
    assert _detect(room[0], out, "--no-picture") == 0
    before = _snapshot(out)
    # What a kill leaves: a half-written staging folder, or the old result moved aside.
    (tmp_path / ".out.staging-abc").mkdir()
    (tmp_path / ".out.staging-abc" / "detections.json").write_text("{")
    out.rename(tmp_path / ".out.old-xyz")
    from ontodetect.io._atomic import _remove_stale

    _remove_stale(tmp_path, "out")
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
    assert _snapshot(out) == before


def test_a_new_run_replaces_every_file_of_the_old_one(room, tmp_path):
    out = tmp_path / "out"
    assert _detect(room[0], out) == 0
    assert (out / "detections.png").exists()
    assert _detect(room[0], out, "--no-picture") == 0
    assert not (out / "detections.png").exists(), "no picture of an older run beside the new"


def test_a_folder_with_other_files_keeps_them(room, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep")
    assert _detect(room[0], out, "--no-picture") == 0
    assert (out / "notes.txt").read_text() == "keep"
    assert (out / "detections.json").exists()


def test_a_folder_an_earlier_run_wrote_is_replaced_beside_the_users_files(room, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep")
    assert _detect(room[0], out, "--no-picture", "--export", "boxes,scannet") == 0
    assert (out / "scannet").is_dir()
    (out / "view.html").write_text("the user's")  # any other file: the per-file path
    assert _detect(room[0], out, "--no-picture", "--export", "boxes,scannet") == 0
    assert (out / "scannet").is_dir() and (out / "notes.txt").read_text() == "keep"
    assert _detect(room[0], out, "--no-picture", "--export", "") == 0
    assert not (out / "scannet").exists(), "the earlier run's export folder goes with it"
    assert (out / "view.html").read_text() == "the user's"


def test_a_run_that_adds_to_an_earlier_one_keeps_its_files(tmp_path):
    from ontodetect.io._atomic import RUN_MARKER, staged_folder

    out = tmp_path / "out"
    with staged_folder(out) as stage:
        (stage / "labelled.ply").write_text("cloud")
        (stage / "detections.json").write_text("old")
    with staged_folder(out, keep_earlier=True) as stage:
        (stage / "detections.json").write_text("with models")
        (stage / "object_map.ply").write_text("map")
    assert (out / "labelled.ply").read_text() == "cloud"
    assert (out / "detections.json").read_text() == "with models"
    listed = set((out / RUN_MARKER).read_text().split())
    assert listed == {"labelled.ply", "detections.json", "object_map.ply"}
    with staged_folder(out) as stage:  # the earlier kind of run again: all of it replaced
        (stage / "detections.json").write_text("new")
    assert sorted(p.name for p in out.iterdir()) == [RUN_MARKER, "detections.json"]


def test_an_output_folder_has_the_permissions_mkdir_gives(room, tmp_path):
    out = tmp_path / "out"
    assert _detect(room[0], out, "--no-picture") == 0
    mask = os.umask(0)
    os.umask(mask)
    assert out.stat().st_mode & 0o777 == 0o777 & ~mask


# ------------------------------------------------------------------------------------------
# 2 (end). The part-assignment search: a branch and bound, same results as every combination


@pytest.fixture(scope="module")
def descriptions(room):
    from ontodetect.config import Config
    from ontodetect.ontology import builtin_ontology
    from ontodetect.segment import segment
    from ontodetect.segment._measure import describe_clusters

    descs = []
    for name, seed in (("tiny", 1), ("dining_room", 5)):
        cloud = (
            room[1] if name == "tiny" else synthesize(name, "rgbd", seed=seed, points=60_000).cloud
        )
        seg = segment(cloud, Config(), seed=0, ontology=builtin_ontology())
        descs.extend(describe_clusters(seg, None))
    assert len(descs) >= 10
    return descs


def test_branch_and_bound_finds_what_every_combination_finds(descriptions):
    from ontodetect.ontology import builtin_ontology
    from ontodetect.ontology._score import score_class

    onto = builtin_ontology()
    compared = 0
    for desc in descriptions:
        for cls in onto.classes:
            fast = score_class(cls, desc)
            slow = score_class(cls, desc, search_exhaustively=True)
            assert fast.assignment == slow.assignment, (cls.name, fast.assignment, slow.assignment)
            assert fast.log_likelihood == slow.log_likelihood
            compared += 1
    assert compared >= 30


def test_a_class_with_12_optional_parts_is_scored_in_seconds(descriptions, tmp_path):
    import time

    from ontodetect.ontology import parse_ontology
    from ontodetect.ontology._score import score_class

    parts = "".join(
        f"      p{k}: {{required: false, missing: 0.5, tilt: {{max: {10 + k}}}, "
        f"height: [{0.1 * k:.1f}, {0.1 * k + 0.5:.1f}]}}\n"
        for k in range(12)
    )
    onto = parse_ontology(ONTOLOGY_HEAD + "  many:\n    parts:\n" + parts)
    cls = onto.classes[0]
    start = time.perf_counter()
    for desc in descriptions:
        score_class(cls, desc)
    assert time.perf_counter() - start < 10.0


# ------------------------------------------------------------------------------------------
# 3. Units, outliers and values outside their meaning


def test_a_room_in_centimetres_is_scaled_as_centimetres(room, tmp_path):
    from ontodetect.preprocess import guess_units
    from ontodetect.preprocess._prepare import guess_scale

    cloud = room[1]
    assert guess_units(cloud.xyz) == "metres"
    assert guess_units(cloud.xyz * 100) == "centimetres"
    assert guess_units(cloud.xyz * 1000) == "millimetres"
    assert guess_scale(cloud.xyz * 100) == 0.01
    a, b = tmp_path / "m", tmp_path / "cm"
    f = write_cloud(tmp_path / "cm.ply", cloud.replace(xyz=cloud.xyz * 100))
    assert _detect(room[0], a, "--no-picture") == 0
    assert _detect(f, b, "--no-picture") == 0
    labels = [
        sorted(d["label"] for d in json.loads((x / "detections.json").read_text())["detections"])
        for x in (a, b)
    ]
    assert labels[0] and labels[1] == labels[0]


def test_one_stray_point_a_kilometre_away_changes_nothing(room, tmp_path):
    from ontodetect.preprocess import guess_units

    cloud = room[1]
    xyz = cloud.xyz.copy()
    xyz[0] = [1000.0, 0.0, 1.0]
    assert guess_units(xyz) == "metres"
    f = write_cloud(tmp_path / "stray.ply", cloud.replace(xyz=xyz))
    a, b = tmp_path / "a", tmp_path / "b"
    assert _detect(room[0], a, "--no-picture") == 0
    assert _detect(f, b, "--no-picture") == 0
    counts = [len(json.loads((x / "detections.json").read_text())["detections"]) for x in (a, b)]
    assert counts[0] > 0 and counts[1] == counts[0]


@pytest.mark.parametrize("value", ["2", "nan", "-0.5"])
def test_indoor_outside_a_probability(room, tmp_path, capsys, value):
    one_line(capsys, _detect(room[0], tmp_path / "o", "--indoor", value), "'indoor'", "[0, 1]")


def test_room_probability_of_inf(room, tmp_path, capsys):
    f = tmp_path / "rooms.yaml"
    f.write_text("office: .inf\n")
    one_line(capsys, _detect(room[0], tmp_path / "o", "--room-probs", str(f)), "office", "inf")


def test_ontology_room_probability_of_inf(room, tmp_path, capsys):
    f = tmp_path / "o.yaml"
    f.write_text(
        ONTOLOGY_HEAD + "  stool:\n    prior: {rooms: {office: .inf}}\n"
        "    parts:\n      seat: {height: [0.4, 0.8]}\n"
    )
    one_line(capsys, _detect(room[0], tmp_path / "o", "--ontology", str(f)), "[classes.stool")


def test_unknown_prior_rooms_table(room, tmp_path, capsys):
    f = tmp_path / "o.yaml"
    f.write_text(
        ONTOLOGY_HEAD + "  stool:\n    prior: {rooms: sitting}\n"
        "    parts:\n      seat: {height: [0.4, 0.8]}\n"
    )
    line = one_line(
        capsys, _detect(room[0], tmp_path / "o", "--ontology", str(f)), "o.yaml", "'sitting'"
    )
    assert "[classes.stool.prior.rooms]" in line and "seating" in line


def test_yaml_reads_1e_minus_12_as_a_number(tmp_path):
    from ontodetect.config import Config
    from ontodetect.ontology import parse_ontology

    f = tmp_path / "c.yaml"
    f.write_text("cluster:\n  radius: 4e-2\n")
    assert Config.from_yaml(f).cluster.radius == 0.04
    onto = parse_ontology(
        ONTOLOGY_HEAD
        + "  stool:\n    extra_plane: 1e-12\n    parts:\n      seat: {height: [4e-1, 8E-1]}\n"
    )
    assert onto.classes[0].extra_plane == 1e-12
    assert Config().with_overrides(["cluster.radius=5e-2"]).cluster.radius == 0.05


def test_unreadable_folder_simulated_for_root(tmp_path, capsys, monkeypatch):
    # Root ignores permissions: the PermissionError a user meets is raised by hand.
    import pathlib

    folder = tmp_path / "locked"
    folder.mkdir()
    target = folder / "a.ply"
    target.write_text("ply\n")
    real_stat = pathlib.Path.stat

    def stat(self, *a, **k):
        if self == target:
            raise PermissionError(13, "Permission denied", str(self))
        return real_stat(self, *a, **k)

    monkeypatch.setattr(pathlib.Path, "stat", stat)
    one_line(capsys, main(["info", str(target)]), "a.ply", "permission denied")


def test_eval_over_an_unreadable_sub_folder(tmp_path, capsys, monkeypatch):
    import pathlib

    data = tmp_path / "data"
    (data / "area_1").mkdir(parents=True)
    locked = data / "area_1"
    real_iterdir = pathlib.Path.iterdir

    def iterdir(self):
        if self == locked:
            raise PermissionError(13, "Permission denied", str(self))
        return real_iterdir(self)

    monkeypatch.setattr(pathlib.Path, "iterdir", iterdir)
    one_line(capsys, main(["eval", str(data), "-o", str(tmp_path / "r")]), "area_1", "permission")
