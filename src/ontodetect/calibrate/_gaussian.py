"""Fitting each constraint's Gaussian to the samples, and writing the ontology back."""

from __future__ import annotations

import copy
import math
import textwrap
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import yaml

from ..config import NON_NEGATIVE, Boolean, Interval, check_param
from ..errors import InvalidParameterError
from ..io._yaml import load_yaml
from ..ontology import Gaussian, parse_ontology
from ..ontology import sigma_floor as feature_sigma_floor
from ._settings import (
    DIGITS,
    LINE_WIDTH,
    LONG_TEXT,
    MAX_DIGITS,
    MIN_GAIN_ROOMS,
    MIN_ROOMS,
    MIN_SAMPLES,
    ONE_SIDED_QUANTILE,
    PRIOR_SIGMA_SHARE,
    PRIOR_STRENGTH,
    ROOM_SAMPLES,
    ConstraintPath,
)


@dataclass(frozen=True)
class FitSettings:
    """How constraints are re-estimated and checked (see the module docstring).

    Attributes
    ----------
    prior_share : float
        σ is at least this share of the prior's σ (:data:`PRIOR_SIGMA_SHARE`).
    quantile : float
        One-sided bounds and plateau ends start from this quantile of the values (and
        1 − it); 0 is the smallest (largest) value (:data:`ONE_SIDED_QUANTILE`).
    min_samples : int
        Fewer values keep the prior (:data:`MIN_SAMPLES`).
    min_rooms : int
        Values from fewer rooms keep the prior (:data:`MIN_ROOMS`): rescans of one
        room measure the same objects again, so they say little about other rooms.
    prior_strength : float
        Weight of the prior, in objects (:data:`PRIOR_STRENGTH`); 0 is the plain
        maximum-likelihood fit.
    room_samples : int
        The objects of one room count as at most this many samples (:data:`ROOM_SAMPLES`).
    validate : bool
        Keep a fitted group of constraints only where the nested check inside the
        calibration rooms (:func:`select_groups`) finds that it does not lower F1.
    accept_ties : bool
        Also keep a group that changes no validation F1 (by default a change needs
        some evidence: it must raise one F1 and lower none).
    min_gain_rooms : int
        A group is kept only when F1 rises in at least this many calibration rooms
        left out in turn and falls in none (:data:`MIN_GAIN_ROOMS`); with fewer
        calibration rooms to leave out, nothing is validated and nothing changes.
    """

    prior_share: float = PRIOR_SIGMA_SHARE
    quantile: float = ONE_SIDED_QUANTILE
    min_samples: int = MIN_SAMPLES
    min_rooms: int = MIN_ROOMS
    prior_strength: float = PRIOR_STRENGTH
    room_samples: int = ROOM_SAMPLES
    validate: bool = True
    accept_ties: bool = False
    min_gain_rooms: int = MIN_GAIN_ROOMS

    def __post_init__(self) -> None:
        for name in ("prior_share", "prior_strength"):
            check_param(name, NON_NEGATIVE, getattr(self, name))
        check_param("quantile", Interval(0.0, 0.5, "left"), self.quantile)
        for name in ("min_samples", "min_rooms", "room_samples", "min_gain_rooms"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InvalidParameterError(name, "a positive integer", value)
        for name in ("validate", "accept_ties"):
            check_param(name, Boolean(), getattr(self, name))

    @property
    def validation_rooms(self) -> int:
        """Calibration rooms the nested check needs before it can accept any change."""
        # Leaving one room out needs another to fit on, and the gain must show in
        # min_gain_rooms of them.
        return max(2, self.min_gain_rooms)


def sigma_floor(prior: Any, feature: str, prior_share: float = PRIOR_SIGMA_SHARE) -> float:
    """The least σ a calibrated constraint may have."""
    return max(prior_share * prior.sigma, feature_sigma_floor(feature))


def fit_gaussian(
    prior: Any,
    values: Sequence[float],
    feature: str,
    *,
    prior_share: float = PRIOR_SIGMA_SHARE,
    quantile: float = ONE_SIDED_QUANTILE,
    min_samples: int = MIN_SAMPLES,
    prior_strength: float = PRIOR_STRENGTH,
    effective_samples: float | None = None,
) -> Any:
    """Posterior re-estimate of one constraint, shrunk to the prior, with floors; keeps its side.

    Parameters
    ----------
    prior : Gaussian
        The constraint as the ontology has it.
    values : sequence of float
        Measured values.
    feature : str
        Feature name (selects the absolute σ floor).
    prior_share : float
        σ is at least this share of the prior's σ.
    quantile : float
        Where the data's estimate of one-sided bounds and plateau ends starts (0: the
        extreme value).
    min_samples : int
        Fewer finite values keep the prior.
    prior_strength : float
        κ0, the prior's weight in objects; 0 gives the maximum-likelihood fit.
    effective_samples : float, optional
        How many independent samples the values are worth (at most their number);
        all of them by default.

    Returns
    -------
    Gaussian
        The prior itself when there are too few values or its form is not known.

    Examples
    --------
    >>> from ontodetect.ontology import Gaussian
    >>> prior = Gaussian(0.55, 0.2)
    >>> g = fit_gaussian(prior, [0.44, 0.46, 0.48], "height", prior_strength=0)
    >>> round(g.mean, 3), round(g.sigma, 3)   # ML; the std 0.016 is below half of 0.2
    (0.46, 0.1)
    >>> g = fit_gaussian(prior, [0.44, 0.46, 0.48], "height", prior_strength=9)
    >>> round(g.mean, 3), round(g.sigma, 3)   # 3 objects against 9: a quarter of the way
    (0.528, 0.185)
    >>> g = fit_gaussian(Gaussian(0.45, 0.2, "min"), [0.3, 0.4, 0.5], "fill", prior_strength=0)
    >>> g.side, round(g.mean, 2)              # stays one-sided; 0.3 minus the expected gap
    ('min', 0.2)
    >>> g = fit_gaussian(Gaussian(0.45, 0.2, "min"), [0.7, 0.8, 0.9], "fill", prior_strength=0)
    >>> round(g.mean, 2)                      # objects inside a bound never tighten it
    0.45
    """

    x = np.asarray(values, dtype=np.float64)
    x = x[np.isfinite(x)]
    if len(x) < max(min_samples, 1):
        return prior
    n = float(len(x)) if effective_samples is None else min(float(len(x)), effective_samples)
    # Share of the data in the conjugate posterior (κ0 = ν0 = prior_strength).
    w = n / (prior_strength + n) if prior_strength + n > 0 else 1.0
    floor = sigma_floor(prior, feature, prior_share)
    spread = float(x.var())
    # The posterior predictive of a new object is wider than the posterior by
    # 1 + 1 / κn: with few objects σ widens rather than narrows.
    predictive = 1.0 + 1.0 / max(prior_strength + n, 1.0)
    if prior.side == "both":
        shift = float(x.mean()) - prior.mean
        var = (1.0 - w) * prior.sigma**2 + w * spread + w * (1.0 - w) * shift**2
        return Gaussian(prior.mean + w * shift, max(math.sqrt(var * predictive), floor))
    if prior.side not in ("min", "max", "plateau"):
        return prior  # a form this version does not know how to fit
    # The softness of a bound loosens like the bound: values well inside it say nothing
    # of how sharply objects beyond it fall off.
    sigma = max(
        math.sqrt(((1.0 - w) * prior.sigma**2 + w * spread) * predictive), floor, prior.sigma
    )
    low = float(np.quantile(x, quantile))
    high = float(np.quantile(x, 1.0 - quantile))
    # The support of n samples reaches beyond their extremes by about range / (n - 1)
    # (the unbiased end points of a uniform law): an end never moves inside it.
    gap = (high - low) / max(n - 1.0, 1.0)
    # Objects beyond a bound show it is too tight; objects inside it do not show that
    # others are not beyond it, so bounds only ever loosen.
    low = min(prior.mean + w * (low - gap - prior.mean), prior.mean)
    if prior.side == "min":
        return Gaussian(low, sigma, "min")
    upper = prior.mean if prior.side == "max" else prior.upper
    high = max(upper + w * (high + gap - upper), upper)
    if prior.side == "max":
        return Gaussian(high, sigma, "max")
    if high - low < floor:
        # Values (nearly) all alike: a plateau as wide as the σ floor around them.
        mid = (low + high) / 2
        low, high = mid - floor / 2, mid + floor / 2
    # A tail softer or sharper than the other stays so, in the same ratio.
    above = None if prior.upper_sigma is None else prior.upper_sigma * sigma / prior.sigma
    return Gaussian.plateau(low, high, sigma, above)


@dataclass(frozen=True)
class ConstraintFit:
    """One constraint before and after calibration.

    Attributes
    ----------
    path : tuple
        Place in the file (see :func:`constraint_values`).
    before, after : Gaussian
        The prior and what was written (the prior itself when unchanged).
    samples : int
        Values measured.
    proposed : Gaussian or None
        The fit before the nested check (``after`` when it was kept).
    note : str
        Why the constraint kept its prior, if it did.
    """

    path: ConstraintPath
    before: Any
    after: Any
    samples: int
    proposed: Any = None
    note: str = ""

    @property
    def name(self) -> str:
        """Dotted place in the file: ``chair.parts.seat.height``, ``chair.relations[0].gap``."""
        return _dotted(self.path)

    @property
    def changed(self) -> bool:
        return self.after is not self.before

    def to_dict(self) -> dict[str, Any]:
        def g(x: Any) -> dict[str, Any]:
            out = {"mean": x.mean, "sigma": x.sigma, "side": x.side}
            if getattr(x, "upper", None) is not None:
                out["upper"] = x.upper
            if getattr(x, "upper_sigma", None) is not None:
                out["upper_sigma"] = x.upper_sigma
            return out

        out = {
            "constraint": self.name,
            "samples": self.samples,
            "before": g(self.before),
            "after": g(self.after),
        }
        if self.proposed is not None and self.proposed is not self.after:
            out["proposed"] = g(self.proposed)
        if self.note:
            out["note"] = self.note
        return out


def _dotted(path: Sequence[Any]) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def constraint_group(path: ConstraintPath) -> ConstraintPath:
    """The group a constraint is accepted or rejected with: its class and part.

    ``(class, "parts", part)``, ``(class, "relations", index)`` or ``(class, "cluster")``.

    Examples
    --------
    >>> constraint_group(("chair", "parts", "seat", "height"))
    ('chair', 'parts', 'seat')
    >>> constraint_group(("chair", "cluster", "length"))
    ('chair', 'cluster')
    """
    return tuple(path[:2]) if path[1] == "cluster" else tuple(path[:3])


def _round(v: float, digits: int = DIGITS) -> float:
    r = float(f"{v:.{digits}g}")
    return 0.0 if r == 0 else r


def _spec_with(spec: Any, g: Any, digits: int) -> Any | None:
    """``spec`` in its own form with ``g``'s numbers; None if rounding collapses it."""
    if isinstance(spec, list) or (isinstance(spec, dict) and "range" in spec):
        lo, hi = _round(g.mean - g.sigma, digits), _round(g.mean + g.sigma, digits)
        if hi <= lo:
            return None
        return [lo, hi] if isinstance(spec, list) else {**spec, "range": [lo, hi]}
    if not isinstance(spec, dict):
        return spec
    if "mean" in spec:
        sigma = _round(g.sigma, digits)
        return {**spec, "mean": _round(g.mean, digits), "sigma": sigma} if sigma > 0 else None
    out = dict(spec)
    if "min" in spec and "max" in spec:
        out["min"], out["max"] = _round(g.mean, digits), _round(g.upper, digits)
        if out["max"] <= out["min"]:
            return None
    elif "min" in spec or "max" in spec:
        out["min" if "min" in spec else "max"] = _round(g.mean, digits)
    else:
        return spec
    if "soft" in spec:
        out["soft"] = _round(g.sigma, digits)
        if out["soft"] <= 0:
            return None
        if isinstance(spec["soft"], list) and g.upper_sigma is not None:
            out["soft"] = [out["soft"], _round(g.upper_sigma, digits)]
            if out["soft"][1] <= 0:
                return None
    return out


def _write_spec(spec: Any, g: Any) -> Any:
    """The YAML value of a constraint in its original form, with ``g``'s numbers."""
    # More digits when rounding would collapse a narrow range or a small sigma to nothing.
    for digits in range(DIGITS, MAX_DIGITS + 1):
        out = _spec_with(spec, g, digits)
        if out is not None:
            return out
    return spec


def _spec_at(data: dict[str, Any], path: ConstraintPath) -> tuple[Any, Any]:
    """(container, key) of a constraint's value in the parsed YAML."""
    cls = data["classes"][path[0]]
    if path[1] == "cluster":
        return cls["cluster"], path[2]
    if path[1] == "parts":
        return cls["parts"][path[2]], path[3]
    return cls["relations"][path[2]], path[3]


class _Dumper(yaml.SafeDumper):
    """Flow style for constraint mappings and number lists, block style around them; no
    aliases (the YAML loader refuses them)."""

    def ignore_aliases(self, data: object) -> bool:
        return True


def _represent_dict(dumper: yaml.SafeDumper, data: dict[str, Any]) -> yaml.Node:
    flow = (
        all(
            not isinstance(v, dict)
            and not (isinstance(v, list) and any(isinstance(x, (dict, list)) for x in v))
            for v in data.values()
        )
        and len(data) <= 4
    )
    return dumper.represent_mapping("tag:yaml.org,2002:map", data, flow_style=flow)


def _represent_list(dumper: yaml.SafeDumper, data: list[Any]) -> yaml.Node:
    flow = all(not isinstance(v, (dict, list)) for v in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


def _represent_str(dumper: yaml.SafeDumper, data: str) -> yaml.Node:
    # Long descriptions as folded blocks (``>``), as people write them.
    style = ">" if len(data) > LONG_TEXT or "\n" in data.rstrip("\n") else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", data, style=style)


_Dumper.add_representer(dict, _represent_dict)
_Dumper.add_representer(str, _represent_str)
_Dumper.add_representer(list, _represent_list)


def _constraint_paths(ontology: Any) -> list[tuple[ConstraintPath, Any]]:
    out = []
    for cls in ontology.classes:
        for feature, g in cls.cluster.constraints.items():
            out.append(((cls.name, "cluster", feature), g))
        for part in cls.parts:
            for feature, g in part.constraints.items():
                out.append(((cls.name, "parts", part.name, feature), g))
        for i, rel in enumerate(cls.relations):
            for feature, g in rel.constraints.items():
                out.append(((cls.name, "relations", i, feature), g))
    return out


def _effective(
    path: ConstraintPath, rooms: Mapping[ConstraintPath, int] | None, settings: FitSettings
) -> float | None:
    return None if rooms is None else float(rooms.get(path, 0) * settings.room_samples)


def fit_constraints(
    ontology: Any,
    values: Mapping[ConstraintPath, Sequence[float]],
    rooms: Mapping[ConstraintPath, int] | None = None,
    settings: FitSettings | None = None,
) -> dict[ConstraintPath, Any]:
    """The re-estimated constraints of an ontology, before any check.

    Parameters
    ----------
    ontology : Ontology
    values : mapping
        Constraint path -> measured values.
    rooms : mapping, optional
        Constraint path -> number of rooms its values come from (not checked when
        omitted; each room's values then count in full).
    settings : FitSettings, optional

    Returns
    -------
    dict
        Constraint path -> new Gaussian, for the constraints that changed.
    """
    settings = settings or FitSettings()
    out = {}
    for path, prior in _constraint_paths(ontology):
        if rooms is not None and rooms.get(path, 0) < settings.min_rooms:
            continue
        after = fit_gaussian(
            prior,
            list(values.get(path, ())),
            path[-1],
            prior_share=settings.prior_share,
            quantile=settings.quantile,
            min_samples=settings.min_samples,
            prior_strength=settings.prior_strength,
            effective_samples=_effective(path, rooms, settings),
        )
        if after is not prior:
            out[path] = after
    return out


def _render(data: Mapping[str, Any], fits: Mapping[ConstraintPath, Any], comment: str = "") -> str:
    """The ontology YAML ``data`` with the constraints of ``fits`` rewritten in their form."""
    data = copy.deepcopy(dict(data))
    for path, g in fits.items():
        container, key = _spec_at(data, path)
        container[key] = _write_spec(container[key], g)
    body = yaml.dump(data, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=LINE_WIDTH)
    lines = [
        w for line in comment.splitlines() for w in (textwrap.wrap(line, LINE_WIDTH - 2) or [""])
    ]
    return "".join(f"# {line}\n" if line else "#\n" for line in lines) + body


def calibrate_ontology(
    text: str,
    values: Mapping[ConstraintPath, Sequence[float]],
    *,
    rooms: Mapping[ConstraintPath, int] | None = None,
    settings: FitSettings | None = None,
    source: str | None = None,
    comment: str | None = None,
    groups: Collection[ConstraintPath] | None = None,
) -> tuple[str, list[ConstraintFit]]:
    """Re-estimate an ontology file's constraints from measured values.

    Parameters
    ----------
    text : str
        The ontology's YAML.
    values : mapping
        Constraint path (see :func:`constraint_values`) -> measured values.
    rooms : mapping, optional
        Constraint path -> number of rooms its values come from; constraints measured
        in fewer than ``settings.min_rooms`` keep their prior, and a room's values
        count as at most ``settings.room_samples`` samples. Not checked when omitted.
    settings : FitSettings, optional
        Floors, quantile, prior strength and minimum counts (defaults: the module
        constants). ``settings.validate`` is not used here (see :func:`select_groups`).
    source : str, optional
        Name of the file, for error messages.
    comment : str, optional
        Written as ``#`` lines at the top of the new file.
    groups : collection of group paths, optional
        Only constraints of these groups (:func:`constraint_group`) change; all by
        default.

    Returns
    -------
    text : str
        The calibrated YAML: same classes, parts, relations and keys, new numbers;
        comments of the original are not kept.
    fits : list of ConstraintFit
        Every constraint, in file order, before and after.
    """

    ontology = parse_ontology(text, source)
    data = load_yaml(text)
    settings = settings or FitSettings()
    proposed = fit_constraints(ontology, values, rooms, settings)
    kept = {p: g for p, g in proposed.items() if groups is None or constraint_group(p) in groups}
    fits = []
    for path, prior in _constraint_paths(ontology):
        note = ""
        if path not in proposed:
            if rooms is not None and rooms.get(path, 0) < settings.min_rooms:
                note = f"measured in fewer than {settings.min_rooms} rooms"
            elif len(values.get(path, ())) < settings.min_samples:
                note = f"fewer than {settings.min_samples} values"
        elif path not in kept:
            note = "its group was not accepted by the nested check"
        fits.append(
            ConstraintFit(
                path,
                prior,
                kept.get(path, prior),
                len(values.get(path, ())),
                proposed.get(path),
                note,
            )
        )
    new_text = _render(data, kept, comment or "")
    parse_ontology(new_text, source)  # the result must be a valid ontology
    return new_text, fits


# -- the nested check ----------------------------------------------------------------------
