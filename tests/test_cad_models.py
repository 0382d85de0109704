"""Model library: canonical frames, thin profiles, sampling, user models through a manifest."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
import yaml

from ontodetect.cad import (
    CadModel,
    ModelLibrary,
    builtin_library,
    fit_object,
    grid_downsample,
    library_figure,
    load_manifest,
    load_mesh,
    orientation,
    sample_surface,
    visible_shell,
    visible_surface,
)
from ontodetect.cad._models import VIEW_HEIGHTS
from ontodetect.errors import CorruptFileError, InvalidParameterError, ReadError
from ontodetect.geometry._mesh import Mesh, box


def test_builtin_library_covers_the_classes():
    lib = builtin_library()
    assert set(lib.labels) == {"chair", "sofa", "table"}
    assert len(lib.for_label("chair")) >= 3
    assert {
        "sofa-2seat",
        "sofa-3seat",
        "table-round",
        "table-rectangular",
        "desk",
        "armchair",
    } <= set(lib)
    assert lib.for_label("lamp") == []
    assert builtin_library() is lib  # cached: samples and trees are built once


@pytest.mark.parametrize("name", list(builtin_library()))
def test_models_are_in_the_canonical_frame(name):
    m = builtin_library()[name]
    lo, hi = m.full.bounds
    assert lo[2] == pytest.approx(0.0, abs=1e-12)  # standing on the floor
    assert (lo[0] + hi[0]) / 2 == pytest.approx(0.0, abs=1e-12)  # footprint centred
    assert (lo[1] + hi[1]) / 2 == pytest.approx(0.0, abs=1e-12)
    assert m.dims["height"] == pytest.approx(hi[2])
    # The thin profile is a part of the full model's surface...
    tlo, thi = m.thin.bounds
    assert np.all(tlo >= lo - 1e-9) and np.all(thi <= hi + 1e-9)
    assert area(m.thin) < 0.9 * area(m.full)
    # ...without the undersides, which no viewpoint above them sees.
    v = m.thin.vertices[m.thin.triangles]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    down = n[:, 2] / np.linalg.norm(n, axis=1) < -0.95
    assert not np.any(down & (v[:, :, 2].max(axis=1) < min(VIEW_HEIGHTS) - 0.01))
    key = "seat_height" if m.is_seating else "top_height"
    assert 0.3 < m.dims[key] < 1.0
    assert m.anchor is not None and m.anchor[2] == pytest.approx(m.dims[key])


def area(mesh: Mesh) -> float:
    v = mesh.vertices[mesh.triangles]
    return float(0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum())


def test_visible_surface_hides_what_no_sensor_sees():
    # A seat board on a block: the block's top under the board and every bottom are hidden.
    board = box((0.5, 0.5, 0.04), (0.0, 0.0, 0.46))
    block = box((0.3, 0.3, 0.44), (0.0, 0.0, 0.22))
    full = Mesh(
        np.vstack([board.vertices, block.vertices]),
        np.vstack([board.triangles, block.triangles + 8]),
    )
    thin = visible_surface(full)
    # Board top and sides, block sides.
    assert area(thin) == pytest.approx(0.25 + 4 * 0.5 * 0.04 + 4 * 0.3 * 0.44, rel=1e-9)
    assert visible_surface(Mesh(block.vertices, np.zeros((0, 3), np.int32))).vertices.shape == (
        8,
        3,
    )


def test_seating_faces_plus_y():
    # The backrest is behind the seat: at negative y.
    chair = builtin_library()["chair-4leg"]
    pts = chair.points(0.02)
    high = pts[pts[:, 2] > 0.7]
    assert high[:, 1].mean() < chair.anchor[1] - 0.1


def test_sampling_is_seeded_and_even():
    plate = box((1.0, 0.5, 0.02))
    a = sample_surface(plate, 0.02, rng=1)
    assert np.array_equal(a, sample_surface(plate, 0.02, rng=1))
    assert not np.array_equal(a, sample_surface(plate, 0.02, rng=2))
    # Area 1.06 m2 at one point per 4 cm2 cell: about 2,650 points, all on the surface.
    assert 2300 < len(a) < 2900
    assert np.all(np.abs(a) <= [0.5 + 1e-9, 0.25 + 1e-9, 0.01 + 1e-9])


def test_point_set_mesh_is_grid_averaged():
    pts = np.array([[0.001, 0.0, 0.0], [0.003, 0.0, 0.0], [0.5, 0.0, 0.0]])
    out = sample_surface(Mesh(pts, np.zeros((0, 3), np.int32)), 0.02)
    np.testing.assert_allclose(out, [[0.002, 0.0, 0.0], [0.5, 0.0, 0.0]])


def test_grid_downsample_ignores_order(rng):
    pts = rng.random((500, 3))
    a = grid_downsample(pts, 0.1)
    b = grid_downsample(pts[::-1], 0.1)
    np.testing.assert_allclose(a, b, atol=1e-12)
    with pytest.raises(InvalidParameterError, match="'spacing'"):
        grid_downsample(pts, 0.0)


def test_visible_shell_drops_downward_faces():
    cube = box((1.0, 1.0, 1.0), (0.0, 0.0, 0.5))
    shell = visible_shell(cube)
    assert len(shell.triangles) == 10
    v = shell.vertices[shell.triangles]
    assert v[..., 2].max(axis=1).min() > 0.0  # no triangle lies on the bottom face


def test_library_merge_and_lookup():
    lib = builtin_library()
    mine = CadModel(
        "chair-4leg",
        "chair",
        box((0.5, 0.5, 0.9)),
        box((0.5, 0.5, 0.9)),
        {"width": 0.5, "depth": 0.5, "height": 0.9, "seat_height": 0.45},
    )
    merged = lib.merged([mine])
    assert merged["chair-4leg"] is mine and lib["chair-4leg"] is not mine
    assert len(merged) == len(lib)
    with pytest.raises(InvalidParameterError, match="'model'"):
        lib["no-such-model"]
    with pytest.raises(InvalidParameterError, match="'symmetry'"):
        CadModel("x", "chair", mine.full, mine.thin, mine.dims, symmetry=3)


def test_library_figure_draws_thin_and_full():
    fig = library_figure(builtin_library(), ["chair-4leg", "table-round"], spacing=0.04)
    assert len(fig.axes) == 4
    assert fig.axes[0].get_title().startswith("chair-4leg")


# -- user models ----------------------------------------------------------------------------


def test_orientation():
    np.testing.assert_array_equal(orientation("z", "y"), np.eye(3))
    R = orientation("y", "-z")  # y-up, facing -z (glTF)
    np.testing.assert_array_equal(R @ [0, 1, 0], [0, 0, 1])
    np.testing.assert_array_equal(R @ [0, 0, -1], [0, 1, 0])
    assert np.linalg.det(R) == pytest.approx(1.0)
    with pytest.raises(InvalidParameterError, match="'front'"):
        orientation("z", "-z")
    with pytest.raises(InvalidParameterError, match="'up'"):
        orientation("w", "y")


def write_mesh(path, vertices, triangles):
    trimesh.Trimesh(vertices, triangles, process=False).export(path)


@pytest.fixture
def upside_down_chair(tmp_path):
    """The generic chair drawn upside down (turned about x), in millimetres, as STL + OBJ."""
    chair = builtin_library()["chair-4leg"]
    flip = np.diag([1.0, -1.0, -1.0]) * 1000.0  # half turn about x, then millimetres
    write_mesh(
        tmp_path / "chair.stl", chair.full.vertices @ flip.T + [5, 7, 9], chair.full.triangles
    )
    write_mesh(
        tmp_path / "chair-thin.obj", chair.thin.vertices @ flip.T + [5, 7, 9], chair.thin.triangles
    )
    manifest = {
        "format": "ontodetect.cad-models/1",
        "models": [
            {
                "name": "my-chair",
                "label": "chair",
                "full": "chair.stl",
                "thin": "chair-thin.obj",
                "up": "-z",
                "front": "-y",
                "units": "mm",
                "seat_height": 0.46,
                "color": [10, 20, 30],
            },
            {
                "name": "derived",
                "label": "chair",
                "full": "chair.stl",
                "up": "-z",
                "front": "-y",
                "units": "mm",
            },
        ],
    }
    path = tmp_path / "models.yaml"
    path.write_text(yaml.safe_dump(manifest))
    return path, chair


def test_manifest_up_axis_rights_an_upside_down_model(upside_down_chair):
    path, chair = upside_down_chair
    lib = load_manifest(path)
    mine = lib["my-chair"]
    assert mine.label == "chair" and mine.color == (10, 20, 30)
    # STL stores float32: back in metres and upright to within a micrometre.
    np.testing.assert_allclose(mine.full.bounds, chair.full.bounds, atol=1e-5)
    np.testing.assert_allclose(
        np.sort(mine.thin.vertices, axis=0), np.sort(chair.thin.vertices, axis=0), atol=1e-5
    )
    assert mine.dims["seat_height"] == 0.46
    assert mine.anchor == (0.0, 0.0, 0.46)
    # Without a thin file the profile is derived in the canonical frame: the same one.
    derived = lib["derived"]
    assert area(derived.thin) == pytest.approx(area(chair.thin), rel=1e-3)
    assert derived.anchor is None


def test_fitting_a_user_model_recovers_a_pose(upside_down_chair):
    path, chair = upside_down_chair
    lib = ModelLibrary([load_manifest(path)["my-chair"]])
    data = chair.points(0.01) @ np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]).T + [2, 3, 0]
    fit = fit_object(data, "chair", lib)
    assert fit.model == "my-chair"
    assert (fit.x, fit.y) == pytest.approx((2.0, 3.0), abs=5e-3)
    assert math.degrees(fit.yaw) == pytest.approx(90.0, abs=0.5)


def test_thin_profile_derived_when_missing_and_point_sets_accepted(tmp_path):
    cube = box((0.8, 0.8, 0.75), (0.0, 0.0, 0.375))
    write_mesh(tmp_path / "table.ply", cube.vertices, cube.triangles)
    pts = np.random.default_rng(0).random((200, 3))
    trimesh.PointCloud(pts).export(tmp_path / "scan.ply")
    (tmp_path / "m.yaml").write_text(
        yaml.safe_dump(
            {
                "models": [
                    {
                        "name": "block",
                        "label": "table",
                        "full": "table.ply",
                        "top_height": 0.75,
                        "symmetry": 4,
                    },
                    {"name": "scanned", "label": "chair", "full": "scan.ply", "units": 1.0},
                ]
            }
        )
    )
    lib = load_manifest(tmp_path / "m.yaml")
    # The thin profile is the top and the four sides: the bottom is dropped.
    assert area(lib["block"].thin) == pytest.approx(0.64 + 4 * 0.8 * 0.75, rel=1e-6)
    assert lib["block"].symmetry == 4
    assert len(lib["scanned"].full.triangles) == 0 and len(lib["scanned"].points(0.05)) > 0


@pytest.mark.parametrize(
    ("entry", "error", "match"),
    [
        ({"label": "chair", "full": "a.stl"}, CorruptFileError, r"models\[0\]\.name"),
        (
            {"name": "a", "label": "chair", "full": "a.stl", "up": "up"},
            CorruptFileError,
            r"models\[0\]\.up",
        ),
        (
            {"name": "a", "label": "chair", "full": "a.stl", "front": "z"},
            CorruptFileError,
            r"models\[0\]\.front",
        ),
        (
            {"name": "a", "label": "chair", "full": "a.stl", "units": "furlong"},
            CorruptFileError,
            r"models\[0\]\.units",
        ),
        (
            {"name": "a", "label": "chair", "full": "a.stl", "colour": [1, 2, 3]},
            CorruptFileError,
            r"models\[0\]\.colour: unknown key",
        ),
        (
            {"name": "a", "label": "chair", "full": "a.stl", "symmetry": 3},
            CorruptFileError,
            r"models\[0\]\.symmetry",
        ),
        (
            {"name": "a", "label": "chair", "full": "a.stl", "seat_height": -1},
            CorruptFileError,
            r"models\[0\]\.seat_height",
        ),
        (
            {"name": "a", "label": "chair", "full": "missing.stl"},
            ReadError,
            r"missing\.stl: no such file",
        ),
        ({"name": "a", "label": "chair", "full": "a.txt"}, ReadError, "not a mesh file"),
    ],
)
def test_manifest_errors_name_the_key(tmp_path, entry, error, match):
    cube = box((1.0, 1.0, 1.0))
    write_mesh(tmp_path / "a.stl", cube.vertices, cube.triangles)
    (tmp_path / "a.txt").write_text("1 2 3\n")
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump({"models": [entry]}))
    with pytest.raises(error, match=match):
        load_manifest(path)


def test_manifest_file_errors(tmp_path):
    with pytest.raises(ReadError, match="no such file"):
        load_manifest(tmp_path / "none.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("models: [\n")
    with pytest.raises(CorruptFileError, match="not valid YAML"):
        load_manifest(bad)
    bad.write_text("format: other/1\nmodels: []\n")
    with pytest.raises(CorruptFileError, match="format"):
        load_manifest(bad)
    bad.write_text("models: []\n")
    with pytest.raises(CorruptFileError, match="non-empty list"):
        load_manifest(bad)
    cube = box((1.0, 1.0, 1.0))
    write_mesh(tmp_path / "a.stl", cube.vertices, cube.triangles)
    entry = {"name": "a", "label": "x", "full": "a.stl"}
    bad.write_text(yaml.safe_dump({"models": [entry, dict(entry)]}))
    with pytest.raises(CorruptFileError, match="used twice"):
        load_manifest(bad)
    (tmp_path / "broken.stl").write_bytes(b"solid x\nfacet normal nonsense\n")
    with pytest.raises(ReadError, match=r"broken\.stl"):
        load_mesh(tmp_path / "broken.stl")


def test_empty_library_behaves():
    lib = ModelLibrary()
    assert len(lib) == 0 and lib.labels == [] and list(lib) == []
