"""Synthetic dataset: synthesize, write, read back; ground-truth consistency; determinism."""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh

from ontodetect import read_cloud
from ontodetect.cloud import pixel_grid, sensor_position
from ontodetect.errors import CorruptFileError, InvalidParameterError, ReadError
from ontodetect.synth import (
    SYNTH_FORMAT,
    RGBDSensor,
    build_room,
    load_synth,
    room_types,
    sensors,
    synthesize,
    synthesize_many,
    write_synth,
)

FILES = ("cloud.ply", "objects.json", "scene.json", "mesh.ply")


@pytest.fixture(scope="module")
def tiny_rgbd():
    return synthesize("tiny", "rgbd", seed=0, points=10_000)


@pytest.fixture(scope="module")
def tiny_folder(tiny_rgbd, tmp_path_factory):
    return write_synth(tiny_rgbd, tmp_path_factory.mktemp("tiny") / "scene")


def test_tiny_room_gives_about_ten_thousand_points(tiny_rgbd):
    assert len(tiny_rgbd.cloud) == 10_000
    assert tiny_rgbd.output.parameters["subsampled_to"] == 10_000
    assert tiny_rgbd.room == "tiny" and tiny_rgbd.sensor == "rgbd"
    classes = tiny_rgbd.objects_by_class()
    assert classes["chair"] == 1 and classes["table"] == 1
    assert "10,000 points" in tiny_rgbd.summary()


def test_written_layout(tiny_rgbd, tiny_folder):
    for name in FILES:
        assert (tiny_folder / name).is_file()
    scene = json.loads((tiny_folder / "scene.json").read_text())
    assert scene["format"] == SYNTH_FORMAT
    assert scene["room_type"] == "tiny" and scene["seed"] == 0
    assert scene["sensor"]["name"] == "rgbd"
    assert scene["sensor"]["parameters"]["stride"] >= 1
    assert scene["scale"] == 1.0 and scene["frame"] == "world"
    assert scene["odometry_distance"] is None
    assert np.asarray(scene["trajectory"]).shape == tiny_rgbd.output.poses.shape
    assert scene["num_points"] == 10_000
    assert scene["class_ids"]["chair"] == 5
    assert sorted(scene["files"]) == sorted(FILES)
    assert scene["intrinsics"]["fx"] == 525.0


def test_load_synth_round_trip(tiny_rgbd, tiny_folder):
    cloud, objects, scene = load_synth(tiny_folder)
    assert len(cloud) == len(tiny_rgbd.cloud)
    assert np.allclose(cloud.xyz, tiny_rgbd.cloud.xyz, atol=1e-5)  # float32 in the file
    assert np.array_equal(cloud.rgb, tiny_rgbd.cloud.rgb)
    for name in ("instance", "class_id"):
        assert cloud.fields[name].dtype == np.int32
        assert np.array_equal(cloud.fields[name], tiny_rgbd.cloud.fields[name])
    assert [o["id"] for o in objects] == [o.instance_id for o in tiny_rgbd.scene.objects]
    assert scene["seed"] == 0


def test_objects_json_describes_every_instance(tiny_rgbd, tiny_folder):
    _, objects, _ = load_synth(tiny_folder)
    counts = np.bincount(tiny_rgbd.cloud.fields["instance"])
    keys = {
        "id",
        "class",
        "class_id",
        "kind",
        "structure",
        "box",
        "pose",
        "dimensions",
        "parts",
        "num_points",
        "seen",
    }
    for entry, obj in zip(objects, tiny_rgbd.scene.objects, strict=True):
        assert keys <= set(entry)
        assert entry["class"] == obj.class_name and entry["class_id"] == obj.class_id
        assert entry["num_points"] == (
            counts[obj.instance_id] if obj.instance_id < len(counts) else 0
        )
        # An object with no points is flagged as unseen, and only then.
        assert entry["seen"] == (entry["num_points"] > 0)
        assert set(entry["box"]) == {"center", "size", "yaw"}
        assert np.asarray(entry["pose"]).shape == (4, 4)
        assert set(entry["parts"]) == set(obj.part_names)
        assert sum(p["triangles"] for p in entry["parts"].values()) == len(obj.triangles)
        assert sum(p["num_points"] for p in entry["parts"].values()) == entry["num_points"]
        for part in entry["parts"].values():
            if part["box"] is not None:
                assert (
                    np.all(
                        np.asarray(part["box"]["size"]) <= np.asarray(entry["box"]["size"]) + 1e-6
                    )
                    or entry["structure"]
                )


def test_every_labelled_point_lies_in_its_object_box(tiny_rgbd):
    cam = RGBDSensor()
    margin = float(5 * cam.sigma(cam.max_range) + cam.quantum(cam.max_range))
    inst = tiny_rgbd.cloud.fields["instance"]
    for obj in tiny_rgbd.scene.objects:
        mine = inst == obj.instance_id
        assert np.all(obj.box.contains(tiny_rgbd.cloud.xyz[mine], margin))
    assert np.all(inst > 0)  # an RGB-D camera has no outliers


def test_labels_match_the_triangle_hit(tiny_rgbd):
    _, _, tri_instance, _ = tiny_rgbd.scene.combined_mesh()
    assert np.array_equal(
        tiny_rgbd.cloud.fields["instance"], tri_instance[tiny_rgbd.output.triangle]
    )


def test_mesh_ply_holds_the_scene(tiny_rgbd, tiny_folder):
    vertices, triangles, _, _ = tiny_rgbd.scene.combined_mesh()
    mesh = trimesh.load(tiny_folder / "mesh.ply", process=False)
    assert mesh.vertices.shape == vertices.shape
    assert np.array_equal(mesh.faces, triangles)
    assert np.allclose(mesh.vertices, vertices, atol=1e-5)
    as_points = read_cloud(tiny_folder / "mesh.ply")
    assert len(as_points) == len(vertices) and as_points.rgb is not None


def test_same_seed_writes_identical_bytes(tmp_path):
    for sensor in ("rgbd", "tls", "monocular", "rgbd-frame"):
        a = write_synth(synthesize("tiny", sensor, 7, points=3000), tmp_path / f"{sensor}-a")
        b = write_synth(synthesize("tiny", sensor, 7, points=3000), tmp_path / f"{sensor}-b")
        names = sorted(p.name for p in a.iterdir())
        assert names == sorted(p.name for p in b.iterdir())
        for name in names:
            assert (a / name).read_bytes() == (b / name).read_bytes(), (sensor, name)
    other = write_synth(synthesize("tiny", "rgbd", 8, points=3000), tmp_path / "other")
    assert (other / "cloud.ply").read_bytes() != (tmp_path / "rgbd-a" / "cloud.ply").read_bytes()


@pytest.mark.parametrize("sensor", ["rgbd", "tls", "monocular"])
def test_points_target_is_reached(sensor):
    result = synthesize("tiny", sensor, 1, points=4000)
    assert len(result.cloud) == 4000


def test_single_frame_writes_an_organized_pcd(tmp_path):
    result = synthesize("tiny", "rgbd-frame", 2, points=20_000)
    assert 10_000 < len(result.cloud) < 40_000  # a frame keeps its grid: roughly the target
    folder = write_synth(result, tmp_path / "frame")
    frame = read_cloud(folder / "frame.pcd")
    meta = result.cloud.meta
    assert frame.meta["organized"] and frame.meta["width"] == meta["width"]
    assert frame.meta["height"] == meta["height"]
    cloud, _, scene = load_synth(folder)
    # cloud.ply is in the world frame; its ``pixel`` is the point's row in frame.pcd.
    assert np.array_equal(cloud.fields["pixel"], frame.index)
    assert np.allclose(frame.xyz, result.cloud.xyz, atol=1e-5)
    pose = np.asarray(scene["trajectory"][0])
    assert np.allclose(cloud.xyz, frame.xyz @ pose[:3, :3].T + pose[:3, 3], atol=1e-4)
    assert "frame.pcd" in scene["files"]
    # read back, the world-frame frame knows where its camera stood and its pixel grid
    assert np.allclose(sensor_position(cloud), pose[:3, 3])
    assert np.allclose(sensor_position(frame), 0.0)  # the camera frame's origin
    pixels, width, height = pixel_grid(cloud)
    assert (width, height) == (meta["width"], meta["height"])
    assert np.array_equal(pixels, frame.index)


def test_single_frame_view_keeps_the_projector_in_sight():
    # In this kitchen the view that sees the most furniture without shadows stands 3 cm
    # left of an open door leaf: the projector, 7.5 cm to the camera's right, would
    # light nothing and the frame would be empty.
    result = synthesize("kitchen", "rgbd-frame", 513, stride=8)
    assert len(result.cloud) > 1000
    pose = result.output.poses[0]
    sensor = RGBDSensor()
    shift = pose[:3, 0] * sensor.baseline
    reach, _ = sensors._caster(result.scene).cast(pose[None, :3, 3], shift[None])
    assert reach[0] > 1.0


def test_tls_writes_intensity(tmp_path):
    folder = write_synth(synthesize("tiny", "tls", 0, points=3000), tmp_path / "tls")
    cloud, _, scene = load_synth(folder)
    assert cloud.fields["intensity"].dtype == np.float32
    assert scene["sensor"]["name"] == "tls"


def test_monocular_records_scale_and_distances(tmp_path):
    result = synthesize("tiny", "monocular", 4, points=3000)
    folder = write_synth(result, tmp_path / "mono")
    _, _, scene = load_synth(folder)
    assert scene["frame"] == "map"
    assert scene["scale"] == pytest.approx(result.output.scale)
    k_s = scene["odometry_distance"] / scene["slam_distance"]
    assert k_s == pytest.approx(scene["scale_factor"])
    assert k_s * scene["scale"] == pytest.approx(1.0, abs=0.05)


def test_object_meshes(tmp_path):
    result = synthesize("tiny", "rgbd", 0, points=2000)
    folder = write_synth(result, tmp_path / "objs", object_meshes=True)
    for obj in result.scene.objects:
        mesh = trimesh.load(folder / "objects" / f"{obj.instance_id}.ply", process=False)
        assert len(mesh.faces) == len(obj.triangles)


def test_a_scene_object_can_be_scanned_directly():
    scene = build_room("tiny", 5)
    result = synthesize(scene, "rgbd", 5, points=2000)
    assert result.scene is scene and result.room == scene.room_type


def test_synthesize_many_numbers_folders_and_seeds(tmp_path):
    seen = []
    folders = synthesize_many(
        2,
        "tiny",
        "rgbd",
        10,
        out_dir=tmp_path / "ds",
        points=2000,
        on_scene=lambda i, r, f: seen.append((i, r.seed, f.name)),
    )
    assert [f.name for f in folders] == ["scene_0000", "scene_0001"]
    assert seen == [(0, 10, "scene_0000"), (1, 11, "scene_0001")]
    alone = write_synth(synthesize("tiny", "rgbd", 11, points=2000), tmp_path / "alone")
    assert (alone / "cloud.ply").read_bytes() == (folders[1] / "cloud.ply").read_bytes()


def test_bad_room_names_the_allowed_ones():
    with pytest.raises(InvalidParameterError, match="'room'") as info:
        synthesize("castle")
    for name in room_types():
        assert name in str(info.value)
    with pytest.raises(InvalidParameterError, match="'room'"):
        synthesize_many(2, ["tiny", "castle"], out_dir="unused")


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"sensor": "sonar"}, "sensor"),
        ({"seed": -1}, "seed"),
        ({"points": 0}, "points"),
        ({"clutter": -1.0}, "clutter"),
        ({"h_res_deg": 1.0}, "h_res_deg"),  # a laser option given to a camera
    ],
)
def test_bad_arguments_name_themselves(kwargs, name):
    args = {"room": "tiny", **kwargs}
    with pytest.raises(InvalidParameterError, match=f"'{name}'"):
        synthesize(**args)


def test_load_synth_errors(tmp_path, tiny_folder):
    with pytest.raises(ReadError, match="no such folder"):
        load_synth(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ReadError, match=r"scene\.json"):
        load_synth(tmp_path / "empty")
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "scene.json").write_text('{"format": "something else"}')
    with pytest.raises(CorruptFileError, match="format"):
        load_synth(broken)
    (broken / "scene.json").write_text("{not json")
    with pytest.raises(CorruptFileError, match="JSON"):
        load_synth(broken)
