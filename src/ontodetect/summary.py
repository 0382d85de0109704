"""What a point cloud looks like at a glance: size, fields, spacing, units and up axis.

:func:`describe_cloud` is what ``ontodetect info`` prints. The guesses are
heuristics a person would make looking at the numbers: indoor rooms are a few
metres across (so a cloud tens of thousands of units wide is in millimetres),
and the up axis is what ``detect --up auto`` would use (:func:`ontodetect._up.guess_up`,
the one heuristic both share: floor, walls and furniture tops of a Manhattan frame).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ._units import estimate_spacing, guess_units
from ._up import guess_up, inferred_view
from .cloud import PointCloud, pixel_grid, sensor_position
from .errors import InvalidParameterError

__all__ = ["CloudSummary", "describe_cloud", "estimate_spacing", "guess_units", "guess_up"]


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
    #: The signed axis (``"z"``, ``"-y"``...) nearest to the up direction ``detect --up
    #: auto`` would estimate, that direction, its angle (deg) from the axis, and the
    #: confidence of the estimate (:func:`ontodetect._up.guess_up`).
    up_axis: str
    up_confidence: float
    up_vector: list[float]
    up_tilt: float
    #: What ``detect`` uses without ``--up``: ``"auto"`` for an organized or single-view
    #: cloud, ``"z"`` for any other.
    up_default: str
    extra: dict[str, Any] = field(default_factory=dict)
    #: Where the sensor stood when the cloud is one camera frame with its pixel grid
    #: (:func:`ontodetect.cloud.sensor_position`), else None.
    sensor: list[float] | None = None

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dictionary."""
        return asdict(self)


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
    # A bare-point view is taken as a frame by detect (detect.infer_view): say so.
    up = guess_up(inferred_view(cloud) or cloud, "auto")
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
        up_axis=up.axis,
        up_confidence=up.confidence,
        up_vector=[round(float(v), 6) for v in up.direction],
        up_tilt=round(up.angle, 3),
        up_default="auto" if up.single_view else "z",
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
