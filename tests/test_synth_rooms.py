"""Furnished rooms: structure, class mix, plausible and collision-free placement, determinism."""

from __future__ import annotations

import hashlib
from collections import Counter

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ontodetect import InvalidParameterError
from ontodetect.synth.rooms import ROOM_TYPES, build_room
from ontodetect.synth.scene import CLASS_IDS

SEEDS = (0, 1, 2)
#: Depth (metres) by which meshes may meet without counting as interpenetrating.
CONTACT = 2e-3


@pytest.fixture(scope="module")
def scenes():
    return {(t, s): build_room(t, s) for t in ROOM_TYPES for s in SEEDS}


def furniture(scene):
    return [o for o in scene.objects if not o.is_structure]


def classes(scene):
    return Counter(o.class_name for o in furniture(scene))


# --------------------------------------------------------------------------------------
# Mesh helpers, independent of the placement code.


def pieces(obj):
    """The closed pieces of an object: (vertices, triangles) per connected component."""
    n = len(obj.vertices)
    t = obj.triangles
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]]])
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    tri_label = label[t[:, 0]]
    return [obj.vertices[t[tri_label == k]] for k in np.unique(tri_label)]


def surface_samples(obj, n, rng):
    """n random points on the surface, pushed CONTACT inside along the inward normal."""
    tri = obj.vertices[obj.triangles]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = np.linalg.norm(normal, axis=1)
    keep = area > 1e-12
    tri, normal, area = tri[keep], normal[keep] / area[keep, None], area[keep]
    pick = rng.choice(len(tri), n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    t = tri[pick]
    p = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
    return p - CONTACT * normal[pick]


def inside_closed(points, tri):
    """Which points lie inside the closed triangle soup ``tri`` (k, 3, 3): ray parity upwards."""
    lo, hi = tri.reshape(-1, 3).min(axis=0), tri.reshape(-1, 3).max(axis=0)
    cand = np.all((points > lo) & (points < hi), axis=1)
    out = np.zeros(len(points), bool)
    if not cand.any():
        return out
    p = points[cand]
    a = tri[None, :, 0]
    e1, e2 = tri[None, :, 1] - a, tri[None, :, 2] - a
    d = p[:, None, :2] - a[..., :2]
    den = e1[..., 0] * e2[..., 1] - e2[..., 0] * e1[..., 1]
    ok = np.abs(den) > 1e-14
    den = np.where(ok, den, 1.0)
    u = (d[..., 0] * e2[..., 1] - e2[..., 0] * d[..., 1]) / den
    v = (e1[..., 0] * d[..., 1] - d[..., 0] * e1[..., 1]) / den
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1)
    z = a[..., 2] + u * e1[..., 2] + v * e2[..., 2]
    crossings = np.sum(hit & (z > p[:, None, 2]), axis=1)
    out[cand] = crossings % 2 == 1
    return out


def aabb(obj):
    return obj.vertices.min(axis=0), obj.vertices.max(axis=0)


# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("room_type", ROOM_TYPES)
def test_every_room_type_builds_with_structure_first(room_type, scenes):
    for seed in SEEDS:
        scene = scenes[room_type, seed]
        assert scene.room_type == room_type and scene.seed == seed
        ids = [o.instance_id for o in scene.objects]
        assert ids == list(range(1, len(ids) + 1))
        structure = [o.is_structure for o in scene.objects]
        assert structure == sorted(structure, reverse=True)  # structure first
        count = Counter(o.class_name for o in scene.objects)
        assert count["floor"] == 1 and count["ceiling"] == 1 and count["wall"] == 4
        assert count["door"] >= 1
        assert all(o.class_name in CLASS_IDS for o in scene.objects)
        v, t, inst, col = scene.combined_mesh()
        assert len(t) == len(inst) == len(col) and t.max() < len(v)


@pytest.mark.parametrize("room_type", ROOM_TYPES)
def test_furniture_inside_the_room_on_the_floor_or_on_a_support(room_type, scenes):
    for seed in SEEDS:
        scene = scenes[room_type, seed]
        L, W, H = scene.size
        objs = furniture(scene)
        for obj in objs:
            lo, hi = aabb(obj)
            assert np.all(lo >= -1e-9) and hi[0] <= L + 1e-9 and hi[1] <= W + 1e-9, obj.kind
            assert hi[2] < H
            if obj.extra.get("wall_mounted"):  # a WC or washbasin hung on a wall touches it
                assert min(lo[0], lo[1], L - hi[0], W - hi[1]) < 2e-3, obj.kind
            elif lo[2] > 1e-9:  # clutter: it rests on the top of something below it
                tops = [o for o in objs if "support_z" in o.extra and o is not obj]
                foot = np.array([[obj.box.center[0], obj.box.center[1], lo[2]]])
                assert any(
                    abs(o.extra["support_z"] + o.pose[2, 3] - lo[2]) < 1e-9
                    and o.box.contains(foot, 1e-6)[0]
                    for o in tops
                ), obj.kind
            else:
                assert lo[2] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("room_type", ROOM_TYPES)
def test_no_two_objects_interpenetrate(room_type, scenes):
    """Surface points of each object, 2 mm inside it, are outside every other object."""
    rng = np.random.default_rng(0)
    scene = scenes[room_type, 0]
    objs = [o for o in scene.objects if o.class_name != "ceiling"]
    solids = {o.instance_id: pieces(o) for o in objs}
    samples = {}
    for o in objs:
        # Keep the samples that really are inside their own object (near an edge the push
        # along one face's normal can leave through another face).
        pts = surface_samples(o, 1500, rng)
        own = np.zeros(len(pts), bool)
        for tri in solids[o.instance_id]:
            own |= inside_closed(pts, tri)
        samples[o.instance_id] = pts[own]
    boxes = {o.instance_id: aabb(o) for o in objs}
    checked = 0
    for a in objs:
        for b in objs:
            if a is b or (a.is_structure and b.is_structure):
                continue
            (lo_a, hi_a), (lo_b, hi_b) = boxes[a.instance_id], boxes[b.instance_id]
            if np.any(np.minimum(hi_a, hi_b) - np.maximum(lo_a, lo_b) < -1e-9):
                continue  # apart: not even touching
            checked += 1
            pts = samples[a.instance_id]
            for tri in solids[b.instance_id]:
                inside = inside_closed(pts, tri)
                assert not inside.any(), (a.kind, a.instance_id, b.kind, b.instance_id)
    assert checked > 0


def test_chairs_are_tucked_under_tables_without_touching_the_top():
    tucked = 0
    for room_type, seed in [("dining_room", 0), ("dining_room", 1), ("conference", 1)]:
        scene = build_room(room_type, seed)
        tables = [o for o in furniture(scene) if o.class_name == "table"]
        for chair in [o for o in furniture(scene) if o.class_name == "chair"]:
            seat = chair.vertices[
                np.unique(
                    chair.triangles[
                        chair.triangle_part == chair.part_names.index(chair.extra["seat_part"])
                    ]
                )
            ]
            for table in tables:
                local = (seat - table.pose[:3, 3]) @ table.pose[:3, :3]
                x0, y0, x1, y1 = table.extra["support_rect"]
                under = (local[:, 0] > x0) & (local[:, 0] < x1) & (local[:, 1] > y0)
                under &= local[:, 1] < y1
                if table.extra["support_round"]:
                    under = np.hypot(local[:, 0], local[:, 1]) < (x1 - x0) / 2
                if under.any():
                    tucked += 1
                    top_bottom = table.dimensions["top_height"] - table.dimensions["top_thickness"]
                    assert seat[under, 2].max() < top_bottom
    assert tucked >= 6


def test_same_seed_same_scene():
    a, b = build_room("living_room", 7), build_room("living_room", 7)
    assert a.size == b.size and len(a.objects) == len(b.objects)
    for oa, ob in zip(a.objects, b.objects):
        assert oa.kind == ob.kind and oa.instance_id == ob.instance_id
        assert np.array_equal(oa.vertices, ob.vertices)
        assert np.array_equal(oa.triangles, ob.triangles)
        assert np.array_equal(oa.triangle_color, ob.triangle_color)
        assert np.array_equal(oa.pose, ob.pose)
    c = build_room("living_room", 8)
    assert c.size != a.size


def test_a_generator_seed_is_recorded_and_reproduces_the_scene():
    scene = build_room("tiny", np.random.default_rng(5))
    again = build_room("tiny", scene.seed)
    assert [o.kind for o in scene.objects] == [o.kind for o in again.objects]
    assert all(np.array_equal(p.vertices, q.vertices) for p, q in zip(scene.objects, again.objects))


MIN_MIX = {
    "office": {"desk": 2, "chair": 2},
    "conference": {"table": 1, "chair": 6},
    "living_room": {"sofa": 1, "table": 1},
    "home_office": {"desk": 1, "chair": 1},
    "dining_room": {"table": 1, "chair": 4},
    "bedroom": {"bed": 1, "closet": 1},
    "kitchen": {"table": 1, "chair": 2, "stool": 1, "cabinet": 1},
    "corridor": {"bench": 1},
    "bathroom": {"toilet": 1, "sink": 1},
    "hotel_room": {"bed": 1, "cabinet": 1, "lamp": 1, "tv_stand": 1, "chair": 1},
}


@pytest.mark.parametrize("room_type", sorted(MIN_MIX))
def test_class_mix(room_type, scenes):
    for seed in SEEDS:
        count = classes(scenes[room_type, seed])
        for cls, n in MIN_MIX[room_type].items():
            assert count[cls] >= n, (room_type, seed, cls, count)
    if room_type == "conference":
        assert all(classes(scenes[room_type, s])["chair"] <= 12 + 2 for s in SEEDS)
    if room_type == "corridor":
        # Nothing stands in the middle 90 cm of a corridor, except against its end walls.
        for seed in SEEDS:
            scene = scenes[room_type, seed]
            L, W, _ = scene.size
            for obj in furniture(scene):
                lo, hi = aabb(obj)
                if min(hi[0], L - lo[0]) < 0.4 if L >= W else min(hi[1], W - lo[1]) < 0.4:
                    continue
                if L >= W:
                    assert hi[1] <= W / 2 - 0.45 + 1e-6 or lo[1] >= W / 2 + 0.45 - 1e-6
                else:
                    assert hi[0] <= L / 2 - 0.45 + 1e-6 or lo[0] >= L / 2 + 0.45 - 1e-6


def test_tiny_room_holds_exactly_a_chair_a_table_and_a_stool(scenes):
    for seed in SEEDS:
        scene = scenes["tiny", seed]
        assert scene.size[:2] == (2.5, 2.5)
        assert classes(scene) == Counter({"chair": 1, "table": 1, "stool": 1})


def test_walls_have_holes_at_doors_and_windows(scenes):
    for (room_type, seed), scene in scenes.items():
        if seed != 0:
            continue
        walls = {o.extra["wall"]: o for o in scene.objects if o.class_name == "wall"}
        for op in scene.extra["openings"]:
            wall = walls[op["wall"]]
            t = scene.extra["wall_thickness"]
            # The middle of the opening, in the middle of the wall's thickness.
            local = np.array([(op["u0"] + op["u1"]) / 2, -t / 2, (op["z0"] + op["z1"]) / 2, 1.0])
            p = (wall.pose @ local)[:3]
            assert not any(inside_closed(p[None], tri)[0] for tri in pieces(wall)), room_type


def test_radiators_stand_under_windows(scenes):
    found = 0
    for scene in scenes.values():
        windows = [o for o in scene.objects if o.class_name == "window"]
        for rad in [o for o in scene.objects if o.class_name == "radiator"]:
            found += 1
            centre = np.asarray(rad.box.center)
            ok = False
            for w in windows:
                # In the window's wall frame: x along the wall, y into the room.
                local = (centre - w.pose[:3, 3]) @ w.pose[:3, :3]
                u = (w.vertices - w.pose[:3, 3]) @ w.pose[:3, :3]
                ok |= bool(
                    u[:, 0].min() < local[0] < u[:, 0].max()
                    and 0 < local[1] < 0.3
                    and rad.vertices[:, 2].max() < w.dimensions["sill_height"]
                )
            assert ok, scene.room_type
    assert found > 0


def test_clutter_scales_the_small_things():
    small = {"plant", "bin", "box", "books"}
    rich = sum(sum(classes(build_room("office", s, clutter=2.0))[c] for c in small) for s in (3, 4))
    bare = sum(sum(classes(build_room("office", s, clutter=0.0))[c] for c in small) for s in (3, 4))
    assert bare == 0 and rich > 4


def test_size_is_honoured():
    scene = build_room("bedroom", 1, size=(4.0, 3.5, 2.6))
    assert scene.size == (4.0, 3.5, 2.6)
    floor = next(o for o in scene.objects if o.class_name == "floor")
    assert floor.vertices[:, :2].max(axis=0) == pytest.approx((4.0, 3.5))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"room_type": "garage", "seed": 0}, "'room_type'"),
        ({"room_type": "office", "seed": -1}, "'seed'"),
        ({"room_type": "office", "seed": 1.5}, "'seed'"),
        ({"room_type": "office", "seed": 0, "size": (1.0, 3.0)}, "'size'"),
        ({"room_type": "office", "seed": 0, "size": (4.0, 3.0, 1.0)}, "'size'"),
        ({"room_type": "office", "seed": 0, "size": "big"}, "'size'"),
        ({"room_type": "office", "seed": 0, "clutter": -1.0}, "'clutter'"),
    ],
)
def test_bad_parameters_are_named(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        build_room(**kwargs)


def fingerprint(scene):
    """A digest of a scene's objects: classes, kinds, parts, meshes (to the micrometre), colours."""
    h = hashlib.sha256()
    h.update(repr((scene.room_type, np.round(scene.size, 6).tolist(), scene.seed)).encode())
    for o in scene.objects:
        h.update(repr((o.instance_id, o.class_name, o.kind, o.part_names)).encode())
        h.update(np.round(o.vertices, 6).tobytes())
        h.update(np.ascontiguousarray(o.triangles, dtype=np.int64).tobytes())
        h.update(np.ascontiguousarray(o.triangle_part, dtype=np.int64).tobytes())
        h.update(np.ascontiguousarray(o.triangle_color, dtype=np.uint8).tobytes())
        h.update(np.round(o.pose, 6).tobytes())
    return h.hexdigest()[:16]


#: Fingerprints of the seed-0 rooms before the bathroom and hotel-room furniture came in:
#: new kinds and room types must not change the rooms that were there.
SEED0_FINGERPRINTS = {
    "office": "f1c77e9b6e9bf58b",
    "conference": "bb6a43b8cddbf64b",
    "living_room": "fe22468b5cd35e81",
    "home_office": "2b71b67dd4f8961c",
    "dining_room": "bbb51825412bdbfd",
    "bedroom": "a73cfa59a7f80a80",
    "kitchen": "4980c52a03cea896",
    "corridor": "30e60dc487ce41ad",
    "tiny": "e1d308ccd18f2618",
}


@pytest.mark.parametrize("room_type", sorted(SEED0_FINGERPRINTS))
def test_earlier_room_types_are_built_as_before(room_type, scenes):
    assert fingerprint(scenes[room_type, 0]) == SEED0_FINGERPRINTS[room_type]


def test_bathroom_sanitary_ware_stands_against_walls(scenes):
    baths = 0
    for seed in SEEDS:
        scene = scenes["bathroom", seed]
        L, W, _ = scene.size
        for obj in furniture(scene):
            if obj.class_name in ("toilet", "sink", "bathtub"):
                lo, hi = aabb(obj)
                assert min(lo[0], lo[1], L - hi[0], W - hi[1]) < 6e-3, obj.kind
            baths += obj.class_name == "bathtub"
    assert baths >= 1


def test_hotel_room_lamps_stand_on_nightstands(scenes):
    for seed in SEEDS:
        objs = furniture(scenes["hotel_room", seed])
        stands = [o for o in objs if o.kind == "nightstand"]
        lamps = [o for o in objs if o.class_name == "lamp"]
        assert lamps
        for lamp in lamps:
            base = np.array([[*lamp.pose[:2, 3], lamp.vertices[:, 2].min()]])
            assert any(
                s.box.contains(base, 1e-6)[0]
                and lamp.vertices[:, 2].min() == pytest.approx(s.extra["support_z"])
                for s in stands
            )
