"""Ontology files: YAML in, validated :class:`Ontology` out, errors with file, line and key.

The format is documented in ``docs/ontology.md``. In short::

    format: ontodetect.ontology/1
    classes:
      chair:
        prior: {rooms: seating}
        cluster: {length: [0.3, 1.2], planes: {min: 2}}
        parts:
          seat: {required: true, tilt: {max: 6}, height: [0.35, 0.75]}
          backrest: {tilt: {mean: 80, sigma: 12}}
        relations:
          - {between: [seat, backrest], angle: [60, 90], distance: {max: 0.1}}
        labeling: {plane_size: {mean: 0.45, sigma: 0.2}}
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping, Sequence, Set
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import yaml

from ..errors import InvalidOntologyError, InvalidParameterError, ReadError
from ..io._textfile import read_text
from ..io._yaml import CSafeYamlLoader, SafeYamlLoader, YamlError, describe_yaml_error
from ._features import CLUSTER_FEATURES, PART_FEATURES, RELATION_FEATURES
from ._gaussian import Gaussian
from ._places import room_table_names

__all__ = [
    "CAD_ROLES",
    "CLUSTER_FEATURES",
    "FORMAT",
    "PART_FEATURES",
    "RELATION_FEATURES",
    "Attach",
    "ClusterRule",
    "LabelModel",
    "LowSeed",
    "ObjectClass",
    "Ontology",
    "Part",
    "Relation",
    "SeedStyle",
    "parse_ontology",
    "read_ontology_file",
]

FORMAT = "ontodetect.ontology/1"

#: What a part may tell CAD fitting (a part's ``cad``): the seat (its height and centre,
#: and with the backrest the front), the backrest, the top.
CAD_ROLES = ("seat", "back", "top")
#: The features of a seed part that say what size of patch may seed in its style.
SEED_SIZE = ("height", "length", "width")
#: Factor used for a part that has no plane when the file does not say.
DEFAULT_MISSING = {True: 0.02, False: 0.3}


@dataclass(frozen=True)
class Part:
    """A planar part of an object class and the Gaussians on its features."""

    name: str
    constraints: Mapping[str, Gaussian]
    required: bool = True
    missing: float = 0.02
    #: Factor for no plane when the part is hidden below the cluster's visible bottom
    #: (a seat behind a desk); ``None``: the same as ``missing``.
    occluded: float | None = None
    #: Name of the seed style (the ontology's ``seeds``) with which a horizontal patch at
    #: this part's height seeds part-driven segmentation; ``None``: not a seed.
    seed: str | None = None
    #: What the part tells CAD fitting: ``seat``, ``back`` or ``top`` (:data:`CAD_ROLES`);
    #: ``None``: nothing.
    cad: str | None = None
    #: Heights (m) where CAD fitting looks for this part in the object's points;
    #: ``None``: the ends of its ``height`` constraint.
    cad_search: tuple[float, float] | None = None
    #: A ``back`` part: CAD fitting takes the points this far (m) above the seat as it.
    cad_above_seat: float | None = None
    #: A top: the upright planes under its outline that do not rise above it (legs,
    #: panels, a pedestal) hold it up, and the plane that takes it explains them.
    supports: bool = False
    #: It may take a lying surface (``planes.level_surfaces``: level pieces of one surface
    #: at one height, a made bed's duvet and pillows) as well as a plane.
    lying: bool = False
    #: It may take a seat's level layer (``planes.seat_layer``: the upward-facing points at
    #: seat height of a cushion MSAC did not fit as a plane) as well as a plane.
    layer: bool = False

    @property
    def height_span(self) -> tuple[float, float] | None:
        """Lowest and highest height its ``height`` constraint allows with a factor of at
        least exp(-1/2): a range's ends, a plateau's or one bound's (the other infinite)."""
        g = self.constraints.get("height")
        if g is None:
            return None
        if g.side == "plateau":
            return g.mean, float(g.upper)  # type: ignore[arg-type]
        if g.side == "min":
            return g.mean, math.inf
        if g.side == "max":
            return -math.inf, g.mean
        return g.mean - g.sigma, g.mean + g.sigma


@dataclass(frozen=True)
class Relation:
    """Constraints between two parts ``a`` and ``b``."""

    a: str
    b: str
    constraints: Mapping[str, Gaussian]


@dataclass(frozen=True)
class NearRule:
    """Another object this class stands beside (a relation between objects, the thesis's
    exteroceptive constraints): a nightstand beside a bed.

    ``distance`` scores the horizontal gap between the two footprints (m); the factor a
    cluster gets is the best, over the other clusters, of their probability of being
    ``target`` times that score, and at least ``missing`` (what having no such object
    beside it costs)."""

    target: str
    distance: Gaussian
    missing: float


@dataclass(frozen=True)
class Attach:
    """Which narrow horizontal parts a little above a seed join it (armrests, back tops).

    Attributes
    ----------
    rise : (float, float)
        Heights (m) above the seed where armrests and back tops stand.
    width : float
        Widest (m) an armrest may be (the widest disc inside it).
    margin : float
        How far (m) outside the seed's outline an armrest may stand ...
    share : float
        ... with at least this share of it.
    back_reach : float
        How far (m) behind the seed the flat top of a thick backrest may stand.
    back_overhang : float
        How much (m) longer than the seed a back top may be.
    back_span : float
        Shortest back top, as a share of the seed's length.
    back_seat_length : float
        Shortest seed (m) that can have a back top (upholstered sofas).
    back_top : float
        Highest (m above the floor) a back top may be.
    outer_margin : float
        Around the parts that joined, the seed's object reaches only this far (m) beyond
        the gaps of a sparse scan: their outer faces drop straight to the floor.
    """

    rise: tuple[float, float]
    width: float
    margin: float
    share: float
    back_reach: float
    back_overhang: float
    back_span: float
    back_seat_length: float
    back_top: float
    outer_margin: float


@dataclass(frozen=True)
class LowSeed:
    """How the cluster of a low seed (a seat found as a dense patch) takes in fragments.

    Attributes
    ----------
    up_to : float
        Seeds no higher than this (m) take fragments within ``margin`` of what they
        claimed at their own height and close to the box of their whole cluster.
    level : float
        Voxels this close (m) to the seed's height are the seat as scanned.
    margin : float
        How far (m) from that the fragments may lie.
    """

    up_to: float
    level: float
    margin: float


@dataclass(frozen=True)
class SeedStyle:
    """How a horizontal part that seeds segmentation claims the rest of its object.

    Attributes
    ----------
    name : str
    margin : float
        How far (m) outside the part's outline its object may reach.
    rise : float
        How high (m) above the part its object may reach.
    outside_cost : float
        Extra path length per metre a voxel lies outside the outline.
    inside_above : bool
        Above the part only what lies inside its outline is the object's (a table:
        a backrest beside its edge is something else).
    attach : Attach or None
        Narrow parts a little above it that join it (a seat's armrests); ``None``: none.
    low : LowSeed or None
        How a low seed's cluster takes in fragments beyond its prism; ``None``: it does not.
    """

    name: str
    margin: float
    rise: float
    outside_cost: float
    inside_above: bool = False
    attach: Attach | None = None
    low: LowSeed | None = None


@dataclass(frozen=True)
class ClusterRule:
    """Constraints on the whole cluster."""

    constraints: Mapping[str, Gaussian] = field(default_factory=dict)


@dataclass(frozen=True)
class LabelModel:
    """Discriminative features of a label for the energy (Eq. 3.8): colour and plane size."""

    color: tuple[tuple[float, float, float], float] | None = None
    plane_size: Gaussian | None = None


@dataclass(frozen=True)
class ObjectClass:
    """One class of the ontology: parts, relations, cluster rules, labelling model, prior."""

    name: str
    label: str
    description: str
    parts: tuple[Part, ...]
    relations: tuple[Relation, ...]
    cluster: ClusterRule
    labeling: LabelModel
    prior_rooms: str | Mapping[str, float] | None = None
    prior_indoor: float | None = None
    prior_outdoor: float | None = None
    detect: bool = True
    matches: tuple[str, ...] = ()
    extra_plane: float = 1.0
    #: Factor for an unexplained large horizontal plane (a second surface, not clutter);
    #: ``None``: the same as ``extra_plane``.
    extra_surface: float | None = None
    #: Classes near which this one is more likely (the labelling's context term: a chair
    #: near a table).
    context: tuple[str, ...] = ()
    #: Objects this class stands beside (:class:`NearRule`), scored once every cluster of
    #: the scene has been (``ontology.score_near``).
    near: tuple[NearRule, ...] = ()
    #: Bounds of the factor CAD fitting may stretch a model's footprint by to the object's
    #: measured seat or top; ``None``: the footprint keeps its generic size.
    cad_scale: tuple[float, float] | None = None
    #: The class this one describes another way (an easy chair is a chair): the two share
    #: a label and a cluster takes the better of the two descriptions, so that a thing
    #: described twice is not made likelier (``ontology.score_cluster``); ``None``: none.
    variant_of: str | None = None
    #: Whether the class was written to compete (``detect: false`` in its file) rather than
    #: be reported; :meth:`Ontology.reporting` keeps it when it reports more. ``None``: as
    #: ``not detect``. A competing class may explain a cluster away (``labeling``).
    written_competing: bool | None = None

    @property
    def competing(self) -> bool:
        """The class was written to compete for clusters, not to be reported (``detect:
        false`` in its file), whatever :meth:`Ontology.reporting` reports now."""
        return (not self.detect) if self.written_competing is None else self.written_competing

    def part(self, name: str) -> Part:
        for p in self.parts:
            if p.name == name:
                return p
        raise KeyError(name)


@dataclass(frozen=True)
class Ontology:
    """A set of object classes, in file order."""

    classes: tuple[ObjectClass, ...]
    source: str | None = None
    #: Seed styles by name (the file's ``seeds``).
    seeds: Mapping[str, SeedStyle] = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        return [c.name for c in self.classes]

    def __getitem__(self, name: str) -> ObjectClass:
        for c in self.classes:
            if c.name == name:
                return c
        raise KeyError(name)

    def __contains__(self, name: object) -> bool:
        return any(c.name == name for c in self.classes)

    def variant_groups(self) -> dict[str, str]:
        """For every class, the class whose descriptions it competes among: its
        ``variant_of``, or itself.

        Raises
        ------
        InvalidOntologyError
            A ``variant_of`` that names no class of the ontology, a variant of a variant,
            or a variant whose label is not its class's.

        Examples
        --------
        >>> onto = parse_ontology('''
        ... format: ontodetect.ontology/1
        ... classes:
        ...   chair: {parts: {seat: {height: [0.35, 0.75]}}}
        ...   easy_chair: {variant_of: chair, parts: {seat: {height: [0.33, 0.48]}}}
        ...   sofa: {parts: {seat: {height: [0.3, 0.55]}}}
        ... ''')
        >>> groups = onto.variant_groups()
        >>> groups["easy_chair"], groups["chair"], groups["sofa"], onto["easy_chair"].label
        ('chair', 'chair', 'sofa', 'chair')
        """
        out = {}
        for c in self.classes:
            target = c.variant_of
            if target is None:
                out[c.name] = c.name
                continue
            key = f"classes.{c.name}.variant_of"
            if target not in self:
                raise InvalidOntologyError(
                    self.source,
                    f"class {c.name!r} is a variant of {target!r}, which is no class of the "
                    f"ontology ({', '.join(self.names)})",
                    key=key,
                )
            main = self[target]
            if main.variant_of is not None:
                raise InvalidOntologyError(
                    self.source,
                    f"class {c.name!r} is a variant of {target!r}, itself a variant of "
                    f"{main.variant_of!r}: name {main.variant_of!r}",
                    key=key,
                )
            if main.label != c.label:
                raise InvalidOntologyError(
                    self.source,
                    f"class {c.name!r} is a variant of {target!r} but its label {c.label!r} "
                    f"is not {target!r}'s ({main.label!r})",
                    key=key,
                )
            out[c.name] = target
        return out

    def merged(self, other: Ontology) -> Ontology:
        """Classes of ``other`` replace same-named ones here; new ones are appended."""
        by_name = {c.name: c for c in self.classes}
        order = list(by_name)
        for c in other.classes:
            if c.name not in by_name:
                order.append(c.name)
            by_name[c.name] = c
        return Ontology(
            tuple(by_name[n] for n in order),
            other.source or self.source,
            {**self.seeds, **other.seeds},
        )

    def reporting(self, classes: str | Sequence[str] = "reported") -> Ontology:
        """The ontology with the classes a detection may carry set to report (``detect``).

        ``"reported"``: as written; ``"all"``: every class, the competing ones too; names
        (a list or a comma-separated string): just those, by class name or label. Which
        classes compete for a cluster does not change, only which win yields a detection.

        Examples
        --------
        >>> from ontodetect.ontology import builtin_ontology
        >>> onto = builtin_ontology().reporting("all")
        >>> onto["toilet"].detect, builtin_ontology()["toilet"].detect
        (True, False)
        >>> [c.name for c in builtin_ontology().reporting("chair,sink").classes if c.detect]
        ['chair', 'easy_chair', 'sink', 'basin']
        """
        if isinstance(classes, str):
            if classes == "reported":
                return self
            if classes == "all":
                wanted = None
            else:
                wanted = {n.strip() for n in classes.split(",") if n.strip()}
        else:
            wanted = set(classes)
        if wanted is not None:
            known = {c.name for c in self.classes} | {c.label for c in self.classes}
            unknown = sorted(wanted - known)
            if unknown:
                raise InvalidParameterError(
                    "detect.classes", f"class names of the ontology ({', '.join(self.names)})",
                    ",".join(unknown),
                )  # fmt: skip
        out = tuple(
            dataclasses.replace(
                c,
                detect=wanted is None or c.name in wanted or c.label in wanted,
                written_competing=c.competing,
            )
            for c in self.classes
        )
        return Ontology(out, self.source, self.seeds)

    def seed_styles(self) -> list[tuple[SeedStyle, float]]:
        """Every seed style with the highest height its seed parts allow, lowest first.

        A horizontal patch at height h takes the first style whose height reaches h,
        and the last one when none does (see ``docs/ontology.md``).
        """
        tops: dict[str, float] = {}
        for p in self._seed_parts():
            span = p.height_span
            top = math.inf if span is None else span[1]
            tops[p.seed] = max(tops.get(p.seed, -math.inf), top)
        return sorted(((self.seeds[k], v) for k, v in tops.items()), key=lambda t: t[1])

    def seed_sizes(self) -> dict[str, tuple[Mapping[str, Gaussian], ...]]:
        """For each seed style, the ``height``, ``length`` and ``width`` constraints of each
        part that seeds in it: what a horizontal patch of that style may measure (see
        ``cluster.seed_by_size`` and :func:`ontodetect.segment.seed_style`)."""
        out: dict[str, list[Mapping[str, Gaussian]]] = {}
        for p in self._seed_parts():
            size = {k: p.constraints[k] for k in SEED_SIZE if k in p.constraints}
            out.setdefault(p.seed, []).append(size)
        return {k: tuple(v) for k, v in out.items()}

    def _seed_parts(self) -> Iterator[Part]:
        """Every part marked ``seed``, class by class."""
        return (p for c in self.classes for p in c.parts if p.seed is not None)

    def context_pairs(self) -> frozenset[tuple[str, str]]:
        """Pairs of class names (both orders) that the context term rewards together."""
        out = set()
        for c in self.classes:
            for other in c.context:
                if other != c.name:
                    out |= {(c.name, other), (other, c.name)}
        return frozenset(out)

    def cad_parts(self, label: str) -> dict[str, str]:
        """Part name -> CAD role for the classes written under ``label``."""
        out: dict[str, str] = {}
        for c in self.classes:
            if c.label == label:
                for p in c.parts:
                    if p.cad is not None:
                        out.setdefault(p.name, p.cad)
        return out

    def cad_search(self, role: str, label: str | None = None) -> tuple[float, float] | None:
        """Heights (m) where CAD fitting looks for a part of ``role``: the union of the
        search heights of such parts of ``label``'s classes, or of every class when
        ``label``'s have none (``None`` when no class has one)."""
        for only in (label, None):
            spans = [
                p.cad_search or p.height_span
                for c in self.classes
                if only is None or c.label == only
                for p in c.parts
                if p.cad == role and (p.cad_search or p.height_span) is not None
            ]
            if spans:
                return min(s[0] for s in spans), max(s[1] for s in spans)  # type: ignore[index]
        return None

    def cad_above_seat(self, label: str | None = None) -> float | None:
        """How far (m) above the seat CAD fitting takes points as the backrest: the first
        ``back`` part of ``label``'s classes that says, else of any class (``None``: none)."""
        for only in (label, None):
            for c in self.classes:
                if only is None or c.label == only:
                    for p in c.parts:
                        if p.cad == "back" and p.cad_above_seat is not None:
                            return p.cad_above_seat
        return None

    def cad_scale(self, label: str) -> tuple[float, float] | None:
        """Footprint scale bounds for the models of ``label`` (its first class that has any)."""
        for c in self.classes:
            if c.label == label and c.cad_scale is not None:
                return c.cad_scale
        return None


# ------------------------------------------------------------------------------------------
# YAML with line numbers


class _Lines:
    """Remembers the line of every mapping key and sequence item, by path."""

    def __init__(self) -> None:
        self.at: dict[tuple[Any, ...], int] = {}

    def line(self, path: tuple[Any, ...]) -> int | None:
        while path:
            if path in self.at:
                return self.at[path]
            path = path[:-1]
        return self.at.get((), None)


def _construct(node: yaml.Node, path: tuple[Any, ...], lines: _Lines, loader: Any) -> Any:
    lines.at.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        out: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            key = loader.construct_object(key_node, deep=True)
            if key in out:
                line = key_node.start_mark.line + 1
                raise _Problem(path + (key,), f"duplicate key {key!r}", line)
            lines.at[path + (key,)] = key_node.start_mark.line + 1
            out[key] = _construct(value_node, path + (key,), lines, loader)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_construct(v, path + (i,), lines, loader) for i, v in enumerate(node.value)]
    return loader.construct_object(node, deep=True)


class _Problem(Exception):
    def __init__(self, path: tuple[Any, ...], message: str, line: int | None = None) -> None:
        super().__init__(message)
        self.path = path
        self.message = message
        self.line = line


def _load_yaml(
    text: str, source: str | None, loader_class: type[SafeYamlLoader] = SafeYamlLoader
) -> tuple[Any, _Lines]:
    lines = _Lines()
    try:
        loader = loader_class(text)
        try:
            node = loader.get_single_node()
            data = None if node is None else _construct(node, (), lines, loader)
        finally:
            loader.dispose()
    except YamlError as exc:
        raise InvalidOntologyError(source, exc.problem, line=exc.line) from exc
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        raise InvalidOntologyError(
            source,
            f"not valid YAML: {exc.problem or exc}",
            line=None if mark is None else mark.line + 1,
        ) from exc
    except yaml.YAMLError as exc:
        raise InvalidOntologyError(source, f"not valid YAML{describe_yaml_error(exc)}") from exc
    except _Problem as exc:
        raise InvalidOntologyError(
            source, exc.message, line=exc.line, key=_dotted(exc.path)
        ) from exc
    return data, lines


def _dotted(path: tuple[Any, ...]) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


# ------------------------------------------------------------------------------------------
# Validation


def _number(value: Any, path: tuple[Any, ...], what: str = "a number") -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _Problem(path, f"expected {what}, got {value!r}")
    return float(value)


def _gaussian(value: Any, path: tuple[Any, ...]) -> Gaussian:
    """``[a, b]``, ``{range: [a, b]}``, ``{mean, sigma}``, ``{min[, soft]}``, ``{max[, soft]}``."""
    shorthand = isinstance(value, list)
    if shorthand:
        value = {"range": value}
    if not isinstance(value, dict):
        raise _Problem(
            path,
            f"expected a range [low, high] or a mapping with mean/sigma, min or max, got {value!r}",
        )
    keys = set(value)
    try:
        if "range" in keys:
            _only(value, {"range"}, path)
            r = value["range"]
            rpath = path if shorthand else path + ("range",)
            if not isinstance(r, list) or len(r) != 2:
                raise _Problem(rpath, f"expected [low, high], got {r!r}")
            lo, hi = (_number(v, rpath + (i,)) for i, v in enumerate(r))
            if not hi > lo:
                raise _Problem(rpath, f"expected low < high, got [{lo:g}, {hi:g}]")
            return Gaussian.from_range(lo, hi)
        if "mean" in keys:
            _only(value, {"mean", "sigma"}, path)
            if "sigma" not in value:
                raise _Problem(path, "a mean needs a sigma")
            sigma = _number(value["sigma"], path + ("sigma",))
            if sigma <= 0:
                raise _Problem(path + ("sigma",), f"sigma must be > 0, got {sigma:g}")
            return Gaussian(_number(value["mean"], path + ("mean",)), sigma)
        if "min" in keys and "max" in keys:
            _only(value, {"min", "max", "soft"}, path)
            lo = _number(value["min"], path + ("min",))
            hi = _number(value["max"], path + ("max",))
            if not hi > lo:
                raise _Problem(path, f"expected min < max, got min {lo:g}, max {hi:g}")
            return Gaussian.plateau(lo, hi, *_softness(value, path, pair=True))
        for side, make in (("min", Gaussian.at_least), ("max", Gaussian.at_most)):
            if side in keys:
                _only(value, {side, "soft"}, path)
                soft, _ = _softness(value, path)
                return make(_number(value[side], path + (side,)), soft)
    except ValueError as exc:  # from Gaussian itself
        raise _Problem(path, str(exc)) from exc
    raise _Problem(
        path, f"expected one of range, mean/sigma, min, max, min+max; got keys {sorted(keys)}"
    )


def _softness(
    value: dict[str, Any], path: tuple[Any, ...], pair: bool = False
) -> tuple[float | None, float | None]:
    """A bound's ``soft``, each number > 0: ``(None, None)`` when not given, ``(s, None)``
    for one number and, for a plateau (``pair``), ``(below, above)`` for ``[below, above]``."""
    soft = value.get("soft")
    if soft is None:
        return None, None
    if pair and isinstance(soft, list):
        # [below, above]: each tail its own softness.
        if len(soft) != 2:
            raise _Problem(path + ("soft",), f"expected soft or [below, above], got {soft!r}")
        below, above = (_number(v, path + ("soft", i)) for i, v in enumerate(soft))
    else:
        below, above = _number(soft, path + ("soft",)), None
    if below <= 0 or (above is not None and above <= 0):
        raise _Problem(path + ("soft",), f"soft must be > 0, got {soft!r}")
    return below, above


def _only(mapping: dict[str, Any], allowed: set[str], path: tuple[Any, ...]) -> None:
    for key in mapping:
        if key not in allowed:
            raise _Problem(
                path + (key,), f"unknown key {key!r} (allowed: {', '.join(sorted(allowed))})"
            )


def _mapping(value: Any, path: tuple[Any, ...]) -> dict[str, Any]:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise _Problem(path, f"expected a mapping, got {type(value).__name__}")
    return value


def _constraints(
    spec: dict[str, Any], allowed: Mapping[str, str], path: tuple[Any, ...], skip: Set[str]
) -> dict[str, Gaussian]:
    out = {}
    for key, value in spec.items():
        if key in skip:
            continue
        if key not in allowed:
            raise _Problem(
                path + (key,),
                f"unknown feature {key!r} (allowed: {', '.join(sorted(set(allowed) | skip))})",
            )
        out[key] = _gaussian(value, path + (key,))
    return out


def _probability(
    spec: Mapping[str, Any], key: str, path: tuple[Any, ...], default: float | None = None
) -> float | None:
    """``spec[key]`` as a probability in (0, 1], or ``default`` when the key is absent."""
    value = spec.get(key, default)
    if value is None:
        return None
    value = _number(value, path + (key,), "a probability")
    if not 0.0 < value <= 1.0:
        raise _Problem(path + (key,), f"expected a probability in (0, 1], got {value:g}")
    return value


#: What a part may say besides its features' constraints.
PART_KEYS = frozenset(
    {"required", "missing", "occluded", "description", "seed", "cad", "supports", "lying", "layer"}
)


def _part(name: str, spec: Any, path: tuple[Any, ...], seeds: Mapping[str, Any]) -> Part:
    spec = _mapping(spec, path)
    required = spec.get("required", True)
    if not isinstance(required, bool):
        raise _Problem(path + ("required",), f"expected true or false, got {required!r}")
    missing = _probability(spec, "missing", path, DEFAULT_MISSING[required])
    occluded = _probability(spec, "occluded", path)
    supports, lying = spec.get("supports", False), spec.get("lying", False)
    layer = spec.get("layer", False)
    for key, value in (("supports", supports), ("lying", lying), ("layer", layer)):
        if not isinstance(value, bool):
            raise _Problem(path + (key,), f"expected true or false, got {value!r}")
    constraints = _constraints(
        spec,
        PART_FEATURES,
        path,
        PART_KEYS,
    )
    seed = spec.get("seed")
    if seed is not None:
        if not isinstance(seed, str) or not seed:
            raise _Problem(path + ("seed",), f"expected the name of a seed style, got {seed!r}")
        if seed not in seeds:
            known = ", ".join(sorted(seeds)) or "none"
            raise _Problem(path + ("seed",), f"no seed style named {seed!r} (seeds: {known})")
        height = constraints.get("height")
        if height is None or height.side == "min":
            raise _Problem(
                path + ("seed",), "a seed part needs a height constraint with an upper end"
            )
    cad, search, above = _cad_role(spec.get("cad"), path + ("cad",))
    return Part(
        name=name,
        constraints=constraints,
        required=required,
        missing=missing,
        occluded=occluded,
        seed=seed,
        cad=cad,
        cad_search=search,
        cad_above_seat=above,
        supports=supports,
        lying=lying,
        layer=layer,
    )


def _pair(value: Any, path: tuple[Any, ...], low: float = 0.0) -> tuple[float, float]:
    """``[a, b]`` with ``low <= a < b``."""
    if not isinstance(value, list) or len(value) != 2:
        raise _Problem(path, f"expected [low, high], got {value!r}")
    a, b = (_number(v, path + (i,)) for i, v in enumerate(value))
    if not low <= a < b:
        raise _Problem(path, f"expected {low:g} <= low < high, got [{a:g}, {b:g}]")
    return a, b


def _cad_role(
    value: Any, path: tuple[Any, ...]
) -> tuple[str | None, tuple[float, float] | None, float | None]:
    """A part's ``cad``: a role name, or ``{role: name, search: [low, high], above_seat: h}``."""
    if value is None:
        return None, None, None
    search = above = None
    role_path = path
    if isinstance(value, dict):
        _only(value, {"role", "search", "above_seat"}, path)
        if "search" in value:
            search = _pair(value["search"], path + ("search",))
        if "above_seat" in value:
            above = _positive(value, "above_seat", path)
        role_path = path + ("role",)
        value = value.get("role")
    if value not in CAD_ROLES:
        raise _Problem(role_path, f"expected one of {', '.join(CAD_ROLES)}, got {value!r}")
    if above is not None and value != "back":
        raise _Problem(path + ("above_seat",), "only a back part has a height above the seat")
    return value, search, above


def _positive(spec: Mapping[str, Any], key: str, path: tuple[Any, ...]) -> float:
    if key not in spec:
        raise _Problem(path, f"missing key {key!r}")
    value = _number(spec[key], path + (key,))
    if value <= 0:
        raise _Problem(path + (key,), f"expected a number > 0, got {value:g}")
    return value


def _attach(spec: Any, path: tuple[Any, ...]) -> Attach:
    spec = _mapping(spec, path)
    names = [
        "width",
        "margin",
        "share",
        "back_reach",
        "back_overhang",
        "back_span",
        "back_seat_length",
        "back_top",
        "outer_margin",
    ]
    _only(spec, {"rise", "description", *names}, path)
    if "rise" not in spec:
        raise _Problem(path, "missing key 'rise'")
    values = {k: _positive(spec, k, path) for k in names}
    for k in ("share", "back_span"):
        if values[k] > 1:
            raise _Problem(path + (k,), f"expected a share in (0, 1], got {values[k]:g}")
    return Attach(rise=_pair(spec["rise"], path + ("rise",)), **values)


def _seed_style(name: str, spec: Any, path: tuple[Any, ...]) -> SeedStyle:
    spec = _mapping(spec, path)
    keys = {"margin", "rise", "outside_cost", "inside_above", "attach", "low", "description"}
    _only(spec, keys, path)
    low = None
    if spec.get("low") is not None:
        lspec = _mapping(spec["low"], path + ("low",))
        _only(lspec, {"up_to", "level", "margin", "description"}, path + ("low",))
        low = LowSeed(*(_positive(lspec, k, path + ("low",)) for k in ("up_to", "level", "margin")))
    inside = spec.get("inside_above", False)
    if not isinstance(inside, bool):
        raise _Problem(path + ("inside_above",), f"expected true or false, got {inside!r}")
    return SeedStyle(
        name=name,
        margin=_positive(spec, "margin", path),
        rise=_positive(spec, "rise", path),
        outside_cost=_positive(spec, "outside_cost", path),
        inside_above=inside,
        attach=None if spec.get("attach") is None else _attach(spec["attach"], path + ("attach",)),
        low=low,
    )


def _relation(spec: Any, path: tuple[Any, ...], parts: set[str]) -> Relation:
    spec = _mapping(spec, path)
    between = spec.get("between")
    if (
        not isinstance(between, list)
        or len(between) != 2
        or not all(isinstance(b, str) for b in between)
    ):
        raise _Problem(path + ("between",), f"expected two part names, got {between!r}")
    for i, b in enumerate(between):
        if b not in parts:
            raise _Problem(
                path + ("between", i),
                f"no part named {b!r} in this class (parts: {', '.join(sorted(parts))})",
            )
    if between[0] == between[1]:
        raise _Problem(path + ("between",), "a relation needs two different parts")
    constraints = _constraints(spec, RELATION_FEATURES, path, {"between", "description"})
    return Relation(a=between[0], b=between[1], constraints=constraints)


def _near(spec: Any, path: tuple[Any, ...]) -> NearRule:
    spec = _mapping(spec, path)
    _only(spec, {"class", "distance", "missing", "description"}, path)
    target = spec.get("class")
    if not isinstance(target, str) or not target:
        raise _Problem(path + ("class",), f"expected a class name, got {target!r}")
    if "distance" not in spec:
        raise _Problem(path, "expected a distance: how far from it the object stands")
    missing = _probability(spec, "missing", path, 1.0)
    assert missing is not None
    return NearRule(target, _gaussian(spec["distance"], path + ("distance",)), missing)


def _labeling(spec: Any, path: tuple[Any, ...]) -> LabelModel:
    spec = _mapping(spec, path)
    _only(spec, {"color", "plane_size"}, path)
    color = None
    if "color" in spec:
        c = _mapping(spec["color"], path + ("color",))
        _only(c, {"mean", "sigma"}, path + ("color",))
        mean = c.get("mean")
        if not isinstance(mean, list) or len(mean) != 3:
            raise _Problem(path + ("color", "mean"), f"expected [r, g, b], got {mean!r}")
        rgb = tuple(_number(v, path + ("color", "mean", i)) for i, v in enumerate(mean))
        sigma = _number(c.get("sigma"), path + ("color", "sigma"))
        if sigma <= 0:
            raise _Problem(path + ("color", "sigma"), f"sigma must be > 0, got {sigma:g}")
        color = (rgb, sigma)  # type: ignore[assignment]
    size = _gaussian(spec["plane_size"], path + ("plane_size",)) if "plane_size" in spec else None
    return LabelModel(color=color, plane_size=size)  # type: ignore[arg-type]


def _prior(spec: Any, path: tuple[Any, ...]) -> tuple[Any, float | None, float | None]:
    spec = _mapping(spec, path)
    _only(spec, {"rooms", "indoor", "outdoor"}, path)
    rooms = spec.get("rooms")
    if isinstance(rooms, str) and rooms not in room_table_names():
        raise _Problem(
            path + ("rooms",),
            f"expected the name of a shipped table ({', '.join(room_table_names())}) "
            f"or a mapping room -> probability, got {rooms!r}",
        )
    if rooms is not None and not isinstance(rooms, str):
        rooms = _mapping(rooms, path + ("rooms",))
        for k, v in rooms.items():
            p = _number(v, path + ("rooms", k), "a probability")
            if not 0.0 <= p <= 1.0:
                raise _Problem(path + ("rooms", k), f"expected a probability in [0, 1], got {p:g}")
    out = []
    for key in ("indoor", "outdoor"):
        v = spec.get(key)
        if v is not None:
            v = _number(v, path + (key,), "a probability")
            if not 0.0 <= v <= 1.0:
                raise _Problem(path + (key,), f"expected a probability in [0, 1], got {v:g}")
        out.append(v)
    return rooms, out[0], out[1]


def _class(name: str, spec: Any, path: tuple[Any, ...], seeds: Mapping[str, Any]) -> ObjectClass:
    spec = _mapping(spec, path)
    _only(
        spec,
        {
            "label",
            "description",
            "detect",
            "matches",
            "prior",
            "cluster",
            "parts",
            "relations",
            "labeling",
            "extra_plane",
            "extra_surface",
            "context",
            "near",
            "cad",
            "variant_of",
        },
        path,
    )
    parts_spec = _mapping(spec.get("parts"), path + ("parts",))
    if not parts_spec:
        raise _Problem(path + ("parts",), "a class needs at least one part")
    parts = tuple(_part(str(n), s, path + ("parts", n), seeds) for n, s in parts_spec.items())
    rel_spec = spec.get("relations") or []
    if not isinstance(rel_spec, list):
        raise _Problem(path + ("relations",), "expected a list of relations")
    names = {p.name for p in parts}
    relations = tuple(_relation(r, path + ("relations", i), names) for i, r in enumerate(rel_spec))
    cluster_spec = _mapping(spec.get("cluster"), path + ("cluster",))
    cluster = ClusterRule(_constraints(cluster_spec, CLUSTER_FEATURES, path + ("cluster",), set()))
    rooms, indoor, outdoor = _prior(spec.get("prior"), path + ("prior",))
    detect = spec.get("detect", True)
    if not isinstance(detect, bool):
        raise _Problem(path + ("detect",), f"expected true or false, got {detect!r}")
    matches = spec.get("matches", [name])
    if isinstance(matches, str):
        matches = [matches]
    if not isinstance(matches, list) or not all(isinstance(m, str) for m in matches):
        raise _Problem(path + ("matches",), f"expected a list of class names, got {matches!r}")
    extra = _probability(spec, "extra_plane", path, 1.0)
    surface = _probability(spec, "extra_surface", path)
    variant_of = spec.get("variant_of")
    if variant_of is not None and (not isinstance(variant_of, str) or not variant_of):
        raise _Problem(path + ("variant_of",), f"expected a class name, got {variant_of!r}")
    if variant_of == name:
        raise _Problem(path + ("variant_of",), "a class cannot be a variant of itself")
    label = spec.get("label", variant_of or name)
    if not isinstance(label, str) or not label:
        raise _Problem(path + ("label",), f"expected a name, got {label!r}")
    context = spec.get("context", [])
    if not isinstance(context, list) or not all(isinstance(m, str) and m for m in context):
        raise _Problem(path + ("context",), f"expected a list of class names, got {context!r}")
    near_spec = spec.get("near") or []
    if not isinstance(near_spec, list):
        raise _Problem(path + ("near",), "expected a list of objects it stands beside")
    near = tuple(_near(r, path + ("near", i)) for i, r in enumerate(near_spec))
    cad = _mapping(spec.get("cad"), path + ("cad",))
    _only(cad, {"scale"}, path + ("cad",))
    cad_scale = _pair(cad["scale"], path + ("cad", "scale")) if "scale" in cad else None
    return ObjectClass(
        name=name,
        label=label,
        description=str(spec.get("description", "")).strip(),
        parts=parts,
        relations=relations,
        cluster=cluster,
        labeling=_labeling(spec.get("labeling"), path + ("labeling",)),
        prior_rooms=rooms,
        prior_indoor=indoor,
        prior_outdoor=outdoor,
        detect=detect,
        matches=tuple(matches),
        extra_plane=extra,
        extra_surface=surface,
        context=tuple(context),
        near=near,
        cad_scale=cad_scale,
        variant_of=variant_of,
    )


def parse_ontology(
    text: str,
    source: str | PathLike[str] | None = None,
    *,
    seeds: Mapping[str, SeedStyle] | None = None,
) -> Ontology:
    """Parse and validate an ontology from YAML text.

    ``seeds`` are seed styles defined elsewhere (the built-in file's) that the file's
    parts may name besides its own.

    Raises
    ------
    InvalidOntologyError
        With the file, line and dotted key of the first problem found.

    Examples
    --------
    >>> o = parse_ontology('''
    ... format: ontodetect.ontology/1
    ... classes:
    ...   stool:
    ...     parts:
    ...       seat: {tilt: {max: 6}, height: [0.4, 0.8]}
    ... ''')
    >>> o.names
    ['stool']
    """
    return _parse(text, None if source is None else str(source), seeds, SafeYamlLoader)


def _parse(
    text: str,
    src: str | None,
    seeds: Mapping[str, SeedStyle] | None,
    loader_class: type[SafeYamlLoader],
) -> Ontology:
    """:func:`parse_ontology` reading the YAML with ``loader_class``."""
    data, lines = _load_yaml(text, src, loader_class)
    try:
        data = _mapping(data, ())
        if data.get("format") != FORMAT:
            raise _Problem(("format",), f"expected format: {FORMAT}, got {data.get('format')!r}")
        _only(data, {"format", "classes", "description", "seeds"}, ())
        own = {
            str(n): _seed_style(str(n), v, ("seeds", n))
            for n, v in _mapping(data.get("seeds"), ("seeds",)).items()
        }
        known = {**(seeds or {}), **own}
        classes_spec = _mapping(data.get("classes"), ("classes",))
        if not classes_spec:
            raise _Problem(("classes",), "an ontology needs at least one class")
        classes = tuple(_class(str(n), s, ("classes", n), known) for n, s in classes_spec.items())
    except _Problem as exc:
        raise InvalidOntologyError(
            src, exc.message, line=exc.line or lines.line(exc.path), key=_dotted(exc.path)
        ) from exc
    return Ontology(classes=classes, source=src, seeds=own)


def parse_shipped_ontology(text: str, source: str) -> Ontology:
    """:func:`parse_ontology` of a file shipped with the package, read with libyaml's
    parser when PyYAML has it (a tenth of the time; the tests check that the shipped
    files read the same both ways); a file it refuses is read again by
    :func:`parse_ontology`, so that the error is that function's."""
    if CSafeYamlLoader is not None:
        try:
            return _parse(text, source, None, CSafeYamlLoader)
        except InvalidOntologyError:
            pass
    return parse_ontology(text, source)


def read_ontology_file(
    path: str | PathLike[str], *, seeds: Mapping[str, SeedStyle] | None = None
) -> Ontology:
    """Read and validate an ontology file (``seeds``: see :func:`parse_ontology`)."""
    p = Path(path)
    try:
        text = read_text(p, "ontology file")
    except ReadError as exc:
        raise InvalidOntologyError(p, exc.problem) from None
    return parse_ontology(text, p, seeds=seeds)
