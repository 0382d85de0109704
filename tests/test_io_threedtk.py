"""3DTK scans: poses applied as 3DTK does, then metres, right-handed, z up."""

from __future__ import annotations

import numpy as np
import pytest

from ontodetect import CorruptFileError, InvalidParameterError, ReadError, read_cloud
from ontodetect.io import detect_format
from ontodetect.io._threedtk import pose_matrix, read_3dtk, threedtk_to_metric


def _scan(folder, number, lines, pose=None):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"scan{number:03d}.3d").write_text("\n".join(lines) + "\n")
    if pose is not None:
        (folder / f"scan{number:03d}.pose").write_text(
            " ".join(map(str, pose[:3])) + "\n" + " ".join(map(str, pose[3:])) + "\n"
        )
    return folder / f"scan{number:03d}.3d"


def _euler_to_matrix4(pos, theta_deg):
    """3DTK's EulerToMatrix4 (globals.icc), entry by entry, column-major."""
    sx, sy, sz = np.sin(np.radians(theta_deg))
    cx, cy, cz = np.cos(np.radians(theta_deg))
    a = [
        cy * cz, sx * sy * cz + cx * sz, -cx * sy * cz + sx * sz, 0.0,
        -cy * sz, -sx * sy * sz + cx * cz, cx * sy * sz + sx * cz, 0.0,
        sy, -sx * cy, cx * cy, 0.0,
        pos[0], pos[1], pos[2], 1.0,
    ]  # fmt: skip
    return np.array(a)


def _transform3(alignxf, p):
    """3DTK's transform3: x' = p . column + translation."""
    return np.array([
        p[0] * alignxf[0] + p[1] * alignxf[4] + p[2] * alignxf[8] + alignxf[12],
        p[0] * alignxf[1] + p[1] * alignxf[5] + p[2] * alignxf[9] + alignxf[13],
        p[0] * alignxf[2] + p[1] * alignxf[6] + p[2] * alignxf[10] + alignxf[14],
    ])  # fmt: skip


def test_ninety_degrees_about_y_and_a_translation(tmp_path):
    # By hand: Ry(90°) takes (100, 0, 0) to (0, 0, -100); + (10, 20, 30) -> (10, 20, -70) cm;
    # to metres, right-handed, z up: (z, -x, y) / 100 = (-0.7, -0.1, 0.2).
    f = _scan(tmp_path, 0, ["100 0 0", "0 100 0"], pose=[10, 20, 30, 0, 90, 0])
    c = read_3dtk(f)
    np.testing.assert_allclose(c.xyz, [[-0.7, -0.1, 0.2], [0.3, -0.1, 1.2]], atol=1e-12)
    assert c.fields["scan"].tolist() == [0, 0]
    assert c.meta["poses"][0] == {"position_cm": [10, 20, 30], "orientation_deg": [0, 90, 0]}


def test_rotation_order_is_x_then_y_then_z_matrices(tmp_path):
    # R = Rx Ry Rz: with θy = θz = 90°, Rz acts first: (100,0,0) -> (0,100,0) -> Ry keeps it.
    f = _scan(tmp_path, 0, ["100 0 0"], pose=[0, 0, 0, 0, 90, 90])
    np.testing.assert_allclose(read_3dtk(f).xyz, [[0, 0, 1]], atol=1e-12)


def test_pose_matrix_matches_3dtk_formulas(rng):
    for _ in range(20):
        pos, theta = rng.uniform(-500, 500, 3), rng.uniform(-180, 180, 3)
        p = rng.uniform(-1000, 1000, 3)
        expected = _transform3(_euler_to_matrix4(pos, theta), p)
        got = pose_matrix(pos, theta) @ np.r_[p, 1.0]
        np.testing.assert_allclose(got[:3], expected, atol=1e-9)


def test_axis_mapping_flips_handedness():
    axes = threedtk_to_metric(np.eye(3), scale=False)
    assert np.linalg.det(axes) == pytest.approx(-1.0)
    # 3DTK's y (up) becomes z; its z (forward) becomes x; its x becomes -y.
    assert threedtk_to_metric(np.array([[0.0, 250.0, 0.0]])).tolist() == [[0.0, 0.0, 2.5]]
    assert threedtk_to_metric(np.array([[0.0, 0.0, 100.0]])).tolist() == [[1.0, 0.0, 0.0]]
    assert threedtk_to_metric(np.array([[100.0, 0.0, 0.0]])).tolist() == [[0.0, -1.0, 0.0]]


def test_folder_of_scans(tmp_path):
    _scan(tmp_path, 2, ["0 0 100 7"], pose=[0, 0, 0, 0, 0, 0])
    _scan(tmp_path, 0, ["0 0 100 5"], pose=[0, 100, 0, 0, 0, 0])
    _scan(tmp_path, 1, ["0 0 100 6"])  # no pose file: identity
    c = read_3dtk(tmp_path)
    assert c.fields["scan"].tolist() == [0, 1, 2]
    assert c.fields["scan"].dtype == np.int32
    np.testing.assert_allclose(c.xyz, [[1, 0, 1], [1, 0, 0], [1, 0, 0]], atol=1e-12)
    assert c.fields["intensity"].tolist() == [5, 6, 7]
    assert c.meta["scans"] == [0, 1, 2] and c.meta["poses"][1] is None
    assert read_3dtk(tmp_path, scans=[2]).fields["scan"].tolist() == [2]


def test_frames_give_the_registered_pose(tmp_path):
    f = _scan(tmp_path, 0, ["0 0 100"], pose=[0, 0, 0, 0, 0, 0])
    first = " ".join(["1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 2"])
    moved = " ".join(
        map(str, [*np.eye(4)[:3].ravel(), 0, 100, 0, 1, 2])
    )  # column-major: t=(0,100,0)
    (tmp_path / "scan000.frames").write_text(first + "\n" + moved + "\n")
    np.testing.assert_allclose(read_3dtk(f).xyz, [[1, 0, 0]], atol=1e-12)
    np.testing.assert_allclose(read_3dtk(f, use_frames=True).xyz, [[1, 0, 1]], atol=1e-12)


@pytest.mark.parametrize(
    ("line", "layout", "check"),
    [
        ("0 0 100 10 20 30", "auto", lambda c: c.rgb.tolist() == [[10, 20, 30]]),
        ("0 0 100 0.5 10 20 30", "auto", lambda c: c.fields["intensity"].tolist() == [0.5]),
        ("0 0 100 10 20 30 0.5", "uos_rgbr", lambda c: c.rgb.tolist() == [[10, 20, 30]]),
        ("0 0 100 0 1 0", "auto", lambda c: np.allclose(c.normals, [[0, 0, 1]])),
        (
            "0 0 100 0.5 0.25 9",
            "auto",
            lambda c: sorted(c.fields) == ["col3", "col4", "col5", "scan"],
        ),
    ],
)
def test_column_layouts(tmp_path, line, layout, check):
    c = read_3dtk(_scan(tmp_path, 0, [line]), layout=layout)
    np.testing.assert_allclose(c.xyz, [[1, 0, 0]])
    assert check(c)


def test_normals_rotate_with_the_pose(tmp_path):
    f = _scan(tmp_path, 0, ["0 0 0 0 0 1"], pose=[50, 50, 50, 0, 90, 0])
    # Ry(90°) turns 3DTK's z axis into x; 3DTK's x is -y in the metric frame.
    np.testing.assert_allclose(read_3dtk(f, layout="uos_normal").normals, [[0, -1, 0]], atol=1e-12)


def test_old_uos_header_and_comments(tmp_path):
    f = _scan(tmp_path, 0, ["3 x 1", "# comment", "0 0 100", "0 0 200 # trailing"])
    np.testing.assert_allclose(read_3dtk(f).xyz, [[1, 0, 0], [2, 0, 0]])


def test_registry_dispatch(tmp_path):
    f = _scan(tmp_path / "scans", 0, ["0 0 100"])
    assert detect_format(f) == "3dtk" and detect_format(f.parent) == "3dtk"
    assert read_cloud(f.parent).meta["format"] == "3dtk"
    assert len(read_cloud(f)) == 1


def test_errors(tmp_path):
    bad = _scan(tmp_path / "a", 0, ["0 0 100", "0 0 x"])
    with pytest.raises(CorruptFileError, match=r"scan000\.3d: line 2: expected numbers"):
        read_3dtk(bad)
    short = _scan(tmp_path / "b", 0, ["0 0 100"])
    (tmp_path / "b" / "scan000.pose").write_text("1 2 3\n")
    with pytest.raises(CorruptFileError, match=r"scan000\.pose: pose: expected 6 numbers, found 3"):
        read_3dtk(short)
    (tmp_path / "b" / "scan000.pose").write_text("1 2 3\n4 five 6\n")
    with pytest.raises(CorruptFileError, match=r"scan000\.pose: .*found 'five'"):
        read_3dtk(short)
    empty = _scan(tmp_path / "c", 0, ["# nothing"])
    with pytest.raises(CorruptFileError, match="contains no points"):
        read_3dtk(empty)
    (tmp_path / "d").mkdir()
    with pytest.raises(ReadError, match="holds no 3DTK scan"):
        read_3dtk(tmp_path / "d")
    with pytest.raises(InvalidParameterError, match="'layout' parameter"):
        read_3dtk(short, layout="xyz")
    with pytest.raises(
        CorruptFileError, match="layout 'uos_rrgb' has 7 columns but the file has 3"
    ):
        read_3dtk(short.parent / "scan000.3d", layout="uos_rrgb")
