"""PCD reader and writer: hand-built files of every encoding, round trips, errors."""

from __future__ import annotations

import os
import struct
import warnings

import hypothesis.extra.numpy as hnp
import lzf
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
from ontodetect.cloud import pixel_grid
from ontodetect.io import _pcd
from ontodetect.io._pcd import read_pcd, write_pcd

PCD_FIELD_TYPES = [
    np.int8,
    np.uint8,
    np.int16,
    np.uint16,
    np.int32,
    np.uint32,
    np.int64,
    np.uint64,
    np.float32,
    np.float64,
]
FIELD_NAMES = ["label", "instance", "intensity", "score", "scalar_curvature"]
BOUNDED = st.floats(-1e6, 1e6, allow_nan=False)


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


def _header(
    fields,
    sizes,
    types,
    width,
    height=1,
    data="ascii",
    counts=None,
    points=None,
    viewpoint="0 0 0 1 0 0 0",
):
    counts = counts or ["1"] * len(fields.split())
    return "\n".join(
        [
            "# .PCD v0.7 - Point Cloud Data file format",
            "VERSION 0.7",
            f"FIELDS {fields}",
            f"SIZE {sizes}",
            f"TYPE {types}",
            f"COUNT {' '.join(counts)}",
            f"WIDTH {width}",
            f"HEIGHT {height}",
            f"VIEWPOINT {viewpoint}",
            f"POINTS {width * height if points is None else points}",
            f"DATA {data}",
            "",
        ]
    ).encode()


def _pack(r, g, b, a=0):
    return (a << 24) | (r << 16) | (g << 8) | b


@st.composite
def clouds(draw, coords=BOUNDED, max_points=30):
    n = draw(st.integers(1, max_points))
    xyz = draw(hnp.arrays(np.float64, (n, 3), elements=coords))
    rgb = draw(st.none() | hnp.arrays(np.uint8, (n, 3)))
    normals = draw(st.none() | hnp.arrays(np.float64, (n, 3), elements=coords))
    names = draw(st.lists(st.sampled_from(FIELD_NAMES), unique=True, max_size=3))
    fields = {}
    for name in names:
        shape = (n,) if draw(st.booleans()) else (n, draw(st.integers(2, 4)))
        fields[name] = draw(hnp.arrays(draw(st.sampled_from(PCD_FIELD_TYPES)), shape))
    return point_cloud(xyz, rgb=rgb, normals=normals, fields=fields)


# ---------------------------------------------------------------------------------
# Known answers
# ---------------------------------------------------------------------------------
def test_organized_ascii_with_nans_keeps_grid_positions(tmp_path):
    f = tmp_path / "grid.pcd"
    rows = ["nan nan nan 0", "1 0 2 1", "nan nan nan 2", "0 1 2 3", "1 1 2 4", "nan 0 0 5"]
    f.write_bytes(
        _header("x y z label", "4 4 4 2", "F F F U", width=3, height=2, viewpoint="1 2 3 1 0 0 0")
        + "\n".join(rows).encode()
        + b"\n"
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # organized clouds drop NaN points silently
        c = read_cloud(f)
    assert c.index.tolist() == [1, 3, 4]
    np.testing.assert_array_equal(c.xyz, [[1, 0, 2], [0, 1, 2], [1, 1, 2]])
    assert c.fields["label"].dtype == np.uint16
    assert c.fields["label"].tolist() == [1, 3, 4]
    assert c.meta["width"] == 3 and c.meta["height"] == 2 and c.meta["organized"] is True
    assert c.meta["viewpoint"] == [1, 2, 3, 1, 0, 0, 0]
    assert c.meta["pcd_data"] == "ascii"
    with pytest.warns(DataWarning, match="dropped 3 of 6 points"):
        read_pcd(f, on_nonfinite="warn")


def test_unorganized_nan_points_warn(tmp_path):
    f = tmp_path / "u.pcd"
    f.write_bytes(_header("x y z", "4 4 4", "F F F", width=2) + b"nan 0 0\n1 2 3\n")
    with pytest.warns(DataWarning, match="dropped 1 of 2"):
        c = read_pcd(f)
    assert c.index.tolist() == [1]
    assert c.meta["organized"] is False


@pytest.mark.parametrize("kind", ["U", "F"])
def test_binary_packed_rgb_uint32_and_float(tmp_path, kind):
    colours = [(255, 0, 0, 255), (0, 128, 255, 0), (1, 2, 3, 255)]
    rec = np.zeros(3, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "<u4")])
    rec["x"] = [1, 2, 3]
    rec["rgb"] = [_pack(*c) for c in colours]
    f = tmp_path / "rgb.pcd"
    f.write_bytes(
        _header("x y z rgb", "4 4 4 4", f"F F F {kind}", width=3, data="binary") + rec.tobytes()
    )
    c = read_pcd(f)
    np.testing.assert_array_equal(c.rgb, [c[:3] for c in colours])
    np.testing.assert_array_equal(c.xyz[:, 0], [1, 2, 3])
    assert c.fields == {}


def test_packed_colour_field_name_is_case_insensitive(tmp_path):
    f = tmp_path / "upper.pcd"
    f.write_bytes(
        _header("x y z RGB", "4 4 4 4", "F F F U", width=1, data="binary")
        + np.float32([1, 2, 3]).tobytes()
        + np.uint32([_pack(255, 128, 1)]).tobytes()
    )
    c = read_pcd(f)
    assert c.rgb.tolist() == [[255, 128, 1]]
    assert c.fields == {}


def test_ascii_packed_rgb_as_pcl_integer_and_as_float(tmp_path):
    # PCL prints a float rgb field as the integer it holds; others print the float.
    as_int = _pack(10, 20, 30, 255)
    as_float = np.array([_pack(40, 50, 60)], "<u4").view("<f4")[0]
    f = tmp_path / "a.pcd"
    f.write_bytes(
        _header("x y z rgb", "4 4 4 4", "F F F F", width=1) + f"0 0 0 {as_int}\n".encode()
    )
    assert read_pcd(f).rgb.tolist() == [[10, 20, 30]]
    f.write_bytes(
        _header("x y z rgb", "4 4 4 4", "F F F F", width=1)
        + f"0 0 0 {float(as_float)!r}\n".encode()
    )
    assert read_pcd(f).rgb.tolist() == [[40, 50, 60]]
    f.write_bytes(
        _header("x y z rgba", "4 4 4 4", "F F F U", width=1)
        + f"0 0 0 {_pack(7, 8, 9, 200)}\n".encode()
    )
    assert read_pcd(f).rgb.tolist() == [[7, 8, 9]]


def test_binary_compressed_built_by_hand(tmp_path):
    """Column-major fields behind two uint32 sizes, as in PCL's writer."""
    n = 4
    x = np.float32([0, 1, 2, 3])
    y = np.float32([4, 5, 6, 7])
    z = np.float32([np.nan, 1, 1, 1])
    rgb = np.array([_pack(1, 2, 3), _pack(4, 5, 6), _pack(7, 8, 9), _pack(250, 251, 252)], "<u4")
    hist = np.arange(n * 2, dtype="<i2").reshape(n, 2)  # COUNT 2: each point's pair together
    raw = x.tobytes() + y.tobytes() + z.tobytes() + rgb.tobytes() + hist.tobytes()
    packed = lzf.compress(raw, len(raw) + 64)
    f = tmp_path / "c.pcd"
    f.write_bytes(
        _header(
            "x y z rgb hist",
            "4 4 4 4 2",
            "F F F F I",
            width=2,
            height=2,
            counts=["1", "1", "1", "1", "2"],
            data="binary_compressed",
        )
        + struct.pack("<II", len(packed), len(raw))
        + packed
    )
    c = read_pcd(f)
    assert c.index.tolist() == [1, 2, 3]
    np.testing.assert_array_equal(c.xyz, [[1, 5, 1], [2, 6, 1], [3, 7, 1]])
    assert c.rgb.tolist() == [[4, 5, 6], [7, 8, 9], [250, 251, 252]]
    assert c.fields["hist"].dtype == np.int16
    assert c.fields["hist"].tolist() == [[2, 3], [4, 5], [6, 7]]
    assert c.meta["pcd_data"] == "binary_compressed"


def test_binary_compressed_by_our_writer_matches_hand_layout(tmp_path, rng):
    cloud = point_cloud(
        rng.normal(size=(20, 3)),
        rgb=rng.integers(0, 256, (20, 3)),
        fields={"label": rng.integers(0, 9, 20).astype(np.uint32)},
    )
    f = write_pcd(tmp_path / "w.pcd", cloud, data="binary_compressed")
    data = f.read_bytes()
    body = data[data.index(b"DATA binary_compressed\n") + len(b"DATA binary_compressed\n") :]
    size, expanded = struct.unpack("<II", body[:8])
    raw = lzf.decompress(body[8 : 8 + size], expanded)
    assert expanded == 20 * 5 * 4
    np.testing.assert_array_equal(
        np.frombuffer(raw, "<f4", 20, 0), cloud.xyz[:, 0].astype(np.float32)
    )
    packed = np.frombuffer(raw, "<u4", 20, 3 * 80)
    np.testing.assert_array_equal((packed >> 16) & 255, cloud.rgb[:, 0])
    np.testing.assert_array_equal(np.frombuffer(raw, "<u4", 20, 4 * 80), cloud.fields["label"])
    assert_same_cloud(read_pcd(f), cloud, np.float32)


def test_padding_fields_and_old_columns_keyword(tmp_path):
    rec = np.zeros(2, dtype=[("x", "<f4"), ("pad", "V4"), ("y", "<f4"), ("z", "<f4")])
    rec["x"], rec["y"], rec["z"] = [1, 2], [3, 4], [5, 6]
    f = tmp_path / "p.pcd"
    head = _header(
        "x _ y z", "4 1 4 4", "F U F F", width=2, data="binary", counts=["1", "4", "1", "1"]
    ).replace(b"FIELDS", b"COLUMNS")
    f.write_bytes(head + rec.tobytes())
    c = read_pcd(f)
    np.testing.assert_array_equal(c.xyz, [[1, 3, 5], [2, 4, 6]])
    assert c.fields == {}


def test_normals_and_curvature(tmp_path):
    f = tmp_path / "n.pcd"
    f.write_bytes(
        _header(
            "x y z normal_x normal_y normal_z curvature", "4 4 4 4 4 4 8", "F F F F F F F", width=1
        )
        + b"1 2 3 0 0 1 0.25\n"
    )
    c = read_pcd(f)
    np.testing.assert_array_equal(c.normals, [[0, 0, 1]])
    assert c.fields["curvature"].dtype == np.float64


def test_writer_keeps_organized_grid_and_viewpoint(tmp_path, rng):
    cloud = point_cloud(
        rng.normal(size=(6, 3)), meta={"width": 3, "height": 2, "viewpoint": [1, 0, 0, 1, 0, 0, 0]}
    )
    c = read_pcd(write_pcd(tmp_path / "o.pcd", cloud))
    assert (c.meta["width"], c.meta["height"], c.meta["organized"]) == (3, 2, True)
    assert c.meta["viewpoint"] == [1, 0, 0, 1, 0, 0, 0]
    # After dropping points the grid no longer fits: written unorganized.
    c = read_pcd(write_pcd(tmp_path / "u.pcd", cloud.select([0, 1, 2])))
    assert (c.meta["width"], c.meta["height"]) == (3, 1)


def _header_line(path, key):
    head = path.read_bytes().split(b"\nDATA ")[0].decode()
    return next(line for line in head.splitlines() if line.startswith(key + " "))


@pytest.mark.parametrize("data", ["binary", "ascii", "binary_compressed"])
def test_map_coordinates_are_written_as_float64(tmp_path, rng, data):
    """UTM-like coordinates: float32 steps there are 3 to 25 cm; float64 keeps them."""
    xyz = rng.random((40, 3)) * 5 + [500000.123, 4000000.456, 10.0]
    normals = rng.normal(size=(40, 3))
    cloud = point_cloud(xyz, rgb=rng.integers(0, 256, (40, 3)), normals=normals)
    f = write_cloud(tmp_path / "utm.pcd", cloud, data=data)
    assert _header_line(f, "SIZE") == "SIZE 8 8 8 4 8 8 8"
    assert _header_line(f, "TYPE") == "TYPE F F F F F F F"
    got = read_cloud(f)
    np.testing.assert_allclose(got.xyz, xyz, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(got.xyz, xyz)  # in fact exactly
    np.testing.assert_array_equal(got.normals, cloud.normals)
    np.testing.assert_array_equal(got.rgb, cloud.rgb)


def test_room_coordinates_stay_float32(tmp_path, rng):
    # float32 moves these by at most 2.4e-7 m: written as before, byte for byte.
    cloud = point_cloud(rng.uniform(-4, 4, (30, 3)), normals=rng.normal(size=(30, 3)))
    f = write_pcd(tmp_path / "room.pcd", cloud)
    assert _header_line(f, "SIZE") == "SIZE 4 4 4 4 4 4"
    assert f.read_bytes() == write_pcd(tmp_path / "f32.pcd", cloud, dtype="float32").read_bytes()
    # Far from the origin but on float32's grid (a cloud read from a float32 file): float32.
    on_grid = point_cloud([[500000.125, 4000000.5, 10.0], [500001.0, 4000000.0, 10.25]])
    f = write_pcd(tmp_path / "grid.pcd", on_grid)
    assert _header_line(f, "SIZE") == "SIZE 4 4 4"
    np.testing.assert_array_equal(read_pcd(f).xyz, on_grid.xyz)
    # An explicit dtype is obeyed.
    f = write_pcd(tmp_path / "f64.pcd", cloud, dtype="float64")
    assert _header_line(f, "SIZE") == "SIZE 8 8 8 8 8 8"


def _frame(rng, width=20, height=15):
    """A depth frame as a camera gives it: (width * height, 3) float32 points in pixel
    order, NaN at the pixels with no depth (a block and some scattered ones)."""
    col, row = np.meshgrid(np.arange(width), np.arange(height))
    depth = 1.5 + 0.01 * rng.random((height, width))
    xyz = np.stack([(col - 9.5) * depth / 50, (row - 7) * depth / 50, depth], -1).reshape(-1, 3)
    missing = np.zeros((height, width), bool)
    missing[2:5, 3:8] = True
    missing.flat[rng.choice(width * height, 20, replace=False)] = True
    xyz[missing.reshape(-1)] = np.nan
    return xyz.astype(np.float32), np.flatnonzero(~missing.reshape(-1))


@pytest.mark.parametrize("data", ["binary", "ascii", "binary_compressed"])
def test_organized_frame_keeps_its_grid_through_read_and_write(tmp_path, rng, data):
    width, height = 20, 15
    xyz, kept = _frame(rng, width, height)
    rgb = rng.integers(0, 256, (width * height, 3))
    rec = np.zeros(width * height, [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("rgb", "<u4")])
    rec["x"], rec["y"], rec["z"] = xyz.T
    rec["rgb"] = _pack(rgb[:, 0], rgb[:, 1], rgb[:, 2])
    f = tmp_path / "frame.pcd"
    head = _header("x y z rgb", "4 4 4 4", "F F F U", width, height, "binary")
    f.write_bytes(head + rec.tobytes())
    first = read_cloud(f)
    assert first.index.tolist() == kept.tolist()
    frame = first.with_fields(label=np.arange(len(first), dtype=np.uint16))
    again = read_cloud(write_cloud(tmp_path / "again.pcd", frame, data=data))
    assert _header_line(tmp_path / "again.pcd", "WIDTH") == "WIDTH 20"
    assert _header_line(tmp_path / "again.pcd", "HEIGHT") == "HEIGHT 15"
    assert _header_line(tmp_path / "again.pcd", "POINTS") == "POINTS 300"
    assert (again.meta["width"], again.meta["height"], again.meta["organized"]) == (20, 15, True)
    assert again.index.tolist() == kept.tolist()
    pixels, w, h = pixel_grid(again)
    assert (pixels.tolist(), w, h) == (kept.tolist(), width, height)
    np.testing.assert_array_equal(again.xyz, xyz[kept].astype(np.float64))
    np.testing.assert_array_equal(again.rgb, rgb[kept])
    np.testing.assert_array_equal(again.fields["label"], np.arange(len(kept)))
    assert again.meta["viewpoint"] == [0, 0, 0, 1, 0, 0, 0]


def test_organized_frame_in_any_point_order_is_written_in_pixel_order(tmp_path, rng):
    xyz, kept = _frame(rng)
    frame = point_cloud(xyz[kept], index=kept, meta={"organized": True, "width": 20, "height": 15})
    shuffled = frame.select(rng.permutation(len(frame)))
    f = write_pcd(tmp_path / "s.pcd", shuffled, data="ascii")
    body = f.read_bytes().split(b"DATA ascii\n")[1].decode().splitlines()
    assert len(body) == 300
    assert [i for i, line in enumerate(body) if not line.startswith("nan")] == kept.tolist()
    again = read_pcd(f)
    assert again.index.tolist() == kept.tolist()
    np.testing.assert_array_equal(again.xyz, frame.xyz)


def test_frame_whose_points_share_pixels_is_written_unorganized(tmp_path, rng):
    xyz, kept = _frame(rng)
    frame = point_cloud(xyz[kept], index=kept, meta={"organized": True, "width": 20, "height": 15})
    doubled = frame.select([0, 0, 1])  # two points on one pixel: no longer a grid
    c = read_pcd(write_pcd(tmp_path / "d.pcd", doubled))
    assert (c.meta["width"], c.meta["height"], c.meta["organized"]) == (3, 1, False)
    np.testing.assert_array_equal(c.xyz, doubled.xyz)
    # Points left out (a crop) keep their pixels: still the frame, with more NaN pixels.
    crop = read_pcd(write_pcd(tmp_path / "c.pcd", frame.select(np.arange(0, len(frame), 2))))
    assert (crop.meta["width"], crop.meta["height"]) == (20, 15)
    assert crop.index.tolist() == kept[::2].tolist()


def test_writer_header_and_open3d_reads_it(tmp_path, rng):
    cloud = point_cloud(
        rng.normal(size=(50, 3)),
        rgb=rng.integers(0, 256, (50, 3)),
        normals=rng.normal(size=(50, 3)),
    )
    f = write_pcd(tmp_path / "o3d.pcd", cloud)
    head = f.read_bytes().split(b"DATA binary\n")[0].decode()
    assert "FIELDS x y z rgb normal_x normal_y normal_z" in head
    assert "TYPE F F F F F F F" in head and "SIZE 4 4 4 4 4 4 4" in head
    import open3d as o3d

    ref = o3d.io.read_point_cloud(str(f))
    np.testing.assert_array_equal(np.asarray(ref.points), cloud.xyz.astype(np.float32))
    np.testing.assert_allclose(np.asarray(ref.colors) * 255, cloud.rgb, atol=1e-9)


def test_writer_refusals(tmp_path):
    cloud = point_cloud(np.zeros((2, 3)))
    with pytest.raises(InvalidParameterError, match="'data' parameter"):
        write_pcd(tmp_path / "a.pcd", cloud, data="zip")
    with pytest.raises(WriteError, match="beyond float32"):
        write_pcd(tmp_path / "a.pcd", point_cloud([[1e300, 0, 0]]), dtype="float32")
    with pytest.raises(WriteError, match="shape"):
        write_pcd(tmp_path / "a.pcd", cloud.with_fields(h=np.zeros((2, 0))))
    assert os.listdir(tmp_path) == []


def test_failed_write_leaves_the_old_file(tmp_path, rng, monkeypatch):
    target = tmp_path / "keep.pcd"
    target.write_bytes(b"old")

    def broken(*args, **kwargs):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(_pcd.lzf, "compress", broken)
    with pytest.raises(WriteError, match="Input/output error"):
        write_cloud(target, point_cloud(rng.normal(size=(5, 3))), data="binary_compressed")
    assert target.read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["keep.pcd"]


# ---------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------
XYZ = ("x y z", "4 4 4", "F F F")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "is empty"),
        (b"\x89PNG\r\n\x1a\n" + bytes(range(256)), "no 'DATA' line"),
        (_header(*XYZ, width=1).replace(b"DATA ascii", b"DATA zipped"), "unknown DATA 'zipped'"),
        (_header(*XYZ, width=10, points=20), r"POINTS 20 disagrees with WIDTH x HEIGHT = 10 x 1"),
        (_header("x y z", "4 4", "F F F", width=1), "SIZE has 2 entries but FIELDS names 3"),
        (_header("x y z", "4 4 3", "F F F", width=1), "TYPE 'F' with SIZE 3"),
        (
            _header("x y z", "4 4 4", "F F F", width=1).replace(b"WIDTH 1", b"WIDTH one"),
            "WIDTH should hold whole numbers",
        ),
        (
            _header("x y z", "4 4 4", "F F F", width=1).replace(b"VERSION", b"COLOUR"),
            "unknown keyword 'COLOUR'",
        ),
        (_header("x y intensity", "4 4 4", "F F F", width=1) + b"1 2 3\n", "has no z field"),
        (_header(*XYZ, width=0), "contains no points"),
        (_header(*XYZ, width=3) + b"1 2 3\n4 5 6\n", "3 points declared, 2 lines of data"),
        (_header(*XYZ, width=2) + b"1 2 3\n4 x 6\n", "line 13: field 'y' should be a number"),
        (_header(*XYZ, width=2) + b"1 2 3\n4 6\n", "line 13: a point line needs 3 values, found 2"),
        (
            _header(*XYZ, width=100, data="binary") + b"\0" * 600,
            "truncated: 100 points of 12 bytes need 1200 bytes of data, the file holds 600",
        ),
        (_header(*XYZ, width=10**12, data="binary") + b"\0" * 12, "truncated"),
        (_header(*XYZ, width=10**12, data="ascii") + b"1 2 3\n", "truncated"),
        (
            _header(*XYZ, width=10, data="binary_compressed")
            + struct.pack("<II", 5, 120)
            + b"\0" * 3,
            "5 bytes of compressed data declared, 3 present",
        ),
        (
            _header(*XYZ, width=10, data="binary_compressed") + struct.pack("<II", 5, 100),
            "expands to 100 bytes, but 10 points of the declared fields need 120",
        ),
        (
            _header(*XYZ, width=10**8, data="binary_compressed")
            + struct.pack("<II", 5, 12 * 10**8),
            "implausible",
        ),
        (
            _header(*XYZ, width=10, data="binary_compressed")
            + struct.pack("<II", 8, 120)
            + b"\xff" * 8,
            "LZF-compressed data is damaged",
        ),
        (
            _header(*XYZ, width=10, data="binary_compressed")
            + struct.pack("<II", 2, 120)
            + b"\x00a",
            r"damaged \(it expands to 1 bytes instead of 120\)",
        ),
        (
            _header("x y z rgb", "4 4 4 2", "F F F U", width=1) + b"0 0 0 1\n",
            "should be one 4-byte packed colour",
        ),
    ],
)
def test_errors_name_the_file_and_the_problem(tmp_path, content, message):
    f = tmp_path / "e.pcd"
    f.write_bytes(content)
    with pytest.raises(CorruptFileError, match=message) as info:
        read_cloud(f)
    assert str(info.value).startswith(str(f))


# ---------------------------------------------------------------------------------
# Round trips
# ---------------------------------------------------------------------------------
@pytest.mark.parametrize("data", ["binary", "ascii", "binary_compressed"])
@given(cloud=clouds())
def test_roundtrip_float32(tmp_path_factory, data, cloud):
    f = tmp_path_factory.mktemp("pcd") / "c.pcd"
    got = read_cloud(write_cloud(f, cloud, data=data, dtype="float32"))
    assert_same_cloud(got, cloud, np.float32)


@pytest.mark.parametrize("data", ["binary", "ascii", "binary_compressed"])
@given(cloud=clouds(coords=st.floats(allow_nan=False, allow_infinity=False)))
def test_roundtrip_float64_is_exact(tmp_path_factory, data, cloud):
    f = tmp_path_factory.mktemp("pcd") / "c.pcd"
    assert_same_cloud(read_cloud(write_cloud(f, cloud, data=data, dtype="float64")), cloud)
