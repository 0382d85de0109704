"""The quarter turn a scan is prepared in: the same points turned by 90°, 180° or 270° about
the vertical, or given in another axis convention, are prepared as one scan.

Every grid of the preparation (voxels, cells) and every step after it (neighbour graphs,
MSAC's samples, the clusters' order) sees the coordinates, so a scan turned by a quarter
meets other voxels and other random draws, and a tenth of its detections move
(docs/benchmarks.md, "What the vote can steady"). A turn by a multiple of 90° about z is
exact in floating point (axes swapped and negated), so turning each scan into a pose
chosen from its own points makes the turned copies one input again, to the last bit.

The pose is chosen by two statistics that turn with the scan: the spread of the points
along x and along y (the longer side goes along x), and the skewness of their distribution
along each axis (the side where the room's mass lies further out goes to +x). Where neither
decides with a margin, the scan keeps its own axes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["QUARTER_RATIO", "QUARTER_SKEW", "quarter_matrix", "quarter_turns", "turn_quarters"]

#: The longer horizontal spread (standard deviation of x or y) must exceed the shorter by
#: this factor to decide which goes along x: an 80 % subsample of a real room moves the
#: ratio by under 0.01, a near-square room (5 % or less) leaves it to the skewness.
QUARTER_RATIO = 1.05
#: Smallest skewness (third standardized moment) that says which way an axis points: an
#: 80 % subsample moves it by about 0.01.
QUARTER_SKEW = 0.02


def _skews(xy: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    d = xy - xy.mean(axis=0)
    sd = np.sqrt((d * d).mean(axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        skew = (d**3).mean(axis=0) / sd**3
    return sd, np.nan_to_num(skew)


def quarter_turns(xyz: ArrayLike) -> int:
    """How many quarter turns (0-3, counter-clockwise about z) put a scan in its pose.

    The longer horizontal spread goes along x (when it exceeds the other by
    :data:`QUARTER_RATIO`), then the skewed side to +x: the turn whose x skewness is
    positive by at least :data:`QUARTER_SKEW`, or else whose y skewness is. A scan turned
    by ``q`` quarters gets ``k - q`` (mod 4), so both end in one pose; 0 when nothing
    decides (the scan keeps its axes).

    Examples
    --------
    >>> gen = np.random.default_rng(0)
    >>> pts = np.c_[gen.exponential(1.0, 2000) * 2, gen.normal(0, 1, 2000), np.zeros(2000)]
    >>> quarter_turns(pts)
    0
    >>> [quarter_turns(turn_quarters(pts, q)) for q in range(4)]
    [0, 3, 2, 1]
    >>> quarter_turns(np.zeros((3, 3)))
    0
    """
    pts = np.asarray(xyz, dtype=np.float64)
    if len(pts) < 3:
        return 0
    sd, skew = _skews(pts[:, :2])
    if not (np.all(np.isfinite(sd)) and sd.min() > 0):
        return 0
    if sd[0] >= QUARTER_RATIO * sd[1]:
        options = (0, 2)
    elif sd[1] >= QUARTER_RATIO * sd[0]:
        options = (1, 3)
    else:
        options = (0, 1, 2, 3)
    turned = {k: turn_quarters(np.r_[skew, 0.0], k)[:2] for k in options}
    for axis in (0, 1):
        best = max(options, key=lambda k: turned[k][axis])
        others = [turned[k][axis] for k in options if k != best]
        if turned[best][axis] >= QUARTER_SKEW and turned[best][axis] - max(others) >= QUARTER_SKEW:
            return best
    return 0


def quarter_matrix(k: int) -> NDArray[np.float64]:
    """(3, 3) rotation by ``k`` quarter turns counter-clockwise about z (exact: 0 and ±1).

    >>> quarter_matrix(1).astype(int).tolist()
    [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    """
    # Its columns are the axes turned; + 0.0 makes the zeros of negated ones positive.
    return turn_quarters(np.eye(3), k).T + 0.0


def turn_quarters(xyz: ArrayLike, k: int) -> NDArray[np.float64]:
    """Points (or directions) turned by ``k`` quarter turns about z, exactly: axes swapped
    and negated, no arithmetic (``xyz`` itself when ``k`` is 0 mod 4).

    >>> turn_quarters([[1.0, 2.0, 3.0]], 1).tolist(), turn_quarters([[1.0, 2.0, 3.0]], 2).tolist()
    ([[-2.0, 1.0, 3.0]], [[-1.0, -2.0, 3.0]])
    """
    pts = np.asarray(xyz, dtype=np.float64)
    k %= 4
    if k == 0:
        return pts
    x, y = pts[..., 0], pts[..., 1]
    out = pts.copy()
    if k == 1:
        out[..., 0], out[..., 1] = -y, x
    elif k == 2:
        out[..., 0], out[..., 1] = -x, -y
    else:
        out[..., 0], out[..., 1] = y, -x
    return out
