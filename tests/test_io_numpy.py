"""NumPy .npy / .npz readers and writers: layouts, round trips, errors."""

from __future__ import annotations

import io
import os
import warnings
import zipfile

import hypothesis.extra.numpy as hnp
import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from ontodetect import (
    CorruptFileError,
    DataWarning,
    ReadError,
    WriteError,
    point_cloud,
    read_cloud,
    write_cloud,
)
from ontodetect.io import _numpy
from ontodetect.io._numpy import read_npy, read_npz, write_npy, write_npz

FIELD_TYPES = [
    np.bool_,
    np.int8,
    np.uint8,
    np.int16,
    np.uint16,
    np.int32,
    np.uint32,
    np.int64,
    np.uint64,
    np.float16,
    np.float32,
    np.float64,
]
FIELD_NAMES = ["label", "instance", "intensity", "score", "feature"]
FINITE = st.floats(allow_nan=False, allow_infinity=False)


@st.composite
def clouds(draw, with_fields=True, max_points=30):
    n = draw(st.integers(1, max_points))
    xyz = draw(hnp.arrays(np.float64, (n, 3), elements=FINITE))
    rgb = draw(st.none() | hnp.arrays(np.uint8, (n, 3)))
    if not with_fields:
        return point_cloud(xyz, rgb=rgb)
    normals = draw(st.none() | hnp.arrays(np.float64, (n, 3)))
    fields = {}
    for name in draw(st.lists(st.sampled_from(FIELD_NAMES), unique=True, max_size=3)):
        shape = (n,) if draw(st.booleans()) else (n, draw(st.integers(1, 3)))
        fields[name] = draw(hnp.arrays(draw(st.sampled_from(FIELD_TYPES)), shape))
    index = draw(hnp.arrays(np.int64, n, elements=st.integers(0, 10**12)))
    return point_cloud(xyz, rgb=rgb, normals=normals, fields=fields, index=index)


# ---------------------------------------------------------------------------------
# Known answers
# ---------------------------------------------------------------------------------
def test_npy_xyz_only(tmp_path):
    f = tmp_path / "p.npy"
    np.save(f, np.array([[1, 2, 3], [4, 5, 6]], np.int32))
    c = read_cloud(f)
    np.testing.assert_array_equal(c.xyz, [[1, 2, 3], [4, 5, 6]])
    assert c.rgb is None and c.fields == {}
    assert c.meta["columns"] == ["x", "y", "z"]


@pytest.mark.parametrize(
    ("colours", "expected"),
    [
        ([[255, 0, 10], [0, 128, 1]], [[255, 0, 10], [0, 128, 1]]),  # 0..255 as in *_vert.npy
        ([[1.0, 0.0, 0.5], [0.2, 0.4, 0.6]], [[255, 0, 128], [51, 102, 153]]),  # 0..1
    ],
)
def test_npy_xyz_rgb(tmp_path, colours, expected):
    f = tmp_path / "p.npy"
    np.save(f, np.hstack([np.zeros((2, 3)), colours]).astype(np.float32))
    assert read_npy(f).rgb.tolist() == expected


def test_npy_extra_columns_become_fields(tmp_path):
    f = tmp_path / "p.npy"
    np.save(f, np.array([[0, 0, 0, 10, 20, 30, 5, 0.5], [1, 1, 1, 40, 50, 60, 6, 0.25]]))
    c = read_npy(f)
    assert c.rgb.tolist() == [[10, 20, 30], [40, 50, 60]]
    assert c.fields["col6"].tolist() == [5, 6]
    assert c.fields["col7"].tolist() == [0.5, 0.25]


def test_npy_columns_that_are_not_colours_stay_fields(tmp_path):
    f = tmp_path / "n.npy"
    table = np.array([[0, 0, 0, 0.0, -1.0, 0.0], [1, 1, 1, 0.5, 0.5, 0.7]])  # normals, say
    np.save(f, table)
    c = read_npy(f)
    assert c.rgb is None
    assert sorted(c.fields) == ["col3", "col4", "col5"]
    np.save(f, np.array([[0, 0, 0, 7.0]]))
    assert read_npy(f).fields["col3"].tolist() == [7.0]


def test_npy_structured_array(tmp_path):
    dt = [
        ("x", "<f4"),
        ("y", "<f4"),
        ("z", ">f8"),
        ("red", "u1"),
        ("green", "u1"),
        ("blue", "u1"),
        ("label", "<i2"),
        ("name", "U3"),
    ]
    arr = np.zeros(2, dt)
    arr["x"], arr["z"], arr["red"], arr["label"] = [1, 2], [3, 4], [9, 8], [-1, 7]
    f = tmp_path / "s.npy"
    np.save(f, arr)
    c = read_npy(f)
    np.testing.assert_array_equal(c.xyz, [[1, 0, 3], [2, 0, 4]])
    assert c.rgb[:, 0].tolist() == [9, 8]
    assert c.fields["label"].dtype == np.int16
    assert set(c.fields) == {"label"}  # text fields are not numbers


def test_npy_fortran_order(tmp_path):
    table = np.asfortranarray(np.arange(12.0).reshape(4, 3))
    f = tmp_path / "f.npy"
    np.save(f, table)
    np.testing.assert_array_equal(read_npy(f).xyz, table)


def test_npz_named_arrays(tmp_path):
    f = tmp_path / "a.npz"
    np.savez_compressed(
        f,
        points=np.ones((3, 3), np.float32),
        colors=np.full((3, 3), 0.5),
        normals=np.tile([0, 0, 1.0], (3, 1)),
        instance=np.array([1, 1, 2], np.uint16),
        feats=np.zeros((3, 4), np.float32),
        bbox=np.zeros((2, 7)),
        name=np.array(["a", "b", "c"]),
    )
    c = read_cloud(f)
    assert c.rgb.tolist() == [[128, 128, 128]] * 3
    np.testing.assert_array_equal(c.normals, np.tile([0, 0, 1.0], (3, 1)))
    assert c.fields["instance"].dtype == np.uint16
    assert c.fields["feats"].shape == (3, 4)
    assert sorted(c.meta["ignored_arrays"]) == ["bbox", "name"]


def test_npz_separate_coordinate_arrays_and_stored_index(tmp_path):
    f = tmp_path / "b.npz"
    np.savez(f, x=[1.0, 2.0], y=[3.0, 4.0], z=[5.0, np.nan], index=np.array([10, 20]))
    with pytest.warns(DataWarning, match="dropped 1 of 2"):
        c = read_npz(f)
    np.testing.assert_array_equal(c.xyz, [[1, 3, 5]])
    assert c.index.tolist() == [10]


def test_npy_writer_drops_what_it_cannot_hold_with_a_warning(tmp_path, rng):
    cloud = point_cloud(
        rng.normal(size=(4, 3)), normals=rng.normal(size=(4, 3)), fields={"label": np.arange(4)}
    )
    with pytest.warns(DataWarning, match=r"not written: normals, label \(write a \.npz"):
        f = write_npy(tmp_path / "p.npy", cloud)
    assert np.load(f).shape == (4, 3)


def test_npy_dark_colours_read_as_unit_floats(tmp_path):
    # A documented ambiguity of plain arrays: colours all <= 1 look like 0..1 floats.
    f = write_npy(tmp_path / "dark.npy", point_cloud(np.zeros((2, 3)), rgb=[[0, 1, 0], [1, 0, 0]]))
    assert read_npy(f).rgb.tolist() == [[0, 255, 0], [255, 0, 0]]


def test_npz_writer_keeps_names_that_clash_with_savez_arguments(tmp_path):
    cloud = point_cloud(np.zeros((2, 3)), fields={"file": [1, 2], "allow_pickle": [3, 4]})
    c = read_npz(write_npz(tmp_path / "k.npz", cloud, compressed=True))
    assert c.fields["file"].tolist() == [1, 2]
    assert c.fields["allow_pickle"].tolist() == [3, 4]


def test_npz_writer_refuses_special_names(tmp_path):
    cloud = point_cloud(np.zeros((2, 3)), fields={"colors": [1, 2]})
    with pytest.raises(WriteError, match="field 'colors' cannot be stored"):
        write_npz(tmp_path / "x.npz", cloud)
    assert os.listdir(tmp_path) == []


def test_failed_write_leaves_the_old_file(tmp_path, rng, monkeypatch):
    target = tmp_path / "keep.npz"
    target.write_bytes(b"old")

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(_numpy.np.lib.format, "write_array", broken)
    with pytest.raises(WriteError, match="No space left on device"):
        write_cloud(target, point_cloud(rng.normal(size=(5, 3))))
    assert target.read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["keep.npz"]


# ---------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------
def _npy_bytes(arr, header_patch=None):
    buf = io.BytesIO()
    np.save(buf, arr)
    data = buf.getvalue()
    if header_patch:
        old, new = header_patch
        data = data.replace(old, new.ljust(len(old)))
    return data


@pytest.mark.parametrize(
    ("content", "error", "message"),
    [
        (b"", CorruptFileError, "bad magic bytes"),
        (b"PK\x03\x04 not numpy", CorruptFileError, "bad magic bytes"),
        (
            _npy_bytes(np.zeros((4, 3)))[:-10],
            CorruptFileError,
            r"truncated, shape \(4, 3\) of float64 needs 96 bytes, 86 present",
        ),
        (
            _npy_bytes(np.zeros((4, 3)), (b"(4, 3)", b"(1000000000000, 3)")),
            CorruptFileError,
            "truncated, shape",
        ),
        (
            _npy_bytes(np.zeros((4, 3)), (b"(4, 3)", b"(-4, 3)")),
            CorruptFileError,
            "invalid .npy header",
        ),
        (
            _npy_bytes(np.zeros((4, 3)), (b"'descr'", b"'dexcr'")),
            CorruptFileError,
            "unreadable .npy header",
        ),
        (_npy_bytes(np.array([[1, "a", None]], dtype=object)), ReadError, "Python objects"),
        (_npy_bytes(np.zeros((4, 2))), ReadError, r"shape \(4, 2\); expected \(n, 3\)"),
        (_npy_bytes(np.zeros(5)), ReadError, r"shape \(5,\)"),
        (_npy_bytes(np.zeros((3, 3), complex)), ReadError, "expected real numbers"),
        (_npy_bytes(np.zeros((0, 3))), CorruptFileError, "contains no points"),
        (_npy_bytes(np.zeros(2, [("a", "f4"), ("b", "f4")])), ReadError, "has no x, y, z"),
    ],
)
def test_npy_errors(tmp_path, content, error, message):
    f = tmp_path / "e.npy"
    f.write_bytes(content)
    with pytest.raises(error, match=message) as info:
        read_cloud(f)
    assert str(info.value).startswith(str(f))


def _zip(**members):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name, data in members.items():
            z.writestr(name, data)
    return buf.getvalue()


@pytest.mark.parametrize(
    ("content", "error", "message"),
    [
        (b"not a zip at all", CorruptFileError, "not a readable .npz archive"),
        (_zip(**{"labels.npy": _npy_bytes(np.zeros(3))}), ReadError, "has no 'xyz'"),
        (_zip(**{"xyz.npy": b"\x93NUMPY garbage"}), CorruptFileError, "array 'xyz'"),
        (
            _zip(**{"xyz.npy": _npy_bytes(np.zeros((4, 3)), (b"(4, 3)", b"(10000000000, 3)"))}),
            CorruptFileError,
            "array 'xyz': truncated",
        ),
        (
            _zip(
                **{"xyz.npy": _npy_bytes(np.zeros((4, 3))), "rgb.npy": _npy_bytes(np.zeros((3, 3)))}
            ),
            CorruptFileError,
            r"array 'rgb' has shape \(3, 3\).*expected \(4, 3\)",
        ),
        (
            _zip(**{"xyz.npy": _npy_bytes(np.zeros((4, 3))), "index.npy": _npy_bytes(np.zeros(4))}),
            CorruptFileError,
            "array 'index' has shape",
        ),
        (_zip(**{"xyz.npy": _npy_bytes(np.zeros((0, 3)))}), CorruptFileError, "no points"),
    ],
)
def test_npz_errors(tmp_path, content, error, message):
    f = tmp_path / "e.npz"
    f.write_bytes(content)
    with pytest.raises(error, match=message) as info:
        read_cloud(f)
    assert str(info.value).startswith(str(f))


def test_npz_zip_bomb_sizes_are_refused_before_inflating(tmp_path):
    data = _zip(**{"xyz.npy": _npy_bytes(np.zeros((4, 3)))})
    # Patch the central directory's uncompressed size of the only member to 2**31.
    at = data.rindex(b"PK\x01\x02") + 24
    f = tmp_path / "bomb.npz"
    f.write_bytes(data[:at] + (2**31).to_bytes(4, "little") + data[at + 4 :])
    with pytest.raises(CorruptFileError, match="implausible sizes"):
        read_npz(f)


# ---------------------------------------------------------------------------------
# Round trips
# ---------------------------------------------------------------------------------
@given(cloud=clouds(with_fields=False))
def test_roundtrip_npy(tmp_path_factory, cloud):
    assume(cloud.rgb is None or cloud.rgb.max() > 1)  # see test_npy_dark_colours_...
    f = tmp_path_factory.mktemp("npy") / "c.npy"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = read_cloud(write_cloud(f, cloud))
    np.testing.assert_array_equal(got.xyz, cloud.xyz)
    if cloud.rgb is None:
        assert got.rgb is None
    else:
        np.testing.assert_array_equal(got.rgb, cloud.rgb)
    assert got.fields == {}


@pytest.mark.parametrize("compressed", [False, True])
@given(cloud=clouds())
def test_roundtrip_npz_keeps_everything(tmp_path_factory, compressed, cloud):
    f = tmp_path_factory.mktemp("npz") / "c.npz"
    got = read_cloud(write_cloud(f, cloud, compressed=compressed))
    np.testing.assert_array_equal(got.xyz, cloud.xyz)
    for attr in ("rgb", "normals"):
        want = getattr(cloud, attr)
        if want is None:
            assert getattr(got, attr) is None
        else:
            np.testing.assert_array_equal(getattr(got, attr), want)
    np.testing.assert_array_equal(got.index, cloud.index)
    assert set(got.fields) == set(cloud.fields)
    for name, values in cloud.fields.items():
        assert got.fields[name].dtype == values.dtype
        assert got.fields[name].shape == values.shape
        np.testing.assert_array_equal(got.fields[name], values)
