"""Scoring a cluster against every class of an ontology (thesis Eq. 3.1–3.3, Alg. 1 steps 10–18).

For each class the cluster's planes are assigned to the class's parts (each
plane to at most one part, a part possibly left without a plane when it is
occluded); the assignment with the highest likelihood

    P_ont|obj = Π_parts P_def,   P_def = P_Pr · P_Or · P_De · P_He      (Eq. 3.2, 3.3)

is kept. A part without a plane contributes its ``missing`` factor instead:
occlusion is penalised, not fatal. When the cluster stops short of the floor beside
a surface that can hide its lower part, and the part belongs below what is visible
(a chair pushed under a desk shows only its backrest), the part's ``occluded``
factor applies instead, if the class gives one. Relations between two parts count
towards ``P_Pr`` of the second part named. Cluster-wide rules (extent, number of planes)
multiply in as one more factor. The posterior over the classes and a "none"
hypothesis is then

    P_obj|ont ∝ P_obj · P_ont|obj                                        (Eq. 3.1)

computed in log space and normalised, so that a cluster matching no class well
puts its mass on "none".
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._features import CUT_MARGIN, FEATURES, is_patch, patch_members
from ._gaussian import Gaussian
from ._schema import ObjectClass, Ontology, Part

__all__ = [
    "ClassScore",
    "ClusterDescription",
    "ClusterScores",
    "ConstraintValue",
    "continuations",
    "missing_factor",
    "part_values",
    "plane_feature",
    "score_class",
    "score_cluster",
    "with_priors",
]

#: Parts consider at most this many candidate planes (best unary scores first).
MAX_CANDIDATES = 6
#: Planes whose unary log-score is below this are not worth assigning (factor < 1e-9).
MIN_LOG_UNARY = math.log(1e-9)
#: Planes tilted less than this (degrees) count as horizontal for the cluster's ``rise``.
HORIZONTAL_TILT = 10.0
#: Name of the hypothesis that the cluster is none of the classes.
NONE = "none"
#: A plane no part explains costs the full ``extra_plane`` factor from this area up (m²);
#: smaller patches (a caster, a strip of a frame) cost proportionally less.
EXTRA_PLANE_AREA = 0.08
#: Planes whose normals differ by less than ``CONTINUE_ANGLE`` (degrees), whose centroids
#: are within ``CONTINUE_STEP`` (m) of each other along the normal and which come within
#: ``CONTINUE_GAP`` (m) are pieces of one surface (a top, a seat or a backrest MSAC found
#: in several patches): the part that takes one explains all.
CONTINUE_ANGLE = 10.0
CONTINUE_STEP = 0.05
CONTINUE_GAP = 0.1
#: A part that ``supports`` explains the planes at least this tilted (degrees) ...
UPRIGHT_TILT = 60.0
#: ... whose centroid lies within its outline widened by this (m), and whose top rises no
#: more than this above its own.
SUPPORT_MARGIN = 0.05
#: ... and only under a top the floor was seen under, over at least this share of its
#: footprint (``open_below``; the built-in table's own bound): legs and a pedestal with
#: knee space hold a top up; under a closed box the sides are the box.
SUPPORT_OPEN = 0.35
#: An unexplained horizontal plane of at least this area (m²) is a second surface, which
#: costs a class's ``extra_surface`` (a seat beside a "table top" is not clutter on it).
SURFACE_AREA = 0.25
#: A cluster whose lowest point is this high above the floor (m) does not stand on it:
#: something in front may hide its lower part ...
LIFTED_BOTTOM = 0.2
#: ... if a neighbouring surface (its ``shelter``) reaches at least this close below
#: the cluster's lowest visible point (m).
SHELTER_TOLERANCE = 0.05
#: A part counts as hidden below a lifted cluster when the centre of its height
#: constraint is less than this above the cluster's lowest point (m) ...
HIDDEN_MARGIN = 0.1
#: ... or, beside a neighbour's surface (``shelter``), less than this: what shows of a
#: chair pushed under a table may begin at its seat's rear edge, and a seat anywhere in
#: Table 4.1's seating plane range (35-75 cm) must count, a dining or stacking chair's as
#: well as an office chair's (EN 1335-1: 420-530 mm); its lowest, 0.35 m, lies 0.20 m under
#: the range's 0.55 m centre.
SHELTERED_MARGIN = 0.2
#: Horizontal planes of at least this area (m²) can hide a part: a neighbour's top that
#: shelters a seat (segment.shelter_heights), and no less a board that ends what shows of
#: a lifted cluster ...
SHELTER_AREA = 0.1
#: ... when it reaches within this (m, the MSAC threshold and a board's thickness) of its
#: top. A chair pushed under a table shows its back's upper edge; a hutch's shelf over its
#: back panel or a cabinet's top over its front shows a board, and hides nothing under it.
TOP_REACH = 0.05
#: A cluster that shows less than this share of itself below ``LIFTED_BOTTOM`` stands on
#: legs and is lifted off the floor too (a chair's legs, column or runners: a few narrow
#: uprights, seen under a backrest that hides the seat). What reaches the floor as a
#: surface puts more there: a chair-high cluster (at most 1.3 m, the chair's bound) whose
#: surfaces run down to the floor has at least 0.2 / 1.3, about 15 %, of its height below
#: 0.2 m (physical argument). Measured on voxels (``ClusterDescription.base``), so that the
#: sampling density does not count.
LEG_SHARE = 0.1
#: In a single view, what hides a seat behind it rises above this (m): the top of a desk
#: or table (EN 527-1 fixed-height desks 740 +/- 20 mm; dining tables 0.72-0.76 m). An
#: upright that ends no higher may be the panel under such a top, which a single view sees
#: edge-on or not at all; a chair's back rises higher (EN 1335-1: 360 mm and more over a
#: seat of 400 mm and more; dining, stacking and folding chairs' backs top out at
#: 0.8-1.0 m). Chairs with lower backs (club armchairs, 0.70-0.85 m) seen from straight
#: behind are the price.
HIDDEN_SEAT_TOP = 0.76


@dataclass(frozen=True)
class ClusterDescription:
    """What the scoring needs to know about a cluster.

    Attributes
    ----------
    planes : sequence of plane objects
        Each with the attributes ``tilt``, ``height``, ``z_min``, ``z_max``, ``length``,
        ``width``, ``area``, ``density``, ``num_points``, ``normal``, ``centroid``
        (``ontodetect.segment.planes.Plane`` has them).
    relations : mapping of (i, j) to relation objects, i < j
        Each with ``angle``, ``distance`` and ``xy_overlap``.
    length, breadth, height, bottom : float
        Longest and shortest horizontal side of the upright box, top and lowest
        point above the floor (m).
    shelter : float
        Height above the floor of the highest horizontal surface of a neighbouring
        object (a desk beside a chair) or, in a single view, of one the sight line to
        just under the cluster crosses (a table seen in front of a chair), which can
        hide this cluster's lower part; ``-inf`` when there is none or it is unknown.
    ceiling : float
        Top of the search volume above the floor (the altitude cut-off, m): a
        cluster that reaches it may go on above, so its height is a lower bound.
    hidden_below : float
        In a single view, the height above the floor under which the cluster itself
        hides from the sensor what stands behind it (a seat behind its backrest, seen
        from behind and above); ``-inf`` when unknown (a scan fused from many views).
    open_below : sequence of float, optional
        Per plane, the share of its footprint under which the floor was seen (the part
        feature ``open_below``); NaN where it was not measured, ``None`` when nothing
        was (then the feature costs nothing).
    base : float
        Height above the floor under which ``LEG_SHARE`` of the cluster's voxels lie:
        above its legs when it stands on legs, at the floor when a surface of it reaches
        the floor; ``-inf`` when unknown (then the lowest point alone says whether the
        cluster is lifted off the floor).
    wall_gap : float
        Horizontal distance (m) from the cluster to the nearest voxel taken as wall; NaN
        when the scan shows no wall (then the feature costs nothing).
    """

    planes: Sequence[Any]
    relations: Mapping[tuple[int, int], Any]
    length: float
    breadth: float
    height: float
    bottom: float
    shelter: float = -math.inf
    ceiling: float = math.inf
    hidden_below: float = -math.inf
    open_below: Sequence[float] | None = None
    base: float = -math.inf
    wall_gap: float = math.nan
    scene: Mapping[str, Sequence[float] | None] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # ``open_below`` is the scene feature detect measures today; it joins the others.
        if self.open_below is not None:
            object.__setattr__(self, "scene", {**self.scene, "open_below": self.open_below})

    def scene_values(self, feature: str) -> Sequence[float] | None:
        """Per plane, the scene feature ``feature``, or ``None`` when it was not measured."""
        return self.scene.get(feature)

    @property
    def cut(self) -> bool:
        """Whether the cluster reaches the top of the search volume."""
        return self.height >= self.ceiling - CUT_MARGIN

    @functools.cached_property
    def continued(self) -> list[frozenset[int]]:
        """:func:`continuations` of this cluster, worked out once for all classes."""
        return continuations(self)

    @functools.cached_property
    def below(self) -> list[frozenset[int]]:
        """For every level plane the floor was seen under (``open_below`` at least
        ``SUPPORT_OPEN``), the upright planes that stand under it: their centroid within
        its outline (``SUPPORT_MARGIN``) and their top no higher than its own. What a part
        with ``supports`` explains besides its plane."""
        out: list[frozenset[int]] = []
        seen = self.scene_values("open_below")
        for c, top in enumerate(self.planes):
            floor_seen = math.nan if seen is None else float(seen[c])
            if (
                float(top.tilt) > HORIZONTAL_TILT
                or is_patch(top)
                or getattr(top, "axes", None) is None
                or not floor_seen >= SUPPORT_OPEN
            ):
                out.append(frozenset())
                continue
            axes = np.asarray(top.axes, dtype=float)
            half = np.array([float(top.length), float(top.width)]) / 2 + SUPPORT_MARGIN
            mine = set()
            for k, p in enumerate(self.planes):
                if k == c or float(p.tilt) < UPRIGHT_TILT or is_patch(p):
                    continue
                if float(p.z_max) > float(top.z_max) + SUPPORT_MARGIN:
                    continue
                uv = axes @ (np.asarray(p.centroid, dtype=float) - np.asarray(top.centroid))
                if np.all(np.abs(uv) <= half):
                    mine.add(k)
            out.append(frozenset(mine))
        return out

    @functools.cached_property
    def conflicts(self) -> list[frozenset[int]]:
        """For every plane, the planes no other part may take with it: a curved patch
        (a plane with ``members``) and its member planes share their points."""
        out: list[set[int]] = [set() for _ in self.planes]
        members = [frozenset(patch_members(p)) for p in self.planes]
        for k, mine in enumerate(members):
            for m in mine:
                out[k].add(m)
                out[m].add(k)
            for j in range(k):
                if mine & members[j]:
                    out[k].add(j)
                    out[j].add(k)
        return [frozenset(x) for x in out]

    def of_kind(self, kind: str) -> NDArray[np.bool_]:
        """(planes,) which planes are patches of ``kind`` (``Patch.kind``)."""
        return np.array([getattr(p, "kind", None) == kind for p in self.planes], dtype=bool)

    @functools.cached_property
    def lying(self) -> NDArray[np.bool_]:
        """(planes,) which planes are lying surfaces (``Patch.kind == "lying"``)."""
        return self.of_kind("lying")

    @functools.cached_property
    def layer(self) -> NDArray[np.bool_]:
        """(planes,) which planes are seats' level layers (``Patch.kind == "layer"``)."""
        return self.of_kind("layer")

    @functools.cached_property
    def _part_values(self) -> dict[str, NDArray[np.float64]]:
        """:func:`part_values` by feature, filled as the classes ask for them: every class
        scores the same planes, most of them with the same features."""
        return {}

    @functools.cached_property
    def _extra_weights(self) -> tuple[NDArray[np.float64], NDArray[np.bool_], list[bool]]:
        """What :func:`_extra_log` needs of the planes, the same for every class: their
        :func:`_plane_weights`, which are large surfaces and which are curved patches."""
        planes = self.planes
        surface = np.array(
            [float(p.tilt) < HORIZONTAL_TILT and float(p.area) >= SURFACE_AREA for p in planes],
            dtype=bool,
        )
        return _plane_weights(planes), surface, [is_patch(p) for p in planes]

    @property
    def rise(self) -> float:
        """Height of the cluster above the top of its highest horizontal plane (m)."""
        tops = [
            float(p.z_max)
            for p in self.planes
            if float(p.tilt) <= HORIZONTAL_TILT and not is_patch(p)
        ]
        return max(0.0, self.height - max(tops)) if tops else self.height


@dataclass(frozen=True)
class ConstraintValue:
    """One evaluated constraint: where it applies, the measured value, its Gaussian, its factor."""

    part: str  # part name, "a~b" for a relation, "cluster" for cluster rules
    feature: str
    group: str  # Or, He, De, Pr, or "cluster"
    value: float | None  # None when the part is missing or the feature was not measured
    gaussian: Gaussian | None
    factor: float


@dataclass(frozen=True)
class ClassScore:
    """The best interpretation of a cluster as one class."""

    name: str
    log_likelihood: float  # log P_ont|obj
    log_prior: float  # log P_obj
    assignment: Mapping[str, int | None]  # part -> plane index or None (missing)
    factors: Mapping[str, Mapping[str, float]]  # part -> {"Or", "He", "De", "Pr", "def"}
    constraints: tuple[ConstraintValue, ...]
    probability: float = 0.0  # P_obj|ont after normalisation (set by score_cluster)
    #: The class whose descriptions this one competes among (``ObjectClass.variant_of``;
    #: ``None``: its own): only the best of them counts in the posterior.
    group: str | None = None

    @property
    def likelihood(self) -> float:
        return math.exp(self.log_likelihood)


@dataclass(frozen=True)
class ClusterScores:
    """Scores of one cluster for every class, plus "none"."""

    classes: Mapping[str, ClassScore]
    probabilities: Mapping[str, float]  # class -> P_obj|ont; includes "none"
    best: str  # most probable class (may be "none")
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def best_probability(self) -> float:
        return self.probabilities[self.best]


def part_values(desc: ClusterDescription, feature: str) -> NDArray[np.float64]:
    """(planes,) the value of a part feature for every plane of the cluster; NaN where it
    was not measured (a scene feature such as ``open_below`` the description lacks)."""
    return np.array(
        [_part_value(desc, i, feature) for i in range(len(desc.planes))], dtype=np.float64
    )


def _part_value(desc: ClusterDescription, i: int, feature: str) -> float:
    """:func:`part_values` of plane ``i`` alone."""
    f = FEATURES["part"][feature]
    if f.scene:
        values = desc.scene_values(feature)
        return math.nan if values is None else float(values[i])
    if f.in_cluster is not None:
        return f.in_cluster(desc, i)
    return f.plane(desc.planes[i])  # type: ignore[misc]


def plane_feature(plane: Any, feature: str) -> float:
    """The value of a part feature (see ``PART_FEATURES``) for one plane (not a scene
    feature such as ``open_below``, nor one measured within the cluster such as ``rise``:
    :func:`part_values`)."""
    f = FEATURES["part"].get(feature)
    if f is None or f.plane is None:
        return float(getattr(plane, feature))
    return f.plane(plane)


def _relation_feature(desc: ClusterDescription, i: int, j: int, feature: str) -> float:
    """The value of a relation feature between planes ``i`` and ``j``; NaN when it cannot
    be measured on them (planes without in-plane axes), costing nothing."""
    return FEATURES["relation"][feature].relation(desc, i, j)  # type: ignore[misc]


def _cluster_feature(desc: ClusterDescription, feature: str) -> float:
    return FEATURES["cluster"][feature].cluster(desc)  # type: ignore[misc]


def cluster_log_factor(g: Gaussian, desc: ClusterDescription, feature: str) -> float:
    """Log-factor of a cluster constraint, by the feature's own rule when it has one.

    The height of a cluster that reaches the altitude cut-off is only known to be at
    least what is seen: the factor is the mean of the Gaussian over ``CUT_SPAN`` above
    it, so a class that is never that tall pays for it and one that may be does not. A
    value not measured (NaN, such as ``wall_gap`` in a scan with no wall) costs nothing,
    as for part and relation features.
    """
    f = FEATURES["cluster"][feature]
    value = f.cluster(desc)  # type: ignore[misc]
    if math.isnan(value):  # not measured: no factor
        return 0.0
    if f.log_factor is not None:
        return f.log_factor(g, desc, value)
    return float(g.log(value))


def _plane_weights(planes: Sequence[Any]) -> np.ndarray:
    """(planes,) share of the full extra-plane penalty each plane costs, by its area."""
    return np.array([min(1.0, float(p.area) / EXTRA_PLANE_AREA) for p in planes])


def _extra_log(cls: ObjectClass, desc: ClusterDescription) -> np.ndarray:
    """(planes,) log-factor each plane of ``desc`` costs when no part of ``cls`` explains it."""
    weights, surface, patches = desc._extra_weights
    out = math.log(cls.extra_plane) * weights
    if cls.extra_surface is not None:
        out[surface] = math.log(cls.extra_surface)
    # A curved patch is its strips again: they cost when nothing explains them, it never.
    out[patches] = 0.0
    return out


def _unary(cls: ObjectClass, desc: ClusterDescription) -> np.ndarray:
    """(parts, planes) log-factor of each plane as each part, relations left out; a
    lying surface is no candidate for a part that does not say ``lying``, a seat's level
    layer none for one that does not say ``layer``."""
    out = np.zeros((len(cls.parts), len(desc.planes)))
    cache = desc._part_values
    for p, part in enumerate(cls.parts):
        # Patches of the kinds only a part that says so may take.
        for mask, allowed in ((desc.lying, part.lying), (desc.layer, part.layer)):
            if not allowed and mask.any():
                out[p, mask] = -math.inf
        for feature, g in part.constraints.items():
            values = cache.get(feature)
            if values is None:
                values = cache[feature] = part_values(desc, feature)
            if len(values):
                known = ~np.isnan(values)  # a feature not measured costs nothing
                out[p, known] += g.log(values[known])
    return out


def continuations(desc: ClusterDescription) -> list[frozenset[int]]:
    """For every plane, the other planes of the cluster that continue its surface.

    Two patches with about the same normal and offset that touch are one top, one
    seat or one backrest split by clutter, a seam or a gap in the scan; a curved patch
    (``members``) continues its strips and they continue it.
    """
    planes = desc.planes
    out: list[set[int]] = [set() for _ in planes]
    for k, p in enumerate(planes):  # a curved patch and its strips are one surface
        for m in patch_members(p):
            out[k].add(m)
            out[m].add(k)
    for (i, j), rel in desc.relations.items():
        if float(rel.angle) > CONTINUE_ANGLE or float(rel.distance) > CONTINUE_GAP:
            continue
        normal = np.asarray(planes[i].normal, dtype=float)
        step = np.asarray(planes[j].centroid, dtype=float) - np.asarray(
            planes[i].centroid, dtype=float
        )
        if abs(float(normal @ step)) <= CONTINUE_STEP:
            out[i].add(j)
            out[j].add(i)
    return [frozenset(x) for x in out]


def _height_span(g: Gaussian) -> tuple[float, float]:
    """Centre and upper end of a height constraint (the upper end may be infinite)."""
    if g.side == "plateau" and g.upper is not None:
        return (g.mean + g.upper) / 2, g.upper
    if g.side == "both":
        return g.mean, g.mean + g.sigma
    return g.mean, (g.mean if g.side == "max" else math.inf)


def missing_factor(part: Part, desc: ClusterDescription) -> float:
    """The factor of ``part`` left without a plane in this cluster.

    ``part.missing``, or ``part.occluded`` when the part can be hidden. The cluster
    must be lifted off the floor (its bottom above ``LIFTED_BOTTOM``, or standing on legs:
    less than ``LEG_SHARE`` of it below that height, ``desc.base``), and then either

    - a neighbouring surface stands about as high as its lowest visible point
      (``desc.shelter``), and the part belongs just below what is visible (the
      centre of its height range is less than ``SHELTERED_MARGIN`` above the
      cluster's bottom, and the top of the range is not below it); or
    - in a single view, the cluster itself hides the height the part belongs at
      from the sensor (the centre of its height range lies under
      ``desc.hidden_below`` and not more than ``HIDDEN_MARGIN`` below the cluster's
      bottom) and rises above a table's top (``HIDDEN_SEAT_TOP``): the seat of a chair
      seen from behind.

    Neither holds when what shows ends in a level board (``SHELTER_AREA``, ``TOP_REACH``).
    """
    bottom = float(desc.bottom)
    if part.occluded is None or max(bottom, float(desc.base)) <= LIFTED_BOTTOM:
        return part.missing
    top = float(desc.height)
    if any(
        float(p.tilt) < HORIZONTAL_TILT
        and float(p.area) >= SHELTER_AREA
        and float(p.z_max) >= top - TOP_REACH
        for p in desc.planes
    ):  # what shows ends in a level board: a shelf or a cabinet's top, not a backrest
        return part.missing
    height = part.constraints.get("height")
    span = None if height is None else _height_span(height)
    if float(desc.shelter) >= bottom - SHELTER_TOLERANCE and (
        span is None or (span[0] < bottom + SHELTERED_MARGIN and bottom <= span[1])
    ):
        return max(part.missing, part.occluded)
    if (
        span is not None
        and bottom - HIDDEN_MARGIN <= span[0] <= float(desc.hidden_below)
        and top > HIDDEN_SEAT_TOP
    ):
        return max(part.missing, part.occluded)
    return part.missing


def _combo_log(
    combo: Sequence[int | None],
    unary: np.ndarray,
    missing: Sequence[float],
    plane_log_extra: np.ndarray,
    more: Sequence[Sequence[frozenset[int]]],
    best_log: float,
    rel_terms: Sequence[tuple[int, int, Any]],
    desc: ClusterDescription,
) -> float:
    """Log-likelihood of one assignment (-inf when it cannot beat ``best_log``);
    ``more[p][c]``: the planes part ``p`` explains with plane ``c`` besides it."""
    used = [c for c in combo if c is not None]
    explained = set(used).union(*(more[p][c] for p, c in enumerate(combo) if c is not None))
    total = float(plane_log_extra.sum()) - float(sum(plane_log_extra[c] for c in explained))
    for p, c in enumerate(combo):
        total += unary[p, c] if c is not None else math.log(missing[p])
    if total <= best_log:
        return -math.inf  # relation factors are <= 1: this cannot win
    for a, b, rel in rel_terms:
        ia, ib = combo[a], combo[b]
        if ia is None or ib is None:
            continue
        for feature, g in rel.constraints.items():
            value = _relation_feature(desc, ia, ib, feature)
            if not math.isnan(value):  # not measured: no factor
                total += float(g.log(value))
    return total


def _exhaustive_assignment(unary, missing, candidates, rel_terms, plane_log_extra, desc, more):
    """Every combination of candidates, in ``itertools.product`` order; the first best wins.
    Exponential in the number of parts: kept as the reference the tests compare with."""
    conflicts = desc.conflicts
    best_log, best_assign = -math.inf, None
    for combo in itertools.product(*candidates):
        used = [c for c in combo if c is not None]
        if len(used) != len(set(used)) or any(conflicts[c] & set(used) for c in used):
            continue
        total = _combo_log(combo, unary, missing, plane_log_extra, more, best_log, rel_terms, desc)
        if total > best_log:
            best_log, best_assign = total, combo
    assert best_assign is not None  # the all-missing combination always exists
    return best_log, best_assign


#: Slack of the branch-and-bound pruning, far above rounding and far below any real gap.
_BOUND_SLACK = 1e-9


def _search_assignment(unary, missing, candidates, rel_terms, plane_log_extra, desc, more):
    """Branch and bound over the parts, in the exhaustive search's order: the same best
    assignment (ties: the first in ``itertools.product`` order), without visiting the
    combinations that cannot beat the best found so far.

    The bound of a partial assignment adds, for every part still open, the best that part
    could add on its own: its best candidate's log-factor plus every plane that candidate
    would explain (or its missing factor). Relations only lower a total (factors <= 1) and a
    plane explained twice counts once, so the bound never falls below what a completion
    reaches; a branch is cut only when its bound is below the best total found.
    """
    conflicts = desc.conflicts
    n = len(candidates)
    gain = np.maximum(-plane_log_extra, 0.0)

    def option_bound(p: int, c: int | None) -> float:
        if c is None:
            return math.log(missing[p])
        return float(unary[p, c]) + float(sum(gain[k] for k in {c} | more[p][c]))

    # best[p]: the most parts p.. can add, each on its own.
    best_rest = [0.0] * (n + 1)
    for p in range(n - 1, -1, -1):
        best_rest[p] = best_rest[p + 1] + max(option_bound(p, c) for c in candidates[p])
    base = float(plane_log_extra.sum())
    state = {"log": -math.inf, "assign": None}
    combo: list[int | None] = [None] * n

    def visit(p: int, used: set[int], explained: set[int], partial: float) -> None:
        if p == n:
            total = _combo_log(
                combo, unary, missing, plane_log_extra, more, state["log"], rel_terms, desc
            )
            if total > state["log"]:
                state["log"], state["assign"] = total, tuple(combo)
            return
        for c in candidates[p]:
            if c is not None and (c in used or conflicts[c] & used):
                continue
            if c is None:
                step, new_explained = math.log(missing[p]), explained
            else:
                new_explained = explained | {c} | more[p][c]
                step = float(unary[p, c]) + float(sum(gain[k] for k in new_explained - explained))
            bound = partial + step + best_rest[p + 1]
            if bound + _BOUND_SLACK < state["log"]:
                continue
            combo[p] = c
            visit(p + 1, used | {c} if c is not None else used, new_explained, partial + step)
        combo[p] = None

    visit(0, set(), set(), base)
    assert state["assign"] is not None  # the all-missing combination always exists
    return state["log"], state["assign"]


def score_class(
    cls: ObjectClass,
    desc: ClusterDescription,
    log_prior: float = 0.0,
    *,
    search_exhaustively: bool = False,
) -> ClassScore:
    """Find the most likely assignment of planes to the class's parts and its likelihood.

    The search is a branch and bound (:func:`_search_assignment`) that finds the same
    assignment as trying every combination (``search_exhaustively=True``, the reference
    the tests compare with) without its exponential cost in the number of parts.
    """
    unary = _unary(cls, desc)
    missing = [missing_factor(part, desc) for part in cls.parts]
    part_index = {p.name: k for k, p in enumerate(cls.parts)}
    candidates: list[list[int | None]] = []
    for p, part in enumerate(cls.parts):
        order = np.argsort(-unary[p], kind="stable")[:MAX_CANDIDATES]
        cand: list[int | None] = [int(i) for i in order if unary[p, i] > MIN_LOG_UNARY]
        candidates.append([*cand, None])
        del part
    rel_terms = [(part_index[r.a], part_index[r.b], r) for r in cls.relations]

    # Planes no part explains cost ``extra_plane`` each, weighted by their size: a stool
    # is not a chair with a back, but a chair is still a chair with a caster in view.
    plane_log_extra = _extra_log(cls, desc)
    # What a part explains besides its plane: the plane's continuations, and for a part
    # that ``supports``, the upright planes standing under it (``desc.below``).
    held = desc.continued
    if any(part.supports for part in cls.parts):
        held = [c | b for c, b in zip(desc.continued, desc.below)]
    more = [held if part.supports else desc.continued for part in cls.parts]
    search = _exhaustive_assignment if search_exhaustively else _search_assignment
    best_log, best_assign = search(
        unary, missing, candidates, rel_terms, plane_log_extra, desc, more
    )

    constraints: list[ConstraintValue] = []
    factors: dict[str, dict[str, float]] = {}
    for p, part in enumerate(cls.parts):
        plane = best_assign[p]
        groups = {"Or": 1.0, "He": 1.0, "De": 1.0, "Pr": 1.0}
        if plane is None:
            groups["missing"] = missing[p]
            constraints.append(ConstraintValue(part.name, "missing", "De", None, None, missing[p]))
        else:
            for feature, g in part.constraints.items():
                group = FEATURES["part"][feature].group
                value = _part_value(desc, plane, feature)
                if math.isnan(value):  # not measured: no factor
                    constraints.append(ConstraintValue(part.name, feature, group, None, g, 1.0))
                    continue
                f = float(g(value))
                groups[group] *= f
                constraints.append(ConstraintValue(part.name, feature, group, value, g, f))
        factors[part.name] = groups
    for a, b, rel in rel_terms:
        ia, ib = best_assign[a], best_assign[b]
        if ia is None or ib is None:
            continue
        name = f"{rel.a}~{rel.b}"
        for feature, g in rel.constraints.items():
            value = _relation_feature(desc, ia, ib, feature)
            if math.isnan(value):  # not measured: no factor
                constraints.append(ConstraintValue(name, feature, "Pr", None, g, 1.0))
                continue
            f = float(g(value))
            factors[rel.b]["Pr"] *= f
            constraints.append(ConstraintValue(name, feature, "Pr", value, g, f))
    cluster_log = 0.0
    cluster_factor = 1.0
    used = {c for c in best_assign if c is not None}
    used = used.union(*(more[p][c] for p, c in enumerate(best_assign) if c is not None))
    unexplained = [
        k for k, plane in enumerate(desc.planes) if k not in used and not is_patch(plane)
    ]
    if unexplained and (cls.extra_plane < 1.0 or cls.extra_surface is not None):
        f = math.exp(float(sum(plane_log_extra[k] for k in unexplained)))
        cluster_factor *= f
        constraints.append(
            ConstraintValue("cluster", "extra_plane", "cluster", float(len(unexplained)), None, f)
        )
    for feature, g in cls.cluster.constraints.items():
        value = _cluster_feature(desc, feature)
        log = cluster_log_factor(g, desc, feature)
        f = math.exp(log)
        cluster_log += log
        cluster_factor *= f
        measured = None if math.isnan(value) else value
        constraints.append(ConstraintValue("cluster", feature, "cluster", measured, g, f))
    for groups in factors.values():
        groups["def"] = math.prod(groups.values())
    factors["cluster"] = {"def": cluster_factor}
    assignment = {part.name: best_assign[p] for p, part in enumerate(cls.parts)}
    return ClassScore(
        # best_log already holds the extra-plane penalty; the cluster rules come on top.
        name=cls.name,
        group=cls.variant_of,
        log_likelihood=best_log + cluster_log,
        log_prior=log_prior,
        assignment=assignment,
        factors=factors,
        constraints=tuple(constraints),
    )


def score_cluster(
    desc: ClusterDescription,
    ontology: Ontology,
    priors: Mapping[str, float] | None = None,
    *,
    none_likelihood: float = 0.05,
    none_prior: float = 1.0,
) -> ClusterScores:
    """Score a cluster against every class and normalise over the classes and "none".

    Parameters
    ----------
    desc : ClusterDescription
        The cluster's planes, relations and extent.
    ontology : Ontology
        The classes.
    priors : mapping of class name to P_obj, optional
        Environment priors (Eq. 3.5, 3.10); 1 for classes not given.
    none_likelihood : float
        Likelihood of the features under "none of the classes": a class must
        explain the cluster better than this to take most of the probability.
    none_prior : float
        Prior weight of "none".

    Returns
    -------
    ClusterScores
    """
    priors = priors or {}
    ontology.variant_groups()  # a variant_of that names no class is an error here
    scores = {}
    for cls in ontology.classes:
        prior = float(priors.get(cls.name, 1.0))
        scores[cls.name] = score_class(cls, desc, math.log(prior) if prior > 0 else -math.inf)
    return _posterior(scores, math.log(none_likelihood) + math.log(none_prior))


def _better(a: str, b: str, group: str, logs: Mapping[str, float]) -> bool:
    """Whether class ``a`` describes the cluster better than ``b`` (both of ``group``)."""
    if logs[a] != logs[b]:
        return logs[a] > logs[b]
    if (a == group) != (b == group):
        return a == group
    return a < b


def _posterior(scores: Mapping[str, ClassScore], none_log: float) -> ClusterScores:
    """P_obj|ont over the classes and "none" from each class's likelihood and prior.

    Classes that describe one thing two ways (``group``: a class's ``variant_of``) count
    once: the best of them (likelihood times prior) takes the posterior and the others
    none, so a second description cannot add probability to what both describe a little
    (the best description, not the sum of the descriptions; a tie goes to the class the
    others are variants of, then to the first name in alphabetical order).
    """
    logs = {k: s.log_likelihood + s.log_prior for k, s in scores.items()}
    best_of: dict[str, str] = {}
    for k, s in scores.items():
        group = s.group or k
        held = best_of.get(group)
        if held is None or _better(k, held, group, logs):
            best_of[group] = k
    for k, s in scores.items():
        if best_of[s.group or k] != k:
            logs[k] = -math.inf
    logs[NONE] = none_log
    top = max(logs.values())
    weights = {k: math.exp(v - top) if v > -math.inf else 0.0 for k, v in logs.items()}
    z = sum(weights.values())
    probs = {k: w / z for k, w in weights.items()}
    out = {k: dataclasses.replace(s, probability=probs[k]) for k, s in scores.items()}
    best = max(probs, key=lambda k: (probs[k], k != NONE))
    return ClusterScores(classes=out, probabilities=probs, best=best)


def with_priors(
    scores: ClusterScores,
    priors: Mapping[str, float],
    *,
    none_likelihood: float = 0.05,
    none_prior: float = 1.0,
) -> ClusterScores:
    """The same cluster's scores under other environment priors (1 for classes not given):
    the likelihoods are kept, only P_obj and the posterior change (Eq. 3.1).

    Examples
    --------
    >>> s = ClassScore("chair", math.log(0.5), 0.0, {}, {}, (), 0.0)
    >>> t = ClassScore("toilet", math.log(0.5), 0.0, {}, {}, (), 0.0)
    >>> flat = _posterior({"chair": s, "toilet": t}, math.log(0.05))
    >>> round(flat.probabilities["chair"], 3), round(flat.probabilities["toilet"], 3)
    (0.476, 0.476)
    >>> bath = with_priors(flat, {"chair": 0.1, "toilet": 1.9})
    >>> round(bath.probabilities["chair"], 3), round(bath.probabilities["toilet"], 3)
    (0.048, 0.905)
    """
    reprior = {}
    for name, s in scores.classes.items():
        prior = float(priors.get(name, 1.0))
        reprior[name] = dataclasses.replace(
            s, log_prior=math.log(prior) if prior > 0 else -math.inf
        )
    out = _posterior(reprior, math.log(none_likelihood) + math.log(none_prior))
    return dataclasses.replace(out, extra=dict(scores.extra))
