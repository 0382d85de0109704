"""Guesses about a scan's units and sampling: the spacing of its points and whether it
is in metres, centimetres or millimetres. Preparation uses them to choose the scale factor k_s;
``ontodetect info`` (:mod:`ontodetect.summary`) shows them."""

from __future__ import annotations

import numpy as np

from .errors import InvalidParameterError

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
    return xyz if len(xyz) <= size else xyz[_sample_rows(len(xyz), size, seed)]


def estimate_spacing(
    xyz: np.ndarray, *, sample: int = SAMPLE_SIZE, seed: int = 0, index: str = "kdtree"
) -> float:
    """Median distance from a point to its nearest neighbour.

    Parameters
    ----------
    xyz : (n, 3) float
        Points.
    sample : int
        At most this many points are queried (against all points).
    seed : int
        Seed of the sample.
    index : {"kdtree", "grid"}
        How neighbours are found; both give the same distances. ``"kdtree"`` (SciPy's
        cKDTree) is the faster search; ``"grid"`` (:func:`nearest_other_sq`, NumPy
        alone) is for a short-lived command such as ``ontodetect info``, where importing
        SciPy's spatial module would cost more than the search.

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
    xyz = np.asarray(xyz, dtype=np.float64)
    if len(xyz) < 2:
        return 0.0
    rows = _sample_rows(len(xyz), sample, seed)
    if index == "grid":
        d = np.sqrt(nearest_other_sq(xyz, rows))
    elif index == "kdtree":
        from scipy.spatial import cKDTree  # lazy: keeps SciPy's spatial off `info`'s path

        dist, _ = cKDTree(xyz).query(xyz[rows], k=2, workers=-1)
        d = dist[:, 1]
    else:
        raise InvalidParameterError("index", "one of kdtree, grid", index)
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


def _sample_rows(n: int, size: int, seed: int) -> np.ndarray:
    """The rows :func:`_sample` takes, in its order."""
    if n <= size:
        return np.arange(n)
    return np.random.default_rng(seed).choice(n, size, replace=False)


#: Cells of the nearest-neighbour grid hold about this many points on a surface.
_POINTS_PER_CELL = 4.0
#: Largest number of candidate pairs measured at once (memory: 40 bytes a pair).
_PAIR_CHUNK = 2_000_000


def nearest_other_sq(xyz: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(m,) float: squared distance from each of ``xyz[rows]`` to its nearest other point.

    Exact, as a k-d tree's second neighbour is (a duplicate of the point counts, at 0),
    with NumPy alone so that ``ontodetect info`` does not import SciPy's spatial module:
    points are hashed into cubic cells, each query point measures the points of the 27
    cells around it, and the cells grow where a query found no point close enough to be
    sure; ``inf`` for a lone point.

    Examples
    --------
    >>> import numpy as np
    >>> p = np.array([[0.0, 0, 0], [0.3, 0, 0], [0.3, 0.4, 0], [5, 5, 5]])
    >>> nearest_other_sq(p, np.arange(4)).round(6).tolist()
    [0.09, 0.09, 0.16, 68.25]
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    rows = np.asarray(rows, dtype=np.int64)
    best = np.full(len(rows), np.inf)
    if len(xyz) < 2 or len(rows) == 0:
        return best
    lo = xyz.min(axis=0)
    extent = float((xyz.max(axis=0) - lo).max())
    if extent == 0.0:
        return np.zeros(len(rows))  # every point is a duplicate of every other
    # A surface of size extent^2 holding n points: cells of a few points each.
    cell = extent * np.sqrt(_POINTS_PER_CELL / len(xyz))
    todo = np.arange(len(rows))
    while todo.size:
        _nearest_in_cells(xyz, rows[todo], lo, cell, best, todo)
        # A neighbour farther than one cell may hide a nearer one two cells away.
        todo = todo[best[todo] > cell * cell]
        if cell >= extent:
            break
        cell *= 2.0
    return best


def _nearest_in_cells(
    xyz: np.ndarray,
    queries: np.ndarray,
    lo: np.ndarray,
    cell: float,
    best: np.ndarray,
    slots: np.ndarray,
) -> None:
    """Lower ``best[slots]`` by the points in the 27 cells around each query row."""
    keys = np.floor((xyz - lo) / cell).astype(np.int64) + 1
    dims = keys.max(axis=0) + 2
    code = (keys[:, 0] * dims[1] + keys[:, 1]) * dims[2] + keys[:, 2]
    order = np.argsort(code, kind="stable")
    cells, cell_start, cell_count = np.unique(code[order], return_index=True, return_counts=True)
    # Queries in cell order: the look-ups below then walk the cells' table in order.
    by_cell = np.argsort(code[queries], kind="stable")
    queries, slots = queries[by_cell], slots[by_cell]
    qcode = code[queries]
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                shifted = qcode + (dx * dims[1] + dy) * dims[2] + dz
                at = np.minimum(np.searchsorted(cells, shifted), len(cells) - 1)
                hit = cells[at] == shifted
                start = np.where(hit, cell_start[at], 0)
                count = np.where(hit, cell_count[at], 0)
                for part in _chunks(count):
                    _measure_pairs(xyz, queries, order, start, count, part, best, slots)


def _chunks(count: np.ndarray) -> list[slice]:
    """Slices of queries whose candidate pairs stay within :data:`_PAIR_CHUNK`."""
    ends = np.cumsum(count)
    out, first = [], 0
    while first < len(count):
        base = ends[first - 1] if first else 0
        last = int(np.searchsorted(ends, base + _PAIR_CHUNK, side="right"))
        last = max(last, first + 1)
        out.append(slice(first, last))
        first = last
    return out


def _measure_pairs(
    xyz: np.ndarray,
    queries: np.ndarray,
    order: np.ndarray,
    start: np.ndarray,
    count: np.ndarray,
    part: slice,
    best: np.ndarray,
    slots: np.ndarray,
) -> None:
    c = count[part]
    total = int(c.sum())
    if total == 0:
        return
    which = np.repeat(np.arange(part.start, part.stop), c)
    first = np.repeat(start[part] - np.concatenate([[0], np.cumsum(c)[:-1]]), c)
    other = order[first + np.arange(total)]
    q = queries[which]
    keep = other != q
    diff = xyz[other[keep]] - xyz[q[keep]]
    d2 = np.einsum("ij,ij->i", diff, diff)
    np.minimum.at(best, slots[which[keep]], d2)
