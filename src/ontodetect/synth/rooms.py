"""Furnished rooms: walls with doors and windows, and furniture placed the way people do.

:func:`build_room` makes a :class:`~ontodetect.synth.scene.Scene` of one room
type. The room spans ``[0, L] x [0, W] x [0, H]``; the floor slab lies below
z = 0, the ceiling slab above H and the walls outside the room, so that every
object stands inside the box. Walls have holes where the doors and windows are;
door leaves (open or closed) and windows (frame, glass, sill) are objects of
class ``"door"`` and ``"window"``.

Furniture is placed by rules (desks and bookshelves against walls, chairs round
tables and partly tucked under them, sofas facing a coffee table, clutter on
tables, plants in corners, radiators under windows) and every placement is
checked: no two objects' collision boxes overlap (see
:func:`~ontodetect.synth.furniture.part_boxes`; a chair's seat may go under a
table top, its backrest may not), nothing stands in a door's swing or in front
of a window higher than its sill, and everything stays inside the room. A
placement that fails is retried with other random draws; the same seed always
gives the same scene.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .._progress import progress
from ..errors import InvalidParameterError
from ..geometry import _mesh as M
from .furniture import make_furniture, part_boxes, place, place_on
from .scene import OrientedBox, Scene, SceneObject, yaw_pose

if TYPE_CHECKING:
    from ..cloud import PointCloud

__all__ = ["ROOM_TYPES", "RoomShell", "build_room", "build_shell", "object_scene"]

#: The room types :func:`build_room` knows.
ROOM_TYPES: tuple[str, ...] = (
    "office",
    "conference",
    "living_room",
    "home_office",
    "dining_room",
    "bedroom",
    "kitchen",
    "corridor",
    "tiny",
    "bathroom",
    "hotel_room",
)

# Floor plans (length x width, metres) typical of each room type (Neufert; workplace
# rules such as the German ASR A1.2 ask 8 m2 for the first office workstation).
_ROOM_SIZES: dict[str, tuple[tuple[float, float], tuple[float, float]]] = {
    "office": ((5.0, 8.0), (3.8, 6.0)),
    "conference": ((5.5, 9.0), (4.0, 6.0)),
    "living_room": ((4.5, 7.0), (3.6, 5.5)),
    "home_office": ((3.2, 4.5), (2.8, 3.8)),
    "dining_room": ((4.0, 5.5), (3.4, 4.5)),
    "bedroom": ((3.6, 5.0), (3.2, 4.5)),
    "kitchen": ((3.6, 5.0), (3.0, 4.0)),
    "corridor": ((6.0, 12.0), (1.8, 2.6)),
    "tiny": ((2.5, 2.5), (2.5, 2.5)),
    "bathroom": ((2.2, 3.4), (1.9, 2.8)),
    "hotel_room": ((3.8, 5.5), (3.2, 4.2)),
}
#: Clear ceiling height (at least 2.4 m in dwellings, 2.5 m in small offices).
CEILING_HEIGHT = (2.5, 3.0)
WALL_THICKNESS = (0.10, 0.25)
SLAB_THICKNESS = 0.15
#: Door openings (DIN 18101: 885-1010 mm wide, 2.0-2.135 m high structural openings).
DOOR_WIDTH = (0.85, 1.0)
DOOR_HEIGHT = (2.0, 2.13)
#: Windows: sill 80-100 cm above the floor (fall protection below 80 cm needs a rail).
WINDOW_SILL = (0.80, 1.00)
WINDOW_HEIGHT = (1.2, 1.5)
WINDOW_WIDTH = (0.8, 2.0)
#: Boxes overlapping by less than this (metres) are touching, not interpenetrating.
CONTACT_TOLERANCE = 1e-3
#: How far in front of a window tall furniture must keep clear (radiators fit below the sill).
WINDOW_CLEARANCE = 0.3
#: Free space kept under the ceiling (lamps, sprinklers); nothing stands taller.
CEILING_CLEARANCE = 0.05
#: Slack (metres) for "inside the room": rounding only.
_INSIDE_SLACK = 1e-9
#: Glazed walls: panes between mullions, glass from just above the floor to near the ceiling.
GLAZED_PANE_WIDTH = (1.2, 1.6)
GLAZED_MULLION = 0.08
GLAZED_BOTTOM = 0.05
GLAZED_TOP_GAP = 0.10
#: Attempts at one placement before giving up on that object.
_TRIES = 40
#: Attempts at furnishing a room before accepting fewer objects than asked.
_FURNISH_ATTEMPTS = 8

# Yaw of an object standing with its back to wall k (its front facing into the room).
_WALL_YAW = (0.0, np.pi / 2, np.pi, -np.pi / 2)

_STRUCTURE_COLORS = {
    "floor": [
        (150, 112, 76),
        (186, 150, 110),
        (120, 120, 124),
        (160, 150, 140),
        (98, 80, 66),
        (200, 196, 188),
    ],
    "wall": [(232, 230, 224), (240, 238, 232), (214, 212, 206), (226, 218, 200), (200, 212, 214)],
    "ceiling": [(244, 244, 242), (236, 236, 234)],
}

# Minimum content per room type: furnishing is retried until the room has it.
_MIN_COUNTS: dict[str, dict[str, int]] = {
    "office": {"desk": 2, "chair": 2},
    "conference": {"table": 1, "chair": 6},
    "living_room": {"sofa": 1, "table": 1},
    "home_office": {"desk": 1, "chair": 1},
    "dining_room": {"table": 1, "chair": 4},
    "bedroom": {"bed": 1, "closet": 1},
    "kitchen": {"table": 1, "chair": 2, "cabinet": 1, "stool": 1},
    "corridor": {"bench": 1},
    "tiny": {"table": 1, "chair": 1, "stool": 1},
    "bathroom": {"toilet": 1, "sink": 1},
    "hotel_room": {"bed": 1, "lamp": 1, "tv_stand": 1},
}


@dataclass(frozen=True)
class _Opening:
    wall: int
    kind: str  # "door" or "window"
    u0: float
    u1: float
    z0: float
    z1: float


# --------------------------------------------------------------------------------------
# Geometry of collision boxes.


def _box_rows(boxes: Sequence[OrientedBox]) -> NDArray[np.float64]:
    """(k, 7) rows cx, cy, half x, half y, yaw, z0, z1."""
    if not boxes:
        return np.zeros((0, 7))
    return np.array(
        [
            [
                b.center[0],
                b.center[1],
                b.size[0] / 2,
                b.size[1] / 2,
                b.yaw,
                b.center[2] - b.size[2] / 2,
                b.center[2] + b.size[2] / 2,
            ]
            for b in boxes
        ]
    )


def _overlapping(
    a: NDArray[np.float64], b: NDArray[np.float64], tol: float = CONTACT_TOLERANCE
) -> NDArray[np.bool_]:
    """(k, m) bool: which upright boxes of ``a`` (k, 7) overlap which of ``b`` (m, 7).

    Separating-axis test on the footprints (two rectangles are apart if their
    projections on one of their four edge directions are), plus the heights.
    """
    A, B = a[:, None, :], b[None, :, :]
    ua = np.stack([np.cos(A[..., 4]), np.sin(A[..., 4])], -1)
    va = np.stack([-np.sin(A[..., 4]), np.cos(A[..., 4])], -1)
    ub = np.stack([np.cos(B[..., 4]), np.sin(B[..., 4])], -1)
    vb = np.stack([-np.sin(B[..., 4]), np.cos(B[..., 4])], -1)
    d = B[..., :2] - A[..., :2]
    apart = np.zeros(np.broadcast_shapes(A.shape[:2], B.shape[:2]), bool)
    for axis in (ua, va, ub, vb):
        ra = A[..., 2] * np.abs(np.sum(ua * axis, -1)) + A[..., 3] * np.abs(np.sum(va * axis, -1))
        rb = B[..., 2] * np.abs(np.sum(ub * axis, -1)) + B[..., 3] * np.abs(np.sum(vb * axis, -1))
        apart |= np.abs(np.sum(d * axis, -1)) >= ra + rb - tol
    z_overlap = np.minimum(A[..., 6], B[..., 6]) - np.maximum(A[..., 5], B[..., 5]) > tol
    return ~apart & z_overlap


# --------------------------------------------------------------------------------------
# The room being furnished.


class _Layout:
    """A room under construction: its size, openings, keep-out zones and placed furniture."""

    def __init__(
        self,
        rng: np.random.Generator,
        room_type: str,
        size: tuple[float, float, float],
        clutter: float,
    ) -> None:
        self.rng = rng
        self.room_type = room_type
        self.L, self.W, self.H = size
        self.clutter = clutter
        self.openings: list[_Opening] = []
        self.keepouts = np.zeros((0, 7))
        self.objects: list[SceneObject] = []
        self._rows: list[NDArray[np.float64]] = []
        self.wall_of: dict[int, tuple[int, float, float]] = {}  # id(obj) -> (wall, u0, u1)

    # Walls: wall k has its origin at an inner corner, u along it and d into the room.
    def wall_length(self, k: int) -> float:
        return self.L if k % 2 == 0 else self.W

    def wall_point(self, k: int, u: float, d: float) -> tuple[float, float]:
        origin = [(0.0, 0.0), (self.L, 0.0), (self.L, self.W), (0.0, self.W)][k]
        e = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][k]
        n = [(0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 0.0)][k]
        return (origin[0] + u * e[0] + d * n[0], origin[1] + u * e[1] + d * n[1])

    def add_keepout(self, k: int, u0: float, u1: float, depth: float, z0: float, z1: float) -> None:
        cx, cy = self.wall_point(k, (u0 + u1) / 2, depth / 2)
        row = [cx, cy, (u1 - u0) / 2, depth / 2, _WALL_YAW[k], z0, z1]
        self.keepouts = np.vstack([self.keepouts, row])

    def count(self, class_name: str) -> int:
        return sum(o.class_name == class_name for o in self.objects)

    def fits(self, obj: SceneObject) -> bool:
        v = obj.vertices
        lo, hi = v.min(axis=0), v.max(axis=0)
        eps = _INSIDE_SLACK
        if (
            np.any(lo < -eps)
            or hi[0] > self.L + eps
            or hi[1] > self.W + eps
            or hi[2] > self.H - CEILING_CLEARANCE
        ):
            return False
        rows = _box_rows(part_boxes(obj))
        others = np.vstack([self.keepouts, *self._rows]) if self._rows else self.keepouts
        return len(others) == 0 or not _overlapping(rows, others).any()

    def add(self, obj: SceneObject) -> SceneObject:
        self.objects.append(obj)
        self._rows.append(_box_rows(part_boxes(obj)))
        return obj

    def try_add(self, obj: SceneObject) -> SceneObject | None:
        return self.add(obj) if self.fits(obj) else None

    def checkpoint(self) -> int:
        return len(self.objects)

    def rollback(self, mark: int) -> None:
        for obj in self.objects[mark:]:
            self.wall_of.pop(id(obj), None)
        del self.objects[mark:]
        del self._rows[mark:]

    def n(self, mean: float) -> int:
        """A random count of optional items, scaled by the clutter level."""
        return int(self.rng.poisson(mean * self.clutter))

    def uniform(self, low: float, high: float) -> float:
        return float(self.rng.uniform(low, high))

    def chance(self, p: float) -> bool:
        return bool(self.rng.random() < p)

    def pick(self, options: Sequence[Any]) -> Any:
        return options[int(self.rng.integers(len(options)))]

    def furniture(self, kind: str, **overrides: Any) -> SceneObject:
        return make_furniture(kind, self.rng, **overrides)


# --------------------------------------------------------------------------------------
# Placement rules.


def _against_wall(
    lay: _Layout,
    obj: SceneObject,
    *,
    walls: Sequence[int] | None = None,
    u: float | None = None,
    corner: str | None = None,
    gap: tuple[float, float] = (0.0, 0.02),
    tries: int = _TRIES,
) -> SceneObject | None:
    """Stand ``obj`` with its back to a wall, facing into the room."""
    w, d = obj.dimensions["width"], obj.dimensions["depth"]
    walls = list(walls) if walls is not None else [0, 1, 2, 3]
    for _ in range(tries):
        k = lay.pick(walls)
        length = lay.wall_length(k)
        if w > length:
            continue
        if u is not None:
            uc = u
        elif corner == "left" or (corner == "any" and lay.chance(0.5)):
            uc = w / 2 + lay.uniform(0.0, 0.02)
        elif corner in ("right", "any"):
            uc = length - w / 2 - lay.uniform(0.0, 0.02)
        else:
            uc = lay.uniform(w / 2, length - w / 2)
        x, y = lay.wall_point(k, uc, d / 2 + lay.uniform(*gap))
        placed = place(obj, x, y, _WALL_YAW[k])
        if lay.try_add(placed):
            lay.wall_of[id(placed)] = (k, uc - w / 2, uc + w / 2)
            return placed
    return None


def _beside(
    lay: _Layout, anchor: SceneObject, obj: SceneObject, gap: float = 0.0
) -> SceneObject | None:
    """Put ``obj`` against the same wall as ``anchor``, touching its left or right side."""
    if id(anchor) not in lay.wall_of:
        return None
    k, u0, u1 = lay.wall_of[id(anchor)]
    w = obj.dimensions["width"]
    sides = [u1 + gap + w / 2, u0 - gap - w / 2]
    if lay.chance(0.5):
        sides.reverse()
    for uc in sides:
        placed = _against_wall(lay, obj, walls=[k], u=uc, tries=1, gap=(0.0, 0.005))
        if placed is not None:
            return placed
    return None


def _free(
    lay: _Layout,
    obj: SceneObject,
    *,
    yaw: tuple[float, float] = (-np.pi, np.pi),
    region: tuple[float, float, float, float] | None = None,
    tries: int = _TRIES,
) -> SceneObject | None:
    """Stand ``obj`` anywhere in ``region`` (x0, y0, x1, y1; default the room) at a random yaw."""
    x0, y0, x1, y1 = region or (0.0, 0.0, lay.L, lay.W)
    r = 0.5 * math.hypot(obj.dimensions["width"], obj.dimensions["depth"])
    for _ in range(tries):
        x = lay.uniform(min(x0 + r, (x0 + x1) / 2), max(x1 - r, (x0 + x1) / 2))
        y = lay.uniform(min(y0 + r, (y0 + y1) / 2), max(y1 - r, (y0 + y1) / 2))
        placed = lay.try_add(place(obj, x, y, lay.uniform(*yaw)))
        if placed is not None:
            return placed
    return None


def _in_corner(lay: _Layout, obj: SceneObject, tries: int = 12) -> SceneObject | None:
    """Stand ``obj`` in a corner of the room (plants, bins), near both walls."""
    r = 0.5 * max(obj.dimensions["width"], obj.dimensions["depth"])
    for _ in range(tries):
        cx, cy = lay.pick([(0, 0), (1, 0), (1, 1), (0, 1)])
        off = r + lay.uniform(0.02, 0.12)
        x = off if cx == 0 else lay.L - off
        y = off if cy == 0 else lay.W - off
        placed = lay.try_add(place(obj, x, y, lay.uniform(-np.pi, np.pi)))
        if placed is not None:
            return placed
    return None


def _on_top(
    lay: _Layout,
    support: SceneObject,
    obj: SceneObject,
    *,
    spot: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0),
    yaw: tuple[float, float] = (-np.pi, np.pi),
    tries: int = 15,
) -> SceneObject | None:
    """Put ``obj`` on ``support``'s top, inside the ``spot`` fraction of its top rectangle."""
    if "support_rect" not in support.extra:
        return None
    sx0, sy0, sx1, sy1 = support.extra["support_rect"]
    round_top = support.extra.get("support_round", False)
    z = float(support.extra["support_z"] + support.pose[2, 3])
    w, d = obj.dimensions["width"], obj.dimensions["depth"]
    margin = 0.02
    for _ in range(tries):
        fx, fy = lay.uniform(spot[0], spot[2]), lay.uniform(spot[1], spot[3])
        lx, ly = sx0 + fx * (sx1 - sx0), sy0 + fy * (sy1 - sy0)
        rel = lay.uniform(*yaw)
        c, s = math.cos(rel), math.sin(rel)
        corners = np.array(
            [
                [lx + c * a - s * b, ly + s * a + c * b]
                for a in (-w / 2, w / 2)
                for b in (-d / 2, d / 2)
            ]
        )
        if round_top:
            centre = np.array([(sx0 + sx1) / 2, (sy0 + sy1) / 2])
            if np.any(np.linalg.norm(corners - centre, axis=1) > (sx1 - sx0) / 2 - margin):
                continue
        elif np.any(corners < [sx0 + margin, sy0 + margin]) or np.any(
            corners > [sx1 - margin, sy1 - margin]
        ):
            continue
        wx, wy = (support.pose @ np.array([lx, ly, 0.0, 1.0]))[:2]
        placed = lay.try_add(place(obj, wx, wy, support.yaw + rel, z))
        if placed is not None:
            return placed
    return None


def _seat_front(chair: SceneObject) -> float:
    """How far in front of its origin a chair's seat (or seat cushion) reaches, object frame."""
    part = chair.part_names.index(chair.extra.get("seat_part", "seat"))
    local = (chair.vertices - chair.pose[:3, 3]) @ chair.pose[:3, :3]
    return float(local[chair.triangles[chair.triangle_part == part].ravel(), 1].max())


def _seat_at(
    lay: _Layout,
    table: SceneObject,
    chair: SceneObject,
    edge: tuple[float, float],
    normal: tuple[float, float],
    *,
    loose: float = 0.3,
) -> SceneObject | None:
    """Set ``chair`` at ``table``'s edge point (table frame), facing the table.

    Most chairs are tucked in (the front of the seat 5-18 cm under the top);
    a ``loose`` share is pulled out and turned by up to 30 degrees. When the
    wished position collides, the chair is tried further out.
    """
    nw = table.pose[:2, :2] @ np.asarray(normal, float)
    ew = (table.pose @ np.array([edge[0], edge[1], 0.0, 1.0]))[:2]
    yaw = math.atan2(nw[0], -nw[1])
    tangent = np.array([-nw[1], nw[0]])
    front = _seat_front(chair)
    if lay.chance(loose):
        tuck, turn, slide = (
            lay.uniform(-0.35, -0.05),
            lay.uniform(-0.52, 0.52),
            lay.uniform(-0.1, 0.1),
        )
    else:
        tuck, turn, slide = (
            lay.uniform(0.05, 0.18),
            lay.uniform(-0.09, 0.09),
            lay.uniform(-0.03, 0.03),
        )
    # Deeper first; at each depth the chair may also shift sideways to clear a table leg.
    for t in [tuck, *np.arange(min(tuck, 0.15) - 0.05, -0.4, -0.05)]:
        for shift in (0.0, 0.15, -0.15, 0.3, -0.3):
            pos = ew + nw * (front - t) + tangent * (slide + shift)
            placed = lay.try_add(place(chair, pos[0], pos[1], yaw + turn))
            if placed is not None:
                return placed
    return None


def _table_slots(
    table: SceneObject, n: int, chair_width: float, *, ends: bool = True
) -> list[tuple[tuple[float, float], tuple[float, float]]]:
    """Up to n (edge point, outward normal) pairs round a table, in its frame."""
    x0, y0, x1, y1 = table.extra["support_rect"]
    if table.extra.get("support_round"):
        r = (x1 - x0) / 2
        fit = max(1, int(2 * np.pi * (r + 0.25) // (chair_width + 0.12)))
        a = np.arange(min(n, fit)) * 2 * np.pi / min(n, fit) + np.pi / 2
        return [
            ((float(r * np.cos(t)), float(r * np.sin(t))), (float(np.cos(t)), float(np.sin(t))))
            for t in a
        ]
    long_x = (x1 - x0) >= (y1 - y0)
    length, width = ((x1 - x0), (y1 - y0)) if long_x else ((y1 - y0), (x1 - x0))
    per_side = max(1, int((length - 0.1) // (chair_width + 0.12)))
    n_long = min(n, 2 * per_side)
    n_ends = min(n - n_long, 2) if ends and width >= chair_width + 0.1 else 0
    slots = []
    for side, count in ((1, (n_long + 1) // 2), (-1, n_long // 2)):
        for i in range(count):
            s = -length / 2 + (i + 0.5) * length / count
            if long_x:
                slots.append(((s, side * (y1 - y0) / 2), (0.0, float(side))))
            else:
                slots.append(((side * (x1 - x0) / 2, s), (float(side), 0.0)))
    for side in (1, -1)[:n_ends]:
        if long_x:
            slots.append(((side * (x1 - x0) / 2, 0.0), (float(side), 0.0)))
        else:
            slots.append(((0.0, side * (y1 - y0) / 2), (0.0, float(side))))
    return slots


def _table_with_chairs(
    lay: _Layout,
    table: SceneObject,
    chair: SceneObject,
    n_chairs: int,
    min_chairs: int,
    *,
    region_margin: float = 0.9,
    loose: float = 0.3,
    tries: int = 12,
) -> SceneObject | None:
    """Place a table near the room's middle and set chairs round it (rolled back if too few)."""
    long_room_x = lay.L >= lay.W
    w, d = table.dimensions["width"], table.dimensions["depth"]
    for attempt in range(tries):
        mark = lay.checkpoint()
        yaw = (0.0 if long_room_x else np.pi / 2) + lay.uniform(-0.05, 0.05)
        if lay.chance(0.2):
            yaw += np.pi / 2
        half = 0.5 * max(w, d)
        # Near the middle first; if that keeps failing (a door's swing, a sofa), anywhere.
        wide = attempt >= tries // 2
        margin = 0.1 if wide else region_margin
        jx = max(0.0, lay.L / 2 - half - margin)
        jy = max(0.0, lay.W / 2 - half - margin)
        if not wide:
            jx, jy = min(jx, 0.6), min(jy, 0.6)
        x = lay.L / 2 + lay.uniform(-jx, jx)
        y = lay.W / 2 + lay.uniform(-jy, jy)
        placed = lay.try_add(place(table, x, y, yaw))
        if placed is None:
            continue
        seated = 0
        for edge, normal in _table_slots(placed, n_chairs, chair.dimensions["width"]):
            if _seat_at(lay, placed, chair, edge, normal, loose=loose) is not None:
                seated += 1
        if seated >= min_chairs:
            return placed
        lay.rollback(mark)
    return None


def _desk_with_chair(
    lay: _Layout,
    desk: SceneObject,
    chair: SceneObject | None,
    *,
    walls: Sequence[int] | None = None,
    equipment: bool = True,
    placed_desk: SceneObject | None = None,
) -> SceneObject | None:
    """A desk against a wall (or already placed), a chair at its knee space, things on top."""
    mark = lay.checkpoint()
    placed = placed_desk or _against_wall(lay, desk, walls=walls, gap=(0.0, 0.03))
    if placed is None:
        return None
    if chair is not None:
        kx = placed.extra.get("knee_center", [0.0, 0.0])[0]
        y1 = placed.extra["support_rect"][3]
        if _seat_at(lay, placed, chair, (kx, y1), (0.0, 1.0), loose=0.5) is None:
            lay.rollback(mark)
            return None
    if equipment:
        _equip_desk(lay, placed)
    return placed


def _equip_desk(lay: _Layout, desk: SceneObject) -> None:
    """Monitor(s) at the back, keyboard and mouse in front of them, maybe clutter."""
    x0, _, x1, _ = desk.extra["support_rect"]
    kx = desk.extra.get("knee_center", [0.0, 0.0])[0]
    fx = (kx - x0) / (x1 - x0)
    if lay.chance(0.85):
        n_mon = 2 if lay.chance(0.25) else 1
        for k in range(n_mon):
            off = 0.0 if n_mon == 1 else (-0.17 if k == 0 else 0.17)
            _on_top(
                lay,
                desk,
                lay.furniture("monitor"),
                spot=(fx + off - 0.05, 0.12, fx + off + 0.05, 0.3),
                yaw=(-0.2, 0.2),
            )
        _on_top(
            lay,
            desk,
            lay.furniture("keyboard"),
            spot=(fx - 0.05, 0.55, fx + 0.05, 0.75),
            yaw=(-0.15, 0.15),
        )
        _on_top(
            lay,
            desk,
            lay.furniture("mouse"),
            spot=(fx + 0.18, 0.55, fx + 0.28, 0.8),
            yaw=(-0.3, 0.3),
        )
    for _ in range(lay.n(0.6)):
        kind = lay.pick(["books", "box", "plant-small", "books"])
        obj = lay.furniture(
            kind,
            **(
                {
                    "width": lay.uniform(0.2, 0.35),
                    "depth": lay.uniform(0.2, 0.3),
                    "height": lay.uniform(0.1, 0.25),
                }
                if kind == "box"
                else {}
            ),
        )
        _on_top(lay, desk, obj)


def _table_clutter(lay: _Layout, table: SceneObject, mean: float) -> None:
    for _ in range(lay.n(mean)):
        kind = lay.pick(["books", "plant-small", "box", "books"])
        overrides = (
            {
                "width": lay.uniform(0.2, 0.4),
                "depth": lay.uniform(0.15, 0.3),
                "height": lay.uniform(0.08, 0.25),
            }
            if kind == "box"
            else {}
        )
        _on_top(lay, table, lay.furniture(kind, **overrides))


def _radiators(lay: _Layout, p: float = 0.75) -> None:
    """A radiator under most windows, centred, no wider than the window."""
    for op in [o for o in lay.openings if o.kind == "window"]:
        if not lay.chance(p):
            continue
        width = min(op.u1 - op.u0 - 0.1, lay.uniform(0.6, 1.6))
        top = op.z0 - 0.06
        obj = lay.furniture(
            "radiator",
            width=max(0.5, width),
            radiator_height=min(0.6, top - 0.15),
            floor_clearance=0.12,
        )
        _against_wall(lay, obj, walls=[op.wall], u=(op.u0 + op.u1) / 2, gap=(0.03, 0.05), tries=2)


def _plants_bins_boxes(lay: _Layout, plants: float, bins: float, boxes: float) -> None:
    for _ in range(lay.n(plants)):
        plant = lay.furniture("plant")
        if _in_corner(lay, plant) is None:
            _against_wall(lay, plant)
    for _ in range(lay.n(bins)):
        waste_bin = lay.furniture("bin")
        if _in_corner(lay, waste_bin) is None:
            _free(lay, waste_bin)
    for _ in range(lay.n(boxes)):
        box = lay.furniture("box")
        if lay.chance(0.6):
            _against_wall(lay, box, gap=(0.0, 0.1))
        else:
            _free(lay, box)


# --------------------------------------------------------------------------------------
# Room programs.

_DINING_CHAIRS = ("chair-4leg", "chair-4leg-arms", "chair-shell", "chair-sled")


def _office(lay: _Layout) -> None:
    _radiators(lay)
    chair_proto = [lay.furniture("chair-office") for _ in range(1 + lay.chance(0.3))]
    desk_kind = lay.pick(["desk-pedestal", "desk-panel"])
    n_desks = int(np.clip(round(lay.L * lay.W / 7.0) + lay.rng.integers(-1, 2), 2, 8))
    placed = 0
    # Back-to-back pairs in the middle of larger rooms, the rest against the walls.
    if lay.W >= 4.2 and lay.chance(0.6):
        desk = lay.furniture(desk_kind)
        d = desk.dimensions["depth"]
        for _ in range(10):
            mark = lay.checkpoint()
            x = lay.uniform(1.6, lay.L - 1.6)
            y = lay.W / 2 + lay.uniform(-0.3, 0.3)
            a = lay.try_add(place(desk, x, y - d / 2, np.pi))
            b = a and lay.try_add(place(desk, x, y + d / 2, 0.0))
            if not (a and b):
                lay.rollback(mark)
                continue
            ok = all(
                _desk_with_chair(lay, dd, lay.pick(chair_proto), placed_desk=dd) for dd in (a, b)
            )
            if ok:
                placed += 2
                break
            lay.rollback(mark)
    for _ in range(3 * n_desks):
        if placed >= n_desks:
            break
        if _desk_with_chair(lay, lay.furniture(desk_kind), lay.pick(chair_proto)) is not None:
            placed += 1
    cab = _against_wall(lay, lay.furniture("cabinet", variant="filing"), corner="any")
    for _ in range(lay.n(1.5)):
        obj = lay.furniture("cabinet")
        if cab is None or _beside(lay, cab, obj) is None:
            _against_wall(lay, obj)
    if lay.chance(0.5):
        _against_wall(lay, lay.furniture("bookshelf"))
    if lay.chance(0.3):
        _against_wall(lay, lay.furniture("closet"), corner="any")
    for _ in range(lay.n(0.6)):
        visitor = lay.furniture(lay.pick(["chair-4leg", "chair-sled", "chair-shell"]))
        if _against_wall(lay, visitor, gap=(0.05, 0.3)) is None:
            _free(lay, visitor)
    _plants_bins_boxes(lay, 1.2, 1.5, 1.0)


def _conference(lay: _Layout) -> None:
    _radiators(lay)
    length_room = max(lay.L, lay.W)
    table = lay.furniture(
        "table-conference", width=min(4.0, max(2.4, length_room - 2.6 - lay.uniform(0.0, 0.6)))
    )
    chair = lay.furniture(
        lay.pick(["chair-office", "chair-office", "chair-sled", "chair-4leg", "chair-shell"])
    )
    n = int(lay.rng.integers(6, 13))
    t = _table_with_chairs(lay, table, chair, n, 6, region_margin=1.0, loose=0.25)
    if t is not None:
        _table_clutter(lay, t, 1.5)
    side = _against_wall(lay, lay.furniture("cabinet", variant="sideboard"))
    if side is not None and lay.chance(0.7):
        _on_top(
            lay, side, lay.furniture("television"), spot=(0.35, 0.25, 0.65, 0.45), yaw=(-0.05, 0.05)
        )
    for _ in range(lay.n(1.0)):
        spare = lay.furniture(chair.kind) if lay.chance(0.5) else chair
        _against_wall(lay, spare, gap=(0.05, 0.3))
    _plants_bins_boxes(lay, 1.2, 0.6, 0.3)


def _living_room(lay: _Layout) -> None:
    _radiators(lay)
    kind = lay.pick(["sofa-2seat", "sofa-3seat", "sofa-3seat", "sofa-armless", "sofa-l-shaped"])
    sofa_obj = lay.furniture(kind)
    corner = None
    if kind == "sofa-l-shaped":
        corner = sofa_obj.extra["corner"]
    sofa = None
    coffee = None
    for _ in range(10):
        mark = lay.checkpoint()
        sofa = _against_wall(lay, sofa_obj, corner=corner, tries=15)
        if sofa is None:
            continue
        # The coffee table stands 35-50 cm in front of the seat (legroom), centred on the seats.
        table = lay.furniture("table-coffee")
        x0, x1, front = sofa.extra["front_span"]
        ly = front + lay.uniform(0.35, 0.5) + table.dimensions["depth"] / 2
        lx = (x0 + x1) / 2 + lay.uniform(-0.1, 0.1)
        wx, wy = (sofa.pose @ np.array([lx, ly, 0.0, 1.0]))[:2]
        coffee = lay.try_add(place(table, wx, wy, sofa.yaw + lay.uniform(-0.08, 0.08)))
        if coffee is not None:
            break
        lay.rollback(mark)
        sofa = None
    if coffee is not None:
        _table_clutter(lay, coffee, 1.2)
        # Armchairs beside the coffee table, turned towards it.
        for sx in [s for s in (-1, 1) if lay.chance(0.55)]:
            arm = lay.furniture(lay.pick(["chair-armchair", "chair-armchair", "chair-4leg-arms"]))
            lx = sx * (coffee.dimensions["width"] / 2 + 0.25 + arm.dimensions["depth"] / 2)
            yaw = coffee.yaw + sx * np.pi / 2 + lay.uniform(-0.3, 0.3)
            for shift in (0.0, 0.15, 0.3):
                wx, wy = (coffee.pose @ np.array([lx + sx * shift, 0.0, 0.0, 1.0]))[:2]
                if lay.try_add(place(arm, wx, wy, yaw)) is not None:
                    break
    if sofa is not None and lay.chance(0.7):
        k = lay.wall_of[id(sofa)][0]
        tv_bench = lay.furniture("cabinet", variant="sideboard", height=lay.uniform(0.45, 0.6))
        bench = _against_wall(lay, tv_bench, walls=[(k + 2) % 4])
        if bench is not None:
            _on_top(
                lay,
                bench,
                lay.furniture("television"),
                spot=(0.4, 0.25, 0.6, 0.45),
                yaw=(-0.05, 0.05),
            )
    if lay.chance(0.5 * lay.clutter + 0.2):
        _free(lay, lay.furniture(lay.pick(["ottoman-box", "ottoman-round"])), yaw=(-0.3, 0.3))
    shelf = _against_wall(lay, lay.furniture("bookshelf"))
    if shelf is not None and lay.chance(0.5):
        _beside(lay, shelf, lay.furniture("bookshelf"))
    if lay.chance(0.4):
        _against_wall(lay, lay.furniture("cabinet", variant="sideboard"))
    _plants_bins_boxes(lay, 1.5, 0.3, 0.3)


def _home_office(lay: _Layout) -> None:
    _radiators(lay)
    chair = lay.furniture(lay.pick(["chair-office", "chair-office", "chair-4leg", "chair-sled"]))
    _desk_with_chair(lay, lay.furniture(lay.pick(["desk-pedestal", "desk-panel"])), chair)
    shelf = _against_wall(lay, lay.furniture("bookshelf"), corner="any")
    if shelf is not None and lay.chance(0.4):
        _beside(lay, shelf, lay.furniture("bookshelf"))
    if lay.chance(0.6):
        _against_wall(lay, lay.furniture("cabinet", variant=lay.pick(["filing", "sideboard"])))
    if lay.chance(0.4):
        seat = lay.furniture(lay.pick(["chair-armchair", "sofa-2seat"]))
        _against_wall(lay, seat, gap=(0.0, 0.1))
    _plants_bins_boxes(lay, 1.0, 1.0, 1.0)


def _dining_room(lay: _Layout) -> None:
    _radiators(lay)
    chair = lay.furniture(lay.pick(_DINING_CHAIRS))
    round_table = lay.chance(0.35)
    if round_table:
        n = int(lay.rng.integers(4, 7))
        table = lay.furniture(
            "table-round", diameter=lay.uniform(0.9, 1.2) if n > 4 else lay.uniform(0.8, 1.1)
        )
    else:
        n = int(lay.rng.integers(4, 9))
        per_side = max(2, math.ceil(min(n, 6) / 2))
        table = lay.furniture(
            "table-dining",
            width=float(
                np.clip(
                    per_side * 0.62 + lay.uniform(0.0, 0.2), 1.2, min(2.0, max(lay.L, lay.W) - 2.2)
                )
            ),
        )
    t = _table_with_chairs(lay, table, chair, n, 4, region_margin=0.8, loose=0.25)
    if t is not None:
        _table_clutter(lay, t, 1.2)
    side = _against_wall(lay, lay.furniture("cabinet", variant="sideboard"))
    if side is not None:
        for _ in range(lay.n(0.8)):
            _on_top(lay, side, lay.furniture(lay.pick(["plant-small", "books", "box"])))
    if lay.chance(0.4):
        _against_wall(lay, lay.furniture(lay.pick(["bookshelf", "cabinet", "closet"])))
    _plants_bins_boxes(lay, 1.2, 0.2, 0.2)


def _bedroom(lay: _Layout) -> None:
    _radiators(lay)
    bed = None
    for _ in range(6):
        bed = _against_wall(lay, lay.furniture("bed"), tries=20)
        if bed is not None:
            break
    if bed is not None:
        for side in (-1, 1):
            if lay.chance(0.8):
                k, u0, u1 = lay.wall_of[id(bed)]
                stand = lay.furniture("nightstand")
                uc = (
                    u1 + 0.01 + stand.dimensions["width"] / 2
                    if side > 0
                    else u0 - 0.01 - stand.dimensions["width"] / 2
                )
                placed = _against_wall(lay, stand, walls=[k], u=uc, tries=1)
                if placed is not None and lay.chance(0.4 * lay.clutter):
                    _on_top(lay, placed, lay.furniture(lay.pick(["books", "plant-small"])))
    _against_wall(lay, lay.furniture("closet"), corner=lay.pick(["any", None]))
    if lay.chance(0.6):
        chair = lay.furniture(lay.pick(["chair-4leg", "chair-office", "chair-shell"]))
        _desk_with_chair(
            lay,
            lay.furniture("desk-panel", width=lay.uniform(1.0, 1.4)),
            chair,
            equipment=lay.chance(0.5),
        )
    if lay.chance(0.7):
        seat = lay.furniture(
            lay.pick(["stool-round", "ottoman-box", "ottoman-round", "stool-square"])
        )
        _free(lay, seat, yaw=(-np.pi, np.pi))
    if lay.chance(0.3):
        _against_wall(lay, lay.furniture(lay.pick(["bookshelf", "cabinet"])))
    _plants_bins_boxes(lay, 0.8, 0.5, 0.8)


def _kitchen(lay: _Layout) -> None:
    _radiators(lay, 0.4)
    # A run of base units from a corner along one wall, maybe turning the corner.
    run = None
    for _ in range(8):
        units = int(lay.rng.integers(2, 5))
        run = _against_wall(
            lay,
            lay.furniture("kitchen-counter", units=units),
            corner="any",
            gap=(0.0, 0.01),
            tries=4,
        )
        if run is not None:
            break
    if run is not None:
        if lay.chance(0.6):
            _beside(lay, run, lay.furniture("cabinet", variant="tall", depth=0.6))
        if lay.chance(0.5):
            _beside(lay, run, lay.furniture("kitchen-counter", units=int(lay.rng.integers(1, 3))))
        for _ in range(lay.n(1.0)):
            _on_top(lay, run, lay.furniture(lay.pick(["box", "plant-small", "books"])))
    chair = lay.furniture(lay.pick(["chair-4leg", "chair-shell", "chair-sled"]))
    table = lay.furniture(lay.pick(["table-small", "table-small", "table-round"]))
    t = _table_with_chairs(
        lay, table, chair, int(lay.rng.integers(2, 5)), 2, region_margin=0.7, loose=0.3
    )
    if t is not None:
        _table_clutter(lay, t, 0.8)
    # Stools: at a breakfast bar if there is room, otherwise loose by the table or counter.
    stool_kind = lay.pick(["stool-bar", "stool-round", "stool-square"])
    if stool_kind == "stool-bar":
        bar = lay.furniture("table-bar")
        stool = lay.furniture(
            "stool-bar", seat_height=float(np.clip(bar.dimensions["top_height"] - 0.28, 0.65, 0.80))
        )
        if (
            _table_with_chairs(
                lay, bar, stool, int(lay.rng.integers(2, 4)), 1, region_margin=0.5, loose=0.3
            )
            is None
        ):
            stool_kind = "stool-round"
    if stool_kind != "stool-bar":
        for _ in range(1 + lay.n(0.7)):
            _free(lay, lay.furniture(stool_kind))
    for _ in range(lay.n(0.8)):
        waste_bin = lay.furniture("bin")
        if _in_corner(lay, waste_bin) is None:
            _free(lay, waste_bin)
    _plants_bins_boxes(lay, 0.5, 0.0, 0.3)


def _corridor(lay: _Layout) -> None:
    _radiators(lay, 0.6)
    # Keep a walking lane of 90 cm free down the middle.
    long_x = lay.L >= lay.W
    lane = 0.9
    if long_x:
        lay.keepouts = np.vstack(
            [lay.keepouts, [lay.L / 2, lay.W / 2, lay.L / 2, lane / 2, 0.0, 0.0, lay.H]]
        )
        long_walls = [0, 2]
    else:
        lay.keepouts = np.vstack(
            [lay.keepouts, [lay.L / 2, lay.W / 2, lane / 2, lay.W / 2, 0.0, 0.0, lay.H]]
        )
        long_walls = [1, 3]
    depth_max = (min(lay.L, lay.W) - lane) / 2
    for _ in range(8):
        bench = lay.furniture("bench", depth=lay.uniform(0.32, max(0.33, min(0.45, depth_max))))
        if _against_wall(lay, bench, walls=long_walls, gap=(0.0, 0.02)):
            break
    for _ in range(lay.n(0.8)):
        _against_wall(
            lay,
            lay.furniture("bench", depth=lay.uniform(0.32, max(0.33, min(0.45, depth_max)))),
            walls=long_walls,
        )
    for _ in range(lay.n(1.2)):
        _against_wall(
            lay,
            lay.furniture(lay.pick(["chair-4leg", "chair-shell", "chair-sled"])),
            walls=long_walls,
            gap=(0.0, 0.05),
        )
    if lay.chance(0.3):
        _against_wall(
            lay,
            lay.furniture("cabinet", variant="filing", depth=min(0.45, depth_max)),
            walls=long_walls,
        )
    _plants_bins_boxes(lay, 1.5, 1.2, 0.3)


def _tiny(lay: _Layout) -> None:
    table = lay.furniture(
        "table-small", width=lay.uniform(0.75, 0.95), depth=lay.uniform(0.65, 0.75)
    )
    chair = lay.furniture(lay.pick(["chair-4leg", "chair-office", "chair-shell"]))
    _table_with_chairs(lay, table, chair, 1, 1, region_margin=0.5, loose=0.2, tries=20)
    for _ in range(4):
        if _free(lay, lay.furniture(lay.pick(["stool-round", "stool-square"]))):
            break


def _bathroom(lay: _Layout) -> None:
    """A bath in a corner (most bathrooms), a WC and a washbasin against the walls."""
    _radiators(lay, 0.5)
    if lay.chance(0.75):
        for _ in range(6):
            bath = lay.furniture("bathtub")
            if _against_wall(lay, bath, corner="any", gap=(0.0, 0.005), tries=6) is not None:
                break
    # Sanitary ware is fixed to the wall: no gap behind it.
    for _ in range(6):
        wc = lay.furniture(lay.pick(["toilet", "toilet", "toilet-wall-hung"]))
        if _against_wall(lay, wc, gap=(0.0, 0.001)) is not None:
            break
    basin = None
    for _ in range(6):
        basin = lay.furniture(lay.pick(["sink-pedestal", "sink-vanity", "sink-wall-hung"]))
        basin = _against_wall(lay, basin, gap=(0.0, 0.001))
        if basin is not None:
            break
    if basin is not None and basin.kind != "sink-vanity" and lay.chance(0.25):
        _beside(lay, basin, lay.furniture(basin.kind), gap=0.1)
    if lay.chance(0.4):
        tall = lay.furniture(
            "cabinet", variant="tall", width=lay.uniform(0.35, 0.6), depth=lay.uniform(0.3, 0.4)
        )
        _against_wall(lay, tall, corner="any")
    _plants_bins_boxes(lay, 0.3, 0.8, 0.0)


def _hotel_room(lay: _Layout) -> None:
    """A bed between nightstands with table lamps, a TV on a stand facing it, an easy chair."""
    _radiators(lay)
    bed = None
    for _ in range(6):
        bed = _against_wall(
            lay, lay.furniture("bed", mattress_width=lay.pick([1.4, 1.6, 1.8])), tries=20
        )
        if bed is not None:
            break
    if bed is not None:
        k, u0, u1 = lay.wall_of[id(bed)]
        for side in (-1, 1):
            if not lay.chance(0.9):
                continue
            stand = lay.furniture("nightstand")
            w = stand.dimensions["width"]
            uc = u1 + 0.01 + w / 2 if side > 0 else u0 - 0.01 - w / 2
            placed = _against_wall(lay, stand, walls=[k], u=uc, tries=1)
            if placed is not None and lay.chance(0.9):
                shade = min(w, stand.dimensions["depth"]) - 0.08
                lamp = lay.furniture("lamp-table", shade_diameter=lay.uniform(0.2, max(0.2, shade)))
                _on_top(lay, placed, lamp, spot=(0.4, 0.4, 0.6, 0.6), yaw=(-0.3, 0.3))
    walls = [(lay.wall_of[id(bed)][0] + 2) % 4] if bed is not None else None
    tv_stand = None
    for _ in range(4):
        tv_stand = _against_wall(lay, lay.furniture("tv-stand"), walls=walls, tries=15)
        if tv_stand is not None:
            break
        walls = None
    if tv_stand is not None and lay.chance(0.85):
        screen = min(1.3, tv_stand.dimensions["width"] - 0.2)
        tv = lay.furniture("television", screen_width=lay.uniform(0.9, max(0.9, screen)))
        _on_top(lay, tv_stand, tv, spot=(0.4, 0.3, 0.6, 0.5), yaw=(-0.05, 0.05))
    for _ in range(1 + lay.n(0.4)):
        easy = lay.furniture(
            lay.pick(["chair-club", "chair-club", "chair-wingback", "chair-lounge"])
        )
        if _against_wall(lay, easy, gap=(0.05, 0.3)) is None:
            _free(lay, easy)
    if lay.chance(0.5):
        _desk_with_chair(
            lay,
            lay.furniture("desk-panel", width=lay.uniform(1.0, 1.4)),
            lay.furniture(lay.pick(["chair-4leg", "chair-4leg-arms", "chair-shell-curved"])),
            equipment=False,
        )
    if lay.chance(0.6):
        _against_wall(lay, lay.furniture("closet", width=lay.uniform(0.8, 1.4)), corner="any")
    _plants_bins_boxes(lay, 0.6, 0.6, 0.3)


_PROGRAMS: dict[str, Callable[[_Layout], None]] = {
    "office": _office,
    "conference": _conference,
    "living_room": _living_room,
    "home_office": _home_office,
    "dining_room": _dining_room,
    "bedroom": _bedroom,
    "kitchen": _kitchen,
    "corridor": _corridor,
    "tiny": _tiny,
    "bathroom": _bathroom,
    "hotel_room": _hotel_room,
}


# --------------------------------------------------------------------------------------
# Structure: floor, walls with openings, ceiling, doors and windows.


def _structure_object(
    class_name: str,
    kind: str,
    pieces: list[tuple[str, M.Mesh, Any]],
    pose: NDArray[np.float64],
    dims: dict[str, float],
) -> SceneObject:
    """A SceneObject from meshes in a local frame and that frame's pose (no re-centring)."""
    mesh = M.concatenate([m for _, m, _ in pieces])
    names = list(dict.fromkeys(p for p, _, _ in pieces))
    counts = [len(m.triangles) for _, m, _ in pieces]
    tpart = np.repeat([names.index(p) for p, _, _ in pieces], counts).astype(np.int32)
    tcol = np.repeat(np.array([c for _, _, c in pieces], dtype=np.uint8), counts, axis=0)
    lo, hi = mesh.bounds
    centre = pose @ np.array([*(lo + hi) / 2, 1.0])
    yaw = float(np.arctan2(pose[1, 0], pose[0, 0]))
    box = OrientedBox(
        (float(centre[0]), float(centre[1]), float(centre[2])),
        tuple(float(v) for v in hi - lo),
        yaw,
    )
    vertices = mesh.vertices @ pose[:3, :3].T + pose[:3, 3]
    return SceneObject(
        0,
        class_name,
        kind,
        vertices,
        mesh.triangles,
        tpart,
        names,
        tcol.astype(np.uint8),
        pose.copy(),
        dims,
        box,
    )


def _plan_openings(lay: _Layout) -> None:
    """Doors and windows: where they are on which wall."""
    rng = lay.rng
    rt = lay.room_type
    long_walls = [0, 2] if lay.L >= lay.W else [1, 3]
    short_walls = [w for w in range(4) if w not in long_walls]
    n_doors = {
        "corridor": int(rng.integers(2, 6)),
        "conference": 1 + int(rng.random() < 0.4),
        "office": 1 + int(rng.random() < 0.3),
    }.get(rt, 1)
    taken: dict[int, list[tuple[float, float]]] = {k: [] for k in range(4)}

    def free_span(k: int, width: float, margin: float) -> float | None:
        length = lay.wall_length(k)
        for _ in range(30):
            u0 = float(rng.uniform(margin, length - margin - width))
            if all(u0 + width + 0.3 < a or u0 > b + 0.3 for a, b in taken[k]):
                return u0
        return None

    door_walls = long_walls if rt == "corridor" else [0, 1, 2, 3]
    for _ in range(n_doors):
        k = door_walls[int(rng.integers(len(door_walls)))]
        width = float(rng.uniform(*DOOR_WIDTH))
        u0 = free_span(k, width, 0.15)
        if u0 is None:
            continue
        taken[k].append((u0, u0 + width))
        lay.openings.append(
            _Opening(k, "door", u0, u0 + width, 0.0, float(rng.uniform(*DOOR_HEIGHT)))
        )
    # Windows on one or two outside walls, away from the doors.
    if rt == "corridor":
        outside = [short_walls[int(rng.integers(2))]] if rng.random() < 0.7 else []
    elif rt == "tiny":
        outside = [int(rng.integers(4))] if rng.random() < 0.7 else []
    else:
        first = int(rng.integers(4))
        outside = [first] + ([(first + 1) % 4] if rng.random() < 0.4 else [])
    sill_range = (1.0, 1.1) if rt == "kitchen" else WINDOW_SILL
    for k in outside:
        length = lay.wall_length(k)
        n = max(1, int(length // 2.6))
        for i in range(n):
            width = float(min(rng.uniform(*WINDOW_WIDTH), length / n - 0.5))
            if width < 0.6:
                continue
            centre = (i + 0.5) * length / n + float(rng.uniform(-0.15, 0.15))
            u0 = centre - width / 2
            if any(not (u0 + width + 0.3 < a or u0 > b + 0.3) for a, b in taken[k]):
                continue
            sill = float(rng.uniform(*sill_range))
            top = min(sill + float(rng.uniform(*WINDOW_HEIGHT)), lay.H - 0.25)
            taken[k].append((u0, u0 + width))
            lay.openings.append(_Opening(k, "window", u0, u0 + width, sill, top))


def _structure(lay: _Layout, thickness: float) -> list[SceneObject]:
    rng = lay.rng
    L, W, H = lay.L, lay.W, lay.H

    def pick_color(name: str) -> tuple[int, ...]:
        options = _STRUCTURE_COLORS[name]
        return options[int(rng.integers(len(options)))]

    floor_color, wall_color, ceiling_color = (
        pick_color("floor"),
        pick_color("wall"),
        pick_color("ceiling"),
    )
    objects = [
        _structure_object(
            "floor",
            "floor",
            [("floor", M.box_between((0, 0, -SLAB_THICKNESS), (L, W, 0)), floor_color)],
            np.eye(4),
            {"width": L, "depth": W, "thickness": SLAB_THICKNESS},
        ),
        _structure_object(
            "ceiling",
            "ceiling",
            [("ceiling", M.box_between((0, 0, H), (L, W, H + SLAB_THICKNESS)), ceiling_color)],
            np.eye(4),
            {"width": L, "depth": W, "thickness": SLAB_THICKNESS},
        ),
    ]
    t = thickness
    for k in range(4):
        length = lay.wall_length(k)
        # Walls 0 and 2 run past the corners so the four walls close without overlapping.
        u_start, u_end = (-t, length + t) if k % 2 == 0 else (0.0, length)
        ops = sorted([o for o in lay.openings if o.wall == k], key=lambda o: o.u0)
        pieces = []
        u = u_start
        for o in ops:
            if o.u0 > u:
                pieces.append(M.box_between((u, -t, 0.0), (o.u0, 0.0, H)))
            if o.z0 > 0:
                pieces.append(M.box_between((o.u0, -t, 0.0), (o.u1, 0.0, o.z0)))
            if o.z1 < H:
                pieces.append(M.box_between((o.u0, -t, o.z1), (o.u1, 0.0, H)))
            u = o.u1
        pieces.append(M.box_between((u, -t, 0.0), (u_end, 0.0, H)))
        origin = lay.wall_point(k, 0.0, 0.0)
        pose = yaw_pose(origin[0], origin[1], _WALL_YAW[k])
        wall = _structure_object(
            "wall",
            "wall",
            [("wall", m, wall_color) for m in pieces],
            pose,
            {"length": length, "thickness": t, "height": H},
        )
        wall.extra["wall"] = k
        objects.append(wall)
    for o in lay.openings:
        origin = lay.wall_point(o.wall, 0.0, 0.0)
        pose = yaw_pose(origin[0], origin[1], _WALL_YAW[o.wall])
        obj = _door(lay, o, t, pose) if o.kind == "door" else _window(lay, o, t, pose)
        obj.extra["wall"] = o.wall
        objects.append(obj)
    return objects


def _door(lay: _Layout, o: _Opening, t: float, pose: NDArray[np.float64]) -> SceneObject:
    rng = lay.rng
    casing = (236, 234, 228)
    leaf_color = [(236, 234, 228), (180, 140, 100), (120, 86, 60), (200, 200, 200)][
        int(rng.integers(4))
    ]
    cw, cd = 0.06, 0.015  # casing width and how far it stands proud of the wall
    pieces = [
        ("frame", M.box_between((o.u0 - cw, 0.0, 0.0), (o.u0, cd, o.z1 + cw)), casing),
        ("frame", M.box_between((o.u1, 0.0, 0.0), (o.u1 + cw, cd, o.z1 + cw)), casing),
        ("frame", M.box_between((o.u0, 0.0, o.z1), (o.u1, cd, o.z1 + cw)), casing),
    ]
    width = o.u1 - o.u0 - 0.01
    is_open = rng.random() < 0.5
    hinge_left = rng.random() < 0.5
    leaf = M.box_between((0.0, -0.02, 0.01), (width, 0.02, o.z1 - 0.005))
    if is_open:
        angle = float(rng.uniform(np.radians(60), np.radians(100)))
        if hinge_left:
            leaf = leaf.rotated("z", angle).translated((o.u0 + 0.005, 0.025, 0.0))
        else:
            leaf = (
                leaf.scaled((-1, 1, 1)).rotated("z", -angle).translated((o.u1 - 0.005, 0.025, 0.0))
            )
    else:
        leaf = leaf.translated((o.u0 + 0.005, -t / 2, 0.0))
    pieces.append(("door", leaf, leaf_color))
    # Nothing may stand in the door's swing (nor on its casing).
    lay.add_keepout(o.wall, o.u0 - cw - 0.05, o.u1 + cw + 0.05, (o.u1 - o.u0) + 0.15, 0.0, lay.H)
    return _structure_object(
        "door",
        "door-open" if is_open else "door-closed",
        pieces,
        pose,
        {"width": o.u1 - o.u0, "height": o.z1},
    )


def _window(lay: _Layout, o: _Opening, t: float, pose: NDArray[np.float64]) -> SceneObject:
    frame_color = [(236, 236, 232), (90, 90, 94), (150, 110, 74)][int(lay.rng.integers(3))]
    f, fd = 0.06, 0.07  # frame width and depth, centred in the wall
    y0, y1 = -t / 2 - fd / 2, -t / 2 + fd / 2
    pieces = [
        ("frame", M.box_between((o.u0, y0, o.z0), (o.u0 + f, y1, o.z1)), frame_color),
        ("frame", M.box_between((o.u1 - f, y0, o.z0), (o.u1, y1, o.z1)), frame_color),
        ("frame", M.box_between((o.u0 + f, y0, o.z0), (o.u1 - f, y1, o.z0 + f)), frame_color),
        ("frame", M.box_between((o.u0 + f, y0, o.z1 - f), (o.u1 - f, y1, o.z1)), frame_color),
        (
            "glass",
            M.box_between(
                (o.u0 + f, -t / 2 - 0.004, o.z0 + f), (o.u1 - f, -t / 2 + 0.004, o.z1 - f)
            ),
            (170, 200, 215),
        ),
        (
            "sill",
            M.box_between((o.u0 - 0.05, y1, o.z0 - 0.025), (o.u1 + 0.05, 0.03, o.z0)),
            (220, 220, 216),
        ),
    ]
    # Tall furniture keeps clear of the window; low things (radiators, desks) fit under the sill.
    lay.add_keepout(o.wall, o.u0 - 0.05, o.u1 + 0.05, WINDOW_CLEARANCE, o.z0 - 0.03, o.z1)
    return _structure_object(
        "window",
        "window",
        pieces,
        pose,
        {"width": o.u1 - o.u0, "height": o.z1 - o.z0, "sill_height": o.z0},
    )


def _glaze(lay: _Layout) -> int | None:
    """Turn one wall without a door into a glazed wall (floor-to-ceiling panes); its index."""
    doors = {o.wall for o in lay.openings if o.kind == "door"}
    walls = [k for k in range(4) if k not in doors]
    if not walls:
        return None
    windowed = [k for k in walls if any(o.wall == k for o in lay.openings)]
    options = windowed or walls
    k = options[int(lay.rng.integers(len(options)))]
    lay.openings = [o for o in lay.openings if o.wall != k]
    length = lay.wall_length(k)
    n = max(1, round((length - 0.3) / (float(np.mean(GLAZED_PANE_WIDTH)) + GLAZED_MULLION)))
    pane = (length - 0.3 - (n - 1) * GLAZED_MULLION) / n
    top = lay.H - GLAZED_TOP_GAP
    for i in range(n):
        u0 = 0.15 + i * (pane + GLAZED_MULLION)
        lay.openings.append(_Opening(k, "window", u0, u0 + pane, GLAZED_BOTTOM, top))
    return k


@dataclass(frozen=True)
class RoomShell:
    """An empty room: floor, ceiling, walls with their openings, doors and windows.

    Attributes
    ----------
    room_type : str
    size : (3,) float
        Length (x), width (y) and height (z) in metres.
    wall_thickness : float
    structure : list of SceneObject
        Floor, ceiling, four walls, then doors and windows (instance ids 0).
    openings : list of dict
        Each door and window: ``wall`` (0-3), ``kind``, ``u0``, ``u1`` (metres along
        the wall from its first inner corner), ``z0``, ``z1``.
    keepouts : (k, 7) float
        Rows cx, cy, half x, half y, yaw, z0, z1 of the upright boxes furniture
        must stay out of: doors' swing, the space in front of windows.
    glazed_wall : int or None
        The wall made of glass panes, if any.
    """

    room_type: str
    size: tuple[float, float, float]
    wall_thickness: float
    structure: list[SceneObject]
    openings: list[dict[str, Any]]
    keepouts: NDArray[np.float64]
    glazed_wall: int | None = None


def build_shell(
    room_type: str,
    rng: np.random.Generator,
    size: tuple[float, float, float],
    *,
    glazed_wall: bool = False,
) -> RoomShell:
    """The empty shell of a room, with doors and windows placed as :func:`build_room` does.

    Parameters
    ----------
    room_type : str
        Chooses how many doors and windows (offices and conference rooms may have two
        doors, kitchens have higher sills); any name is accepted.
    rng : numpy.random.Generator
        Draws the wall thickness, the openings and the colours.
    size : (3,) float
        Length, width and height in metres.
    glazed_wall : bool
        Make one wall without a door a glazed wall: panes of glass (a window part named
        ``glass``, which sensors see through) from 5 cm above the floor to 10 cm under the
        ceiling between narrow mullions.

    Returns
    -------
    RoomShell

    Examples
    --------
    >>> shell = build_shell("office", np.random.default_rng(0), (5.0, 4.0, 2.7), glazed_wall=True)
    >>> [o.class_name for o in shell.structure][:6]
    ['floor', 'ceiling', 'wall', 'wall', 'wall', 'wall']
    >>> shell.glazed_wall is not None
    True
    """
    L, W, H = (float(v) for v in size)
    thickness = float(rng.uniform(*WALL_THICKNESS))
    lay = _Layout(rng, room_type, (L, W, H), 1.0)
    _plan_openings(lay)
    glazed = _glaze(lay) if glazed_wall else None
    structure = _structure(lay, thickness)
    return RoomShell(
        room_type,
        (L, W, H),
        thickness,
        structure,
        [dataclasses.asdict(o) for o in lay.openings],
        lay.keepouts.copy(),
        glazed,
    )


# --------------------------------------------------------------------------------------
# Public entry point.


def _check_inputs(
    room_type: str, seed: Any, size: Any, clutter: Any
) -> tuple[int, tuple[float, ...] | None, float]:
    if room_type not in ROOM_TYPES:
        raise InvalidParameterError("room_type", f"one of {', '.join(ROOM_TYPES)}", room_type)
    if isinstance(seed, np.random.Generator):
        seed_int = int(seed.integers(2**31 - 1))
    elif isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed >= 0:
        seed_int = int(seed)
    else:
        raise InvalidParameterError("seed", "an integer >= 0 or a numpy Generator", seed)
    dims = None
    if size is not None:
        try:
            dims = tuple(float(v) for v in size)
        except (TypeError, ValueError):
            dims = ()
        if (
            len(dims) not in (2, 3)
            or not all(math.isfinite(v) for v in dims)
            or min(dims[:2]) < 1.5
            or (len(dims) == 3 and not 2.2 <= dims[2] <= 10.0)
        ):
            raise InvalidParameterError(
                "size",
                "(length, width) or (length, width, height) in metres, length and width "
                "at least 1.5 and height 2.2-10",
                size,
            )
    if (
        isinstance(clutter, bool)
        or not isinstance(clutter, (int, float, np.number))
        or not (math.isfinite(clutter) and clutter >= 0)
    ):
        raise InvalidParameterError("clutter", "a number >= 0", clutter)
    return seed_int, dims, float(clutter)


def build_room(
    room_type: str,
    seed: int | np.random.Generator,
    *,
    size: tuple[float, ...] | None = None,
    clutter: float = 1.0,
) -> Scene:
    """Build a furnished room of ``room_type``.

    Parameters
    ----------
    room_type : str
        One of :data:`ROOM_TYPES`: ``"office"``, ``"conference"``, ``"living_room"``,
        ``"home_office"``, ``"dining_room"``, ``"bedroom"``, ``"kitchen"``,
        ``"corridor"``, ``"tiny"`` (2.5 x 2.5 m with one table, one chair and
        one stool, for quick tests), ``"bathroom"`` (WC, washbasin, mostly a bath)
        or ``"hotel_room"`` (bed, nightstands with table lamps, a TV on a stand,
        easy chairs).
    seed : int or numpy.random.Generator
        The same integer always gives the same scene. A generator is used to
        draw an integer seed, which the scene records.
    size : (2,) or (3,) float, optional
        Room length (x), width (y) and optionally height (z) in metres; drawn
        from sizes typical of the room type when omitted.
    clutter : float, default 1.0
        Scales the expected number of optional small things (plants, bins,
        boxes, books, desk clutter); 0 leaves only the main furniture.

    Returns
    -------
    Scene
        Structure first (floor, ceiling, four walls, doors, windows), then the
        furniture; instance ids 1, 2, ... in that order.

    Examples
    --------
    >>> scene = build_room("tiny", 3)
    >>> sorted(o.class_name for o in scene.objects if not o.is_structure)
    ['chair', 'stool', 'table']
    >>> scene.size[:2]
    (2.5, 2.5)
    """
    seed_int, dims, clutter = _check_inputs(room_type, seed, size, clutter)
    rng = np.random.default_rng(seed_int)
    (l0, l1), (w0, w1) = _ROOM_SIZES[room_type]
    L, W = float(rng.uniform(l0, l1)), float(rng.uniform(w0, w1))
    H = float(rng.uniform(*CEILING_HEIGHT))
    if dims is not None:
        L, W = dims[0], dims[1]
        H = dims[2] if len(dims) == 3 else H
    thickness = float(rng.uniform(*WALL_THICKNESS))
    lay = _Layout(rng, room_type, (L, W, H), clutter)
    with progress(f"Building a {room_type.replace('_', ' ')}", total=_FURNISH_ATTEMPTS) as advance:
        _plan_openings(lay)
        structure = _structure(lay, thickness)
        keepouts = lay.keepouts.copy()
        wanted = _MIN_COUNTS[room_type]
        best: list[SceneObject] = []
        for _attempt in range(_FURNISH_ATTEMPTS):
            lay.rollback(0)
            lay.keepouts = keepouts.copy()
            _PROGRAMS[room_type](lay)
            advance(1)
            if all(lay.count(c) >= n for c, n in wanted.items()):
                best = list(lay.objects)
                break
            score = sum(min(lay.count(c), n) for c, n in wanted.items())
            if not best or score > sum(
                min(sum(o.class_name == c for o in best), n) for c, n in wanted.items()
            ):
                best = list(lay.objects)
    objects = [dataclasses.replace(o, instance_id=i + 1) for i, o in enumerate(structure + best)]
    extra = {
        "wall_thickness": thickness,
        "clutter": clutter,
        "openings": [dataclasses.asdict(o) for o in lay.openings],
    }
    return Scene(room_type, (L, W, H), objects, seed_int, extra)


# --------------------------------------------------------------------------------------
# A few chosen objects in an empty room, scanned.

#: Gap between neighbouring objects, and from the corner, in :func:`object_scene`.
OBJECT_SCENE_GAP = 0.1
#: Ceiling height of :func:`object_scene`'s room unless one is given.
OBJECT_SCENE_HEIGHT = 2.6


def object_scene(
    objects: Sequence[Any],
    room: Sequence[float] = (3.0, 3.0),
    *,
    sensor: str = "rgbd",
    points: int | None = 30000,
    seed: int = 0,
    **sensor_opts: Any,
) -> tuple[PointCloud, Scene]:
    """Scan a few chosen objects standing side by side in a corner of a small empty room.

    The objects stand with their backs to the wall y = 0, from the corner at the
    origin along x, 10 cm apart; the room has no doors or windows. This is the quick
    way to get a labelled cloud of chosen furniture, e.g. a WC and a washbasin, or a
    nightstand with a lamp on it.

    Parameters
    ----------
    objects : sequence
        Each item is a kind (``"toilet"``, built from ``seed``), a built
        :class:`~ontodetect.synth.scene.SceneObject` (in its own frame), or a group
        ``(support, item, ...)`` of those: the support stands on the floor and the
        items on its top, side by side (see :func:`~ontodetect.synth.furniture.place_on`).
    room : (2,) or (3,) float
        Length (x), width (y) and optionally height (z) of the room, metres.
    sensor : str
        As :func:`~ontodetect.synth.dataset.synthesize`: ``"rgbd"`` (frames fused),
        ``"rgbd-frame"``, ``"tls"`` or ``"monocular"``.
    points : int, optional
        About this many points (see :func:`~ontodetect.synth.dataset.synthesize`).
    seed : int
        Seed of the objects built from kinds, the room's colours and the sensor.
    **sensor_opts
        Options of the sensor.

    Returns
    -------
    cloud : PointCloud
        The points with the fields ``instance`` and ``class_id`` (0 for misses).
    scene : Scene
        Room type ``"objects"``: floor, ceiling and four walls (instance ids 1-6),
        then the objects in the order given, each group's support before its items.

    Examples
    --------
    >>> cloud, scene = object_scene(["toilet", ("nightstand", "lamp-table")], points=3000)
    >>> [o.class_name for o in scene.objects if not o.is_structure]
    ['toilet', 'cabinet', 'lamp']
    >>> lamp = scene.objects[-1].instance_id
    >>> bool((cloud.fields["instance"] == lamp).any())
    True
    """
    from .dataset import synthesize  # lazy: the dataset module imports this one

    try:
        dims = tuple(float(v) for v in room)
    except (TypeError, ValueError):
        dims = ()
    if len(dims) not in (2, 3) or not all(math.isfinite(v) and v >= 1.5 for v in dims):
        raise InvalidParameterError(
            "room", "(length, width) or (length, width, height), each at least 1.5 m", room
        )
    L, W = dims[0], dims[1]
    H = dims[2] if len(dims) == 3 else OBJECT_SCENE_HEIGHT
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidParameterError("seed", "an integer >= 0", seed)
    rng = np.random.default_rng(int(seed))

    def built(item: Any) -> SceneObject:
        if isinstance(item, SceneObject):
            return item
        if isinstance(item, str):
            return make_furniture(item, rng)
        raise InvalidParameterError("objects", "kinds, SceneObjects or groups of them", item)

    placed: list[SceneObject] = []
    x = OBJECT_SCENE_GAP
    for item in objects:
        group = [built(i) for i in item] if isinstance(item, (list, tuple)) else [built(item)]
        if not group:
            raise InvalidParameterError("objects", "no empty group", item)
        support, on_top = group[0], group[1:]
        w, d = support.dimensions["width"], support.dimensions["depth"]
        if x + w > L - OBJECT_SCENE_GAP or d > W - OBJECT_SCENE_GAP:
            raise InvalidParameterError(
                "objects", f"objects that fit side by side along a {L:g} m wall", item
            )
        support = place(support, x + w / 2, d / 2, 0.0)
        placed.append(support)
        for i, thing in enumerate(on_top):
            placed.append(place_on(thing, support, ((i + 0.5) / len(on_top), 0.5)))
        x += w + OBJECT_SCENE_GAP
    lay = _Layout(rng, "objects", (L, W, H), 0.0)
    thickness = float(np.mean(WALL_THICKNESS))
    structure = _structure(lay, thickness)
    scene = Scene(
        "objects",
        (L, W, H),
        [dataclasses.replace(o, instance_id=i + 1) for i, o in enumerate(structure + placed)],
        int(seed),
        {"wall_thickness": thickness, "clutter": 0.0, "openings": []},
    )
    result = synthesize(scene, sensor, int(seed), points=points, **sensor_opts)
    return result.cloud, scene
