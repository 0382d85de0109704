"""Environment priors P_obj (thesis Eq. 3.4–3.5 and 3.9–3.10, Table 4.10).

``P_obj = Σ_N P_N · P_obj|N`` over the 24 indoor categories of Places205, where
``P_N`` is how likely the scene is of category N (a known room type, or a
distribution from a scene classifier) and ``P_obj|N`` how often the object is
found there. The indoor/outdoor form ``P_obj = P_in · P_obj|in + P_out · P_obj|out``
serves when only that is known. Without information the prior is 1.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .._rules import PROBABILITY, WEIGHT, check_param
from ..errors import InvalidParameterError
from ._places import places_data, room_table_names
from ._schema import ObjectClass, Ontology

__all__ = [
    "class_priors",
    "object_prior",
    "room_categories",
    "room_distribution",
    "room_table",
]


def _data() -> dict[str, Any]:
    return places_data()


def room_categories() -> list[str]:
    """The 24 Places205 indoor categories (Table 3.1), snake_case."""
    return list(_data()["categories"])


def room_table(name: str) -> dict[str, float]:
    """A shipped table P(object | category), e.g. ``"seating"`` (Table 4.10)."""
    cats = _data()["categories"]
    if name not in room_table_names():
        raise InvalidParameterError("prior.rooms", f"one of {room_table_names()}", name)
    return {c: float(v[name]) for c, v in cats.items()}


def room_distribution(room: str | Mapping[str, float] | None) -> dict[str, float] | None:
    """P_N over the categories, normalised to sum to 1.

    Parameters
    ----------
    room : str, mapping or None
        A category (``"office"``), an alias (``"conference"``, ``"bedroom"``), a
        preset (``"office_scenes"``, ``"home_scenes"``, ``"seminar_rooms"``:
        Tables 4.11–4.13), or a mapping category -> weight. None: unknown.

    Examples
    --------
    >>> room_distribution("office")["office"]
    1.0
    >>> round(room_distribution({"office": 3, "lobby": 1})["lobby"], 2)
    0.25
    """
    if room is None:
        return None
    data = _data()
    cats = data["categories"]
    if isinstance(room, str):
        key = room.strip().lower().replace("-", "_").replace(" ", "_")
        if key in cats:
            return {key: 1.0}
        if key in data["aliases"]:
            alias = data["aliases"][key]
            return room_distribution(alias if isinstance(alias, dict) else str(alias))
        if key in data["presets"]:
            return room_distribution(data["presets"][key])
        allowed = sorted([*cats, *data["aliases"], *data["presets"]])
        raise InvalidParameterError("room", f"one of {', '.join(allowed)}", room)
    weights: dict[str, float] = {}
    for k, v in room.items():
        key = str(k).strip().lower().replace("-", "_").replace(" ", "_")
        if key not in cats:
            raise InvalidParameterError("room", f"keyed by categories ({', '.join(cats)})", k)
        w = check_param(f"room[{k!r}]", WEIGHT, v)
        weights[key] = weights.get(key, 0.0) + w
    total = sum(weights.values())
    if total <= 0:
        raise InvalidParameterError("room", "a distribution with a positive total", dict(room))
    return {k: w / total for k, w in weights.items()}


def object_prior(
    cls: ObjectClass,
    rooms: Mapping[str, float] | None = None,
    indoor: float | None = None,
) -> float:
    """P_obj of one class: Eq. 3.10 with a room distribution, Eq. 3.5 with P_in, else 1."""
    if rooms is not None and cls.prior_rooms is not None:
        table = (
            room_table(cls.prior_rooms)
            if isinstance(cls.prior_rooms, str)
            else {str(k): float(v) for k, v in cls.prior_rooms.items()}
        )
        return float(sum(p * table.get(n, 0.0) for n, p in rooms.items()))
    if indoor is not None and cls.prior_indoor is not None:
        if not 0.0 <= indoor <= 1.0:
            raise InvalidParameterError("indoor", "a probability in [0, 1]", indoor)
        outdoor = cls.prior_outdoor if cls.prior_outdoor is not None else 0.0
        return float(indoor * cls.prior_indoor + (1.0 - indoor) * outdoor)
    return 1.0


def class_priors(
    ontology: Ontology,
    room: str | Mapping[str, float] | None = None,
    indoor: float | None = None,
) -> dict[str, float]:
    """P_obj for every class of an ontology."""
    if indoor is not None:
        indoor = check_param("indoor", PROBABILITY, indoor)
    rooms = room_distribution(room)
    return {c.name: object_prior(c, rooms, indoor) for c in ontology.classes}
