import os

import numpy as np
import pytest

from ontodetect import ReadError, UnsupportedFormatError, WriteError, point_cloud, read_cloud
from ontodetect.io import FORMATS, READERS, WRITERS, detect_format, supported_formats, write_cloud
from ontodetect.io._atomic import atomic_write, atomic_write_text


@pytest.mark.parametrize(
    ("name", "fmt"),
    [
        ("a.ply", "ply"),
        ("a.PCD", "pcd"),
        ("a.xyz", "text"),
        ("a.csv", "text"),
        ("a.pts", "text"),
        ("a.npy", "npy"),
        ("a.npz", "npz"),
        ("a.las", "las"),
        ("a.laz", "las"),
        ("scan000.3d", "3dtk"),
        ("scene0000_00_vert.npy", "scannet-votenet"),
    ],
)
def test_detect_format_by_name(name, fmt):
    assert detect_format(name) == fmt


def test_detect_format_folders(tmp_path):
    (tmp_path / "room" / "Annotations").mkdir(parents=True)
    assert detect_format(tmp_path / "room") == "s3dis"
    (tmp_path / "scan").mkdir()
    (tmp_path / "scan" / "scene0001_00_vh_clean_2.ply").write_bytes(b"")
    assert detect_format(tmp_path / "scan") == "scannet"
    with pytest.raises(UnsupportedFormatError, match="folder"):
        detect_format(tmp_path)


def test_unknown_extension_lists_supported_formats(tmp_path):
    f = tmp_path / "cloud.abc"
    f.write_text("1 2 3\n")
    msg = r"cloud\.abc: unknown file extension '\.abc'.*ply"
    with pytest.raises(UnsupportedFormatError, match=msg):
        read_cloud(f)


def test_missing_file_names_the_file(tmp_path):
    with pytest.raises(ReadError, match=r"nope\.ply: no such file"):
        read_cloud(tmp_path / "nope.ply")


def test_unknown_format_option(tmp_path):
    f = tmp_path / "a.ply"
    f.write_text("ply\n")
    with pytest.raises(UnsupportedFormatError, match="unknown format 'foo'"):
        read_cloud(f, format="foo")


def test_registries_cover_formats():
    assert set(READERS.keys()) == {n for n, f in FORMATS.items() if f.reader}
    assert set(WRITERS.keys()) == set(supported_formats("write"))
    assert "3dtk" not in WRITERS


def test_write_rejects_non_clouds_and_unwritable_formats(tmp_path):
    with pytest.raises(WriteError, match="expected a PointCloud"):
        write_cloud(tmp_path / "a.ply", np.zeros((3, 3)))
    with pytest.raises(UnsupportedFormatError, match="cannot"):
        write_cloud(tmp_path / "a.3d", point_cloud(np.zeros((3, 3))))


def test_atomic_write_keeps_old_file_on_failure(tmp_path):
    target = tmp_path / "out.txt"
    atomic_write_text(target, "old")
    with pytest.raises(RuntimeError), atomic_write(target, "w") as fh:
        fh.write("half")
        raise RuntimeError("boom")
    assert target.read_text() == "old"
    assert os.listdir(tmp_path) == ["out.txt"]


def test_atomic_write_into_missing_folder(tmp_path):
    with pytest.raises(WriteError, match="does not exist"):
        atomic_write_text(tmp_path / "no" / "x.txt", "a")
