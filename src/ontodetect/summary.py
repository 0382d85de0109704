"""What a point cloud looks like at a glance: size, fields, spacing, units and up axis.

:func:`describe_cloud` is what ``ontodetect info`` prints. The guesses are
heuristics a person would make looking at the numbers: indoor rooms are a few
metres across (so a cloud tens of thousands of units wide is in millimetres),
and the up axis is the one along which the most points sit on a few large
horizontal planes (floor, ceiling, table tops).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ._units import SAMPLE_SIZE, _sample, estimate_spacing, guess_units
from .cloud import PointCloud, pixel_grid, sensor_position
from .errors import InvalidParameterError

__all__ = ["CloudSummary", "describe_cloud", "estimate_spacing", "guess_units", "guess_up_axis"]


@dataclass(frozen=True)
class CloudSummary:
    """Facts and guesses about one cloud, as ``ontodetect info`` shows them."""

    source: str | None
    format: str | None
    num_points: int
    fields: list[str]
    has_colors: bool
    has_normals: bool
    bounds_min: list[float]
    bounds_max: list[float]
    extent: list[float]
    spacing: float
    density: float
    units: str
    up_axis: str
    up_confidence: float
    extra: dict[str, Any] = field(default_factory=dict)
    #: Where the sensor stood when the cloud is one camera frame with its pixel grid
    #: (:func:`ontodetect.cloud.sensor_position`), else None.
    sensor: list[float] | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dictionary."""
        return asdict(self)


def guess_up_axis(
    xyz: np.ndarray, *, sample: int = SAMPLE_SIZE, seed: int = 0
) -> tuple[str, float]:
    """Which signed axis points up, and how sure the guess is (0..1).

    Indoors, the floor, ceiling and table tops are large planes perpendicular to
    the up axis, so coordinates along that axis pile up in a few histogram bins.
    The sign says where the floor is: most points lie above it, and the floor
    holds more points than the ceiling in a scan.

    Returns
    -------
    axis : str
        One of ``"+x" "-x" "+y" "-y" "+z" "-z"``.
    confidence : float
        Share of the best axis's concentration score among the three.
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    if len(xyz) < 10:
        return "+z", 0.0
    pts = _sample(xyz, sample, seed)
    scores = []
    for a in range(3):
        c = pts[:, a]
        span = float(np.ptp(c))
        if span <= 0:
            scores.append(0.0)
            continue
        bins = max(10, int(span / 0.02)) if span < 100 else 200
        hist, _ = np.histogram(c, bins=min(bins, 2000))
        top = np.sort(hist)[::-1][: max(2, len(hist) // 50)]
        scores.append(float(top.sum()) / len(c))
    scores_arr = np.asarray(scores)
    axis = int(np.argmax(scores_arr))
    conf = float(scores_arr[axis] / scores_arr.sum()) if scores_arr.sum() > 0 else 0.0
    c = pts[:, axis]
    lo, hi = np.percentile(c, [2, 98])
    # The floor side holds more points in its lowest tenth than the ceiling side.
    band = (hi - lo) * 0.1
    n_low = int(np.count_nonzero(c < lo + band))
    n_high = int(np.count_nonzero(c > hi - band))
    sign = "+" if n_low >= n_high else "-"
    return f"{sign}{'xyz'[axis]}", conf


def describe_cloud(cloud: PointCloud, *, seed: int = 0) -> CloudSummary:
    """Summarize a cloud for people and scripts.

    Examples
    --------
    >>> import numpy as np
    >>> from ontodetect import point_cloud
    >>> s = describe_cloud(point_cloud(np.random.default_rng(0).random((500, 3)) * 3))
    >>> s.num_points, s.units
    (500, 'metres')
    """
    xyz = cloud.xyz
    n = len(cloud)
    lo = xyz.min(axis=0) if n else np.zeros(3)
    hi = xyz.max(axis=0) if n else np.zeros(3)
    spacing = estimate_spacing(xyz, seed=seed, index="grid")  # no SciPy import at start-up
    ext = hi - lo
    # Points per square metre of surface: one point per spacing² cell.
    density = 1.0 / spacing**2 if spacing > 0 else 0.0
    up, conf = guess_up_axis(xyz, seed=seed)
    extra = {k: v for k, v in cloud.meta.items() if k not in ("source", "format")}
    return CloudSummary(
        source=cloud.meta.get("source"),
        format=cloud.meta.get("format"),
        num_points=n,
        fields=list(cloud.fields),
        has_colors=cloud.has_colors,
        has_normals=cloud.has_normals,
        bounds_min=[float(v) for v in lo],
        bounds_max=[float(v) for v in hi],
        extent=[float(v) for v in ext],
        spacing=spacing,
        density=density,
        units=guess_units(xyz, spacing),
        up_axis=up,
        up_confidence=conf,
        extra={k: v for k, v in extra.items() if isinstance(v, (str, int, float, bool, list))},
        sensor=_single_view_sensor(cloud),
    )


def _single_view_sensor(cloud: PointCloud) -> list[float] | None:
    try:
        eye = sensor_position(cloud)
    except InvalidParameterError:
        return None
    if eye is None or pixel_grid(cloud) is None:
        return None
    return [float(v) for v in eye]
