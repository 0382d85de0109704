"""The room shell in open-plan rooms (issue 20): glazed and curtained walls are wall, a
drifted second floor layer is floor, and what stands beside them stays an object."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect.config import Config
from ontodetect.geometry import _mesh as M
from ontodetect.pipeline import detect
from ontodetect.preprocess import prepare
from ontodetect.synth import synthesize
from ontodetect.synth.artefacts import duplicate_floor_layer
from ontodetect.synth.furniture import make_furniture, place
from test_recognition import _mesh_obj
from test_synth_sensors import box_room

#: Surface density of the hand-made scans (points per m²): about a ScanNet room at 50,000
#: points (3-5 cm between points).
DENSITY = 700.0
FLOOR, WALL = 1, 2
#: The glazed and curtained walls are off by default (docs/benchmarks.md: they cost the real
#: development scans a table); these tests switch them on.
SHELL = Config().replace(prepare={"shell_walls": True})


def _plane(rng, origin, u, v, density=DENSITY):
    """Points on the parallelogram ``origin + a u + b v``, a, b in [0, 1)."""
    u, v = np.asarray(u, float), np.asarray(v, float)
    n = max(1, int(np.linalg.norm(np.cross(u, v)) * density))
    ab = rng.random((n, 2))
    return np.asarray(origin, float) + ab[:, :1] * u + ab[:, 1:] * v


def _box(rng, lo, hi, density=DENSITY):
    """Points on the five visible faces of an axis-aligned box (no bottom)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    d = hi - lo
    ex, ey, ez = np.diag(d)
    faces = [
        _plane(rng, [lo[0], lo[1], hi[2]], ex, ey, density),
        _plane(rng, lo, ex, ez, density),
        _plane(rng, [lo[0], hi[1], lo[2]], ex, ez, density),
        _plane(rng, lo, ey, ez, density),
        _plane(rng, [hi[0], lo[1], lo[2]], ey, ez, density),
    ]
    return np.vstack(faces)


def _chair(rng, x, y):
    """A four-legged chair of boxes, seat at 0.45 m, its backrest towards +y."""
    parts = [_box(rng, [x - 0.22, y - 0.22, 0.42], [x + 0.22, y + 0.22, 0.46], 1500)]
    for dx in (-0.2, 0.18):
        for dy in (-0.2, 0.18):
            parts.append(_box(rng, [x + dx, y + dy, 0.0], [x + dx + 0.03, y + dy + 0.03, 0.42]))
    parts.append(_box(rng, [x - 0.22, y + 0.18, 0.46], [x + 0.22, y + 0.22, 0.9], 1500))
    return np.vstack(parts)


def _room(rng, open_side):
    """A 4 x 3.5 m room, 2.6 m high, seen up to 2.2 m: floor and three walls; the wall
    at y = 3.5 is replaced by ``open_side`` (points). Returns points and a label per point
    (0 floor, 1 walls, 2 the open side)."""
    L, W, top = 4.0, 3.5, 2.2
    floor = _plane(rng, [0, 0, 0], [L, 0, 0], [0, W, 0])
    walls = np.vstack(
        [
            _plane(rng, [0, 0, 0], [L, 0, 0], [0, 0, top]),
            _plane(rng, [0, 0, 0], [0, W, 0], [0, 0, top]),
            _plane(rng, [L, 0, 0], [0, W, 0], [0, 0, top]),
        ]
    )
    pts = np.vstack([floor, walls, open_side])
    part = np.repeat([0, 1, 2], [len(floor), len(walls), len(open_side)])
    return pts, part


def _curtain(rng, y=3.38, top=2.2, depth=0.04, wave=0.15):
    """A curtain drawn across the wall at y = 3.5: a vertical sheet folded every ``wave``."""
    s = rng.random((int(3.0 * top * DENSITY * 1.3), 2))
    x = 0.5 + 3.0 * s[:, 0]
    return np.c_[x, y + depth * np.sin(2 * np.pi * x / wave), 0.02 + (top - 0.02) * s[:, 1]]


def _labels_of(points, cfg=None):
    scene = prepare(points, cfg)
    return scene, scene.structure_label[scene.point_to_voxel]


def _share(labels, mask, value):
    return float(np.mean(labels[mask] == value))


def _joined(scene, a, b):
    """Whether object voxels of the points ``a`` and ``b`` (masks) are linked at the
    clustering radius (``cluster.radius``, at least ``spacing_factor`` spacings)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    cfg = Config().cluster
    radius = max(cfg.radius, cfg.spacing_factor * scene.spacing)
    obj = np.flatnonzero(scene.object_mask)
    pairs = cKDTree(scene.centers[obj]).query_pairs(radius, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), (len(obj), len(obj)))
    _, comp = connected_components(graph, directed=False)
    where = np.full(len(scene.centers), -1)
    where[obj] = comp
    ca = set(where[scene.point_to_voxel[a]].tolist()) - {-1}
    cb = set(where[scene.point_to_voxel[b]].tolist()) - {-1}
    return bool(ca & cb)


# -- glazed and curtained walls ------------------------------------------------------------------
def test_a_curtain_is_wall_and_the_chair_in_front_of_it_is_not():
    rng = np.random.default_rng(0)
    pts, part = _room(rng, _curtain(rng))
    chair = _chair(rng, 2.0, 3.04)  # its backrest 10 cm from the nearest fold
    scene, lab = _labels_of(np.vstack([pts, chair]), SHELL)
    is_chair = np.r_[np.zeros(len(pts), bool), np.ones(len(chair), bool)]
    curtain = np.r_[part == 2, np.zeros(len(chair), bool)]
    assert _share(lab, curtain, WALL) > 0.9
    assert _share(lab, is_chair, WALL) < 0.02
    assert not _joined(scene, is_chair, curtain)
    # Off (the default): most of the curtain stays an object, and the chair is joined to it.
    scene, off = _labels_of(np.vstack([pts, chair]))
    assert _share(off, curtain, WALL) < 0.5
    assert _joined(scene, is_chair, curtain)


def _window_with_curtains(rng):
    """The wall at y = 3.5 with a window from x = 0.9 to 2.1: glass (no returns) above a
    bottom frame from 5 to 11 cm, and a curtain gathered at each side. Returns the points
    and which are the frame."""
    top = 2.2
    wall = np.vstack(
        [
            _plane(rng, [0, 3.5, 0], [0.9, 0, 0], [0, 0, top]),
            _plane(rng, [2.1, 3.5, 0], [1.9, 0, 0], [0, 0, top]),
        ]
    )
    frame = _box(rng, [0.9, 3.46, 0.05], [2.1, 3.5, 0.11], 1500)
    panels = []
    for x0 in (0.5, 2.1):
        c = _curtain(rng)
        c = c[(c[:, 0] >= 0.5) & (c[:, 0] < 0.9)]
        c[:, 0] += x0 - 0.5
        panels.append(c)
    pts = np.vstack([wall, frame, *panels])
    return pts, np.r_[
        np.zeros(len(wall), bool),
        np.ones(len(frame), bool),
        np.zeros(len(pts) - len(wall) - len(frame), bool),
    ]


def test_the_frame_between_two_curtains_is_wall_and_the_chair_in_front_is_not_joined_to_it():
    rng = np.random.default_rng(1)
    side, is_frame = _window_with_curtains(rng)
    pts, _ = _room(rng, side)
    chair = _chair(rng, 1.5, 3.19)  # its back legs 4 cm from the window's bottom frame
    all_pts = np.vstack([pts, chair])
    frame = np.r_[np.zeros(len(pts) - len(side), bool), is_frame, np.zeros(len(chair), bool)]
    is_chair = np.r_[np.zeros(len(pts), bool), np.ones(len(chair), bool)]
    scene, lab = _labels_of(all_pts, SHELL)
    assert _share(lab, frame, WALL) > 0.9
    assert _share(lab, is_chair, WALL) < 0.02
    assert not _joined(scene, is_chair, frame)
    scene, lab = _labels_of(all_pts)
    assert _joined(scene, is_chair, frame)


def test_a_tall_cabinet_in_the_middle_of_the_room_is_no_wall():
    # Tall, but with the room behind it: not at the room's boundary.
    rng = np.random.default_rng(2)
    pts, _ = _room(rng, _plane(rng, [0, 3.5, 0], [4, 0, 0], [0, 0, 2.2]))
    cabinet = _box(rng, [1.0, 1.5, 0.0], [3.0, 1.9, 2.0])
    _, lab = _labels_of(np.vstack([pts, cabinet]), SHELL)
    assert _share(lab, np.r_[np.zeros(len(pts), bool), np.ones(len(cabinet), bool)], WALL) < 0.05


def test_furniture_lower_than_the_head_height_along_a_wall_is_no_wall():
    # A row of sideboards 0.9 m high along a wall: near the floor, at the boundary, but
    # not tall.
    rng = np.random.default_rng(3)
    wall = _plane(rng, [0, 3.5, 0], [4, 0, 0], [0, 0, 2.2])
    pts, _ = _room(rng, wall)
    sideboards = _box(rng, [0.2, 3.0, 0.0], [3.8, 3.49, 0.9])
    sideboards = sideboards[sideboards[:, 1] < 3.45]  # their backs are hidden
    _, lab = _labels_of(np.vstack([pts, sideboards]), SHELL)
    mask = np.r_[np.zeros(len(pts), bool), np.ones(len(sideboards), bool)]
    assert _share(lab, mask, WALL) < 0.05


# -- a drifted second floor layer ----------------------------------------------------------------
def _floor_room(rng, offset, share=0.4, tilt_deg=0.5, furniture=()):
    """Floor, walls and ``furniture``, plus a copy of the floor's x < share * 4 m moved by
    ``offset`` (m) and tilted about the y axis. Returns points and which are the copy."""
    pts, _ = _room(rng, _plane(rng, [0, 3.5, 0], [4, 0, 0], [0, 0, 2.2]))
    floor = pts[(pts[:, 2] == 0.0) & (pts[:, 0] < share * 4.0)]
    cx = share * 2.0
    copy = floor.copy()
    copy[:, 2] = offset + np.tan(np.radians(tilt_deg)) * (copy[:, 0] - cx)
    all_pts = np.vstack([pts, *furniture, copy])
    return all_pts, np.r_[np.zeros(len(all_pts) - len(copy), bool), np.ones(len(copy), bool)]


@pytest.mark.parametrize("offset", [0.05, -0.05])
def test_a_drifted_floor_layer_is_floor(offset):
    rng = np.random.default_rng(4)
    pts, copy = _floor_room(rng, offset)
    scene, lab = _labels_of(pts)
    assert scene.floor_found
    # The floor is the true one, not the copy (levelled z of the true floor is 0).
    assert abs(float(np.median(scene.cloud.xyz[~copy & (pts[:, 2] == 0), 2]))) < 0.01
    assert _share(lab, copy, FLOOR) > 0.97


def test_without_the_rule_a_raised_floor_layer_stays_an_object():
    rng = np.random.default_rng(4)
    pts, copy = _floor_room(rng, 0.05)
    _, lab = _labels_of(pts, Config().replace(prepare={"floor_layers": False}))
    assert _share(lab, copy, FLOOR) < 0.5


@settings(max_examples=12, deadline=None)
@given(
    offset=st.floats(0.02, 0.12) | st.floats(-0.12, -0.02),
    share=st.floats(0.2, 0.5),
    tilt=st.floats(0.0, 1.0),
)
def test_a_drifted_floor_layer_is_floor_whatever_its_offset_share_and_tilt(offset, share, tilt):
    rng = np.random.default_rng(5)
    pts, copy = _floor_room(rng, offset, share, tilt)
    scene, lab = _labels_of(pts)
    assert scene.floor_found
    assert _share(lab, copy, FLOOR) > 0.95


def _table(rng, x, y, height, size=(1.0, 0.6)):
    top = _box(rng, [x, y, height - 0.03], [x + size[0], y + size[1], height], 1500)
    legs = [
        _box(rng, [x + dx, y + dy, 0.0], [x + dx + 0.04, y + dy + 0.04, height - 0.03])
        for dx in (0.02, size[0] - 0.06)
        for dy in (0.02, size[1] - 0.06)
    ]
    return np.vstack([top, *legs])


@pytest.mark.parametrize("offset", [0.05, -0.05])
def test_a_coffee_table_is_not_floor_beside_a_floor_layer(offset):
    rng = np.random.default_rng(6)
    table = _table(rng, 2.2, 1.2, 0.4)
    pts, copy = _floor_room(rng, offset, furniture=[table])
    _, lab = _labels_of(pts)
    is_top = np.zeros(len(pts), bool)
    start = np.flatnonzero(~copy)[-1] + 1 - len(table)
    is_top[start : start + len(table)] = table[:, 2] > 0.3
    assert _share(lab, is_top, FLOOR) == 0.0


def test_a_platform_higher_than_a_stair_riser_is_not_floor():
    # 1.5 m² at 0.25 m (a low bed, a stage): higher than a floor layer may be.
    rng = np.random.default_rng(7)
    pts, _ = _room(rng, _plane(rng, [0, 3.5, 0], [4, 0, 0], [0, 0, 2.2]))
    platform = _box(rng, [1.0, 1.0, 0.0], [2.5, 2.0, 0.25])
    _, lab = _labels_of(np.vstack([pts, platform]))
    top = np.r_[np.zeros(len(pts), bool), platform[:, 2] > 0.24]
    assert _share(lab, top, FLOOR) == 0.0


# -- detection: the chair is found on its own --------------------------------------------------
def _simulated_curtain_scan():
    x = np.linspace(0.6, 3.4, 120)
    y = 3.38 + 0.04 * np.sin(2 * np.pi * x / 0.15)
    grid = np.stack(
        [np.stack([x, y, np.full_like(x, 0.02)], 1), np.stack([x, y, np.full_like(x, 2.3)], 1)],
        axis=1,
    )
    curtain = _mesh_obj(9, "curtain", M.thick_surface(grid, 0.008), (200, 190, 160))
    chair = dataclasses.replace(
        place(make_furniture("chair-4leg", 4), 2.0, 3.05, np.pi), instance_id=8
    )
    room = box_room([chair, curtain], size=(4.0, 3.5, 2.6))
    return synthesize(room, sensor="rgbd", seed=0, points=60_000).cloud


@pytest.mark.slow
def test_a_chair_beside_a_curtain_is_detected_without_the_curtain():
    scan = _simulated_curtain_scan()
    inst = np.asarray(scan.fields["instance"])
    row = {int(r): k for k, r in enumerate(scan.index)}

    def chair_detections(cfg):
        found = []
        for d in detect(scan, config=cfg).detections:
            ii = inst[[row[int(p)] for p in d.point_indices]]
            if d.label == "chair" and np.mean(ii == 8) > 0:
                found.append((float(np.mean(ii == 8)), float(np.sum(ii == 8) / np.sum(inst == 8))))
        return found

    found = chair_detections(SHELL)
    assert len(found) == 1
    purity, recall = found[0]
    assert purity > 0.95 and recall > 0.8
    # Before the rule the curtain made most of the chair's detection.
    before = chair_detections(Config())
    assert all(p < 0.5 for p, _ in before)


@pytest.mark.slow
@pytest.mark.parametrize("sign", [1, -1])
def test_a_drifted_floor_layer_makes_no_table_and_the_coffee_table_stays(sign):
    table = dataclasses.replace(place(make_furniture("table-coffee", 3), 2.0, 1.6), instance_id=7)
    room = box_room([table], size=(4.0, 3.5, 2.6))
    scan = synthesize(room, sensor="rgbd", seed=0, points=50_000).cloud
    n = len(scan)
    for seed in range(20):  # the side of the copy is drawn: take the first seed on ``sign``
        out = duplicate_floor_layer(scan, seed, share=0.4, offset=0.05, max_tilt_deg=0.5)
        if np.sign(np.median(out.xyz[n:, 2])) == sign:
            break
    inst = np.asarray(out.fields["instance"])
    copy = np.r_[np.zeros(n, bool), np.ones(len(out) - n, bool)]
    row = {int(r): k for k, r in enumerate(out.index)}
    result = detect(out)
    for d in result.detections:
        rows = [row[int(p)] for p in d.point_indices]
        assert np.mean(copy[rows]) < 0.1, f"a {d.label} made of the copied floor"
    tables = [
        d
        for d in result.detections
        if d.label == "table" and np.mean(inst[[row[int(p)] for p in d.point_indices]] == 7) > 0.5
    ]
    assert len(tables) == 1
