"""Virtual sensors: noise models, labels, occlusion, organized frames, scale recovery."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ontodetect.errors import InvalidParameterError
from ontodetect.synth import sensors
from ontodetect.synth.scene import OrientedBox, Scene, SceneObject, yaw_pose
from ontodetect.synth.sensors import (
    RGBDSensor,
    camera_trajectory,
    scan_monocular_slam,
    scan_rgbd_frame,
    scan_rgbd_trajectory,
    scan_tls,
    tls_stations,
)

# -- scenes made of boxes ---------------------------------------------------------------
_CORNERS = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
_FACES = np.array(
    [
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ],
    np.int32,
)


def box_object(iid, cls, center, size, yaw=0.0, color=(150, 120, 90)):
    """A closed box mesh with outward normals, standing at ``center`` (its middle)."""
    center, size = np.asarray(center, float), np.asarray(size, float)
    pose = yaw_pose(center[0], center[1], yaw, center[2] - size[2] / 2)
    verts = (_CORNERS * size + [0, 0, size[2] / 2]) @ pose[:3, :3].T + pose[:3, 3]
    return SceneObject(
        iid,
        cls,
        "box",
        verts,
        _FACES.copy(),
        np.zeros(12, np.int32),
        ["body"],
        np.tile(np.array(color, np.uint8), (12, 1)),
        pose,
        {"width": size[0], "depth": size[1], "height": size[2]},
        OrientedBox(tuple(center), tuple(size), yaw),
    )


def box_room(furniture=(), size=(4.0, 3.0, 2.6), room_type="office"):
    """Floor, four walls and a ceiling (ids 1-6) around ``furniture``."""
    L, W, H = size
    t = 0.1
    grey = (215, 215, 205)
    objects = [
        box_object(1, "floor", (L / 2, W / 2, -t / 2), (L, W, t), color=(120, 110, 100)),
        box_object(2, "wall", (-t / 2, W / 2, H / 2), (t, W, H), color=grey),
        box_object(3, "wall", (L + t / 2, W / 2, H / 2), (t, W, H), color=grey),
        box_object(4, "wall", (L / 2, -t / 2, H / 2), (L, t, H), color=grey),
        box_object(5, "wall", (L / 2, W + t / 2, H / 2), (L, t, H), color=grey),
        box_object(6, "ceiling", (L / 2, W / 2, H + t / 2), (L, W, t), color=(240, 240, 240)),
    ]
    return Scene(room_type, size, objects + list(furniture), 0)


def furnished_room():
    return box_room(
        [
            box_object(7, "table", (2.0, 1.5, 0.375), (1.2, 0.8, 0.75), 0.1, (140, 90, 50)),
            box_object(8, "chair", (2.0, 0.7, 0.45), (0.45, 0.45, 0.9), 0.3, (40, 40, 40)),
            box_object(9, "cabinet", (0.3, 2.6, 0.6), (0.5, 0.6, 1.2), 0.0, (200, 200, 200)),
        ]
    )


def looking_along_x(position):
    """Camera at ``position`` looking along world +x (camera x = world -y, y = world -z)."""
    T = np.eye(4)
    T[:3, :3] = np.column_stack([(0, -1, 0), (0, 0, -1), (1, 0, 0)])
    T[:3, 3] = position
    return T


def wall_scene(distance):
    """One big wall whose face is the plane x = distance."""
    wall = box_object(1, "wall", (distance + 0.05, 0.0, 1.5), (0.1, 30.0, 30.0))
    return Scene("office", (10.0, 10.0, 3.0), [wall], 0)


def point_depths(out):
    """Depth of every fused point along the optical axis of the frame that saw it."""
    pose = out.poses[out.cloud.fields["frame"]]
    return np.einsum("ni,ni->n", out.cloud.xyz - pose[:, :3, 3], pose[:, :3, 2])


# -- noise models -------------------------------------------------------------------------
@pytest.mark.parametrize("distance", [1.0, 2.5, 4.0])
@pytest.mark.parametrize("disparity_step", [0.125, 0.0])
def test_rgbd_noise_matches_model_on_flat_wall(distance, disparity_step):
    out = scan_rgbd_frame(
        wall_scene(distance),
        pose=looking_along_x((0, 0, 1.5)),
        stride=4,
        disparity_step=disparity_step,
        rng=5,
    )
    offset = out.world_cloud().xyz[:, 0] - distance
    expected = RGBDSensor().sigma(distance)
    assert len(offset) > 15_000  # a frontal wall fills the image
    assert abs(offset.std() / expected - 1) < 0.15
    assert abs(offset.mean()) < 3 * expected / np.sqrt(len(offset)) + 0.1 * expected


def test_rgbd_custom_noise_model():
    out = scan_rgbd_frame(
        wall_scene(3.0),
        pose=looking_along_x((0, 0, 1.5)),
        stride=4,
        noise=(0.004, 0.0),
        disparity_step=0.0,
        rng=1,
    )
    assert abs(out.world_cloud().xyz[:, 0].std() / 0.004 - 1) < 0.15


@pytest.mark.parametrize("sigma", [0.002, 0.005])
def test_tls_range_noise_matches_sigma_on_flat_wall(sigma):
    station = np.eye(4)
    station[2, 3] = 1.5
    out = scan_tls(
        wall_scene(2.0),
        stations=station[None],
        h_res_deg=0.5,
        v_res_deg=0.5,
        noise_sigma=sigma,
        rng=3,
    )
    rel = out.cloud.xyz - station[:3, 3]
    # Near the wall's normal the range noise is (almost) the distance to the plane.
    frontal = rel[:, 0] / np.linalg.norm(rel, axis=1) > np.cos(np.radians(10))
    assert frontal.sum() > 1000
    offset = out.cloud.xyz[frontal, 0] - 2.0
    assert abs(offset.std() / sigma - 1) < 0.15


def test_sigma_and_quantum_follow_the_kinect_model():
    cam = RGBDSensor()
    a, b = sensors.KINECT_NOISE
    assert cam.sigma(3.0) == pytest.approx(a + b * 9)
    # Kinect v1: about 7 cm depth resolution at 5 m (Khoshelham & Elberink 2012).
    assert 0.05 < cam.quantum(5.0) < 0.09
    assert RGBDSensor(disparity_step=0).quantum(5.0) == 0


# -- single organized frame ---------------------------------------------------------------
def test_frame_is_organized_in_the_camera_frame():
    out = scan_rgbd_frame(wall_scene(2.0), pose=looking_along_x((0, 0, 1.5)), rng=0)
    cloud = out.cloud
    assert out.frame == "camera" and out.sensor == "rgbd-frame"
    assert (cloud.meta["width"], cloud.meta["height"], cloud.meta["organized"]) == (640, 480, True)
    assert np.all(np.diff(cloud.index) > 0) and cloud.index.max() < 640 * 480
    assert np.all(cloud.xyz[:, 2] > 1.8)
    # Pixel (u, v) sees the direction ((u - cx) / fx, (v - cy) / fy, 1): x right, y down.
    u, v = cloud.index % 640, cloud.index // 640
    ray = cloud.xyz[:, :2] / cloud.xyz[:, 2:3]
    assert np.allclose(ray[:, 0], (u - 319.5) / 525.0)
    assert np.allclose(ray[:, 1], (v - 239.5) / 525.0)
    world = out.world_cloud()
    assert np.allclose(world.xyz[:, 0], 2.0, atol=0.05)
    # Image right is world -y, image down is world -z for this pose.
    right = u > 400
    assert np.all(world.xyz[right, 1] < 0)
    assert np.all(world.xyz[v > 300, 2] < 1.5)


def test_frame_default_pose_sees_the_furniture():
    out = scan_rgbd_frame(furnished_room(), stride=4, rng=2)
    seen = set(np.unique(out.cloud.fields["instance"]).tolist())
    assert {7, 8} <= seen


def test_grazing_rays_return_nothing():
    floor = box_object(1, "floor", (5.0, 0.0, -0.05), (10.0, 10.0, 0.1))
    scene = Scene("office", (10.0, 10.0, 3.0), [floor], 0)
    pose = looking_along_x((0.0, 0.0, 0.6))
    wide = scan_rgbd_frame(
        scene, pose=pose, stride=4, max_incidence_deg=90, max_range=8.0, baseline=0, rng=0
    )
    narrow = scan_rgbd_frame(scene, pose=pose, stride=4, max_range=8.0, baseline=0, rng=0)
    assert len(narrow.cloud) < len(wide.cloud)
    # Incidence on the floor: angle between the ray and the vertical.
    ray = narrow.world_cloud().xyz - pose[:3, 3]
    incidence = np.degrees(np.arccos(-ray[:, 2] / np.linalg.norm(ray, axis=1)))
    assert incidence.max() <= 75.0 + 0.5  # half a degree for the depth noise


def test_projector_shadow_hides_background_left_of_an_edge():
    wall = box_object(1, "wall", (3.05, 0.0, 1.5), (0.1, 10.0, 10.0))
    block = box_object(2, "box", (1.5, 0.0, 1.5), (0.3, 0.4, 0.4))
    scene = Scene("office", (10.0, 10.0, 3.0), [wall, block], 0)
    pose = looking_along_x((0.0, 0.0, 1.5))
    common = {"pose": pose, "stride": 2, "edge_dropout": 0.0, "rng": 0}
    lit = scan_rgbd_frame(scene, baseline=0.0, **common)
    shadowed = scan_rgbd_frame(scene, baseline=0.075, **common)
    lost = np.setdiff1d(lit.cloud.index, shadowed.cloud.index)
    assert len(lost) > 50
    lost_instance = lit.cloud.fields["instance"][np.isin(lit.cloud.index, lost)]
    assert np.all(lost_instance == 1)  # only the wall behind loses points
    # The projector sits on the camera's right: its shadow falls left of the block.
    block_u = (shadowed.cloud.index % 320)[shadowed.cloud.fields["instance"] == 2]
    assert np.all(lost % 320 < block_u.min())


# -- labels -------------------------------------------------------------------------------
def _assert_labels_consistent(scene, out, tolerance):
    _, triangles, tri_instance, _ = scene.combined_mesh()
    vertices = scene.combined_mesh()[0]
    tri = out.triangle
    inst = out.cloud.fields["instance"]
    cls = out.cloud.fields["class_id"]
    assert len(tri) == len(out.cloud)
    hit = tri >= 0
    assert np.array_equal(inst[hit], tri_instance[tri[hit]])
    for obj in scene.objects:
        mine = inst == obj.instance_id
        assert np.all(cls[mine] == obj.class_id)
        assert np.all(
            obj.box.contains(
                out.world_cloud().xyz[mine] / out.scale, margin=float(np.max(tolerance))
            )
        )
    # Every point lies on the plane of the triangle it is labelled with (within the noise).
    v0 = vertices[triangles[tri[hit], 0]]
    n = np.cross(vertices[triangles[tri[hit], 1]] - v0, vertices[triangles[tri[hit], 2]] - v0)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    dist = np.abs(np.einsum("ij,ij->i", out.world_cloud().xyz[hit] / out.scale - v0, n))
    assert np.all(dist <= np.broadcast_to(tolerance, hit.shape)[hit])


def test_rgbd_labels_match_the_triangle_hit_and_boxes():
    scene = furnished_room()
    out = scan_rgbd_trajectory(scene, num_frames=6, stride=8, rng=4)
    cam = RGBDSensor()
    depth = point_depths(out)
    assert len(out.cloud) > 10_000
    _assert_labels_consistent(scene, out, 5 * cam.sigma(depth) + cam.quantum(depth))
    counts = np.bincount(out.cloud.fields["instance"], minlength=10)
    assert np.all(counts[[7, 8, 9]] > 100)  # every piece of furniture is seen


def test_tls_labels_and_fields():
    scene = furnished_room()
    out = scan_tls(scene, stations=2, h_res_deg=2.0, v_res_deg=2.0, rng=1)
    _assert_labels_consistent(scene, out, 6 * 0.002)
    intensity = out.cloud.fields["intensity"]
    assert intensity.dtype == np.float32 and intensity.min() >= 0 and intensity.max() <= 1
    assert set(np.unique(out.cloud.fields["station"]).tolist()) == {0, 1}
    assert np.allclose(out.poses[:, 2, 3], sensors.TRIPOD_HEIGHT)
    for box in (o.box for o in scene.objects if not o.is_structure):
        feet = np.column_stack([out.poses[:, :2, 3], np.full(2, box.center[2])])
        assert not box.contains(feet).any()  # no tripod stands on furniture


def test_tls_result_does_not_depend_on_chunking(monkeypatch):
    scene = furnished_room()
    kwargs = {
        "stations": 1,
        "h_res_deg": 3.0,
        "v_res_deg": 3.0,
        "noise_sigma": 0.0,
        "color_noise": 0.0,
        "rng": 2,
    }
    whole = scan_tls(scene, **kwargs)
    monkeypatch.setattr(sensors, "CHUNK_RAYS", 997)
    chunked = scan_tls(scene, **kwargs)
    assert np.array_equal(whole.cloud.xyz, chunked.cloud.xyz)
    assert np.array_equal(whole.cloud.fields["instance"], chunked.cloud.fields["instance"])


def test_hidden_object_gets_no_points_and_occluded_fewer():
    occluder = box_object(1, "cabinet", (2.0, 0.0, 0.5), (0.2, 1.0, 1.0))
    hidden = box_object(2, "box", (3.0, 0.0, 0.5), (0.3, 0.3, 0.3))
    partly = box_object(3, "box", (3.0, -0.75, 0.5), (0.3, 0.3, 0.3))
    visible = box_object(4, "box", (3.0, 1.2, 0.5), (0.3, 0.3, 0.3))
    wall = box_object(5, "wall", (4.05, 0.0, 1.5), (0.1, 10.0, 10.0))
    scene = Scene("office", (5.0, 5.0, 3.0), [occluder, hidden, partly, visible, wall], 0)
    out = scan_rgbd_frame(scene, pose=looking_along_x((0.0, 0.0, 0.5)), stride=2, rng=0)
    counts = np.bincount(out.cloud.fields["instance"], minlength=6)
    assert counts[2] == 0
    assert counts[4] > 200
    assert 0 < counts[3] < counts[4]


# -- fusion, drift, determinism -------------------------------------------------------------
def test_voxel_fusion_keeps_one_point_per_voxel():
    scene = furnished_room()
    dense = scan_rgbd_trajectory(scene, num_frames=4, stride=8, rng=1)
    fused = scan_rgbd_trajectory(scene, num_frames=4, stride=8, voxel=0.05, rng=1)
    assert len(fused.cloud) < len(dense.cloud)
    cells = np.floor(fused.cloud.xyz / 0.05)
    # Averages of points from one voxel stay apart by construction, at most a voxel each way.
    assert len(np.unique(cells, axis=0)) > 0.5 * len(fused.cloud)
    _assert_labels_consistent(scene, fused, 0.05 * np.sqrt(3) + 0.2)


def test_drift_changes_the_fused_poses_only():
    scene = furnished_room()
    still = scan_rgbd_trajectory(scene, num_frames=5, stride=16, rng=3)
    drifting = scan_rgbd_trajectory(scene, num_frames=5, stride=16, drift=0.02, rng=3)
    assert np.array_equal(still.poses, still.estimated_poses)
    assert np.array_equal(still.poses, drifting.poses)
    assert np.array_equal(drifting.estimated_poses[0], drifting.poses[0])
    gap = np.linalg.norm(drifting.estimated_poses[1:, :3, 3] - drifting.poses[1:, :3, 3], axis=1)
    assert np.all(gap > 0)
    assert drifting.parameters["drift"] == 0.02


@pytest.mark.parametrize(
    ("scan", "kwargs"),
    [
        (scan_rgbd_trajectory, {"num_frames": 3, "stride": 16}),
        (scan_rgbd_frame, {"stride": 8}),
        (scan_tls, {"stations": 2, "h_res_deg": 4.0, "v_res_deg": 4.0}),
        (scan_monocular_slam, {"num_frames": 3, "stride": 8}),
    ],
)
def test_same_seed_same_points(scan, kwargs):
    scene = furnished_room()
    a, b = scan(scene, rng=11, **kwargs), scan(scene, rng=11, **kwargs)
    c = scan(scene, rng=12, **kwargs)
    assert np.array_equal(a.cloud.xyz, b.cloud.xyz)
    assert np.array_equal(a.cloud.rgb, b.cloud.rgb)
    assert np.array_equal(a.cloud.fields["instance"], b.cloud.fields["instance"])
    assert len(a.cloud) != len(c.cloud) or not np.array_equal(a.cloud.xyz, c.cloud.xyz)


def test_scene_is_not_modified():
    scene = furnished_room()
    before = [o.vertices.copy() for o in scene.objects]
    scan_rgbd_trajectory(scene, num_frames=2, stride=16, rng=0)
    assert all(np.array_equal(o.vertices, v) for o, v in zip(scene.objects, before, strict=True))


# -- monocular SLAM -------------------------------------------------------------------------
def test_monocular_scale_is_recovered_from_odometry():
    scene = furnished_room()
    out = scan_monocular_slam(scene, num_frames=6, stride=4, scale=0.37, rng=2)
    assert out.frame == "map" and out.scale == 0.37
    assert out.scale_factor * out.scale == pytest.approx(1.0, abs=0.03)
    # Scaled back, the points lie on the objects they are labelled with.
    inliers = out.cloud.fields["instance"] > 0
    metric = out.cloud.xyz[inliers] * out.scale_factor
    for obj in scene.objects:
        mine = out.cloud.fields["instance"][inliers] == obj.instance_id
        assert obj.box.contains(metric[mine], margin=0.25).sum() >= 0.99 * mine.sum()


def test_monocular_unknown_scale_is_drawn_from_the_seed():
    scene = furnished_room()
    a = scan_monocular_slam(scene, num_frames=2, stride=8, rng=1)
    b = scan_monocular_slam(scene, num_frames=2, stride=8, rng=2)
    lo, hi = sensors.SLAM_SCALE_RANGE
    assert lo <= a.scale <= hi and a.scale != b.scale
    assert a.scale_factor * a.scale == pytest.approx(1.0, abs=0.05)


def test_monocular_points_sit_on_edges_and_outliers_are_unlabelled():
    scene = furnished_room()
    common = {"num_frames": 4, "stride": 4, "scale": 1.0, "rng": 3}
    edges_only = scan_monocular_slam(scene, texture=0.0, outlier_ratio=0.0, **common)
    textured = scan_monocular_slam(scene, texture=1.0, outlier_ratio=0.0, **common)
    assert 0 < len(edges_only.cloud) < len(textured.cloud) / 3
    noisy = scan_monocular_slam(scene, outlier_ratio=0.2, **common)
    outlier = noisy.cloud.fields["instance"] == 0
    assert 0.12 < outlier.mean() < 0.28
    assert np.all(noisy.triangle[outlier] == -1)
    assert np.all(noisy.cloud.fields["class_id"][outlier] == 0)


# -- where sensors stand --------------------------------------------------------------------
def test_camera_trajectory_stays_in_the_room_and_looks_at_the_furniture():
    scene = furnished_room()
    poses = camera_trajectory(scene, 16, rng=0)
    pos = poses[:, :3, 3]
    assert np.all((pos[:, 0] > 0) & (pos[:, 0] < 4) & (pos[:, 1] > 0) & (pos[:, 1] < 3))
    assert np.all((pos[:, 2] >= 1.2 - 1e-9) & (pos[:, 2] <= 1.7 + 1e-9))
    R = poses[:, :3, :3]
    assert np.allclose(R @ R.transpose(0, 2, 1), np.eye(3))
    assert np.allclose(np.linalg.det(R), 1.0)
    assert np.all(R[:, 2, 2] < 0)  # every camera looks down a little
    assert np.all(R[:, 2, 0] == pytest.approx(0.0, abs=1e-12))  # no roll: image rows level
    for box in (o.box for o in scene.objects if not o.is_structure):
        feet = np.column_stack([pos[:, :2], np.full(len(pos), box.center[2])])
        assert not box.contains(feet).any()


def test_tls_stations_spread_out():
    poses = tls_stations(furnished_room(), 4, rng=1)
    xy = poses[:, :2, 3]
    gaps = np.linalg.norm(xy[:, None] - xy[None], axis=-1)[np.triu_indices(4, 1)]
    assert gaps.min() > 0.3


# -- parameters -----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("scan", "kwargs", "name"),
    [
        (scan_rgbd_trajectory, {"num_frames": 0}, "num_frames"),
        (scan_rgbd_trajectory, {"stride": 0}, "stride"),
        (scan_rgbd_trajectory, {"noise": (-1, 0)}, "noise"),
        (scan_rgbd_trajectory, {"max_range": 0.1}, "max_range"),
        (scan_rgbd_trajectory, {"drift": -0.1}, "drift"),
        (scan_rgbd_trajectory, {"voxel": 0}, "voxel"),
        (scan_rgbd_trajectory, {"focal": 500}, "focal"),
        (scan_rgbd_frame, {"pose": np.ones((4, 4))}, "pose"),
        (scan_rgbd_frame, {"edge_dropout": 1.5}, "edge_dropout"),
        (scan_tls, {"h_res_deg": 0}, "h_res_deg"),
        (scan_tls, {"stations": 0}, "stations"),
        (scan_tls, {"noise_sigma": float("nan")}, "noise_sigma"),
        (scan_tls, {"elevation": (10, -10)}, "elevation"),
        (scan_monocular_slam, {"scale": 0}, "scale"),
        (scan_monocular_slam, {"outlier_ratio": 2}, "outlier_ratio"),
        (scan_monocular_slam, {"baseline": 0.1}, "baseline"),
    ],
)
def test_bad_parameters_name_themselves(scan, kwargs, name):
    with pytest.raises(InvalidParameterError, match=f"'{name}'"):
        scan(furnished_room(), rng=0, **kwargs)


def test_scene_must_be_a_scene():
    with pytest.raises(InvalidParameterError, match="'scene'"):
        scan_rgbd_frame("office")


def test_organized_cloud_is_the_full_grid_with_nan_holes():
    scene = box_room([box_object(7, "table", (2.0, 1.5, 0.375), (1.2, 0.8, 0.75))])
    pose = looking_along_x((0.3, 1.5, 1.4))
    out = scan_rgbd_frame(scene, pose=pose, stride=4, rng=0)
    grid = out.organized_cloud()
    assert len(grid) == 160 * 120
    hole = np.isnan(grid.xyz).any(axis=1)
    assert hole.sum() == 160 * 120 - len(out.cloud) > 0  # projector shadows, edges
    assert np.array_equal(grid.xyz[out.cloud.index], out.cloud.xyz)
    assert np.array_equal(grid.fields["instance"][out.cloud.index], out.cloud.fields["instance"])
    assert np.all(grid.fields["instance"][hole] == 0)
    assert not out.organized_cloud(fields=False).fields
    with pytest.raises(InvalidParameterError, match="'sensor'"):
        scan_tls(scene, stations=1, h_res_deg=10, v_res_deg=10, rng=0).organized_cloud()


def test_rays_pass_through_glass():
    pane = dataclasses.replace(
        box_object(1, "window", (1.5, 0.0, 1.5), (0.01, 2.0, 2.0)), part_names=["glass"]
    )
    behind = box_object(2, "cabinet", (3.0, 0.0, 1.5), (0.4, 0.6, 0.6))
    scene = Scene("office", (5.0, 5.0, 3.0), [pane, behind], 0)
    out = scan_rgbd_frame(scene, pose=looking_along_x((0.0, 0.0, 1.5)), stride=8, rng=0)
    counts = np.bincount(out.cloud.fields["instance"], minlength=3)
    assert counts[1] == 0 and counts[2] > 50
    only_glass = Scene("office", (5.0, 5.0, 3.0), [pane], 0)
    assert len(scan_tls(only_glass, stations=1, h_res_deg=10, v_res_deg=10, rng=0).cloud) == 0
