"""A simulated building floor: rooms of :func:`~ontodetect.synth.synthesize` side by side.

Each room is built and scanned on its own (its own seed, walls, furniture and sensor
path) and moved to its place on a grid of rooms, ``gap`` apart (the walls between them).
The floor's points carry the rooms' per-point labels, with instance ids made unique
across rooms. :func:`iter_floor_rooms` hands the rooms out one at a time, so that a floor
of any size can be written to a file without holding it (``benchmarks/bench_tiled.py``).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..cloud import PointCloud, point_cloud
from ..errors import InvalidParameterError
from .dataset import SynthResult, synthesize

__all__ = ["FLOOR_ROOM_TYPES", "INSTANCE_STRIDE", "FloorRoom", "building_floor", "iter_floor_rooms"]

#: Room types a floor cycles through by default (those with chairs, tables and sofas).
FLOOR_ROOM_TYPES = ("office", "conference", "dining_room", "living_room", "kitchen")
#: Room k's instance ids are its own plus ``k * INSTANCE_STRIDE``.
INSTANCE_STRIDE = 1000


@dataclass(frozen=True)
class FloorRoom:
    """One room of a floor: the scan, where it was moved to, and its points there."""

    number: int
    result: SynthResult
    offset: NDArray[np.float64]

    @property
    def xyz(self) -> NDArray[np.float64]:
        """(n, 3) float: the room's points in the floor's frame."""
        return self.result.cloud.xyz + self.offset

    @property
    def instance(self) -> NDArray[np.int64]:
        """(n,) int: per-point instance ids, unique across the floor (0: none)."""
        ids = np.asarray(self.result.cloud.fields["instance"], dtype=np.int64)
        return np.where(ids > 0, ids + self.number * INSTANCE_STRIDE, ids)


def iter_floor_rooms(
    rooms: int | Sequence[str] = 4,
    *,
    columns: int | None = None,
    sensor: str = "rgbd",
    points_per_room: int = 50_000,
    seed: int = 0,
    gap: float = 0.3,
) -> Iterator[FloorRoom]:
    """The rooms of a floor, one at a time, each moved to its place.

    Parameters
    ----------
    rooms : int or sequence of str
        How many rooms (their types cycle through :data:`FLOOR_ROOM_TYPES`), or their types.
    columns : int, optional
        Rooms per row of the grid (default: all in one row).
    sensor, points_per_room
        How each room is scanned (:func:`~ontodetect.synth.synthesize`).
    seed : int
        Room k is built with seed ``seed + k``.
    gap : float
        Metres between neighbouring rooms.
    """
    kinds = (
        list(itertools.islice(itertools.cycle(FLOOR_ROOM_TYPES), rooms))
        if isinstance(rooms, int)
        else list(rooms)
    )
    if not kinds:
        raise InvalidParameterError("rooms", "at least one room", rooms)
    columns = len(kinds) if columns is None else columns
    if isinstance(columns, bool) or not isinstance(columns, int) or columns < 1:
        raise InvalidParameterError("columns", "a whole number >= 1", columns)
    y = 0.0
    for row in range(0, len(kinds), columns):
        x, depth = 0.0, 0.0
        for k in range(row, min(row + columns, len(kinds))):
            result = synthesize(kinds[k], sensor, seed=seed + k, points=points_per_room)
            yield FloorRoom(k, result, np.array([x, y, 0.0]))
            x += float(result.scene.size[0]) + gap
            depth = max(depth, float(result.scene.size[1]))
        y += depth + gap


def building_floor(
    rooms: int | Sequence[str] = 4,
    *,
    columns: int | None = None,
    sensor: str = "rgbd",
    points_per_room: int = 50_000,
    seed: int = 0,
    gap: float = 0.3,
) -> PointCloud:
    """A building floor of rooms side by side as one cloud (see :func:`iter_floor_rooms`).

    Returns
    -------
    PointCloud
        Colours, and the fields ``instance`` (unique across rooms) and ``class_id``;
        ``meta["rooms"]`` lists each room's type, seed and offset.

    Examples
    --------
    >>> floor = building_floor(["tiny", "tiny"], points_per_room=2000, seed=1)
    >>> len(floor), [r["type"] for r in floor.meta["rooms"]]
    (4000, ['tiny', 'tiny'])
    """
    parts = list(
        iter_floor_rooms(
            rooms,
            columns=columns,
            sensor=sensor,
            points_per_room=points_per_room,
            seed=seed,
            gap=gap,
        )
    )
    clouds = [p.result.cloud for p in parts]
    rgb = None if any(c.rgb is None for c in clouds) else np.vstack([c.rgb for c in clouds])
    return point_cloud(
        np.vstack([p.xyz for p in parts]),
        rgb=rgb,
        fields={
            "instance": np.concatenate([p.instance for p in parts]),
            "class_id": np.concatenate([np.asarray(c.fields["class_id"]) for c in clouds]),
        },
        meta={
            "rooms": [
                {"type": p.result.room, "seed": p.result.seed, "offset": p.offset.tolist()}
                for p in parts
            ]
        },
        copy=False,
    )
