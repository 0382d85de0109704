"""The features an ontology file may constrain, registered by name (thesis Eq. 3.3).

Every feature is a :class:`Feature`: where it applies (a part, a pair of parts, the
whole cluster), how it is measured on a cluster, how a Gaussian on it scores, and the
smallest sigma calibration may fit to it. The schema accepts exactly the registered
names and the scoring looks each one up here, so a new feature is one
:func:`register_feature` call, never a branch in the scoring::

    register_feature(Feature("slope", "part", "Or", "...", plane=lambda p: float(p.slope)))

Part features are measured on one plane (``plane``) or, when they depend on the scene
around the cluster (whether the floor shows under a top), read from the cluster
description's per-plane scene measurements (``scene=True``, see
:attr:`~ontodetect.ontology.ClusterDescription.scene`): NaN there means not measured,
which costs nothing.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._gaussian import Gaussian

__all__ = [
    "CLUSTER_FEATURES",
    "FEATURES",
    "PART_FEATURES",
    "RELATION_FEATURES",
    "SCOPES",
    "Feature",
    "feature_registry",
    "is_patch",
    "patch_members",
    "register_feature",
    "sigma_floor",
]

#: Where a feature applies: a part (one plane), a relation (two parts) or the cluster.
SCOPES = ("part", "relation", "cluster")
#: A cluster whose top comes this close (m) to the top of the search volume may go on
#: above it (a cabinet or a shelf cut at the altitude cut-off) ...
CUT_MARGIN = 0.05
#: ... so its height is only known to be at least what is seen: its height factor is the
#: mean of the constraint over this span (m) above the seen top.
CUT_SPAN = 0.6
CUT_SAMPLES = 13
#: In a single view, a cluster that hides what stands behind it shows only its facing
#: side: its depth is only known to be at least what is seen, and may go on this far (m)
#: behind, a seat's depth; the shadow a hidden seat is sought in is as deep
#: (``segment._measure.SELF_SHADOW`` is this value).
HIDDEN_DEPTH = 0.3


@dataclass(frozen=True)
class Feature:
    """One feature of the ontology, found by its scope and name.

    Attributes
    ----------
    name : str
        The key in the ontology file.
    scope : {"part", "relation", "cluster"}
    group : str
        The factor of Eq. 3.3 a part feature belongs to (``Or``, ``He``, ``De``, ``Pr``);
        ``Pr`` for relations, ``cluster`` for cluster features.
    description : str
        What is measured, with its unit.
    sigma_floor : float
        Calibration fits no sigma below this (units of the feature).
    plane : callable, optional
        Part features: ``plane -> float``, the value on one plane.
    in_cluster : callable, optional
        Part features measured on a plane within its cluster: ``(desc, i) -> float``
        for plane ``i`` of the cluster description ``desc``.
    scene : bool
        Part features: the value comes from the cluster description's scene
        measurements (``desc.scene[name][i]``), not from the plane.
    relation : callable, optional
        Relation features: ``(desc, i, j) -> float`` for planes ``i`` (part a), ``j`` (b).
    cluster : callable, optional
        Cluster features: ``desc -> float``.
    log_factor : callable, optional
        ``(gaussian, desc, value) -> float``, the log-factor when it is not
        ``gaussian.log(value)`` (a censored measurement).
    """

    name: str
    scope: str
    group: str
    description: str
    sigma_floor: float = 0.0
    plane: Callable[[Any], float] | None = None
    in_cluster: Callable[[Any, int], float] | None = None
    scene: bool = False
    relation: Callable[[Any, int, int], float] | None = None
    cluster: Callable[[Any], float] | None = None
    log_factor: Callable[[Gaussian, Any, float], float] | None = None

    def __post_init__(self) -> None:
        if self.scope not in SCOPES:
            raise ValueError(f"scope must be one of {SCOPES}, got {self.scope!r}")
        measures = {
            "part": self.plane is not None or self.in_cluster is not None or self.scene,
            "relation": self.relation is not None,
            "cluster": self.cluster is not None,
        }
        if not measures[self.scope]:
            raise ValueError(f"feature {self.name!r}: a {self.scope} feature needs a measure")


#: The registry: scope -> name -> Feature.
FEATURES: dict[str, dict[str, Feature]] = {scope: {} for scope in SCOPES}


def register_feature(feature: Feature, *, replace: bool = False) -> Feature:
    """Add a feature to the registry (``replace`` to redefine an existing one)."""
    table = FEATURES[feature.scope]
    if feature.name in table and not replace:
        raise ValueError(f"a {feature.scope} feature named {feature.name!r} is registered")
    table[feature.name] = feature
    return feature


def feature_registry(scope: str | None = None) -> Mapping[str, Any]:
    """The registered features: ``{scope: {name: Feature}}``, or one scope's ``{name: Feature}``.

    Examples
    --------
    >>> feature_registry("part")["tilt"].group
    'Or'
    >>> feature_registry("cluster")["height"].sigma_floor
    0.02
    """
    if scope is None:
        return FEATURES
    return FEATURES[scope]


def sigma_floor(name: str) -> float:
    """The smallest sigma calibration may fit to a feature of this name (0 if none).

    A name used in several scopes (``height`` of a part and of a cluster) has one floor.
    """
    return max((t[name].sigma_floor for t in FEATURES.values() if name in t), default=0.0)


# -- measures --------------------------------------------------------------------------------


def patch_members(plane: Any) -> tuple[int, ...]:
    """The planes a curved patch (``segment.planes.Patch``) joins; ``()`` for a plane."""
    return tuple(getattr(plane, "members", ()))


def is_patch(plane: Any) -> bool:
    """Whether ``plane`` is a patch (``segment.planes.Patch``: a curved surface, a lying
    surface, a seat's level layer) rather than one of the cluster's MSAC planes."""
    return getattr(plane, "kind", None) is not None


def _fill(plane: Any) -> float:
    box = float(plane.length) * float(plane.width)
    return float(plane.area) / box if box > 0 else 0.0


def _attribute(name: str) -> Callable[[Any], float]:
    return lambda obj: float(getattr(obj, name))


def _relation_attribute(name: str, absent: float) -> Callable[[Any, int, int], float]:
    def measure(desc: Any, i: int, j: int) -> float:
        rel = desc.relations.get((min(i, j), max(i, j)))
        return absent if rel is None else float(getattr(rel, name))

    return measure


def _gap(desc: Any, i: int, j: int) -> float:
    return float(desc.planes[j].centroid[2] - desc.planes[i].centroid[2])


def _over(desc: Any, i: int, j: int) -> float:
    return float(desc.planes[j].z_max - desc.planes[i].z_max)


#: A plane whose normal leans less than this from vertical (the sine of 17 degrees from
#: horizontal) has no front and back: ``behind`` is 0 for it.
_FACING = 0.3


def _facing(plane: Any) -> tuple[NDArray[np.float64], float] | None:
    """The horizontal part of a plane's normal and its length, when the plane faces
    sideways (the length at least ``_FACING``); ``None`` for a level one."""
    normal = np.asarray(plane.normal, dtype=float)[:2]
    size = float(np.hypot(*normal))
    return (normal, size) if size >= _FACING else None


def _step(a: Any, b: Any) -> NDArray[np.float64]:
    """From a's centroid to b's, horizontally."""
    return np.asarray(b.centroid, dtype=float)[:2] - np.asarray(a.centroid, dtype=float)[:2]


def _behind(desc: Any, i: int, j: int) -> float:
    """How far (m) b's centroid lies behind plane a, horizontally along a's outward normal
    (a backrest's normal points away from its seat): negative in front of it."""
    a, b = desc.planes[i], desc.planes[j]
    facing = _facing(a)
    if facing is None:
        return 0.0
    normal, size = facing
    return float(normal @ _step(a, b)) / size


def _aside(desc: Any, i: int, j: int) -> float:
    """How far (m) the two centroids lie apart along the upright one of the two planes
    (a's if it faces sideways, else b's), horizontally and across its normal: 0 when b
    stands centred before or behind a, as a backrest on its seat's middle line."""
    a, b = desc.planes[i], desc.planes[j]
    facing = _facing(a) or _facing(b)
    if facing is None:
        return 0.0
    normal, size = facing
    along = np.array([-normal[1], normal[0]]) / size
    return abs(float(along @ _step(a, b)))


#: A level plane has a long axis when it is at least this many times longer than wide
#: (a mattress is twice as long as wide; one cushion of a sofa's seat is about square).
_LONG = 1.25


def _level_upright(desc: Any, i: int, j: int) -> tuple[Any, Any] | None:
    """Planes ``i`` and ``j`` as (the level one, the upright one), whichever comes first;
    None unless one leans less than 45 degrees from level and the other more."""
    a, b = desc.planes[i], desc.planes[j]
    if float(a.tilt) > float(b.tilt):
        a, b = b, a
    if float(a.tilt) > 45.0 or float(b.tilt) < 45.0:
        return None
    return a, b


def _across(desc: Any, i: int, j: int) -> float:
    """Angle (degrees, 0..90) between the long axis of the level plane of the two and the
    horizontal run of the upright one: 0 for a sofa's back along its seat, 90 for a bed's
    headboard across the end of its mattress; 0 unless one is level and the other upright,
    NaN (not measured) when the level one has no long axis or comes without its axes."""
    pair = _level_upright(desc, i, j)
    if pair is None:
        return 0.0
    a, b = pair
    axes = getattr(a, "axes", None)
    if axes is None or float(a.length) < _LONG * float(a.width):
        return math.nan  # no long axis to speak of (one cushion of a sofa), or none given
    long = np.asarray(axes, dtype=float)[0][:2]
    facing = _facing(b)
    if facing is None or float(np.hypot(*long)) < 1e-9:
        return 0.0
    normal, _ = facing
    run = np.array([-normal[1], normal[0]])
    cos = abs(float(long @ run)) / (float(np.hypot(*long)) * float(np.hypot(*run)))
    return math.degrees(math.acos(min(1.0, cos)))


def _span(desc: Any, i: int, j: int) -> float:
    """How much of the level plane's extent the upright one spans, along the upright one's
    horizontal run: the run's extent of each (a plane's rectangle, ``length`` along
    ``axes[0]`` and ``width`` along ``axes[1]``, projected on the run), the upright's over
    the level's. About 1 for a cabinet's front under its top; a third for a desk's drawer
    pedestal under a desk's top. NaN (not measured) unless one is level and the other
    upright, or when a plane comes without its axes."""
    pair = _level_upright(desc, i, j)
    if pair is None:
        return math.nan
    a, b = pair
    if getattr(a, "axes", None) is None or getattr(b, "axes", None) is None:
        return math.nan
    facing = _facing(b)
    if facing is None:
        return math.nan
    normal, size = facing
    run = np.array([-normal[1], normal[0], 0.0]) / size

    def extent(plane: Any) -> float:
        axes = np.asarray(plane.axes, dtype=float)
        return float(plane.length) * abs(float(axes[0] @ run)) + float(plane.width) * abs(
            float(axes[1] @ run)
        )

    level = extent(a)
    return math.nan if level <= 0.0 else extent(b) / level


def _rise_above(desc: Any, i: int) -> float:
    """Height of the cluster above the highest inlier of plane ``i`` (m, at least 0)."""
    return max(0.0, float(desc.height) - float(desc.planes[i].z_max))


def _at_least(g: Gaussian, value: float, span: float) -> float:
    """Log of the mean of ``g`` over ``[value, value + span]``: the factor of a measure
    only known to be at least ``value``, and at most ``span`` more."""
    logs = np.asarray(g.log(np.linspace(value, value + span, CUT_SAMPLES)), dtype=np.float64)
    return _logsumexp(logs) - math.log(CUT_SAMPLES)


def _logsumexp(a: NDArray[np.float64]) -> float:
    """``log(sum(exp(a)))`` of a 1-D array, as ``scipy.special.logsumexp`` computes it (the
    largest terms taken out of the sum for precision, the direct sum where that is not
    finite), to the last bit, without its array-API dispatch (about ten times the cost
    of the arithmetic on the 13 values a censored measure sums, thousands of times a scan)."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        top = float(a.max())
        is_top = a == top
        m = float(np.count_nonzero(is_top))
        s = float(np.exp(np.where(is_top, -np.inf, a) - top).sum())
        if s != 0.0:
            s /= m
        out = float(np.log1p(s) + np.log(m) + top)
        if not math.isfinite(out):
            out = float(np.log(np.exp(a).sum()))
    return out


def _censored_height(g: Gaussian, desc: Any, value: float) -> float:
    """The height of a cluster that reaches the altitude cut-off is only known to be at
    least what is seen: the mean of the Gaussian over ``CUT_SPAN`` above it."""
    if not desc.cut:
        return float(g.log(value))
    return _at_least(g, value, CUT_SPAN)


def _censored_breadth(g: Gaussian, desc: Any, value: float) -> float:
    """In a single view, a cluster that hides from the sensor what stands behind it (its
    ``hidden_below`` above its bottom: a backrest seen from behind, its seat behind it)
    shows only its facing side, so its breadth is only known to be at least what is seen:
    the mean of the Gaussian over ``HIDDEN_DEPTH`` more. Elsewhere the breadth as seen."""
    if not float(desc.hidden_below) > float(desc.bottom):
        return float(g.log(value))
    return _at_least(g, value, HIDDEN_DEPTH)


# The sigma floors are calibration's absolute floors (units of the feature: m, degrees,
# m², ratios), chosen for the resolution of the measurements; ``density`` and ``points``
# depend on the sensor and have none.
for _feature in (
    Feature(
        "tilt", "part", "Or", "degrees between the plane's normal and vertical: 0 = horizontal",
        1.0, plane=_attribute("tilt"),
    ),
    Feature("height", "part", "He", "centroid height above the floor (m)", 0.02,
            plane=_attribute("height")),
    Feature("top", "part", "He", "highest inlier above the floor (m)", 0.02,
            plane=_attribute("z_max")),
    Feature("bottom", "part", "He", "lowest inlier above the floor (m)", 0.02,
            plane=_attribute("z_min")),
    Feature("rise", "part", "He",
            "height of the cluster above the plane's highest inlier (m): nothing rises "
            "above a cabinet's top", 0.02, in_cluster=_rise_above),
    Feature("length", "part", "Pr", "extent along the plane's major axis (m)", 0.03,
            plane=_attribute("length")),
    Feature("width", "part", "Pr", "extent along its minor axis (m)", 0.03,
            plane=_attribute("width")),
    Feature("area", "part", "Pr", "covered area (m²)", 0.01, plane=_attribute("area")),
    Feature("spread", "part", "Or",
            "spread of the surface's normals (degrees, area-weighted RMS): 0 for a plane, "
            "more for a curved patch (planes.curved)", 1.0,
            plane=lambda p: float(getattr(p, "spread", 0.0))),
    Feature("fill", "part", "De", "covered area / (length × width): how solid the patch is",
            0.03, plane=_fill),
    Feature("density", "part", "De", "points per m² (depends on the sensor)",
            plane=_attribute("density")),
    Feature("points", "part", "De", "inlier count (depends on the sensor)",
            plane=_attribute("num_points")),
    # Open below (a top on legs) or closed (a cabinet, a bed, a box hide the floor under
    # them). Measured by detect for horizontal planes; unknown elsewhere, costing nothing.
    Feature("open_below", "part", "Pr",
            "share of the plane's footprint under which the floor was seen (0..1)", 0.03,
            scene=True),
    # A closed top hides what is under it (a cabinet); a seat seen inside the U of an
    # armchair's arms and back top was seen through it. Measured by detect from the
    # cluster's own planes.
    Feature("seen_below", "part", "Pr",
            "share of a horizontal plane's outline over which a lower horizontal plane of "
            "the cluster was seen (0..1)", 0.03, scene=True),
    # Nothing of a chair stands over its seat; a desk's top covers the pedestal under it.
    Feature("covered", "part", "Pr",
            "share of a horizontal plane's outline over which a higher horizontal plane of "
            "the cluster was seen (0..1)", 0.03, scene=True),
    # A basin's bowl is sunk in its rim; a table's top is a plate over knee space and a
    # cabinet's is closed. Measured by detect from the cluster's points, so a curved bowl
    # that makes no plane still counts.
    Feature("sunk", "part", "Pr",
            "share of a horizontal plane's outline over which the cluster lies 4-25 cm "
            "under it, its level planes left out (0..1)", 0.03, scene=True),
    # A seat ends where its chair ends: a level surface that goes on at its height into the
    # next cluster is the rest of a bench or a sofa.
    Feature("runs_on", "part", "Pr",
            "length of the longest level plane of another cluster that goes on from this "
            "level plane at its height, touching it (m; 0 when none)", 0.03, scene=True),
    Feature("angle", "relation", "Pr", "angle between the normals, folded to [0, 90] degrees",
            2.0, relation=_relation_attribute("angle", 0.0)),
    Feature("distance", "relation", "Pr",
            "closest distance between the two planes' points (m)", 0.01,
            relation=_relation_attribute("distance", math.inf)),
    Feature("gap", "relation", "Pr", "height of b's centroid minus a's (m)", 0.02,
            relation=_gap),
    Feature("over", "relation", "Pr", "height of b's highest point minus a's (m)", 0.02,
            relation=_over),
    Feature("behind", "relation", "Pr",
            "horizontal distance of b's centroid behind plane a, along a's outward normal "
            "(m; negative in front of it)", 0.02, relation=_behind),
    Feature("across", "relation", "Pr",
            "angle between the long axis of the level plane and the run of the upright "
            "one (degrees, 0..90): 0 for a sofa's back along its seat; not measured on a "
            "level plane less than 1.25 times longer than wide", 1.0,
            relation=_across),
    Feature("span", "relation", "Pr",
            "share of the level plane's extent the upright one spans along its horizontal "
            "run: about 1 for a cabinet's front under its top, a third for a desk's drawer "
            "pedestal; not measured unless one is level and the other upright", 0.03,
            relation=_span),
    Feature("aside", "relation", "Pr",
            "horizontal distance between the centroids along the upright plane of the two, "
            "across its normal (m): 0 for a backrest centred on its seat", 0.02,
            relation=_aside),
    Feature("overlap", "relation", "Pr",
            "share of the smaller footprint the two overlap in the xy plane (0..1)", 0.03,
            relation=_relation_attribute("xy_overlap", 0.0)),
    Feature("length", "cluster", "cluster", "longest horizontal side of the upright box (m)",
            0.03, cluster=_attribute("length")),
    Feature("breadth", "cluster", "cluster", "shortest horizontal side of the upright box (m)",
            0.03, cluster=_attribute("breadth"), log_factor=_censored_breadth),
    Feature("height", "cluster", "cluster", "top of the cluster above the floor (m)", 0.02,
            cluster=_attribute("height"), log_factor=_censored_height),
    Feature("bottom", "cluster", "cluster", "lowest point above the floor (m)", 0.02,
            cluster=_attribute("bottom")),
    Feature("planes", "cluster", "cluster", "number of planes found in the cluster", 0.5,
            cluster=lambda desc: float(sum(not is_patch(p) for p in desc.planes))),
    Feature("rise", "cluster", "cluster",
            "height of the cluster above its highest horizontal plane (m): a backrest rises "
            "above a seat, nothing rises above a cabinet top", 0.02,
            cluster=_attribute("rise")),
    # What hangs on a wall (a radiator on its brackets) stands within a few centimetres of
    # it. Measured from the voxels the preparation took as wall; not where none was found.
    Feature("wall_gap", "cluster", "cluster",
            "horizontal distance from the cluster to the nearest wall voxel (m); not "
            "measured in a scan with no wall", 0.02,
            cluster=_attribute("wall_gap")),
):  # fmt: skip
    register_feature(_feature)
del _feature


class _View(Mapping[str, str]):
    """A live ``name -> text`` view of one scope of the registry."""

    def __init__(self, scope: str, what: Callable[[Feature], str]) -> None:
        self._scope, self._what = scope, what

    def __getitem__(self, name: str) -> str:
        return self._what(FEATURES[self._scope][name])

    def __iter__(self):
        return iter(FEATURES[self._scope])

    def __len__(self) -> int:
        return len(FEATURES[self._scope])

    def __repr__(self) -> str:
        return repr(dict(self))


#: Part features and the factor of Eq. 3.3 each belongs to (a view of the registry).
PART_FEATURES: Mapping[str, str] = _View("part", lambda f: f.group)
#: Relation features ``between: [a, b]`` and what they measure.
RELATION_FEATURES: Mapping[str, str] = _View("relation", lambda f: f.description)
#: Cluster features and what they measure.
CLUSTER_FEATURES: Mapping[str, str] = _View("cluster", lambda f: f.description)
