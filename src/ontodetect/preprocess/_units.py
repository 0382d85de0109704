"""Guesses about a scan's units and sampling: the spacing of its points and whether it
is in metres, centimetres or millimetres. Preparation uses them to choose the scale factor k_s;
``ontodetect info`` (:mod:`ontodetect.summary`) shows them."""

from __future__ import annotations

import numpy as np

__all__ = [
    "EXTENT_PERCENTILE",
    "MAX_CENTIMETRE_EXTENT",
    "MAX_METRIC_EXTENT",
    "SAMPLE_SIZE",
    "estimate_spacing",
    "guess_units",
    "robust_extent",
]

#: Points sampled for spacing and up-axis estimates; enough for a stable median.
SAMPLE_SIZE = 20_000
#: A room-scale scene measured in metres is at most this wide (a large hall; between the
#: percentiles below). Beyond it, a room is read in centimetres (a 1.5 m booth is 150).
MAX_METRIC_EXTENT = 120.0
#: Beyond MAX_METRIC_EXTENT and up to this, a scene is in centimetres (1.2-25 m): in
#: millimetres it would be a single object under 2.5 m, which is not a scene.
MAX_CENTIMETRE_EXTENT = 2500.0
#: The extent is measured between these percentiles of each axis, so that a few stray
#: points (one reflection a kilometre away) do not change the guess.
EXTENT_PERCENTILE = 0.5


def _sample(xyz: np.ndarray, size: int, seed: int) -> np.ndarray:
    if len(xyz) <= size:
        return xyz
    rng = np.random.default_rng(seed)
    return xyz[rng.choice(len(xyz), size, replace=False)]


def estimate_spacing(xyz: np.ndarray, *, sample: int = SAMPLE_SIZE, seed: int = 0) -> float:
    """Median distance from a point to its nearest neighbour.

    Parameters
    ----------
    xyz : (n, 3) float
        Points.
    sample : int
        At most this many points are queried (against all points).
    seed : int
        Seed of the sample.

    Returns
    -------
    float
        The median nearest-neighbour distance (0 for fewer than 2 points).

    Examples
    --------
    >>> import numpy as np
    >>> g = np.stack(np.meshgrid(np.arange(10), np.arange(10), [0]), -1).reshape(-1, 3)
    >>> round(estimate_spacing(g * 0.02), 6)
    0.02
    """
    from scipy.spatial import cKDTree  # heavy: imported when used (start-up)

    xyz = np.asarray(xyz, dtype=np.float64)
    if len(xyz) < 2:
        return 0.0
    tree = cKDTree(xyz)
    query = _sample(xyz, sample, seed)
    dist, _ = tree.query(query, k=2, workers=-1)
    d = dist[:, 1]
    d = d[d > 0]
    return float(np.median(d)) if d.size else 0.0


def robust_extent(xyz: np.ndarray) -> float:
    """The widest axis of the points, measured between the :data:`EXTENT_PERCENTILE` and
    ``100 - EXTENT_PERCENTILE`` percentiles (finite points only; 0 for none).

    Examples
    --------
    >>> import numpy as np
    >>> pts = np.r_[np.random.default_rng(0).uniform(0, 5, (1000, 3)), [[1000.0, 0, 0]]]
    >>> robust_extent(pts) < 5
    True
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    xyz = xyz[np.isfinite(xyz).all(axis=1)] if xyz.ndim == 2 else xyz.reshape(0, 3)
    if len(xyz) < 2:
        return 0.0
    lo, hi = np.percentile(xyz, [EXTENT_PERCENTILE, 100.0 - EXTENT_PERCENTILE], axis=0)
    return float(np.max(hi - lo))


def guess_units(xyz: np.ndarray, spacing: float | None = None) -> str:
    """ "metres", "centimetres" or "millimetres" (or "unknown"), from the size of the scene
    (:func:`robust_extent`, so a few far points do not flip it).

    Examples
    --------
    >>> import numpy as np
    >>> guess_units(np.array([[0, 0, 0], [4000.0, 3000, 2500]]))
    'millimetres'
    >>> guess_units(np.array([[0, 0, 0], [600.0, 400, 250]]))
    'centimetres'
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    if len(xyz) < 2:
        return "unknown"
    extent = robust_extent(xyz)
    if extent > MAX_CENTIMETRE_EXTENT:
        return "millimetres"
    if extent > MAX_METRIC_EXTENT:
        return "centimetres"
    if spacing is not None and spacing > 5.0:
        return "millimetres"
    return "metres"
