"""Splitting scenes into calibration and held-out sets, by room."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..config import COUNT, SHARE, check_param
from ..errors import InvalidParameterError
from ..io._layouts import SceneSource, natural_key, scene_group


# -- split ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class SceneSplit:
    """Scenes for calibration and scenes kept aside, split by room.

    Attributes
    ----------
    calibration, held_out : list
        The scenes (SceneSource or names), each in the order given.
    fraction : float
        Share of the rooms asked for calibration.
    seed : int
        Seed of the split.
    """

    calibration: list[Any]
    held_out: list[Any]
    fraction: float
    seed: int

    def groups(self, side: str) -> list[str]:
        """Rooms on one side (``"calibration"`` or ``"held_out"``)."""
        items = getattr(self, side)
        return sorted({_group_of(s) for s in items}, key=natural_key)

    def describe(self) -> str:
        """One line naming the rooms of each side and how they were drawn."""
        cal, held = self.groups("calibration"), self.groups("held_out")
        return (
            f"split seed {self.seed}, {self.fraction:g} of the rooms for calibration: "
            f"calibration {', '.join(cal)} ({len(self.calibration)} scenes); held out "
            f"{', '.join(held) or 'none'} ({len(self.held_out)} scenes)"
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "fraction": self.fraction,
            "seed": self.seed,
            "calibration": [_name_of(s) for s in self.calibration],
            "held_out": [_name_of(s) for s in self.held_out],
            "calibration_rooms": self.groups("calibration"),
            "held_out_rooms": self.groups("held_out"),
        }


def _name_of(scene: Any) -> str:
    return scene.name if isinstance(scene, SceneSource) else str(scene)


def _group_of(scene: Any) -> str:
    return scene.group if isinstance(scene, SceneSource) else scene_group(str(scene))


def split_scenes(scenes: Sequence[Any], fraction: float = 0.5, seed: int = 0) -> SceneSplit:
    """Split scenes into calibration and held-out sets, keeping each room on one side.

    Rooms (:func:`~ontodetect.evaluation.scene_group`: ``scene0000_00``, ``_01`` and
    ``_02`` are one room) are put in natural order and shuffled with ``seed``; the
    first ``round(fraction × rooms)`` go to calibration (at least one room on each
    side when ``fraction < 1``; ``fraction = 1`` keeps nothing aside).

    Parameters
    ----------
    scenes : sequence of SceneSource or str
    fraction : float
        Share of the rooms used for calibration, in (0, 1].
    seed : int

    Examples
    --------
    >>> s = split_scenes(["scene0000_00", "scene0000_01", "scene0002_00", "scene0003_00"],
    ...                  0.5, seed=1)
    >>> sorted(s.groups("calibration") + s.groups("held_out"))
    ['scene0000', 'scene0002', 'scene0003']
    """
    check_param("split", SHARE, fraction)  # a share of the rooms
    seed = check_param("seed", COUNT, seed)
    items = list(scenes)
    groups = sorted({_group_of(s) for s in items}, key=natural_key)
    if not groups:
        raise InvalidParameterError("scenes", "at least one scene", "none")
    if fraction < 1.0 and len(groups) < 2:
        raise InvalidParameterError(
            "split", "1 (no held-out scenes) for a dataset of a single room", fraction
        )
    order = np.random.default_rng(int(seed)).permutation(len(groups))
    k = (
        len(groups)
        if fraction >= 1.0
        else int(np.clip(round(fraction * len(groups)), 1, len(groups) - 1))
    )
    chosen = {groups[i] for i in order[:k]}
    return SceneSplit(
        [s for s in items if _group_of(s) in chosen],
        [s for s in items if _group_of(s) not in chosen],
        float(fraction),
        int(seed),
    )


# -- measuring -----------------------------------------------------------------------------
