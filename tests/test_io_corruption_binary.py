"""Damaged PLY, PCD and NumPy files: only OntoDetectError, never a crash or a huge allocation.

Every valid file below is cut short at many offsets and has bytes flipped at
seeded random places. Reading must then either give a consistent cloud or raise
an :class:`OntoDetectError`; any other exception (IndexError, ValueError,
MemoryError, a RuntimeWarning from NumPy) is a bug. Headers that claim 10**12
points must be refused from the file size, before any allocation.
"""

from __future__ import annotations

import io
import struct
import warnings
import zipfile

import numpy as np
import pytest

from ontodetect import CorruptFileError, DataWarning, OntoDetectError, point_cloud, read_cloud
from ontodetect.io._numpy import write_npy, write_npz
from ontodetect.io._pcd import write_pcd
from ontodetect.io._ply import write_ply

#: Truncation points drawn at random in the body (every header offset is tried too).
BODY_CUTS = 40
#: Damaged copies per file, each with 1 to MAX_FLIPS changed bytes.
FLIP_CASES = 120
MAX_FLIPS = 3
SEED = 8128


def _cloud(n=24):
    rng = np.random.default_rng(SEED)
    return point_cloud(
        rng.normal(size=(n, 3)),
        rgb=rng.integers(0, 256, (n, 3)),
        normals=rng.normal(size=(n, 3)),
        fields={
            "label": rng.integers(0, 40, n).astype(np.int32),
            "score": rng.random(n).astype(np.float32),
        },
    )


def _ply_mesh(tmp_path, fmt):
    """A mesh: an element before the vertices and faces after, like real exports."""
    cloud = _cloud(12)
    body_fmt = "ascii" if fmt == "ascii" else f"binary_{fmt}_endian"
    order = "<" if fmt == "little" else ">"
    lines = [
        "ply",
        f"format {body_fmt} 1.0",
        "comment damaged on purpose",
        "element material 2",
        "property list uchar float params",
        "element vertex 12",
        "property float x",
        "property float y",
        "property float z",
        "property uchar red",
        "property uchar green",
        "property uchar blue",
        "property int label",
        "element face 4",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    head = ("\n".join(lines) + "\n").encode()
    if fmt == "ascii":
        body = "2 0.5 1.5\n1 3\n"
        for p, c, lab in zip(cloud.xyz, cloud.rgb, cloud.fields["label"]):
            body += " ".join(f"{v:.6g}" for v in p) + " " + " ".join(map(str, c)) + f" {lab}\n"
        body += "".join(f"3 {k} {k + 1} {k + 2}\n" for k in range(4))
        data = head + body.encode()
    else:
        vert = np.empty(12, [("p", f"{order}f4", 3), ("c", "u1", 3), ("l", f"{order}i4")])
        vert["p"], vert["c"], vert["l"] = cloud.xyz, cloud.rgb, cloud.fields["label"]
        pre = struct.pack(f"{order}B2f", 2, 0.5, 1.5) + struct.pack(f"{order}Bf", 1, 3)
        faces = b"".join(struct.pack(f"{order}B3i", 3, k, k + 1, k + 2) for k in range(4))
        data = head + pre + vert.tobytes() + faces
    f = tmp_path / f"mesh_{fmt}.ply"
    f.write_bytes(data)
    return f


def _organized_pcd(tmp_path, data):
    grid = _cloud(24)
    organized = point_cloud(
        grid.xyz, rgb=grid.rgb, fields=dict(grid.fields), meta={"width": 6, "height": 4}
    )
    return write_pcd(tmp_path / f"grid_{data}.pcd", organized, data=data)


def _npz_stored(tmp_path):
    return write_npz(tmp_path / "stored.npz", _cloud())


def _npz_deflated(tmp_path):
    return write_npz(tmp_path / "deflated.npz", _cloud(), compressed=True)


def _npy_table(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataWarning)  # normals and fields are not stored
        return write_npy(tmp_path / "table.npy", _cloud())


def _npy_structured(tmp_path):
    arr = np.zeros(16, [("x", "<f4"), ("y", "<f4"), ("z", "<f8"), ("label", "<u2")])
    arr["x"] = np.arange(16)
    f = tmp_path / "rec.npy"
    np.save(f, arr)
    return f


MAKERS = {
    "ply-binary": (lambda p: write_ply(p / "c.ply", _cloud()), "ply"),
    "ply-binary-float32": (lambda p: write_ply(p / "c32.ply", _cloud(), dtype="float32"), "ply"),
    "ply-ascii": (lambda p: write_ply(p / "a.ply", _cloud(), ascii=True), "ply"),
    "ply-mesh-little": (lambda p: _ply_mesh(p, "little"), "ply"),
    "ply-mesh-big": (lambda p: _ply_mesh(p, "big"), "ply"),
    "ply-mesh-ascii": (lambda p: _ply_mesh(p, "ascii"), "ply"),
    "pcd-binary": (lambda p: _organized_pcd(p, "binary"), "pcd"),
    "pcd-ascii": (lambda p: _organized_pcd(p, "ascii"), "pcd"),
    "pcd-binary_compressed": (lambda p: _organized_pcd(p, "binary_compressed"), "pcd"),
    "npy-table": (_npy_table, "npy"),
    "npy-structured": (_npy_structured, "npy"),
    "npz-stored": (_npz_stored, "npz"),
    "npz-deflated": (_npz_deflated, "npz"),
}


def _header_length(data: bytes) -> int:
    for marker in (b"end_header\n", b"DATA binary_compressed\n", b"DATA binary\n", b"DATA ascii\n"):
        at = data.find(marker)
        if at >= 0:
            return at + len(marker)
    return min(len(data), 128)


def _read_damaged(path, fmt):
    """Read a damaged file: a consistent cloud or an OntoDetectError, nothing else."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a NumPy RuntimeWarning here would be a bug
        warnings.simplefilter("ignore", DataWarning)  # damage may well make NaN points
        try:
            cloud = read_cloud(path, format=fmt)
        except OntoDetectError:
            return
    n = len(cloud)
    assert n > 0
    assert cloud.xyz.dtype == np.float64 and cloud.xyz.shape == (n, 3)
    assert np.isfinite(cloud.xyz).all()
    assert cloud.index.shape == (n,)
    assert cloud.rgb is None or (cloud.rgb.dtype == np.uint8 and cloud.rgb.shape == (n, 3))
    for values in cloud.fields.values():
        assert values.shape[0] == n


@pytest.mark.parametrize("name", sorted(MAKERS))
def test_valid_file_reads(tmp_path, name):
    make, fmt = MAKERS[name]
    cloud = read_cloud(make(tmp_path), format=fmt, on_nonfinite="drop")
    assert len(cloud) > 0


@pytest.mark.parametrize("name", sorted(MAKERS))
def test_truncated_files(tmp_path, name):
    make, fmt = MAKERS[name]
    data = make(tmp_path).read_bytes()
    rng = np.random.default_rng(SEED)
    head = _header_length(data)
    cuts = set(range(0, head + 1)) | set(rng.integers(head, len(data), BODY_CUTS).tolist())
    cuts.discard(len(data))
    target = tmp_path / "damaged"
    for cut in sorted(cuts):
        target.write_bytes(data[:cut])
        _read_damaged(target, fmt)


@pytest.mark.parametrize("name", sorted(MAKERS))
def test_flipped_bytes(tmp_path, name):
    make, fmt = MAKERS[name]
    data = make(tmp_path).read_bytes()
    rng = np.random.default_rng(SEED)
    head = _header_length(data)
    target = tmp_path / "damaged"
    for case in range(FLIP_CASES):
        buf = bytearray(data)
        # Half the cases hit the header, where a flip changes the meaning of everything.
        limit = head if case % 2 else len(buf)
        for at in rng.integers(0, limit, rng.integers(1, MAX_FLIPS + 1)):
            buf[at] ^= int(rng.integers(1, 256))
        target.write_bytes(bytes(buf))
        _read_damaged(target, fmt)


def _npy_claiming(shape: str) -> bytes:
    buf = io.BytesIO()
    np.save(buf, np.zeros((2, 3)))
    return buf.getvalue().replace(b"(2, 3)", shape.encode().ljust(6))


@pytest.mark.parametrize(
    ("fmt", "content"),
    [
        (
            "ply",
            b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n"
            b"property double x\nproperty double y\nproperty double z\nend_header\n" + b"\0" * 48,
        ),
        (
            "ply",
            b"ply\nformat binary_little_endian 1.0\nelement face 1000000000000\n"
            b"property list uchar int vertex_indices\nelement vertex 1\nproperty float x\n"
            b"property float y\nproperty float z\nend_header\n" + b"\3" * 64,
        ),
        (
            "ply",
            b"ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\n"
            b"property float y\nproperty float z\nend_header\n1 2 3\n",
        ),
        (
            "pcd",
            b"VERSION 0.7\nFIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nCOUNT 1 1 1\n"
            b"WIDTH 1000000 \nHEIGHT 1000000\nPOINTS 1000000000000\nDATA binary\n" + b"\0" * 48,
        ),
        (
            "pcd",
            b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            b"WIDTH 1000000000000\nHEIGHT 1\nPOINTS 1000000000000\n"
            b"DATA binary_compressed\n" + struct.pack("<II", 16, 4294967295) + b"\0" * 16,
        ),
        (
            "pcd",
            b"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1000000000\n"
            b"WIDTH 1000\nHEIGHT 1\nPOINTS 1000\nDATA binary\n" + b"\0" * 48,
        ),
        ("npy", _npy_claiming("(1000000000000, 3)")),
    ],
)
def test_headers_claiming_huge_counts_are_refused_from_the_file_size(tmp_path, fmt, content):
    f = tmp_path / "huge"
    f.write_bytes(content)
    with pytest.raises(CorruptFileError):
        read_cloud(f, format=fmt)


def test_npz_member_claiming_huge_shape(tmp_path):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("xyz.npy", _npy_claiming("(1000000000000, 3)"))
    f = tmp_path / "huge.npz"
    f.write_bytes(buf.getvalue())
    with pytest.raises(CorruptFileError, match="truncated"):
        read_cloud(f)
