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

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import yaml

from ..errors import InvalidOntologyError
from ._features import CLUSTER_FEATURES, PART_FEATURES, RELATION_FEATURES
from ._gaussian import Gaussian

__all__ = [
    "CLUSTER_FEATURES",
    "FORMAT",
    "PART_FEATURES",
    "RELATION_FEATURES",
    "ClusterRule",
    "LabelModel",
    "ObjectClass",
    "Ontology",
    "Part",
    "Relation",
    "parse_ontology",
    "read_ontology_file",
]

FORMAT = "ontodetect.ontology/1"

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


@dataclass(frozen=True)
class Relation:
    """Constraints between two parts ``a`` and ``b``."""

    a: str
    b: str
    constraints: Mapping[str, Gaussian]


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

    def merged(self, other: Ontology) -> Ontology:
        """Classes of ``other`` replace same-named ones here; new ones are appended."""
        by_name = {c.name: c for c in self.classes}
        order = list(by_name)
        for c in other.classes:
            if c.name not in by_name:
                order.append(c.name)
            by_name[c.name] = c
        return Ontology(tuple(by_name[n] for n in order), other.source or self.source)


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


def _load_yaml(text: str, source: str | None) -> tuple[Any, _Lines]:
    lines = _Lines()
    try:
        loader = yaml.SafeLoader(text)
        try:
            node = loader.get_single_node()
            data = None if node is None else _construct(node, (), lines, loader)
        finally:
            loader.dispose()
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        raise InvalidOntologyError(
            source,
            f"not valid YAML: {exc.problem or exc}",
            line=None if mark is None else mark.line + 1,
        ) from exc
    except yaml.YAMLError as exc:
        raise InvalidOntologyError(source, f"not valid YAML: {exc}") from exc
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
            soft = value.get("soft")
            if soft is not None and _number(soft, path + ("soft",)) <= 0:
                raise _Problem(path + ("soft",), f"soft must be > 0, got {soft!r}")
            return Gaussian.plateau(lo, hi, None if soft is None else float(soft))
        for side, make in (("min", Gaussian.at_least), ("max", Gaussian.at_most)):
            if side in keys:
                _only(value, {side, "soft"}, path)
                soft = value.get("soft")
                if soft is not None and _number(soft, path + ("soft",)) <= 0:
                    raise _Problem(path + ("soft",), f"soft must be > 0, got {soft!r}")
                return make(
                    _number(value[side], path + (side,)), None if soft is None else float(soft)
                )
    except ValueError as exc:  # from Gaussian itself
        raise _Problem(path, str(exc)) from exc
    raise _Problem(
        path, f"expected one of range, mean/sigma, min, max, min+max; got keys {sorted(keys)}"
    )


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
    spec: dict[str, Any], allowed: Mapping[str, str], path: tuple[Any, ...], skip: set[str]
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


def _part(name: str, spec: Any, path: tuple[Any, ...]) -> Part:
    spec = _mapping(spec, path)
    required = spec.get("required", True)
    if not isinstance(required, bool):
        raise _Problem(path + ("required",), f"expected true or false, got {required!r}")
    missing = _probability(spec, "missing", path, DEFAULT_MISSING[required])
    occluded = _probability(spec, "occluded", path)
    constraints = _constraints(
        spec, PART_FEATURES, path, {"required", "missing", "occluded", "description"}
    )
    return Part(
        name=name, constraints=constraints, required=required, missing=missing, occluded=occluded
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


def _class(name: str, spec: Any, path: tuple[Any, ...]) -> ObjectClass:
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
        },
        path,
    )
    parts_spec = _mapping(spec.get("parts"), path + ("parts",))
    if not parts_spec:
        raise _Problem(path + ("parts",), "a class needs at least one part")
    parts = tuple(_part(str(n), s, path + ("parts", n)) for n, s in parts_spec.items())
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
    label = spec.get("label", name)
    if not isinstance(label, str) or not label:
        raise _Problem(path + ("label",), f"expected a name, got {label!r}")
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
    )


def parse_ontology(text: str, source: str | PathLike[str] | None = None) -> Ontology:
    """Parse and validate an ontology from YAML text.

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
    src = None if source is None else str(source)
    data, lines = _load_yaml(text, src)
    try:
        data = _mapping(data, ())
        if data.get("format") != FORMAT:
            raise _Problem(("format",), f"expected format: {FORMAT}, got {data.get('format')!r}")
        _only(data, {"format", "classes", "description"}, ())
        classes_spec = _mapping(data.get("classes"), ("classes",))
        if not classes_spec:
            raise _Problem(("classes",), "an ontology needs at least one class")
        classes = tuple(_class(str(n), s, ("classes", n)) for n, s in classes_spec.items())
    except _Problem as exc:
        raise InvalidOntologyError(
            src, exc.message, line=exc.line or lines.line(exc.path), key=_dotted(exc.path)
        ) from exc
    return Ontology(classes=classes, source=src)


def read_ontology_file(path: str | PathLike[str]) -> Ontology:
    """Read and validate an ontology file."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError as exc:
        raise InvalidOntologyError(p, "no such file") from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidOntologyError(p, f"cannot read the file ({exc})") from exc
    return parse_ontology(text, p)
