"""Rooms furnished with furniture that designers made: Sweet Home 3D catalogue models.

The parametric furniture of :mod:`~ontodetect.synth.furniture` shares the
assumptions of the detector's priors. To measure how the detector generalizes,
:func:`furnished_scene` furnishes a room with models of Sweet Home 3D furniture
catalogues (:mod:`~ontodetect.synth.sh3d`) instead: office and dining chairs,
club armchairs, lounge chairs, sofas, coffee tables, desks, and the things a
room is full of that are neither (beds, nightstands, toilets, sinks, bathtubs,
counters, wardrobes, lamps, plants, radiators, curtains).

Which model is which class and furniture family comes from the package's data
file ``data/sh3d_classes.yaml`` (see :func:`model_classes`), matched by the
catalogue's model id. The room shell is :func:`~ontodetect.synth.rooms.build_shell`'s;
the result is a :class:`~ontodetect.synth.scene.Scene`, so the virtual sensors
and :func:`~ontodetect.synth.dataset.write_synth` work unchanged.

Placement follows each room type's habits (chairs round tables and under desks,
sofas facing coffee tables, beds against walls with nightstands at the head,
toilets, sinks and counters against walls) and adds the scenes that broke the
detector on real rooms (:data:`CHALLENGES`): chairs pushed under desks and
tables so that only the backrest shows above the top, armchairs side by side,
cushions, clothes and bags on seats, a glazed wall, and curtains. No two objects
interpenetrate: upright boxes are tested first, and where one object may reach
under another (a chair under a table top) their surfaces are compared on a
2 cm voxel grid. Every object stands on the floor, hangs on a wall at its
catalogue elevation, or lies on a surface.

Models made by others come with licences: :func:`attribution` lists the
catalogues, creators and licences of the models a scene uses, and
:func:`furnished_scene` stores it in ``scene.extra["attribution"]`` (written to
scene.json). :data:`ATTRIBUTION` is the text to cite for the catalogues.
"""

from __future__ import annotations

import functools
import math
import os
from collections import Counter
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from ..errors import CorruptFileError, InvalidParameterError, ReadError
from ..geometry import _mesh as M
from .dataset import synthesize
from .furniture import place
from .rooms import _WALL_YAW, CONTACT_TOLERANCE, _box_rows, _overlapping, build_shell
from .scene import CLASS_IDS, OrientedBox, Scene, SceneObject
from .sh3d import CatalogEntry, ModelMesh, load_model, read_catalogs

__all__ = [
    "ATTRIBUTION",
    "CHALLENGES",
    "FURNISHED_ROOM_TYPES",
    "attribution",
    "attribution_text",
    "available_families",
    "furnished_scene",
    "model_classes",
    "synthesize_furnished",
]

#: Room types :func:`furnished_scene` knows.
FURNISHED_ROOM_TYPES: tuple[str, ...] = (
    "office",
    "conference",
    "classroom",
    "dining",
    "living_room",
    "bedroom",
    "bathroom",
    "kitchen",
    "open_plan",
)
#: The scenes that broke the detector on real rooms (docs/DESIGN "Lessons from rooms kept
#: aside"); :func:`furnished_scene` adds all of them unless told otherwise.
CHALLENGES: tuple[str, ...] = (
    "tucked_chairs",  # chairs pushed under desks and tables: only the backrest shows
    "side_by_side",  # armchairs touching each other
    "seat_clutter",  # cushions, clothes and bags on seats
    "glazed_wall",  # a wall of glass panes (offices, living rooms, open plan)
    "curtains",  # curtains from near the floor to 2 m and more
)
#: What to cite for the catalogues the furnished rooms use.
ATTRIBUTION = (
    "Furniture models from the Sweet Home 3D furniture libraries (Debian package "
    "sweethome3d-furniture, www.sweethome3d.com), converted to OBJ by Emmanuel Puybaret / "
    "eTeks: Blend Swap CC-0 (public domain) and Blend Swap CC-BY (Creative Commons "
    "Attribution 3.0; models by their Blend Swap authors, named per model), Kator Legaz "
    "(Creative Commons Attribution 3.0 US, (c) 2003-2008 Andrew Kator & Jennifer Legaz), "
    "Scopia (Creative Commons Attribution 3.0, (c) Emmanuel Puybaret / eTeks and Scopia "
    "Visual Interfaces Systems)."
)
CLASSES_FORMAT = "ontodetect.sh3d-classes/1"

# Floor plans (length x width, metres) per room type.
_ROOM_SIZES: dict[str, tuple[tuple[float, float], tuple[float, float]]] = {
    "office": ((4.5, 7.0), (3.6, 5.5)),
    "conference": ((5.5, 8.5), (4.0, 6.0)),
    "classroom": ((7.0, 9.5), (6.0, 7.5)),
    "dining": ((4.0, 5.5), (3.4, 4.5)),
    "living_room": ((4.5, 7.0), (3.8, 5.5)),
    "bedroom": ((3.6, 5.0), (3.2, 4.5)),
    "bathroom": ((2.2, 3.4), (1.9, 2.8)),
    "kitchen": ((3.6, 5.0), (3.0, 4.0)),
    "open_plan": ((8.0, 11.0), (6.0, 8.0)),
}
_CEILING_HEIGHT = (2.5, 3.0)
#: Room types whose glazed wall comes with the ``glazed_wall`` challenge (probability).
_GLAZED_CHANCE = {"open_plan": 1.0, "office": 0.5, "living_room": 0.5, "conference": 0.5}
#: Room types that get curtains at their windows with the ``curtains`` challenge.
_CURTAIN_ROOMS = ("living_room", "bedroom", "open_plan", "office", "dining", "conference")
#: At most this many pieces of furniture per room (keeps a scan at 50,000 points fast).
MAX_OBJECTS = 60
#: Furnishing is retried (up to _FURNISH_ATTEMPTS times) until a room holds this much;
#: otherwise the attempt closest to it is kept.
_MIN_COUNTS: dict[str, dict[str, int]] = {
    "office": {"desk": 2, "chair": 2},
    "conference": {"table": 1, "chair": 6},
    "classroom": {"chair": 8},
    "dining": {"table": 1, "chair": 4},
    "living_room": {"sofa": 1, "table": 1, "chair": 1},
    "bedroom": {"bed": 1, "nightstand": 1},
    "bathroom": {"toilet": 1, "sink": 1},
    "kitchen": {"counter": 2, "chair": 1},
    "open_plan": {"sofa": 1, "table": 2, "chair": 4},
}
_FURNISH_ATTEMPTS = 4
#: Voxel size (metres) of the surface test between objects whose boxes overlap.
SURFACE_VOXEL = 0.02
#: Surface samples per square metre for that test (1 cm spacing), at most _MAX_SAMPLES.
_SAMPLES_PER_M2 = 10_000
_MAX_SAMPLES = 40_000
_MAX_VERTEX_SAMPLES = 5_000
#: Horizontal triangles (|normal z| above this) make tops and seats.
_HORIZONTAL = 0.9
#: Placement attempts per object.
_TRIES = 30
#: Families that are seats (their seat is found from the mesh: the largest horizontal
#: surface 0.25-0.8 m up).
_SEATING_CLASSES = ("chair", "sofa", "stool", "bench", "ottoman", "bed")
#: Families whose top carries things; chairs may go under tables and desks.
_OPEN_BELOW_CLASSES = ("table", "desk")

_CUSHION_COLORS = [(180, 40, 40), (230, 200, 60), (60, 90, 160), (220, 220, 210), (90, 140, 90)]
_CURTAIN_COLORS = [(230, 226, 210), (200, 190, 170), (120, 130, 150), (150, 60, 60), (80, 80, 90)]
_CLOTH_COLORS = [(40, 40, 60), (120, 120, 130), (160, 30, 40), (30, 90, 140), (200, 180, 140)]


# --------------------------------------------------------------------------------------
# The class mapping.


@dataclass(frozen=True)
class _Family:
    name: str
    class_name: str
    models: tuple[str, ...]


@functools.cache
def _families() -> dict[str, _Family]:
    text = resources.files("ontodetect").joinpath("data/sh3d_classes.yaml").read_text("utf-8")
    where = "builtin:sh3d_classes.yaml"
    data = yaml.safe_load(text)
    if not isinstance(data, dict) or data.get("format") != CLASSES_FORMAT:
        raise CorruptFileError(where, f"'format' should be {CLASSES_FORMAT!r}")
    out = {}
    for name, spec in (data.get("families") or {}).items():
        if not isinstance(spec, dict) or spec.get("class") not in CLASS_IDS:
            raise CorruptFileError(
                where, f"family {name!r}: 'class' should be a key of CLASS_IDS, found {spec!r}"
            )
        models = tuple(str(m) for m in spec.get("models") or ())
        out[str(name)] = _Family(str(name), str(spec["class"]), models)
    return out


def model_classes() -> dict[str, tuple[str, str]]:
    """Catalogue model id -> (class, family) of every model the furnished rooms use.

    Read from the package's ``data/sh3d_classes.yaml``.

    Examples
    --------
    >>> model_classes()["Scopia#office_chair"]
    ('chair', 'chair-office')
    >>> model_classes()["Blend Swap CC-BY#coffeeTable"]
    ('table', 'table-coffee')
    """
    return {m: (f.class_name, f.name) for f in _families().values() for m in f.models}


def available_families(catalog_dir: str | os.PathLike[str] | None = None) -> dict[str, int]:
    """How many models of each family the catalogues of ``catalog_dir`` hold.

    Parameters
    ----------
    catalog_dir : str or PathLike, optional
        Folder of ``.sh3f`` files (default :func:`~ontodetect.synth.sh3d.default_catalog_dir`).

    Returns
    -------
    dict of str to int
        Family -> number of models, in the order of the mapping file.
    """
    library = _Library.load(catalog_dir)
    return {name: len(entries) for name, entries in library.by_family.items()}


@dataclass
class _Library:
    """The catalogue entries available per family."""

    by_family: dict[str, list[CatalogEntry]]

    @classmethod
    def load(cls, catalog_dir: str | os.PathLike[str] | None) -> _Library:
        catalogs = read_catalogs(catalog_dir)
        entries = {e.id: e for c in catalogs for e in c if not e.door_or_window}
        by_family = {}
        for name, fam in _families().items():
            found = [entries[m] for m in fam.models if m in entries]
            if found:
                by_family[name] = found
        if not by_family:
            where = catalog_dir if catalog_dir is not None else "the catalogue folder"
            raise ReadError(
                where, "none of its catalogues holds a model listed in data/sh3d_classes.yaml"
            )
        return cls(by_family)


# --------------------------------------------------------------------------------------
# Objects from models.


@dataclass
class _Surface:
    """A horizontal surface of an object in its own frame: height and rectangle."""

    z: float
    rect: tuple[float, float, float, float]  # x0, y0, x1, y1


def _horizontal_surfaces(mesh: ModelMesh) -> tuple[NDArray, NDArray, NDArray]:
    """Centres (k, 3) and areas (k,) of the horizontal triangles, and their xy corners."""
    v = mesh.vertices[mesh.triangles]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    area2 = np.linalg.norm(n, axis=1)
    flat = np.abs(n[:, 2]) > _HORIZONTAL * np.maximum(area2, 1e-15)
    return v[flat].mean(axis=1), area2[flat] / 2, v[flat]


def _surface_at(
    centres: NDArray, areas: NDArray, corners: NDArray, z_lo: float, z_hi: float, pick: str
) -> _Surface | None:
    """The horizontal surface between ``z_lo`` and ``z_hi``: the highest or the largest."""
    keep = (centres[:, 2] >= z_lo) & (centres[:, 2] <= z_hi)
    if not keep.any():
        return None
    z = centres[keep, 2]
    a = areas[keep]
    bins = np.floor(z / 0.02).astype(np.int64)
    _, inverse = np.unique(bins, return_inverse=True)
    per_bin = np.bincount(inverse, weights=a)
    if pick == "largest":
        b = int(np.argmax(per_bin))
    else:  # the highest bin holding a fifth of the largest one's area
        b = int(np.flatnonzero(per_bin >= 0.2 * per_bin.max())[-1])
    sel = np.flatnonzero(keep)[inverse == b]
    xy = corners[sel][:, :, :2].reshape(-1, 2)
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    height = float(np.average(centres[sel, 2], weights=areas[sel]))
    return _Surface(height, (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])))


@dataclass
class _Item:
    """A SceneObject being placed, with what placement needs to know about it."""

    obj: SceneObject
    top: _Surface | None = None  # local frame, for things put on it
    seat: _Surface | None = None
    open_below: bool = False
    on: int | None = None  # index of the object it lies on
    ignore_keepouts: bool = False
    samples: NDArray[np.float64] | None = None  # surface points in the object frame
    _voxels: NDArray[np.int64] | None = field(default=None, repr=False)

    def voxels(self) -> NDArray[np.int64]:
        """Sorted unique keys of the 2 cm voxels the object's surface passes through."""
        if self._voxels is None:
            pose = self.obj.pose
            if self.samples is None:
                local = _surface_samples(
                    (self.obj.vertices - pose[:3, 3]) @ pose[:3, :3], self.obj.triangles
                )
            else:
                local = self.samples
            self._voxels = _voxel_keys(local @ pose[:3, :3].T + pose[:3, 3])
        return self._voxels


def _surface_samples(vertices: NDArray, triangles: NDArray) -> NDArray[np.float64]:
    """(n, 3) points spread over the surface (1 cm apart on average) plus the vertices."""
    v = vertices[triangles]
    area = np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1) / 2
    total = float(area.sum())
    if total <= 0:
        return np.asarray(vertices, dtype=np.float64)
    n = int(np.clip(total * _SAMPLES_PER_M2, 200, _MAX_SAMPLES))
    rng = np.random.default_rng(0)  # the same object always gives the same samples
    tri = rng.choice(len(triangles), n, p=area / total)
    r = rng.random((n, 2))
    flip = r.sum(axis=1) > 1
    r[flip] = 1 - r[flip]
    t = v[tri]
    points = t[:, 0] + r[:, :1] * (t[:, 1] - t[:, 0]) + r[:, 1:] * (t[:, 2] - t[:, 0])
    # The vertices too (thin parts have little area), at most _MAX_VERTEX_SAMPLES of them.
    step = max(1, len(vertices) // _MAX_VERTEX_SAMPLES)
    return np.concatenate([points, vertices[::step]])


@functools.lru_cache(maxsize=256)
def _model_samples(entry: CatalogEntry) -> NDArray[np.float64]:
    mesh = load_model(entry)
    samples = _surface_samples(mesh.vertices, mesh.triangles)
    samples.flags.writeable = False
    return samples


def _voxel_keys(points: NDArray[np.float64]) -> NDArray[np.int64]:
    """Sorted unique keys of the SURFACE_VOXEL cells holding the (n, 3) points."""
    ijk = np.floor(points / SURFACE_VOXEL).astype(np.int64) + (1 << 19)
    return np.unique((ijk[:, 0] << 42) | (ijk[:, 1] << 21) | ijk[:, 2])


def _model_item(entry: CatalogEntry, family: _Family) -> _Item:
    """The entry's model as an object at the origin (identity pose)."""
    mesh = load_model(entry)
    v = mesh.vertices
    lo, hi = v.min(axis=0), v.max(axis=0)
    centre = (lo + hi) / 2
    dims = {
        "width": float(entry.width),
        "depth": float(entry.depth),
        "height": float(entry.height),
        "elevation": float(entry.elevation),
    }
    centres, areas, corners = _horizontal_surfaces(mesh)
    top = seat = None
    cls = family.class_name
    if cls in _SEATING_CLASSES:
        seat = _surface_at(
            centres, areas, corners, 0.2, min(0.85, 0.9 * float(hi[2])), pick="largest"
        )
        if seat is not None:
            dims["seat_height"] = seat.z
    else:
        top = _surface_at(centres, areas, corners, 0.3 * float(hi[2]), float(hi[2]), "highest")
        if top is not None and cls in _OPEN_BELOW_CLASSES + ("nightstand", "dresser", "counter"):
            dims["top_height"] = top.z
    obj = SceneObject(
        instance_id=0,
        class_name=cls,
        kind=family.name,
        vertices=v,
        triangles=mesh.triangles,
        triangle_part=mesh.triangle_part,
        part_names=list(mesh.part_names),
        triangle_color=mesh.triangle_color,
        pose=np.eye(4),
        dimensions=dims,
        box=OrientedBox(
            (float(centre[0]), float(centre[1]), float(centre[2])),
            tuple(float(x) for x in hi - lo),
            0.0,
        ),
        extra={
            "catalog": entry.catalog,
            "model_id": entry.id,
            "model_name": entry.name,
            "creator": entry.creator,
            "license": entry.license,
        },
    )
    return _Item(
        obj,
        top=top,
        seat=seat,
        open_below=cls in _OPEN_BELOW_CLASSES,
        samples=_model_samples(entry),
    )


def _mesh_item(
    class_name: str,
    kind: str,
    mesh: M.Mesh,
    color: tuple[int, int, int],
    part: str,
    dims: dict[str, float] | None = None,
) -> _Item:
    """A simple generated object (cushion, curtain, bag) at the origin."""
    lo, hi = mesh.bounds
    centre = (lo + hi) / 2
    t = len(mesh.triangles)
    size = hi - lo
    obj = SceneObject(
        instance_id=0,
        class_name=class_name,
        kind=kind,
        vertices=mesh.vertices,
        triangles=np.asarray(mesh.triangles, np.int32),
        triangle_part=np.zeros(t, np.int32),
        part_names=[part],
        triangle_color=np.tile(np.asarray(color, np.uint8), (t, 1)),
        pose=np.eye(4),
        dimensions=dims
        or {"width": float(size[0]), "depth": float(size[1]), "height": float(size[2])},
        box=OrientedBox(
            (float(centre[0]), float(centre[1]), float(centre[2])),
            tuple(float(x) for x in size),
            0.0,
        ),
        extra={"generated": True},
    )
    return _Item(obj)


def _moved(item: _Item, x: float, y: float, yaw: float, z: float = 0.0) -> _Item:
    return _Item(
        place(item.obj, x, y, yaw, z),
        top=item.top,
        seat=item.seat,
        open_below=item.open_below,
        ignore_keepouts=item.ignore_keepouts,
        samples=item.samples,
    )


def _local_to_world(obj: SceneObject, x: float, y: float) -> tuple[float, float]:
    p = obj.pose @ np.array([x, y, 0.0, 1.0])
    return float(p[0]), float(p[1])


# --------------------------------------------------------------------------------------
# The room being furnished.


class _Room:
    def __init__(
        self,
        rng: np.random.Generator,
        room_type: str,
        size: tuple[float, float, float],
        library: _Library,
        keepouts: NDArray[np.float64],
        openings: list[dict[str, Any]],
        challenges: frozenset[str],
    ) -> None:
        self.rng = rng
        self.room_type = room_type
        self.L, self.W, self.H = size
        self.library = library
        self.keepouts = keepouts
        self.openings = openings
        self.challenges = challenges
        self.items: list[_Item] = []
        self._rows = np.zeros((0, 7))
        self.wall_of: dict[int, tuple[int, float, float]] = {}  # item index -> wall, u0, u1

    # -- random draws
    def uniform(self, low: float, high: float) -> float:
        return float(self.rng.uniform(low, high))

    def chance(self, p: float) -> bool:
        return bool(self.rng.random() < p)

    def pick(self, options: Sequence[Any]) -> Any:
        return options[int(self.rng.integers(len(options)))]

    def has(self, challenge: str) -> bool:
        return challenge in self.challenges

    # -- models
    def model(self, *families: str) -> _Item | None:
        """A random model of one of ``families`` (those the catalogues have), or None."""
        present = [f for f in families if f in self.library.by_family]
        if not present:
            return None
        family = _families()[self.pick(present)]
        return _model_item(self.pick(self.library.by_family[family.name]), family)

    def full(self) -> bool:
        return len(self.items) >= MAX_OBJECTS

    # -- walls: wall k has its origin at an inner corner, u along it and d into the room
    def wall_length(self, k: int) -> float:
        return self.L if k % 2 == 0 else self.W

    def wall_point(self, k: int, u: float, d: float) -> tuple[float, float]:
        origin = [(0.0, 0.0), (self.L, 0.0), (self.L, self.W), (0.0, self.W)][k]
        e = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][k]
        n = [(0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 0.0)][k]
        return (origin[0] + u * e[0] + d * n[0], origin[1] + u * e[1] + d * n[1])

    # -- collisions
    def fits(self, item: _Item, ignore: Collection[int] = ()) -> bool:
        v = item.obj.vertices
        lo, hi = v.min(axis=0), v.max(axis=0)
        if (
            lo[0] < -1e-9
            or lo[1] < -1e-9
            or hi[0] > self.L + 1e-9
            or hi[1] > self.W + 1e-9
            or hi[2] > self.H - 0.05
        ):
            return False
        row = _box_rows([item.obj.box])
        if (
            not item.ignore_keepouts
            and len(self.keepouts)
            and _overlapping(row, self.keepouts).any()
        ):
            return False
        if not len(self._rows):
            return True
        hits = np.flatnonzero(_overlapping(row, self._rows, CONTACT_TOLERANCE)[0])
        for j in hits:
            if int(j) in ignore:
                continue
            other = self.items[int(j)]
            if not (item.open_below or other.open_below):
                return False
            if np.intersect1d(item.voxels(), other.voxels(), assume_unique=True).size:
                return False
        return True

    def add(self, item: _Item) -> int:
        self.items.append(item)
        self._rows = np.vstack([self._rows, _box_rows([item.obj.box])])
        return len(self.items) - 1

    def remove_last(self) -> None:
        """Take back the object placed last."""
        self.items.pop()
        self._rows = self._rows[:-1]
        self.wall_of.pop(len(self.items), None)

    def try_add(self, item: _Item, ignore: Collection[int] = ()) -> int | None:
        if self.full() or not self.fits(item, ignore):
            return None
        return self.add(item)

    # -- placement rules
    def against_wall(
        self,
        item: _Item | None,
        *,
        walls: Sequence[int] | None = None,
        u: float | None = None,
        corner: bool = False,
        tries: int = _TRIES,
    ) -> int | None:
        """Stand ``item`` with its back to a wall, facing into the room."""
        if item is None:
            return None
        w, d = item.obj.dimensions["width"], item.obj.dimensions["depth"]
        options = list(walls) if walls is not None else [0, 1, 2, 3]
        for _ in range(tries):
            k = self.pick(options)
            length = self.wall_length(k)
            if w > length:
                continue
            if u is not None:
                uc = u
            elif corner:
                uc = w / 2 + 0.01 if self.chance(0.5) else length - w / 2 - 0.01
            else:
                uc = self.uniform(w / 2, length - w / 2)
            x, y = self.wall_point(k, uc, d / 2 + self.uniform(0.0, 0.02))
            i = self.try_add(_moved(item, x, y, _WALL_YAW[k]))
            if i is not None:
                self.wall_of[i] = (k, uc - w / 2, uc + w / 2)
                return i
        return None

    def beside(self, anchor: int | None, item: _Item | None, gap: float = 0.02) -> int | None:
        """Against the same wall as ``anchor``, to its left or right."""
        if anchor is None or item is None or anchor not in self.wall_of:
            return None
        k, u0, u1 = self.wall_of[anchor]
        w = item.obj.dimensions["width"]
        sides = [u1 + gap + w / 2, u0 - gap - w / 2]
        if self.chance(0.5):
            sides.reverse()
        for uc in sides:
            i = self.against_wall(item, walls=[k], u=uc, tries=1)
            if i is not None:
                return i
        return None

    def free(
        self,
        item: _Item | None,
        *,
        region: tuple[float, float, float, float] | None = None,
        yaw: tuple[float, float] | float | None = None,
        tries: int = _TRIES,
    ) -> int | None:
        """Stand ``item`` anywhere in ``region`` (x0, y0, x1, y1)."""
        if item is None:
            return None
        x0, y0, x1, y1 = region or (0.0, 0.0, self.L, self.W)
        r = 0.5 * math.hypot(item.obj.dimensions["width"], item.obj.dimensions["depth"])
        for _ in range(tries):
            x = self.uniform(min(x0 + r, (x0 + x1) / 2), max(x1 - r, (x0 + x1) / 2))
            y = self.uniform(min(y0 + r, (y0 + y1) / 2), max(y1 - r, (y0 + y1) / 2))
            if yaw is None:
                angle = self.pick(_WALL_YAW) + self.uniform(-0.1, 0.1)
            elif isinstance(yaw, tuple):
                angle = self.uniform(*yaw)
            else:
                angle = float(yaw)
            i = self.try_add(_moved(item, x, y, angle))
            if i is not None:
                return i
        return None

    def in_corner(self, item: _Item | None, tries: int = 12) -> int | None:
        if item is None:
            return None
        r = 0.5 * max(item.obj.dimensions["width"], item.obj.dimensions["depth"])
        for _ in range(tries):
            cx, cy = self.pick([(0, 0), (1, 0), (1, 1), (0, 1)])
            off = r + self.uniform(0.02, 0.1)
            x = off if cx == 0 else self.L - off
            y = off if cy == 0 else self.W - off
            i = self.try_add(_moved(item, x, y, self.uniform(-np.pi, np.pi)))
            if i is not None:
                return i
        return None

    def on_top(self, host: int | None, item: _Item | None, tries: int = 12) -> int | None:
        """Put ``item`` on ``host``'s top surface (or its seat, for seating)."""
        if host is None or item is None:
            return None
        h = self.items[host]
        surface = h.top if h.top is not None else h.seat
        if surface is None:
            return None
        sx0, sy0, sx1, sy1 = surface.rect
        w, d = item.obj.dimensions["width"], item.obj.dimensions["depth"]
        margin = 0.03
        for _ in range(tries):
            rel = self.uniform(-np.pi, np.pi)
            c, s = abs(math.cos(rel)), abs(math.sin(rel))
            hw, hd = (c * w + s * d) / 2, (s * w + c * d) / 2
            if sx1 - sx0 < 2 * (hw + margin) or sy1 - sy0 < 2 * (hd + margin):
                continue
            lx = self.uniform(sx0 + hw + margin, sx1 - hw - margin)
            ly = self.uniform(sy0 + hd + margin, sy1 - hd - margin)
            x, y = _local_to_world(h.obj, lx, ly)
            moved = _moved(item, x, y, h.obj.yaw + rel, surface.z + float(h.obj.pose[2, 3]))
            moved.on = host
            i = self.try_add(moved, ignore=(host,))
            if i is not None:
                return i
        return None

    def seat_at(
        self,
        table: int,
        chair: _Item | None,
        edge: tuple[float, float],
        normal: tuple[float, float],
        *,
        tucked: bool,
    ) -> int | None:
        """Set ``chair`` at the table's edge point (table frame), facing the table.

        A tucked chair starts with most of its seat under the top and backs off
        until it fits; a loose one stands 5-40 cm out.
        """
        if chair is None:
            return None
        t = self.items[table].obj
        depth = chair.obj.dimensions["depth"]
        if tucked:
            start = self.uniform(0.35, 0.65) * depth
        else:
            start = -self.uniform(0.05, 0.4)
        yaw_table = t.yaw
        out = math.atan2(normal[1], normal[0])
        # The chair's front (+y) points against the normal: yaw = direction(-normal) - 90 deg.
        yaw = yaw_table + out + np.pi / 2 + self.uniform(-0.12, 0.12)
        for tuck in np.arange(start, -0.45, -0.03):
            d = depth / 2 - tuck
            x, y = _local_to_world(t, edge[0] + normal[0] * d, edge[1] + normal[1] * d)
            i = self.try_add(_moved(chair, x, y, yaw))
            if i is not None:
                return i
        return None

    def chairs_around(self, table: int | None, families: Sequence[str], count: int) -> list[int]:
        """Up to ``count`` chairs of one model round a table, spaced along its long sides."""
        if table is None:
            return []
        top = self.items[table].top
        x0, y0, x1, y1 = top.rect if top is not None else (-0.5, -0.5, 0.5, 0.5)
        first = self.model(*families)
        if first is None:
            return []
        width = first.obj.dimensions["width"]
        slots = []
        per_side = max(1, int((x1 - x0 + 0.1) // (width + 0.12)))
        for side in (1, -1):
            for j in range(per_side):
                u = x0 + (j + 0.5) * (x1 - x0) / per_side
                slots.append(((u, y1 if side > 0 else y0), (0.0, float(side))))
        if y1 - y0 > width + 0.2:
            slots += [(((x1, (y0 + y1) / 2)), (1.0, 0.0)), ((x0, (y0 + y1) / 2), (-1.0, 0.0))]
        order = self.rng.permutation(len(slots))
        placed = []
        for k in order[:count]:
            edge, normal = slots[int(k)]
            tucked = self.has("tucked_chairs") and self.chance(0.7)
            i = self.seat_at(table, first, edge, normal, tucked=tucked)
            if i is not None:
                placed.append(i)
        return placed

    def chair_at_desk(self, desk: int | None, families: Sequence[str]) -> int | None:
        if desk is None:
            return None
        top = self.items[desk].top
        x0, _, x1, y1 = top.rect if top is not None else (-0.4, -0.3, 0.4, 0.3)
        u = self.uniform(x0 + 0.3 * (x1 - x0), x1 - 0.3 * (x1 - x0))
        tucked = self.has("tucked_chairs") and self.chance(0.75)
        return self.seat_at(desk, self.model(*families), (u, y1), (0.0, 1.0), tucked=tucked)

    def seat_clutter(self, seat: int | None, p: float = 0.5) -> None:
        """Cushions, clothes or a bag on a seat (the ``seat_clutter`` challenge)."""
        if seat is None or not self.has("seat_clutter") or not self.chance(p):
            return
        host = self.items[seat]
        if host.seat is None:
            return
        what = self.pick(["cushion", "cushion", "clothes", "bag"])
        if what == "cushion":
            n = 1 if host.obj.class_name != "sofa" else int(self.rng.integers(1, 4))
            for _ in range(n):
                self.cushion_on(seat)
        elif what == "clothes":
            item = self.model("clothes") or _clothes_item(self.rng)
            self.on_seat(seat, item)
        else:
            item = self.model("bag") or _bag_item(self.rng)
            self.on_seat(seat, item)

    def on_seat(self, seat: int, item: _Item) -> int | None:
        host = self.items[seat]
        saved = host.top
        host.top = host.seat
        try:
            return self.on_top(seat, item)
        finally:
            host.top = saved

    def cushion_on(self, seat: int) -> int | None:
        """A cushion leaning back at the back of the seat."""
        host = self.items[seat]
        sx0, sy0, sx1, sy1 = host.seat.rect
        size = (self.uniform(0.38, 0.5), self.uniform(0.1, 0.15), self.uniform(0.38, 0.5))
        if sx1 - sx0 < size[0] + 0.04 or sy1 - sy0 < size[1] + 0.1:
            return None
        tilt = self.uniform(0.15, 0.45)
        mesh = M.cushion(size, softness=0.3).translated((0, 0, size[2] / 2)).rotated("x", -tilt)
        mesh = mesh.translated((0.0, -float(mesh.bounds[0][1]), -float(mesh.bounds[0][2])))
        item = _mesh_item("pillow", "cushion", mesh, self.pick(_CUSHION_COLORS), "cushion")
        for _ in range(8):
            lx = self.uniform(sx0 + size[0] / 2 + 0.02, sx1 - size[0] / 2 - 0.02)
            ly = sy0 + self.uniform(0.0, 0.08)
            x, y = _local_to_world(host.obj, lx, ly)
            z = host.seat.z + float(host.obj.pose[2, 3])
            moved = _moved(item, x, y, host.obj.yaw + self.uniform(-0.15, 0.15), z)
            moved.on = seat
            i = self.try_add(moved, ignore=(seat,))
            if i is not None:
                return i
        return None

    def curtains(self, p: float = 0.7) -> None:
        """Curtains at windows, from 2 cm above the floor to above the window (2 m at least)."""
        if not self.has("curtains") or self.room_type not in _CURTAIN_ROOMS:
            return
        color = self.pick(_CURTAIN_COLORS)
        for o in self.openings:
            if o["kind"] != "window" or not self.chance(p):
                continue
            k, u0, u1 = int(o["wall"]), float(o["u0"]), float(o["u1"])
            top = min(self.H - 0.07, max(float(o["z1"]) + 0.15, 2.05))
            width = u1 - u0
            drawn = self.chance(0.3)
            panels = (
                [(u0 - 0.1, u1 + 0.1)]
                if drawn
                else [
                    (u0 - 0.15, u0 - 0.15 + min(0.6, self.uniform(0.3, 0.45) * width + 0.15)),
                    (u1 + 0.15 - min(0.6, self.uniform(0.3, 0.45) * width + 0.15), u1 + 0.15),
                ]
            )
            for a, b in panels:
                a, b = max(a, 0.02), min(b, self.wall_length(k) - 0.02)
                if b - a < 0.2:
                    continue
                item = _curtain_item(self.rng, b - a, top - 0.02, color, gathered=not drawn)
                item.ignore_keepouts = True
                depth = item.obj.dimensions["depth"]
                x, y = self.wall_point(k, (a + b) / 2, self.uniform(0.06, 0.12) + depth / 2)
                self.try_add(_moved(item, x, y, _WALL_YAW[k], 0.02))

    def radiators(self, p: float = 0.7) -> None:
        for o in self.openings:
            if o["kind"] == "window" and float(o["z0"]) > 0.6 and self.chance(p):
                item = self.model("radiator")
                if item is not None and item.obj.box.size[2] + 0.1 < float(o["z0"]):
                    u = (float(o["u0"]) + float(o["u1"])) / 2
                    self.against_wall(item, walls=[int(o["wall"])], u=u, tries=1)


def _curtain_item(
    rng: np.random.Generator,
    width: float,
    height: float,
    color: tuple[int, int, int],
    *,
    gathered: bool,
) -> _Item:
    """A thin wavy sheet: folds every 12-20 cm, deeper when the curtain is pulled aside."""
    wave = float(rng.uniform(0.12, 0.2))
    amplitude = float(rng.uniform(0.03, 0.05) if gathered else rng.uniform(0.015, 0.03))
    phase = float(rng.uniform(0, 2 * np.pi))
    nu = max(2, int(width / 0.02) + 1)
    x = np.linspace(-width / 2, width / 2, nu)
    y = amplitude * np.sin(2 * np.pi * x / wave + phase)
    grid = np.stack(
        [
            np.stack([x, y, np.zeros(nu)], axis=1),
            np.stack([x, y, np.full(nu, height)], axis=1),
        ],
        axis=1,
    )
    mesh = M.thick_surface(grid, 0.008)
    return _mesh_item(
        "curtain",
        "curtain",
        mesh,
        color,
        "curtain",
        {"width": width, "depth": 2 * amplitude + 0.008, "height": height},
    )


def _clothes_item(rng: np.random.Generator) -> _Item:
    size = (float(rng.uniform(0.35, 0.5)), float(rng.uniform(0.3, 0.45)), 0.05)
    mesh = M.cushion(size, softness=0.6).translated((0, 0, size[2] / 2))
    color = _CLOTH_COLORS[int(rng.integers(len(_CLOTH_COLORS)))]
    return _mesh_item("clothes", "clothes-folded", mesh, color, "clothes")


def _bag_item(rng: np.random.Generator) -> _Item:
    size = (float(rng.uniform(0.28, 0.38)), float(rng.uniform(0.12, 0.2)), 0.35)
    mesh = M.cushion(size, softness=0.35).translated((0, 0, size[2] / 2))
    color = _CLOTH_COLORS[int(rng.integers(len(_CLOTH_COLORS)))]
    return _mesh_item("bag", "bag", mesh, color, "bag")


# --------------------------------------------------------------------------------------
# Room programs.

_WORK_CHAIRS = ("chair-office",)
_MEETING_CHAIRS = ("chair-office", "chair-stacking", "chair-dining")
_DINING_CHAIRS = ("chair-dining", "chair-stacking", "chair-folding")
_EASY_CHAIRS = ("armchair-club", "lounge-chair", "armchair-wingback", "recliner", "chair-shell")


def _desk_group(room: _Room, walls: Sequence[int] | None = None) -> int | None:
    desk = room.against_wall(room.model("desk"), walls=walls)
    if desk is None:
        return None
    chair = room.chair_at_desk(desk, _WORK_CHAIRS + ("chair-dining",))
    room.seat_clutter(chair, 0.3)
    if room.chance(0.6):
        room.on_top(desk, room.model("lamp-table", "laptop", "books", "plant-small"))
    if room.chance(0.4):
        room.on_top(desk, room.model("laptop", "books"))
    return desk


def _pair(room: _Room, item: _Item | None) -> list[int]:
    """Two of ``item`` side by side: against a wall if one has room, else free-standing.

    With the ``side_by_side`` challenge they stand 0-5 cm apart, else 30-60 cm.
    """
    if item is None:
        return []
    gap = room.uniform(0.0, 0.05) if room.has("side_by_side") else room.uniform(0.3, 0.6)
    for _ in range(4):
        first = room.against_wall(item, tries=8)
        if first is None:
            break
        second = room.beside(first, item, gap=gap)
        if second is not None:
            return [first, second]
        room.remove_last()
    step = item.obj.dimensions["width"] + gap
    for _ in range(_TRIES // 3):
        first = room.free(item, tries=1)
        if first is None:
            continue
        a = room.items[first].obj
        for side in (1.0, -1.0):
            x, y = _local_to_world(a, side * step, 0.0)
            second = room.try_add(_moved(item, x, y, a.yaw))
            if second is not None:
                return [first, second]
        room.remove_last()
    return []


def _storage(room: _Room, families: Sequence[str], n: int) -> None:
    for _ in range(n):
        room.against_wall(room.model(*families))


def _sitting_group(
    room: _Room, region: tuple[float, float, float, float] | None = None
) -> int | None:
    """A sofa facing a coffee table, easy chairs (side by side) across it; the sofa's index."""
    sofa = (
        room.against_wall(room.model("sofa", "sofa-corner"))
        if region is None
        else room.free(room.model("sofa"), region=region)
    )
    if sofa is None:
        return None
    s = room.items[sofa].obj
    room.seat_clutter(sofa, 0.8)
    table = room.model("table-coffee")
    table_index = None
    if table is not None:
        gap = room.uniform(0.3, 0.5)
        for _ in range(6):
            d = s.dimensions["depth"] / 2 + gap + table.obj.dimensions["depth"] / 2
            x, y = _local_to_world(s, room.uniform(-0.2, 0.2), d)
            table_index = room.try_add(_moved(table, x, y, s.yaw))
            if table_index is not None:
                break
            gap += 0.05
    # Easy chairs across the coffee table, facing the sofa, side by side.
    first = room.model(*_EASY_CHAIRS)
    if first is None:
        return sofa
    n = int(room.rng.integers(1, 3))
    gap = room.uniform(0.0, 0.05) if room.has("side_by_side") else room.uniform(0.3, 0.8)
    w = first.obj.dimensions["width"]
    reach = s.dimensions["depth"] / 2 + 0.4
    if table_index is not None:
        t = room.items[table_index].obj
        reach += t.dimensions["depth"] + room.uniform(0.3, 0.5)
    reach += first.obj.dimensions["depth"] / 2
    centre = room.uniform(-0.3, 0.3)
    offsets = [centre] if n == 1 else [centre - (w + gap) / 2, centre + (w + gap) / 2]
    for off in offsets:
        x, y = _local_to_world(s, off, reach)
        i = room.try_add(_moved(first, x, y, s.yaw + np.pi))
        room.seat_clutter(i, 0.5)
    if table_index is not None and room.chance(0.5):
        room.on_top(table_index, room.model("plant-small", "books"))
    return sofa


def _office(room: _Room) -> None:
    for _ in range(int(room.rng.integers(2, 5))):
        _desk_group(room)
    _storage(room, ("bookshelf", "shelves", "cabinet"), int(room.rng.integers(1, 3)))
    if room.chance(0.7):  # visitors' easy chairs, side by side
        for i in _pair(room, room.model("armchair-club", "lounge-chair", "chair-dining")):
            room.seat_clutter(i, 0.4)
    for _ in range(int(room.rng.integers(1, 3))):
        room.in_corner(room.model("plant", "bin"))
    if room.chance(0.3):
        room.against_wall(room.model("whiteboard"))


def _conference(room: _Room) -> None:
    cx, cy = room.L / 2, room.W / 2
    table = room.free(
        room.model("table-conference", "table-dining"),
        region=(cx - 1.6, cy - 1.4, cx + 1.6, cy + 1.4),
        yaw=0.0 if room.L >= room.W else np.pi / 2,
    )
    chairs = room.chairs_around(table, _MEETING_CHAIRS, int(room.rng.integers(6, 11)))
    for c in chairs:
        room.seat_clutter(c, 0.15)
    room.against_wall(room.model("whiteboard", "tv-stand"))
    _storage(room, ("cabinet", "shelves"), int(room.rng.integers(0, 2)))
    room.in_corner(room.model("plant"))


def _classroom(room: _Room) -> None:
    room.against_wall(room.model("whiteboard"), walls=[0])
    teacher = room.free(room.model("desk"), region=(0.5, 0.6, room.L - 0.5, 1.9), yaw=np.pi)
    if teacher is not None:
        top = room.items[teacher].top
        y0 = top.rect[1] if top is not None else -0.3
        room.seat_at(teacher, room.model(*_WORK_CHAIRS), (0.0, y0), (0.0, -1.0), tucked=False)
    rows = int((room.W - 2.6) // 1.5)
    cols = int((room.L - 1.0) // 1.6)
    for r in range(rows):
        for c in range(cols):
            if room.full():
                return
            x = 0.5 + (c + 0.5) * (room.L - 1.0) / cols
            y = 2.4 + r * 1.5 + 0.35
            desk = room.model("desk")
            if desk is not None and desk.obj.dimensions["width"] <= 1.45:
                i = room.free(desk, region=(x - 0.8, y - 0.4, x + 0.8, y + 0.4), yaw=0.0, tries=4)
                chair = room.chair_at_desk(i, ("chair-stacking", "chair-dining", "chair-office"))
                room.seat_clutter(chair, 0.3)
            else:
                room.free(
                    room.model("chair-classroom", "chair-stacking"),
                    region=(x - 0.5, y - 0.4, x + 0.5, y + 0.6),
                    yaw=np.pi,
                    tries=4,
                )
    _storage(room, ("shelves", "bookshelf", "cabinet"), 1)


def _dining(room: _Room) -> None:
    cx, cy = room.L / 2, room.W / 2
    table = room.free(
        room.model("table-dining"),
        region=(cx - 1.0, cy - 0.8, cx + 1.0, cy + 0.8),
        yaw=(-0.1, 0.1) if room.chance(0.5) else (np.pi / 2 - 0.1, np.pi / 2 + 0.1),
    )
    chairs = room.chairs_around(table, _DINING_CHAIRS, int(room.rng.integers(4, 9)))
    for c in chairs:
        room.seat_clutter(c, 0.25)
    if table is not None and room.chance(0.6):
        room.on_top(table, room.model("plant-small"))
    _storage(room, ("cabinet", "dresser", "bookshelf"), int(room.rng.integers(1, 3)))
    room.in_corner(room.model("plant", "lamp-floor"))


def _living_room(room: _Room) -> None:
    sofa = _sitting_group(room)
    if room.chance(0.5):
        side = room.beside(sofa, room.model("table-side", "nightstand"), gap=room.uniform(0.0, 0.1))
        room.on_top(side, room.model("lamp-table", "plant-small"))
    if room.chance(0.3):
        room.free(room.model("ottoman", "stool-low"))
    stand = room.against_wall(room.model("tv-stand"))
    if stand is not None:
        room.on_top(stand, room.model("television"))
    _storage(room, ("bookshelf", "shelves", "cabinet"), int(room.rng.integers(0, 2)))
    room.in_corner(room.model("lamp-floor"))
    for _ in range(int(room.rng.integers(1, 3))):
        room.in_corner(room.model("plant"))
    if room.chance(0.5):
        for i in _pair(room, room.model(*_EASY_CHAIRS)):
            room.seat_clutter(i, 0.5)


def _bedroom(room: _Room) -> None:
    bed = room.against_wall(room.model("bed-double", "bed-single"))
    if bed is not None:
        for _ in range(2):
            stand = room.beside(bed, room.model("nightstand"), gap=room.uniform(0.0, 0.08))
            room.on_top(stand, room.model("lamp-table"))
        if room.has("seat_clutter") and room.chance(0.5):
            room.on_seat(bed, room.model("clothes", "bag") or _clothes_item(room.rng))
    room.against_wall(room.model("wardrobe"))
    if bed is not None and room.chance(0.3):
        room.free(room.model("bench", "ottoman"))
    dresser = room.against_wall(room.model("dresser"))
    if dresser is not None and room.chance(0.5):
        room.on_top(dresser, room.model("lamp-table", "plant-small"))
    if room.chance(0.6):
        _desk_group(room)
    else:
        chair = room.against_wall(room.model("chair-dining", *_EASY_CHAIRS))
        room.seat_clutter(chair, 0.7)
    room.in_corner(room.model("plant", "bin"))


def _bathroom(room: _Room) -> None:
    tub = room.against_wall(room.model("bathtub", "shower"), corner=True)
    if tub is not None and room.items[tub].obj.class_name == "bathtub" and room.chance(0.4):
        room.beside(tub, room.model("shower-curtain"), gap=0.0)
    room.against_wall(room.model("toilet"))
    sink = room.against_wall(room.model("sink", "sink-vanity"))
    if sink is not None and room.chance(0.3):
        room.beside(sink, room.model("sink"), gap=0.1)
    room.against_wall(room.model("radiator"))
    room.in_corner(room.model("bin"))


def _kitchen_run(
    room: _Room, k: int, start_corner: bool = True, *, with_sink: bool = True
) -> list[int]:
    """Base cabinets, a sink, a cooker and a fridge along wall ``k``, wall cabinets above some."""
    length = room.wall_length(k)
    u = 0.0 if start_corner else room.uniform(0.0, 0.6)
    placed: list[int] = []
    sink_done = not with_sink
    fridge = room.model("refrigerator")
    while u < length - 0.4 and not room.full():
        item = None
        if not sink_done and placed and (room.chance(0.5) or len(placed) >= 2):
            item = room.model("sink-kitchen")
        if item is None and placed and room.chance(0.25):
            item = room.model("appliance")
        if item is None:
            item = room.model("counter")
        if item is None:
            break
        w = item.obj.dimensions["width"]
        if u + w > length:
            break
        i = room.against_wall(item, walls=[k], u=u + w / 2, tries=1)
        if i is None:
            u += 0.1
            continue
        placed.append(i)
        sink_done = sink_done or room.items[i].obj.kind == "sink-kitchen"
        if room.chance(0.5):
            upper = room.model("cabinet-wall")
            if upper is not None and upper.obj.dimensions["width"] <= w + 0.3:
                room.against_wall(upper, walls=[k], u=u + w / 2, tries=1)
        u += w + 0.002
    if fridge is not None and u + fridge.obj.dimensions["width"] <= length:
        room.against_wall(fridge, walls=[k], u=u + fridge.obj.dimensions["width"] / 2, tries=1)
    return placed


def _kitchen(room: _Room) -> None:
    walls = [0, 1, 2, 3]
    k = room.pick(walls)
    _kitchen_run(room, k)
    if room.chance(0.5):
        _kitchen_run(room, (k + 1) % 4, start_corner=False, with_sink=False)
    if room.chance(0.5):
        island = room.free(room.model("counter-island"))
        if island is not None:
            for _ in range(int(room.rng.integers(1, 4))):
                room.chair_at_desk(island, ("stool-bar",))
            return
    table = room.free(room.model("table-dining"), tries=20)
    chairs = room.chairs_around(table, _DINING_CHAIRS, int(room.rng.integers(2, 5)))
    for c in chairs:
        room.seat_clutter(c, 0.3)
    room.in_corner(room.model("bin"))


def _open_plan(room: _Room) -> None:
    L, W = room.L, room.W
    _sitting_group(room, region=(0.3, 0.3, L / 2, W - 0.3))
    table = room.free(room.model("table-dining"), region=(L / 2, W / 2, L - 0.3, W - 0.3))
    chairs = room.chairs_around(table, _DINING_CHAIRS, int(room.rng.integers(4, 7)))
    for c in chairs:
        room.seat_clutter(c, 0.3)
    _kitchen_run(room, room.pick([0, 1, 2, 3]), start_corner=room.chance(0.5))
    _desk_group(room)
    room.against_wall(room.model("tv-stand", "bookshelf", "shelves"))
    for _ in range(int(room.rng.integers(1, 4))):
        room.in_corner(room.model("plant", "lamp-floor"))


_PROGRAMS = {
    "office": _office,
    "conference": _conference,
    "classroom": _classroom,
    "dining": _dining,
    "living_room": _living_room,
    "bedroom": _bedroom,
    "bathroom": _bathroom,
    "kitchen": _kitchen,
    "open_plan": _open_plan,
}


# --------------------------------------------------------------------------------------
# Public entry points.


def _check_challenges(challenges: Any) -> frozenset[str]:
    if isinstance(challenges, str):
        challenges = [c for c in challenges.split(",") if c.strip()]
    try:
        chosen = frozenset(str(c).strip() for c in challenges)
    except TypeError:
        raise InvalidParameterError(
            "challenges", f"a collection of {', '.join(CHALLENGES)}", challenges
        ) from None
    unknown = sorted(chosen - set(CHALLENGES))
    if unknown:
        raise InvalidParameterError("challenges", f"some of {', '.join(CHALLENGES)}", unknown)
    return chosen


def furnished_scene(
    room_type: str,
    seed: int,
    *,
    catalog_dir: str | os.PathLike[str] | None = None,
    challenges: Collection[str] = CHALLENGES,
) -> Scene:
    """A room of ``room_type`` furnished with Sweet Home 3D catalogue models.

    Parameters
    ----------
    room_type : str
        One of :data:`FURNISHED_ROOM_TYPES`.
    seed : int
        The same seed (and the same catalogues) always gives the same scene.
    catalog_dir : str or PathLike, optional
        Folder of ``.sh3f`` catalogues; default
        :func:`~ontodetect.synth.sh3d.default_catalog_dir`. Models listed in
        ``data/sh3d_classes.yaml`` that the folder lacks are simply not used.
    challenges : collection of str
        Which of :data:`CHALLENGES` to include (default all; ``()`` for none).

    Returns
    -------
    Scene
        Structure first (floor, ceiling, walls, doors, windows), then furniture;
        instance ids 1, 2, ... Each piece of furniture has its class (``chair``,
        ``sofa``, ``table``, ``desk``, ``bed``, ``toilet`` ...) as ``class_name``, its
        family as ``kind`` (``chair-office``, ``armchair-club``, ``table-coffee`` ...),
        ``dimensions`` with ``width``, ``depth``, ``height`` and, where found,
        ``seat_height`` or ``top_height``, and ``extra`` naming its ``catalog``,
        ``model_id``, ``model_name``, ``creator`` and ``license`` (generated cushions,
        clothes, bags and curtains have ``extra["generated"]``).
        ``scene.extra["attribution"]`` is :func:`attribution` of the scene.

    Raises
    ------
    InvalidParameterError
        Unknown room type, a negative seed or an unknown challenge.
    ReadError
        The catalogue folder is missing, empty or holds none of the mapped models.

    Examples
    --------
    >>> scene = furnished_scene("living_room", 3)  # doctest: +SKIP
    >>> sorted({o.class_name for o in scene.objects if not o.is_structure})  # doctest: +SKIP
    ['chair', 'curtain', 'lamp', 'pillow', 'plant', 'sofa', 'table', 'television', 'tv_stand']
    """
    if room_type not in FURNISHED_ROOM_TYPES:
        raise InvalidParameterError(
            "room_type", f"one of {', '.join(FURNISHED_ROOM_TYPES)}", room_type
        )
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidParameterError("seed", "a non-negative integer", seed)
    chosen = _check_challenges(challenges)
    library = _Library.load(catalog_dir)
    rng = np.random.default_rng(int(seed))
    (l0, l1), (w0, w1) = _ROOM_SIZES[room_type]
    size = (
        float(rng.uniform(l0, l1)),
        float(rng.uniform(w0, w1)),
        float(rng.uniform(*_CEILING_HEIGHT)),
    )
    glazed = "glazed_wall" in chosen and bool(rng.random() < _GLAZED_CHANCE.get(room_type, 0.0))
    shell = build_shell(room_type, rng, size, glazed_wall=glazed)
    wanted = _MIN_COUNTS[room_type]
    room = best = None
    best_score = -1
    for _attempt in range(_FURNISH_ATTEMPTS):
        room = _Room(rng, room_type, size, library, shell.keepouts, shell.openings, chosen)
        room.curtains()
        _PROGRAMS[room_type](room)
        room.radiators()
        counts = Counter(item.obj.class_name for item in room.items)
        score = sum(min(counts[c], n) for c, n in wanted.items())
        if score > best_score:
            best, best_score = room, score
        if score == sum(wanted.values()):
            break
    room = best
    objects = [
        _with_id(o, i + 1)
        for i, o in enumerate(shell.structure + [item.obj for item in room.items])
    ]
    scene = Scene(
        room_type,
        size,
        objects,
        int(seed),
        {
            "furnished": True,
            "wall_thickness": shell.wall_thickness,
            "openings": shell.openings,
            "glazed_wall": shell.glazed_wall,
            "challenges": sorted(chosen),
        },
    )
    scene.extra["attribution"] = attribution(scene)
    return scene


def _with_id(obj: SceneObject, instance_id: int) -> SceneObject:
    from dataclasses import replace

    return replace(obj, instance_id=instance_id)


def attribution(scene: Scene) -> list[dict[str, Any]]:
    """The catalogues, licences and creators of the catalogue models a scene uses.

    Parameters
    ----------
    scene : Scene

    Returns
    -------
    list of dict
        One per catalogue, sorted by name: ``catalog``, ``license`` (the models' licences,
        joined by "; " when they differ) and ``models``, a list of ``{"model_id",
        "model_name", "creator", "license", "count"}`` sorted by id.

    Examples
    --------
    >>> from ontodetect.synth.rooms import build_room
    >>> attribution(build_room("tiny", 0))
    []
    """
    found: dict[str, dict[str, Any]] = {}
    for obj in scene.objects:
        e = obj.extra
        if "model_id" not in e:
            continue
        models = found.setdefault(e["catalog"], {})
        m = models.setdefault(
            e["model_id"],
            {
                "model_id": e["model_id"],
                "model_name": e["model_name"],
                "creator": e["creator"],
                "license": e["license"],
                "count": 0,
            },
        )
        m["count"] += 1
    out = []
    for catalog, models in sorted(found.items()):
        licences = sorted({m["license"] for m in models.values()})
        out.append(
            {
                "catalog": catalog,
                "license": licences[0] if len(licences) == 1 else "; ".join(licences),
                "models": [models[k] for k in sorted(models)],
            }
        )
    return out


def attribution_text(scene: Scene) -> str:
    """One line per catalogue: its licence and the models used with their creators.

    Examples
    --------
    >>> from ontodetect.synth.rooms import build_room
    >>> attribution_text(build_room("tiny", 0))
    ''
    """
    lines = []
    for cat in attribution(scene):
        models = ", ".join(
            f"{m['model_name']} ({m['creator']})" if m["creator"] else m["model_name"]
            for m in cat["models"]
        )
        lines.append(f"{cat['catalog']} ({cat['license']}): {models}")
    return "\n".join(lines)


def synthesize_furnished(
    room_type: str,
    sensor: str = "rgbd",
    seed: int = 0,
    *,
    catalog_dir: str | os.PathLike[str] | None = None,
    challenges: Collection[str] = CHALLENGES,
    points: int | None = None,
    **sensor_opts: Any,
) -> Any:
    """Build a furnished room (:func:`furnished_scene`) and scan it (:func:`synthesize`).

    Returns
    -------
    SynthResult
        Write it with :func:`~ontodetect.synth.dataset.write_synth`; scene.json carries
        the attribution under ``scene_extra``.
    """
    scene = furnished_scene(room_type, seed, catalog_dir=catalog_dir, challenges=challenges)
    return synthesize(scene, sensor, seed, points=points, **sensor_opts)
