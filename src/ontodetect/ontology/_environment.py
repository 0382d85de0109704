"""Environment priors P_obj (thesis Eq. 3.4–3.5 and 3.9–3.10, Table 4.10).

``P_obj = Σ_N P_N · P_obj|N`` over the 24 indoor categories of Places205, where
``P_N`` is how likely the scene is of category N (a known room type, or a
distribution from a scene classifier) and ``P_obj|N`` how often the object is
found there. The indoor/outdoor form ``P_obj = P_in · P_obj|in + P_out · P_obj|out``
serves when only that is known. Without information the prior is 1.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

from .._rules import PROBABILITY, WEIGHT, Interval, check_param
from ..errors import InvalidParameterError
from ._places import places_data, room_table_names
from ._schema import ObjectClass, Ontology

__all__ = [
    "class_priors",
    "object_prior",
    "relative_priors",
    "room_area_likelihood",
    "room_categories",
    "room_distribution",
    "room_table",
    "rooms_from_objects",
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
    table = _class_table(cls) if rooms is not None else None
    if table is not None:
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


def _class_table(cls: ObjectClass) -> dict[str, float] | None:
    """P(cls | category) over the categories, or None when the class names no table."""
    if cls.prior_rooms is None:
        return None
    if isinstance(cls.prior_rooms, str):
        return room_table(cls.prior_rooms)
    return {str(k): float(v) for k, v in cls.prior_rooms.items()}


#: The z of a log-normal's 95th percentile (Φ⁻¹(0.95)).
_Z95 = 1.6448536269514722


def room_area_likelihood(area: float, *, whole_room: bool = True) -> dict[str, float]:
    """How likely each category makes a floor area ``area`` (m²) seen by the scan,
    relative to the likeliest (the largest is 1).

    Room areas of a category N are log-normal (``areas`` of places205.yaml: the median
    and the 95th percentile, from standards and design guides), ``ln A ~ N(μ_N, σ_N²)``.
    Each kind of scan bounds the room's area on one side only:

    - a fused scan walked through the room (``whole_room``) covers at least that room,
      and maybe more (a flat's kitchen with its living room, an open-plan floor), so the
      room is at most what was seen: ``P(A_room ≤ A)``, the log-normal's distribution
      function. A 7 m² scan is no classroom; a 60 m² one may hold a bathroom.
    - one view (a camera frame, a scanner station) sees a share ``u`` of the room's floor,
      unknown and taken uniform on (0, 1) (the least said): ``ln A = ln A_room − E`` with
      ``E ~ Exp(1)``, an exponentially modified normal whose log-density is
      ``x − μ + σ²/2 + ln Φ(−(x − μ + σ²)/σ)`` at ``x = ln A``. A small part of a large
      hall rules nothing out; 60 m² seen rules out a bathroom.

    Examples
    --------
    >>> small = room_area_likelihood(6.0)
    >>> round(small["kitchenette"], 2), small["classroom"] < 1e-6
    (1.0, True)
    >>> round(room_area_likelihood(60.0)["bathroom"], 2)  # a flat scanned whole
    1.0
    >>> frame = room_area_likelihood(6.0, whole_room=False)
    >>> frame["classroom"] > 0.05  # a frame may see 6 m² of a classroom
    True
    >>> room_area_likelihood(60.0, whole_room=False)["bathroom"] < 1e-3
    True
    """
    from scipy.special import log_ndtr  # lazy: scipy.special is heavy to import

    area = check_param("area", Interval(0.0), area)
    x = math.log(area)
    logs: dict[str, float] = {}
    for name, a in _data()["areas"].items():
        mu = math.log(float(a["median"]))
        sigma = (math.log(float(a["p95"])) - mu) / _Z95
        if whole_room:
            logs[name] = float(log_ndtr((x - mu) / sigma))
        else:
            logs[name] = x - mu + sigma**2 / 2 + float(log_ndtr(-(x - mu + sigma**2) / sigma))
    top = max(logs.values())
    return {n: math.exp(v - top) for n, v in logs.items()}


def rooms_from_objects(
    found: Iterable[Mapping[str, float]],
    ontology: Ontology,
    *,
    shape: Mapping[str, float] | None = None,
) -> dict[str, float]:
    """P_N from the objects a first labelling found, every class competing.

    Each object found is evidence about the room, weighed by how sure the labelling is of
    it: ``{class: p}`` (the class it was labelled with and its probability; several classes
    may be given, with "none" taking the rest). A class makes a
    category more likely by the ratio ``r_c(N) = P(c | N) / mean_N' P(c | N')`` of its
    table (Table 4.10 for seating): how much more often such a thing stands in a room of
    that category than in any room. The object's factor is the expected ratio,
    ``Σ_c p_c · r_c(N)`` (a class without a table, and "none", count 1), and from a
    uniform P_N, ``P(N | objects) ∝ Π_objects Σ_c p_c · r_c(N)`` (virtual evidence,
    Pearl 1988, §2.2.2). A WC and a basin make a bathroom likely; a dozen chairs and a
    table a room for sitting at a table; one doubtful object moves little. ``shape``, a
    likelihood of each category from the room's shape (:func:`room_area_likelihood`),
    is one more factor.

    Examples
    --------
    >>> from ontodetect.ontology import builtin_ontology
    >>> onto = builtin_ontology()
    >>> p = rooms_from_objects([{"toilet": 0.5, "chair": 0.3}, {"sink": 0.6}], onto)
    >>> max(p, key=p.get), round(p["bathroom"], 2)
    ('bathroom', 0.78)
    >>> p = rooms_from_objects([{"chair": 0.7}] * 8 + [{"table": 0.8}], onto)
    >>> p["bathroom"] < 1e-4 < 0.1 < p["conference_room"]
    True
    >>> sorted(set(rooms_from_objects([], onto).values()))  # nothing found: uniform
    [0.038461538461538464]
    """
    cats = room_categories()
    ratios: dict[str, dict[str, float] | None] = {}

    def ratio(name: str) -> dict[str, float] | None:
        if name not in ratios:
            table = _class_table(ontology[name]) if name in ontology else None
            mean = sum(table.get(n, 0.0) for n in cats) / len(cats) if table else 0.0
            ratios[name] = {n: table.get(n, 0.0) / mean for n in cats} if mean > 0 else None
        return ratios[name]

    logs = dict.fromkeys(cats, 0.0)
    if shape is not None:
        for n in cats:
            logs[n] += math.log(max(float(shape.get(n, 0.0)), 1e-300))
    for probs in found:
        factor = dict.fromkeys(cats, 0.0)
        for name, p in probs.items():
            r = ratio(name)
            for n in cats:
                factor[n] += float(p) * (r[n] if r is not None else 1.0)
        rest = max(0.0, 1.0 - sum(float(p) for p in probs.values()))
        for n in cats:
            logs[n] += math.log(max(factor[n] + rest, 1e-300))
    top = max(logs.values())
    weights = {n: math.exp(v - top) for n, v in logs.items()}
    z = sum(weights.values())
    return {n: weights[n] / z for n in cats}


def relative_priors(ontology: Ontology, rooms: Mapping[str, float]) -> dict[str, float]:
    """P_obj under ``rooms`` relative to P_obj in a room of unknown kind, at most 1.

    ``min(1, Σ_N P_N · P(obj | N) / mean_N P(obj | N))``: how much less likely the class
    is in this room than in any room. With nothing known it is 1 for every class, as
    without a prior, so a P_N estimated from the scan cannot penalise a class where the
    scan says nothing; a room the scan shows to be a bathroom makes a chair a tenth as
    likely, and leaves a toilet as likely as its shape says. Capped at 1: the estimate
    may explain an object away, never make one more likely than its shape alone, since
    the P_N it comes from was itself read off these objects. (Eq. 3.10's own P_obj
    serves a room the user names; this ratio serves a P_N the scan estimates.)

    Examples
    --------
    >>> from ontodetect.ontology import builtin_ontology
    >>> onto = builtin_ontology()
    >>> flat = {n: 1 / 26 for n in room_categories()}
    >>> {round(v, 6) for v in relative_priors(onto, flat).values()}
    {1.0}
    >>> bath = relative_priors(onto, {"bathroom": 1.0})
    >>> bath["toilet"], round(bath["chair"], 2), round(bath["table"], 2)
    (1.0, 0.1, 0.04)
    """
    cats = room_categories()
    out: dict[str, float] = {}
    for cls in ontology.classes:
        table = _class_table(cls)
        if table is None:
            out[cls.name] = 1.0
            continue
        mean = sum(table.get(n, 0.0) for n in cats) / len(cats)
        here = sum(p * table.get(n, 0.0) for n, p in rooms.items())
        out[cls.name] = min(1.0, here / mean) if mean > 0 else 1.0
    return out
