"""Sweet Home 3D catalogues and the rooms furnished with them, on a catalogue the tests write.

The tests never need Debian's sweethome3d-furniture package: they build a small
``.sh3f`` (a zip with a properties file and OBJ + MTL models made of boxes)
whose model ids are ones the class mapping lists.
"""

from __future__ import annotations

import json
import zipfile
from collections import Counter

import numpy as np
import pytest

from ontodetect.cli import main
from ontodetect.errors import CorruptFileError, InvalidParameterError, ReadError
from ontodetect.synth import synthesize, write_synth
from ontodetect.synth.furnished import (
    CHALLENGES,
    FURNISHED_ROOM_TYPES,
    attribution,
    attribution_text,
    furnished_scene,
    model_classes,
)
from ontodetect.synth.scene import CLASS_IDS
from ontodetect.synth.sh3d import (
    CATALOG_DIR_ENV,
    default_catalog_dir,
    load_model,
    parse_properties,
    read_catalog,
    read_catalogs,
)

# --------------------------------------------------------------------------------------
# A tiny catalogue. Models are boxes in Sweet Home 3D's frame (y up, front towards +z),
# in arbitrary units: loading scales them to the declared size.

CHAIR = [  # seat, backrest at the back (-z), four legs
    ((-20, 40, -20), (20, 45, 20), "fabric"),
    ((-20, 45, -20), (20, 90, -16), "fabric"),
    *[((x, 0, z), (x + 3, 40, z + 3), "metal") for x in (-20, 17) for z in (-20, 17)],
]
TABLE = [
    ((-60, 68, -30), (60, 72, 30), "wood"),
    *[((x, 0, z), (x + 4, 68, z + 4), "wood") for x in (-60, 56) for z in (-30, 26)],
]
SOFA = [
    ((-90, 0, -40), (90, 42, 40), "fabric"),
    ((-90, 42, -40), (90, 85, -25), "fabric"),
    ((-90, 42, -25), (-78, 60, 40), "fabric"),
    ((78, 42, -25), (90, 60, 40), "fabric"),
]
# Authored z up (height along the OBJ's z): the entry's modelRotation turns it y up.
TABLE_Z_UP = [
    ((-60, -45, 70), (60, 45, 74), "wood"),
    *[((x, y, 0), (x + 5, y + 5, 70), "wood") for x in (-60, 55) for y in (-45, 40)],
]
RADIATOR = [((-50, 0, -5), (50, 60, 5), "metal")]
DOOR = [((-45, 0, -2), (45, 205, 2), "wood")]
MATERIALS = "newmtl fabric\nKd 0.8 0.1 0.1\nnewmtl wood\nKd 0.6 0.4 0.2\nnewmtl metal\nNs 10\n"
Z_UP_TO_Y_UP = "1 0 0 0 0 1 0 -1 0"

#: (id, model boxes, width, depth, height (cm), extra properties)
ENTRIES = [
    ("Scopia#office_chair", CHAIR, 50, 52, 95, {"creator": "Ada"}),
    ("Kator Legaz#dining-chair", CHAIR, 45, 50, 90, {"name": "Chaise \\u00e0 bascule"}),
    ("Blend Swap CC-0#lbDesk", TABLE, 140, 70, 74, {}),
    ("Blend Swap CC-0#oakTable", TABLE_Z_UP, 160, 90, 75, {"modelRotation": Z_UP_TO_Y_UP}),
    ("Scopia#beige_sofa", SOFA, 200, 85, 85, {"license": "Public domain"}),
    ("Blend Swap CC-BY#coffeeTable", TABLE, 100, 55, 45, {}),
    ("Blend Swap CC-BY#armchair1", SOFA, 85, 80, 80, {}),
    ("Blend Swap CC-0#radiator", RADIATOR, 100, 10, 60, {"elevation": "10"}),
    ("Kator Legaz#exterior-door-01", DOOR, 90, 4, 205, {"doorOrWindow": "true"}),
]


def obj_text(boxes):
    lines = ["mtllib model.mtl"]
    for k, (lo, hi, material) in enumerate(boxes):
        lines.append(f"usemtl {material}")
        for x in (lo[0], hi[0]):
            for y in (lo[1], hi[1]):
                for z in (lo[2], hi[2]):
                    lines.append(f"v {x} {y} {z}")
        b = 8 * k + 1
        # Corners: index = 4 * ix + 2 * iy + iz.
        quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
        for q in quads:
            a, c, d, e = (b + i for i in q)
            lines += [f"f {a} {c} {d}", f"f {a} {d} {e}"]
    return "\n".join(lines) + "\n"


def properties_text(entries):
    lines = [
        "# a catalogue written by the tests",
        "id=tests#catalog",
        "name=Test catalogue",
        "license=Creative Commons Attribution 3.0 license",
        "provider=tests",
    ]
    for n, (entry_id, _, w, d, h, extra) in enumerate(entries, start=1):
        folder = entry_id.split("#")[1]
        props = {
            "id": entry_id,
            "name": extra.get("name", folder),
            "category": "Test",
            "tags": "Seat, \\\n    Test",  # a continuation line
            "model": f"/test/{folder}/{folder}.obj",
            "width": w,
            "depth": d,
            "height": h,
            "creator": "Tester",
            **{k: v for k, v in extra.items() if k != "name"},
        }
        lines += [f"{k}#{n}={v}" for k, v in props.items()]
    return "\n".join(lines) + "\n"


def write_catalog(path, entries=ENTRIES, properties=None):
    with zipfile.ZipFile(path, "w") as z:
        z.writestr(
            "PluginFurnitureCatalog.properties",
            (properties or properties_text(entries)).encode("latin-1"),
        )
        for entry_id, boxes, *_ in entries:
            folder = entry_id.split("#")[1]
            z.writestr(f"test/{folder}/{folder}.obj", obj_text(boxes))
            z.writestr(f"test/{folder}/model.mtl", MATERIALS)
    return path


@pytest.fixture(scope="module")
def catalog_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sh3d")
    write_catalog(folder / "test.sh3f")
    return folder


@pytest.fixture(scope="module")
def catalog(catalog_dir):
    return read_catalog(catalog_dir / "test.sh3f")


# --------------------------------------------------------------------------------------
# Reading catalogues.


def test_properties_escapes_and_continuations():
    text = "# c\n! c\na=1\nb : two \\\n   words\nc\\=d=x\\ty\nname=\\u00e9t\\u00e9\n"
    assert parse_properties(text) == {"a": "1", "b": "two words", "c=d": "x\ty", "name": "été"}


def test_entries_sizes_in_metres_and_fields(catalog):
    assert catalog.name == "Test catalogue" and len(catalog) == len(ENTRIES)
    chair = catalog.entry("Scopia#office_chair")
    assert chair.size == pytest.approx((0.50, 0.52, 0.95))
    assert chair.creator == "Ada" and chair.tags == ("Seat", "Test")
    assert chair.license == "Creative Commons Attribution 3.0 license"  # the catalogue's
    assert catalog.entry("Scopia#beige_sofa").license == "Public domain"  # the entry's own
    assert catalog.entry("Kator Legaz#dining-chair").name == "Chaise à bascule"
    assert catalog.entry("Blend Swap CC-0#radiator").elevation == pytest.approx(0.10)
    assert catalog.entry("Kator Legaz#exterior-door-01").door_or_window
    assert not chair.door_or_window


def test_model_scaled_to_declared_size_and_z_up(catalog):
    entry = catalog.entry("Scopia#office_chair")
    mesh = load_model(entry)
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    np.testing.assert_allclose(hi - lo, entry.size, atol=1e-9)
    np.testing.assert_allclose([lo[0] + hi[0], lo[1] + hi[1], lo[2]], 0.0, atol=1e-9)
    # The backrest (the model's -z, its back) is the top of the chair at our -y.
    top = mesh.vertices[mesh.vertices[:, 2] > 0.8 * hi[2]]
    assert top[:, 1].max() < 0
    # Kd colours per material; grey where the material has none.
    fabric = mesh.part_names.index("fabric")
    metal = mesh.part_names.index("metal")
    assert tuple(mesh.triangle_color[mesh.triangle_part == fabric][0]) == (204, 26, 26)
    assert tuple(mesh.triangle_color[mesh.triangle_part == metal][0]) == (160, 160, 160)
    assert load_model(entry) is mesh  # cached


def test_model_rotation_applied(catalog):
    entry = catalog.entry("Blend Swap CC-0#oakTable")
    mesh = load_model(entry)
    np.testing.assert_allclose(np.ptp(mesh.vertices, axis=0), (1.60, 0.90, 0.75), atol=1e-9)
    # The top, authored at the OBJ's high z, is at our high z after the turn.
    z = mesh.vertices[:, 2]
    top_area = mesh.vertices[z > 0.7]
    assert np.ptp(top_area[:, 0]) == pytest.approx(1.6) and np.ptp(top_area[:, 1]) == pytest.approx(
        0.9
    )


def test_elevation_lifts_the_model(catalog):
    mesh = load_model(catalog.entry("Blend Swap CC-0#radiator"))
    assert mesh.vertices[:, 2].min() == pytest.approx(0.10)
    assert mesh.vertices[:, 2].max() == pytest.approx(0.70)


def test_missing_field_names_file_and_key(tmp_path):
    text = properties_text(ENTRIES[:1]).replace("height#1=95\n", "")
    path = write_catalog(tmp_path / "bad.sh3f", ENTRIES[:1], properties=text)
    with pytest.raises(CorruptFileError, match=r"bad\.sh3f.*height#1"):
        read_catalog(path)


def test_bad_number_names_the_key(tmp_path):
    text = properties_text(ENTRIES[:1]).replace("width#1=50", "width#1=wide")
    path = write_catalog(tmp_path / "bad.sh3f", ENTRIES[:1], properties=text)
    with pytest.raises(CorruptFileError, match=r"'width#1'.*'wide'"):
        read_catalog(path)


def test_corrupt_and_missing_files(tmp_path):
    junk = tmp_path / "junk.sh3f"
    junk.write_bytes(b"not a zip at all")
    with pytest.raises(CorruptFileError, match=r"junk\.sh3f.*not a zip"):
        read_catalog(junk)
    with pytest.raises(ReadError, match=r"nothing\.sh3f"):
        read_catalog(tmp_path / "nothing.sh3f")
    empty = tmp_path / "empty.sh3f"
    with zipfile.ZipFile(empty, "w") as z:
        z.writestr("readme.txt", "hello")
    with pytest.raises(CorruptFileError, match=r"PluginFurnitureCatalog\.properties"):
        read_catalog(empty)


def test_model_missing_from_archive(tmp_path):
    path = tmp_path / "nomodel.sh3f"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("PluginFurnitureCatalog.properties", properties_text(ENTRIES[:1]))
    entry = read_catalog(path).entries[0]
    with pytest.raises(CorruptFileError, match=r"nomodel\.sh3f.*office_chair.obj"):
        load_model(entry)


def test_default_catalog_dir_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv(CATALOG_DIR_ENV, str(tmp_path))
    assert default_catalog_dir() == tmp_path
    with pytest.raises(ReadError, match=r"no furniture catalogue"):
        read_catalogs()
    monkeypatch.setenv(CATALOG_DIR_ENV, str(tmp_path / "missing"))
    with pytest.raises(ReadError, match=CATALOG_DIR_ENV):
        default_catalog_dir()


def test_mapping_uses_known_classes():
    mapping = model_classes()
    assert mapping["Scopia#office_chair"] == ("chair", "chair-office")
    assert all(cls in CLASS_IDS for cls, _ in mapping.values())
    assert len(mapping) > 150


# --------------------------------------------------------------------------------------
# Furnished rooms on the tiny catalogue.

#: Classes that lie on a surface (seat, top) rather than on the floor.
ON_SURFACES = {"pillow", "clothes", "bag", "lamp", "television", "books", "otherprop"}
#: Classes other objects may reach under.
OPEN_BELOW = {"table", "desk"}


@pytest.fixture(scope="module")
def rooms(catalog_dir):
    return {
        (t, s): furnished_scene(t, s, catalog_dir=catalog_dir)
        for t in ("living_room", "office", "dining")
        for s in (0, 1)
    }


def furniture(scene):
    return [o for o in scene.objects if not o.is_structure]


def test_deterministic_for_a_seed(catalog_dir, rooms):
    again = furnished_scene("living_room", 0, catalog_dir=catalog_dir)
    first = rooms[("living_room", 0)]
    assert [o.kind for o in again.objects] == [o.kind for o in first.objects]
    for a, b in zip(again.objects, first.objects, strict=True):
        np.testing.assert_array_equal(a.vertices, b.vertices)
    other = rooms[("living_room", 1)]
    assert other.size != first.size


def test_rooms_hold_their_main_furniture(rooms):
    living = Counter(o.kind for o in furniture(rooms[("living_room", 0)]))
    assert living["sofa"] == 1 and living["table-coffee"] == 1 and living["armchair-club"] >= 1
    office = Counter(o.class_name for o in furniture(rooms[("office", 0)]))
    assert office["desk"] >= 2 and office["chair"] >= 2
    dining = Counter(o.kind for o in furniture(rooms[("dining", 1)]))
    assert dining["table-dining"] == 1 and dining["chair-dining"] >= 3


def test_classes_kinds_and_extra(rooms):
    mapping = model_classes()
    for scene in rooms.values():
        for obj in furniture(scene):
            assert obj.class_name in CLASS_IDS
            if obj.extra.get("generated"):
                assert obj.kind in {"cushion", "curtain", "clothes-folded", "bag"}
                continue
            assert set(obj.extra) == {"catalog", "model_id", "model_name", "creator", "license"}
            assert mapping[obj.extra["model_id"]] == (obj.class_name, obj.kind)
            assert obj.extra["model_id"] != "Kator Legaz#exterior-door-01"
            assert obj.extra["catalog"] == "Test catalogue"


def test_objects_stand_on_the_floor_or_on_something(rooms):
    for scene in rooms.values():
        objects = furniture(scene)
        for obj in objects:
            bottom = obj.vertices[:, 2].min()
            if obj.class_name in ON_SURFACES:
                below = [
                    o
                    for o in objects
                    if o is not obj
                    and o.box.contains(np.array([[*obj.box.center[:2], bottom - 0.01]]))[0]
                ]
                assert below, (obj.kind, bottom)
            elif obj.class_name == "curtain":
                assert 0.0 < bottom < 0.05 and obj.vertices[:, 2].max() >= 2.0
            else:
                assert bottom == pytest.approx(obj.dimensions["elevation"], abs=1e-9), obj.kind
            lo, hi = obj.vertices.min(axis=0), obj.vertices.max(axis=0)
            assert np.all(lo[:2] >= -1e-9) and np.all(hi <= np.asarray(scene.size) + 1e-9)


def test_no_two_objects_overlap(rooms):
    """Box test, except where a chair reaches under a table (then surfaces must stay apart)."""
    rng = np.random.default_rng(0)
    for scene in rooms.values():
        objects = furniture(scene)
        for i, a in enumerate(objects):
            for b in objects[i + 1 :]:
                if {a.class_name, b.class_name} & ON_SURFACES:
                    continue  # lies on its host by design
                tables = [o for o in (a, b) if o.class_name in OPEN_BELOW]
                if len(tables) == 1:
                    # Something may reach under a table, not into its top (the top 5 cm).
                    table, other = (a, b) if tables[0] is a else (b, a)
                    top = table.vertices[:, 2].max()
                    slab = table.vertices[table.vertices[:, 2] > top - 0.05]
                    lo, hi = slab.min(axis=0), slab.max(axis=0)
                    inside = np.all((other.vertices > lo + 0.01) & (other.vertices < hi - 0.01), 1)
                    assert not inside.any(), (table.kind, other.kind)
                    continue
                pts = b.vertices[rng.choice(len(b.vertices), min(400, len(b.vertices)))]
                assert not a.box.contains(pts, margin=-0.01).any(), (a.kind, b.kind)


def test_tucked_chairs_reach_under_the_top(catalog_dir):
    scene = furnished_scene("office", 3, catalog_dir=catalog_dir, challenges=["tucked_chairs"])
    desks = [o for o in furniture(scene) if o.class_name == "desk"]
    chairs = [o for o in furniture(scene) if o.class_name == "chair"]
    under = sum(
        any(d.box.contains(c.vertices[c.vertices[:, 2] < 0.6]).any() for d in desks) for c in chairs
    )
    assert under >= 1


def test_challenges_off_means_no_clutter_or_curtains(catalog_dir):
    for seed in range(3):
        scene = furnished_scene("living_room", seed, catalog_dir=catalog_dir, challenges=())
        kinds = {o.kind for o in furniture(scene)}
        assert not kinds & {"cushion", "curtain", "clothes-folded", "bag"}
        assert scene.extra["glazed_wall"] is None


def test_attribution_lists_models_and_licences(rooms):
    scene = rooms[("living_room", 0)]
    credits = attribution(scene)
    assert [c["catalog"] for c in credits] == ["Test catalogue"]
    used = Counter(o.extra["model_id"] for o in furniture(scene) if "model_id" in o.extra)
    assert {m["model_id"]: m["count"] for m in credits[0]["models"]} == dict(used)
    assert scene.extra["attribution"] == credits
    # The sofa carries its own licence; the other models the catalogue's.
    assert credits[0]["license"] == "Creative Commons Attribution 3.0 license; Public domain"
    sofa = next(m for m in credits[0]["models"] if m["model_id"] == "Scopia#beige_sofa")
    assert sofa["license"] == "Public domain"
    assert attribution_text(scene).startswith("Test catalogue (")


def test_scan_writes_attribution(tmp_path, rooms):
    result = synthesize(rooms[("living_room", 0)], "rgbd", seed=0, num_frames=4, stride=16)
    assert len(result.cloud) > 0
    folder = write_synth(result, tmp_path / "scan")
    data = json.loads((folder / "scene.json").read_text())
    assert data["room_type"] == "living_room"
    assert data["scene_extra"]["attribution"][0]["catalog"] == "Test catalogue"
    objects = json.loads((folder / "objects.json").read_text())["objects"]
    assert any(o.get("extra", {}).get("model_id") == "Scopia#beige_sofa" for o in objects)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"room_type": "attic"}, "room_type"),
        ({"seed": -1}, "seed"),
        ({"challenges": ["dragons"]}, "challenges"),
    ],
)
def test_bad_parameters(catalog_dir, kwargs, match):
    args = {"room_type": "office", "seed": 0, **kwargs}
    with pytest.raises(InvalidParameterError, match=match):
        furnished_scene(args.pop("room_type"), args.pop("seed"), catalog_dir=catalog_dir, **args)


def test_folder_without_mapped_models(tmp_path):
    write_catalog(tmp_path / "doors.sh3f", ENTRIES[-1:])
    with pytest.raises(ReadError, match=r"sh3d_classes\.yaml"):
        furnished_scene("office", 0, catalog_dir=tmp_path)


def test_room_types_and_challenges_are_listed():
    assert "open_plan" in FURNISHED_ROOM_TYPES and "bathroom" in FURNISHED_ROOM_TYPES
    assert "glazed_wall" in CHALLENGES


def test_cli_furnished(tmp_path, catalog_dir, capsys):
    out = tmp_path / "out"
    quick = ["--catalog", str(catalog_dir), "-O", "num_frames=2", "-O", "stride=16"]
    code = main(["synth", "--room", "living_room", *quick, "-o", str(out)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert json.loads((out / "scene.json").read_text())["scene_extra"]["furnished"]
    code = main(
        ["synth", "--room", "dining,office", "--count", "2", "--seed", "4", *quick, "-o", str(out)]
    )
    lines = capsys.readouterr().out.strip().splitlines()
    assert code == 0 and len(lines) == 2
    seeds = [json.loads((out / f"scene_{i:04d}" / "scene.json").read_text()) for i in (0, 1)]
    assert [(d["room_type"], d["seed"]) for d in seeds] == [("dining", 4), ("office", 5)]
    code = main(["synth", "--room", "attic", "--furnished", "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "attic" in err[0]
    code = main(["synth", "--room", "office", "--catalog", str(tmp_path / "none"), "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "none" in err[0]
