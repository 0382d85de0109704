"""Text point clouds (XYZ, TXT, CSV, PTS): hand-written files, round trips, errors."""

from __future__ import annotations

import os
import warnings

import hypothesis.extra.numpy as hnp
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ontodetect import (
    CorruptFileError,
    DataWarning,
    InvalidParameterError,
    point_cloud,
    read_cloud,
    write_cloud,
)
from ontodetect._progress import use_reporter
from ontodetect.io import _text
from ontodetect.io._text import load_numeric_table, read_text, write_text


def _write(path, text: str):
    path.write_bytes(text.encode("latin-1"))
    return path


class _Recorder:
    """A progress reporter that remembers what it was told."""

    def __init__(self):
        self.totals, self.advanced = [], 0.0

    def start(self, description, total):
        self.totals.append((description, total))
        return len(self.totals)

    def advance(self, task, amount):
        self.advanced += amount

    def finish(self, task):
        pass


# -- reading ----------------------------------------------------------------------
def test_plain_xyz(tmp_path):
    c = read_text(_write(tmp_path / "a.xyz", "0 0 0\n1.5 -2 3e2\n"))
    np.testing.assert_array_equal(c.xyz, [[0, 0, 0], [1.5, -2, 300]])
    assert c.rgb is None and dict(c.fields) == {}
    assert c.index.tolist() == [0, 1]
    assert c.meta["columns"] == ["x", "y", "z"]


def test_header_names_columns(tmp_path):
    f = _write(tmp_path / "a.txt", "x y z r g b intensity\n1 2 3 255 128 0 0.5\n4 5 6 0 0 9 7\n")
    c = read_text(f)
    np.testing.assert_array_equal(c.xyz, [[1, 2, 3], [4, 5, 6]])
    assert c.rgb.tolist() == [[255, 128, 0], [0, 0, 9]]
    assert c.fields["intensity"].tolist() == [0.5, 7.0]


def test_header_in_any_order(tmp_path):
    f = _write(tmp_path / "a.txt", "intensity z y x\n9 3 2 1\n")
    c = read_text(f)
    assert c.xyz.tolist() == [[1, 2, 3]]
    assert c.fields["intensity"].tolist() == [9.0]


def test_cloudcompare_csv_header(tmp_path):
    f = _write(
        tmp_path / "a.csv", "//X,Y,Z,R,G,B,Scalar_Label\r\n1,2,3,10,20,30,4\r\n5,6,7,1,2,3,0\r\n"
    )
    c = read_text(f)
    assert c.xyz.tolist() == [[1, 2, 3], [5, 6, 7]]
    assert c.rgb.tolist() == [[10, 20, 30], [1, 2, 3]]
    assert c.fields["label"].dtype == np.int32
    assert c.fields["label"].tolist() == [4, 0]
    assert c.meta["delimiter"] == ","


def test_comment_header_right_above_data(tmp_path):
    f = _write(
        tmp_path / "a.txt", "# exported scan\n# x y z class_id\n1 2 3 5\n\n4 5 6 7 # chair\n"
    )
    c = read_text(f)
    assert c.fields["class_id"].tolist() == [5, 7]
    assert c.fields["class_id"].dtype == np.int32
    assert c.index.tolist() == [0, 1]


def test_unnamed_extra_columns(tmp_path):
    c = read_text(_write(tmp_path / "a.xyz", "1 2 3 0.25 -4\n"))
    assert sorted(c.fields) == ["col3", "col4"]
    assert c.fields["col4"].tolist() == [-4.0]


def test_six_columns_colour_or_not(tmp_path):
    colours = read_text(_write(tmp_path / "a.xyz", "1 2 3 255 0 7\n4 5 6 1 2 3\n"))
    assert colours.rgb.tolist() == [[255, 0, 7], [1, 2, 3]]
    normals_like = read_text(_write(tmp_path / "b.xyz", "1 2 3 0 -1 0\n4 5 6 0.6 0.8 0\n"))
    assert normals_like.rgb is None
    assert sorted(normals_like.fields) == ["col3", "col4", "col5"]


def test_float_colours_are_scaled(tmp_path):
    c = read_text(_write(tmp_path / "a.txt", "x y z r g b\n0 0 0 1.0 0.5 0\n"))
    assert c.rgb.tolist() == [[255, 128, 0]]


def test_sixteen_bit_colours_keep_high_byte(tmp_path):
    c = read_text(_write(tmp_path / "a.txt", "x y z red green blue\n0 0 0 65535 4660 256\n"))
    assert c.rgb.tolist() == [[255, 0x12, 1]]


def test_colours_out_of_range(tmp_path):
    f = _write(tmp_path / "a.txt", "x y z r g b\n0 0 0 -1 0 0\n")
    with pytest.raises(CorruptFileError, match=r"a\.txt: colour columns r/g/b .* -1"):
        read_text(f)


def test_named_normals(tmp_path):
    c = read_text(_write(tmp_path / "a.txt", "x y z nx ny nz\n0 0 0 0 0 1\n"))
    assert c.normals.tolist() == [[0, 0, 1]]


def test_columns_option_overrides(tmp_path):
    f = _write(tmp_path / "a.xyz", "1 2 3 0 0 1\n")
    c = read_text(f, columns="x y z nx ny nz")
    assert c.normals.tolist() == [[0, 0, 1]] and c.rgb is None
    with pytest.raises(InvalidParameterError, match="'columns' parameter must be a list of 6"):
        read_text(f, columns=["x", "y", "z"])


def test_leica_pts(tmp_path):
    f = _write(tmp_path / "a.pts", "2\n1 2 3 -1200 10 20 30\n4 5 6 300 40 50 60\n")
    c = read_text(f)
    assert c.xyz.tolist() == [[1, 2, 3], [4, 5, 6]]
    assert c.fields["intensity"].tolist() == [-1200.0, 300.0]
    assert c.rgb.tolist() == [[10, 20, 30], [40, 50, 60]]
    assert c.meta["declared_count"] == 2


def test_pts_with_several_sections(tmp_path):
    c = read_text(_write(tmp_path / "a.pts", "1\n1 2 3 5\n2\n4 5 6 5\n7 8 9 5\n"))
    assert len(c) == 3 and c.meta["declared_count"] == 3


def test_pts_count_mismatch(tmp_path):
    f = _write(tmp_path / "a.pts", "3\n1 2 3 0\n4 5 6 0\n")
    with pytest.raises(CorruptFileError, match=r"a\.pts: the point count says 3 points but 2"):
        read_text(f)


def test_nan_points_are_dropped_with_a_warning(tmp_path):
    f = _write(tmp_path / "a.xyz", "1 2 3\nnan 0 0\n4 5 6\n")
    with pytest.warns(DataWarning, match=r"a\.xyz: dropped 1 of 3"):
        c = read_text(f)
    assert c.index.tolist() == [0, 2]


@pytest.mark.parametrize(
    ("text", "line", "what"),
    [
        ("1 2 3\n4 5 abc\n", 2, "expected numbers"),
        ("x y z\n1 2 3\n\n4 5\n", 4, "expected 3 columns, found 2"),
        ("# c\n1,2,3\n4,,6\n", 3, "expected numbers"),
        ("hello\x00\x01 world\n1 2 3\n", 1, "expected numbers"),
        ("1 2 3\n4 5 6 # ok\n7 8 9\x10\n", 3, "expected numbers"),
    ],
)
def test_bad_lines_name_file_and_line(tmp_path, text, line, what):
    f = _write(tmp_path / "bad.txt", text)
    with pytest.raises(CorruptFileError, match=rf"bad\.txt: line {line}: {what}"):
        read_text(f)


def test_line_numbers_across_chunks(tmp_path, monkeypatch):
    lines = [f"{i} {i} {i}" for i in range(500)]
    lines[437] = "1 2 oops"
    f = _write(tmp_path / "a.xyz", "x y z\n" + "\n".join(lines) + "\n")
    monkeypatch.setattr(_text, "CHUNK_BYTES", 100)
    with pytest.raises(CorruptFileError, match=r"line 439: expected numbers, found '1 2 oops'"):
        read_text(f)


def test_small_chunks_give_the_same_cloud(tmp_path, monkeypatch, rng):
    xyz = rng.normal(size=(300, 3))
    f = write_text(tmp_path / "a.txt", point_cloud(xyz, fields={"label": np.arange(300)}))
    whole = read_text(f)
    monkeypatch.setattr(_text, "CHUNK_BYTES", 37)
    pieces = read_text(f)
    np.testing.assert_array_equal(whole.xyz, pieces.xyz)
    np.testing.assert_array_equal(pieces.xyz, xyz)
    np.testing.assert_array_equal(pieces.fields["label"], np.arange(300))


def test_progress_counts_bytes(tmp_path):
    f = _write(tmp_path / "a.xyz", "x y z\n" + "1 2 3\n" * 1000)
    rec = _Recorder()
    with use_reporter(rec):
        read_text(f)
    assert rec.totals == [("Reading a.xyz", os.path.getsize(f) - len("x y z\n"))]
    assert rec.advanced == rec.totals[0][1]


@pytest.mark.parametrize("text", ["", "\n\n", "# only a comment\n", "x y z\n", "0\n"])
def test_no_points(tmp_path, text):
    with pytest.raises(CorruptFileError, match=r"e\.xyz: contains no points"):
        read_text(_write(tmp_path / "e.xyz", text))


def test_header_disagrees_with_data(tmp_path):
    f = _write(tmp_path / "a.txt", "x y z r g b\n1 2 3\n")
    with pytest.raises(CorruptFileError, match="line 1 names 6 columns but line 2 has 3"):
        read_text(f)


def test_load_numeric_table_repairs_control_characters(tmp_path):
    f = _write(tmp_path / "a.txt", "1 2 3\n4 5\x10 6\n7 8\x109 10\n")
    table, stats = load_numeric_table(f, repair=True)
    assert table.tolist() == [[1, 2, 3], [4, 5, 6]]
    assert stats.repaired == [2] and stats.skipped == [3]


@pytest.mark.parametrize("ext", [".xyz", ".txt", ".csv", ".pts"])
def test_registry_dispatch(tmp_path, ext):
    c = point_cloud([[1.0, 2.0, 3.0]], rgb=[[1, 2, 3]])
    f = write_cloud(tmp_path / f"a{ext}", c)
    back = read_cloud(f)
    assert back.meta["format"] == "text"
    assert back.xyz.tolist() == [[1, 2, 3]] and back.rgb.tolist() == [[1, 2, 3]]


# -- writing ----------------------------------------------------------------------
def test_writer_layout(tmp_path):
    c = point_cloud(
        [[0.1, 2, 3]],
        rgb=[[1, 2, 3]],
        normals=[[0, 0, 1]],
        fields={"class_id": np.array([5], np.int32), "pair": np.array([[0.5, 1.5]]), "ok": [True]},
    )
    f = write_text(tmp_path / "a.txt", c)
    assert f.read_text() == (
        "x y z r g b nx ny nz class_id pair_0 pair_1 ok\n"
        "0.1 2.0 3.0 1 2 3 0.0 0.0 1.0 5 0.5 1.5 1\n"
    )
    back = read_text(f)
    assert back.normals.tolist() == [[0, 0, 1]]
    assert back.fields["class_id"].tolist() == [5]
    assert back.fields["pair_1"].tolist() == [1.5]


def test_writer_csv_precision_and_no_leftovers(tmp_path):
    f = write_text(tmp_path / "a.csv", point_cloud([[1 / 3, 2, 3]]), precision=3)
    assert f.read_text() == "x,y,z\n0.333,2.000,3.000\n"
    assert os.listdir(tmp_path) == ["a.csv"]
    with pytest.raises(InvalidParameterError, match="'precision' parameter"):
        write_text(tmp_path / "b.csv", point_cloud([[0, 0, 0]]), precision=-1)


def test_writer_names_that_look_like_numbers(tmp_path):
    f = write_text(tmp_path / "a.txt", point_cloud([[0, 0, 0]], fields={"1": [7]}))
    assert read_text(f).fields["f_1"].tolist() == [7.0]


def test_pts_writer(tmp_path):
    c = point_cloud(
        [[1, 2, 3]], rgb=[[4, 5, 6]], fields={"intensity": [-7], "class_id": np.array([2])}
    )
    with pytest.warns(DataWarning, match=r"no room for fields \['class_id'\]"):
        f = write_text(tmp_path / "a.pts", c)
    assert f.read_text() == "1\n1.0 2.0 3.0 -7 4 5 6\n"
    back = read_text(f)
    assert back.fields["intensity"].tolist() == [-7.0] and back.rgb.tolist() == [[4, 5, 6]]


FINITE = st.floats(allow_nan=False, allow_infinity=False)


@st.composite
def text_clouds(draw):
    n = draw(st.integers(1, 25))
    xyz = draw(hnp.arrays(np.float64, (n, 3), elements=FINITE))
    rgb = draw(st.none() | hnp.arrays(np.uint8, (n, 3)))
    fields = {}
    if draw(st.booleans()):
        fields["classification"] = draw(hnp.arrays(np.uint8, n))
    if draw(st.booleans()):
        fields["intensity"] = draw(hnp.arrays(np.float64, n, elements=FINITE))
    return point_cloud(xyz, rgb=rgb, fields=fields)


def _check_same(back, cloud, atol=0.0):
    np.testing.assert_allclose(back.xyz, cloud.xyz, rtol=0, atol=atol)
    if cloud.rgb is None:
        assert back.rgb is None
    else:
        np.testing.assert_array_equal(back.rgb, cloud.rgb)
    assert set(back.fields) == set(cloud.fields)
    for name, values in cloud.fields.items():
        np.testing.assert_allclose(back.fields[name], values, rtol=0, atol=atol)


@given(cloud=text_clouds(), ext=st.sampled_from([".xyz", ".csv"]))
def test_round_trip_is_exact(tmp_path_factory, cloud, ext):
    f = tmp_path_factory.mktemp("rt") / f"c{ext}"
    write_text(f, cloud)
    _check_same(read_text(f), cloud)


@given(
    cloud=text_clouds(),
    precision=st.integers(0, 9),
)
def test_round_trip_to_written_precision(tmp_path_factory, cloud, precision):
    # Fixed-point text of huge numbers is long but still exact to the digits written.
    small = cloud.replace(xyz=np.clip(cloud.xyz, -1e6, 1e6))
    fields = {
        k: np.clip(v, -1e6, 1e6) if v.dtype.kind == "f" else v for k, v in small.fields.items()
    }
    small = small.replace(fields=fields)
    f = tmp_path_factory.mktemp("rtp") / "c.txt"
    write_text(f, small, precision=precision)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = read_text(f)
    # Half a unit in the last written digit, plus float64 rounding of numbers up to 1e6.
    _check_same(back, small, atol=0.5 * 10.0**-precision + 1e-9)


def test_fewer_than_three_columns(tmp_path):
    with pytest.raises(CorruptFileError, match=r"line 2: expected at least 3 columns .* found 2"):
        read_text(_write(tmp_path / "a.txt", "# two\n1 2\n3 4\n"))
