"""Choosing and fitting models to objects, frames, detections, and the object map."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import trimesh

from ontodetect import read_cloud
from ontodetect.cad import (
    CadFit,
    LevelFrame,
    ModelLibrary,
    ObjectHints,
    builtin_library,
    cad_dict,
    fit_detections,
    fit_document,
    fit_object,
    hints_from_points,
    model_scale,
    object_map_cloud,
    object_map_meshes,
    write_object_map,
)
from ontodetect.cad._models import sample_surface, visible_shell
from ontodetect.errors import InvalidParameterError
from ontodetect.geometry._mesh import Mesh
from ontodetect.synth import synthesize
from ontodetect.synth.furniture import make_furniture, place


def angle_error(a: float, b: float, period: float = 2 * math.pi) -> float:
    d = (a - b) % period
    return math.degrees(min(d, period - d))


def scanned(kind: str, seed: int, x: float, y: float, yaw: float, spacing: float = 0.015):
    """A simulated object placed at (x, y, yaw), sampled on the faces a sensor would see."""
    obj = place(make_furniture(kind, seed), x, y, yaw)
    mesh = visible_shell(Mesh(obj.vertices, obj.triangles))
    return sample_surface(mesh, spacing, rng=seed), obj


@pytest.fixture(scope="module")
def tiny():
    """A small simulated room (one table, one chair, one stool) and its detections."""
    from ontodetect.pipeline import detect

    r = synthesize("tiny", "rgbd", seed=3, points=30_000)
    return r, detect(r.cloud)


# -- hints ---------------------------------------------------------------------------------


def test_hints_find_seat_and_front():
    pts, obj = scanned("chair-4leg", 2, 1.0, 2.0, 0.7)
    h = hints_from_points(pts)
    assert h.seat_center[2] == pytest.approx(obj.dimensions["seat_height"], abs=0.015)
    # The model faces +y: the object's front is its yaw + 90 degrees.
    assert angle_error(h.front_yaw, 0.7 + math.pi / 2) < 5.0


def test_hints_find_the_table_top():
    pts, obj = scanned("table-dining", 4, 0.0, 0.0, 0.3)
    h = hints_from_points(pts)
    assert h.top_center[2] == pytest.approx(obj.dimensions["top_height"], abs=0.01)
    np.testing.assert_allclose(
        h.top_extent, [obj.dimensions["width"], obj.dimensions["depth"]], atol=0.03
    )
    assert angle_error(h.axis_yaw, 0.3, math.pi) < 1.0


def test_hints_merge_prefers_given_values():
    given = ObjectHints(
        seat_center=np.array([0.0, 0.0, 0.5]), backrest_center=np.array([0.0, -0.3, 0.8])
    )
    found = ObjectHints(seat_center=np.array([1.0, 1.0, 0.4]), height=0.9, front_yaw=0.0)
    merged = given.merged(found)
    assert merged.seat_center[2] == 0.5 and merged.height == 0.9
    assert merged.front_yaw == pytest.approx(math.pi / 2)  # from the given seat and backrest


def test_model_scale_follows_the_object():
    lib = builtin_library()
    table = lib["table-rectangular"]
    s = model_scale(
        table, ObjectHints(top_center=np.array([0, 0, 0.8]), top_extent=np.array([2.4, 0.9]))
    )
    np.testing.assert_allclose(s, [1.5, 1.0, 0.8 / 0.74])
    # Out-of-range measures are clipped, and a chair keeps its generic seat size.
    chair = lib["chair-4leg"]
    s = model_scale(
        chair, ObjectHints(seat_center=np.array([0, 0, 2.0]), seat_extent=np.array([0.6, 0.6]))
    )
    assert s[0] == s[1] == 1.0 and s[2] == pytest.approx(1.35)


# -- fitting one object --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kind", "seed"), [("chair-4leg", 1), ("chair-office", 2), ("chair-sled", 3)]
)
def test_fits_simulated_chairs(kind, seed):
    pts, _ = scanned(kind, seed, 2.0, 1.0, 2.5)
    fit = fit_object(pts, "chair", seed=0)
    assert fit.label == "chair" and not fit.blank
    assert angle_error(fit.yaw, 2.5) < 5.0
    assert math.hypot(fit.x - 2.0, fit.y - 1.0) < 0.05
    assert fit.inlier_fraction > 0.6 and fit.rms < 0.02
    # Upright on the floor.
    assert fit.level_pose[2].tolist() == [0.0, 0.0, 1.0, 0.0]


@pytest.mark.parametrize(("kind", "period"), [("table-dining", math.pi), ("table-round", None)])
def test_fits_simulated_tables(kind, period):
    pts, _ = scanned(kind, 5, -1.0, 0.5, 0.4)
    fit = fit_object(pts, "table", seed=0)
    assert math.hypot(fit.x + 1.0, fit.y - 0.5) < 0.03
    if period is not None:
        assert angle_error(fit.yaw, 0.4, period) < 3.0
    else:
        assert fit.model == "table-round"


def test_same_seed_same_fit():
    pts, _ = scanned("chair-4leg", 7, 0.0, 0.0, 1.0)
    a = fit_object(pts, "chair", seed=3)
    b = fit_object(pts, "chair", seed=3)
    assert a.model == b.model and np.array_equal(a.pose, b.pose)


def test_blank_box_when_no_model_or_too_few_points():
    pts, _ = scanned("chair-4leg", 1, 0.0, 0.0, 0.0)
    fit = fit_object(pts, "lamp", seed=0)
    assert fit.blank and fit.model == "box" and "no model for label 'lamp'" in fit.reason
    assert math.isnan(fit.rms) and cad_dict(fit)["rms"] is None
    # The box stands around the points.
    assert fit.scale[2] == pytest.approx(pts[:, 2].max() - pts[:, 2].min(), abs=1e-9)
    few = fit_object(pts[:5], "chair", seed=0)
    assert few.blank and "5 points" in few.reason


def test_input_frame_pose_and_colour():
    # The input is in millimetres with y up and the floor at y = -1200 mm.
    frame = LevelFrame.from_dict({"up": [0, 1, 0], "ground_z": -1200.0, "scale": 0.001})
    pts, _ = scanned("chair-4leg", 1, 0.5, -0.25, 0.3)
    raw = frame.from_level(pts)
    np.testing.assert_allclose(frame.level(raw), pts, atol=1e-9)
    colors = np.tile(np.array([[200, 100, 50]], np.uint8), (len(pts), 1))
    fit = fit_object(frame.level(raw), "chair", frame=frame, colors=colors, seed=0)
    assert fit.color.tolist() == [200, 100, 50]
    # pose maps the model (metres) into the input (millimetres, y up).
    model = fit.cad_model.points(0.02) * fit.scale
    placed = model @ fit.pose[:3, :3].T + fit.pose[:3, 3]
    back = frame.level(placed)
    expected = model @ fit.level_pose[:3, :3].T + fit.level_pose[:3, 3]
    np.testing.assert_allclose(back, expected, atol=1e-6)
    up_in_input = fit.pose[:3, :3] @ [0.0, 0.0, 1.0]
    np.testing.assert_allclose(up_in_input / np.linalg.norm(up_in_input), [0, 1, 0], atol=1e-9)
    assert np.linalg.norm(up_in_input) == pytest.approx(1000.0)
    np.testing.assert_allclose(fit.up, [0, 1, 0], atol=1e-9)


def test_fit_object_rejects_bad_parameters():
    pts = np.zeros((30, 3))
    with pytest.raises(InvalidParameterError, match="'kernel'"):
        fit_object(pts, "chair", kernel="bisquare")
    with pytest.raises(InvalidParameterError, match="'points'"):
        fit_object(np.zeros((30, 2)), "chair")
    with pytest.raises(InvalidParameterError, match="'library'"):
        fit_object(pts, "chair", library={"a": 1})
    with pytest.raises(InvalidParameterError, match="'frame'"):
        LevelFrame.from_dict({"up": [0, 0, 0], "ground_z": 0, "scale": 1})


# -- detections ----------------------------------------------------------------------------


def test_fit_detections_through_the_detector(tiny):
    r, result = tiny
    fits = fit_detections(result, seed=0)
    assert [f.id for f in fits] == [d.id for d in result.detections]
    truth = {o.class_name: o for o in r.scene.objects if not o.is_structure}
    for f in fits:
        assert not f.blank
        gt = truth[f.label]
        assert math.hypot(f.x - gt.pose[0, 3], f.y - gt.pose[1, 3]) < 0.05
        period = 2 * math.pi
        if f.label == "table":  # modulo the table's symmetry: a square top has four
            w, d = gt.dimensions["width"], gt.dimensions["depth"]
            period = math.pi / 2 if abs(w - d) <= 0.05 * max(w, d) else math.pi
        assert angle_error(f.yaw, gt.yaw, period) < 5.0
        d = cad_dict(f)
        assert {"model", "pose", "rms", "scale", "inlier_fraction", "color"} <= set(d)
        json.dumps(d)


def test_low_scores_get_the_detection_box(tiny):
    _, result = tiny
    fits = fit_detections(result, min_score=0.99)
    for f, d in zip(fits, result.detections):
        assert f.blank and f.model == "box" and "below min_score" in f.reason
        np.testing.assert_allclose(f.scale, d.size, atol=1e-9)
        np.testing.assert_allclose(f.transform @ [0, 0, 0.5, 1], [*d.center, 1], atol=1e-9)
    with pytest.raises(InvalidParameterError, match="'min_score'"):
        fit_detections(result, min_score=2.0)


def test_fit_document_matches_fit_detections(tiny):
    _, result = tiny
    doc = json.loads(json.dumps(result.to_dict()))
    fits = fit_document(doc, result.cloud, seed=0)
    direct = fit_detections(result, seed=0)
    for a, b in zip(fits, direct):
        assert a.model == b.model
        assert np.abs(a.pose[:3, 3] - b.pose[:3, 3]).max() < 0.01
    with pytest.raises(InvalidParameterError, match="'cloud'"):
        fit_document(doc, result.cloud.select(np.arange(10)))


# -- the object map ------------------------------------------------------------------------


@pytest.fixture
def fits():
    lib = builtin_library()
    out = []
    for k, (kind, label, x) in enumerate(
        [("chair-4leg", "chair", 0.0), ("table-dining", "table", 2.0)]
    ):
        pts, _ = scanned(kind, k, x, 0.0, 0.2)
        out.append(
            fit_object(
                pts,
                label,
                lib,
                object_id=k + 1,
                seed=0,
                colors=np.full((len(pts), 3), 40 * (k + 1), np.uint8),
            )
        )
    out.append(fit_object(np.random.default_rng(0).random((50, 3)), "lamp", object_id=3))
    return out


def test_object_map_cloud(fits):
    cloud = object_map_cloud(fits, spacing=0.03)
    ids = np.asarray(cloud.fields["object"])
    assert set(ids.tolist()) == {1, 2, 3}
    assert np.all(cloud.rgb[ids == 1] == 40) and np.all(cloud.rgb[ids == 2] == 80)
    # The chair's full model stands on the floor where it was fitted.
    chair = cloud.xyz[ids == 1]
    assert chair[:, 2].min() == pytest.approx(0.0, abs=0.02)
    assert np.hypot(*(chair[:, :2].mean(axis=0) - [fits[0].x, fits[0].y])) < 0.1
    names = [m[0] for m in object_map_meshes(fits)]
    assert names == ["1-chair-chair-4leg", "2-table-table-rectangular", "3-lamp-box"]


def test_write_object_map(fits, tmp_path):
    files = write_object_map(fits, tmp_path / "map", spacing=0.03)
    cloud = read_cloud(files.points)
    assert len(cloud) == len(object_map_cloud(fits, spacing=0.03))
    assert "object" in cloud.fields and cloud.rgb is not None
    scene = trimesh.load(files.glb)
    assert set(scene.graph.nodes_geometry) == {
        "1-chair-chair-4leg",
        "2-table-table-rectangular",
        "3-lamp-box",
    }
    # glTF is y-up: the chair's height runs along y.
    lo, hi = scene.geometry["1-chair-chair-4leg"].bounds
    assert hi[1] - lo[1] == pytest.approx(fits[0].cad_model.dims["height"], rel=0.05)
    mesh = trimesh.load(files.mesh)
    assert len(mesh.faces) == sum(len(m[2]) for m in object_map_meshes(fits))
    assert mesh.bounds[1][2] == pytest.approx(
        max(f.transform[2, 2] * f.cad_model.dims["height"] + f.transform[2, 3] for f in fits),
        abs=0.01,
    )
    none = write_object_map([], tmp_path / "empty", glb=False, mesh=False)
    assert b"element vertex 0" in none.points.read_bytes() and none.glb is None
    # No object: the map and the mesh are empty, and there is no GLB (not a crash).
    empty = write_object_map([], tmp_path / "empty2")
    assert empty.glb is None and not (tmp_path / "empty2" / "object_map.glb").exists()
    assert empty.mesh is not None and empty.mesh.is_file()


def test_cad_dict_is_the_contract():
    fit = CadFit(
        4,
        "chair",
        "chair-4leg",
        np.eye(4),
        np.eye(4),
        np.ones(3),
        0.01,
        0.8,
        np.array([1, 2, 3], np.uint8),
    )
    d = cad_dict(fit)
    assert d["model"] == "chair-4leg" and d["pose"][3] == [0.0, 0.0, 0.0, 1.0]
    assert d["rms"] == 0.01 and d["blank"] is False and "reason" not in d
    assert ModelLibrary([builtin_library()["desk"]]).labels == ["table"]
