"""Rules a value must obey, declared once and used by the configuration and by public
functions alike (:func:`check_param`): a bad value raises
:class:`~ontodetect.errors.InvalidParameterError` naming the parameter, the rule and the
value, e.g. "The 'cluster.radius' parameter must be a float in the range (0, inf). Got -1
instead." The configuration (:mod:`ontodetect.config`) re-exports every name here.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from .errors import InvalidParameterError

__all__ = [
    "ANGLE",
    "COUNT",
    "FRACTION",
    "NON_NEGATIVE",
    "ON_NONFINITE",
    "POSITIVE",
    "PROBABILITY",
    "SEED",
    "SHARE",
    "WEIGHT",
    "Boolean",
    "Interval",
    "Names",
    "Nullable",
    "OneOf",
    "Pair",
    "check_param",
]


class _Rule:
    """A constraint on one value: ``check`` returns the value, normalised, or raises."""

    def describe(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def check(self, name: str, value: Any) -> Any:  # pragma: no cover - abstract
        raise NotImplementedError


def _fmt(x: float) -> str:
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:g}"


@dataclass(frozen=True)
class Interval(_Rule):
    """A real (or integer) number in a range; ``closed`` says which ends are included."""

    lo: float = -math.inf
    hi: float = math.inf
    closed: str = "neither"  # "neither", "left", "right", "both"
    integer: bool = False

    def describe(self) -> str:
        left = "[" if self.closed in ("left", "both") else "("
        right = "]" if self.closed in ("right", "both") else ")"
        kind = "an int" if self.integer else "a float"
        return f"{kind} in the range {left}{_fmt(self.lo)}, {_fmt(self.hi)}{right}"

    def contains(self, x: float) -> bool:
        lo_ok = x >= self.lo if self.closed in ("left", "both") else x > self.lo
        hi_ok = x <= self.hi if self.closed in ("right", "both") else x < self.hi
        return lo_ok and hi_ok

    def check(self, name: str, value: Any) -> Any:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InvalidParameterError(name, self.describe(), value)
        if self.integer and isinstance(value, float) and not value.is_integer():
            raise InvalidParameterError(name, self.describe(), value)
        number = int(value) if self.integer else float(value)
        if math.isnan(number) or not self.contains(number):
            raise InvalidParameterError(name, self.describe(), value)
        return number


@dataclass(frozen=True)
class Pair(_Rule):
    """Two numbers ``[low, high]`` with ``low <= high``, both obeying ``each``."""

    each: Interval

    def describe(self) -> str:
        return f"a pair [low, high] with low <= high, each {self.each.describe()}"

    def check(self, name: str, value: Any) -> Any:
        if not isinstance(value, (list, tuple)) or len(value) != 2:
            raise InvalidParameterError(name, self.describe(), value)
        try:
            lo, hi = (self.each.check(name, v) for v in value)
        except InvalidParameterError:
            raise InvalidParameterError(name, self.describe(), value) from None
        if lo > hi:
            raise InvalidParameterError(name, self.describe(), value)
        return (lo, hi)


@dataclass(frozen=True)
class OneOf(_Rule):
    """One of a fixed set of strings; with ``booleans``, false and true stand for the two
    options named there (a switch that gained a third position).

    Examples
    --------
    >>> OneOf(("off", "views", "on"), booleans=("off", "on")).check("cluster.x", True)
    'on'
    """

    options: tuple[str, ...]
    booleans: tuple[str, str] | None = None

    def describe(self) -> str:
        words = "one of " + ", ".join(repr(o) for o in self.options)
        if self.booleans is not None:
            words += f" (false: {self.booleans[0]!r}, true: {self.booleans[1]!r})"
        return words

    def check(self, name: str, value: Any) -> Any:
        if isinstance(value, bool) and self.booleans is not None:
            return self.booleans[int(value)]
        if not isinstance(value, str) or value not in self.options:
            raise InvalidParameterError(name, self.describe(), value)
        return value


@dataclass(frozen=True)
class Names(_Rule):
    """One of a few words, or a comma-separated list of names (checked where they are used).

    Examples
    --------
    >>> Names(("reported", "all")).check("detect.classes", "toilet, sink")
    'toilet,sink'
    """

    words: tuple[str, ...]

    def describe(self) -> str:
        return " or ".join(repr(w) for w in self.words) + " or a comma-separated list of names"

    def check(self, name: str, value: Any) -> Any:
        if not isinstance(value, str):
            raise InvalidParameterError(name, self.describe(), value)
        items = [v.strip() for v in value.split(",")]
        if not all(items) or not all(re.fullmatch(r"[A-Za-z_][\w-]*", v) for v in items):
            raise InvalidParameterError(name, self.describe(), value)
        return ",".join(items)


@dataclass(frozen=True)
class Boolean(_Rule):
    def describe(self) -> str:
        return "true or false"

    def check(self, name: str, value: Any) -> Any:
        if not isinstance(value, bool):
            raise InvalidParameterError(name, self.describe(), value)
        return value


@dataclass(frozen=True)
class Nullable(_Rule):
    """``None`` (meaning "automatic" or "off") or a value obeying ``rule``."""

    rule: _Rule

    def describe(self) -> str:
        return f"null or {self.rule.describe()}"

    def check(self, name: str, value: Any) -> Any:
        if value is None:
            return None
        try:
            return self.rule.check(name, value)
        except InvalidParameterError:
            raise InvalidParameterError(name, self.describe(), value) from None


def check_param(name: str, rule: _Rule, value: Any) -> Any:
    """Check one parameter of a public function against a rule declared here.

    The one validation path of the library: configuration sections and functions use the
    same rule objects (:class:`Interval`, :class:`OneOf`...), so one rule has one wording.
    NumPy scalars count as the Python numbers they hold.

    Returns
    -------
    The value, normalised by the rule (ints for integer intervals, floats otherwise).

    Raises
    ------
    InvalidParameterError
        Naming the parameter, the rule and the value.

    Examples
    --------
    >>> check_param("radius", POSITIVE, 0.05)
    0.05
    >>> try:
    ...     check_param("radius", POSITIVE, -1)
    ... except InvalidParameterError as exc:
    ...     print(exc)
    The 'radius' parameter must be a float in the range (0, inf). Got -1 instead.
    """
    numpy_scalar = getattr(value, "dtype", None) is not None and getattr(value, "shape", None) == ()
    plain = value.item() if numpy_scalar else value
    return rule.check(name, plain)


POSITIVE = Interval(0.0, math.inf)
NON_NEGATIVE = Interval(0.0, math.inf, "left")
FRACTION = Interval(0.0, 1.0, "both")
ANGLE = Interval(0.0, 90.0, "both")
#: What a reader does with points whose coordinates are not finite.
ON_NONFINITE = OneOf(("warn", "drop", "raise"))
#: A share that cannot be empty: an overlap threshold, a part of the rooms.
SHARE = Interval(0.0, 1.0, "right")
#: A number of things: workers, passes, neighbours (0 allowed).
COUNT = Interval(0, math.inf, "left", integer=True)
#: A random seed: what NumPy's generators accept (0 <= seed < 2**63 here).
SEED = Interval(0, 2**63, "left", integer=True)
#: A probability.
PROBABILITY = Interval(0.0, 1.0, "both")
#: A weight of a distribution: a finite number >= 0.
WEIGHT = Interval(0.0, math.inf, "left")
