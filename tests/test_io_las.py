"""LAS / LAZ: exact scaled coordinates, colours, fields, metadata, round trips, errors."""

from __future__ import annotations

import hypothesis.extra.numpy as hnp
import laspy
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from laspy.vlrs.known import GeoKeyDirectoryVlr, GeoKeyEntryStruct

from ontodetect import (
    CorruptFileError,
    InvalidParameterError,
    WriteError,
    point_cloud,
    read_cloud,
    write_cloud,
)
from ontodetect.io._las import read_las, write_las

UTM = np.array([500000.0, 4000000.0, 0.0])


def _laspy_file(path, point_format=3, version="1.2", n=4, **dims):
    """A file written by laspy itself, integer coordinates 1000 + i at scale 0.001."""
    header = laspy.LasHeader(point_format=point_format, version=version)
    header.scales = [0.001, 0.001, 0.001]
    header.offsets = UTM
    for name, values in dims.items():
        if name.startswith("extra_"):
            header.add_extra_dim(laspy.ExtraBytesParams(name=name[6:], type=values.dtype))
    las = laspy.LasData(header)
    las.X = np.arange(n) + 1000
    las.Y = np.arange(n) * 2
    las.Z = -np.arange(n)
    for name, values in dims.items():
        las[name.removeprefix("extra_")] = values
    las.write(str(path))
    return path


def test_large_offsets_stay_exact(tmp_path):
    c = read_las(_laspy_file(tmp_path / "a.las"))
    expected_x = 500000.0 + (np.arange(4) + 1000) * 0.001
    # float32 would be off by up to 3 cm this far from the origin.
    np.testing.assert_allclose(c.xyz[:, 0], expected_x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(c.xyz[:, 1], 4000000.0 + np.arange(4) * 0.002, rtol=0, atol=1e-9)
    assert c.xyz.dtype == np.float64
    assert c.meta["scale"] == [0.001] * 3
    assert c.meta["offset"] == UTM.tolist()
    assert c.meta["point_format"] == 3 and c.meta["version"] == "1.2"
    assert c.meta["point_count"] == 4 and c.meta["compressed"] is False


def test_sixteen_bit_colours_keep_high_byte(tmp_path):
    red = np.array([0xFFFF, 0x1234, 0x0100, 0], np.uint16)
    f = _laspy_file(tmp_path / "a.las", red=red, green=red, blue=red)
    assert read_las(f).rgb[:, 0].tolist() == [0xFF, 0x12, 0x01, 0]


def test_eight_bit_values_in_sixteen_bit_fields_are_kept(tmp_path):
    red = np.array([255, 18, 1, 0], np.uint16)
    f = _laspy_file(tmp_path / "a.las", red=red, green=red, blue=red)
    assert read_las(f).rgb[:, 0].tolist() == [255, 18, 1, 0]


def test_standard_and_extra_dimensions_become_fields(tmp_path):
    f = _laspy_file(
        tmp_path / "a.laz",
        classification=np.array([2, 5, 6, 31], np.uint8),
        intensity=np.array([0, 1, 65535, 7], np.uint16),
        return_number=np.array([1, 2, 3, 1], np.uint8),
        point_source_id=np.array([9, 9, 8, 8], np.uint16),
        gps_time=np.array([0.5, 1.5, 2.5, 3.5]),
        extra_reflectance=np.array([0.1, 0.2, 0.3, 0.4], np.float32),
        extra_instance=np.array([0, 1, 1, 2], np.int32),
    )
    c = read_las(f)
    assert c.fields["classification"].tolist() == [2, 5, 6, 31]
    assert c.fields["classification"].dtype == np.uint8
    assert c.fields["intensity"].tolist() == [0, 1, 65535, 7]
    assert c.fields["return_number"].tolist() == [1, 2, 3, 1]
    assert c.fields["point_source_id"].tolist() == [9, 9, 8, 8]
    assert c.fields["gps_time"].tolist() == [0.5, 1.5, 2.5, 3.5]
    assert c.fields["reflectance"].dtype == np.float32
    assert c.fields["instance"].tolist() == [0, 1, 1, 2]
    assert c.meta["compressed"] is True


def test_gps_time_only_when_present(tmp_path):
    c = read_las(_laspy_file(tmp_path / "a.las", point_format=2))
    assert "gps_time" not in c.fields
    assert c.rgb is not None


def test_crs_from_wkt_and_geotiff_keys(tmp_path):
    header = laspy.LasHeader(point_format=0, version="1.2")
    keys = GeoKeyDirectoryVlr()
    keys.geo_keys_header.number_of_keys = 2
    geographic, projected = GeoKeyEntryStruct(), GeoKeyEntryStruct()
    geographic.id, geographic.value_offset = 2048, 4326
    projected.id, projected.value_offset = 3072, 32632
    keys.geo_keys = [geographic, projected]
    header.vlrs.append(keys)
    header.vlrs.append(laspy.vlrs.known.WktCoordinateSystemVlr('PROJCS["UTM 32N"]'))
    las = laspy.LasData(header)
    las.X = np.array([1])
    f = tmp_path / "a.las"
    las.write(str(f))
    c = read_las(f)
    assert c.meta["crs_epsg"] == 32632
    assert c.meta["crs_wkt"] == 'PROJCS["UTM 32N"]'


# -- writing ----------------------------------------------------------------------
def _cloud(n=6, **fields):
    xyz = UTM + np.arange(n * 3).reshape(n, 3) * 0.001
    rgb = np.arange(n * 3).reshape(n, 3) * 10 % 256
    return point_cloud(xyz, rgb=rgb, fields=fields)


@pytest.mark.parametrize("ext", ["las", "laz"])
def test_round_trip(tmp_path, ext):
    n = 6
    c = _cloud(
        n,
        classification=np.array([0, 1, 2, 5, 6, 31], np.uint8),
        intensity=np.arange(n, dtype=np.uint16) * 1000,
        score=np.linspace(0, 1, n),
        instance=np.array([0, 1, 1, 2, 2, 0], np.int32),
    )
    c = c.replace(normals=np.tile([0.0, 0.6, 0.8], (n, 1)), meta={"crs_wkt": "GEOGCS[]"})
    f = write_las(tmp_path / f"a.{ext}", c)
    back = read_las(f)
    np.testing.assert_allclose(back.xyz, c.xyz, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(back.rgb, c.rgb)
    np.testing.assert_array_equal(back.fields["classification"], c.fields["classification"])
    np.testing.assert_array_equal(back.fields["intensity"], c.fields["intensity"])
    np.testing.assert_array_equal(back.fields["score"], c.fields["score"])
    assert back.fields["instance"].dtype == np.int32
    np.testing.assert_allclose(back.normals, c.normals, atol=1e-7)
    assert back.meta["point_format"] == 2 and back.meta["crs_wkt"] == "GEOGCS[]"
    assert back.meta["offset"] == np.floor(c.xyz.min(axis=0)).tolist()
    assert back.meta["compressed"] is (ext == "laz")


def test_point_format_choice(tmp_path):
    big = write_las(tmp_path / "a.las", _cloud(2, classification=np.array([40, 5])))
    assert read_las(big).meta["point_format"] == 7
    assert read_las(big).meta["version"] == "1.4"
    assert read_las(big).fields["classification"].tolist() == [40, 5]
    timed = write_las(tmp_path / "b.las", _cloud(2, gps_time=np.array([1.0, 2.0])))
    assert read_las(timed).meta["point_format"] == 3
    plain = write_las(tmp_path / "c.las", point_cloud(np.zeros((2, 3))))
    assert read_las(plain).meta["point_format"] == 0


def test_scale_and_offset_options(tmp_path):
    c = point_cloud([[0.123456, 1.0, 2.0]])
    f = write_las(tmp_path / "a.las", c, scale=0.01, offset=(0, 0, 0))
    back = read_las(f)
    assert back.meta["scale"] == [0.01] * 3
    np.testing.assert_allclose(back.xyz, [[0.12, 1.0, 2.0]], atol=1e-12)


def test_writer_refuses_what_las_cannot_hold(tmp_path):
    with pytest.raises(WriteError, match=r"field 'intensity' must hold integers 0\.\.65535"):
        write_las(tmp_path / "a.las", _cloud(2, intensity=np.array([0.5, 1.0])))
    with pytest.raises(WriteError, match=r"field 'classification' must hold integers 0\.\.255"):
        write_las(tmp_path / "a.las", _cloud(2, classification=np.array([300, 1])))
    with pytest.raises(WriteError, match="too much for 32-bit integers"):
        write_las(tmp_path / "a.las", point_cloud([[0, 0, 0], [1e7, 0, 0]]), scale=0.001)
    with pytest.raises(WriteError, match="cannot be a LAS extra dimension"):
        write_las(tmp_path / "a.las", _cloud(2, **{"n" * 40: np.zeros(2)}))
    with pytest.raises(InvalidParameterError, match="'scale' parameter"):
        write_las(tmp_path / "a.las", _cloud(2), scale=0)
    assert not list(tmp_path.iterdir())


def test_registry_dispatch(tmp_path):
    f = write_cloud(tmp_path / "a.laz", _cloud(3))
    back = read_cloud(f)
    assert back.meta["format"] == "las" and len(back) == 3


# -- damaged files ----------------------------------------------------------------
@pytest.mark.parametrize("ext", ["las", "laz"])
def test_truncated_file(tmp_path, ext):
    f = write_las(tmp_path / f"a.{ext}", _cloud(2000))
    data = f.read_bytes()
    f.write_bytes(data[: len(data) * 3 // 4])
    with pytest.raises(CorruptFileError, match=rf"a\.{ext}: .*(truncated|decode|chunk)"):
        read_las(f)


def test_not_a_las_file(tmp_path):
    f = tmp_path / "a.las"
    f.write_bytes(b"hello, this is not lidar data" * 20)
    with pytest.raises(CorruptFileError, match=r"a\.las: is not a LAS/LAZ file"):
        read_las(f)


def test_zero_points(tmp_path):
    header = laspy.LasHeader(point_format=0, version="1.2")
    f = tmp_path / "a.las"
    laspy.LasData(header).write(str(f))
    with pytest.raises(CorruptFileError, match="contains no points"):
        read_las(f)


def test_damaged_record_count_fails_fast(tmp_path):
    f = write_las(tmp_path / "a.las", _cloud(3))
    data = bytearray(f.read_bytes())
    data[100:104] = (2**31).to_bytes(4, "little")  # number of variable-length records
    f.write_bytes(bytes(data))
    with pytest.raises(CorruptFileError, match="variable-length records cannot fit"):
        read_las(f)


COORD = st.floats(-1e4, 1e4, allow_nan=False)


@st.composite
def las_clouds(draw):
    n = draw(st.integers(1, 20))
    xyz = draw(hnp.arrays(np.float64, (n, 3), elements=COORD)) + UTM
    rgb = draw(st.none() | hnp.arrays(np.uint8, (n, 3)))
    fields = {}
    if draw(st.booleans()):
        fields["classification"] = draw(hnp.arrays(np.uint8, n))
    if draw(st.booleans()):
        fields["intensity"] = draw(hnp.arrays(np.uint16, n))
    return point_cloud(xyz, rgb=rgb, fields=fields)


@given(
    cloud=las_clouds(), ext=st.sampled_from(["las", "laz"]), scale=st.sampled_from([0.001, 0.01])
)
def test_round_trip_to_the_scale(tmp_path_factory, cloud, ext, scale):
    f = write_las(tmp_path_factory.mktemp("las") / f"c.{ext}", cloud, scale=scale)
    back = read_las(f)
    # Rounded to the nearest multiple of the scale (plus float64 rounding at 4e6).
    np.testing.assert_allclose(back.xyz, cloud.xyz, rtol=0, atol=scale / 2 + 1e-8)
    if cloud.rgb is None:
        assert back.rgb is None
    else:
        np.testing.assert_array_equal(back.rgb, cloud.rgb)
    for name in ("classification", "intensity"):
        if name in cloud.fields:
            np.testing.assert_array_equal(back.fields[name], cloud.fields[name])
