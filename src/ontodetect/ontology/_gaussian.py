"""Soft constraints: every ontological rule is a Gaussian on a measured feature.

A constraint written ``{mean: 0.46, sigma: 0.05}`` is ``N(0.46, 0.05²)``; a range
``[0.35, 0.75]`` is read as the Gaussian centred on the range whose σ is half its
width, so the bounds score ``exp(-1/2) ≈ 0.61`` and values far outside fall off
quickly; ``{min: 0.3}`` and ``{max: 1.2}`` are one-sided: 1 on the allowed side
and a Gaussian tail of the given (or default) softness beyond the bound;
``{min: 0.5, max: 4, soft: 0.2}`` is a plateau: 1 inside, tails on both sides;
``{min: 65, max: 85, soft: [12, 4]}`` gives its two tails their own softness (below, above).

The factor is the Gaussian's density scaled to 1 at its mean, so a perfect
measurement contributes 1 and products of factors stay comparable between
classes with different numbers of constraints (thesis Eq. 3.2–3.3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Gaussian"]

#: One-sided bounds without an explicit softness fall off with σ = this share of |bound|.
DEFAULT_SOFTNESS = 0.15
#: Smallest σ accepted, to keep log-probabilities finite.
MIN_SIGMA = 1e-9


@dataclass(frozen=True)
class Gaussian:
    """A soft constraint on one feature.

    Parameters
    ----------
    mean : float
        Centre (for one-sided constraints: the bound).
    sigma : float
        Standard deviation (> 0).
    side : {"both", "min", "max", "plateau"}
        "both" is a plain Gaussian; "min" scores 1 for ``x >= mean``; "max"
        scores 1 for ``x <= mean``; "plateau" scores 1 on ``[mean, upper]``.
    upper : float, optional
        The plateau's upper end.
    upper_sigma : float, optional
        The plateau's tail above ``upper`` (σ); ``sigma`` when not given, which is
        then the tail on both sides.

    Examples
    --------
    >>> g = Gaussian.from_range(0.35, 0.75)
    >>> round(g.mean, 2), round(g.sigma, 2)
    (0.55, 0.2)
    >>> round(float(g(0.75)), 3)
    0.607
    >>> float(Gaussian(0.3, 0.05, "min")(1.0))
    1.0
    """

    mean: float
    sigma: float
    side: str = "both"
    upper: float | None = None
    upper_sigma: float | None = None

    def __post_init__(self) -> None:
        if not math.isfinite(self.mean) or not math.isfinite(self.sigma) or self.sigma <= 0:
            raise ValueError(f"Gaussian needs a finite mean and sigma > 0, got {self}")
        if self.upper_sigma is not None and (
            self.side != "plateau" or not math.isfinite(self.upper_sigma) or self.upper_sigma <= 0
        ):
            raise ValueError(f"only a plateau has an upper sigma, finite and > 0, got {self}")
        if self.side not in ("both", "min", "max", "plateau"):
            raise ValueError(
                f"Gaussian side must be 'both', 'min', 'max' or 'plateau', got {self.side!r}"
            )
        if self.side == "plateau" and (self.upper is None or not self.upper > self.mean):
            raise ValueError(f"a plateau needs min < max, got [{self.mean}, {self.upper}]")

    @classmethod
    def from_range(cls, low: float, high: float) -> Gaussian:
        """The Gaussian centred on ``[low, high]`` with σ = half its width."""
        if not high > low:
            raise ValueError(f"a range needs low < high, got [{low}, {high}]")
        return cls((low + high) / 2.0, max((high - low) / 2.0, MIN_SIGMA))

    @classmethod
    def plateau(
        cls,
        low: float,
        high: float,
        softness: float | None = None,
        upper_softness: float | None = None,
    ) -> Gaussian:
        """1 on ``[low, high]``, Gaussian tails of σ = ``softness`` outside (above ``high``
        of σ = ``upper_softness`` when given).

        >>> g = Gaussian.plateau(65, 86, 12, 2)
        >>> [round(float(g(x)), 3) for x in (53, 70, 88)]
        [0.607, 1.0, 0.607]
        """
        s = softness if softness is not None else max((high - low) * DEFAULT_SOFTNESS, MIN_SIGMA)
        return cls(low, s, "plateau", high, upper_softness)

    @classmethod
    def at_least(cls, bound: float, softness: float | None = None) -> Gaussian:
        """1 at or above ``bound``, a Gaussian tail below it."""
        s = softness if softness is not None else max(abs(bound) * DEFAULT_SOFTNESS, MIN_SIGMA)
        return cls(bound, s, "min")

    @classmethod
    def at_most(cls, bound: float, softness: float | None = None) -> Gaussian:
        """1 at or below ``bound``, a Gaussian tail above it."""
        s = softness if softness is not None else max(abs(bound) * DEFAULT_SOFTNESS, MIN_SIGMA)
        return cls(bound, s, "max")

    def z(self, x: ArrayLike) -> NDArray[np.float64]:
        """Signed distance from the allowed region in units of σ (0 inside it)."""
        if self.side == "plateau":
            v = np.asarray(x, dtype=np.float64)
            below = np.minimum(v - self.mean, 0.0) / self.sigma
            above = np.maximum(v - self.upper, 0.0) / (self.upper_sigma or self.sigma)
            return below + above
        d = (np.asarray(x, dtype=np.float64) - self.mean) / self.sigma
        if self.side == "min":
            d = np.minimum(d, 0.0)
        elif self.side == "max":
            d = np.maximum(d, 0.0)
        return d

    def log(self, x: ArrayLike) -> NDArray[np.float64]:
        """Log of the factor: ``-z²/2``."""
        return -0.5 * self.z(x) ** 2

    def __call__(self, x: ArrayLike) -> NDArray[np.float64]:
        """The factor in (0, 1]: the Gaussian density scaled to 1 at its mean."""
        return np.exp(self.log(x))

    def describe(self) -> str:
        """Short human form: ``N(0.55, 0.20²)``, ``≥ 0.30 (±0.05)``."""
        if self.side == "min":
            return f">= {self.mean:.3g} (soft {self.sigma:.2g})"
        if self.side == "max":
            return f"<= {self.mean:.3g} (soft {self.sigma:.2g})"
        if self.side == "plateau":
            soft = f"{self.sigma:.2g}"
            if self.upper_sigma is not None:
                soft += f", {self.upper_sigma:.2g}"
            return f"in [{self.mean:.3g}, {self.upper:.3g}] (soft {soft})"
        return f"N({self.mean:.3g}, {self.sigma:.2g}²)"
