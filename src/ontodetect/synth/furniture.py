"""Parametric furniture: meshes with named parts, ergonomic dimensions and materials.

:func:`make_furniture` builds one object of a kind (``"chair-4leg"``,
``"sofa-l-shaped"``, ``"table-round"``, ``"bookshelf"`` ...) in its object frame:
origin at the centre of its footprint on the floor, x to its right, y to its
front (the way a person sitting on it faces), z up. :func:`place` puts it in
the world. Every part (``seat``, ``backrest``, ``leg``, ``top``, ``cushion`` ...)
is a closed solid with a realistic thickness, because the virtual sensors
ray-cast them.

Dimensions are drawn from the ranges of furniture standards and of Neufert's
*Architects' Data*; each range cites its source where it is defined. Any
drawn value can be fixed with a keyword (``make_furniture("chair-4leg", 0,
seat_height=0.45)``); the names are those of the returned ``dimensions`` where
one exists.

Besides the fields of :class:`~ontodetect.synth.scene.SceneObject`, objects
carry in ``extra``:

- ``collision_boxes``: list of [xmin, ymin, zmin, xmax, ymax, zmax] in the object
  frame, one per rigid piece that other objects must not enter (a table's top
  and each of its legs, so that chairs can be tucked between the legs); see
  :func:`part_boxes`;
- ``seat_part`` and ``seat_center`` (object frame xy) for objects one sits on:
  the top of that part at that point is at ``dimensions["seat_height"]``;
- ``support_rect`` ([xmin, ymin, xmax, ymax], object frame), ``support_z`` and
  ``support_round`` for objects things can be put on (tables, desks, cabinets);
- ``knee_center`` (object frame xy) for desks: where the chair goes;
- ``front_span`` ([x0, x1, y], object frame) for sofas: the free front edge of the
  seats, where a coffee table goes;
- ``bowl_center``, ``basin_center``, ``tub_center`` (object frame xy) for WCs,
  washbasins and baths: the lowest point of the bowl's inside is straight below;
- ``wall_mounted`` (True) for what hangs on a wall without touching the floor
  (some WCs and washbasins); ``dimensions["floor_clearance"]`` is then its lowest
  point's height.
"""

from __future__ import annotations

import copy
import dataclasses
import itertools
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..geometry import _mesh as M
from .scene import OrientedBox, SceneObject, yaw_pose

__all__ = [
    "FURNITURE",
    "FURNITURE_CLASSES",
    "kinds_of",
    "make_furniture",
    "part_boxes",
    "place",
    "place_on",
]

Seed = int | np.random.Generator | None

# --------------------------------------------------------------------------------------
# Materials: base colours (sRGB) that each object jitters a little.

WOOD = {
    "oak": (188, 148, 98),
    "beech": (214, 178, 136),
    "walnut": (104, 72, 50),
    "cherry": (150, 86, 56),
    "ash": (212, 196, 166),
    "mahogany": (98, 46, 34),
    "black_stain": (48, 40, 36),
    "white_paint": (232, 230, 224),
}
LAMINATE = {
    "white": (236, 236, 232),
    "light_grey": (196, 198, 198),
    "oak_decor": (196, 160, 114),
    "beech_decor": (220, 186, 146),
    "anthracite": (68, 70, 72),
    "maple_decor": (226, 202, 160),
}
FABRIC = {
    "grey": (124, 124, 128),
    "charcoal": (58, 60, 64),
    "beige": (202, 186, 160),
    "navy": (42, 56, 96),
    "forest": (66, 98, 72),
    "burgundy": (120, 36, 44),
    "mustard": (196, 154, 58),
    "teal": (40, 108, 112),
    "cognac_leather": (132, 74, 40),
    "black_leather": (30, 28, 28),
    "cream": (228, 220, 200),
    "sky": (110, 150, 190),
}
PLASTIC = {
    "black": (30, 30, 32),
    "dark_grey": (72, 72, 76),
    "light_grey": (176, 176, 178),
    "white": (236, 236, 232),
    "red": (190, 44, 40),
    "yellow": (232, 188, 48),
    "blue": (52, 94, 164),
    "green": (96, 150, 96),
}
METAL = {
    "chrome": (204, 206, 210),
    "black": (36, 36, 38),
    "aluminium": (176, 180, 184),
    "white": (226, 226, 224),
    "brass": (180, 150, 80),
}
CERAMIC = {
    "terracotta": (176, 96, 64),
    "white": (230, 228, 222),
    "anthracite": (62, 64, 66),
    "sand": (196, 178, 146),
}
FOLIAGE = {
    "green": (62, 112, 52),
    "dark_green": (40, 82, 40),
    "olive": (100, 118, 58),
    "lime": (110, 150, 60),
}
PAPER = {
    "red": (150, 40, 40),
    "blue": (40, 70, 130),
    "green": (50, 100, 60),
    "yellow": (210, 180, 70),
    "white": (230, 226, 214),
    "black": (36, 36, 36),
    "orange": (210, 120, 50),
    "brown": (120, 84, 56),
    "grey": (140, 140, 140),
}
CARDBOARD = {"kraft": (176, 136, 92), "light": (200, 168, 122), "white": (226, 222, 212)}
#: Largest random change of each colour channel, so that no two objects look identical.
COLOR_JITTER = 10

#: Vertical gap between stacked parts that would otherwise share a face (keeps faces distinct).
_GAP = 0.002


# --------------------------------------------------------------------------------------
# Drawing parameters with optional overrides.


class _Params:
    """Draw an object's parameters; a keyword given by the caller replaces the draw.

    Every parameter is drawn even when overridden, so fixing one does not
    change the others.
    """

    def __init__(self, kind: str, rng: np.random.Generator, overrides: dict[str, Any]):
        self.kind = kind
        self.rng = rng
        self.overrides = dict(overrides)
        self.used: set[str] = set()

    def _take(self, name: str, drawn: Any) -> Any:
        self.used.add(name)
        return self.overrides.get(name, drawn)

    def uniform(self, name: str, low: float, high: float) -> float:
        value = self._take(name, float(self.rng.uniform(low, high)))
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float, np.number))
            or not (math.isfinite(value) and value > 0)
        ):
            raise InvalidParameterError(name, f"a number greater than 0 for {self.kind!r}", value)
        return float(value)

    def integer(self, name: str, low: int, high: int) -> int:
        """An integer in [low, high] (both included)."""
        value = self._take(name, int(self.rng.integers(low, high + 1)))
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise InvalidParameterError(name, f"an integer >= 1 for {self.kind!r}", value)
        return int(value)

    def choice(
        self, name: str, options: Sequence[Any], weights: Sequence[float] | None = None
    ) -> Any:
        w = None if weights is None else np.asarray(weights, float) / np.sum(weights)
        value = self._take(name, options[int(self.rng.choice(len(options), p=w))])
        if value not in options:
            raise InvalidParameterError(
                name, f"one of {', '.join(map(repr, options))} for {self.kind!r}", value
            )
        return value

    def option(self, name: str, default: Any, options: Sequence[Any]) -> Any:
        """A setting the caller may choose but that is not drawn: adding one to a builder
        leaves every drawn value, and so every object built before, unchanged."""
        value = self._take(name, default)
        if value not in options:
            raise InvalidParameterError(
                name, f"one of {', '.join(map(repr, options))} for {self.kind!r}", value
            )
        return value

    def color(self, name: str, *palettes: dict[str, tuple[int, int, int]]) -> NDArray[np.uint8]:
        """A colour from the palettes, jittered; the override is a name or an (r, g, b) triple."""
        table = {k: v for pal in palettes for k, v in pal.items()}
        names = sorted(table)
        key = names[int(self.rng.integers(len(names)))]
        jitter = self.rng.integers(-COLOR_JITTER, COLOR_JITTER + 1, 3)
        value = self._take(name, key)
        if isinstance(value, str):
            if value not in table:
                raise InvalidParameterError(name, f"one of {', '.join(names)}", value)
            base = np.asarray(table[value])
        else:
            base = np.asarray(value)
            if base.shape != (3,) or not np.all((base >= 0) & (base <= 255)):
                raise InvalidParameterError(
                    name, "a colour name or an (r, g, b) triple in 0..255", value
                )
            jitter = np.zeros(3, int)
        return np.clip(base + jitter, 0, 255).astype(np.uint8)

    def check_all_used(self) -> None:
        unknown = sorted(set(self.overrides) - self.used)
        if unknown:
            raise InvalidParameterError(
                unknown[0],
                f"a parameter of {self.kind!r} ({', '.join(sorted(self.used))})",
                self.overrides[unknown[0]],
            )


# --------------------------------------------------------------------------------------
# Assembling parts into a SceneObject.

#: Keys of ``extra`` holding object-frame xy points (moved when the object is re-centred).
_FRAME_POINTS = ("seat_center", "knee_center", "bowl_center", "basin_center", "tub_center")


class _Assembly:
    """Collects (part name, closed mesh, colour, collision group) and makes the object."""

    def __init__(self) -> None:
        self.meshes: list[M.Mesh] = []
        self.parts: list[str] = []
        self.colors: list[NDArray[np.uint8]] = []
        self.groups: list[str] = []
        self.boxes: list[list[NDArray[np.float64]] | None] = []

    def add(
        self,
        part: str,
        mesh: M.Mesh,
        color: ArrayLike,
        group: str | None = None,
        boxes: list[NDArray[np.float64]] | None = None,
    ) -> None:
        """Add a part; ``boxes`` ((2, 3) low/high corners) replace the mesh's one collision box."""
        self.meshes.append(mesh)
        self.parts.append(part)
        self.colors.append(np.asarray(color, dtype=np.uint8))
        self.groups.append(part if group is None else group)
        self.boxes.append(boxes)

    def mirror_x(self) -> None:
        self.meshes = [m.scaled((-1.0, 1.0, 1.0)) for m in self.meshes]
        flip = np.diag([-1.0, 1.0, 1.0])
        self.boxes = [
            None if bs is None else [np.sort(b @ flip, axis=0) for b in bs] for bs in self.boxes
        ]

    def build(
        self,
        class_name: str,
        kind: str,
        dimensions: dict[str, float],
        extra: dict[str, Any] | None = None,
    ) -> SceneObject:
        mesh = M.concatenate(self.meshes)
        lo, hi = mesh.bounds
        shift = np.array([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, 0.0])
        vertices = mesh.vertices + shift
        names = list(dict.fromkeys(self.parts))
        per_mesh_part = np.array([names.index(p) for p in self.parts], dtype=np.int32)
        counts = [len(m.triangles) for m in self.meshes]
        triangle_part = np.repeat(per_mesh_part, counts).astype(np.int32)
        triangle_color = np.repeat(np.stack(self.colors), counts, axis=0).astype(np.uint8)

        boxes: dict[str, NDArray[np.float64]] = {}
        for i, (m, g, own) in enumerate(zip(self.meshes, self.groups, self.boxes)):
            if own is not None:
                for j, b in enumerate(own):
                    boxes[f"{g}#{i}.{j}"] = np.asarray(b) + shift
                continue
            b = m.bounds + shift
            boxes[g] = (
                b
                if g not in boxes
                else np.stack([np.minimum(boxes[g][0], b[0]), np.maximum(boxes[g][1], b[1])])
            )
        extra = copy.deepcopy(extra or {})
        for key in _FRAME_POINTS:
            if key in extra:
                extra[key] = [float(extra[key][0] + shift[0]), float(extra[key][1] + shift[1])]
        if "front_span" in extra:
            x0, x1, y = extra["front_span"]
            extra["front_span"] = [float(x0 + shift[0]), float(x1 + shift[0]), float(y + shift[1])]
        if "support_rect" in extra:
            r = extra["support_rect"]
            extra["support_rect"] = [
                float(r[0] + shift[0]),
                float(r[1] + shift[1]),
                float(r[2] + shift[0]),
                float(r[3] + shift[1]),
            ]
        extra["collision_boxes"] = [[float(v) for v in b.ravel()] for b in boxes.values()]

        size = hi - lo
        dims = {"width": float(size[0]), "depth": float(size[1]), "height": float(hi[2])}
        dims.update({k: float(v) for k, v in dimensions.items()})
        return SceneObject(
            instance_id=0,
            class_name=class_name,
            kind=kind,
            vertices=vertices,
            triangles=mesh.triangles,
            triangle_part=triangle_part,
            part_names=names,
            triangle_color=triangle_color,
            pose=np.eye(4),
            dimensions=dims,
            box=OrientedBox(
                (0.0, 0.0, float((lo[2] + hi[2]) / 2)),
                (float(size[0]), float(size[1]), float(size[2])),
                0.0,
            ),
            extra=extra,
        )


def _part_top(asm: _Assembly, part: str) -> float:
    return max(float(m.bounds[1, 2]) for m, p in zip(asm.meshes, asm.parts) if p == part)


def _on_floor(mesh: M.Mesh) -> M.Mesh:
    """Drop or lift a mesh so that its lowest point is exactly on the floor."""
    return mesh.translated((0.0, 0.0, -mesh.bounds[0, 2]))


def _split_boxes(mesh: M.Mesh, z: float) -> list[NDArray[np.float64]]:
    """Collision boxes of a mesh's parts below and above height z (a frame that rises into
    a backrest must not block the space under a table top in front of the backrest)."""
    v = mesh.vertices
    out = []
    for keep in (v[:, 2] <= z, v[:, 2] > z):
        if keep.any():
            out.append(np.stack([v[keep].min(axis=0), v[keep].max(axis=0)]))
    return out


def _shade(color: NDArray[np.uint8], factor: float) -> NDArray[np.uint8]:
    return np.clip(color.astype(float) * factor, 0, 255).astype(np.uint8)


def place(obj: SceneObject, x: float, y: float, yaw: float = 0.0, z: float = 0.0) -> SceneObject:
    """A copy of ``obj`` with its object frame moved to (x, y, z), turned by ``yaw`` about z.

    The placement is absolute: placing a placed object again moves it from its
    own frame, not from where it was.

    Examples
    --------
    >>> chair = make_furniture("chair-4leg", 0)
    >>> moved = place(chair, 2.0, 1.0, np.pi / 2)
    >>> np.allclose(moved.box.center[:2], (2.0, 1.0)), round(moved.yaw, 6)
    (True, 1.570796)
    """
    T = yaw_pose(x, y, yaw, z)
    to_local = np.linalg.inv(obj.pose)
    M4 = T @ to_local
    vertices = obj.vertices @ M4[:3, :3].T + M4[:3, 3]
    c = M4 @ np.array([*obj.box.center, 1.0])
    box = OrientedBox((float(c[0]), float(c[1]), float(c[2])), obj.box.size, float(yaw))
    return dataclasses.replace(
        obj, vertices=vertices, pose=T, box=box, extra=copy.deepcopy(obj.extra)
    )


def place_on(
    obj: SceneObject,
    support: SceneObject,
    at: tuple[float, float] = (0.5, 0.5),
    yaw: float = 0.0,
) -> SceneObject:
    """A copy of ``obj`` standing on the top of ``support`` (a lamp on a nightstand).

    Parameters
    ----------
    obj : SceneObject
        The object to put down (its own placement is ignored).
    support : SceneObject
        An object with a top to put things on: ``extra`` has ``support_rect`` and
        ``support_z`` (tables, desks, cabinets, nightstands, TV stands).
    at : (2,) float
        Where on the top, as fractions of ``support_rect`` in the support's frame:
        (0.5, 0.5) is the middle, (0.5, 0.2) the middle near the back.
    yaw : float
        Turn (radians) relative to the support.

    Examples
    --------
    >>> stand = place(make_furniture("nightstand", 0), 1.0, 0.3)
    >>> lamp = place_on(make_furniture("lamp-table", 0), stand)
    >>> bool(np.isclose(lamp.vertices[:, 2].min(), stand.vertices[:, 2].max()))
    True
    """
    if "support_rect" not in support.extra or "support_z" not in support.extra:
        raise InvalidParameterError(
            "support", "an object with a top (support_rect and support_z)", support.kind
        )
    x0, y0, x1, y1 = support.extra["support_rect"]
    u, v = (float(f) for f in at)
    local = np.array([x0 + u * (x1 - x0), y0 + v * (y1 - y0), 0.0, 1.0])
    wx, wy = (support.pose @ local)[:2]
    z = float(support.extra["support_z"] + support.pose[2, 3])
    return place(obj, float(wx), float(wy), support.yaw + yaw, z)


def part_boxes(obj: SceneObject) -> list[OrientedBox]:
    """The object's collision boxes in the world: upright boxes around its rigid pieces.

    Two objects whose boxes do not overlap do not interpenetrate. A table gives
    one box for its top and one per leg, so a chair may stand between the legs
    with its seat under the top.
    """
    out = []
    for b in obj.extra.get("collision_boxes", []):
        lo, hi = np.asarray(b[:3]), np.asarray(b[3:])
        c = obj.pose @ np.array([*(lo + hi) / 2, 1.0])
        out.append(
            OrientedBox(
                (float(c[0]), float(c[1]), float(c[2])), tuple(float(v) for v in hi - lo), obj.yaw
            )
        )
    return out


# --------------------------------------------------------------------------------------
# Shared part builders.


def _leg(style: str, x: float, y: float, z0: float, z1: float, width: float) -> M.Mesh:
    """A vertical leg from z0 to z1 centred on (x, y): square, tapered or round."""
    if style == "round":
        return M.cylinder(width / 2, z1 - z0, 16, center=(x, y, z0))
    if style == "tapered":
        # Tapered legs are narrower at the foot (about 70 % of the top).
        return M.tapered_box((0.7 * width, 0.7 * width), (width, width), z1 - z0).translated(
            (x, y, z0)
        )
    return M.box_between((x - width / 2, y - width / 2, z0), (x + width / 2, y + width / 2, z1))


def _four_legs(
    asm: _Assembly,
    style: str,
    x: float,
    y: float,
    z0: float,
    z1: float,
    width: float,
    color: NDArray[np.uint8],
    group: str,
) -> None:
    """Four legs at (±x, ±y) from z0 to z1, in the order (-x, -y), (-x, y), (x, -y), (x, y)."""
    for sx in (-1, 1):
        for sy in (-1, 1):
            asm.add("leg", _leg(style, sx * x, sy * y, z0, z1, width), color, group=group)


def _plinth_or_legs(
    asm: _Assembly,
    plinth: bool,
    w: float,
    d: float,
    z0: float,
    color: NDArray[np.uint8],
    *,
    plinth_inset: float,
    leg_inset: float,
) -> None:
    """A low case's base up to ``z0`` under a ``w`` x ``d`` body: a plinth set in by
    ``plinth_inset`` at the sides and 5 cm at the back, or four tapered legs set in by
    ``leg_inset`` at the sides and 5 cm front and back."""
    if plinth:
        lo = (-w / 2 + plinth_inset, -d / 2, 0.0)
        hi = (w / 2 - plinth_inset, d / 2 - 0.05, z0 + 0.001)
        asm.add("base", M.box_between(lo, hi), _shade(color, 0.6), group="body")
    else:
        x, y = w / 2 - leg_inset, d / 2 - 0.05
        _four_legs(asm, "tapered", x, y, 0.0, z0 + 0.001, 0.035, _shade(color, 0.7), group="body")


def _tilted_box(lo: ArrayLike, hi: ArrayLike, tilt: float, pivot: ArrayLike) -> M.Mesh:
    """A box given in a frame reclined by ``tilt`` (top towards -y) about ``pivot``.

    ``lo``/``hi`` are relative to the pivot before the tilt.
    """
    p = np.asarray(pivot, dtype=np.float64)
    return M.box_between(np.asarray(lo) + p, np.asarray(hi) + p).rotated("x", tilt, about=p)


def _reclined(
    pivot: ArrayLike, tilt: float, along: float, forward: float = 0.0
) -> NDArray[np.float64]:
    """The point ``along`` up a reclined backrest line from ``pivot`` and ``forward`` off it."""
    p = np.asarray(pivot, dtype=np.float64)
    up = np.array([0.0, -np.sin(tilt), np.cos(tilt)])
    front = np.array([0.0, np.cos(tilt), np.sin(tilt)])
    return p + along * up + forward * front


def _resample(path: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """n points evenly spaced along a polyline."""
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(t, s, path[:, k]) for k in range(path.shape[1])])


def _handle(
    x: float, y_front: float, z: float, length: float, vertical: bool, color: NDArray[np.uint8]
) -> M.Mesh:
    """A bar handle standing 2.5 cm proud of a front at ``y_front``."""
    size = (0.012, 0.025, length) if vertical else (length, 0.025, 0.012)
    return M.box(size, (x, y_front + 0.0125, z))


# --------------------------------------------------------------------------------------
# Chairs.
#
# Seat heights 40-50 cm: EN 12520 (domestic seating) with Neufert's typical dining
# chair, 43-48 cm; office work chairs EN 1335-1 (seat height adjustable over at least
# 40-51 cm) and ANSI/BIFMA G1 (seat depth 38-47 cm, armrests 18-27 cm above the seat;
# EN 1335-1 asks 20-25 cm). Backrest recline 95-110 degrees between seat and back
# (DIN 4551 / EN 1335-1 comfort range).

CHAIR_SEAT_HEIGHT = (0.42, 0.48)
OFFICE_SEAT_HEIGHT = (0.42, 0.50)
CHAIR_SEAT_WIDTH = (0.40, 0.50)
CHAIR_SEAT_DEPTH = (0.38, 0.46)
SEAT_THICKNESS = (0.02, 0.05)
CHAIR_LEG_WIDTH = (0.03, 0.05)
RECLINE_DEGREES = (95.0, 110.0)
ARMREST_ABOVE_SEAT = (0.20, 0.25)


def _chair_back_and_legs(p: _Params, asm: _Assembly, *, arms: bool) -> dict[str, float]:
    """Four-legged wooden chair, with or without armrests."""
    seat_h = p.uniform("seat_height", *CHAIR_SEAT_HEIGHT)
    sw = p.uniform("seat_width", *((0.46, 0.54) if arms else CHAIR_SEAT_WIDTH))
    sd = p.uniform("seat_depth", *CHAIR_SEAT_DEPTH)
    st = p.uniform("seat_thickness", *SEAT_THICKNESS)
    lw = p.uniform("leg_width", *CHAIR_LEG_WIDTH)
    back_top = p.uniform("backrest_height", 0.80, 1.00)
    recline = p.uniform("recline", *RECLINE_DEGREES)
    arm_h = p.uniform("armrest_above_seat", *ARMREST_ABOVE_SEAT)
    arm_w = p.uniform("armrest_width", 0.045, 0.06)
    back_style = p.choice("back_style", ("panel", "slats", "spindles", "upholstered"))
    leg_style = p.choice("leg_style", ("square", "tapered", "round"))
    stretchers = p.choice("stretchers", (True, False))
    rails = p.choice("seat_rails", (True, False))
    upholstered = p.choice("upholstered_seat", (False, True))
    wood = p.color("frame_color", WOOD)
    fabric = p.color("fabric_color", FABRIC)
    tilt = math.radians(recline - 90.0)

    inset = 0.01
    lx, ly = sw / 2 - inset - lw / 2, sd / 2 - inset - lw / 2
    seat_bottom = seat_h - st
    # Seat: a board, or an upholstered pad with softened vertical edges.
    seat_mesh = (
        M.rounded_box((sw, sd, st), 0.03, center=(0, 0, seat_h - st / 2))
        if upholstered
        else M.box_between((-sw / 2, -sd / 2, seat_bottom), (sw / 2, sd / 2, seat_h))
    )
    asm.add("seat", seat_mesh, fabric if upholstered else wood)
    _four_legs(asm, leg_style, lx, ly, 0.0, seat_bottom, lw, wood, group="legs")
    if rails:
        rh, rt = 0.06, 0.018
        z0 = seat_bottom - rh
        asm.add(
            "frame",
            M.box_between((-lx, ly - rt / 2, z0), (lx, ly + rt / 2, seat_bottom)),
            wood,
            group="legs",
        )
        asm.add(
            "frame",
            M.box_between((-lx, -ly - rt / 2, z0), (lx, -ly + rt / 2, seat_bottom)),
            wood,
            group="legs",
        )
        for sx in (-1, 1):
            asm.add(
                "frame",
                M.box_between((sx * lx - rt / 2, -ly, z0), (sx * lx + rt / 2, ly, seat_bottom)),
                wood,
                group="legs",
            )
    if stretchers:
        zs = 0.15
        for sx in (-1, 1):
            asm.add(
                "stretcher",
                M.box_between((sx * lx - 0.008, -ly, zs - 0.01), (sx * lx + 0.008, ly, zs + 0.01)),
                wood,
                group="legs",
            )

    # Backrest: two reclined uprights rising from the rear legs, and a panel, slats,
    # spindles or an upholstered pad between them.
    pivot_y, pivot_z = -ly, seat_bottom
    length = (back_top - pivot_z - 0.45 * lw * math.sin(tilt)) / math.cos(tilt)
    for sx in (-1, 1):
        asm.add(
            "backrest",
            _tilted_box(
                (sx * lx - lw / 2, -0.45 * lw, 0.0),
                (sx * lx + lw / 2, 0.45 * lw, length),
                tilt,
                (0.0, pivot_y, pivot_z),
            ),
            wood,
            group="back",
        )
    xin = lx - lw / 2 + 0.004
    pivot = (0.0, pivot_y, pivot_z)
    if back_style == "panel":
        ph = min(0.30, 0.6 * length)
        asm.add(
            "backrest",
            _tilted_box((-xin, -0.011, length - ph), (xin, 0.011, length - 0.01), tilt, pivot),
            wood,
            group="back",
        )
    elif back_style == "slats":
        for k in range(3):
            top = length - 0.01 - k * 0.09
            asm.add(
                "backrest",
                _tilted_box((-xin, -0.01, top - 0.05), (xin, 0.01, top), tilt, pivot),
                wood,
                group="back",
            )
    elif back_style == "spindles":
        low = st + 0.10
        asm.add(
            "backrest",
            _tilted_box((-xin, -0.012, length - 0.08), (xin, 0.012, length - 0.01), tilt, pivot),
            wood,
            group="back",
        )
        asm.add(
            "backrest",
            _tilted_box((-xin, -0.01, low), (xin, 0.01, low + 0.03), tilt, pivot),
            wood,
            group="back",
        )
        for x in np.linspace(-xin, xin, 6)[1:-1]:
            rod = M.cylinder(
                0.008,
                length - 0.08 - low - 0.03 + 0.004,
                10,
                center=(x, pivot_y, pivot_z + low + 0.028),
            )
            asm.add("backrest", rod.rotated("x", tilt, about=pivot), wood, group="back")
    else:
        low = st + 0.14
        pad = M.rounded_box(
            (2 * xin, 0.045, length - 0.02 - low),
            0.015,
            axis="x",
            center=(0.0, pivot_y + 0.02, pivot_z + (length - 0.02 + low) / 2),
        )
        asm.add("backrest", pad.rotated("x", tilt, about=pivot), fabric, group="back")

    dims = {
        "seat_height": seat_h,
        "seat_width": sw,
        "seat_depth": sd,
        "seat_thickness": st,
        "recline": recline,
    }
    if arms:
        # Armrest: a pad on a post rising from the front leg, its back end in the upright.
        top = seat_h + arm_h
        pad_t = 0.025
        back_end = pivot_y - (top - pivot_z) * math.tan(tilt)
        for sx in (-1, 1):
            x = sx * lx
            asm.add(
                "armrest",
                M.box_between(
                    (x - arm_w / 2, back_end, top - pad_t), (x + arm_w / 2, ly + lw / 2 + 0.02, top)
                ),
                wood,
                group="arms",
            )
            asm.add(
                "armrest",
                M.box_between(
                    (x - 0.4 * lw, ly - 0.4 * lw, seat_bottom),
                    (x + 0.4 * lw, ly + 0.4 * lw, top - pad_t + 0.002),
                ),
                wood,
                group="arms",
            )
        dims["armrest_height"] = top
    dims["backrest_height"] = _part_top(asm, "backrest")
    return dims


def _chair_4leg(p: _Params) -> SceneObject:
    asm = _Assembly()
    dims = _chair_back_and_legs(p, asm, arms=False)
    return asm.build("chair", p.kind, dims, {"seat_part": "seat", "seat_center": [0.0, 0.0]})


def _chair_4leg_arms(p: _Params) -> SceneObject:
    asm = _Assembly()
    dims = _chair_back_and_legs(p, asm, arms=True)
    return asm.build("chair", p.kind, dims, {"seat_part": "seat", "seat_center": [0.0, 0.0]})


def _chair_office(p: _Params) -> SceneObject:
    """Swivel chair: five-star base on casters, gas-lift column, seat, backrest, armrests."""
    seat_h = p.uniform("seat_height", *OFFICE_SEAT_HEIGHT)
    sw = p.uniform("seat_width", 0.45, 0.52)
    sd = p.uniform("seat_depth", 0.40, 0.47)
    st = p.uniform("seat_thickness", 0.05, 0.08)
    # A five-star base of 60-70 cm diameter keeps the chair stable (EN 1335-2).
    base_r = p.uniform("base_radius", 0.30, 0.34)
    wheel_r = p.uniform("caster_radius", 0.025, 0.03)
    back_above = p.uniform("backrest_above_seat", 0.45, 0.70)
    back_w = p.uniform("backrest_width", 0.40, 0.48)
    back_t = p.uniform("backrest_thickness", 0.05, 0.08)
    lumbar_gap = p.uniform("backrest_gap", 0.06, 0.12)
    recline = p.uniform("recline", *RECLINE_DEGREES)
    arm_h = p.uniform("armrest_above_seat", *ARMREST_ABOVE_SEAT)
    arms = p.choice("arms", (True, False), (2, 1))
    plastic = p.color("base_color", PLASTIC, {"chrome": METAL["chrome"]})
    fabric = p.color("fabric_color", FABRIC)
    column_color = p.color("column_color", {"black": METAL["black"], "chrome": METAL["chrome"]})
    tilt = math.radians(recline - 90.0)
    asm = _Assembly()

    # Five legs slope down from the hub to the casters.
    leg_lo = 2 * wheel_r + 0.012
    hub_lo, hub_hi = leg_lo + 0.01, leg_lo + 0.08
    asm.add(
        "base", M.cylinder(0.045, hub_hi - hub_lo, 16, center=(0, 0, hub_lo)), plastic, group="base"
    )
    phase = p.uniform("base_rotation", 0.01, 2 * np.pi / 5)
    for k in range(5):
        a = phase + 2 * np.pi * k / 5
        # Corner i: outer end if i & 1, +y side if i & 2, top if i & 4 (see meshes.hexahedron).
        outer = (np.arange(8) & 1) > 0
        right = (np.arange(8) & 2) > 0
        upper = (np.arange(8) & 4) > 0
        c = np.column_stack(
            [
                np.where(outer, base_r - 0.02, 0.02),
                np.where(right, 0.5, -0.5) * np.where(outer, 0.035, 0.05),
                np.where(outer, leg_lo, hub_lo + 0.005) + upper * np.where(outer, 0.03, 0.045),
            ]
        )
        leg = M.hexahedron(c).rotated("z", a)
        asm.add("leg", leg, plastic, group="base")
        # Caster: a wheel under the leg's end, on a short stem.
        end = np.array([np.cos(a), np.sin(a)]) * (base_r - 0.025)
        trail = np.array([np.cos(a), np.sin(a)]) * 0.012
        side = np.array([-np.sin(a), np.cos(a)]) * 0.018
        centre = end + trail
        wheel = M.cylinder_between(
            (*(centre - side), wheel_r), (*(centre + side), wheel_r), wheel_r, 16
        )
        asm.add("caster", _on_floor(wheel), _shade(plastic, 0.6), group="base")
        asm.add(
            "caster",
            M.cylinder(0.008, leg_lo + 0.01 - 1.5 * wheel_r, 8, center=(*end, 1.5 * wheel_r)),
            _shade(plastic, 0.6),
            group="base",
        )

    mech_h = 0.045
    seat_y = p.uniform("seat_offset", 0.0, 0.03)
    z_mech = seat_h - st - mech_h
    asm.add(
        "column",
        M.frustum(0.035, 0.03, 0.5 * (z_mech - hub_hi) + 0.01, 16, center=(0, 0, hub_hi - 0.01)),
        _shade(plastic, 0.9),
        group="column",
    )
    asm.add(
        "column",
        M.cylinder(0.014, z_mech - hub_hi + 0.005, 12, center=(0, 0, hub_hi)),
        column_color,
        group="column",
    )
    asm.add(
        "mechanism",
        M.box((0.22, 0.24, mech_h), (0, seat_y, z_mech + mech_h / 2)),
        _shade(plastic, 0.8),
        group="column",
    )
    asm.add("seat", M.cushion((sw, sd, st), 0.15, center=(0, seat_y, seat_h - st / 2)), fabric)

    # Backrest pad, reclined about its lower edge, held by a bent spine from the mechanism.
    back_h = back_above - lumbar_gap
    pivot = np.array([0.0, seat_y - sd / 2 - back_t / 2 + 0.015, seat_h + lumbar_gap])
    pad = M.cushion((back_w, back_t, back_h), 0.2, center=pivot + (0, 0, back_h / 2))
    asm.add("backrest", pad.rotated("x", tilt, about=pivot), fabric, group="back")
    spine_r = 0.016
    p2 = _reclined(pivot, tilt, 0.05, -back_t / 2 - spine_r + 0.004)
    p3 = _reclined(pivot, tilt, 0.55 * back_h, -back_t / 2 - spine_r + 0.004)
    z_spine = z_mech + mech_h / 2
    p1 = p2 - (p2[2] - z_spine) / math.cos(tilt) * np.array([0, -math.sin(tilt), math.cos(tilt)])
    p0 = np.array([0.0, seat_y - 0.06, z_spine])
    spine = M.tube(M.fillet_path([p0, p1, p2, p3], 0.06), spine_r, 10)
    asm.add("backrest", spine, plastic, group="back")

    dims = {
        "seat_height": seat_h,
        "seat_width": sw,
        "seat_depth": sd,
        "seat_thickness": st,
        "recline": recline,
        "base_radius": base_r,
    }
    if arms:
        top = seat_h + arm_h
        for sx in (-1, 1):
            x = sx * (sw / 2 + 0.035)
            post = M.fillet_path(
                [
                    (sx * 0.09, seat_y - 0.04, z_spine),
                    (x, seat_y - 0.04, z_spine),
                    (x, seat_y - 0.04, top - 0.02),
                ],
                0.04,
            )
            asm.add("armrest", M.tube(post, 0.014, 10), plastic, group=f"arm{sx}")
            asm.add(
                "armrest",
                M.rounded_box((0.075, 0.26, 0.025), 0.03, center=(x, seat_y - 0.02, top - 0.0125)),
                _shade(plastic, 1.2),
                group=f"arm{sx}",
            )
        dims["armrest_height"] = top
    dims["backrest_height"] = _part_top(asm, "backrest")
    return asm.build("chair", p.kind, dims, {"seat_part": "seat", "seat_center": [0.0, seat_y]})


def _chair_shell(p: _Params, curved: bool = False) -> SceneObject:
    """Moulded plastic shell (seat and back in one curved piece) on four splayed legs.

    The plain shell has a flat seat between a rolled front lip and the curve into the
    back; ``curved=True`` makes a tub whose seat dips and flows into the back with no
    flat plane anywhere.
    """
    seat_h = p.uniform("seat_height", 0.43, 0.47)
    sw = p.uniform("seat_width", 0.44, 0.50)
    sd = p.uniform("seat_depth", 0.40, 0.46)
    t = p.uniform("shell_thickness", 0.010, 0.014)
    back_len = p.uniform("backrest_length", 0.36, 0.44)
    recline = p.uniform("recline", 100.0, 110.0)
    leg_r = p.uniform("leg_radius", 0.015, 0.02)
    splay = p.uniform("leg_splay", 0.03, 0.06)
    shell_color = p.color("shell_color", PLASTIC)
    leg_color = p.color("leg_color", WOOD, {"black": METAL["black"], "chrome": METAL["chrome"]})
    tilt = math.radians(recline - 90.0)
    if p.option("curved", curved, (False, True)):
        return _chair_tub(
            p.kind, seat_h, sw, sd, t, back_len, recline, leg_r, splay, shell_color, leg_color
        )
    asm = _Assembly()

    # Mid-surface profile in (y, z): a front lip rolling down, a flat seat, a curve up into
    # the reclined back.
    zm = seat_h - t / 2
    corner = np.array([0.0, -sd / 2, zm])
    top = corner + back_len * np.array([0.0, -math.sin(tilt), math.cos(tilt)])
    profile = M.fillet_path(
        [
            (0, sd / 2 + 0.015, zm - 0.035),
            (0, sd / 2 - 0.02, zm),
            (0, -sd / 2 + 0.06, zm),
            corner,
            top,
        ],
        0.06,
        samples=8,
    )
    prof = _resample(profile[:, 1:], 28)
    tangent = np.gradient(prof, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    toward_sitter = np.column_stack([tangent[:, 1], -tangent[:, 0]])
    s = np.linspace(-1.0, 1.0, 15)
    arc = np.linspace(0.0, 1.0, len(prof))
    width = np.interp(arc, [0.0, 0.06, 0.6, 1.0], [0.88 * sw, sw, sw, 0.94 * sw])
    # Raised rim: the edges curl 3 cm towards the sitter, the middle stays flat.
    curl = 0.03 * s**4
    grid = np.empty((len(s), len(prof), 3))
    grid[..., 0] = s[:, None] * width[None, :] / 2
    grid[..., 1] = prof[None, :, 0] + curl[:, None] * toward_sitter[None, :, 0]
    grid[..., 2] = prof[None, :, 1] + curl[:, None] * toward_sitter[None, :, 1]
    shell = M.thick_surface(grid, t)
    # Two collision boxes, seat and back, so that the seat can slide under a table top.
    n_v = len(prof)
    j = np.tile(np.arange(n_v), 2 * len(s))
    seat_rows = prof[:, 1] < zm + 0.04
    split = int(np.nonzero(seat_rows)[0].max())
    parts_v = [shell.vertices[j <= split], shell.vertices[j > split]]
    asm.add(
        "shell",
        shell,
        shell_color,
        boxes=[np.stack([v.min(axis=0), v.max(axis=0)]) for v in parts_v],
    )

    # Legs meet the shell's mid-surface, so their top ends are buried in it.
    ax, ay = sw / 2 - 0.08, sd / 2 - 0.09
    z_att = zm + 0.03 * (ax / (sw / 2)) ** 4
    for sx in (-1, 1):
        for sy in (-1, 1):
            top_pt = np.array([sx * ax, sy * ay, z_att])
            foot = np.array([sx * (ax + splay), sy * (ay + splay), 0.0])
            d = (top_pt - foot) / np.linalg.norm(top_pt - foot)
            foot[2] = leg_r * math.sqrt(1 - d[2] ** 2)
            asm.add(
                "leg",
                _on_floor(M.cylinder_between(foot, top_pt, leg_r, 12)),
                leg_color,
                group="legs",
            )
    seat_center_y = (sd / 2 - 0.02 + (-sd / 2 + 0.06)) / 2
    dims = {
        "seat_height": seat_h,
        "seat_width": sw,
        "seat_depth": sd,
        "seat_thickness": t,
        "recline": recline,
        "backrest_height": _part_top(asm, "shell"),
    }
    return asm.build(
        "chair", p.kind, dims, {"seat_part": "shell", "seat_center": [0.0, seat_center_y]}
    )


def _dished_shell(
    corners: ArrayLike,
    width: float,
    curl: float,
    thickness: float,
    fillet: float,
    rows: int = 32,
    cols: int = 15,
) -> tuple[M.Mesh, NDArray[np.float64]]:
    """A curved sheet along a rounded (k, 3) polyline of (0, y, z) corners, ``width`` wide,
    dished across: its sides rise ``curl`` metres towards the sitter (quadratically, so no
    row is flat). Returns the solid and its (cols, rows, 3) mid-surface grid."""
    profile = M.fillet_path(corners, fillet, samples=10)
    prof = _resample(profile[:, 1:], rows)
    tangent = np.gradient(prof, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    toward_sitter = np.column_stack([tangent[:, 1], -tangent[:, 0]])
    s = np.linspace(-1.0, 1.0, cols)
    lift = curl * s**2
    grid = np.empty((cols, rows, 3))
    grid[..., 0] = s[:, None] * width / 2
    grid[..., 1] = prof[None, :, 0] + lift[:, None] * toward_sitter[None, :, 0]
    grid[..., 2] = prof[None, :, 1] + lift[:, None] * toward_sitter[None, :, 1]
    return M.thick_surface(grid, thickness), grid


def _lowest_seat_point(
    mesh: M.Mesh, grid: NDArray[np.float64], seat_rows: NDArray[np.bool_]
) -> NDArray[np.float64]:
    """The lowest point of a dished shell's upper face along its middle, among the seat rows.

    ``thick_surface`` keeps its two faces' vertices in grid order, so the vertex over
    grid point (i, j) is i * rows + j on one face and that plus the grid size on the other.
    """
    cols, rows = grid.shape[:2]
    n = cols * rows
    idx = (cols // 2) * rows + np.nonzero(seat_rows)[0]
    v = mesh.vertices
    upper = np.where(v[idx, 2] >= v[idx + n, 2], idx, idx + n)
    return v[upper[np.argmin(v[upper, 2])]]


def _chair_tub(
    kind: str,
    seat_h: float,
    sw: float,
    sd: float,
    t: float,
    back_len: float,
    recline: float,
    leg_r: float,
    splay: float,
    shell_color: NDArray[np.uint8],
    leg_color: NDArray[np.uint8],
) -> SceneObject:
    """The curved shell chair: seat and back one continuous dished surface on four legs."""
    tilt = math.radians(recline - 90.0)
    corner = np.array([0.0, -sd / 2, 0.0])
    top = corner + back_len * np.array([0.0, -math.sin(tilt), math.cos(tilt)])
    # The seat dips about 2.5 cm below its front edge and the start of the back.
    corners = [
        (0.0, sd / 2 + 0.015, -0.02),
        (0.0, sd / 2 - 0.03, 0.012),
        (0.0, -0.04, -0.013),
        corner,
        top,
    ]
    shell, grid = _dished_shell(corners, sw, 0.05, t, 0.14)
    seat_rows = grid[grid.shape[0] // 2, :, 2] < 0.04
    low = _lowest_seat_point(shell, grid, seat_rows)
    lift = np.array([0.0, 0.0, seat_h - low[2]])
    shell = shell.translated(lift)
    grid = grid + lift
    asm = _Assembly()
    asm.add("shell", shell, shell_color, boxes=_split_boxes(shell, seat_h + 0.05))
    mid = grid.reshape(-1, 3)
    ax, ay = sw / 2 - 0.08, sd / 2 - 0.09
    for sx in (-1, 1):
        for sy in (-1, 1):
            # Each leg ends on the shell's mid-surface, buried in the shell.
            top_pt = mid[np.argmin(np.hypot(mid[:, 0] - sx * ax, mid[:, 1] - sy * ay))]
            foot = np.array([sx * (ax + splay), sy * (ay + splay), 0.0])
            d = (top_pt - foot) / np.linalg.norm(top_pt - foot)
            foot[2] = leg_r * math.sqrt(1 - d[2] ** 2)
            asm.add(
                "leg",
                _on_floor(M.cylinder_between(foot, top_pt, leg_r, 12)),
                leg_color,
                group="legs",
            )
    dims = {
        "seat_height": seat_h,
        "seat_width": sw,
        "seat_depth": sd,
        "seat_thickness": t,
        "recline": recline,
        "backrest_height": _part_top(asm, "shell"),
    }
    extra = {"seat_part": "shell", "seat_center": [float(low[0]), float(low[1])]}
    return asm.build("chair", kind, dims, extra)


def _chair_sled(p: _Params) -> SceneObject:
    """Tubular steel chair: a sled (closed loop per side) or cantilever (S-bent) frame."""
    seat_h = p.uniform("seat_height", 0.44, 0.48)
    sw = p.uniform("seat_width", 0.42, 0.48)
    sd = p.uniform("seat_depth", 0.40, 0.46)
    st = p.uniform("seat_thickness", 0.03, 0.05)
    r = p.uniform("tube_radius", 0.010, 0.0125)
    back_top = p.uniform("backrest_height", 0.80, 0.90)
    recline = p.uniform("recline", 95.0, 105.0)
    panel_h = p.uniform("backrest_panel_height", 0.20, 0.30)
    frame = p.choice("frame", ("sled", "cantilever"))
    metal = p.color("frame_color", METAL)
    seat_color = p.color("seat_color", FABRIC, WOOD, PLASTIC)
    tilt = math.radians(recline - 90.0)
    asm = _Assembly()

    x = sw / 2 - 0.03
    z_top = seat_h - st - r + 0.003  # tube top slightly inside the seat
    back_y = -sd / 2 + 0.03
    length = (back_top - z_top) / math.cos(tilt)
    for sx in (-1, 1):
        xs = sx * x
        if frame == "sled":
            loop = [
                (xs, sd / 2 + 0.03, r),
                (xs, sd / 2 - 0.03, z_top),
                (xs, back_y, z_top),
                (xs, -sd / 2 - 0.03, r),
            ]
            asm.add(
                "base",
                _on_floor(M.tube(M.fillet_path(loop, 0.05, 8, closed=True), r, 12, closed=True)),
                metal,
                group="frame",
            )
            upright = [
                np.array([xs, back_y, z_top - 0.02]),
                _reclined((xs, back_y, z_top), tilt, length),
            ]
            asm.add("backrest", M.tube(np.array(upright), r, 12), metal, group="back")
        else:
            path = [
                (xs, -sd / 2 + 0.05, r),
                (xs, sd / 2 + 0.02, r),
                (xs, sd / 2 - 0.02, z_top),
                (xs, back_y, z_top),
                _reclined((xs, back_y, z_top), tilt, length),
            ]
            frame_tube = _on_floor(M.tube(M.fillet_path(path, 0.06, 8), r, 12))
            asm.add(
                "base",
                frame_tube,
                metal,
                group="frame",
                boxes=_split_boxes(frame_tube, z_top + r + 0.005),
            )
    if frame == "cantilever":
        asm.add(
            "base",
            _on_floor(M.tube(np.array([(-x, -sd / 2 + 0.05, r), (x, -sd / 2 + 0.05, r)]), r, 12)),
            metal,
            group="frame",
        )
    asm.add("seat", M.rounded_box((sw, sd, st), 0.04, center=(0, 0, seat_h - st / 2)), seat_color)
    pivot = np.array([0.0, back_y, z_top])
    panel = M.rounded_box(
        (2 * x + 2 * r + 0.02, 0.02, panel_h),
        0.03,
        axis="y",
        center=pivot + (0, r + 0.01, length - panel_h / 2),
    )
    asm.add("backrest", panel.rotated("x", tilt, about=pivot), seat_color, group="back")
    dims = {
        "seat_height": seat_h,
        "seat_width": sw,
        "seat_depth": sd,
        "seat_thickness": st,
        "recline": recline,
        "backrest_height": _part_top(asm, "backrest"),
    }
    return asm.build("chair", p.kind, dims, {"seat_part": "seat", "seat_center": [0.0, 0.0]})


# --------------------------------------------------------------------------------------
# Sofas and armchairs.
#
# Upholstered seating (Neufert; EN 12520 / EN 1728 cover its strength): seat height
# 38-45 cm on the cushions, seat depth 50-60 cm, overall depth 80-100 cm, back 75-95 cm
# high, 55-70 cm of width per seat, arms 15-25 cm above the seat and 12-25 cm wide.

SOFA_SEAT_HEIGHT = (0.38, 0.45)
SOFA_DEPTH = (0.82, 1.00)
SOFA_HEIGHT = (0.75, 0.95)
SOFA_SEAT_WIDTH = (0.55, 0.70)
SOFA_ARM_WIDTH = (0.12, 0.25)
SOFA_ARM_ABOVE_SEAT = (0.15, 0.25)


def _sofa_base(p: _Params, *, armchair: bool = False) -> dict[str, Any]:
    q = {
        "seat_h": p.uniform("seat_height", *((0.40, 0.45) if armchair else SOFA_SEAT_HEIGHT)),
        "depth": p.uniform("depth", *SOFA_DEPTH),
        "height": p.uniform("height", *SOFA_HEIGHT),
        "per_seat": p.uniform("seat_width", *((0.52, 0.62) if armchair else SOFA_SEAT_WIDTH)),
        "arm_w": p.uniform("arm_width", *SOFA_ARM_WIDTH),
        "arm_above": p.uniform(
            "armrest_above_seat", *(ARMREST_ABOVE_SEAT if armchair else SOFA_ARM_ABOVE_SEAT)
        ),
        "cushion_t": p.uniform("cushion_thickness", 0.10, 0.18),
        "back_t": p.uniform("back_thickness", 0.15, 0.22),
        "back_cushion_t": p.uniform("back_cushion_thickness", 0.12, 0.18),
        "recline": p.uniform("recline", 100.0, 110.0),
        "feet": p.choice("feet", ("feet", "plinth")),
        "foot_h": p.uniform("foot_height", 0.04, 0.12),
        "fabric": p.color("fabric_color", FABRIC),
        "foot_color": p.color(
            "foot_color", WOOD, {"black": METAL["black"], "chrome": METAL["chrome"]}
        ),
    }
    q["z0"] = q["foot_h"] if q["feet"] == "feet" else 0.03
    return q


def _sofa_cushions(
    asm: _Assembly,
    q: dict[str, Any],
    x0: float,
    x1: float,
    y_back: float,
    y_front: float,
    n: int,
    *,
    back: bool = True,
    run: str = "",
) -> None:
    """n seat cushions side by side over [x0, x1] x [y_back, y_front], with back cushions."""
    seat_h, ct, bct = q["seat_h"], q["cushion_t"], q["back_cushion_t"]
    tilt = math.radians(q["recline"] - 90.0)
    edges = np.linspace(x0, x1, n + 1)
    for a, b in itertools.pairwise(edges):
        y_seat = y_back + (bct if back else 0.0)
        asm.add(
            "cushion",
            M.cushion(
                (b - a - 0.006, y_front - y_seat, ct),
                0.18,
                center=((a + b) / 2, (y_seat + y_front) / 2, seat_h - ct / 2),
            ),
            q["fabric"],
            group="cushion" + run,
        )
        if back:
            bh = q["height"] - seat_h - 0.03
            pivot = np.array([(a + b) / 2, y_back + bct / 2, seat_h - 0.02])
            c = M.cushion((b - a - 0.006, bct, bh), 0.25, center=pivot + (0, 0, bh / 2))
            asm.add(
                "back_cushion",
                c.rotated("x", tilt, about=pivot),
                _shade(q["fabric"], 0.95),
                group="back_cushion" + run,
            )


def _sofa_feet(asm: _Assembly, q: dict[str, Any], corners: list[tuple[float, float]]) -> None:
    if q["feet"] == "feet":
        for i, (x, y) in enumerate(corners):
            asm.add(
                "leg",
                M.frustum(0.02, 0.025, q["z0"], 12, center=(x, y, 0.0)),
                q["foot_color"],
                group=f"foot{i}",
            )


def _sofa_straight(p: _Params, n_seats: int, arms: bool, class_name: str = "sofa") -> SceneObject:
    armchair = class_name == "chair"
    q = _sofa_base(p, armchair=armchair)
    asm = _Assembly()
    dims, extra = _upholstered(asm, q, n_seats, arms)
    return asm.build(class_name, p.kind, dims, extra)


def _upholstered(
    asm: _Assembly, q: dict[str, Any], n_seats: int, arms: bool
) -> tuple[dict[str, float], dict[str, Any]]:
    """A straight sofa or an armchair from its drawn parameters ``q`` (see :func:`_sofa_base`);
    returns its dimensions and ``extra``."""
    aw = q["arm_w"] if arms else 0.0
    inner = n_seats * q["per_seat"]
    W, D, z0 = inner + 2 * aw, q["depth"], q["z0"]
    seat_bottom = q["seat_h"] - q["cushion_t"]
    bt = q["back_t"]
    # Frame under the cushions and the upholstered back (the backrest proper).
    asm.add(
        "frame",
        M.box_between((-inner / 2, -D / 2 + bt - 0.01, z0), (inner / 2, D / 2 - 0.01, seat_bottom)),
        q["fabric"],
        group="body",
    )
    asm.add(
        "backrest",
        M.rounded_box(
            (W if arms else inner, bt, q["height"] - z0),
            0.04,
            axis="x",
            center=(0, -D / 2 + bt / 2, (q["height"] + z0) / 2),
        ),
        q["fabric"],
        group="body",
    )
    dims = {
        "seat_height": q["seat_h"],
        "seat_depth": D - bt - q["back_cushion_t"],
        "seat_width": q["per_seat"],
        "seats": float(n_seats),
        "recline": q["recline"],
    }
    if arms:
        top = q["seat_h"] + q["arm_above"]
        for sx in (-1, 1):
            xc = sx * (inner / 2 + aw / 2)
            asm.add(
                "arm",
                M.rounded_box(
                    (aw, D, top - z0),
                    min(0.06, aw / 2 - 0.005),
                    axis="y",
                    center=(xc, 0.0, (top + z0) / 2),
                ),
                q["fabric"],
                group=f"arm{sx}",
            )
        dims["armrest_height"] = top
        dims["arm_width"] = aw
    if q["feet"] == "plinth":
        asm.add(
            "base",
            M.box_between(
                (-W / 2 + 0.03, -D / 2 + 0.03, 0.0), (W / 2 - 0.03, D / 2 - 0.03, z0 + 0.001)
            ),
            _shade(q["fabric"], 0.5),
            group="body",
        )
    _sofa_cushions(asm, q, -inner / 2, inner / 2, -D / 2 + bt, D / 2, n_seats)
    fx, fy = W / 2 - 0.05, D / 2 - 0.05
    feet = [(sx * fx, sy * fy) for sx in (-1, 1) for sy in (-1, 1)]
    if n_seats >= 3:
        feet += [(0.0, -fy), (0.0, fy)]
    _sofa_feet(asm, q, feet)
    dims["backrest_height"] = max(_part_top(asm, "backrest"), _part_top(asm, "back_cushion"))
    first = -inner / 2 + q["per_seat"] / 2
    seat_center = [first, (-D / 2 + bt + q["back_cushion_t"] + D / 2) / 2]
    return dims, {
        "seat_part": "cushion",
        "seat_center": seat_center,
        "front_span": [-W / 2, W / 2, D / 2],
    }


def _sofa_l(p: _Params) -> SceneObject:
    """Corner sofa: two runs at right angles with backs along both, arms at the open ends."""
    q = _sofa_base(p)
    W = p.uniform("width", 2.2, 3.0)
    # The side run must hold at least one seat beyond the corner.
    Dt = q["depth"] + q["arm_w"] + p.uniform("side_run_length", 0.55, 1.1)
    side = p.choice("corner", ("left", "right"))
    asm = _Assembly()
    D, bt, aw, z0 = q["depth"], q["back_t"], q["arm_w"], q["z0"]
    seat_bottom = q["seat_h"] - q["cushion_t"]
    top = q["seat_h"] + q["arm_above"]
    H = q["height"]
    x0, y0 = -W / 2, -Dt / 2  # the corner, built on the left and mirrored for "right"
    f = q["fabric"]
    asm.add("backrest", M.box_between((x0, y0, z0), (W / 2 - aw, y0 + bt, H)), f, group="back1")
    asm.add(
        "backrest", M.box_between((x0, y0 + bt, z0), (x0 + bt, Dt / 2 - aw, H)), f, group="back2"
    )
    asm.add(
        "arm",
        M.rounded_box(
            (aw, D, top - z0),
            min(0.06, aw / 2 - 0.005),
            axis="y",
            center=(W / 2 - aw / 2, y0 + D / 2, (top + z0) / 2),
        ),
        f,
        group="arm1",
    )
    asm.add(
        "arm",
        M.rounded_box(
            (D, aw, top - z0),
            min(0.06, aw / 2 - 0.005),
            axis="x",
            center=(x0 + D / 2, Dt / 2 - aw / 2, (top + z0) / 2),
        ),
        f,
        group="arm2",
    )
    asm.add(
        "frame",
        M.box_between(
            (x0 + bt - 0.01, y0 + bt - 0.01, z0), (W / 2 - aw + 0.005, y0 + D - 0.01, seat_bottom)
        ),
        f,
        group="frame_main",
    )
    asm.add(
        "frame",
        M.box_between(
            (x0 + bt - 0.01, y0 + D - 0.011, z0), (x0 + D - 0.01, Dt / 2 - aw + 0.005, seat_bottom)
        ),
        f,
        group="frame_side",
    )
    bct = q["back_cushion_t"]
    # Main run: cushions along x, backs against the main back; the corner seat belongs to it.
    n_main = max(2, round((W - aw - bt) / q["per_seat"]))
    _sofa_cushions(asm, q, x0 + bt + bct, W / 2 - aw, y0 + bt, y0 + D - 0.01, n_main, run="_main")
    # Side run: cushions along y, back cushions leaning on the side back.
    n_side = max(1, round((Dt / 2 - aw - (y0 + D)) / q["per_seat"]))
    side_asm = _Assembly()
    length = Dt / 2 - aw - (y0 + D)
    _sofa_cushions(
        side_asm, q, -length / 2, length / 2, -(D - 0.01 - bt) / 2, (D - 0.01 - bt) / 2, n_side
    )
    for m, part, color in zip(side_asm.meshes, side_asm.parts, side_asm.colors):
        # Turn the run a quarter to the right so its back faces -x, then move it beside the corner.
        m2 = m.rotated("z", -np.pi / 2).translated(
            (x0 + bt + (D - 0.01 - bt) / 2, y0 + D + length / 2, 0.0)
        )
        asm.add(part, m2, color, group=part + "_side")
    # The corner's own back cushion against the side back, above the main run's first cushion.
    corner_back = M.cushion((D - bt - bct - 0.01, bct, H - q["seat_h"] - 0.03), 0.25)
    pivot = np.array([0.0, 0.0, q["seat_h"] - 0.02])
    cb = corner_back.translated((0, 0, q["seat_h"] - 0.02 + (H - q["seat_h"] - 0.03) / 2))
    cb = cb.rotated("x", math.radians(q["recline"] - 90.0), about=pivot).rotated("z", -np.pi / 2)
    asm.add(
        "back_cushion",
        cb.translated((x0 + bt + bct / 2, y0 + bt + bct + (D - bt - bct) / 2, 0.0)),
        _shade(f, 0.95),
        group="back_cushion_main",
    )
    fx, fy = 0.05, 0.05
    _sofa_feet(
        asm,
        q,
        [
            (x0 + fx, y0 + fy),
            (W / 2 - fx, y0 + fy),
            (W / 2 - fx, y0 + D - fy),
            (x0 + fx, Dt / 2 - fy),
            (x0 + D - fx, Dt / 2 - fy),
            (x0 + D - fx, y0 + D - fy),
        ],
    )
    if q["feet"] == "plinth":
        asm.add(
            "base",
            M.box_between((x0 + 0.03, y0 + 0.03, 0.0), (W / 2 - 0.03, y0 + D - 0.03, z0 + 0.001)),
            _shade(f, 0.5),
            group="frame_main",
        )
        asm.add(
            "base",
            M.box_between(
                (x0 + 0.03, y0 + D - 0.03, 0.0), (x0 + D - 0.03, Dt / 2 - 0.03, z0 + 0.001)
            ),
            _shade(f, 0.5),
            group="frame_side",
        )
    seat_center = [
        W / 2 - aw - (W - aw - bt - bct) / n_main / 2,
        (y0 + bt + bct + y0 + D - 0.01) / 2,
    ]
    if side == "right":
        asm.mirror_x()
        seat_center[0] = -seat_center[0]
    dims = {
        "seat_height": q["seat_h"],
        "seat_depth": D - bt - bct,
        "armrest_height": top,
        "arm_width": aw,
        "recline": q["recline"],
        "seats": float(n_main + n_side),
        "backrest_height": max(_part_top(asm, "backrest"), _part_top(asm, "back_cushion")),
    }
    # The free edge in front of the main run (beyond the side run), for a coffee table.
    front_span = [x0 + D, W / 2, y0 + D]
    if side == "right":
        front_span = [-W / 2, W / 2 - D, y0 + D]
    extra = {
        "seat_part": "cushion",
        "seat_center": seat_center,
        "corner": side,
        "front_span": front_span,
    }
    return asm.build("sofa", p.kind, dims, extra)


# --------------------------------------------------------------------------------------
# Easy chairs: club armchairs, wingbacks, lounge chairs.
#
# Catalogue ranges of upholstered easy chairs (EN 12520 sets their strength and safety
# requirements, EN 1022 their stability test): club chairs 80-100 cm wide, 80-95 cm
# deep and 70-85 cm high, the seat cushion 37-45 cm above the floor, arms 55-65 cm high
# and 15-25 cm wide, the middle of the backrest 47-60 cm up; upholstered down to the
# floor or on feet up to 12 cm. Wingbacks have a backrest 100-120 cm high with wings
# beside the head. Lounge chairs are a shell on a pedestal, the seat 38-42 cm high and
# the back reclined 20-30 degrees from the vertical.

CLUB_WIDTH = (0.80, 1.00)
CLUB_DEPTH = (0.80, 0.95)
CLUB_HEIGHT = (0.70, 0.85)
CLUB_SEAT_HEIGHT = (0.37, 0.45)
CLUB_ARM_HEIGHT = (0.55, 0.65)
CLUB_ARM_WIDTH = (0.15, 0.25)
CLUB_BACK_CENTER = (0.47, 0.60)
CLUB_FOOT_HEIGHT = (0.03, 0.12)
WINGBACK_HEIGHT = (1.00, 1.20)
WINGBACK_WIDTH = (0.75, 0.90)
WINGBACK_SEAT_HEIGHT = (0.40, 0.46)
WINGBACK_ARM_WIDTH = (0.10, 0.16)
LOUNGE_SEAT_HEIGHT = (0.38, 0.42)
LOUNGE_BACK_TILT = (20.0, 30.0)
#: Least height of the arms above the seat cushion (a forearm rests on them).
_EASY_ARM_ABOVE_SEAT = 0.12


def _easy_chair(p: _Params, wingback: bool) -> SceneObject:
    """A club armchair, or a wingback (tall back with wings, on legs), built like a sofa."""
    seat_h = p.uniform("seat_height", *(WINGBACK_SEAT_HEIGHT if wingback else CLUB_SEAT_HEIGHT))
    width = p.uniform("width", *(WINGBACK_WIDTH if wingback else CLUB_WIDTH))
    depth = p.uniform("depth", *CLUB_DEPTH)
    height = p.uniform("height", *(WINGBACK_HEIGHT if wingback else CLUB_HEIGHT))
    arm_h = p.uniform("armrest_height", *CLUB_ARM_HEIGHT)
    arm_w = p.uniform("arm_width", *(WINGBACK_ARM_WIDTH if wingback else CLUB_ARM_WIDTH))
    q: dict[str, Any] = {
        "cushion_t": p.uniform("cushion_thickness", 0.10, 0.16),
        "back_t": p.uniform("back_thickness", 0.15, 0.22),
        "back_cushion_t": p.uniform("back_cushion_thickness", 0.10, 0.16),
        "recline": p.uniform("recline", 100.0, 110.0),
        "feet": p.choice("feet", ("feet", "plinth"), (5, 1) if wingback else (1, 1)),
        "foot_h": p.uniform("foot_height", *CLUB_FOOT_HEIGHT),
        "fabric": p.color("fabric_color", FABRIC),
        "foot_color": p.color(
            "foot_color", WOOD, {"black": METAL["black"], "chrome": METAL["chrome"]}
        ),
    }
    wing_depth = p.uniform("wing_depth", 0.20, 0.30)
    wing_t = p.uniform("wing_thickness", 0.06, 0.10)
    if not wingback:
        # The middle of the backrest stays in its range: a low seat goes with a taller back.
        height = min(height, 2 * CLUB_BACK_CENTER[1] - seat_h)
    # At least 50 cm between the arms; the arms clear the seat cushion.
    arm_w = min(arm_w, (width - 0.50) / 2)
    arm_h = max(arm_h, seat_h + _EASY_ARM_ABOVE_SEAT)
    q.update(
        seat_h=seat_h,
        depth=depth,
        height=height,
        per_seat=width - 2 * arm_w,
        arm_w=arm_w,
        arm_above=arm_h - seat_h,
        z0=q["foot_h"] if q["feet"] == "feet" else 0.03,
    )
    asm = _Assembly()
    dims, extra = _upholstered(asm, q, 1, True)
    if wingback:
        # Wings: upholstered side panels from the arms to near the top of the back.
        z0, z1 = arm_h - 0.01, height - 0.03
        y0 = -depth / 2 + q["back_t"] - 0.02
        for sx in (-1, 1):
            asm.add(
                "wing",
                M.cushion(
                    (wing_t, wing_depth, z1 - z0),
                    0.2,
                    center=(sx * (width / 2 - wing_t / 2), y0 + wing_depth / 2, (z0 + z1) / 2),
                ),
                q["fabric"],
                group=f"wing{sx}",
            )
        dims["wing_depth"] = wing_depth
    dims["backrest_center"] = (seat_h + height) / 2
    dims["backrest_height"] = max(dims["backrest_height"], height)
    return asm.build("chair", p.kind, dims, extra)


def _chair_lounge(p: _Params) -> SceneObject:
    """A lounge chair: one dished shell, seat tilted back and back reclined, on a pedestal."""
    seat_h = p.uniform("seat_height", *LOUNGE_SEAT_HEIGHT)
    sw = p.uniform("seat_width", 0.55, 0.68)
    sd = p.uniform("seat_depth", 0.48, 0.56)
    back_len = p.uniform("backrest_length", 0.55, 0.72)
    back_tilt = p.uniform("back_tilt", *LOUNGE_BACK_TILT)
    seat_tilt = p.uniform("seat_tilt", 4.0, 10.0)
    t = p.uniform("shell_thickness", 0.02, 0.035)
    base = p.choice("base", ("star", "disc"))
    shell_color = p.color("shell_color", FABRIC, WOOD, PLASTIC)
    base_color = p.color("base_color", METAL)
    tilt_b, tilt_s = math.radians(back_tilt), math.radians(seat_tilt)
    corner = np.array([0.0, -sd / 2, 0.0])
    front = corner + sd * np.array([0.0, math.cos(tilt_s), math.sin(tilt_s)])
    top = corner + back_len * np.array([0.0, -math.sin(tilt_b), math.cos(tilt_b)])
    corners = [front + (0.0, 0.02, -0.04), front, corner + (0.0, sd / 2, -0.01), corner, top]
    shell, grid = _dished_shell(corners, sw, 0.06, t, 0.16)
    seat_rows = grid[grid.shape[0] // 2, :, 2] < front[2] + 0.02
    low = _lowest_seat_point(shell, grid, seat_rows)
    lift = np.array([0.0, 0.0, seat_h - low[2]])
    shell = shell.translated(lift)
    grid = grid + lift
    asm = _Assembly()
    asm.add("shell", shell, shell_color, boxes=_split_boxes(shell, seat_h + 0.08))
    # A column from the base into the shell under the middle of the seat.
    mid = grid.reshape(-1, 3)
    col_top = mid[np.argmin(np.hypot(mid[:, 0], mid[:, 1] - low[1]))]
    base_h = 0.04
    if base == "disc":
        asm.add(
            "base",
            M.lathe([(0, 0), (0.26, 0), (0.26, 0.012), (0.05, base_h), (0, base_h)], 32).translated(
                (0.0, low[1], 0.0)
            ),
            base_color,
            group="base",
        )
    else:
        for k in range(4):
            foot = M.box_between((0.0, -0.025, 0.0), (0.34, 0.025, base_h)).rotated(
                "z", np.pi / 4 + k * np.pi / 2
            )
            asm.add("base", foot.translated((0.0, low[1], 0.0)), base_color, group="base")
    asm.add(
        "column",
        M.cylinder(0.03, col_top[2] - base_h + 0.002, 16, center=(0.0, col_top[1], base_h - 0.002)),
        base_color,
        group="base",
    )
    dims = {
        "seat_height": seat_h,
        "seat_width": sw,
        "seat_depth": sd,
        "seat_thickness": t,
        "back_tilt": back_tilt,
        "recline": 90.0 + back_tilt - seat_tilt,
        "backrest_height": _part_top(asm, "shell"),
    }
    extra = {"seat_part": "shell", "seat_center": [float(low[0]), float(low[1])]}
    return asm.build("chair", p.kind, dims, extra)


# --------------------------------------------------------------------------------------
# Stools, benches, ottomans (seating without a back; not chairs).
#
# Stool seat heights 45-80 cm: 45-50 cm at a table (EN 1729-1 size marks, Neufert),
# 60-68 cm at a 90 cm kitchen counter and 72-80 cm at a 105-115 cm bar (Neufert).
# Benches 42-48 cm high, 30-45 cm deep (EN 12520 / Neufert); ottomans 38-45 cm.

STOOL_HEIGHT = (0.45, 0.50)
BAR_STOOL_HEIGHT = (0.65, 0.80)


def _stool(p: _Params, shape: str) -> SceneObject:
    bar = shape == "bar"
    seat_h = p.uniform("seat_height", *(BAR_STOOL_HEIGHT if bar else STOOL_HEIGHT))
    size = p.uniform("seat_size", 0.30, 0.40)
    st = p.uniform("seat_thickness", 0.03, 0.05)
    leg_r = p.uniform("leg_radius", 0.015, 0.02)
    n_legs = p.choice("legs", (3, 4)) if shape == "round" else 4
    base = p.choice("base", ("legs", "pedestal")) if bar else "legs"
    wood = p.color("frame_color", WOOD, {"black": METAL["black"], "chrome": METAL["chrome"]})
    seat_color = p.color("seat_color", WOOD, FABRIC, PLASTIC)
    asm = _Assembly()
    z_seat = seat_h - st
    if shape == "square":
        asm.add(
            "seat",
            M.box_between((-size / 2, -size / 2, z_seat), (size / 2, size / 2, seat_h)),
            seat_color,
        )
        lx = size / 2 - 0.03
        _four_legs(asm, "square", lx, lx, 0.0, z_seat + 0.001, 2 * leg_r, wood, group="legs")
        for k in range(4):
            bar_mesh = (
                M.box_between((-lx, -0.008, 0.16), (lx, 0.008, 0.18))
                .translated((0.0, lx, 0.0))
                .rotated("z", k * np.pi / 2)
            )
            asm.add("stretcher", bar_mesh, wood, group="legs")
    else:
        asm.add("seat", M.cylinder(size / 2, st, 24, center=(0, 0, z_seat)), seat_color)
        if base == "pedestal":
            asm.add(
                "base",
                M.lathe([(0, 0), (0.21, 0), (0.2, 0.015), (0.05, 0.035), (0, 0.035)], 28),
                wood,
                group="legs",
            )
            asm.add(
                "column",
                M.cylinder(0.028, z_seat - 0.03, 16, center=(0, 0, 0.03)),
                wood,
                group="legs",
            )
            asm.add(
                "footrest",
                M.torus(0.16, 0.01, 32, 8).translated((0, 0, seat_h - 0.30)),
                wood,
                group="legs",
            )
            for k in range(3):
                a = k * 2 * np.pi / 3
                asm.add(
                    "footrest",
                    M.cylinder_between(
                        (0, 0, seat_h - 0.30),
                        (0.16 * np.cos(a), 0.16 * np.sin(a), seat_h - 0.30),
                        0.008,
                        8,
                    ),
                    wood,
                    group="legs",
                )
        else:
            top_r = size / 2 - 0.05
            foot_r = top_r + 0.04 + 0.04 * bar
            angles = np.arange(n_legs) * 2 * np.pi / n_legs + np.pi / n_legs
            for a in angles:
                d = np.array([np.cos(a), np.sin(a)])
                top_pt = np.array([*(d * top_r), z_seat + 0.005])
                foot = np.array([*(d * foot_r), 0.0])
                axis = (top_pt - foot) / np.linalg.norm(top_pt - foot)
                foot[2] = leg_r * math.sqrt(1 - axis[2] ** 2)
                asm.add(
                    "leg",
                    _on_floor(M.cylinder_between(foot, top_pt, leg_r, 12)),
                    wood,
                    group="legs",
                )
            # A ring joins the legs; on a bar stool it is the footrest, 30-45 cm below the seat.
            z_ring = seat_h - 0.42 if bar else 0.18
            ring_r = foot_r + (top_r - foot_r) * z_ring / z_seat
            asm.add(
                "footrest" if bar else "stretcher",
                M.torus(ring_r, 0.009 if not bar else 0.011, 32, 8).translated((0, 0, z_ring)),
                wood,
                group="legs",
            )
    dims = {"seat_height": seat_h, "seat_thickness": st}
    return asm.build("stool", p.kind, dims, {"seat_part": "seat", "seat_center": [0.0, 0.0]})


def _bench(p: _Params) -> SceneObject:
    seat_h = p.uniform("seat_height", 0.42, 0.48)
    length = p.uniform("width", 1.0, 2.0)
    depth = p.uniform("depth", 0.32, 0.45)
    st = p.uniform("seat_thickness", 0.03, 0.05)
    slats = p.choice("slats", (1, 3, 4))
    support = p.choice("support", ("panels", "legs"))
    shelf = p.choice("shelf", (False, True), (3, 1))
    wood = p.color("seat_color", WOOD)
    frame = p.color("frame_color", WOOD, {"black": METAL["black"], "aluminium": METAL["aluminium"]})
    asm = _Assembly()
    gap = 0.01 if slats > 1 else 0.0
    w = (depth - gap * (slats - 1)) / slats
    for k in range(slats):
        y0 = -depth / 2 + k * (w + gap)
        asm.add(
            "seat",
            M.box_between((-length / 2, y0, seat_h - st), (length / 2, y0 + w, seat_h)),
            wood,
            group="seat",
        )
    inset = min(0.2, 0.12 * length)
    if support == "panels":
        for sx in (-1, 1):
            x = sx * (length / 2 - inset)
            asm.add(
                "leg",
                M.box_between(
                    (x - 0.02, -depth / 2 + 0.02, 0.0), (x + 0.02, depth / 2 - 0.02, seat_h - st)
                ),
                frame,
                group=f"leg{sx}",
            )
    else:
        xs = [-(length / 2 - inset), length / 2 - inset] + ([0.0] if length > 1.6 else [])
        for i, x in enumerate(xs):
            for sy in (-1, 1):
                asm.add(
                    "leg",
                    _leg("square", x, sy * (depth / 2 - 0.04), 0.0, seat_h - st, 0.04),
                    frame,
                    group=f"leg{i}{sy}",
                )
    if shelf:
        asm.add(
            "shelf",
            M.box_between(
                (-(length / 2 - inset) + 0.02, -depth / 2 + 0.03, 0.12),
                (length / 2 - inset - 0.02, depth / 2 - 0.03, 0.14),
            ),
            frame,
            group="shelf",
        )
    dims = {"seat_height": seat_h, "seat_thickness": st}
    return asm.build(
        "bench", p.kind, dims, {"seat_part": "seat", "seat_center": [0.0, -depth / 2 + w / 2]}
    )


def _ottoman(p: _Params, shape: str) -> SceneObject:
    seat_h = p.uniform("seat_height", 0.38, 0.45)
    w = p.uniform("width", 0.45, 0.85) if shape == "box" else p.uniform("diameter", 0.40, 0.60)
    d = p.uniform("depth", 0.40, 0.60) if shape == "box" else w
    ct = p.uniform("cushion_thickness", 0.06, 0.10)
    feet = p.choice("feet", (False, True))
    fabric = p.color("fabric_color", FABRIC)
    foot_color = p.color("foot_color", WOOD)
    asm = _Assembly()
    z0 = 0.05 if feet else 0.0
    body_top = seat_h - ct + 0.01
    if shape == "box":
        asm.add(
            "base",
            M.rounded_box((w, d, body_top - z0), 0.04, center=(0, 0, (body_top + z0) / 2)),
            _shade(fabric, 0.9),
        )
        asm.add("cushion", M.cushion((w, d, ct), 0.15, center=(0, 0, seat_h - ct / 2)), fabric)
    else:
        asm.add(
            "base", M.cylinder(w / 2, body_top - z0, 32, center=(0, 0, z0)), _shade(fabric, 0.9)
        )
        asm.add(
            "cushion",
            M.superellipsoid((w, w, ct), 0.2, 1.0, 10, 32, center=(0, 0, seat_h - ct / 2)),
            fabric,
        )
    if feet:
        r = 0.7 * min(w, d) / 2 if shape == "round" else None
        pts = (
            [(r * np.cos(a), r * np.sin(a)) for a in np.arange(4) * np.pi / 2 + np.pi / 4]
            if r
            else [(sx * (w / 2 - 0.05), sy * (d / 2 - 0.05)) for sx in (-1, 1) for sy in (-1, 1)]
        )
        for x, y in pts:
            asm.add(
                "leg",
                M.frustum(0.015, 0.02, z0 + 0.001, 12, center=(x, y, 0)),
                foot_color,
                group="feet",
            )
    dims = {"seat_height": seat_h}
    return asm.build("ottoman", p.kind, dims, {"seat_part": "cushion", "seat_center": [0.0, 0.0]})


# --------------------------------------------------------------------------------------
# Tables and desks.
#
# Dining and conference tables 72-76 cm high (EN 1730 tests them; heights per
# Neufert), coffee tables 35-50 cm; office desks EN 527-1: fixed height 74 +/- 2 cm,
# top at least 120 x 80 cm. Tops 2-4 cm thick; table legs 4-6 cm (heavier than a
# chair's 3-5 cm).

TABLE_HEIGHT = (0.72, 0.76)
COFFEE_TABLE_HEIGHT = (0.35, 0.50)
BAR_TABLE_HEIGHT = (0.90, 1.05)
DESK_HEIGHT = (0.72, 0.76)
TOP_THICKNESS = (0.02, 0.04)
TABLE_LEG_WIDTH = (0.04, 0.06)


def _table_top(
    asm: _Assembly, p: _Params, w: float, d: float, h: float, t: float, color: NDArray[np.uint8]
) -> None:
    radius = p.uniform("corner_radius", 0.001, 0.06)
    asm.add("top", M.rounded_box((w, d, t), radius, center=(0, 0, h - t / 2)), color, group="top")


def _legged_table(
    p: _Params,
    w: float,
    d: float,
    h: float,
    *,
    kind_class: str = "table",
    apron_p: float = 0.8,
    extra_legs: bool = False,
    shelf: bool = False,
) -> SceneObject:
    t = p.uniform("top_thickness", *TOP_THICKNESS)
    lw = p.uniform("leg_width", *TABLE_LEG_WIDTH)
    inset = p.uniform("leg_inset", 0.03, 0.10)
    leg_style = p.choice("leg_style", ("square", "tapered", "round"))
    apron = p.choice("apron", (True, False), (apron_p, 1 - apron_p))
    apron_h = p.uniform("apron_height", 0.06, 0.10)
    top_color = p.color("top_color", WOOD, LAMINATE)
    leg_color = p.color("leg_color", WOOD, METAL)
    asm = _Assembly()
    _table_top(asm, p, w, d, h, t, top_color)
    lx, ly = w / 2 - inset - lw / 2, d / 2 - inset - lw / 2
    xs = [-lx, lx] + ([0.0] if extra_legs else [])
    for i, x in enumerate(xs):
        for sy in (-1, 1):
            asm.add(
                "leg",
                _leg(leg_style, x, sy * ly, 0.0, h - t + 0.001, lw),
                leg_color,
                group=f"leg{i}{sy}",
            )
    if apron:
        z0, z1 = h - t - apron_h, h - t + 0.001
        at = 0.02
        for sy in (-1, 1):
            asm.add(
                "apron",
                M.box_between((-lx, sy * ly - at / 2, z0), (lx, sy * ly + at / 2, z1)),
                leg_color,
                group=f"apron_y{sy}",
            )
        for sx in (-1, 1):
            asm.add(
                "apron",
                M.box_between((sx * lx - at / 2, -ly, z0), (sx * lx + at / 2, ly, z1)),
                leg_color,
                group=f"apron_x{sx}",
            )
    if shelf:
        asm.add(
            "shelf",
            M.box_between((-lx + lw / 2, -ly + lw / 2, 0.12), (lx - lw / 2, ly - lw / 2, 0.14)),
            top_color,
            group="shelf",
        )
    dims = {"top_height": h, "top_thickness": t}
    extra = {"support_rect": [-w / 2, -d / 2, w / 2, d / 2], "support_z": h, "support_round": False}
    return asm.build(kind_class, p.kind, dims, extra)


def _table_dining(p: _Params) -> SceneObject:
    w = p.uniform("width", 1.2, 2.0)
    d = p.uniform("depth", 0.75, 1.0)
    h = p.uniform("top_height", *TABLE_HEIGHT)
    return _legged_table(p, w, d, h)


def _table_small(p: _Params) -> SceneObject:
    """A small square or rectangular table for two to four (kitchens, small rooms)."""
    w = p.uniform("width", 0.75, 1.2)
    d = p.uniform("depth", 0.65, 0.85)
    h = p.uniform("top_height", *TABLE_HEIGHT)
    return _legged_table(p, w, d, h)


def _table_coffee(p: _Params) -> SceneObject:
    w = p.uniform("width", 0.9, 1.3)
    d = p.uniform("depth", 0.5, 0.7)
    h = p.uniform("top_height", *COFFEE_TABLE_HEIGHT)
    shelf = p.choice("shelf", (False, True))
    return _legged_table(p, w, d, h, apron_p=0.4, shelf=shelf)


def _table_bar(p: _Params) -> SceneObject:
    """A high table (breakfast bar, kitchen island) for bar stools."""
    w = p.uniform("width", 1.0, 1.6)
    d = p.uniform("depth", 0.55, 0.8)
    h = p.uniform("top_height", *BAR_TABLE_HEIGHT)
    return _legged_table(p, w, d, h, apron_p=0.3)


def _table_round(p: _Params) -> SceneObject:
    """Round top on a central pedestal standing on a disc or four feet."""
    diameter = p.uniform("diameter", 0.7, 1.2)
    h = p.uniform("top_height", *TABLE_HEIGHT)
    t = p.uniform("top_thickness", *TOP_THICKNESS)
    col_r = p.uniform("pedestal_radius", 0.04, 0.08)
    foot = p.choice("base", ("disc", "cross"))
    top_color = p.color("top_color", WOOD, LAMINATE)
    base_color = p.color("base_color", WOOD, METAL)
    asm = _Assembly()
    asm.add("top", M.cylinder(diameter / 2, t, 40, center=(0, 0, h - t)), top_color, group="top")
    base_r = min(0.32, 0.32 * diameter + 0.1)
    if foot == "disc":
        asm.add(
            "base",
            M.lathe([(0, 0), (base_r, 0), (base_r, 0.015), (col_r + 0.02, 0.05), (0, 0.05)], 36),
            base_color,
            group="base",
        )
    else:
        for k in range(4):
            c = np.array(
                [
                    [(i & 1) * base_r, ((i >> 1) & 1) * 0.05 - 0.025, (i >> 2) * 0.05]
                    for i in range(8)
                ]
            )
            c[5, 2] = c[7, 2] = 0.025  # feet thin out towards their ends
            asm.add(
                "base",
                M.hexahedron(c).rotated("z", k * np.pi / 2 + np.pi / 4),
                base_color,
                group="base",
            )
    asm.add(
        "pedestal",
        M.cylinder(col_r, h - t - 0.04, 24, center=(0, 0, 0.04)),
        base_color,
        group="base",
    )
    dims = {"top_height": h, "top_thickness": t, "diameter": diameter}
    extra = {
        "support_rect": [-diameter / 2, -diameter / 2, diameter / 2, diameter / 2],
        "support_z": h,
        "support_round": True,
    }
    return asm.build("table", p.kind, dims, extra)


def _table_conference(p: _Params) -> SceneObject:
    """Long meeting table, 2.4-4 m, on several legs or on panel legs."""
    w = p.uniform("width", 2.4, 4.0)
    d = p.uniform("depth", 1.0, 1.4)
    h = p.uniform("top_height", *TABLE_HEIGHT)
    t = p.uniform("top_thickness", 0.03, 0.04)
    support = p.choice("support", ("legs", "panels"))
    panel_inset = p.uniform("panel_inset", 0.30, 0.50)
    top_color = p.color("top_color", WOOD, LAMINATE)
    leg_color = p.color("leg_color", METAL, LAMINATE)
    lw = p.uniform("leg_width", 0.05, 0.07)
    asm = _Assembly()
    _table_top(asm, p, w, d, h, t, top_color)
    n = 3 if w > 3.0 else 2
    xs = np.linspace(-(w / 2 - panel_inset), w / 2 - panel_inset, n)
    if support == "panels":
        for i, x in enumerate(xs):
            asm.add(
                "leg",
                M.box_between((x - 0.025, -0.35 * d, 0.0), (x + 0.025, 0.35 * d, h - t + 0.001)),
                leg_color,
                group=f"panel{i}",
            )
            asm.add(
                "leg",
                M.box_between((x - 0.04, -0.38 * d, 0.0), (x + 0.04, 0.38 * d, 0.02)),
                leg_color,
                group=f"panel{i}",
            )
        asm.add(
            "frame",
            M.box_between((xs[0], -0.05, h - t - 0.12), (xs[-1], 0.05, h - t + 0.001)),
            leg_color,
            group="beam",
        )
    else:
        ly = d / 2 - 0.08
        xs_legs = np.linspace(-(w / 2 - 0.1), w / 2 - 0.1, n)
        for i, x in enumerate(xs_legs):
            for sy in (-1, 1):
                asm.add(
                    "leg",
                    _leg("square", x, sy * ly, 0.0, h - t + 0.001, lw),
                    leg_color,
                    group=f"leg{i}{sy}",
                )
    dims = {"top_height": h, "top_thickness": t}
    extra = {"support_rect": [-w / 2, -d / 2, w / 2, d / 2], "support_z": h, "support_round": False}
    return asm.build("table", p.kind, dims, extra)


def _desk(p: _Params, style: str) -> SceneObject:
    w = p.uniform("width", 1.2, 1.8)
    d = p.uniform("depth", 0.7, 0.9)
    h = p.uniform("top_height", *DESK_HEIGHT)
    t = p.uniform("top_thickness", 0.025, 0.035)
    side = p.choice("pedestal_side", (-1, 1))
    legs = p.choice("support", ("legs", "panels"))
    modesty_h = p.uniform("modesty_panel_height", 0.30, 0.50)
    top_color = p.color("top_color", LAMINATE, WOOD)
    body_color = p.color("body_color", LAMINATE, METAL)
    handle_color = p.color("handle_color", METAL)
    asm = _Assembly()
    asm.add(
        "top", M.box_between((-w / 2, -d / 2, h - t), (w / 2, d / 2, h)), top_color, group="top"
    )
    under = h - t + 0.001
    knee = [0.0, 0.0]

    def end_support(x: float, group: str) -> None:
        if legs == "panels":
            asm.add(
                "leg",
                M.box_between((x - 0.0125, -d / 2 + 0.02, 0.0), (x + 0.0125, d / 2 - 0.03, under)),
                body_color,
                group=group,
            )
        else:
            for sy in (-1, 1):
                asm.add(
                    "leg",
                    _leg("square", x, sy * (d / 2 - 0.06), 0.0, under, 0.05),
                    body_color,
                    group=f"{group}{sy}",
                )

    if style == "pedestal":
        pw = p.uniform("pedestal_width", 0.40, 0.45)
        x0 = side * (w / 2 - 0.02) - (pw if side > 0 else 0.0)
        x1 = x0 + pw
        y_front = d / 2 - 0.03
        asm.add(
            "pedestal",
            M.box_between((x0, -d / 2 + 0.03, 0.0), (x1, y_front, under)),
            body_color,
            group="pedestal",
        )
        n = 3
        hd = (under - 0.02) / n
        for k in range(n):
            z0 = 0.01 + k * hd
            asm.add(
                "drawer",
                M.box_between(
                    (x0 + 0.003, y_front, z0 + 0.002),
                    (x1 - 0.003, y_front + 0.018, z0 + hd - 0.002),
                ),
                _shade(body_color, 1.05),
                group="pedestal",
            )
            asm.add(
                "handle",
                _handle((x0 + x1) / 2, y_front + 0.018, z0 + hd - 0.04, 0.12, False, handle_color),
                handle_color,
                group="pedestal",
            )
        end_support(-side * (w / 2 - 0.04), "legs")
        knee = [float((-side * (w / 2 - 0.04) + (x0 if side > 0 else x1)) / 2), 0.0]
    else:
        for sx in (-1, 1):
            end_support(sx * (w / 2 - 0.04), f"legs{sx}")
    modesty = p.choice("modesty_panel", (True, False))
    if style == "panel" or modesty:
        y = -d / 2 + 0.06
        xm = w / 2 - 0.04 - (0.0125 if legs == "panels" else 0.025)
        asm.add(
            "modesty_panel",
            M.box_between((-xm, y, under - modesty_h), (xm, y + 0.018, under)),
            body_color,
            group="modesty",
        )
    dims = {"top_height": h, "top_thickness": t}
    extra = {
        "support_rect": [-w / 2, -d / 2, w / 2, d / 2],
        "support_z": h,
        "support_round": False,
        "knee_center": knee,
    }
    return asm.build("desk", p.kind, dims, extra)


# --------------------------------------------------------------------------------------
# Storage: cabinets, kitchen counters, closets, bookshelves.
#
# Sideboards and office storage 70-120 cm high, 40-50 cm deep; kitchen base units
# EN 1116: 60 cm modules, worktop 85-95 cm high, 60 cm deep; wardrobes 55-65 cm deep
# and 180-220 cm high; bookshelves 25-40 cm deep with 30-38 cm between shelves (Neufert).


def _fronts(
    asm: _Assembly,
    x0: float,
    x1: float,
    z0: float,
    z1: float,
    y: float,
    cols: int,
    rows: int,
    part: str,
    color: NDArray[np.uint8],
    handle_color: NDArray[np.uint8],
    group: str,
) -> None:
    """A grid of door or drawer fronts on the plane y (front faces at y + 18 mm)."""
    gap = 0.003
    xs = np.linspace(x0, x1, cols + 1)
    zs = np.linspace(z0, z1, rows + 1)
    for i in range(cols):
        for j in range(rows):
            asm.add(
                part,
                M.box_between(
                    (xs[i] + gap, y, zs[j] + gap), (xs[i + 1] - gap, y + 0.018, zs[j + 1] - gap)
                ),
                color,
                group=group,
            )
            if part == "door":
                hx = xs[i + 1] - 0.04 if i % 2 == 0 else xs[i] + 0.04
                asm.add(
                    "handle",
                    _handle(hx, y + 0.018, (zs[j] + zs[j + 1]) / 2, 0.12, True, handle_color),
                    handle_color,
                    group=group,
                )
            else:
                asm.add(
                    "handle",
                    _handle(
                        (xs[i] + xs[i + 1]) / 2,
                        y + 0.018,
                        zs[j + 1] - 0.04,
                        0.12,
                        False,
                        handle_color,
                    ),
                    handle_color,
                    group=group,
                )


def _cabinet(p: _Params) -> SceneObject:
    variant = p.choice("variant", ("sideboard", "filing", "tall"))
    ranges = {
        "sideboard": ((0.8, 1.6), (0.40, 0.50), (0.70, 1.00)),
        "filing": ((0.4, 0.9), (0.45, 0.60), (0.70, 1.30)),
        "tall": ((0.6, 1.0), (0.40, 0.60), (1.60, 2.00)),
    }[variant]
    w = p.uniform("width", *ranges[0])
    d = p.uniform("depth", *ranges[1])
    h = p.uniform("height", *ranges[2])
    plinth = p.choice("plinth", ("plinth", "legs"))
    color = p.color("color", LAMINATE, WOOD)
    handle_color = p.color("handle_color", METAL)
    asm = _Assembly()
    z0 = 0.08 if plinth == "plinth" else 0.12
    _plinth_or_legs(asm, plinth == "plinth", w, d, z0, color, plinth_inset=0.04, leg_inset=0.04)
    top_t = 0.025
    y_front = d / 2 - 0.018
    asm.add(
        "body",
        M.box_between((-w / 2, -d / 2, z0), (w / 2, y_front, h - top_t)),
        color,
        group="body",
    )
    asm.add(
        "top",
        M.box_between((-w / 2 - 0.005, -d / 2, h - top_t), (w / 2 + 0.005, d / 2, h)),
        color,
        group="body",
    )
    if variant == "filing":
        _fronts(
            asm,
            -w / 2,
            w / 2,
            z0,
            h - top_t,
            y_front,
            1,
            max(2, round((h - z0) / 0.3)),
            "drawer",
            color,
            handle_color,
            "body",
        )
    else:
        cols = max(1, round(w / 0.45))
        _fronts(
            asm,
            -w / 2,
            w / 2,
            z0,
            h - top_t,
            y_front,
            cols,
            1 + (variant == "tall"),
            "door",
            color,
            handle_color,
            "body",
        )
    dims = {"top_height": h}
    extra = {
        "support_rect": [-w / 2, -d / 2, w / 2, d / 2],
        "support_z": h,
        "support_round": False,
        "variant": variant,
    }
    return asm.build("cabinet", p.kind, dims, extra)


def _nightstand(p: _Params) -> SceneObject:
    w = p.uniform("width", 0.40, 0.50)
    d = p.uniform("depth", 0.35, 0.45)
    h = p.uniform("height", 0.45, 0.60)
    color = p.color("color", WOOD, LAMINATE)
    handle_color = p.color("handle_color", METAL)
    asm = _Assembly()
    z0 = 0.1
    _four_legs(
        asm, "tapered", (w / 2 - 0.03), (d / 2 - 0.03), 0.0, z0 + 0.001, 0.03, color, group="body"
    )
    asm.add(
        "body", M.box_between((-w / 2, -d / 2, z0), (w / 2, d / 2 - 0.018, h)), color, group="body"
    )
    _fronts(
        asm,
        -w / 2,
        w / 2,
        z0,
        h,
        d / 2 - 0.018,
        1,
        2,
        "drawer",
        _shade(color, 1.05),
        handle_color,
        "body",
    )
    extra = {"support_rect": [-w / 2, -d / 2, w / 2, d / 2], "support_z": h, "support_round": False}
    return asm.build("cabinet", p.kind, {"top_height": h}, extra)


def _kitchen_counter(p: _Params) -> SceneObject:
    units = p.integer("units", 1, 4)
    h = p.uniform("top_height", 0.86, 0.92)
    depth = p.uniform("depth", 0.60, 0.62)
    t = p.uniform("top_thickness", 0.03, 0.04)
    color = p.color("color", LAMINATE, WOOD)
    top_color = p.color("top_color", LAMINATE, WOOD, {"granite": (60, 60, 64)})
    handle_color = p.color("handle_color", METAL)
    w = 0.6 * units
    asm = _Assembly()
    plinth_h = 0.12
    y_front = depth - 0.03 - 0.018 - depth / 2
    asm.add(
        "base",
        M.box_between((-w / 2, -depth / 2, 0.0), (w / 2, y_front - 0.05, plinth_h)),
        _shade(color, 0.5),
        group="body",
    )
    asm.add(
        "body",
        M.box_between((-w / 2, -depth / 2, plinth_h - 0.001), (w / 2, y_front, h - t)),
        color,
        group="body",
    )
    asm.add(
        "top",
        M.box_between((-w / 2, -depth / 2, h - t), (w / 2, depth / 2, h)),
        top_color,
        group="body",
    )
    for k in range(units):
        x0 = -w / 2 + 0.6 * k
        if p.rng.random() < 0.35:
            _fronts(
                asm,
                x0,
                x0 + 0.6,
                plinth_h,
                h - t,
                y_front,
                1,
                3,
                "drawer",
                color,
                handle_color,
                "body",
            )
        else:
            _fronts(
                asm,
                x0,
                x0 + 0.6,
                plinth_h,
                h - t,
                y_front,
                1,
                1,
                "door",
                color,
                handle_color,
                "body",
            )
    extra = {
        "support_rect": [-w / 2, -depth / 2, w / 2, depth / 2],
        "support_z": h,
        "support_round": False,
    }
    return asm.build("cabinet", p.kind, {"top_height": h}, extra)


def _closet(p: _Params) -> SceneObject:
    w = p.uniform("width", 0.8, 2.0)
    d = p.uniform("depth", 0.55, 0.65)
    h = p.uniform("height", 1.8, 2.2)
    color = p.color("color", LAMINATE, WOOD)
    handle_color = p.color("handle_color", METAL)
    asm = _Assembly()
    z0 = 0.06
    asm.add(
        "base",
        M.box_between((-w / 2 + 0.03, -d / 2, 0.0), (w / 2 - 0.03, d / 2 - 0.05, z0 + 0.001)),
        _shade(color, 0.6),
        group="body",
    )
    y_front = d / 2 - 0.018
    asm.add(
        "body", M.box_between((-w / 2, -d / 2, z0), (w / 2, y_front, h - 0.03)), color, group="body"
    )
    asm.add(
        "top", M.box_between((-w / 2, -d / 2, h - 0.03), (w / 2, d / 2, h)), color, group="body"
    )
    doors = max(2, round(w / 0.5))
    _fronts(
        asm, -w / 2, w / 2, z0, h - 0.03, y_front, doors, 1, "door", color, handle_color, "body"
    )
    return asm.build("closet", p.kind, {}, {})


def _bookshelf(p: _Params) -> SceneObject:
    w = p.uniform("width", 0.6, 1.0)
    d = p.uniform("depth", 0.25, 0.40)
    h = p.uniform("height", 0.8, 2.0)
    bt = p.uniform("board_thickness", 0.018, 0.025)
    spacing = p.uniform("shelf_spacing", 0.30, 0.38)
    fill = p.uniform("fill", 0.3, 1.0)
    color = p.color("color", WOOD, LAMINATE)
    asm = _Assembly()
    base_h = 0.06
    for sx in (-1, 1):
        asm.add(
            "side",
            M.box_between(
                (sx * w / 2 - (bt if sx > 0 else 0), -d / 2, 0.0),
                (sx * w / 2 + (0 if sx > 0 else bt), d / 2, h),
            ),
            color,
            group="body",
        )
    xin = w / 2 - bt
    asm.add(
        "back",
        M.box_between((-xin, -d / 2, 0.0), (xin, -d / 2 + 0.006, h)),
        _shade(color, 0.9),
        group="body",
    )
    asm.add(
        "base",
        M.box_between((-xin, d / 2 - 0.03, 0.0), (xin, d / 2 - 0.01, base_h)),
        color,
        group="body",
    )
    n = max(1, int((h - base_h - bt) // spacing))
    levels = np.linspace(base_h, h - bt, n + 1)
    for z in levels:
        part = "top" if z == levels[-1] else "shelf"
        asm.add(
            part,
            M.box_between((-xin, -d / 2 + 0.006, z), (xin, d / 2, z + bt)),
            color,
            group="body",
        )
    # Books stand on each shelf, spines out, filling part of each row.
    rng = p.rng
    for z0, z1 in zip(levels[:-1] + bt, levels[1:]):
        x = -xin + 0.005
        end = -xin + fill * 2 * xin * rng.uniform(0.6, 1.0)
        while True:
            bw = rng.uniform(0.015, 0.06)
            if x + bw > min(end, xin - 0.003):
                break
            bh = rng.uniform(0.6, 0.95) * min(0.32, z1 - z0 - 0.01)
            bd = rng.uniform(0.6, 0.95) * (d - 0.03)
            color_b = np.asarray(list(PAPER.values())[rng.integers(len(PAPER))]) + rng.integers(
                -20, 21, 3
            )
            y_front = d / 2 - rng.uniform(0.005, 0.03)
            asm.add(
                "books",
                M.box_between((x, y_front - bd, z0 + _GAP), (x + bw, y_front, z0 + bh)),
                np.clip(color_b, 0, 255),
                group="body",
            )
            x += bw + rng.uniform(0.0, 0.004)
    return asm.build("bookshelf", p.kind, {"shelves": float(n)}, {})


# --------------------------------------------------------------------------------------
# Beds: DIN EN 1334 / EN 1725 mattress sizes 90-180 x 200 cm; mattress top 45-60 cm
# above the floor, headboard 90-120 cm (Neufert).


def _bed(p: _Params) -> SceneObject:
    width = p.choice("mattress_width", (0.9, 1.2, 1.4, 1.6, 1.8))
    length = p.choice("mattress_length", (2.0, 2.0, 1.9, 2.1))
    top = p.uniform("mattress_height", 0.45, 0.60)
    mt = p.uniform("mattress_thickness", 0.15, 0.25)
    head_h = p.uniform("headboard_height", 0.90, 1.20)
    legs = p.choice("legs", (True, False))
    duvet = p.choice("duvet", (True, False), (3, 1))
    frame_color = p.color("frame_color", WOOD, FABRIC)
    linen = p.color(
        "linen_color",
        {
            "white": (238, 238, 234),
            "cream": (230, 222, 200),
            "grey": (170, 172, 176),
            "blue": (120, 150, 190),
        },
    )
    duvet_color = p.color("duvet_color", FABRIC, {"white": (236, 236, 232)})
    asm = _Assembly()
    fw, fl = width + 0.06, length + 0.06
    frame_top = top - mt + 0.02
    z0 = 0.12 if legs else 0.0
    head_t = 0.06
    y_head = -fl / 2
    asm.add(
        "frame",
        M.box_between((-fw / 2, y_head + head_t - 0.001, z0), (fw / 2, fl / 2 + head_t, frame_top)),
        frame_color,
        group="body",
    )
    if legs:
        for sx in (-1, 1):
            for sy in (-1, 1):
                asm.add(
                    "leg",
                    _leg(
                        "square",
                        sx * (fw / 2 - 0.05),
                        y_head + head_t + 0.04 if sy < 0 else fl / 2 + head_t - 0.05,
                        0.0,
                        z0 + 0.001,
                        0.05,
                    ),
                    frame_color,
                    group="body",
                )
    asm.add(
        "headboard",
        M.rounded_box(
            (fw, head_t, head_h), 0.02, axis="y", center=(0, y_head + head_t / 2, head_h / 2)
        ),
        frame_color,
        group="body",
    )
    yc = y_head + head_t + 0.03 + length / 2
    asm.add(
        "mattress",
        M.cushion((width, length, mt), 0.1, center=(0, yc, top - mt / 2)),
        linen,
        group="body",
    )
    n_pillows = 1 if width < 1.3 else 2
    pw = min(0.7, (width - 0.1) / n_pillows)
    for k in range(n_pillows):
        x = (k - (n_pillows - 1) / 2) * (width / n_pillows)
        asm.add(
            "pillow",
            M.cushion(
                (pw - 0.04, 0.42, 0.12), 0.35, center=(x, yc - length / 2 + 0.28, top + 0.05)
            ),
            _shade(linen, 0.97),
            group="body",
        )
    if duvet:
        dl = 0.62 * length
        asm.add(
            "duvet",
            M.cushion(
                (width + 0.06, dl, 0.10),
                0.3,
                center=(0, yc + length / 2 - dl / 2 + 0.02, top - 0.02),
            ),
            duvet_color,
            group="body",
        )
    dims = {"mattress_height": top, "mattress_width": width, "headboard_height": head_h}
    return asm.build("bed", p.kind, dims, {"support_z": top})


# --------------------------------------------------------------------------------------
# Small things and distractors.


def _box(p: _Params) -> SceneObject:
    w = p.uniform("width", 0.2, 0.6)
    d = p.uniform("depth", 0.2, 0.5)
    h = p.uniform("height", 0.15, 0.5)
    color = p.color("color", CARDBOARD)
    asm = _Assembly()
    asm.add("box", M.box_between((-w / 2, -d / 2, 0.0), (w / 2, d / 2, h)), color)
    asm.add(
        "tape",
        M.box_between((-w / 2 - 0.001, -0.025, h - 0.02), (w / 2 + 0.001, 0.025, h + 0.001)),
        (196, 170, 120),
    )
    return asm.build("box", p.kind, {}, {})


def _books(p: _Params) -> SceneObject:
    """A stack of books lying flat."""
    n = p.integer("count", 1, 5)
    asm = _Assembly()
    z = 0.0
    rng = p.rng
    for _ in range(n):
        w, d, t = rng.uniform(0.15, 0.30), rng.uniform(0.12, 0.22), rng.uniform(0.015, 0.05)
        a = rng.uniform(-0.25, 0.25)
        color = np.asarray(list(PAPER.values())[rng.integers(len(PAPER))])
        asm.add("book", M.box((w, d, t), (0, 0, z + t / 2)).rotated("z", a), color)
        z += t
    return asm.build("books", p.kind, {}, {})


def _monitor(p: _Params, television: bool = False) -> SceneObject:
    """A flat screen on a stand (ISO 9241-5: top of the screen at or below eye height)."""
    w = p.uniform("screen_width", *((0.90, 1.45) if television else (0.48, 0.72)))
    t = p.uniform("screen_thickness", 0.02, 0.05)
    lift = p.uniform("screen_lift", *((0.05, 0.10) if television else (0.08, 0.16)))
    color = p.color(
        "color",
        {
            "black": (26, 26, 28),
            "dark_grey": (60, 62, 66),
            "silver": (170, 172, 176),
            "white": (230, 230, 228),
        },
    )
    h = w * 9 / 16 + 0.03
    asm = _Assembly()
    asm.add(
        "screen",
        M.box_between((-w / 2, -t / 2, lift), (w / 2, t / 2, lift + h)),
        (18, 18, 22) if television else _shade(color, 0.5),
    )
    foot_w = 0.35 * w if television else 0.24
    asm.add("base", M.rounded_box((foot_w, 0.2, 0.015), 0.04, center=(0, -0.02, 0.0075)), color)
    asm.add(
        "stand",
        M.box_between((-0.03, -t / 2 - 0.03, 0.014), (0.03, -t / 2 + 0.001, lift + 0.6 * h)),
        color,
    )
    return asm.build("television", p.kind, {"screen_width": w}, {})


def _keyboard(p: _Params) -> SceneObject:
    w = p.uniform("width", 0.42, 0.46)
    d = p.uniform("depth", 0.13, 0.16)
    h = p.uniform("height", 0.015, 0.025)
    color = p.color(
        "color", {"black": (28, 28, 30), "white": (232, 232, 230), "grey": (120, 122, 126)}
    )
    asm = _Assembly()
    asm.add("body", M.box_between((-w / 2, -d / 2, 0.0), (w / 2, d / 2, h)), color)
    asm.add(
        "keys",
        M.box_between(
            (-w / 2 + 0.01, -d / 2 + 0.01, h - 0.001), (w / 2 - 0.01, d / 2 - 0.02, h + 0.008)
        ),
        _shade(color, 0.85),
    )
    return asm.build("keyboard", p.kind, {}, {})


def _mouse(p: _Params) -> SceneObject:
    color = p.color("color", {"black": (28, 28, 30), "white": (232, 232, 230)})
    asm = _Assembly()
    asm.add("body", M.superellipsoid((0.06, 0.11, 0.07), 0.6, 0.8, 8, 16), color)
    # Flatten the lower half onto the desk: a flat-bottomed pebble 3.5 cm high.
    obj_mesh = asm.meshes[0]
    v = obj_mesh.vertices.copy()
    v[:, 2] = np.maximum(v[:, 2], 0.0)
    asm.meshes[0] = M.Mesh(v, obj_mesh.triangles)
    return asm.build("otherprop", p.kind, {}, {})


def _plant(p: _Params, small: bool = False) -> SceneObject:
    pot_r = p.uniform("pot_radius", *((0.06, 0.09) if small else (0.12, 0.22)))
    pot_h = p.uniform("pot_height", *((0.08, 0.14) if small else (0.18, 0.40)))
    height = p.uniform("height", *((0.2, 0.4) if small else (0.6, 1.6)))
    habit = p.choice("habit", ("bush", "tree"))
    pot_color = p.color("pot_color", CERAMIC)
    leaf = p.color("foliage_color", FOLIAGE)
    rng = p.rng
    asm = _Assembly()
    r0, wall = 0.78 * pot_r, 0.012
    asm.add(
        "pot",
        M.lathe(
            [
                (0, 0),
                (r0, 0),
                (pot_r, pot_h),
                (pot_r - wall, pot_h),
                (pot_r - wall - (pot_r - r0) * 0.1, 0.85 * pot_h),
                (0, 0.85 * pot_h),
            ],
            28,
        ),
        pot_color,
        group="pot",
    )
    asm.add(
        "soil",
        M.cylinder(pot_r - wall - 0.004, 0.01, 24, center=(0, 0, 0.85 * pot_h)),
        (70, 52, 38),
        group="pot",
    )
    crown_h = height - pot_h
    if habit == "tree" and not small:
        trunk_top = pot_h + 0.55 * crown_h
        asm.add(
            "stem",
            M.cylinder(0.015, trunk_top - 0.85 * pot_h + 0.05, 10, center=(0, 0, 0.85 * pot_h)),
            (96, 72, 50),
            group="crown",
        )
        radii = (0.8 * 0.45 * crown_h, 0.8 * 0.45 * crown_h, 0.5 * (height - trunk_top) + 0.05)
        centre_z = height - radii[2]
        asm.add("foliage", M.blob(radii, rng, 0.3, center=(0, 0, centre_z)), leaf, group="crown")
    else:
        rx = max(pot_r * 1.3, 0.45 * crown_h)
        rz = crown_h / 2 + 0.03
        asm.add(
            "foliage",
            M.blob((rx, rx * rng.uniform(0.8, 1.0), rz), rng, 0.3, center=(0, 0, height - rz)),
            leaf,
            group="crown",
        )
    return asm.build("plant", p.kind, {}, {})


def _bin(p: _Params) -> SceneObject:
    r = p.uniform("radius", 0.13, 0.18)
    h = p.uniform("height", 0.28, 0.45)
    shape = p.choice("shape", ("round", "square"))
    color = p.color("color", PLASTIC, {"steel": METAL["aluminium"]})
    asm = _Assembly()
    wall = 0.008
    if shape == "round":
        r0 = 0.82 * r
        asm.add(
            "bin",
            M.lathe([(0, 0), (r0, 0), (r, h), (r - wall, h), (r0 - wall, 0.012), (0, 0.012)], 28),
            color,
        )
    else:
        s = 1.6 * r
        asm.add("bin", M.box_between((-s / 2, -s / 2, 0.0), (s / 2, s / 2, 0.012)), color)
        for k in range(4):
            asm.add(
                "bin",
                M.box_between((-s / 2, s / 2 - wall, 0.011), (s / 2 - wall, s / 2, h)).rotated(
                    "z", k * np.pi / 2
                ),
                color,
            )
    return asm.build("bin", p.kind, {}, {})


def _radiator(p: _Params) -> SceneObject:
    """Panel or column radiator on two floor consoles (EN 442; 10-15 cm above the floor)."""
    w = p.uniform("width", 0.6, 1.6)
    h = p.uniform("radiator_height", 0.40, 0.60)
    d = p.uniform("radiator_depth", 0.06, 0.11)
    lift = p.uniform("floor_clearance", 0.10, 0.15)
    style = p.choice("style", ("panel", "column"))
    color = p.color(
        "color", {"white": (236, 236, 232), "cream": (232, 226, 210), "grey": (190, 190, 192)}
    )
    asm = _Assembly()
    if style == "panel":
        for y in (-d / 2, d / 2 - 0.022):
            asm.add(
                "panel",
                M.box_between((-w / 2, y, lift), (w / 2, y + 0.022, lift + h)),
                color,
                group="body",
            )
        asm.add(
            "grille",
            M.box_between(
                (-w / 2 + 0.01, -d / 2 + 0.02, lift + h - 0.03),
                (w / 2 - 0.01, d / 2 - 0.02, lift + h - 0.005),
            ),
            _shade(color, 0.9),
            group="body",
        )
    else:
        n = max(4, int(w / 0.06))
        xs = np.linspace(-w / 2 + 0.025, w / 2 - 0.025, n)
        for x in xs:
            asm.add(
                "section",
                M.box_between(
                    (x - 0.022, -d / 2, lift + 0.02), (x + 0.022, d / 2, lift + h - 0.02)
                ),
                color,
                group="body",
            )
        for z in (lift, lift + h - 0.04):
            asm.add(
                "header",
                M.box_between((-w / 2, -0.02, z), (w / 2, 0.02, z + 0.04)),
                color,
                group="body",
            )
    for sx in (-1, 1):
        x = sx * (w / 2 - 0.1)
        asm.add(
            "bracket",
            M.box_between((x - 0.02, -d / 2, 0.0), (x + 0.02, -d / 2 + 0.03, lift + 0.001)),
            _shade(color, 0.8),
            group="body",
        )
    dims = {"radiator_height": h, "floor_clearance": lift}
    return asm.build("radiator", p.kind, dims, {})


# --------------------------------------------------------------------------------------
# Sanitary ware: WCs, washbasins, baths.
#
# EN 33 fixes the connecting dimensions of floor-standing and wall-hung WC pans; within
# them catalogue pans put the seat 38-43 cm above the floor (wall-hung ones, hung at the
# user's height, 40-43 cm) and have bowls 34-40 cm wide; a close-coupled suite reaches
# 60-70 cm from the wall with its cistern (34-42 cm wide, 15-20 cm deep, its lid 75-85 cm
# up), a wall-hung pan 48-58 cm from the wall or the boxing of its cistern. Washbasins
# (EN 31 pedestal and EN 32 wall-hung connecting dimensions, EN 14688 requirements):
# 50-65 cm wide, 40-50 cm deep, the rim 80-90 cm high (85 cm usual), the bowl 12-18 cm
# deep; vanity units 60-120 cm wide and 45-55 cm deep, backsplashes 10-30 cm high. Baths
# (EN 232 connecting dimensions, EN 198 acrylic baths): 160-180 x 70-80 cm, the rim
# 50-60 cm high, 38-45 cm deep inside with the inner bottom at least 10 cm above the
# floor for the waste.

WC_SEAT_HEIGHT = (0.38, 0.43)
WALL_WC_SEAT_HEIGHT = (0.40, 0.43)
WC_BOWL_WIDTH = (0.34, 0.40)
WC_PROJECTION = (0.60, 0.70)
WALL_WC_PROJECTION = (0.48, 0.58)
CISTERN_WIDTH = (0.34, 0.42)
CISTERN_DEPTH = (0.15, 0.20)
CISTERN_HEIGHT = (0.75, 0.85)
#: Top of the boxing of a wall-hung WC's cistern (or of its flush plate when concealed).
WALL_CISTERN_HEIGHT = (0.95, 1.20)
BASIN_WIDTH = (0.50, 0.65)
BASIN_DEPTH = (0.40, 0.50)
BASIN_RIM_HEIGHT = (0.80, 0.90)
BASIN_BOWL_DEPTH = (0.12, 0.18)
VANITY_WIDTH = (0.60, 1.20)
VANITY_DEPTH = (0.45, 0.55)
BACKSPLASH_HEIGHT = (0.10, 0.30)
BATH_LENGTH = (1.60, 1.80)
BATH_WIDTH = (0.70, 0.80)
BATH_RIM_HEIGHT = (0.50, 0.60)
BATH_INNER_DEPTH = (0.38, 0.45)
BATH_INNER_BOTTOM = 0.10

SANITARY = {"white": CERAMIC["white"], "ivory": (232, 226, 208), "manhattan": (206, 206, 202)}
TAP = {"chrome": METAL["chrome"], "black": METAL["black"], "brass": METAL["brass"]}


def _superellipse(phi: NDArray[np.float64] | float, n: float) -> NDArray[np.float64]:
    """Radius of the unit superellipse |x|^n + |y|^n = 1 towards angle phi (n = 2: a circle)."""
    c, s = np.abs(np.cos(phi)), np.abs(np.sin(phi))
    return np.asarray((c**n + s**n) ** (-1.0 / n))


def _oval(
    profile: ArrayLike,
    a: float,
    b: float,
    *,
    center: tuple[float, float] = (0.0, 0.0),
    squareness: float = 2.0,
    closed: bool = False,
    segments: int = 32,
) -> M.Mesh:
    """A solid of revolution (a ``lathe`` profile of (radius, z), radius 1 on the outline)
    stretched to an oval of semi-axes ``a`` (x) and ``b`` (y) about ``center``;
    ``squareness`` above 2 squares the outline off towards a rectangle with round
    corners (a superellipse). Bowls, basins, seat rings, lids."""
    m = M.lathe(profile, segments, closed=closed)
    v = m.vertices.copy()
    if squareness != 2.0:
        v[:, :2] *= _superellipse(np.arctan2(v[:, 1], v[:, 0]), squareness)[:, None]
    v[:, 0] = v[:, 0] * a + center[0]
    v[:, 1] = v[:, 1] * b + center[1]
    return M.Mesh(v, m.triangles)


def _slab_with_hole(
    rect: tuple[float, float, float, float],
    z0: float,
    z1: float,
    a: float,
    b: float,
    center: tuple[float, float],
    squareness: float = 2.0,
    segments: int = 32,
) -> list[M.Mesh]:
    """A slab over ``rect`` (x0, y0, x1, y1) from z0 to z1 with an oval hole (semi-axes a, b
    about ``center``, outlined as :func:`_oval`): one solid wedge from the hole to the edge
    per step round the hole (a worktop with its basin cut-out, a bath's rim)."""
    x0, y0, x1, y1 = rect
    cx, cy = center
    corners = np.array([[x1, y1], [x0, y1], [x0, y0], [x1, y0]]) - (cx, cy)
    # Wedges break at the outline points that face the slab's corners, so that the outer
    # edge of every wedge lies on one side of the slab.
    corner_phi = np.arctan2(corners[:, 1] / b, corners[:, 0] / a)
    even = np.linspace(-np.pi, np.pi, segments, endpoint=False)
    gap = np.abs(np.angle(np.exp(1j * (even[:, None] - corner_phi[None, :]))))
    phi = np.sort(np.concatenate([even[gap.min(axis=1) > 0.02], corner_phi]))

    def ends(t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r = float(_superellipse(t, squareness))
        inner = np.array([cx + a * r * np.cos(t), cy + b * r * np.sin(t)])
        d = (inner - (cx, cy)) / np.hypot(inner[0] - cx, inner[1] - cy)
        reach = [
            ((hi if d[k] > 0 else lo) - c) / d[k]
            for k, (lo, hi, c) in enumerate(((x0, x1, cx), (y0, y1, cy)))
            if abs(d[k]) > 1e-12
        ]
        return inner, np.array([cx, cy]) + min(reach) * d

    pieces = []
    for t0, t1 in zip(phi, np.roll(phi, -1)):
        e = (ends(t0), ends(t1))
        c8 = np.array(
            [[*e[(i >> 1) & 1][i & 1], z1 if i >> 2 else z0] for i in range(8)], dtype=np.float64
        )
        pieces.append(M.hexahedron(c8))
    return pieces


def _tap(x: float, y: float, z: float, height: float, reach: tuple[float, float]) -> list[M.Mesh]:
    """A pillar tap standing on (x, y, z): a column and a spout bending out by ``reach`` (xy)."""
    top = z + height - 0.02
    end = (x + reach[0], y + reach[1])
    spout = M.fillet_path([(x, y, top), (*end, top), (*end, top - 0.04)], 0.03)
    return [M.cylinder(0.022, height, 16, center=(x, y, z - 0.002)), M.tube(spout, 0.011, 10)]


def _toilet(p: _Params, wall_hung: bool) -> SceneObject:
    """A WC: a bowl whose inside is a deep depression, a seat ring, a lid, and a cistern.

    Floor-standing: a close-coupled suite, the pan on its foot and the cistern on its back.
    Wall-hung: the pan hangs on the wall in front of a boxed cistern that reaches the
    floor, or of a concealed one of which only the flush plate shows (then nothing
    touches the floor: ``extra["wall_mounted"]``, ``dimensions["floor_clearance"]``).
    The lid is up (leaning back), down on the seat, or missing.
    """
    seat_h = p.uniform("seat_height", *(WALL_WC_SEAT_HEIGHT if wall_hung else WC_SEAT_HEIGHT))
    bw = p.uniform("bowl_width", *WC_BOWL_WIDTH)
    proj = p.uniform("projection", *(WALL_WC_PROJECTION if wall_hung else WC_PROJECTION))
    cw = p.uniform("cistern_width", *CISTERN_WIDTH)
    cd = p.uniform("cistern_depth", *CISTERN_DEPTH)
    c_top = p.uniform("cistern_height", *(WALL_CISTERN_HEIGHT if wall_hung else CISTERN_HEIGHT))
    bowl_d = p.uniform("bowl_depth", *((0.16, 0.20) if wall_hung else (0.20, 0.26)))
    seat_t = p.uniform("seat_thickness", 0.02, 0.03)
    lid = p.choice("lid", ("up", "down", "none"), (4, 3, 1))
    cistern = p.choice("cistern", ("boxed", "concealed")) if wall_hung else "close-coupled"
    ceramic = p.color("color", SANITARY)
    seat_color = p.color(
        "seat_color", {"white": (240, 240, 236), "black": (32, 32, 34), "oak": WOOD["oak"]}
    )
    plate_color = p.color("plate_color", TAP, {"white": (236, 236, 232)})
    asm = _Assembly()
    rim = seat_h - seat_t - _GAP
    a = bw / 2
    # Bowl profile, radius 1 on the outline: up the outside to the rim, then down the
    # inside into the trap's water surface.
    inside = [(0.97, rim), (0.80, rim), (0.72, rim - 0.05), (0.42, rim - bowl_d + 0.02)]
    inside.append((0.0, rim - bowl_d))
    extra: dict[str, Any] = {}
    dims: dict[str, float] = {}
    if wall_hung:
        y_back = cd if cistern == "boxed" else 0.0
        b = proj / 2
        zb = rim - 0.24
        outside = [(0.0, zb), (0.55, zb), (0.85, zb + 0.08), (1.0, rim - 0.015)]
    else:
        # The bowl reaches 6 cm under the cistern, which stands on the pan's back.
        y_back = cd
        b = (proj - cd + 0.06) / 2
        zb = 0.0
        outside = [(0.0, 0.0), (0.62, 0.0), (0.60, 0.06), (0.66, 0.45 * rim), (0.92, rim - 0.06)]
        outside.append((1.0, rim - 0.015))
    yc = y_back + proj - b if wall_hung else proj - b
    asm.add("bowl", _oval(outside + inside, a, b, center=(0.0, yc)), ceramic, group="bowl")
    behind = yc - 0.84 * b  # the back of the pan, behind the depression
    if wall_hung:
        asm.add(
            "bowl",
            M.box_between((-0.5 * a, y_back, zb + 0.04), (0.5 * a, behind, rim - 0.01)),
            ceramic,
            group="bowl",
        )
        if cistern == "boxed":
            box_w = cw + 0.16
            asm.add(
                "cistern",
                M.box_between((-box_w / 2, 0.0, 0.0), (box_w / 2, cd, c_top)),
                _shade(ceramic, 0.97),
                group="cistern",
            )
            plate_y, plate_z = cd, c_top - 0.14
        else:
            plate_y, plate_z = 0.0, c_top - 0.08
            extra["wall_mounted"] = True
            dims["floor_clearance"] = zb
        asm.add(
            "flush_plate",
            M.box((0.25, 0.012, 0.16), (0.0, plate_y + 0.006, plate_z)),
            plate_color,
            group="cistern",
        )
    else:
        foot = M.tapered_box((0.5 * bw, behind - 0.03), (0.7 * bw, behind - 0.03), rim - 0.01)
        asm.add("pedestal", foot.translated((0.0, (0.03 + behind) / 2, 0.0)), ceramic, group="bowl")
        z_c = rim + _GAP
        asm.add(
            "cistern",
            M.rounded_box(
                (cw, cd, c_top - 0.02 - z_c), 0.02, center=(0.0, cd / 2, (z_c + c_top - 0.02) / 2)
            ),
            ceramic,
            group="cistern",
        )
        asm.add(
            "cistern",
            M.box_between((-cw / 2 - 0.005, 0.0, c_top - 0.02), (cw / 2 + 0.005, cd + 0.01, c_top)),
            ceramic,
            group="cistern",
        )
    # Seat ring and lid: ovals from the hinge (just in front of the cistern) to the front.
    y_hinge = y_back + (0.01 if not wall_hung else 0.015)
    front = yc + b
    bs = (front - y_hinge) / 2
    y_seat = y_hinge + bs
    as_ = 0.97 * a
    ring = [(0.58, rim + _GAP), (1.0, rim + _GAP), (1.0, seat_h), (0.58, seat_h)]
    asm.add(
        "seat", _oval(ring, as_, bs, center=(0.0, y_seat), closed=True), seat_color, group="seat"
    )
    lt = 0.018
    disc = [(0.0, 0.0), (1.0, 0.0), (1.0, lt), (0.0, lt)]
    if lid == "down":
        lid_mesh = _oval(disc, as_, bs, center=(0.0, y_seat)).translated((0, 0, seat_h + _GAP))
        asm.add("lid", lid_mesh, seat_color, group="seat")
    elif lid == "up":
        upright = _oval(disc, as_, bs).rotated("x", np.pi / 2)  # its back face now at y = 0
        lid_mesh = upright.translated((0.0, y_hinge + lt, seat_h + _GAP + bs))
        asm.add("lid", lid_mesh, seat_color, group="lid")
    dims.update(
        seat_height=seat_h,
        rim_height=rim,
        bowl_width=bw,
        bowl_depth=bowl_d,
        projection=proj,
        cistern_height=c_top,
    )
    extra.update(seat_part="seat", seat_center=[0.0, y_seat + 0.79 * bs], bowl_center=[0.0, yc])
    return asm.build("toilet", p.kind, dims, extra)


def _sink(p: _Params, style: str) -> SceneObject:
    """A washbasin with a tap: on a pedestal, set in the top of a vanity unit whose closed
    front reaches the floor, or hung on the wall with only its trap below (then nothing
    touches the floor: ``extra["wall_mounted"]``). Any of them may have a backsplash."""
    vanity = style == "vanity"
    rim = p.uniform("rim_height", *BASIN_RIM_HEIGHT)
    w = p.uniform("width", *(VANITY_WIDTH if vanity else BASIN_WIDTH))
    d = p.uniform("depth", *(VANITY_DEPTH if vanity else BASIN_DEPTH))
    bowl_d = p.uniform("bowl_depth", *BASIN_BOWL_DEPTH)
    squareness = p.uniform("squareness", 2.0, 3.5)
    backsplash = p.choice("backsplash", (True, False), (3, 1) if vanity else (1, 2))
    splash_h = p.uniform("backsplash_height", *BACKSPLASH_HEIGHT)
    tap_h = p.uniform("tap_height", 0.10, 0.18)
    top_t = p.uniform("top_thickness", 0.02, 0.04)
    fronts = p.choice("fronts", ("doors", "drawers"))
    ceramic = p.color("color", SANITARY)
    cabinet_color = p.color("cabinet_color", LAMINATE, WOOD)
    splash_color = p.color("backsplash_color", CERAMIC, LAMINATE)
    tap_color = p.color("tap_color", TAP)
    handle_color = p.color("handle_color", METAL)
    asm = _Assembly()
    body_h = bowl_d + 0.04
    # Basin profile, radius 1 on the outline: the underside, the rim, the bowl inside.
    basin = [(0.0, rim - body_h), (0.75, rim - body_h), (0.95, rim - 0.05), (1.0, rim - 0.01)]
    basin += [(0.98, rim), (0.84, rim), (0.78, rim - 0.02), (0.55, rim - bowl_d + 0.02)]
    basin.append((0.0, rim - bowl_d))
    extra: dict[str, Any] = {}
    dims = {"rim_height": rim, "bowl_depth": bowl_d}
    if not vanity:
        a, b = w / 2, d / 2
        yc = b
        asm.add(
            "basin",
            _oval(basin, a, b, center=(0.0, yc), squareness=squareness),
            ceramic,
            group="basin",
        )
        # A ledge at the back for the tap.
        ledge = 0.09
        asm.add(
            "basin",
            M.box_between((-0.32 * w, 0.0, rim - 0.05), (0.32 * w, ledge, rim)),
            ceramic,
            group="basin",
        )
        tap_at, tap_z = (0.0, ledge / 2 + 0.005), rim
        if style == "pedestal":
            asm.add(
                "pedestal",
                M.frustum(0.10, 0.08, rim - body_h + 0.01, 24, center=(0.0, 0.6 * b, 0.0)),
                ceramic,
                group="pedestal",
            )
        else:
            # A bottle trap under the waste, its pipe running back into the wall.
            z_t = rim - body_h - 0.18
            trap = [
                M.cylinder(0.016, rim - bowl_d - z_t, 12, center=(0.0, yc, z_t)),
                M.cylinder(0.032, 0.12, 16, center=(0.0, yc, z_t - 0.02)),
                M.cylinder_between((0.0, yc, z_t + 0.03), (0.0, 0.0, z_t + 0.03), 0.016, 12),
            ]
            for m in trap:
                asm.add("trap", m, tap_color, group="trap")
            extra["wall_mounted"] = True
            dims["floor_clearance"] = z_t - 0.02
        splash_z = rim
    else:
        # The basin sits in a cut-out of the top with its rim 1 cm proud of it.
        top = rim - 0.01
        a, b = min(0.25, w / 2 - 0.08), min(0.20, (d - 0.16) / 2)
        yc = d - 0.04 - b
        for piece in _slab_with_hole(
            (-w / 2, 0.0, w / 2, d), top - top_t, top, 0.9 * a, 0.9 * b, (0.0, yc), squareness
        ):
            asm.add("top", piece, splash_color, group="top")
        asm.add(
            "basin",
            _oval(basin, a, b, center=(0.0, yc), squareness=squareness),
            ceramic,
            group="basin",
        )
        # The carcass: sides, back and bottom boards, closed by fronts down to the floor.
        y_front = d - 0.03 - 0.018
        under = top - top_t
        carcass = [
            M.box_between((-w / 2, 0.0, 0.0), (-w / 2 + 0.018, y_front, under)),
            M.box_between((w / 2 - 0.018, 0.0, 0.0), (w / 2, y_front, under)),
            M.box_between((-w / 2 + 0.018, 0.0, 0.0), (w / 2 - 0.018, 0.012, under)),
            M.box_between((-w / 2 + 0.018, 0.012, 0.0), (w / 2 - 0.018, y_front, 0.02)),
        ]
        for m in carcass:
            asm.add("body", m, cabinet_color, group="body")
        drawers = fronts == "drawers"
        _fronts(
            asm,
            -w / 2,
            w / 2,
            0.0,
            under,
            y_front,
            (1 if w < 0.9 else 2) if drawers else max(1, round(w / 0.5)),
            2 if drawers else 1,
            "drawer" if drawers else "door",
            cabinet_color,
            handle_color,
            "body",
        )
        tap_at, tap_z = (0.0, yc - b - 0.045), top
        splash_z = top
        dims["top_height"] = top
    for m in _tap(*tap_at, tap_z, tap_h, (0.0, 0.10)):
        asm.add("tap", m, tap_color, group="basin")
    if backsplash:
        asm.add(
            "backsplash",
            M.box_between((-w / 2, 0.0, splash_z), (w / 2, 0.012, splash_z + splash_h)),
            splash_color,
            group="backsplash",
        )
    dims.update(
        basin_width=2 * a, basin_depth=2 * b, backsplash_height=splash_h if backsplash else 0.0
    )
    extra["basin_center"] = [0.0, yc]
    return asm.build("sink", p.kind, dims, extra)


def _bathtub(p: _Params) -> SceneObject:
    """A built-in bath: a hollow tub under a rim deck, a front panel to the floor, a tap."""
    length = p.uniform("length", *BATH_LENGTH)
    width = p.uniform("width", *BATH_WIDTH)
    rim = p.uniform("rim_height", *BATH_RIM_HEIGHT)
    inner_d = p.uniform("inner_depth", *BATH_INNER_DEPTH)
    rim_w = p.uniform("rim_width", 0.05, 0.10)
    squareness = p.uniform("squareness", 3.0, 5.0)
    tap_end = p.choice("tap_end", (-1, 1))
    tap_h = p.uniform("tap_height", 0.08, 0.12)
    ceramic = p.color("color", SANITARY)
    panel_color = p.color("panel_color", SANITARY, LAMINATE)
    tap_color = p.color("tap_color", TAP)
    inner_d = min(inner_d, rim - BATH_INNER_BOTTOM)
    zb = rim - inner_d
    a, b = length / 2 - rim_w, width / 2 - rim_w
    yc = width / 2
    deck = 0.03
    asm = _Assembly()
    for piece in _slab_with_hole(
        (-length / 2, 0.0, length / 2, width), rim - deck, rim, a, b, (0.0, yc), squareness, 48
    ):
        asm.add("rim", piece, ceramic, group="tub")
    # The tub, radius 1 at the rim's opening: under the deck, down the inside to the bottom.
    tub = [(0.0, zb - 0.03), (0.97, zb - 0.03), (1.04, zb + 0.05), (1.04, rim - 0.01)]
    tub += [(1.0, rim - 0.01), (0.96, zb + 0.06), (0.85, zb), (0.0, zb)]
    asm.add(
        "tub",
        _oval(tub, a, b, center=(0.0, yc), squareness=squareness, segments=48),
        ceramic,
        group="tub",
    )
    under = rim - deck
    asm.add(
        "panel",
        M.box_between((-length / 2, width - 0.02, 0.0), (length / 2, width, under)),
        panel_color,
        group="panel",
    )
    for m in (
        M.box_between((-length / 2, 0.0, 0.0), (length / 2, 0.02, under)),
        M.box_between((-length / 2, 0.02, 0.0), (-length / 2 + 0.02, width - 0.02, under)),
        M.box_between((length / 2 - 0.02, 0.02, 0.0), (length / 2, width - 0.02, under)),
    ):
        asm.add("side", m, panel_color, group="panel")
    x_tap = tap_end * (length / 2 - rim_w / 2)
    for m in _tap(x_tap, yc, rim, tap_h, (-tap_end * 0.08, 0.0)):
        asm.add("tap", m, tap_color, group="tap")
    dims = {"length": length, "rim_height": rim, "inner_depth": inner_d}
    return asm.build("bathtub", p.kind, dims, {"tub_center": [0.0, yc]})


# --------------------------------------------------------------------------------------
# Lamps and TV stands.
#
# Table lamps for a bedside table (catalogue ranges): 30-60 cm high, the base 10-18 cm
# across, the shade (a truncated cone) 20-40 cm across at its bottom. TV stands: low
# sideboards 120-200 cm long, 35-50 cm deep, their top 40-60 cm up (a screen's middle
# near the eye height of a seated viewer, about 1 m).

LAMP_HEIGHT = (0.30, 0.60)
LAMP_BASE_WIDTH = (0.10, 0.18)
LAMP_SHADE_DIAMETER = (0.20, 0.40)
TV_STAND_WIDTH = (1.2, 2.0)
TV_STAND_DEPTH = (0.35, 0.50)
TV_STAND_HEIGHT = (0.40, 0.60)


def _lamp_table(p: _Params) -> SceneObject:
    """A table lamp: a base, a stem, a bulb and a hollow conical shade open at both ends."""
    height = p.uniform("height", *LAMP_HEIGHT)
    bw = p.uniform("base_width", *LAMP_BASE_WIDTH)
    shade_d = p.uniform("shade_diameter", *LAMP_SHADE_DIAMETER)
    taper = p.uniform("shade_taper", 0.55, 0.9)
    shade_frac = p.uniform("shade_fraction", 0.35, 0.5)
    base_h = p.uniform("base_height", 0.02, 0.06)
    stem_r = p.uniform("stem_radius", 0.006, 0.015)
    base_shape = p.choice("base", ("round", "square"))
    shade_color = p.color(
        "shade_color",
        {
            "white": (236, 232, 220),
            "linen": (214, 200, 176),
            "grey": (150, 150, 150),
            "black": (34, 34, 34),
            "sage": (150, 166, 140),
        },
    )
    base_color = p.color("base_color", METAL, CERAMIC, WOOD)
    asm = _Assembly()
    if base_shape == "round":
        profile = [(0, 0), (bw / 2, 0), (bw / 2, 0.4 * base_h), (0.35 * bw, base_h), (0, base_h)]
        asm.add("base", M.lathe(profile, 28), base_color, group="lamp")
    else:
        asm.add(
            "base",
            M.rounded_box((bw, bw, base_h), 0.01, center=(0.0, 0.0, base_h / 2)),
            base_color,
            group="lamp",
        )
    sh = shade_frac * height
    z_shade = height - sh
    z_bulb = z_shade + 0.25 * sh
    asm.add(
        "stem",
        M.cylinder(stem_r, z_bulb - base_h + 0.002, 12, center=(0.0, 0.0, base_h - 0.002)),
        _shade(base_color, 0.9),
        group="lamp",
    )
    asm.add(
        "bulb",
        M.ellipsoid((0.025, 0.025, 0.03), center=(0.0, 0.0, z_bulb + 0.03)),
        (250, 246, 230),
        group="lamp",
    )
    r0, r1, wall = shade_d / 2, taper * shade_d / 2, 0.004
    shade = M.lathe(
        [(r0, z_shade), (r1, height), (r1 - wall, height), (r0 - wall, z_shade)], 32, True
    )
    asm.add("shade", shade, shade_color, group="lamp")
    dims = {"height": height, "shade_diameter": shade_d, "base_width": bw}
    return asm.build("lamp", p.kind, dims, {})


def _tv_stand(p: _Params) -> SceneObject:
    """A low, long cabinet with a closed front for a television (put one on it with
    :func:`place_on`)."""
    w = p.uniform("width", *TV_STAND_WIDTH)
    d = p.uniform("depth", *TV_STAND_DEPTH)
    h = p.uniform("top_height", *TV_STAND_HEIGHT)
    base = p.choice("base", ("plinth", "legs"))
    leg_h = p.uniform("leg_height", 0.06, 0.15)
    fronts = p.choice("fronts", ("doors", "drawers"))
    color = p.color("color", LAMINATE, WOOD)
    handle_color = p.color("handle_color", METAL)
    asm = _Assembly()
    top_t = 0.025
    z0 = 0.05 if base == "plinth" else leg_h
    _plinth_or_legs(asm, base == "plinth", w, d, z0, color, plinth_inset=0.03, leg_inset=0.05)
    y_front = d / 2 - 0.018 - 0.025  # the handles stay within the top's depth
    asm.add(
        "body",
        M.box_between((-w / 2, -d / 2, z0), (w / 2, y_front, h - top_t)),
        color,
        group="body",
    )
    asm.add(
        "top", M.box_between((-w / 2, -d / 2, h - top_t), (w / 2, d / 2, h)), color, group="body"
    )
    cols = max(2, round(w / 0.6))
    part = "door" if fronts == "doors" else "drawer"
    _fronts(asm, -w / 2, w / 2, z0, h - top_t, y_front, cols, 1, part, color, handle_color, "body")
    extra = {"support_rect": [-w / 2, -d / 2, w / 2, d / 2], "support_z": h, "support_round": False}
    return asm.build("tv_stand", p.kind, {"top_height": h}, extra)


# --------------------------------------------------------------------------------------
# The registry.

_Builder = Callable[[_Params], SceneObject]

_BUILDERS: dict[str, tuple[str, _Builder]] = {
    "chair-4leg": ("chair", _chair_4leg),
    "chair-4leg-arms": ("chair", _chair_4leg_arms),
    "chair-sled": ("chair", _chair_sled),
    "chair-office": ("chair", _chair_office),
    "chair-shell": ("chair", _chair_shell),
    "chair-armchair": ("chair", lambda p: _sofa_straight(p, 1, True, "chair")),
    "stool-round": ("stool", lambda p: _stool(p, "round")),
    "stool-square": ("stool", lambda p: _stool(p, "square")),
    "stool-bar": ("stool", lambda p: _stool(p, "bar")),
    "bench": ("bench", _bench),
    "ottoman-box": ("ottoman", lambda p: _ottoman(p, "box")),
    "ottoman-round": ("ottoman", lambda p: _ottoman(p, "round")),
    "sofa-2seat": ("sofa", lambda p: _sofa_straight(p, 2, True)),
    "sofa-3seat": ("sofa", lambda p: _sofa_straight(p, 3, True)),
    "sofa-armless": ("sofa", lambda p: _sofa_straight(p, p.choice("seats", (2, 3)), False)),
    "sofa-l-shaped": ("sofa", _sofa_l),
    "table-dining": ("table", _table_dining),
    "table-small": ("table", _table_small),
    "table-round": ("table", _table_round),
    "table-coffee": ("table", _table_coffee),
    "table-conference": ("table", _table_conference),
    "table-bar": ("table", _table_bar),
    "desk-pedestal": ("desk", lambda p: _desk(p, "pedestal")),
    "desk-panel": ("desk", lambda p: _desk(p, "panel")),
    "cabinet": ("cabinet", _cabinet),
    "nightstand": ("cabinet", _nightstand),
    "kitchen-counter": ("cabinet", _kitchen_counter),
    "closet": ("closet", _closet),
    "bookshelf": ("bookshelf", _bookshelf),
    "bed": ("bed", _bed),
    "box": ("box", _box),
    "books": ("books", _books),
    "monitor": ("television", _monitor),
    "television": ("television", lambda p: _monitor(p, True)),
    "keyboard": ("keyboard", _keyboard),
    "mouse": ("otherprop", _mouse),
    "plant": ("plant", _plant),
    "plant-small": ("plant", lambda p: _plant(p, True)),
    "bin": ("bin", _bin),
    "radiator": ("radiator", _radiator),
    "chair-shell-curved": ("chair", lambda p: _chair_shell(p, curved=True)),
    "chair-club": ("chair", lambda p: _easy_chair(p, False)),
    "chair-wingback": ("chair", lambda p: _easy_chair(p, True)),
    "chair-lounge": ("chair", _chair_lounge),
    "toilet": ("toilet", lambda p: _toilet(p, False)),
    "toilet-wall-hung": ("toilet", lambda p: _toilet(p, True)),
    "sink-pedestal": ("sink", lambda p: _sink(p, "pedestal")),
    "sink-vanity": ("sink", lambda p: _sink(p, "vanity")),
    "sink-wall-hung": ("sink", lambda p: _sink(p, "wall-hung")),
    "bathtub": ("bathtub", _bathtub),
    "lamp-table": ("lamp", _lamp_table),
    "tv-stand": ("tv_stand", _tv_stand),
}

#: Kind -> class name (a key of :data:`~ontodetect.synth.scene.CLASS_IDS`).
FURNITURE_CLASSES: dict[str, str] = {k: c for k, (c, _) in _BUILDERS.items()}


def _registered(kind: str) -> Callable[..., SceneObject]:
    def build(rng: Seed = None, **overrides: Any) -> SceneObject:
        return make_furniture(kind, rng, **overrides)

    build.__name__ = "build_" + kind.replace("-", "_")
    build.__doc__ = f"Build a {kind!r} ({FURNITURE_CLASSES[kind]}); see :func:`make_furniture`."
    return build


#: Kind -> builder ``builder(rng, **overrides) -> SceneObject``.
FURNITURE: dict[str, Callable[..., SceneObject]] = {k: _registered(k) for k in _BUILDERS}


def kinds_of(class_name: str) -> tuple[str, ...]:
    """The kinds whose objects have this class, e.g. ``kinds_of("sofa")``."""
    return tuple(k for k, c in FURNITURE_CLASSES.items() if c == class_name)


def make_furniture(kind: str, rng: Seed = None, **overrides: Any) -> SceneObject:
    """Build one piece of furniture of ``kind`` in its object frame.

    Parameters
    ----------
    kind : str
        A key of :data:`FURNITURE`, e.g. ``"chair-office"``, ``"sofa-3seat"``,
        ``"table-round"``, ``"bookshelf"``.
    rng : int or numpy.random.Generator, optional
        Seed or generator for every random choice (dimensions, style, colours).
    **overrides
        Fixed values for drawn parameters, e.g. ``seat_height=0.45``,
        ``arms=False``, ``fabric_color="navy"``; an unknown name raises
        :class:`~ontodetect.errors.InvalidParameterError` listing the known ones.

    Returns
    -------
    SceneObject
        With ``instance_id`` 0 and the identity pose: origin at the centre of
        the footprint on the floor, x right, y front, z up.

    Examples
    --------
    >>> chair = make_furniture("chair-4leg", 7, seat_height=0.45)
    >>> chair.class_name, round(chair.dimensions["seat_height"], 2)
    ('chair', 0.45)
    >>> {"seat", "leg", "backrest"} <= set(chair.part_names)
    True
    >>> bool(abs(chair.vertices[:, 2].min()) < 1e-9)
    True
    """
    if kind not in _BUILDERS:
        raise InvalidParameterError("kind", f"one of {', '.join(sorted(_BUILDERS))}", kind)
    params = _Params(kind, np.random.default_rng(rng), overrides)
    obj = _BUILDERS[kind][1](params)
    params.check_all_used()
    return obj
