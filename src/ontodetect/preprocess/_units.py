"""Guesses about a scan's units and sampling: the spacing of its points and whether it
is in metres or millimetres. Preparation uses them to choose the scale factor k_s;
``ontodetect info`` (:mod:`ontodetect.summary`) shows them."""

from __future__ import annotations

import numpy as np

__all__ = ["MAX_METRIC_EXTENT", "SAMPLE_SIZE", "estimate_spacing", "guess_units"]

#: Points sampled for spacing and up-axis estimates; enough for a stable median.
SAMPLE_SIZE = 20_000
#: A room-scale scene measured in metres is at most this wide (a building floor).
MAX_METRIC_EXTENT = 500.0


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


def guess_units(xyz: np.ndarray, spacing: float | None = None) -> str:
    """ "metres" or "millimetres" (or "unknown"), from the size of the scene.

    Examples
    --------
    >>> import numpy as np
    >>> guess_units(np.array([[0, 0, 0], [4000.0, 3000, 2500]]))
    'millimetres'
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    if len(xyz) < 2:
        return "unknown"
    extent = float(np.max(np.ptp(xyz, axis=0)))
    if extent > MAX_METRIC_EXTENT:
        return "millimetres"
    if spacing is not None and spacing > 5.0:
        return "millimetres"
    return "metres"
