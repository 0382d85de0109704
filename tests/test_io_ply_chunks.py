"""Chunked, two-thread decoding of binary PLY vertices against a plain decode.

The reader converts records chunk by chunk on several threads; whatever the
chunk size and the number of threads, the cloud must be bit for bit the one a
single ``numpy.frombuffer`` of the whole body gives through ``point_cloud``.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from ontodetect import (
    CorruptFileError,
    DataWarning,
    InvalidParameterError,
    ReadError,
    point_cloud,
)
from ontodetect._progress import use_reporter
from ontodetect.io import _chunks
from ontodetect.io._chunks import read_records
from ontodetect.io._ply import read_ply

N = 200
#: Rows holding NaN or infinite coordinates: first, last, and on both sides of
#: the boundaries of 7-, 16- and 37-row chunks.
NONFINITE_ROWS = [0, 6, 7, 15, 16, 36, 37, 38, 111, 112, N - 1]
#: A layout with everything the fast path must carry: extra fields of several
#: types and sizes around the coordinates, doubles, colours after a field.
LAYOUT = [
    ("label", "i2"),
    ("x", "f4"),
    ("y", "f4"),
    ("z", "f4"),
    ("intensity", "f8"),
    ("red", "u1"),
    ("green", "u1"),
    ("blue", "u1"),
    ("nx", "f4"),
    ("ny", "f4"),
    ("nz", "f4"),
    ("instance", "u4"),
]
PLY_NAMES = {
    "i2": "short",
    "i4": "int",
    "u1": "uchar",
    "u2": "ushort",
    "u4": "uint",
    "f4": "float",
    "f8": "double",
}
ENCODINGS = {"<": "binary_little_endian", ">": "binary_big_endian"}


def _rows(rng: np.random.Generator, order: str, layout=LAYOUT, n=N) -> np.ndarray:
    rows = np.zeros(n, dtype=[(name, order + code) for name, code in layout])
    for name, code in layout:
        kind = np.dtype(code)
        if kind.kind == "f":
            rows[name] = rng.normal(scale=100.0, size=n)
        else:
            info = np.iinfo(kind)
            rows[name] = rng.integers(info.min, info.max, n, endpoint=True)
    return rows


def _write(path: Path, rows: np.ndarray, order: str, faces: int = 0) -> Path:
    lines = ["ply", f"format {ENCODINGS[order]} 1.0", f"element vertex {len(rows)}"]
    lines += [f"property {PLY_NAMES[rows.dtype[n].str[1:]]} {n}" for n in rows.dtype.names]
    if faces:
        lines += [f"element face {faces}", "property list uchar int vertex_indices"]
    lines.append("end_header\n")
    body = rows.tobytes()
    if faces:
        tri = np.zeros(faces, dtype=[("k", "u1"), ("v", order + "i4", 3)])
        tri["k"] = 3
        body += tri.tobytes()
    path.write_bytes("\n".join(lines).encode() + body)
    return path


def _plain(rows, source: Path, on_nonfinite: str = "drop"):
    """What the reader must return, built without any chunking (``rows``: named columns)."""
    names = rows.dtype.names if isinstance(rows, np.ndarray) else tuple(rows)
    stack = lambda *cols: np.stack([rows[c] for c in cols], axis=1)  # noqa: E731
    rgb = stack("red", "green", "blue") if "red" in names else None
    normals = stack("nx", "ny", "nz").astype(np.float64) if "nx" in names else None
    fields = {
        n: rows[n].astype(rows[n].dtype.newbyteorder("="))
        for n in names
        if n not in {"x", "y", "z", "red", "green", "blue", "nx", "ny", "nz"}
    }
    return point_cloud(
        stack("x", "y", "z").astype(np.float64),
        rgb=rgb,
        normals=normals,
        fields=fields,
        meta={"source": str(source)},
        on_nonfinite=on_nonfinite,
    )


def _same_bits(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def assert_identical(got, want):
    assert _same_bits(got.xyz, want.xyz)
    assert _same_bits(got.rgb, want.rgb)
    assert _same_bits(got.normals, want.normals)
    assert got.fields.keys() == want.fields.keys()
    for name in want.fields:
        assert _same_bits(got.fields[name], want.fields[name]), name
    assert _same_bits(got.index, want.index)


@pytest.fixture
def tiny_chunks(monkeypatch):
    """Make every file "large": chunks of ``rows`` records on ``threads`` threads."""

    def use(rows: int, threads: int, size: int) -> None:
        monkeypatch.setattr(_chunks, "CHUNK_BYTES", rows * size)
        monkeypatch.setattr(_chunks, "PARALLEL_MIN_BYTES", 1)
        monkeypatch.setattr(_chunks, "READ_THREADS", threads)
        monkeypatch.setattr(_chunks, "cpu_count", lambda: threads)

    return use


@pytest.mark.parametrize("order", ["<", ">"])
@pytest.mark.parametrize(("rows_per_chunk", "threads"), [(7, 1), (7, 2), (16, 3), (37, 2), (N, 2)])
def test_chunked_read_is_bit_identical_to_a_plain_decode(
    tmp_path, rng, tiny_chunks, order, rows_per_chunk, threads
):
    rows = _rows(rng, order)
    bad = np.array([np.nan, np.inf, -np.inf])
    rows["x"][NONFINITE_ROWS[::3]] = bad[0]
    rows["y"][NONFINITE_ROWS[1::3]] = bad[1]
    rows["z"][NONFINITE_ROWS[2::3]] = bad[2]
    rows["x"][[1, 2]] = [-0.0, np.finfo(np.float32).tiny / 4]  # signed zero, subnormal
    f = _write(tmp_path / "v.ply", rows, order, faces=3)
    tiny_chunks(rows_per_chunk, threads, rows.dtype.itemsize)
    with pytest.warns(DataWarning, match=f"dropped {len(NONFINITE_ROWS)} of {N} points"):
        got = read_ply(f)
    assert_identical(got, _plain(rows, f))
    assert got.index.tolist() == sorted(set(range(N)) - set(NONFINITE_ROWS))
    assert got.meta["faces"] == 3


@pytest.mark.parametrize("order", ["<", ">"])
def test_common_layout_all_finite_keeps_every_row(tmp_path, rng, tiny_chunks, order):
    layout = [("x", "f4"), ("y", "f4"), ("z", "f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")]
    rows = _rows(rng, order, layout)
    f = _write(tmp_path / "c.ply", rows, order)
    tiny_chunks(16, 2, rows.dtype.itemsize)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = read_ply(f)
    # Nothing was dropped, so the row index is left to be built on first use.
    assert got._index is None
    assert got.is_complete
    assert_identical(got, _plain(rows, f))
    for arr in (got.xyz, got.rgb, got.index):
        assert not arr.flags.writeable


XYZ_F8 = [("x", "f8"), ("y", "f8"), ("z", "f8")]
RGB_U1 = [("red", "u1"), ("green", "u1"), ("blue", "u1")]


@pytest.mark.parametrize(
    ("layout", "order"),
    [
        (XYZ_F8 + RGB_U1, "<"),  # doubles moved as raw bytes, colours last
        (XYZ_F8 + RGB_U1, ">"),
        ([("x", "f8"), ("label", "i2"), ("y", "f8"), ("z", "f8")], "<"),  # x y z apart
        (XYZ_F8 + [("red", "u2"), ("green", "u2"), ("blue", "u2")], "<"),  # 16-bit colours
        (
            [("z", "f4"), ("x", "f4"), ("y", "f4"), ("blue", "u1"), ("green", "u1"), ("red", "u1")],
            "<",
        ),
        (
            [
                ("x", "i4"),
                ("y", "i4"),
                ("z", "i4"),
                ("red", "u1"),
                ("alpha", "u1"),
                ("green", "u1"),
                ("blue", "u1"),
            ],
            "<",
        ),
        (
            [
                ("x", "f4"),
                ("y", "f4"),
                ("z", "f4"),
                ("red", "u1"),
                ("green", "u1"),
                ("blue", "u1"),
                ("alpha", "u1"),
            ],
            ">",
        ),
    ],
)
def test_other_layouts_match_a_plain_decode(tmp_path, rng, tiny_chunks, layout, order):
    rows = _rows(rng, order, layout)
    f = _write(tmp_path / "o.ply", rows, order)
    tiny_chunks(5, 2, rows.dtype.itemsize)
    got = read_ply(f)
    want = _plain({n: rows[n] for n in rows.dtype.names if n != "alpha"}, f)
    assert_identical(got, want)


def test_float_colours_match_a_plain_decode(tmp_path, rng, tiny_chunks):
    layout = [("x", "f4"), ("y", "f4"), ("z", "f4"), ("red", "f4"), ("green", "f4"), ("blue", "f4")]
    rows = _rows(rng, "<", layout)
    for c in ("red", "green", "blue"):
        rows[c] = rng.random(N)
    f = _write(tmp_path / "fc.ply", rows, "<")
    tiny_chunks(9, 2, rows.dtype.itemsize)
    assert_identical(read_ply(f), _plain(rows, f))


@pytest.mark.parametrize("on_nonfinite", ["drop", "raise"])
def test_nonfinite_policies_on_the_chunked_path(tmp_path, rng, tiny_chunks, on_nonfinite):
    rows = _rows(rng, "<")
    rows["z"][[15, 16]] = np.nan
    f = _write(tmp_path / "n.ply", rows, "<")
    tiny_chunks(16, 2, rows.dtype.itemsize)
    if on_nonfinite == "raise":
        with pytest.raises(CorruptFileError, match=r"n\.ply: 2 of 200 points have NaN"):
            read_ply(f, on_nonfinite="raise")
        return
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = read_ply(f, on_nonfinite="drop")
    assert len(got) == N - 2
    assert 15 not in got.index and 16 not in got.index


def _records_file(tmp_path: Path, n: int) -> tuple[Path, np.dtype, np.ndarray]:
    rec = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("label", "<i4")])
    rows = np.zeros(n, rec)
    for i, c in enumerate("xyz"):
        rows[c] = np.arange(n) + i / 4
    rows["label"] = np.arange(n) * 3
    f = tmp_path / "r.bin"
    f.write_bytes(b"HEAD" + rows.tobytes())
    return f, rec, rows


@pytest.mark.parametrize("chunk_rows", [1, 3, 50, 1000])
@pytest.mark.parametrize("threads", [1, 2, 4])
def test_read_records_every_chunking(tmp_path, chunk_rows, threads):
    n = 50
    f, rec, rows = _records_file(tmp_path, n)
    xyz = np.empty((n, 3))
    label = np.empty(n, np.int32)
    copies = [(xyz, i, c) for i, c in enumerate("xyz")] + [(label, None, "label")]
    assert read_records(f, 4, rec, n, copies, xyz, chunk_rows=chunk_rows, threads=threads)
    np.testing.assert_array_equal(xyz, np.stack([rows[c] for c in "xyz"], axis=1))
    np.testing.assert_array_equal(label, rows["label"])


def test_read_records_reports_every_row_once(tmp_path):
    n = 40
    f, rec, _ = _records_file(tmp_path, n)
    xyz = np.empty((n, 3))

    class Recorder:
        def __init__(self):
            self.total = None
            self.done = 0

        def start(self, description, total):
            self.total = total
            return description

        def advance(self, task, amount):
            self.done += amount

        def finish(self, task):
            pass

    recorder = Recorder()
    with use_reporter(recorder):
        read_records(f, 4, rec, n, [(xyz, 0, "x")], xyz, chunk_rows=3, threads=2)
    assert recorder.total == n
    assert recorder.done == n


@pytest.mark.parametrize("threads", [1, 2])
def test_read_records_file_shorter_than_declared(tmp_path, threads):
    f, rec, _ = _records_file(tmp_path, 20)
    xyz = np.empty((30, 3))
    with pytest.raises(
        CorruptFileError, match=r"r\.bin: ends inside the data at byte (324|388|452)"
    ):
        read_records(f, 4, rec, 30, [(xyz, 0, "x")], xyz, chunk_rows=4, threads=threads)


def test_read_records_missing_file_is_a_read_error(tmp_path):
    xyz = np.empty((2, 3))
    rec = np.dtype([("x", "<f4")])
    with pytest.raises(ReadError, match="cannot read"):
        read_records(tmp_path / "gone.bin", 0, rec, 2, [(xyz, 0, "x")], xyz, threads=2)


@pytest.mark.parametrize(("name", "value"), [("chunk_rows", 0), ("threads", -1), ("threads", 1.5)])
def test_read_records_bad_parameters(tmp_path, name, value):
    f, rec, _ = _records_file(tmp_path, 5)
    xyz = np.empty((5, 3))
    with pytest.raises(InvalidParameterError, match=f"The '{name}' parameter must be"):
        read_records(f, 4, rec, 5, [(xyz, 0, "x")], xyz, **{name: value})


@pytest.mark.parametrize("rows_per_chunk", [7, 16, N])
def test_colour_block_is_the_same_whatever_the_chunking(tmp_path, rng, tiny_chunks, rows_per_chunk):
    # Colours are moved 4 bytes at a time into an (n, 4) block; its hidden last
    # column must still be a function of the file alone: the byte after blue
    # (here the next point's first byte), 0 after the last point.
    layout = [("x", "f4"), ("y", "f4"), ("z", "f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1")]
    rows = _rows(rng, "<", layout)
    f = _write(tmp_path / "b.ply", rows, "<")
    tiny_chunks(rows_per_chunk, 2, rows.dtype.itemsize)
    got = read_ply(f)
    block = np.asarray(got.rgb.base)
    assert block.shape == (N, 4)
    after_blue = np.append(rows.view(np.uint8).reshape(N, -1)[1:, 0], 0)
    np.testing.assert_array_equal(block[:, 3], after_blue)
