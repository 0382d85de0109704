import numpy as np
import pytest

from ontodetect import DataWarning, InvalidParameterError, PointCloud, point_cloud


def test_arrays_are_copied_and_read_only(rng):
    xyz = rng.normal(size=(10, 3))
    before = xyz.copy()
    cloud = point_cloud(xyz)
    xyz[0, 0] = 99.0
    assert np.array_equal(cloud.xyz, before)
    with pytest.raises(ValueError):
        cloud.xyz[0, 0] = 1.0
    assert cloud.xyz.dtype == np.float64
    assert cloud.index.tolist() == list(range(10))


def test_nonfinite_points_dropped_with_counted_warning_and_index_kept():
    xyz = np.array([[0, 0, 0], [np.nan, 0, 0], [1, 1, 1], [np.inf, 0, 0]], dtype=float)
    with pytest.warns(DataWarning, match="dropped 2 of 4 points"):
        cloud = point_cloud(xyz, fields={"label": [1, 2, 3, 4]})
    assert cloud.index.tolist() == [0, 2]
    assert cloud.fields["label"].tolist() == [1, 3]
    with pytest.raises(InvalidParameterError, match="'xyz'"):
        point_cloud(xyz, on_nonfinite="raise")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"xyz": np.zeros((3, 2))}, "'xyz' parameter must be an array of shape"),
        ({"xyz": np.zeros((3, 3)), "rgb": np.zeros((2, 3))}, "'rgb'"),
        ({"xyz": np.zeros((3, 3)), "normals": np.zeros((3, 4))}, "'normals'"),
        ({"xyz": np.zeros((3, 3)), "fields": {"label": [1, 2]}}, "fields\\['label'\\]"),
        ({"xyz": np.zeros((3, 3)), "fields": {"x": [1, 2, 3]}}, "reserved"),
        ({"xyz": np.zeros((3, 3)), "index": [0, 1]}, "'index'"),
    ],
)
def test_bad_inputs_name_the_parameter(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        point_cloud(**kwargs)


def test_colour_conventions():
    xyz = np.zeros((3, 3))
    assert point_cloud(xyz, rgb=[[0, 0.5, 1.0]] * 3).rgb[0].tolist() == [0, 128, 255]
    assert point_cloud(xyz, rgb=np.full((3, 3), 65535)).rgb[0].tolist() == [255, 255, 255]
    assert point_cloud(xyz, rgb=np.full((3, 3), 7, np.uint8)).rgb.dtype == np.uint8


def test_select_keeps_file_rows_and_fields(rng):
    cloud = point_cloud(rng.normal(size=(6, 3)), fields={"instance": np.arange(6) * 10})
    sub = cloud.select(np.array([False, True, False, True, True, False])).select([2, 0])
    assert isinstance(sub, PointCloud)
    assert sub.index.tolist() == [4, 1]
    assert sub.fields["instance"].tolist() == [40, 10]
    with pytest.raises(InvalidParameterError):
        cloud.select([0, 6])


def test_open3d_conversion(rng):
    cloud = point_cloud(rng.normal(size=(5, 3)), rgb=np.full((5, 3), 255, np.uint8))
    pc = cloud.to_open3d()
    assert np.allclose(np.asarray(pc.points), cloud.xyz)
    assert np.allclose(np.asarray(pc.colors), 1.0)
