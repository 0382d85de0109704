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

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "QUARTER_RATIO",
    "QUARTER_SKEW",
    "WALL_NEIGHBOURS",
    "WALL_POINTS",
    "WALL_QUERIES",
    "quarter_matrix",
    "quarter_turns",
    "turn_about_z",
    "turn_quarters",
    "wall_yaw",
]

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


#: Neighbours of each point whose scatter gives its surface's normal in :func:`wall_yaw`.
WALL_NEIGHBOURS = 12
#: :func:`wall_yaw` reads normals at about this many points of a scan ...
WALL_QUERIES = 20_000
#: ... among about this many (all of a smaller scan).
WALL_POINTS = 400_000


def _height_draw(z: NDArray[np.float64]) -> NDArray[np.float64]:
    """A number in [0, 1) drawn from each point's height alone (a hash of its bits): a
    turn about z, a move along x or y and a shuffle keep every point's draw, so a subset
    taken by it is the same points."""
    bits = np.ascontiguousarray(z + 0.0).view(np.uint64)  # + 0.0: -0.0 as 0.0
    with np.errstate(over="ignore"):  # SplitMix64's finaliser, modulo 2**64
        h = (bits ^ (bits >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        h = (h ^ (h >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        h = h ^ (h >> np.uint64(31))
    return (h >> np.uint64(11)).astype(np.float64) / float(1 << 53)


def wall_yaw(xyz: ArrayLike) -> float:
    """The walls' direction about z (radians, in (-pi/4, pi/4]), read so that it turns
    with the scan to the rounding error: a scan turned by ``a`` reads ``a`` more (mod 90°).

    The normal at a point is the least direction of its :data:`WALL_NEIGHBOURS` nearest
    neighbours' scatter, each weighed down smoothly to nothing at the farthest's distance
    (a neighbourhood the turn does not change, whichever of equally far points it takes),
    read at about :data:`WALL_QUERIES` points among about :data:`WALL_POINTS` (both drawn
    by a hash of each point's height, which a turn about z does not change); the direction
    is the fourth circular moment of the normals' horizontal parts, ``arg Σ p_i h_i^4 / 4``
    with ``h_i = n_x + i n_y`` and ``p_i`` the neighbourhood's planarity
    ``(λ1 - λ0) / λ2``.
    Every weight is a smooth function of what a turn about z keeps, so no point counts
    or not by a threshold: an upright surface (``|h| = 1``) counts fully, a level one not
    at all, and a wall and the wall across from it, or at a right angle to it, agree.
    0 for fewer than :data:`WALL_NEIGHBOURS` points or no upright surface.

    Examples
    --------
    >>> gen = np.random.default_rng(0)
    >>> wall = np.c_[gen.uniform(0, 4, 3000), np.zeros(3000), gen.uniform(0, 2.5, 3000)]
    >>> side = np.c_[np.zeros(2000), gen.uniform(0, 3, 2000), gen.uniform(0, 2.5, 2000)]
    >>> room = np.vstack([wall, side])
    >>> round(float(np.degrees(wall_yaw(room))), 2) + 0.0
    0.0
    >>> round(float(np.degrees(wall_yaw(turn_about_z(room, np.radians(20))))), 2)
    20.0
    """
    from scipy.spatial import cKDTree  # lazy: only scans prepared in the walls' frame

    pts = np.asarray(xyz, dtype=np.float64)
    if len(pts) < WALL_NEIGHBOURS:
        return 0.0
    # Subsets drawn by height, so that a turned or moved copy draws the same points.
    draw = _height_draw(pts[:, 2])
    pts, draw = pts[draw < WALL_POINTS / len(pts)], draw[draw < WALL_POINTS / len(pts)]
    queries = pts[draw < WALL_QUERIES / len(draw)] if len(draw) else pts
    if len(pts) < WALL_NEIGHBOURS or not len(queries):
        return 0.0
    dist, idx = cKDTree(pts).query(queries, k=WALL_NEIGHBOURS, workers=-1)
    # Each neighbour weighs less the further it is, nothing at the farthest's distance:
    # which of several points at the same distance is taken last then does not matter (a
    # scan on a grid has many such ties, and a turn breaks them another way).
    with np.errstate(invalid="ignore", divide="ignore"):
        w = np.nan_to_num(np.clip(1.0 - (dist / dist[:, -1:]) ** 2, 0.0, 1.0) ** 2, nan=1.0)
    w /= w.sum(axis=1, keepdims=True)
    near = pts[idx]
    near = near - np.einsum("nk,nki->ni", w, near)[:, None, :]
    lam, vec = np.linalg.eigh(np.einsum("nk,nki,nkj->nij", w, near, near))
    lam = np.maximum(lam, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        planar = np.nan_to_num((lam[:, 1] - lam[:, 0]) / lam[:, 2])
    terms = planar * (vec[:, 0, 0] + 1j * vec[:, 1, 0]) ** 4
    # Summed exactly (math.fsum), so that the rows' order does not enter the last bits.
    moment = complex(math.fsum(terms.real), math.fsum(terms.imag))
    return float(np.angle(moment) / 4) if moment != 0 else 0.0


def turn_about_z(xyz: ArrayLike, angle: float) -> NDArray[np.float64]:
    """Points turned by ``angle`` (radians, counter-clockwise) about the z axis.

    >>> turn_about_z([[1.0, 0.0, 2.0]], np.pi / 2).round(12).tolist()
    [[0.0, 1.0, 2.0]]
    """
    pts = np.asarray(xyz, dtype=np.float64)
    c, s = math.cos(angle), math.sin(angle)
    out = pts.copy()
    out[..., 0] = c * pts[..., 0] - s * pts[..., 1]
    out[..., 1] = s * pts[..., 0] + c * pts[..., 1]
    return out


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
