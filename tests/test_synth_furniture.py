"""Parametric furniture: closed parts, ergonomic dimensions, seat heights, placement."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from ontodetect import InvalidParameterError
from ontodetect.geometry import _mesh as M
from ontodetect.synth.furniture import (
    FURNITURE,
    FURNITURE_CLASSES,
    kinds_of,
    make_furniture,
    part_boxes,
    place,
    place_on,
)
from ontodetect.synth.scene import CLASS_IDS

KINDS = sorted(FURNITURE)
SEEDS = range(8)


@pytest.fixture(scope="module")
def built():
    """Every kind built from seeds 0-7."""
    return {k: [make_furniture(k, s) for s in SEEDS] for k in KINDS}


def top_at(vertices, triangles, x, y):
    """Highest surface point of a mesh straight above (x, y), or -inf."""
    tri = vertices[triangles]
    a = tri[:, 0]
    e1, e2 = tri[:, 1] - a, tri[:, 2] - a
    p = np.array([x, y]) - a[:, :2]
    den = e1[:, 0] * e2[:, 1] - e2[:, 0] * e1[:, 1]
    ok = np.abs(den) > 1e-14
    den = np.where(ok, den, 1.0)
    u = (p[:, 0] * e2[:, 1] - e2[:, 0] * p[:, 1]) / den
    v = (e1[:, 0] * p[:, 1] - p[:, 0] * e1[:, 1]) / den
    inside = ok & (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9)
    z = a[:, 2] + u * e1[:, 2] + v * e2[:, 2]
    return z[inside].max() if inside.any() else -np.inf


# --------------------------------------------------------------------------------------
# Primitives


PRIMITIVES = {
    "box": lambda: M.box((1.0, 2.0, 3.0)),
    "hexahedron": lambda: M.hexahedron(M._UNIT_CORNERS * [1, 2, 3] + [0, 0, 1]),
    "tapered_box": lambda: M.tapered_box((0.05, 0.05), (0.03, 0.04), 0.4, (0.01, 0.0)),
    "prism": lambda: M.prism(M.rounded_rectangle((1.0, 0.5), 0.1), 0.0, 0.03),
    "rounded_box_x": lambda: M.rounded_box((1.0, 0.5, 0.3), 0.1, "x"),
    "rounded_box_y": lambda: M.rounded_box((1.0, 0.5, 0.3), 0.1, "y"),
    "cylinder": lambda: M.cylinder(0.2, 0.5),
    "frustum": lambda: M.frustum(0.2, 0.1, 0.5),
    "cylinder_between": lambda: M.cylinder_between((0, 0, 0), (0.1, -0.2, 0.5), 0.02),
    "torus": lambda: M.torus(0.2, 0.02),
    "superellipsoid": lambda: M.superellipsoid((0.5, 0.6, 0.1), 0.2, 1.0),
    "cushion": lambda: M.cushion((0.5, 0.6, 0.15)),
    "ellipsoid": lambda: M.ellipsoid((0.1, 0.2, 0.3)),
    "blob": lambda: M.blob((0.3, 0.3, 0.4), 1),
    "tube": lambda: M.tube(M.fillet_path([[0, 0, 0], [0, 0.5, 0], [0, 0.5, 0.5]], 0.05), 0.01),
    "tube_loop": lambda: M.tube(
        M.fillet_path([[0, 0, 0], [0, 0.5, 0], [0, 0.5, 0.5], [0, 0, 0.5]], 0.05, closed=True),
        0.01,
        closed=True,
    ),
    "lathe_cup": lambda: M.lathe(
        [(0, 0), (0.12, 0), (0.15, 0.4), (0.14, 0.4), (0.11, 0.01), (0, 0.01)]
    ),
    "thick_surface": lambda: M.thick_surface(
        np.stack(
            [
                *np.meshgrid(np.linspace(-0.2, 0.2, 9), np.linspace(0, 0.5, 12), indexing="ij"),
                np.zeros((9, 12)),
            ],
            -1,
        )
        + [0, 0, 0.1],
        0.01,
    ),
}


@pytest.mark.parametrize("name", sorted(PRIMITIVES))
def test_primitives_are_closed_volumes_with_outward_normals(name):
    mesh = PRIMITIVES[name]()
    assert mesh.vertices.dtype == np.float64 and mesh.triangles.dtype == np.int32
    t = trimesh.Trimesh(mesh.vertices, mesh.triangles, process=False)
    assert t.is_watertight and t.is_winding_consistent and t.is_volume
    assert mesh.volume > 0  # outward normals enclose a positive volume


def test_primitive_volumes_are_right():
    assert M.box((1.0, 2.0, 3.0)).volume == pytest.approx(6.0)
    assert M.cylinder(1.0, 1.0, segments=256).volume == pytest.approx(np.pi, rel=1e-3)
    assert M.ellipsoid((1, 2, 3), rings=64, segments=128).volume == pytest.approx(
        4 / 3 * np.pi * 6, rel=2e-2
    )
    mirrored = M.box((1.0, 2.0, 3.0)).scaled((-1, 1, 1))
    assert mirrored.volume == pytest.approx(6.0)  # mirroring keeps the normals outwards


def test_superellipsoid_top_is_exactly_at_its_size():
    m = M.cushion((0.5, 0.6, 0.12), center=(0, 0, 0.4))
    assert m.bounds[1, 2] == pytest.approx(0.46) and m.bounds[0, 2] == pytest.approx(0.34)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: M.box((1.0, -1.0, 1.0)), "'size'"),
        (lambda: M.hexahedron(np.zeros((7, 3))), "'corners'"),
        (lambda: M.prism([[0, 0], [1, 0]], 0, 1), "'polygon'"),
        (lambda: M.lathe([(1, 0), (1, 1), (0, 1)]), "'profile'"),
        (lambda: M.torus(0.1, 0.2), "'minor_radius'"),
        (lambda: M.box((1, 1, 1)).rotated("w", 1.0), "'axis'"),
        (lambda: M.tube([[0, 0, 0], [0, 0, 0]], 0.01), "'path'"),
    ],
)
def test_bad_primitive_parameters_are_named(call, match):
    with pytest.raises(InvalidParameterError, match=match):
        call()


# --------------------------------------------------------------------------------------
# Every kind


def test_registry_covers_the_classes():
    assert set(FURNITURE_CLASSES.values()) <= set(CLASS_IDS)
    assert len(kinds_of("chair")) >= 5 and len(kinds_of("sofa")) >= 4
    for cls in (
        "chair",
        "stool",
        "bench",
        "ottoman",
        "sofa",
        "table",
        "desk",
        "cabinet",
        "closet",
        "bookshelf",
        "bed",
        "box",
        "television",
        "keyboard",
        "plant",
        "bin",
        "radiator",
    ):
        assert kinds_of(cls), cls


@pytest.mark.parametrize("kind", KINDS)
def test_every_piece_is_a_closed_volume(kind):
    for obj in [make_furniture(kind, s) for s in (0, 1)]:
        t = trimesh.Trimesh(obj.vertices, obj.triangles, process=False)
        assert t.is_winding_consistent
        pieces = t.split(only_watertight=False)
        assert all(p.is_volume for p in pieces), kind


@pytest.mark.parametrize("kind", KINDS)
def test_arrays_floor_contact_and_tight_box(kind, built):
    for obj in built[kind]:
        v, t = obj.vertices, obj.triangles
        assert v.dtype == np.float64 and v.shape[1] == 3
        assert t.dtype == np.int32 and t.min() >= 0 and t.max() < len(v)
        assert obj.triangle_part.dtype == np.int32 and len(obj.triangle_part) == len(t)
        assert obj.triangle_part.max() < len(obj.part_names)
        assert obj.triangle_color.dtype == np.uint8 and obj.triangle_color.shape == t.shape
        assert obj.class_name == FURNITURE_CLASSES[kind] and obj.kind == kind
        assert np.array_equal(obj.pose, np.eye(4))
        # Stands on the floor (or hangs on the wall at its clearance), footprint centred.
        low = obj.dimensions["floor_clearance"] if obj.extra.get("wall_mounted") else 0.0
        assert v[:, 2].min() == pytest.approx(low, abs=1e-9)
        lo, hi = v.min(axis=0), v.max(axis=0)
        assert np.allclose((lo + hi)[:2], 0.0, atol=1e-9)
        # The box holds every vertex and touches the mesh on all six sides.
        assert obj.box.contains(v, margin=1e-9).all()
        assert np.allclose(obj.box.size, hi - lo)
        d = obj.dimensions
        # The height is the top's, from the floor, also for what hangs on a wall.
        assert (d["width"], d["depth"], d["height"] - low) == pytest.approx(tuple(hi - lo))


@pytest.mark.parametrize("kind", KINDS)
def test_collision_boxes_cover_every_vertex(kind, built):
    obj = place(built[kind][0], 1.5, -2.0, 0.7)
    inside = np.zeros(len(obj.vertices), bool)
    for b in part_boxes(obj):
        inside |= b.contains(obj.vertices, margin=1e-9)
    assert inside.all()


SEATED = [
    k for k in KINDS if FURNITURE_CLASSES[k] in ("chair", "sofa", "stool", "bench", "ottoman")
]


@pytest.mark.parametrize("kind", SEATED)
def test_seat_height_is_the_top_of_the_seat(kind, built):
    for obj in built[kind]:
        part = obj.part_names.index(obj.extra["seat_part"])
        x, y = obj.extra["seat_center"]
        top = top_at(obj.vertices, obj.triangles[obj.triangle_part == part], x, y)
        assert top == pytest.approx(obj.dimensions["seat_height"], abs=2e-3), kind


#: Easy chairs follow catalogue ranges, not those of upright and office chairs.
EASY_CHAIRS = ("chair-club", "chair-wingback", "chair-lounge")
UPRIGHT_CHAIRS = tuple(k for k in kinds_of("chair") if k not in EASY_CHAIRS)

# (kinds, dimension, low, high): the ranges the standards give (see furniture.py).
RANGES = [
    (UPRIGHT_CHAIRS, "seat_height", 0.40, 0.50),
    (UPRIGHT_CHAIRS + ("chair-club", "chair-wingback"), "recline", 95.0, 110.0),
    (kinds_of("sofa"), "seat_height", 0.38, 0.45),
    (kinds_of("stool"), "seat_height", 0.45, 0.80),
    (("stool-round", "stool-square"), "seat_height", 0.45, 0.50),
    (("stool-bar",), "seat_height", 0.65, 0.80),
    (("bench",), "seat_height", 0.42, 0.48),
    (kinds_of("ottoman"), "seat_height", 0.38, 0.45),
    (("table-dining", "table-small", "table-round", "table-conference"), "top_height", 0.70, 0.76),
    (("table-coffee",), "top_height", 0.35, 0.50),
    (kinds_of("desk"), "top_height", 0.72, 0.76),
    (kinds_of("table") + kinds_of("desk"), "top_thickness", 0.02, 0.04),
    (("table-conference",), "width", 2.4, 4.0),
    (("sofa-3seat",), "width", 1.9, 2.6),
    (("bed",), "mattress_height", 0.45, 0.60),
    (("closet",), "height", 1.8, 2.2),
]


@pytest.mark.parametrize(("kinds", "key", "low", "high"), RANGES)
def test_dimensions_stay_in_the_standard_ranges(kinds, key, low, high, built):
    for kind in kinds:
        for obj in built[kind]:
            assert low - 1e-9 <= obj.dimensions[key] <= high + 1e-9, (kind, key)


def test_armrests_and_backrests(built):
    for kind in KINDS:
        for obj in built[kind]:
            d = obj.dimensions
            if kind in UPRIGHT_CHAIRS and "armrest_height" in d:
                # EN 1335-1: armrests 20-25 cm above the seat.
                assert 0.20 - 1e-9 <= d["armrest_height"] - d["seat_height"] <= 0.25 + 1e-9
            if FURNITURE_CLASSES[kind] == "sofa" and "armrest_height" in d:
                assert 0.15 - 1e-9 <= d["armrest_height"] - d["seat_height"] <= 0.25 + 1e-9
            if FURNITURE_CLASSES[kind] in ("chair", "sofa"):
                assert d["backrest_height"] > d["seat_height"] + 0.25
    arms = [o for o in built["chair-office"] if "armrest" in o.part_names]
    assert arms and len(arms) < len(built["chair-office"])  # armrests are optional


def test_backrest_is_reclined_backwards(built):
    for obj in built["chair-4leg"]:
        back = obj.vertices[
            np.unique(obj.triangles[obj.triangle_part == obj.part_names.index("backrest")])
        ]
        low = back[back[:, 2] < np.percentile(back[:, 2], 20)]
        high = back[back[:, 2] > np.percentile(back[:, 2], 80)]
        assert high[:, 1].mean() < low[:, 1].mean()  # the top leans to the back (-y)


EXPECTED_PARTS = {
    "chair-4leg": {"seat", "leg", "backrest"},
    "chair-4leg-arms": {"seat", "leg", "backrest", "armrest"},
    "chair-sled": {"seat", "backrest", "base"},
    "chair-office": {"seat", "backrest", "column", "leg", "caster", "base"},
    "chair-shell": {"shell", "leg"},
    "chair-armchair": {"cushion", "back_cushion", "arm", "backrest"},
    "stool-round": {"seat", "leg"},
    "stool-square": {"seat", "leg"},
    "stool-bar": {"seat", "footrest"},
    "bench": {"seat", "leg"},
    "ottoman-box": {"cushion", "base"},
    "ottoman-round": {"cushion", "base"},
    "sofa-2seat": {"cushion", "back_cushion", "arm", "backrest", "frame"},
    "sofa-3seat": {"cushion", "back_cushion", "arm", "backrest", "frame"},
    "sofa-armless": {"cushion", "back_cushion", "backrest", "frame"},
    "sofa-l-shaped": {"cushion", "back_cushion", "arm", "backrest", "frame"},
    "table-dining": {"top", "leg"},
    "table-small": {"top", "leg"},
    "table-round": {"top", "pedestal", "base"},
    "table-coffee": {"top", "leg"},
    "table-conference": {"top", "leg"},
    "table-bar": {"top", "leg"},
    "desk-pedestal": {"top", "pedestal", "drawer", "handle"},
    "desk-panel": {"top", "leg", "modesty_panel"},
    "cabinet": {"body", "top", "handle"},
    "nightstand": {"body", "drawer"},
    "kitchen-counter": {"body", "top", "base"},
    "closet": {"body", "door", "handle"},
    "bookshelf": {"side", "shelf", "top", "books"},
    "bed": {"frame", "mattress", "headboard", "pillow"},
    "box": {"box"},
    "books": {"book"},
    "monitor": {"screen", "stand", "base"},
    "television": {"screen", "stand", "base"},
    "keyboard": {"body", "keys"},
    "mouse": {"body"},
    "plant": {"pot", "foliage"},
    "plant-small": {"pot", "foliage"},
    "bin": {"bin"},
    "radiator": {"bracket"},
    "chair-shell-curved": {"shell", "leg"},
    "chair-club": {"cushion", "back_cushion", "arm", "backrest"},
    "chair-wingback": {"cushion", "back_cushion", "arm", "backrest", "wing"},
    "chair-lounge": {"shell", "column", "base"},
    "toilet": {"bowl", "pedestal", "seat", "cistern"},
    "toilet-wall-hung": {"bowl", "seat", "flush_plate"},
    "sink-pedestal": {"basin", "pedestal", "tap"},
    "sink-vanity": {"basin", "top", "body", "tap"},
    "sink-wall-hung": {"basin", "trap", "tap"},
    "bathtub": {"tub", "rim", "panel", "tap"},
    "lamp-table": {"base", "stem", "shade", "bulb"},
    "tv-stand": {"body", "top"},
}


@pytest.mark.parametrize("kind", KINDS)
def test_named_parts(kind, built):
    assert kind in EXPECTED_PARTS, "add the new kind's parts to EXPECTED_PARTS"
    for obj in built[kind]:
        assert EXPECTED_PARTS[kind] <= set(obj.part_names)
        assert len(set(obj.part_names)) == len(obj.part_names)


def test_parts_have_realistic_thickness(built):
    def part_extent(obj, name, axis):
        v = obj.vertices[np.unique(obj.triangles[obj.triangle_part == obj.part_names.index(name)])]
        return np.ptp(v[:, axis])

    for obj in built["chair-4leg"]:
        assert 0.02 - 1e-9 <= obj.dimensions["seat_thickness"] <= 0.05 + 1e-9
        assert part_extent(obj, "seat", 2) == pytest.approx(obj.dimensions["seat_thickness"])
    for obj in built["table-dining"]:
        assert 0.02 - 1e-9 <= part_extent(obj, "top", 2) <= 0.04 + 1e-9
    for obj in built["sofa-3seat"]:
        arm = obj.vertices[
            np.unique(obj.triangles[obj.triangle_part == obj.part_names.index("arm")])
        ]
        assert np.ptp(arm[arm[:, 0] > 0, 0]) >= 0.12 - 1e-9  # thick arms


def test_variety_across_seeds(built):
    assert len({round(o.dimensions["seat_height"], 4) for o in built["chair-4leg"]}) == len(SEEDS)
    colours = {tuple(o.triangle_color[0]) for o in built["sofa-2seat"]}
    assert len(colours) > 3
    frames = {o.extra["corner"] for o in built["sofa-l-shaped"]}
    assert frames == {"left", "right"}


def test_mirrored_l_sofa_keeps_normals_outwards():
    for corner in ("left", "right"):
        obj = make_furniture("sofa-l-shaped", 4, corner=corner)
        assert M.Mesh(obj.vertices, obj.triangles).volume > 0
        assert obj.extra["corner"] == corner


def test_same_seed_same_object_and_input_not_shared():
    a, b = make_furniture("chair-office", 11), make_furniture("chair-office", 11)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(
        a.triangle_color, b.triangle_color
    )
    assert a.dimensions == b.dimensions
    c = make_furniture("chair-office", 12)
    assert a.vertices.shape != c.vertices.shape or not np.allclose(a.vertices, c.vertices)
    gen = np.random.default_rng(3)
    assert make_furniture("bed", gen).dimensions != make_furniture("bed", gen).dimensions


def test_overrides_fix_one_value_and_keep_the_others():
    free = make_furniture("chair-4leg", 5)
    fixed = make_furniture("chair-4leg", 5, seat_height=0.45, fabric_color=(10, 20, 30))
    assert fixed.dimensions["seat_height"] == pytest.approx(0.45)
    assert fixed.dimensions["seat_width"] == free.dimensions["seat_width"]
    assert make_furniture("chair-office", 1, arms=False).part_names.count("armrest") == 0
    assert "armrest" in make_furniture("chair-office", 1, arms=True).part_names


@pytest.mark.parametrize(
    ("kind", "overrides", "match"),
    [
        ("armchair", {}, "'kind'"),
        ("chair-4leg", {"wobble": 1.0}, "'wobble'.*chair-4leg"),
        ("chair-4leg", {"seat_height": -0.4}, "'seat_height'"),
        ("chair-4leg", {"seat_height": "high"}, "'seat_height'"),
        ("chair-office", {"arms": "maybe"}, "'arms'"),
        ("sofa-2seat", {"fabric_color": "plaid"}, "'fabric_color'"),
        ("sofa-2seat", {"fabric_color": (300, 0, 0)}, "'fabric_color'"),
        ("kitchen-counter", {"units": 0}, "'units'"),
    ],
)
def test_bad_kinds_and_overrides_are_named(kind, overrides, match):
    with pytest.raises(InvalidParameterError, match=match):
        make_furniture(kind, 0, **overrides)


def test_place_is_absolute_and_moves_box_and_boxes():
    obj = make_furniture("table-dining", 2)
    moved = place(obj, 2.0, 1.0, np.pi / 2, z=0.3)
    assert moved.yaw == pytest.approx(np.pi / 2)
    assert moved.box.center == pytest.approx((2.0, 1.0, 0.3 + obj.box.center[2]))
    assert moved.box.contains(moved.vertices, margin=1e-9).all()
    again = place(moved, 2.0, 1.0, np.pi / 2, z=0.3)
    assert np.allclose(again.vertices, moved.vertices)
    back = place(moved, 0.0, 0.0, 0.0)
    assert np.allclose(back.vertices, obj.vertices)
    assert np.array_equal(obj.pose, np.eye(4))  # the input is not modified
    # The table's x axis (its length) now points along world +y.
    assert np.ptp(moved.vertices[:, 1]) == pytest.approx(obj.dimensions["width"])


def test_a_chair_seat_fits_under_a_table_top_but_its_back_does_not():
    table = make_furniture("table-dining", 0, top_height=0.74, apron=False)
    chair = make_furniture("chair-4leg", 0, seat_height=0.45, stretchers=False)
    rows = part_boxes(table)
    y_edge = table.dimensions["depth"] / 2
    seat = chair.vertices[
        np.unique(chair.triangles[chair.triangle_part == chair.part_names.index("seat")])
    ]
    front = seat[:, 1].max()

    def bounds(b):
        # Both objects are turned by a multiple of 90 degrees: the boxes stay axis-aligned.
        half = (
            np.abs(np.array([[np.cos(b.yaw), -np.sin(b.yaw)], [np.sin(b.yaw), np.cos(b.yaw)]]))
            @ np.asarray(b.size[:2])
            / 2
        )
        c = np.asarray(b.center)
        h = np.array([*half, b.size[2] / 2])
        return c - h, c + h

    def overlaps(tuck):
        c = place(chair, 0.0, y_edge + front - tuck, np.pi)
        for a in part_boxes(c):
            lo_a, hi_a = bounds(a)
            for b in rows:
                lo_b, hi_b = bounds(b)
                if np.all(np.minimum(hi_a, hi_b) - np.maximum(lo_a, lo_b) > 1e-4):
                    return True
        return False

    assert not overlaps(0.10)  # the seat's front 10 cm under the top
    assert overlaps(chair.dimensions["seat_depth"] + 0.1)  # pushed in until the back hits


# --------------------------------------------------------------------------------------
# Bathroom, bedroom and living-room kinds the ontology must tell from chairs and tables

NEW_KINDS = (
    "toilet",
    "toilet-wall-hung",
    "sink-pedestal",
    "sink-vanity",
    "sink-wall-hung",
    "bathtub",
    "lamp-table",
    "tv-stand",
    "chair-club",
    "chair-wingback",
    "chair-lounge",
    "chair-shell-curved",
)
MANY = range(20)


@pytest.fixture(scope="module")
def many():
    """The new kinds built from 20 seeds."""
    return {k: [make_furniture(k, s) for s in MANY] for k in NEW_KINDS}


def part_vertices(obj, name):
    return obj.vertices[np.unique(obj.triangles[obj.triangle_part == obj.part_names.index(name)])]


def part_top_at(obj, name, x, y):
    return top_at(
        obj.vertices, obj.triangles[obj.triangle_part == obj.part_names.index(name)], x, y
    )


def test_new_kinds_have_their_classes_and_ids():
    expected = {
        "toilet": ("toilet", 33),
        "toilet-wall-hung": ("toilet", 33),
        "sink-pedestal": ("sink", 34),
        "sink-vanity": ("sink", 34),
        "sink-wall-hung": ("sink", 34),
        "bathtub": ("bathtub", 36),
        "lamp-table": ("lamp", 35),
        "tv-stand": ("tv_stand", 111),
        "chair-club": ("chair", 5),
        "chair-wingback": ("chair", 5),
        "chair-lounge": ("chair", 5),
        "chair-shell-curved": ("chair", 5),
    }
    for kind, (cls, class_id) in expected.items():
        obj = make_furniture(kind, 0)
        assert (obj.class_name, obj.class_id) == (cls, class_id), kind


# (kinds, dimension, low, high): the catalogue and standard ranges cited in furniture.py.
NEW_RANGES = [
    (("toilet",), "seat_height", 0.38, 0.43),
    (("toilet-wall-hung",), "seat_height", 0.40, 0.43),
    (("toilet", "toilet-wall-hung"), "bowl_width", 0.34, 0.40),
    (("toilet",), "depth", 0.60, 0.70),  # from the wall, cistern included
    (("toilet",), "cistern_height", 0.75, 0.85),
    (("toilet",), "width", 0.34, 0.43),  # the cistern's lid overhangs it by 5 mm a side
    (("toilet-wall-hung",), "projection", 0.48, 0.58),
    (("sink-pedestal", "sink-wall-hung"), "width", 0.50, 0.65),
    (("sink-pedestal", "sink-wall-hung"), "depth", 0.40, 0.50),
    (("sink-pedestal", "sink-vanity", "sink-wall-hung"), "rim_height", 0.80, 0.90),
    (("sink-pedestal", "sink-vanity", "sink-wall-hung"), "bowl_depth", 0.12, 0.18),
    (("sink-vanity",), "width", 0.60, 1.20),
    (("bathtub",), "width", 1.60, 1.80),
    (("bathtub",), "depth", 0.70, 0.80),
    (("bathtub",), "rim_height", 0.50, 0.60),
    (("bathtub",), "inner_depth", 0.38, 0.45),
    (("lamp-table",), "height", 0.30, 0.60),
    (("lamp-table",), "base_width", 0.10, 0.18),
    (("lamp-table",), "shade_diameter", 0.20, 0.40),
    (("tv-stand",), "width", 1.2, 2.0),
    (("tv-stand",), "depth", 0.35, 0.50),
    (("tv-stand",), "top_height", 0.40, 0.60),
    (("tv-stand",), "height", 0.40, 0.60),
    (("chair-club",), "width", 0.80, 1.00),
    (("chair-club", "chair-wingback"), "depth", 0.80, 0.95),
    (("chair-club",), "height", 0.70, 0.85),
    (("chair-club",), "seat_height", 0.37, 0.45),
    (("chair-club", "chair-wingback"), "armrest_height", 0.55, 0.65),
    (("chair-club",), "arm_width", 0.15, 0.25),
    (("chair-club",), "backrest_center", 0.47, 0.60),
    (("chair-wingback",), "height", 1.00, 1.20),
    (("chair-lounge",), "seat_height", 0.38, 0.42),
    (("chair-lounge",), "back_tilt", 20.0, 30.0),
]


@pytest.mark.parametrize(("kinds", "key", "low", "high"), NEW_RANGES)
def test_new_kinds_stay_in_their_ranges(kinds, key, low, high, many):
    for kind in kinds:
        for obj in many[kind]:
            assert low - 1e-9 <= obj.dimensions[key] <= high + 1e-9, (kind, key)


def test_easy_chairs_stand_low_or_on_short_feet(many):
    for kind in ("chair-club", "chair-wingback"):
        for obj in many[kind]:
            d = obj.dimensions
            assert d["armrest_height"] >= d["seat_height"] + 0.1
            if "leg" in obj.part_names:
                assert part_vertices(obj, "leg")[:, 2].max() <= 0.12 + 1e-9
    wings = [o for o in many["chair-wingback"] if "wing" in o.part_names]
    assert len(wings) == len(MANY)
    for obj in wings:  # the wings rise beside the head, above the arms
        assert part_vertices(obj, "wing")[:, 2].max() > obj.dimensions["armrest_height"] + 0.3


def test_club_chair_seat_is_in_the_catalogue_range():
    for seed in MANY:
        obj = make_furniture("chair-club", seed)
        x, y = obj.extra["seat_center"]
        top = part_top_at(obj, "cushion", x, y)
        assert 0.37 - 1e-9 <= top <= 0.45 + 1e-9
    assert make_furniture("chair-club", 0, seat_height=0.40).dimensions["seat_height"] == 0.40


def test_lounge_chair_back_is_reclined_20_to_30_degrees(many):
    for obj in many["chair-lounge"]:
        shell = part_vertices(obj, "shell")
        seat_y = obj.extra["seat_center"][1]
        back = shell[
            (shell[:, 2] > obj.dimensions["seat_height"] + 0.15) & (np.abs(shell[:, 0]) < 0.05)
        ]
        # The back's mid-line leans to -y by tan(20-30 degrees) per metre of rise.
        slope = np.polyfit(back[:, 2], back[:, 1], 1)[0]
        assert np.tan(np.radians(15)) < -slope < np.tan(np.radians(35))
        assert back[:, 1].mean() < seat_y


def test_curved_shell_has_no_flat_seat(many):
    def flat_share(obj):
        """Share of the shell's upward-facing seat triangles that are level within 1 degree."""
        shell = obj.part_names.index("shell")
        tri = obj.vertices[obj.triangles[obj.triangle_part == shell]]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        seat = (tri[:, :, 2].max(axis=1) < obj.dimensions["seat_height"] + 0.03) & (n[:, 2] > 0.5)
        return np.mean(n[seat, 2] > np.cos(np.radians(1.0)))

    plain = [flat_share(make_furniture("chair-shell", s)) for s in range(3)]
    curved = [flat_share(o) for o in many["chair-shell-curved"][:3]]
    assert min(plain) > 0.1  # the plain shell's seat is a plane
    assert max(curved) < 0.05  # the tub's seat curves everywhere
    # The same draws give the curved variant of a plain shell.
    a, b = make_furniture("chair-shell", 3), make_furniture("chair-shell", 3, curved=True)
    assert a.dimensions["seat_height"] == b.dimensions["seat_height"]
    assert b.kind == "chair-shell" and flat_share(b) < 0.05


def test_bowls_and_basins_are_depressions(many):
    for kind in ("toilet", "toilet-wall-hung"):
        for obj in many[kind]:
            x, y = obj.extra["bowl_center"]
            inside = part_top_at(obj, "bowl", x, y)
            rim = obj.dimensions["rim_height"]
            assert inside == pytest.approx(rim - obj.dimensions["bowl_depth"], abs=1e-6)
            assert inside < rim - 0.15
            assert part_vertices(obj, "bowl")[:, 2].max() == pytest.approx(rim, abs=1e-6)
    for kind in ("sink-pedestal", "sink-vanity", "sink-wall-hung"):
        for obj in many[kind]:
            x, y = obj.extra["basin_center"]
            # Nothing else covers the basin: the whole object's top there is the bowl's bottom.
            inside = top_at(obj.vertices, obj.triangles, x, y)
            rim = obj.dimensions["rim_height"]
            assert inside == pytest.approx(rim - obj.dimensions["bowl_depth"], abs=1e-6)
            assert inside < rim - 0.1
    for obj in many["bathtub"]:
        x, y = obj.extra["tub_center"]
        inside = top_at(obj.vertices, obj.triangles, x, y)
        rim = obj.dimensions["rim_height"]
        assert inside == pytest.approx(rim - obj.dimensions["inner_depth"], abs=1e-6)
        assert 0.1 - 1e-9 <= inside <= rim - 0.38
        # The front panel reaches the floor.
        assert part_vertices(obj, "panel")[:, 2].min() == pytest.approx(0.0, abs=1e-9)


def test_toilet_seat_lid_and_cistern():
    for lid in ("up", "down", "none"):
        obj = make_furniture("toilet", 4, lid=lid)
        x, y = obj.extra["seat_center"]
        assert part_top_at(obj, "seat", x, y) == pytest.approx(obj.dimensions["seat_height"])
        assert ("lid" in obj.part_names) == (lid != "none")
        cistern = part_vertices(obj, "cistern")
        assert cistern[:, 2].max() == pytest.approx(obj.dimensions["cistern_height"])
        # The cistern stands at the back (y min), the bowl reaches the front.
        assert cistern[:, 1].min() == pytest.approx(obj.vertices[:, 1].min())
        if lid == "up":
            upright = part_vertices(obj, "lid")
            assert np.ptp(upright[:, 2]) > 5 * np.ptp(upright[:, 1])
        if lid == "down":
            flat = part_vertices(obj, "lid")
            assert flat[:, 2].min() >= obj.dimensions["seat_height"]
    hung = make_furniture("toilet-wall-hung", 2, cistern="concealed")
    assert hung.extra["wall_mounted"] and "pedestal" not in hung.part_names
    assert hung.vertices[:, 2].min() > 0.1  # nothing under the pan
    boxed = make_furniture("toilet-wall-hung", 2, cistern="boxed")
    assert boxed.vertices[:, 2].min() == pytest.approx(0.0, abs=1e-9)
    assert "wall_mounted" not in boxed.extra


def test_backsplash_is_an_option_of_every_sink():
    for kind in ("sink-pedestal", "sink-vanity", "sink-wall-hung"):
        with_it = make_furniture(kind, 5, backsplash=True, backsplash_height=0.2)
        without = make_furniture(kind, 5, backsplash=False)
        assert "backsplash" in with_it.part_names and "backsplash" not in without.part_names
        splash = part_vertices(with_it, "backsplash")
        assert np.ptp(splash[:, 2]) == pytest.approx(0.2)
        assert np.ptp(splash[:, 1]) < 0.02  # a thin panel along the back edge
        assert splash[:, 1].min() == pytest.approx(with_it.vertices[:, 1].min())
        assert without.dimensions["backsplash_height"] == 0.0
        assert with_it.dimensions["rim_height"] == without.dimensions["rim_height"]
    vanity = make_furniture("sink-vanity", 1)
    front = [p for p in ("door", "drawer") if p in vanity.part_names]
    assert front and part_vertices(vanity, front[0])[:, 2].min() < 0.005  # closed to the floor
    hung = make_furniture("sink-wall-hung", 1)
    assert hung.extra["wall_mounted"]
    assert hung.vertices[:, 2].min() == pytest.approx(part_vertices(hung, "trap")[:, 2].min())


def test_lamp_shade_is_a_hollow_cone_above_the_base(many):
    for obj in many["lamp-table"]:
        shade = part_vertices(obj, "shade")
        assert shade[:, 2].max() == pytest.approx(obj.dimensions["height"])
        low, high = (
            shade[shade[:, 2] < shade[:, 2].min() + 1e-9],
            shade[shade[:, 2] > shade[:, 2].max() - 1e-9],
        )
        assert np.hypot(low[:, 0], low[:, 1]).max() > np.hypot(high[:, 0], high[:, 1]).max()
        # Open: straight down the axis the first surface is the bulb, not a shade cap.
        assert part_top_at(obj, "shade", 0.0, 0.0) == -np.inf
        assert part_vertices(obj, "base")[:, 2].min() == pytest.approx(0.0, abs=1e-9)


def test_place_on_stands_a_lamp_on_a_nightstand():
    stand = place(make_furniture("nightstand", 3), 2.0, 1.0, np.pi / 2)
    lamp = place_on(make_furniture("lamp-table", 3), stand, (0.5, 0.5))
    assert lamp.vertices[:, 2].min() == pytest.approx(stand.extra["support_z"])
    assert np.allclose(lamp.pose[:2, 3], stand.box.center[:2], atol=0.03)
    assert lamp.yaw == pytest.approx(stand.yaw)
    with pytest.raises(InvalidParameterError, match="'support'"):
        place_on(lamp, make_furniture("chair-club", 0))


def test_new_kind_overrides_and_bad_values():
    obj = make_furniture("bathtub", 3, length=1.7, rim_height=0.55)
    assert obj.dimensions["width"] == pytest.approx(1.7)
    assert obj.dimensions["rim_height"] == pytest.approx(0.55)
    assert make_furniture("toilet", 3, seat_height=0.42).dimensions["seat_height"] == pytest.approx(
        0.42
    )
    tv = make_furniture("tv-stand", 3, width=1.5, top_height=0.5)
    assert tv.dimensions["width"] == pytest.approx(1.5) and tv.extra["support_z"] == 0.5
    with pytest.raises(InvalidParameterError, match="'lid'"):
        make_furniture("toilet", 0, lid="ajar")
    with pytest.raises(InvalidParameterError, match="'curved'"):
        make_furniture("chair-shell", 0, curved="very")
    with pytest.raises(InvalidParameterError, match="'backsplash'"):
        make_furniture("sink-vanity", 0, backsplash="tiled")
