"""The simulated world: objects as triangle meshes with named parts, and their ground truth.

A :class:`Scene` is what the room builders produce and what the virtual sensors
ray-cast. Everything is in metres, in a right-handed frame with z up and the
floor at z = 0. Every object carries its class, an oriented box, a pose and
its dimensions so that sensors can label the points they return and the
dataset writer can describe each instance.

Class ids follow NYU40 (the ids ScanNet uses) where NYU40 has the class, so
that one evaluation serves simulated and real scans; classes NYU40 lacks get
ids from 100 up.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..geometry import yaw_pose

__all__ = [
    "CLASS_IDS",
    "CLASS_NAMES",
    "OrientedBox",
    "Scene",
    "SceneObject",
    "yaw_pose",
]

#: Class name -> id (NYU40 where it exists, 100+ otherwise). 0 means unlabelled.
CLASS_IDS: dict[str, int] = {
    "unlabelled": 0,
    "wall": 1,
    "floor": 2,
    "cabinet": 3,
    "bed": 4,
    "chair": 5,
    "sofa": 6,
    "table": 7,
    "door": 8,
    "window": 9,
    "bookshelf": 10,
    "desk": 14,
    "shelves": 15,
    "ceiling": 22,
    "books": 23,
    "television": 25,  # monitors
    "box": 29,
    "otherfurniture": 39,
    "otherprop": 40,
    "stool": 101,
    "bench": 102,
    "ottoman": 103,
    "plant": 104,
    "bin": 105,
    "radiator": 106,
    "keyboard": 107,
    "closet": 108,
    # Furnished rooms (synth.furnished): NYU40 ids where NYU40 has the class.
    "counter": 12,
    "curtain": 16,
    "dresser": 17,
    "pillow": 18,
    "clothes": 21,
    "refrigerator": 24,
    "shower_curtain": 28,
    "whiteboard": 30,
    "nightstand": 32,
    "toilet": 33,
    "sink": 34,
    "lamp": 35,
    "bathtub": 36,
    "bag": 37,
    "shower": 109,
    "appliance": 110,  # cookers, ovens, washing machines
    "tv_stand": 111,
}
#: Id -> class name.
CLASS_NAMES: dict[int, str] = {v: k for k, v in CLASS_IDS.items()}


@dataclass(frozen=True)
class OrientedBox:
    """A box standing upright: centre, size along its own x/y/z, and yaw about z.

    ``size`` is (length along the box's x, width along its y, height); the box's
    x axis points along ``yaw`` in the world. This is the box of the
    detections.json contract.
    """

    center: tuple[float, float, float]
    size: tuple[float, float, float]
    yaw: float

    def contains(self, points: NDArray[np.float64], margin: float = 0.0) -> NDArray[np.bool_]:
        """(n,) bool: which of the (n, 3) points lie inside the box grown by ``margin``."""
        p = np.asarray(points, dtype=np.float64) - np.asarray(self.center)
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        local = np.stack([c * p[:, 0] + s * p[:, 1], -s * p[:, 0] + c * p[:, 1], p[:, 2]], 1)
        half = np.asarray(self.size) / 2 + margin
        return np.all(np.abs(local) <= half, axis=1)

    def to_dict(self) -> dict[str, Any]:
        return {
            "center": [float(v) for v in self.center],
            "size": [float(v) for v in self.size],
            "yaw": float(self.yaw),
        }


@dataclass
class SceneObject:
    """One object (or one piece of room structure) of a simulated scene.

    Attributes
    ----------
    instance_id : int
        1, 2, ... for objects; room structure (floor, walls, ceiling) gets ids too.
    class_name : str
        A key of :data:`CLASS_IDS` (``"chair"``, ``"stool"``, ``"wall"`` ...).
    kind : str
        The variety, e.g. ``"chair-4leg"``, ``"office-swivel"``, ``"sofa-l-shaped"``.
    vertices : (v, 3) float64
        Mesh vertices in the world frame (metres, z up, floor at 0).
    triangles : (t, 3) int32
        Vertex indices of each triangle.
    triangle_part : (t,) int32
        Index into ``part_names`` of the part each triangle belongs to.
    part_names : list of str
        Named parts: ``"seat"``, ``"backrest"``, ``"leg"``, ``"armrest"``, ``"top"``,
        ``"cushion"``, ``"base"``, ``"column"``, ``"shell"``, ``"panel"``, ``"drawer"``...
    triangle_color : (t, 3) uint8
        Material colour of each triangle (shading noise is added by the sensors).
    pose : (4, 4) float64
        Object frame -> world. The object frame has its origin at the centre of
        the footprint on the floor, x to the object's right, y to its front
        (the direction a person sitting on it faces), z up.
    dimensions : dict of str to float
        Overall ``width``, ``depth``, ``height`` and class-specific ones such as
        ``seat_height``, ``top_height``, ``backrest_height``.
    box : OrientedBox
        The tight upright box around the mesh in the world.
    """

    instance_id: int
    class_name: str
    kind: str
    vertices: NDArray[np.float64]
    triangles: NDArray[np.int32]
    triangle_part: NDArray[np.int32]
    part_names: list[str]
    triangle_color: NDArray[np.uint8]
    pose: NDArray[np.float64]
    dimensions: dict[str, float]
    box: OrientedBox
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def class_id(self) -> int:
        return CLASS_IDS[self.class_name]

    @property
    def yaw(self) -> float:
        return float(np.arctan2(self.pose[1, 0], self.pose[0, 0]))

    @property
    def is_structure(self) -> bool:
        """True for floor, walls and ceiling."""
        return self.class_name in ("floor", "wall", "ceiling", "door", "window")


@dataclass
class Scene:
    """A room and everything in it.

    Attributes
    ----------
    room_type : str
        ``"office"``, ``"conference"``, ``"living_room"``, ``"home_office"``,
        ``"dining_room"``, ``"bedroom"``, ``"kitchen"``, ``"corridor"``; or one of
        :data:`~ontodetect.synth.furnished.FURNISHED_ROOM_TYPES` for furnished rooms.
    size : (3,) float
        Room length (x), width (y) and height (z) in metres; the room spans
        ``[0, size[0]] x [0, size[1]] x [0, size[2]]``.
    objects : list of SceneObject
        Structure first, then furniture.
    seed : int
        The seed the scene was built from.
    """

    room_type: str
    size: tuple[float, float, float]
    objects: list[SceneObject]
    seed: int
    extra: dict[str, Any] = field(default_factory=dict)

    def combined_mesh(
        self,
    ) -> tuple[NDArray[np.float64], NDArray[np.int32], NDArray[np.int32], NDArray[np.uint8]]:
        """All objects as one mesh.

        Returns
        -------
        vertices : (V, 3) float64
        triangles : (T, 3) int32
        triangle_instance : (T,) int32
            ``instance_id`` of the object each triangle belongs to.
        triangle_color : (T, 3) uint8
        """
        verts, tris, inst, cols = [], [], [], []
        offset = 0
        for obj in self.objects:
            verts.append(obj.vertices)
            tris.append(obj.triangles.astype(np.int64) + offset)
            inst.append(np.full(len(obj.triangles), obj.instance_id, np.int32))
            cols.append(obj.triangle_color)
            offset += len(obj.vertices)
        if not verts:
            return (
                np.zeros((0, 3)),
                np.zeros((0, 3), np.int32),
                np.zeros(0, np.int32),
                np.zeros((0, 3), np.uint8),
            )
        return (
            np.concatenate(verts),
            np.concatenate(tris).astype(np.int32),
            np.concatenate(inst),
            np.concatenate(cols),
        )

    def object(self, instance_id: int) -> SceneObject:
        """The object with this instance id."""
        for obj in self.objects:
            if obj.instance_id == instance_id:
                return obj
        raise KeyError(instance_id)
