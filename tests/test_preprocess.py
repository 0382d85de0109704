"""Preparation: voxel grid and index map, denoising, gravity and floor, structure, scale."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from ontodetect import DataWarning, point_cloud
from ontodetect.config import Config
from ontodetect.errors import InvalidParameterError
from ontodetect.preprocess import (
    PreparedScene,
    denoise,
    estimate_normals,
    estimate_up,
    far_outlier_mask,
    find_floor,
    find_ground,
    guess_scale,
    level_transform,
    manhattan_axes,
    prepare,
    radius_outlier_mask,
    rotation_between,
    scale_from_travel,
    smooth_surface,
    statistical_outlier_mask,
    surface_scatter,
    voxelize,
)


# -- generated scenes ----------------------------------------------------------------------
def rect(rng, corner, u, v, spacing, noise=0.002):
    """Jittered grid on the parallelogram corner + s u + t v, s, t in [0, 1]."""
    corner, u, v = (np.asarray(a, dtype=float) for a in (corner, u, v))
    nu = max(2, int(np.linalg.norm(u) / spacing))
    nv = max(2, int(np.linalg.norm(v) / spacing))
    s, t = np.meshgrid((np.arange(nu) + rng.random(nu)) / nu, (np.arange(nv) + rng.random(nv)) / nv)
    pts = corner + s.reshape(-1, 1) * u + t.reshape(-1, 1) * v
    return pts + rng.normal(0, noise, pts.shape)


def box(rng, lo, hi, spacing):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    d = hi - lo
    ex, ey, ez = np.diag(d)
    # No bottom face: scanners never see the underside of furniture.
    faces = [(lo + ez, ex, ey), (lo, ex, ez), (lo + ey, ex, ez), (lo, ey, ez), (lo + ex, ey, ez)]
    return np.vstack([rect(rng, c, u, v, spacing) for c, u, v in faces])


def room(rng, spacing=0.03, size=(4.0, 3.0), height=2.5, ceiling=False):
    """Floor, four walls and two pieces of furniture; z up, floor at 0. Returns points, kinds."""
    w, d = size
    parts = {
        "floor": rect(rng, (0, 0, 0), (w, 0, 0), (0, d, 0), spacing),
        "wall": np.vstack(
            [
                rect(rng, (0, 0, 0), (w, 0, 0), (0, 0, height), spacing),
                rect(rng, (0, d, 0), (w, 0, 0), (0, 0, height), spacing),
                rect(rng, (0, 0, 0), (0, d, 0), (0, 0, height), spacing),
                rect(rng, (w, 0, 0), (0, d, 0), (0, 0, height), spacing),
            ]
        ),
        "furniture": np.vstack(
            [
                box(rng, (1.0, 1.0, 0.0), (2.2, 1.8, 0.75), spacing / 1.5),
                box(rng, (2.8, 0.8, 0.0), (3.3, 1.3, 0.45), spacing / 1.5),
            ]
        ),
    }
    if ceiling:
        parts["ceiling"] = rect(rng, (0, 0, height), (w, 0, 0), (0, d, 0), spacing)
    pts = np.vstack(list(parts.values()))
    kinds = np.concatenate([np.full(len(v), k) for k, v in parts.items()])
    return pts, kinds


def transform(points, R, t):
    return points @ np.asarray(R).T + np.asarray(t)


# -- voxel grid ----------------------------------------------------------------------------
def test_every_point_maps_to_the_voxel_containing_it(rng):
    pts = rng.random((5000, 3)) * [2.0, 1.0, 0.5] - 0.3
    g = voxelize(pts, 0.05)
    keys = np.floor((pts - g.origin) / g.size).astype(np.int64)
    assert np.array_equal(g.keys[g.point_to_voxel], keys)
    assert g.counts.sum() == len(pts)
    assert np.array_equal(np.bincount(g.point_to_voxel), g.counts)
    # Centres are the means of their points and lie in their voxel.
    for a in range(3):
        mean = np.bincount(g.point_to_voxel, pts[:, a]) / g.counts
        assert np.allclose(g.centers[:, a], mean)
    assert np.all(np.floor((g.centers - g.origin) / g.size) == g.keys)
    # points_of is the inverse of the map, in input order.
    for v in (0, len(g) // 2, len(g) - 1):
        assert np.array_equal(g.points_of([v]), np.flatnonzero(g.point_to_voxel == v))


def test_voxelize_colors_mask_and_order(rng):
    pts = rng.random((2000, 3))
    cols = rng.integers(0, 256, (2000, 3)).astype(np.uint8)
    mask = rng.random(2000) > 0.3
    g = voxelize(pts, 0.1, cols, mask=mask)
    assert np.all(g.point_to_voxel[~mask] == -1)
    assert g.counts.sum() == mask.sum()
    v = g.point_to_voxel[mask][0]
    members = mask & (g.point_to_voxel == v)
    assert np.array_equal(g.colors[v], np.rint(cols[members].mean(0)).astype(np.uint8))
    # The same voxels whatever the order of the points.
    perm = rng.permutation(2000)
    g2 = voxelize(pts[perm], 0.1, cols[perm], mask=mask[perm], origin=g.origin)
    assert np.array_equal(g.keys, g2.keys) and np.allclose(g.centers, g2.centers)
    assert np.array_equal(g.point_to_voxel[perm], g2.point_to_voxel)


def test_voxelize_rejects_bad_input():
    with pytest.raises(InvalidParameterError, match="'size'"):
        voxelize(np.zeros((3, 3)), 0)
    with pytest.raises(InvalidParameterError, match=r"'points'.*\(n, 3\)"):
        voxelize(np.zeros((3, 2)), 0.1)
    assert len(voxelize(np.zeros((0, 3)), 0.1)) == 0


# -- denoising -----------------------------------------------------------------------------
def test_outliers_at_known_indices_are_removed(rng):
    surface = rect(rng, (0, 0, 0), (2, 0, 0), (0, 2, 0), 0.01)
    specks = rng.random((20, 3)) * [2, 2, 0] + [0, 0, 0.5]  # isolated points above
    far = np.array([[40.0, 0, 0], [0, -30, 2]])
    pts = np.vstack([surface, specks, far])
    n = len(surface)
    keep = denoise(pts, voxel_size=0.02, method="both", radius=0.05)
    assert keep[:n].mean() > 0.995
    assert not keep[n:].any()
    assert not far_outlier_mask(pts)[-2:].any()
    assert statistical_outlier_mask(np.vstack([surface[::5], far]), 8, 2.0)[-2:].sum() == 0
    assert not radius_outlier_mask(np.vstack([surface[::5], far]), 0.05)[-2:].any()
    assert denoise(pts, method="none")[n : n + 20].all()  # no neighbourhood test


def test_denoise_keeps_the_edges_of_clean_surfaces():
    g = np.stack(np.meshgrid(np.arange(50), np.arange(50), [0]), -1).reshape(-1, 3) * 0.02
    assert statistical_outlier_mask(g, 8, 1.0).all()


def test_denoise_rejects_bad_method():
    with pytest.raises(InvalidParameterError, match="'method'"):
        denoise(np.zeros((4, 3)), method="median")


# -- gravity and floor ---------------------------------------------------------------------
def test_floor_found_when_not_at_zero(rng):
    pts, kinds = room(rng)
    scene = prepare(pts + [0.5, -1.0, 0.37])
    assert scene.floor_found
    assert scene.floor_z == pytest.approx(0.37, abs=0.01)
    assert np.allclose(scene.up, [0, 0, 1], atol=1e-3)
    z = scene.cloud.xyz[:, 2]
    assert np.abs(z[kinds == "floor"]).max() < 0.02
    top = scene.cloud.xyz[kinds == "furniture", 2].max()
    assert top == pytest.approx(0.75, abs=0.02)


def test_tilted_scan_is_levelled_on_its_floor(rng):
    pts, kinds = room(rng)
    R = Rotation.from_euler("xy", [6.0, -4.0], degrees=True).as_matrix()
    scene = prepare(transform(pts, R, [0, 0, 1.2]), up="z")  # drifted map, floor not at 0
    true_up = R @ [0, 0, 1]
    assert np.degrees(np.arccos(scene.up @ true_up)) < 0.5
    assert np.abs(scene.cloud.xyz[kinds == "floor", 2]).max() < 0.02
    assert scene.cloud.xyz[kinds == "furniture", 2].max() == pytest.approx(0.75, abs=0.02)


def test_camera_frame_up_is_estimated(rng):
    pts, kinds = room(rng)
    # A camera 1.3 m high looking along +x, pitched 20 degrees down: y down, z forward.
    world_to_cam = Rotation.from_euler("x", 20, degrees=True).as_matrix() @ np.array(
        [[0, -1, 0], [0, 0, -1], [1, 0, 0]], dtype=float
    )
    cam = transform(pts - [0.2, 1.5, 1.3], world_to_cam, [0, 0, 0])
    cloud = point_cloud(cam, meta={"width": 640, "height": 480})
    scene = prepare(cloud, up="auto")
    true_up = world_to_cam @ [0, 0, 1]
    assert np.degrees(np.arccos(scene.up @ true_up)) < 1.0
    assert scene.floor_z == pytest.approx(-1.3, abs=0.02)
    assert np.abs(scene.cloud.xyz[kinds == "floor", 2]).max() < 0.03


def test_up_auto_on_an_unknown_frame(rng):
    pts, _ = room(rng, ceiling=False)
    R = Rotation.from_euler("zyx", [30, 70, 10], degrees=True).as_matrix()
    up, confidence = estimate_up(transform(pts, R, [0, 0, 0]), hint=None)
    assert np.degrees(np.arccos(up @ (R @ [0, 0, 1]))) < 1.0
    assert 0 < confidence <= 1


def test_no_floor_falls_back_with_a_warning(rng):
    pts = box(rng, (0, 0, 1.0), (0.6, 0.6, 1.5), 0.01)  # a box floating in the air
    with pytest.warns(DataWarning, match="no floor found"):
        scene = prepare(pts)
    assert not scene.floor_found
    assert scene.cloud.xyz[:, 2].min() == pytest.approx(0.0, abs=0.01)


def test_manhattan_axes_and_rotations():
    R = Rotation.from_euler("zyx", [20, 10, 5], degrees=True).as_matrix()
    normals = np.repeat(np.eye(3), [60, 30, 10], axis=0) @ R.T
    axes = manhattan_axes(normals)
    assert np.allclose(np.abs(axes @ R), np.eye(3), atol=1e-9)
    for a, b in [([0, -1, 0], [0, 0, 1]), ([0, 0, -1], [0, 0, 1]), ([1, 2, 3], [0, 0, 1])]:
        M = rotation_between(a, b)
        assert np.allclose(M @ (np.array(a) / np.linalg.norm(a)), b)
        assert np.allclose(M @ M.T, np.eye(3)) and np.linalg.det(M) == pytest.approx(1.0)
    T = level_transform([0, 0, 1], 0.4, 2.0)
    assert np.allclose(T @ [1, 1, 0.2, 1], [2, 2, 0, 1])


def test_find_floor_on_arrays(rng):
    pts, _ = room(rng)
    fit = find_floor(pts + [0, 0, -0.25], [0, 0, 1])
    assert fit.found and fit.offset == pytest.approx(-0.25, abs=0.01)
    assert fit.area > 5.0


# -- structure and search volume -----------------------------------------------------------
def test_structure_and_object_mask(rng):
    pts, kinds = room(rng, ceiling=True)
    scene = prepare(pts + [0, 0, 0.3])
    label = np.full(len(scene.voxels) + 1, -1)
    label[:-1] = scene.structure_label
    per_point = label[scene.point_to_voxel]
    assert np.mean(per_point[kinds == "floor"] == 1) > 0.95
    assert np.mean(per_point[kinds == "wall"] == 2) > 0.9
    assert np.mean(per_point[kinds == "ceiling"] == 3) > 0.95
    furniture = np.mean(
        np.append(scene.object_mask, False)[scene.point_to_voxel][kinds == "furniture"]
    )
    assert furniture > 0.9
    kinds_found = sorted({p.kind for p in scene.structure_planes})
    assert kinds_found == ["ceiling", "floor", "wall"]
    assert sum(p.kind == "wall" for p in scene.structure_planes) == 4
    # Nothing above the altitude cut-off is searched.
    assert scene.centers[scene.object_mask, 2].max() <= 1.4


#: Walls as tall as a scan that stops low (off by default: docs/benchmarks.md, "Walls in
#: a scan that stops low").
LOW_SCAN = Config().with_overrides(["prepare.low_scan_walls=true"])


@pytest.mark.parametrize("top", [1.3, 1.45])
def test_a_small_room_scanned_only_to_chest_height_has_its_walls(rng, top):
    # A bathroom seen by a sensor that stops at 1.3-1.45 m: its walls reach no higher than
    # the scan, a bath and a WC stand against them and the corridor shows through the door
    # (so a wall is not a low wall with nothing behind it). Every wall is still wall, and
    # what stands against one is not joined to it.
    w, d = 3.6, 2.1
    walls = [  # the wall at y = 0 has a door, and the corridor shows through it
        rect(rng, (0, 0, 0), (1.4, 0, 0), (0, 0, top), 0.03),
        rect(rng, (2.2, 0, 0), (w - 2.2, 0, 0), (0, 0, top), 0.03),
        rect(rng, (0, d, 0), (w, 0, 0), (0, 0, top), 0.03),
        rect(rng, (0, 0, 0), (0, d, 0), (0, 0, top), 0.03),
        rect(rng, (w, 0, 0), (0, d, 0), (0, 0, top), 0.03),
    ]
    bath = box(rng, (0.0, d - 0.7, 0.0), (1.8, d, 0.55), 0.02)
    wc = box(rng, (2.8, d - 0.6, 0.0), (3.2, d, 0.75), 0.02)
    floor = rect(rng, (0, 0, 0), (w, 0, 0), (0, d, 0), 0.03)
    corridor = np.vstack(
        [
            rect(rng, (1.2, -0.8, 0), (1.2, 0, 0), (0, 0.8, 0), 0.03),
            rect(rng, (1.2, -0.8, 0), (1.2, 0, 0), (0, 0, top), 0.03),
        ]
    )
    pts = np.vstack([floor, *walls, bath, wc, corridor])
    kinds = np.repeat(
        ["floor", "wall", "furniture", "corridor"],
        [len(floor), sum(map(len, walls)), len(bath) + len(wc), len(corridor)],
    )
    # By default a wall must reach 1.5 m: the one with the door, the corridor behind it,
    # is lost.
    plain = prepare(pts)
    default = np.append(plain.structure_label, -1)[plain.point_to_voxel]
    assert np.mean(default[kinds == "wall"] == 2) < 0.9
    scene = prepare(pts, LOW_SCAN)
    assert sum(p.kind == "wall" for p in scene.structure_planes) >= 4
    label = np.append(scene.structure_label, -1)[scene.point_to_voxel]
    assert np.mean(label[kinds == "wall"] == 2) > 0.9
    # What of the bath and the WC stands off the wall (all but their backs) is not wall.
    x, y = pts[:, 0], pts[:, 1]
    off_wall = (kinds == "furniture") & (y < d - 0.06) & (x > 0.06) & (x < w - 0.06)
    assert np.mean(label[off_wall] == 0) > 0.95


def test_a_cabinet_in_a_room_scanned_to_chest_height_is_no_wall(rng):
    # Lowering the top a wall must reach to the scan's own top does not make a free-standing
    # cabinet a wall: the room lies behind it as well as in front.
    pts, _ = room(rng, size=(5.0, 4.0))
    cabinet = box(rng, (2.0, 1.8, 0.0), (3.2, 2.3, 1.3), 0.02)
    pts = np.vstack([pts[pts[:, 2] <= 1.4], cabinet])
    scene = prepare(pts, LOW_SCAN)
    walls = [p for p in scene.structure_planes if p.kind == "wall"]
    assert len(walls) == 4
    assert all(
        min(abs(p.offset), abs(abs(p.offset) - 4.0), abs(abs(p.offset) - 5.0)) < 0.1 for p in walls
    )


def test_walls_do_not_depend_on_where_the_scan_sits(rng):
    # Walls a little out of true (a drifting scan): each cell's normal is off by a degree
    # or so, which must not split or lose a wall when the scan sits far from the origin.
    pts, _ = room(rng, size=(6.0, 5.0))
    pts = pts + rng.normal(0.0, 0.002, pts.shape)
    near = prepare(pts)
    far = prepare(pts + [40.0, -25.0, 0.0])
    for scene in (near, far):
        assert sum(p.kind == "wall" for p in scene.structure_planes) == 4
    assert np.mean(near.structure_label == far.structure_label) > 0.999
    offsets = sorted(float(p.offset) for p in near.structure_planes)
    moved = sorted(float(p.offset - p.normal[:2] @ [40.0, -25.0]) for p in far.structure_planes)
    assert offsets == pytest.approx(moved, abs=1e-3)


@pytest.mark.xfail(
    strict=True,
    reason="walls found move with a 0.7 degree turn (docs/benchmarks.md, 'Walls under a "
    "small turn'): the histogram's bins, not the wall, choose the cells",
)
@pytest.mark.parametrize("seed", range(2))
def test_a_small_turn_finds_the_same_walls(seed):
    # A room scanned to 1.5 m whose walls are a little out of true and not quite flat, one
    # of them showing only between two tall cupboards. The vote's passes turn the scan by
    # 0.7 degrees: the walls found, and the points taken as wall, should not change with it.
    rng = np.random.default_rng(seed)
    w, d, top = 6.0, 5.0, 1.5
    walls = [
        rect(rng, (0, 0, 0), (w, 0, 0), (0, 0, top), 0.03),
        rect(rng, (0, d, 0), (w, 0, 0), (0, 0, top), 0.03),
        rect(rng, (0, 0, 0), (0, d, 0), (0, 0, top), 0.03),
        rect(rng, (w, 1.8, 0), (0, 1.4, 0), (0, 0, top), 0.03),
    ]
    floor = rect(rng, (0, 0, 0), (w, 0, 0), (0, d, 0), 0.03)
    stuff = [
        box(rng, (1.0, 1.0, 0.0), (2.2, 1.8, 0.75), 0.02),
        box(rng, (0.0, 2.5, 0.0), (0.5, 3.7, 1.2), 0.02),
        box(rng, (w - 0.6, 0.0, 0.0), (w, 1.8, 2.0), 0.03),
        box(rng, (w - 0.6, 3.2, 0.0), (w, d, 2.0), 0.03),
    ]
    pts = np.vstack([floor, *walls, *stuff])
    pts += rng.normal(0.0, 0.004, pts.shape)
    pts[:, :2] += 0.01 * np.sin(3.0 * pts[:, 2:3] + pts[:, :1])
    found, labels = [], []
    for turn in (0.0, 0.7, -0.7):
        scene = prepare(pts, Config().with_overrides([f"prepare.turn={turn}"]))
        found.append(sum(p.kind == "wall" for p in scene.structure_planes))
        labels.append(np.append(scene.structure_label, -1)[scene.point_to_voxel] == 2)
    # The four walls, the cupboards' backs on the fourth; their fronts have a wall behind.
    assert found == [4, 4, 4]
    for other in labels[1:]:
        assert np.mean(labels[0] != other) < 0.005


def test_altitude_cutoff_is_configurable(rng):
    pts, _ = room(rng)
    cfg = Config().with_overrides(["prepare.altitude_cutoff=0.5"])
    scene = prepare(pts, cfg)
    assert scene.centers[scene.object_mask, 2].max() <= 0.5


# -- scale ---------------------------------------------------------------------------------
def test_scale_recovery(rng):
    pts, _ = room(rng, spacing=0.05)
    assert scale_from_travel(10.0, 4.0) == 2.5
    with pytest.raises(InvalidParameterError, match="'slam_distance'"):
        scale_from_travel(1.0, 0.0)
    mm = prepare(pts * 1000.0)
    assert mm.scale == 0.001 and mm.info["scale_source"] == "units"
    assert guess_scale(pts) == 1.0
    half = prepare(pts * 0.5, travelled=(2.0, 1.0))
    assert half.scale == 2.0
    assert half.cloud.xyz[:, 2].max() == pytest.approx(2.5, abs=0.02)
    given = prepare(pts, scale=1.0)
    assert given.info["scale_source"] == "given"
    with pytest.raises(InvalidParameterError, match="'scale'"):
        prepare(pts, scale=-1.0)


# -- the prepared scene --------------------------------------------------------------------
def test_prepared_scene_maps_back_exactly(rng):
    pts, _ = room(rng)
    pts = np.vstack([pts, [[50.0, 50.0, 50.0]]])  # one far outlier
    cloud = point_cloud(pts)
    scene = prepare(cloud)
    assert isinstance(scene, PreparedScene)
    assert len(scene.cloud) == len(pts) == len(scene.point_to_voxel)
    assert not scene.inliers[-1] and scene.point_to_voxel[-1] == -1
    assert np.array_equal(scene.inliers, scene.point_to_voxel >= 0)
    # Levelled coordinates go back to the input exactly.
    assert np.allclose(scene.from_level(scene.cloud.xyz), pts, atol=1e-9)
    assert np.allclose(scene.level(pts), scene.cloud.xyz, atol=1e-9)
    obj = np.flatnonzero(scene.object_mask)
    idx = scene.points_of(obj)
    assert np.all(scene.object_mask[scene.point_to_voxel[idx]])
    summary = scene.summary()
    assert summary["num_points"] == len(pts) and summary["floor_found"]


def test_prepare_does_not_modify_input_and_is_deterministic(rng):
    pts, _ = room(rng)
    cloud = point_cloud(pts)
    before = cloud.xyz.copy()
    a = prepare(cloud)
    b = prepare(cloud)
    assert np.array_equal(cloud.xyz, before)
    assert np.array_equal(a.cloud.xyz, b.cloud.xyz)
    assert np.array_equal(a.point_to_voxel, b.point_to_voxel)
    assert np.array_equal(a.structure_label, b.structure_label)


def test_a_shared_ground_gives_the_same_scene_at_every_turn(rng):
    """Passes that differ in their turn share one find_ground; each comes out as if it had
    prepared the scan alone."""
    pts, _ = room(rng)
    tilted = transform(pts, Rotation.from_euler("x", 8, degrees=True).as_matrix(), (0, 0, 0.6))
    cloud = point_cloud(tilted)
    ground = find_ground(cloud, up="auto")
    assert ground.num_points == len(pts) and ground.floor.found
    for turn in (0.0, 0.7, -12.0):
        cfg = Config().replace(prepare={"turn": turn})
        alone, shared = prepare(cloud, cfg, up="auto"), prepare(cloud, cfg, ground=ground)
        assert np.array_equal(alone.to_level, shared.to_level)
        assert np.array_equal(alone.cloud.xyz, shared.cloud.xyz)
        assert np.array_equal(alone.point_to_voxel, shared.point_to_voxel)
        assert np.array_equal(alone.structure_label, shared.structure_label)
        assert np.array_equal(alone.object_mask, shared.object_mask)
    with pytest.raises(InvalidParameterError, match="'ground'"):
        prepare(point_cloud(pts[:-5]), ground=ground)


def test_prepare_rejects_empty_and_bad_up():
    with pytest.raises(InvalidParameterError, match="'cloud'"):
        prepare(np.zeros((0, 3)))
    with pytest.raises(InvalidParameterError, match="'up'"):
        prepare(np.random.default_rng(0).random((100, 3)), up="w")


def test_bent_floor_is_followed(rng):
    pts, kinds = room(rng)
    bent = pts.copy()
    bent[:, 2] += 0.02 * (bent[:, 0] - 2.0) ** 2  # the floor rises 8 cm towards two walls
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene = prepare(bent)
    floor = scene.cloud.xyz[kinds == "floor", 2]
    assert np.abs(floor).max() < 0.03
    assert scene.info["floor_warp"] > 0.05


def test_normals_and_smoothing(rng):
    plane = rect(rng, (0, 0, 0), (1, 0, 0), (0, 1, 0), 0.01, noise=0.002)
    normals, _ = estimate_normals(plane, 16)
    assert np.mean(normals[:, 2] > 0.95) > 0.95
    smooth = smooth_surface(plane, 16)
    assert smooth[:, 2].std() < 0.5 * plane[:, 2].std()


@pytest.mark.parametrize("sigma", [0.002, 0.006, 0.012])
def test_surface_scatter_is_the_noise_of_a_flat_floor(sigma):
    rng = np.random.default_rng(3)
    floor = rect(rng, (0, 0, 0), (4, 0, 0), (0, 3, 0), 0.03, noise=0.0)
    noisy = floor + np.c_[np.zeros((len(floor), 2)), rng.normal(0, sigma, len(floor))]
    assert surface_scatter(noisy) == pytest.approx(sigma, rel=0.15)


def test_surface_scatter_ignores_a_floor_registered_twice_over_a_third_of_it():
    # A SLAM map that closed its loop late keeps a copy of part of the floor a few cm up:
    # the cells holding both layers scatter more, the median cell does not.
    rng = np.random.default_rng(4)
    floor = rect(rng, (0, 0, 0), (4, 0, 0), (0, 3, 0), 0.03, noise=0.003)
    copy = rect(rng, (0, 0, 0.05), (4, 0, 0), (0, 1, 0), 0.03, noise=0.003)
    assert surface_scatter(np.vstack([floor, copy])) == pytest.approx(0.003, rel=0.25)
    assert surface_scatter(floor[:5]) is None


def test_surface_scatter_is_not_read_off_a_floor_barely_seen():
    # Most of the floor lost: the cells that still hold points are those of the chair legs
    # and boxes standing on it, not the floor's noise.
    rng = np.random.default_rng(7)
    floor = rect(rng, (0, 0, 0), (4, 0, 0), (0, 3, 0), 0.03, noise=0.003)
    kept = floor[rng.random(len(floor)) < 0.05]
    legs = np.vstack(
        [
            rect(rng, (x, y, 0), (0.05, 0, 0), (0, 0, 0.03), 0.004)
            for x, y in rng.uniform(0.2, 2.8, size=(40, 2))
        ]
    )
    assert surface_scatter(np.vstack([floor, legs])) == pytest.approx(0.003, rel=0.3)
    assert surface_scatter(np.vstack([kept, legs])) is None


@given(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3), st.floats(-5.0, 5.0))
def test_surface_scatter_does_not_depend_on_where_the_floor_lies(dx, dy, dz):
    rng = np.random.default_rng(5)
    floor = rect(rng, (0, 0, 0), (2, 0, 0), (0, 2, 0), 0.03, noise=0.005)
    moved = surface_scatter(floor + [dx, dy, dz])
    assert moved == pytest.approx(surface_scatter(floor), rel=1e-3)


@pytest.mark.parametrize(
    ("sigma", "settings", "smoothed"),
    [
        (0.003, [], False),
        (0.014, [], True),
        (0.014, ["prepare.auto_smoothing=false"], False),
        (0.003, ["prepare.smoothing=true"], True),
    ],
)
def test_a_scan_as_noisy_as_the_inlier_distance_is_smoothed(sigma, settings, smoothed):
    # 1.4 cm of scatter leaves 52 % of a plane's points within the 1 cm inlier distance,
    # 3 mm leaves all of them.
    rng = np.random.default_rng(6)
    pts, _ = room(rng)
    noisy = pts + rng.normal(0, sigma, pts.shape)
    scene = prepare(noisy, config=Config().with_overrides(settings))
    assert scene.info["floor_scatter"] == pytest.approx(sigma, rel=0.25)
    assert scene.info["smoothed"] is smoothed


def test_turn_rotates_the_levelled_frame_only(rng):
    pts, _ = room(rng)
    plain = prepare(pts)
    turned = prepare(pts, Config().replace(prepare={"turn": 30.0}))
    a = np.radians(30.0)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    assert np.allclose(turned.cloud.xyz[:, :2], plain.cloud.xyz[:, :2] @ rot.T, atol=1e-9)
    assert np.allclose(turned.cloud.xyz[:, 2], plain.cloud.xyz[:, 2], atol=1e-9)
    assert np.allclose(turned.from_level(turned.cloud.xyz), pts, atol=1e-9)
    assert sum(p.kind == "wall" for p in turned.structure_planes) == 4


def test_far_scan_is_prepared_in_a_local_frame():
    # A room 400 km from its origin, as in UTM coordinates: the same floor and levelled
    # cloud as the room at home, and levelling still maps the input frame.
    from ontodetect.preprocess import local_origin

    rng = np.random.default_rng(5)
    floor = np.c_[rng.random((6000, 2)) * 4, rng.normal(0, 0.002, 6000)]
    box = np.c_[rng.random((900, 2)) * 0.5 + 1, rng.random(900) * 0.45]
    home = np.vstack([floor, box])
    offset = np.array([4e5, 5.2e6, 30.0])
    assert local_origin(home).tolist() == [0.0, 0.0, 0.0]
    assert local_origin(home + offset).tolist() == [400002.0, 5200002.0, 0.0]
    near = prepare(home)
    far = prepare(home + offset)
    assert far.floor_z == pytest.approx(near.floor_z + 30.0, abs=1e-3)
    np.testing.assert_allclose(far.level(home + offset)[:, 2], near.level(home)[:, 2], atol=1e-3)
    assert int(far.object_mask.sum()) == int(near.object_mask.sum())


def test_far_scan_gives_the_same_detections():
    from ontodetect import detect, point_cloud
    from ontodetect.synth import synthesize

    cloud = synthesize("tiny", seed=2).cloud
    moved = point_cloud(cloud.xyz + [4e5, 4e5, 0.0], rgb=cloud.rgb)
    a, b = detect(cloud), detect(moved)
    assert [d.label for d in a.detections] == [d.label for d in b.detections]
    for da, db in zip(a.detections, b.detections):
        np.testing.assert_array_equal(da.point_indices, db.point_indices)
        np.testing.assert_allclose(db.center[:2], np.add(da.center[:2], 4e5), atol=1e-3)
