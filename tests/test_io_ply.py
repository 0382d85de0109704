"""PLY reader and writer: hand-written files with known content, round trips, errors."""

from __future__ import annotations

import os
import struct
import warnings
from pathlib import Path

import hypothesis.extra.numpy as hnp
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ontodetect import (
    CorruptFileError,
    DataWarning,
    InvalidParameterError,
    WriteError,
    point_cloud,
    read_cloud,
    write_cloud,
)
from ontodetect.io import _ply
from ontodetect.io._ply import assemble_cloud, plan_columns, read_ply, write_ply

PLY_FIELD_TYPES = [
    np.int8,
    np.uint8,
    np.int16,
    np.uint16,
    np.int32,
    np.uint32,
    np.float32,
    np.float64,
]
FIELD_NAMES = ["label", "instance", "intensity", "score", "scalar_curvature"]
BOUNDED = st.floats(-1e6, 1e6, allow_nan=False)
ANY_FINITE = st.floats(allow_nan=False, allow_infinity=False)


def _header(fmt: str, *lines: str) -> bytes:
    return ("\n".join(["ply", f"format {fmt} 1.0", *lines, "end_header"]) + "\n").encode()


@st.composite
def clouds(draw, field_types=PLY_FIELD_TYPES, coords=ANY_FINITE, max_points=30):
    n = draw(st.integers(1, max_points))
    xyz = draw(hnp.arrays(np.float64, (n, 3), elements=coords))
    rgb = draw(st.none() | hnp.arrays(np.uint8, (n, 3)))
    normals = draw(st.none() | hnp.arrays(np.float64, (n, 3), elements=coords))
    names = draw(st.lists(st.sampled_from(FIELD_NAMES), unique=True, max_size=3))
    fields = {name: draw(hnp.arrays(draw(st.sampled_from(field_types)), n)) for name in names}
    return point_cloud(xyz, rgb=rgb, normals=normals, fields=fields)


def assert_same_cloud(got, want, coord_type=np.float64):
    """Points and normals as stored in ``coord_type``; colours and fields exactly."""
    np.testing.assert_array_equal(got.xyz, want.xyz.astype(coord_type).astype(np.float64))
    if want.rgb is None:
        assert got.rgb is None
    else:
        np.testing.assert_array_equal(got.rgb, want.rgb)
    if want.normals is None:
        assert got.normals is None
    else:
        np.testing.assert_array_equal(
            got.normals, want.normals.astype(coord_type).astype(np.float64)
        )
    assert set(got.fields) == set(want.fields)
    for name, values in want.fields.items():
        assert got.fields[name].dtype == values.dtype, name
        np.testing.assert_array_equal(got.fields[name], values)
    np.testing.assert_array_equal(got.index, np.arange(len(want)))


# ---------------------------------------------------------------------------------
# Known answers
# ---------------------------------------------------------------------------------
def test_ascii_mesh_with_extra_properties_and_faces(tmp_path):
    f = tmp_path / "mesh.ply"
    f.write_bytes(
        _header(
            "ascii",
            "comment made by hand",
            "obj_info scanner v1",
            "element vertex 4",
            "property float x",
            "property float y",
            "property double z",
            "property uchar red",
            "property uchar green",
            "property uchar blue",
            "property uchar alpha",
            "property int label",
            "property float intensity",
            "element face 2",
            "property list uchar int vertex_indices",
        )
        + b"0 0 0 255 0 0 255 3 0.5\n1 0 0 0 255 0 255 3 0.25\n"
        b"0 1 0.5 0 0 255 128 -7 1e-3\n1 1 2 10 20 30 0 9 -2\n3 0 1 2\n4 0 1 2 3\n"
    )
    c = read_cloud(f)
    np.testing.assert_array_equal(c.xyz, [[0, 0, 0], [1, 0, 0], [0, 1, 0.5], [1, 1, 2]])
    np.testing.assert_array_equal(c.rgb, [[255, 0, 0], [0, 255, 0], [0, 0, 255], [10, 20, 30]])
    assert set(c.fields) == {"label", "intensity"}
    assert c.fields["label"].dtype == np.int32
    assert c.fields["label"].tolist() == [3, 3, -7, 9]
    assert c.fields["intensity"].dtype == np.float32
    np.testing.assert_array_equal(c.fields["intensity"], np.float32([0.5, 0.25, 1e-3, -2]))
    assert c.meta["faces"] == 2
    assert c.meta["ply_format"] == "ascii"
    assert c.meta["comments"] == ["made by hand", "scanner v1"]
    assert c.meta["format"] == "ply"


def test_big_endian_binary_with_mixed_types(tmp_path):
    f = tmp_path / "be.ply"
    rows = [(1.5, -2.0, 3, 65535, 0.25), (-1e10, 7.5, -4, 2, 0.0)]
    body = b"".join(struct.pack(">dfhHf", *r) for r in rows)
    f.write_bytes(
        _header(
            "binary_big_endian",
            "element vertex 2",
            "property double x",
            "property float y",
            "property short z",
            "property ushort label",
            "property float nx",
        )
        + body
    )
    c = read_ply(f)
    np.testing.assert_array_equal(c.xyz, [[1.5, -2.0, 3], [-1e10, 7.5, -4]])
    assert c.fields["label"].dtype == np.uint16
    assert c.fields["label"].tolist() == [65535, 2]
    # nx without ny, nz is not a set of normals; "nx" is reserved, so it is renamed.
    assert c.normals is None
    assert c.fields["nx_field"].tolist() == [0.25, 0.0]
    assert c.meta["ply_format"] == "binary_big_endian"


def test_property_order_colour_spellings_and_normals(tmp_path):
    f = tmp_path / "order.ply"
    body = struct.pack("<3B3f3f", 1, 2, 3, 0.5, 0.25, 0.125, 9, 8, 7)
    f.write_bytes(
        _header(
            "binary_little_endian",
            "element vertex 1",
            "property uchar diffuse_red",
            "property uchar diffuse_green",
            "property uchar diffuse_blue",
            "property float nx",
            "property float ny",
            "property float nz",
            "property float z",
            "property float y",
            "property float x",
        )
        + body
    )
    c = read_ply(f)
    np.testing.assert_array_equal(c.xyz, [[7, 8, 9]])
    np.testing.assert_array_equal(c.rgb, [[1, 2, 3]])
    np.testing.assert_array_equal(c.normals, [[0.5, 0.25, 0.125]])


@pytest.mark.parametrize(
    ("decl", "values", "expected"),
    [
        ("float", (1.0, 0.5, 0.0), [255, 128, 0]),  # floats 0..1
        ("ushort", (65535, 32768, 256), [255, 128, 1]),  # 16-bit colours keep the high byte
    ],
)
def test_colour_types(tmp_path, decl, values, expected):
    f = tmp_path / "c.ply"
    code = "f" if decl == "float" else "H"
    f.write_bytes(
        _header(
            "binary_little_endian",
            "element vertex 1",
            "property float x",
            "property float y",
            "property float z",
            f"property {decl} r",
            f"property {decl} g",
            f"property {decl} b",
        )
        + struct.pack(f"<3f3{code}", 0, 0, 0, *values)
    )
    assert read_ply(f).rgb.tolist() == [expected]


def test_reserved_property_names_are_renamed(tmp_path):
    f = tmp_path / "r.ply"
    f.write_bytes(
        _header(
            "ascii",
            "element vertex 2",
            "property float x",
            "property float y",
            "property float z",
            "property int index",
            "property uchar red",
        )
        + b"0 0 0 5 1\n1 1 1 6 2\n"
    )
    c = read_ply(f)
    assert c.rgb is None
    assert c.fields["index_field"].tolist() == [5, 6]
    assert c.fields["red_field"].tolist() == [1, 2]
    assert c.index.tolist() == [0, 1]


def test_elements_before_the_vertices_are_skipped(tmp_path):
    # Variable-length lists first (the row-by-row path), then uniform ones (one strided test).
    head = _header(
        "binary_little_endian",
        "element material 3",
        "property uchar id",
        "property list uchar float params",
        "element camera 2",
        "property list int double pose",
        "property short tag",
        "element vertex 2",
        "property float x",
        "property float y",
        "property float z",
        "element face 1",
        "property list uchar int vertex_indices",
    )
    material = (
        struct.pack("<BB", 1, 0) + struct.pack("<BB2f", 2, 2, 1, 2) + struct.pack("<BB1f", 3, 1, 5)
    )
    camera = b"".join(struct.pack("<i3dh", 3, 1, 2, 3, k) for k in range(2))
    vertices = struct.pack("<6f", 1, 2, 3, 4, 5, 6)
    f = tmp_path / "pre.ply"
    f.write_bytes(head + material + camera + vertices + struct.pack("<B3i", 3, 0, 1, 0))
    c = read_ply(f)
    np.testing.assert_array_equal(c.xyz, [[1, 2, 3], [4, 5, 6]])
    assert c.meta["faces"] == 1

    g = tmp_path / "pre_ascii.ply"
    g.write_bytes(
        _header(
            "ascii",
            "element material 2",
            "property list uchar float params",
            "element vertex 1",
            "property float x",
            "property float y",
            "property float z",
        )
        + b"2 1 2\n0\n7 8 9\n"
    )
    np.testing.assert_array_equal(read_ply(g).xyz, [[7, 8, 9]])


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_vertex_element_with_a_list_property(tmp_path, fmt):
    head = _header(
        fmt,
        "element vertex 2",
        "property float x",
        "property list uchar int ids",
        "property float y",
        "property float z",
        "property uchar label",
    )
    if fmt == "ascii":
        body = b"1 2 10 11 2 3 4\n4 0 5 6 9\n"
    else:
        body = struct.pack("<fB2iffB", 1, 2, 10, 11, 2, 3, 4) + struct.pack("<fBffB", 4, 0, 5, 6, 9)
    f = tmp_path / "vl.ply"
    f.write_bytes(head + body)
    c = read_ply(f)
    np.testing.assert_array_equal(c.xyz, [[1, 2, 3], [4, 5, 6]])
    assert c.fields["label"].tolist() == [4, 9]
    assert c.fields["label"].dtype == np.uint8


def test_crlf_header_and_blank_header_lines(tmp_path):
    f = tmp_path / "crlf.ply"
    f.write_bytes(
        b"ply\r\nformat ascii 1.0\r\n\r\nelement vertex 1\r\nproperty float x\r\n"
        b"property float y\r\nproperty float z\r\nend_header\r\n1 2 3\r\n"
    )
    np.testing.assert_array_equal(read_ply(f).xyz, [[1, 2, 3]])


def test_nonfinite_points_dropped_with_a_counted_warning(tmp_path):
    f = tmp_path / "nan.ply"
    xyz = np.array([[0, 0, 0], [np.nan, 0, 0], [1, 1, 1], [0, np.inf, 0]], np.float32)
    f.write_bytes(
        _header(
            "binary_little_endian",
            "element vertex 4",
            "property float x",
            "property float y",
            "property float z",
        )
        + xyz.tobytes()
    )
    with pytest.warns(DataWarning, match=r"nan\.ply: dropped 2 of 4 points"):
        c = read_ply(f)
    assert c.index.tolist() == [0, 2]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_ply(f, on_nonfinite="drop").index.tolist() == [0, 2]
    with pytest.raises(CorruptFileError, match="2 of 4 points have NaN"):
        read_ply(f, on_nonfinite="raise")
    with pytest.raises(InvalidParameterError, match="on_nonfinite"):
        read_ply(f, on_nonfinite="ignore")


def test_signalling_nan_float32_reads_without_runtime_warning(tmp_path):
    f = tmp_path / "snan.ply"
    bits = np.array([[0x7F800001, 0, 0], [0, 0, 0]], dtype="<u4")  # a signalling NaN
    f.write_bytes(
        _header(
            "binary_little_endian",
            "element vertex 2",
            "property float x",
            "property float y",
            "property float z",
        )
        + bits.tobytes()
    )
    assert read_ply(f, on_nonfinite="drop").index.tolist() == [1]


def test_matches_real_mesh_layout_read_by_open3d(tmp_path, rng):
    # The layout of a ScanNet mesh: float xyz, uchar rgba, then triangle faces.
    n = 500
    xyz = rng.uniform(-5, 5, (n, 3)).astype(np.float32)
    rgba = rng.integers(0, 256, (n, 4), dtype=np.uint8)
    vert = np.empty(n, dtype=[("p", "<f4", 3), ("c", "u1", 4)])
    vert["p"], vert["c"] = xyz, rgba
    faces = np.empty(300, dtype=[("k", "u1"), ("v", "<i4", 3)])
    faces["k"], faces["v"] = 3, rng.integers(0, n, (300, 3))
    f = tmp_path / "scene_vh_clean_2.ply"
    f.write_bytes(
        _header(
            "binary_little_endian",
            "comment VCGLIB generated",
            f"element vertex {n}",
            "property float x",
            "property float y",
            "property float z",
            "property uchar red",
            "property uchar green",
            "property uchar blue",
            "property uchar alpha",
            "element face 300",
            "property list uchar int vertex_indices",
        )
        + vert.tobytes()
        + faces.tobytes()
    )
    c = read_ply(f)
    np.testing.assert_array_equal(c.xyz, xyz.astype(np.float64))
    np.testing.assert_array_equal(c.rgb, rgba[:, :3])
    assert c.fields == {}
    assert c.meta["faces"] == 300
    import open3d as o3d

    ref = o3d.io.read_point_cloud(str(f))
    np.testing.assert_array_equal(np.asarray(ref.points), c.xyz)


def test_fast_assembly_equals_point_cloud(rng):
    xyz = rng.normal(size=(50, 3))
    rgb = rng.integers(0, 256, (50, 3), dtype=np.uint8)
    fields = {"label": rng.integers(0, 9, 50)}
    fast = assemble_cloud(
        Path("x.ply"),
        xyz.copy(),
        rgb=rgb.copy(),
        fields={k: v.copy() for k, v in fields.items()},
    )
    slow = point_cloud(xyz, rgb=rgb, fields=fields, meta={"source": "x.ply"})
    assert_same_cloud(fast, slow)
    assert dict(fast.meta) == dict(slow.meta)
    for arr in (fast.xyz, fast.rgb, fast.index, fast.fields["label"]):
        assert not arr.flags.writeable


def test_plan_columns_aliases():
    p = plan_columns(["X", "Y", "Z", "r", "g", "b", "a", "normal_x", "normal_y", "normal_z"])
    assert p.xyz == ("X", "Y", "Z")
    assert p.rgb == ("r", "g", "b")
    assert p.normals == ("normal_x", "normal_y", "normal_z")
    assert p.ignored == ("a",)
    assert dict(p.fields) == {}


# ---------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------
XYZ = ("property float x", "property float y", "property float z")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", r"e\.ply: is empty"),
        (b"PLY\nformat ascii 1.0\n", "does not start with the line 'ply'"),
        (b"\x00\x01garbage" * 10, "does not start with the line 'ply'"),
        (b"ply\nformat ascii 1.0\nelement vertex 1\n", "no 'end_header' line"),
        (
            _header("binary_middle_endian", "element vertex 1", *XYZ),
            "header line 2: unknown format 'binary_middle_endian 1.0'",
        ),
        (
            _header("ascii", "element vertex 1", *XYZ).replace(b"format ascii 1.0\n", b""),
            "no 'format' line",
        ),
        (
            _header("ascii", "property float x", "element vertex 1"),
            "header line 3: 'property' before any 'element'",
        ),
        (_header("ascii", "element vertex 1", "property float128 x"), "header line 4"),
        (
            _header("ascii", "element vertex 1", "property float x", "property float x"),
            "property 'x' is declared twice",
        ),
        (_header("ascii", "element vertex -3", *XYZ), "count should be a whole number"),
        (
            _header("ascii", "element vertex 1", *XYZ, "colour red"),
            "unknown header keyword 'colour'",
        ),
        (
            _header("ascii", "element vertex 1", "property float x", "property float y"),
            "element 'vertex' has no z property",
        ),
        (
            _header("ascii", "element face 1", "property list uchar int vertex_indices")
            + b"3 0 1 2\n",
            "has no 'vertex' element",
        ),
        (_header("ascii", "element vertex 0", *XYZ), "contains no points"),
        (
            _header("ascii", "element vertex 3", *XYZ) + b"1 2 3\n4 5 6\n",
            "the header declares 3 vertices but the file holds only 2 vertex lines",
        ),
        (
            _header("ascii", "element vertex 2", *XYZ) + b"1 2 3\n4 five 6\n",
            r"line 9: vertex property 'y' should be a number, found 'five'",
        ),
        (
            _header("ascii", "element vertex 2", *XYZ) + b"1 2 3\n4 5\n",
            "line 9: a vertex line needs 3 values, found 2",
        ),
        (
            _header("ascii", "element vertex 1", "property uchar x", *XYZ[1:]) + b"300 1 1\n",
            "should be an integer fitting uint8, found '300'",
        ),
        (
            _header("binary_little_endian", "element vertex 100", *XYZ) + b"\0" * 600,
            r"truncated: the header declares 100 vertices \(1200 bytes from byte \d+\) but the "
            r"file holds only 600 bytes",
        ),
        (
            _header("binary_little_endian", "element vertex 1000000000000", *XYZ) + b"\0" * 12,
            "truncated: the header declares 1000000000000 vertices",
        ),
        (_header("ascii", "element vertex 1000000000000", *XYZ) + b"1 2 3\n", "truncated"),
        (
            _header(
                "binary_little_endian",
                "element face 1000000000",
                "property list uchar int v",
                "element vertex 1",
                *XYZ,
            )
            + b"\0" * 64,
            "element 'face' declares 1000000000 rows, more than the",
        ),
    ],
)
def test_errors_name_the_file_and_the_problem(tmp_path, content, message):
    f = tmp_path / "e.ply"
    f.write_bytes(content)
    with pytest.raises(CorruptFileError, match=message) as info:
        read_cloud(f)
    assert str(info.value).startswith(str(f))


def test_list_rows_running_past_the_end(tmp_path):
    head = _header(
        "binary_little_endian",
        "element face 2",
        "property list uchar int v",
        "element vertex 1",
        *XYZ,
    )
    f = tmp_path / "l.ply"
    f.write_bytes(head + struct.pack("<B3i", 3, 0, 1, 2) + struct.pack("<B", 200) + b"\0" * 20)
    with pytest.raises(CorruptFileError, match=r"ends inside element 'face' \(row 1 of 2\)"):
        read_ply(f)


# ---------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------
def test_writer_header_types(tmp_path, rng):
    cloud = point_cloud(
        rng.normal(size=(3, 3)),
        rgb=np.zeros((3, 3), np.uint8),
        normals=np.eye(3),
        fields={
            "label": np.array([1, 2, 3], np.int64),
            "score": np.array([0.5, 1, 2], np.float32),
            "flag": np.array([True, False, True]),
            "feat": np.arange(6, dtype=np.int16).reshape(3, 2),
        },
    )
    f = write_ply(tmp_path / "w.ply", cloud)
    head = f.read_bytes().split(b"end_header\n")[0].decode()
    assert "format binary_little_endian 1.0" in head
    for line in [
        "property double x",
        "property uchar red",
        "property double nx",
        "property int label",
        "property float score",
        "property uchar flag",
        "property short feat_0",
        "property short feat_1",
    ]:
        assert line in head
    c = read_ply(f)
    assert c.fields["label"].dtype == np.int32
    assert c.fields["label"].tolist() == [1, 2, 3]
    assert c.fields["feat_1"].tolist() == [1, 3, 5]
    assert c.fields["flag"].tolist() == [1, 0, 1]
    g = write_ply(tmp_path / "w32.ply", cloud, dtype="float32", ascii=True)
    text = g.read_text()
    assert "format ascii 1.0" in text and "property float x" in text
    np.testing.assert_array_equal(read_ply(g).xyz, cloud.xyz.astype(np.float32))


def test_writer_refusals(tmp_path):
    with pytest.raises(WriteError, match="outside the int32 range"):
        write_ply(
            tmp_path / "a.ply", point_cloud(np.zeros((1, 3)), fields={"big": np.array([2**40])})
        )
    with pytest.raises(InvalidParameterError, match="'dtype' parameter must be 'float32' or"):
        write_ply(tmp_path / "a.ply", point_cloud(np.zeros((1, 3))), dtype="int8")
    with pytest.raises(WriteError, match="names must be non-empty and without spaces"):
        write_ply(tmp_path / "a.ply", point_cloud(np.zeros((1, 3)), fields={"a b": [1]}))
    with pytest.raises(WriteError, match="expected a PointCloud"):
        write_ply(tmp_path / "a.ply", np.zeros((1, 3)))
    assert os.listdir(tmp_path) == []


def test_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, rng, monkeypatch):
    target = tmp_path / "keep.ply"
    target.write_bytes(b"old content")

    def broken(fh, columns, n, label):
        fh.write(b"partial")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(_ply, "write_rows", broken)
    with pytest.raises(WriteError, match=r"keep\.ply: cannot write \(No space left on device\)"):
        write_cloud(target, point_cloud(rng.normal(size=(10, 3))))
    assert target.read_bytes() == b"old content"
    assert os.listdir(tmp_path) == ["keep.ply"]


# ---------------------------------------------------------------------------------
# Round trips
# ---------------------------------------------------------------------------------
@given(cloud=clouds())
def test_roundtrip_binary_float64_is_exact(tmp_path_factory, cloud):
    f = tmp_path_factory.mktemp("ply") / "c.ply"
    assert_same_cloud(read_cloud(write_cloud(f, cloud)), cloud)


def float32_type(cloud) -> type:
    """What ``dtype="float32"`` stores coordinates and normals as: float32 when that moves
    no value by more than 10 µm, else float64 (map coordinates keep every digit)."""
    arrays = [cloud.xyz] if cloud.normals is None else [cloud.xyz, cloud.normals]
    moved = max(float(np.abs(a.astype(np.float32) - a).max()) for a in arrays)
    return np.float32 if moved <= 1e-5 else np.float64


@given(cloud=clouds(coords=BOUNDED))
def test_roundtrip_binary_float32(tmp_path_factory, cloud):
    f = tmp_path_factory.mktemp("ply") / "c.ply"
    got = read_cloud(write_cloud(f, cloud, dtype="float32"))
    assert_same_cloud(got, cloud, float32_type(cloud))


@given(cloud=clouds())
def test_roundtrip_ascii_float64_is_exact(tmp_path_factory, cloud):
    f = tmp_path_factory.mktemp("ply") / "c.ply"
    assert_same_cloud(read_cloud(write_cloud(f, cloud, ascii=True)), cloud)


@given(cloud=clouds(coords=BOUNDED))
def test_roundtrip_ascii_float32(tmp_path_factory, cloud):
    f = tmp_path_factory.mktemp("ply") / "c.ply"
    got = read_cloud(write_cloud(f, cloud, ascii=True, dtype="float32"))
    assert_same_cloud(got, cloud, float32_type(cloud))
