"""MSAC plane extraction and plane features (thesis §3.3, Algorithm 1 steps 8–9).

Every candidate cluster is broken into planar parts with MSAC, the M-estimator
sample consensus of Torr & Zisserman (2000): a plane hypothesis through three
random points is scored by the truncated quadratic cost ``sum(min(r², t²))``
instead of the plain RANSAC inlier count, so that of two planes with as many
points within the inlier distance ``t`` the tighter one wins. Each plane then
gets the features the ontological priors are written against: orientation
(tilt), height above the floor, size (length, width, area), point density and
colour, and every pair of planes gets its relation (angle, adjacency, which one
lies above the other).

- :class:`PlaneModel` and :func:`msac` fit one plane, robustly.
- :func:`extract_planes` peels planes off a cluster one after the other and
  describes each as a :class:`Plane`.
- :func:`plane_relations` measures every pair of planes (:class:`PlaneRelation`).

Coordinates are in metres with z up and the floor at ``floor_z`` (0 after
levelling). Everything is NumPy-vectorized: hypotheses are generated and scored
in batches, on a fixed random subset of the points when the cluster is large,
and only the best few of each batch are scored on all points.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError, cKDTree

from .._progress import progress
from ..errors import InvalidParameterError
from ..geometry import as_points, canonical_sign

__all__ = [
    "MsacResult",
    "Patch",
    "Plane",
    "PlaneModel",
    "PlaneRelation",
    "curved_patches",
    "extract_planes",
    "level_layers",
    "level_surfaces",
    "msac",
    "plane_relations",
    "seat_layer",
]

# -- tolerances and tuning constants --------------------------------------------------------

#: Points whose second principal spread is below this share of the first lie on a line:
#: no plane is defined by them (relative standard deviations).
COLLINEAR_RTOL = 1e-6
#: Points whose largest spread is below this share of their magnitude all coincide.
COINCIDENT_RTOL = 1e-12
#: A minimal sample is degenerate when the sine of the angle between its two edges is
#: below this: the three points are (numerically) collinear or two of them coincide.
SAMPLE_MIN_SINE = 1e-6
#: Number of minimal samples turned into hypotheses and scored at once.
HYPOTHESIS_BATCH = 64
#: Above this many points, hypotheses are first scored on a fixed random subset of this size.
SCORE_SUBSET = 2048
#: At most this many hypotheses of a batch (the best on the subset) are scored on all points.
VERIFY_PER_BATCH = 4
#: Least-squares refinements (re-selecting the inliers each time) after the sampling.
REFINE_ITERATIONS = 3
#: :func:`local_plane`: at most this many hypotheses, the most planar neighbourhoods ...
LOCAL_HYPOTHESES = 256
#: ... and least-squares refinement on the inliers until they no longer change (at most
#: this many times).
LOCAL_REFINE = 50
#: Size of a minimal sample for a plane.
SAMPLE_SIZE = 3

#: A plane with a tilt below this is oriented upwards (+z); above, away from the cluster.
UP_RULE_MAX_TILT_DEG = 45.0
#: Default tolerance of :meth:`Plane.is_horizontal` and :meth:`Plane.is_vertical`, in
#: degrees: the seat inclination of Table 4.1 (-6° to 6°).
ORIENTATION_TOLERANCE_DEG = 6.0
#: Length and width are the spread between these quantiles of the in-plane coordinates,
#: rescaled so that a uniformly sampled extent is measured without bias.
EXTENT_QUANTILE = 0.02
#: The area grid's cell is this many mean point spacings wide (about 9 points per full cell).
AREA_CELL_SPACINGS = 3.0
#: Planes with more inliers have the convex hull that orients their rectangle computed on a
#: random subset of this many.
HULL_MAX_POINTS = 4096
#: The hull's rectangle is taken to lie along the principal axes when its sides are within
#: this sine (about 1°) of them: its extents would be the same.
SAME_FRAME_SINE = 0.017
#: A border cell counts for at most this many full cells: counts scatter around their mean
#: (capping at 1 would shrink randomly sampled planes), but a dense seam should not inflate.
BORDER_CELL_CAP = 1.5
#: Fewer interior cells than this: the points per full cell come from the bounding extent.
MIN_INTERIOR_CELLS = 4
#: Up to this many inliers, connectivity is computed between the points themselves; above,
#: between the means of grid cells a third of the connectivity distance wide.
CONNECTIVITY_EXACT_MAX_POINTS = 4096
#: Cells per connectivity distance when the points are thinned for connectivity.
CONNECTIVITY_CELLS_PER_RADIUS = 3.0
#: Candidate planes rejected in a row (too small once split, or too short) before
#: :func:`extract_planes` gives up on the remaining points.
MAX_CONSECUTIVE_REJECTIONS = 3
#: A level layer (``extract_planes(level_first=True)``) is kept as a plane when its
#: least-squares fit is tilted by no more than this (degrees): Table 4.1's seat
#: inclination (±6°) with a margin for cushions ...
LEVEL_MAX_TILT = 10.0
#: ... and its points spread at least this far across (m): a seat or a top has depth,
#: while a horizontal band across a slanted or upright surface is a strip.
LEVEL_MIN_WIDTH = 0.1

#: Default cell of the xy footprint grid used by :func:`plane_relations`, metres.
FOOTPRINT_CELL = 0.05
#: Planes with more inliers are subsampled (evenly, in input order) for adjacency distance.
RELATION_MAX_POINTS = 2000
#: Plane i lies above plane j when its centroid is at least this much higher (metres) ...
ABOVE_MIN_GAP = 0.02
#: ... and at least this share of the smaller xy footprint is shared.
ABOVE_MIN_OVERLAP = 0.25

#: :func:`curved_patches`: planes of a cluster whose normals differ by at most this
#: (degrees) and that meet (``PATCH_GAP``) are strips of one curved surface. Half the
#: least angle between a seat and its backrest (60 deg, Table 4.1's recline) keeps a
#: seat and a back apart however they are cut.
PATCH_ANGLE = 30.0
#: ... meeting means coming within this (m): one sampling step of a scan, a seam.
PATCH_GAP = 0.04
#: ... and a group is curved when two of its planes differ by more than this (degrees);
#: flatter groups are pieces of one plane, which the scoring already joins.
PATCH_MIN_TURN = 10.0
#: :func:`level_surfaces`: level planes (tilt at most ``LEVEL_TILT`` degrees, the
#: scoring's horizontal parts) that meet with centroids at most ``LEVEL_STEP`` apart in
#: height (and inliers as close: a pillow's edge rests on the mattress) are pieces of one
#: lying surface: a mattress under its pillows and duvet folds. Pillows and seat cushions
#: stand 5-10 cm proud of what they lie on (catalogue); an armrest or a table top stands
#: 20 cm and more above a seat (EN 1335-1, Table 4.1), so it never joins one.
LEVEL_TILT = 10.0
LEVEL_STEP = 0.08
#: :func:`seat_layer`: where a seat may lie, metres above the floor: Table 4.1's seating
#: plane (35-75 cm) less 5 cm for a cushion that sags under its own cover (catalogue
#: upholstered seats, EN 1022 / EN 12520 domestic seat heights 38-48 cm).
SEAT_LAYER_HEIGHTS = (0.30, 0.75)
#: ... its points face up: a normal within this of the vertical (degrees). A seat is a
#: surface one sits on, so it faces up even where it is not one plane; a band of the same
#: height across a wall, a curtain or a backrest faces sideways.
SEAT_LAYER_FACING = 30.0
#: ... and it holds more than this share of the points of the cluster that face up at those
#: heights: the one surface there, not one shelf of several.
SEAT_LAYER_SHARE = 0.5
#: ... in a cluster that reaches this close (m) to the floor: a seat stands on its legs or
#: its base (a pillow on a bed, a cushion on a shelf do not).
SEAT_LAYER_FOOT = 0.1


def _readonly(a: NDArray[Any]) -> NDArray[Any]:
    a.flags.writeable = False
    return a


# NumPy reduces a tall (k, 3) array along axis 0 with an inner loop of 3: one column at a
# time is an order of magnitude faster.
def _col_mean(a: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([a[:, i].mean() for i in range(a.shape[1])])


def _col_std(a: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([a[:, i].std() for i in range(a.shape[1])])


def _col_min(a: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([a[:, i].min() for i in range(a.shape[1])])


def _col_span(a: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([np.ptp(a[:, i]) for i in range(a.shape[1])])


# -- parameter checks ----------------------------------------------------------------------


def _as_points(points: ArrayLike, name: str = "points") -> NDArray[np.float64]:
    """Finite (n, 3) coordinates; any empty input is no points."""
    try:
        if np.size(points) == 0:
            return np.zeros((0, 3))
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(
            name, "an (n, 3) array of coordinates", type(points).__name__
        ) from exc
    return as_points(points, name, finite=True)


def _positive(name: str, value: object, *, allow_zero: bool = False) -> float:
    ok = isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(float(value))
    if ok and (float(value) > 0 or (allow_zero and float(value) == 0)):
        return float(value)
    rule = "a finite float >= 0" if allow_zero else "a finite float > 0"
    raise InvalidParameterError(name, rule, value)


def _integer(name: str, value: object, minimum: int) -> int:
    if isinstance(value, Integral) and not isinstance(value, bool) and int(value) >= minimum:
        return int(value)
    raise InvalidParameterError(name, f"an int >= {minimum}", value)


# -- the plane model -----------------------------------------------------------------------


def _principal(
    pts: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], str]:
    """Principal frame of points (k >= 1, 3).

    Returns the points minus their centroid, the centroid, the principal
    directions (columns, least spread first) and why the points define no plane
    ("" when they do).
    """
    centroid = _col_mean(pts)
    centered = pts - centroid
    # The 3x3 scatter matrix costs O(k); its eigenvectors are the right-singular vectors.
    eig, vectors = np.linalg.eigh(centered.T @ centered / len(pts))
    spread = np.sqrt(np.clip(eig, 0.0, None))
    reason = ""
    if spread[2] <= COINCIDENT_RTOL * (1.0 + float(np.abs(centroid).max())):
        reason = "all points coincide"
    elif spread[1] <= COLLINEAR_RTOL * spread[2]:
        reason = "all points are collinear"
    return centered, centroid, vectors, reason


@dataclass(frozen=True, eq=False)
class PlaneModel:
    """The plane ``normal · x + offset = 0`` with a unit normal.

    A model built directly is normalised: ``normal`` is scaled to unit length and
    ``offset`` with it.

    Attributes
    ----------
    normal : (3,) float
        Unit normal.
    offset : float
        Signed distance term ``d``: the plane's distance to the origin is ``|d|``.

    Examples
    --------
    >>> m = PlaneModel.from_estimate([[0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]])
    >>> m.normal.tolist(), round(m.offset, 6)
    ([0.0, 0.0, 1.0], -1.0)
    >>> m.residuals([[0.5, 0.5, 1.25], [3, 3, 0]]).tolist()
    [0.25, 1.0]
    >>> PlaneModel.from_estimate([[0, 0, 0], [1, 1, 1], [2, 2, 2]]) is None  # collinear
    True
    """

    normal: NDArray[np.float64]
    offset: float

    def __post_init__(self) -> None:
        normal = np.asarray(self.normal, dtype=np.float64).reshape(-1).copy()
        offset = float(self.offset)
        norm = float(np.linalg.norm(normal)) if normal.shape == (3,) else 0.0
        if normal.shape != (3,) or not np.isfinite(normal).all() or norm == 0.0:
            raise InvalidParameterError("normal", "a finite non-zero 3-vector", self.normal)
        if not math.isfinite(offset):
            raise InvalidParameterError("offset", "a finite float", self.offset)
        object.__setattr__(self, "normal", _readonly(normal / norm))
        object.__setattr__(self, "offset", offset / norm)

    @classmethod
    def from_estimate(cls, points: ArrayLike) -> PlaneModel | None:
        """Fit the total-least-squares plane to points.

        The plane passes through the points' centroid; its normal is the direction
        of least spread (the last right-singular vector of the centred points). Of
        the two opposite normals the one :func:`canonical_sign` keeps is returned (the
        largest component positive, ties going to z, then y, then x), so that a
        horizontal plane's normal points up.

        Parameters
        ----------
        points : (k, 3) float
            At least 3 points.

        Returns
        -------
        PlaneModel or None
            None when the points define no plane: fewer than 3, non-finite, all
            coincident or all collinear.
        """
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < SAMPLE_SIZE:
            return None
        if not np.isfinite(pts).all():
            return None
        _, centroid, vectors, degenerate = _principal(pts)
        if degenerate:
            return None
        normal = vectors[:, 0]
        normal = canonical_sign(normal) * normal
        return cls(normal, -float(normal @ centroid))

    def signed_distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """Signed distance of every point, positive on the side the normal points to.

        Parameters
        ----------
        points : (n, 3) float

        Returns
        -------
        (n,) float
        """
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return pts @ self.normal + self.offset

    def residuals(self, points: ArrayLike) -> NDArray[np.float64]:
        """Absolute point-to-plane distance of every point.

        Absolute, as consensus methods compare residuals with a threshold; use
        :meth:`signed_distance` for the side.

        Parameters
        ----------
        points : (n, 3) float

        Returns
        -------
        (n,) float
        """
        return np.abs(self.signed_distance(points))


@dataclass(frozen=True, eq=False)
class MsacResult:
    """The outcome of :func:`msac`; falsy when no plane was found.

    Attributes
    ----------
    model : PlaneModel or None
        The plane, or None on failure.
    inliers : (k,) int
        Indices (into the points given) of the points within ``threshold`` of the
        plane, ascending; empty on failure.
    cost : float
        MSAC cost ``sum(min(r², t²))`` over all points given; ``inf`` on failure.
    trials : int
        Minimal samples drawn.
    reason : str
        Why no plane was found, when ``model`` is None.
    """

    model: PlaneModel | None
    inliers: NDArray[np.intp]
    cost: float
    trials: int
    reason: str = ""

    def __bool__(self) -> bool:
        return self.model is not None


def _failure(reason: str, trials: int = 0) -> MsacResult:
    return MsacResult(None, _readonly(np.zeros(0, dtype=np.intp)), math.inf, trials, reason)


def _trials_needed(inlier_ratio: float, confidence: float) -> float:
    """Samples needed to draw one all-inlier minimal sample with the given confidence."""
    if inlier_ratio <= 0.0:
        return math.inf
    p_good = inlier_ratio**SAMPLE_SIZE
    if p_good >= 1.0:
        return 1.0
    return max(1.0, math.ceil(math.log1p(-confidence) / math.log1p(-p_good)))


def _draw_triples(rng: np.random.Generator, m: int, size: int) -> NDArray[np.intp]:
    """``size`` samples of 3 distinct indices in ``range(m)``, uniformly, vectorized."""
    a = rng.integers(0, m, size)
    b = rng.integers(0, m - 1, size)
    b += b >= a
    c = rng.integers(0, m - 2, size)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    c += c >= lo
    c += c >= hi
    return np.stack([a, b, c], axis=1)


def _hypotheses(
    pts: NDArray[np.float64], triples: NDArray[np.intp]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Planes through the non-degenerate minimal samples: normals (h, 3), offsets (h,)."""
    p0 = pts[triples[:, 0]]
    e1 = pts[triples[:, 1]] - p0
    e2 = pts[triples[:, 2]] - p0
    # The cross product written out: np.cross costs more in overhead than in arithmetic here.
    cross = np.column_stack(
        [
            e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1],
            e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2],
            e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0],
        ]
    )
    norm = np.sqrt(np.einsum("ij,ij->i", cross, cross))
    scale = np.sqrt(np.einsum("ij,ij->i", e1, e1) * np.einsum("ij,ij->i", e2, e2))
    ok = norm > SAMPLE_MIN_SINE * scale
    normals = cross[ok] / norm[ok, None]
    offsets = -np.einsum("ij,ij->i", normals, p0[ok])
    return normals, offsets


def _costs(
    pts: NDArray[np.float64],
    normals: NDArray[np.float64],
    offsets: NDArray[np.float64],
    t2: float,
) -> NDArray[np.float64]:
    """MSAC cost of every hypothesis over the points."""
    # Hypotheses in rows: each reduction then runs over contiguous memory.
    r = normals @ pts.T
    r += offsets[:, None]
    np.square(r, out=r)
    np.minimum(r, t2, out=r)
    return r.sum(axis=1)


def msac(
    points: ArrayLike,
    *,
    threshold: float,
    max_trials: int = 1000,
    confidence: float = 0.999,
    min_inliers: int = 3,
    sample_indices: ArrayLike | None = None,
    rng: int | np.random.Generator | None = None,
) -> MsacResult:
    """Fit one plane robustly with MSAC (M-estimator sample consensus).

    Planes through random minimal samples of 3 points (collinear or coincident
    samples are skipped) are scored by the truncated quadratic cost
    ``sum(min(r², t²))`` over the points, ``r`` being the point-to-plane distance
    and ``t`` the threshold. The number of samples adapts to the inlier ratio
    ``w`` of the best plane so far: sampling stops once ``1 - (1 - w³)^trials``
    reaches ``confidence``, or after ``max_trials``. As long as no plane has
    ``min_inliers`` inliers, ``w = min_inliers / n`` is used, so that sampling
    also stops once such a plane would have been found with that confidence.
    The best plane is then refined by least squares on its inliers, re-selecting
    them, as long as the cost decreases.

    Hypotheses are scored in batches of :data:`HYPOTHESIS_BATCH`. Above
    :data:`SCORE_SUBSET` points they are first scored on a fixed random subset
    of that size, and those of the best :data:`VERIFY_PER_BATCH` of a batch
    that beat the best plane so far on the subset are scored on all points;
    the returned cost is always over all points.

    Parameters
    ----------
    points : (n, 3) float
        Coordinates.
    threshold : float
        Inlier distance ``t`` (> 0), in the points' unit (Table 4.1: 0.5–1.5 cm).
    max_trials : int
        Most minimal samples drawn (>= 1).
    confidence : float
        Wanted probability, in (0, 1), of having drawn at least one sample of
        inliers only.
    min_inliers : int
        Fewest inliers (>= 3) for the plane to count as found.
    sample_indices : (m,) int, optional
        Only these points are drawn into minimal samples (say, a region of
        interest); all points are still scored. Default: all points.
    rng : int or numpy.random.Generator, optional
        Seed or generator; the same points and seed give the same result.

    Returns
    -------
    MsacResult
        Truthy with the plane and its inliers; falsy, with a reason, when fewer
        than 3 points are given, they are all coincident or collinear, no sample
        was usable, or the best plane has fewer than ``min_inliers`` inliers.

    Raises
    ------
    InvalidParameterError
        If a parameter is out of range or the points are not a finite (n, 3) array.

    Notes
    -----
    The result depends on the order of the points, as samples are drawn by
    position: a permuted input gives the same plane up to the sampling noise,
    not necessarily bit for bit.

    Examples
    --------
    >>> gen = np.random.default_rng(0)
    >>> xy = gen.uniform(-1, 1, (200, 2))
    >>> pts = np.column_stack([xy, 0.5 + 0.002 * gen.standard_normal(200)])
    >>> pts[:10, 2] += 0.3  # ten outliers
    >>> result = msac(pts, threshold=0.01, rng=0)
    >>> normal = np.round(result.model.normal, 2) + 0.0  # + 0.0 turns -0.0 into 0.0
    >>> bool(result), normal.tolist(), round(result.model.offset, 2)
    (True, [0.0, 0.0, 1.0], -0.5)
    >>> sorted(set(range(200)) - set(result.inliers.tolist()))
    [0, 1, 2, 3, 4, 5, 6, 7, 8, 9]
    >>> msac(pts[:2], threshold=0.01).reason
    'fewer than 3 points (got 2)'
    """
    pts = _as_points(points)
    t = _positive("threshold", threshold)
    max_trials = _integer("max_trials", max_trials, 1)
    min_inliers = _integer("min_inliers", min_inliers, SAMPLE_SIZE)
    if not (
        isinstance(confidence, Real)
        and not isinstance(confidence, bool)
        and 0.0 < float(confidence) < 1.0
    ):
        raise InvalidParameterError("confidence", "a float in the open range (0, 1)", confidence)
    confidence = float(confidence)
    n = len(pts)
    pool: NDArray[np.intp] | None = None
    if sample_indices is not None:
        pool = np.asarray(sample_indices)
        if pool.size and (pool.ndim != 1 or not np.issubdtype(pool.dtype, np.integer)):
            raise InvalidParameterError(
                "sample_indices",
                "a 1-D array of point indices",
                f"{pool.dtype} array of shape {pool.shape}",
            )
        pool = np.unique(pool.astype(np.intp, copy=False))
        if pool.size and (pool[0] < 0 or pool[-1] >= n):
            raise InvalidParameterError(
                "sample_indices", f"indices in [0, {n})", f"range [{pool[0]}, {pool[-1]}]"
            )
    gen = np.random.default_rng(rng)

    if n < SAMPLE_SIZE:
        return _failure(f"fewer than 3 points (got {n})")
    if n < min_inliers:
        return _failure(f"fewer points ({n}) than min_inliers={min_inliers}")
    if pool is not None and pool.size < SAMPLE_SIZE:
        return _failure(f"fewer than 3 points to sample from (got {pool.size})")

    # Centre on the sample pool: offsets stay small and well conditioned far from the origin.
    centered, shift, _, reason = _principal(pts if pool is None else pts[pool])
    if reason:
        return _failure(reason if pool is None else f"{reason} (of sample_indices)")
    if pool is None:
        sample_pts = centered
    else:
        sample_pts, centered = centered, pts - shift
    m = len(sample_pts)

    t2 = t * t
    exact = n <= SCORE_SUBSET
    # A subset drawn with replacement is as good an estimate and costs no permutation.
    score_pts = centered if exact else centered[np.sort(gen.integers(0, n, SCORE_SUBSET))]
    # Until a plane of min_inliers exists, sample long enough to find one if it did.
    min_ratio = min(min_inliers, m) / m
    required = min(max_trials, _trials_needed(min_ratio, confidence))
    best_normal: NDArray[np.float64] | None = None
    best_offset = 0.0
    best_cost = best_score = math.inf
    trials = 0
    while trials < required:
        batch = int(min(HYPOTHESIS_BATCH, required - trials))
        trials += batch
        normals, offsets = _hypotheses(sample_pts, _draw_triples(gen, m, batch))
        if len(normals) == 0:
            continue
        scores = _costs(score_pts, normals, offsets, t2)
        pick = np.argsort(scores, kind="stable")[: 1 if exact else VERIFY_PER_BATCH]
        # Only hypotheses that beat the best one on the subset are worth a full pass.
        pick = pick[scores[pick] < best_score]
        if pick.size == 0:
            continue
        full = scores[pick] if exact else _costs(centered, normals[pick], offsets[pick], t2)
        k = int(np.argmin(full))
        if full[k] >= best_cost:
            continue
        best_cost, best_score = float(full[k]), float(scores[pick[k]])
        best_normal, best_offset = normals[pick[k]], float(offsets[pick[k]])
        ratio_pts = score_pts if pool is None else sample_pts
        count = np.count_nonzero(np.abs(ratio_pts @ best_normal + best_offset) <= t)
        ratio = max(count / len(ratio_pts), min_ratio)
        required = min(max_trials, _trials_needed(ratio, confidence))

    if best_normal is None:
        return _failure(f"no non-degenerate sample of 3 points in {trials} trials", trials)

    best_normal, best_offset, best_cost, r = _refine(
        centered, best_normal, best_offset, best_cost, t, REFINE_ITERATIONS
    )
    inliers = np.flatnonzero(np.abs(r) <= t)
    if inliers.size < min_inliers:
        return _failure(
            f"the best plane has {inliers.size} inliers, fewer than min_inliers={min_inliers}",
            trials,
        )
    model = PlaneModel(best_normal, best_offset - float(best_normal @ shift))
    return MsacResult(model, _readonly(inliers), best_cost, trials)


def _refine(
    centered: NDArray[np.float64],
    normal: NDArray[np.float64],
    offset: float,
    cost: float,
    t: float,
    iterations: int,
) -> tuple[NDArray[np.float64], float, float, NDArray[np.float64]]:
    """Least-squares refinement of a plane on its inliers, kept only while the truncated
    cost decreases, stopping when the inliers no longer change: the plane, its cost and
    the residuals of every point."""
    t2 = t * t
    r = centered @ normal + offset
    inside = np.abs(r) <= t
    for _ in range(iterations):
        refined = PlaneModel.from_estimate(centered[inside])
        if refined is None:
            break
        r_new = centered @ refined.normal + refined.offset
        new_cost = float(np.minimum(r_new * r_new, t2).sum())
        if new_cost >= cost:
            break
        normal, offset, cost, r = refined.normal, refined.offset, new_cost, r_new
        previous, inside = inside, np.abs(r) <= t
        if np.array_equal(inside, previous):
            break  # the same inliers give the same fit
    return normal, offset, cost, r


def local_plane(
    points: ArrayLike,
    normals: ArrayLike,
    variation: ArrayLike,
    *,
    threshold: float,
    min_inliers: int = 3,
) -> MsacResult:
    """Fit one plane with MSAC's cost, from hypotheses the surface itself gives.

    Instead of planes through random triples of points, the hypotheses are the planes
    through the :data:`LOCAL_HYPOTHESES` most planar points along their local normals
    (least surface ``variation`` first, ties by position). The one of least truncated
    quadratic cost ``sum(min(r², t²))`` is refined by least squares on its inliers until
    they no longer change: the cost never grows on the way, and the plane reached is
    the same from any hypothesis in its basin. No random draw: the same surface gives
    the same plane, and a surface moved by a fraction of a millimetre the same plane
    moved with it, where random samples would settle on any of the planes whose cost is
    within their sampling noise (a seat found whole or in part, a backrest or not).

    Parameters
    ----------
    points : (n, 3) float
    normals : (n, 3) float
        Unit local normals (e.g. ``ontodetect.preprocess.graph_normals``).
    variation : (n,) float
        Surface variation of each point's neighbourhood (0: flat).
    threshold : float
        Inlier distance ``t`` (> 0).
    min_inliers : int
        Fewest inliers (>= 3) for the plane to count as found.

    Returns
    -------
    MsacResult
        As :func:`msac` (``trials`` is the number of hypotheses scored).

    Examples
    --------
    >>> gen = np.random.default_rng(0)
    >>> xy = gen.uniform(-1, 1, (400, 2))
    >>> pts = np.column_stack([xy, 0.5 + 0.002 * gen.standard_normal(400)])
    >>> pts[:20, 2] += 0.3
    >>> up = np.tile([0.0, 0.0, 1.0], (400, 1))
    >>> found = local_plane(pts, up, np.zeros(400), threshold=0.01)
    >>> round(found.model.offset, 2), found.inliers.size
    (-0.5, 380)
    """
    pts = _as_points(points)
    t = _positive("threshold", threshold)
    min_inliers = _integer("min_inliers", min_inliers, SAMPLE_SIZE)
    n = len(pts)
    nrm = np.asarray(normals, dtype=np.float64).reshape(n, 3)
    var = np.asarray(variation, dtype=np.float64).reshape(n)
    if n < SAMPLE_SIZE:
        return _failure(f"fewer than 3 points (got {n})")
    if n < min_inliers:
        return _failure(f"fewer points ({n}) than min_inliers={min_inliers}")
    shift = _col_mean(pts)
    centered = pts - shift
    order = np.lexsort((np.arange(n), var))
    cand = order[:LOCAL_HYPOTHESES]
    cn = nrm[cand]
    offsets = -np.einsum("ij,ij->i", cn, centered[cand])
    t2 = t * t
    costs = _costs(centered, cn, offsets, t2)
    k = int(np.argmin(costs))
    normal, offset, best, r = _refine(
        centered, cn[k], float(offsets[k]), float(costs[k]), t, LOCAL_REFINE
    )
    inliers = np.flatnonzero(np.abs(r) <= t)
    if inliers.size < min_inliers:
        return _failure(
            f"the best plane has {inliers.size} inliers, fewer than min_inliers={min_inliers}",
            len(cand),
        )
    model = PlaneModel(np.asarray(normal, dtype=np.float64), offset - float(normal @ shift))
    return MsacResult(model, _readonly(inliers), best, len(cand))


def level_layers(
    points: ArrayLike,
    *,
    threshold: float,
    min_inliers: int = 3,
) -> list[NDArray[np.intp]]:
    """The level layers of a set of points, densest first: the points within a band
    ``2 * threshold`` high, the bands chosen greedily without overlap among all the bands
    that start at a point's height, each holding at least ``min_inliers`` points.

    Seats and tops are level (Table 4.1: seat inclination within ±6°) and the scan is
    levelled: where a gently curved seat gives no plane more inliers than a slanted one
    through seat and backrest, its heights still pile up in one band. No random draw: the
    same heights give the same layers, whatever the order of the points.

    Parameters
    ----------
    points : (n, 3) float
        Levelled, z up.
    threshold : float
        Half the band's height (> 0): the MSAC inlier distance.
    min_inliers : int
        Fewest points (>= 1) in a band.

    Returns
    -------
    list of (k,) int
        Positions of each band's points, ascending, densest band first (ties: the lower).

    Examples
    --------
    >>> gen = np.random.default_rng(0)
    >>> seat = np.column_stack([gen.uniform(0, 0.4, (200, 2)), 0.45 + 0.003 * gen.random(200)])
    >>> top = np.column_stack([gen.uniform(0, 0.4, (80, 2)), np.full(80, 0.75)])
    >>> [len(b) for b in level_layers(np.vstack([seat, top]), threshold=0.01, min_inliers=50)]
    [200, 80]
    """
    pts = _as_points(points)
    t = _positive("threshold", threshold)
    min_inliers = _integer("min_inliers", min_inliers, 1)
    z = pts[:, 2]
    order = np.argsort(z, kind="stable")
    zs = z[order]
    ends = np.searchsorted(zs, zs + 2.0 * t, side="right")
    counts = ends - np.arange(len(zs))
    taken = np.zeros(len(zs), dtype=bool)
    out: list[NDArray[np.intp]] = []
    for start in np.lexsort((np.arange(len(zs)), -counts)):
        if counts[start] < min_inliers:
            break
        band = slice(int(start), int(ends[start]))
        if taken[band].any():
            continue
        taken[band] = True
        out.append(np.sort(order[band]))
    return out


# -- plane features --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Plane:
    """A planar part of a cluster and the features the ontological priors score.

    Attributes
    ----------
    normal : (3,) float
        Unit normal. A plane tilted less than 45° points up (+z); a steeper one
        points away from the centroid of all the points given to
        :func:`extract_planes` (a backrest's normal points away from its seat).
    offset : float
        ``normal · x + offset = 0`` on the plane.
    centroid : (3,) float
        Mean of the inliers.
    inliers : (k,) int
        Indices of the inliers in the points given to :func:`extract_planes`, ascending.
    axes : (2, 3) float
        In-plane unit directions, the longer extent first; ``axes[0] × axes[1] = normal``.
    length : float
        Extent along ``axes[0]``, metres: the spread between the 2nd and 98th
        percentiles rescaled by 1/0.96 (unbiased for uniform sampling, blind to a
        few stray points), never more than the full spread. The axes are those
        of the smallest robust rectangle around the points among the principal
        axes and the sides of the smallest rectangle around their convex hull.
        Points on a grid (voxel centres) span one grid step less than the
        voxels they stand for: length, width and area then measure the centres.
    width : float
        Extent along ``axes[1]`` (``width <= length``).
    area : float
        Covered area, m²: the points are binned in a grid in the plane whose cell
        holds about 9 points when full (or of the cell size asked for); a cell
        with its four neighbours occupied counts in full, a border cell for the
        share of a full cell's points it holds. Holes and L shapes are measured
        as such, and partly covered border cells count in part. Within a few per
        cent for 300 points or more; planes of fewer than about 150 points come
        out some 5–10 % small.
    tilt : float
        Angle between the normal and the vertical, degrees in [0, 90]: 0 for a
        horizontal plane (a seat), 90 for a vertical one (a wall).
    height : float
        Centroid z above ``floor_z``, metres.
    z_min, z_max : float
        Lowest and highest inlier z (absolute, not above the floor).
    density : float
        Inliers per square metre (``num_points / area``).
    color_mean : (3,) float or None
        Mean colour of the inliers (in the colours' own scale, 0..255 for uint8).
    color_std : (3,) float or None
        Standard deviation of the inliers' colours.
    num_points : int
        Number of inliers.
    rms : float
        Root mean square distance of the inliers to the plane, metres.
    """

    normal: NDArray[np.float64]
    offset: float
    centroid: NDArray[np.float64]
    inliers: NDArray[np.intp]
    axes: NDArray[np.float64]
    length: float
    width: float
    area: float
    tilt: float
    height: float
    z_min: float
    z_max: float
    density: float
    color_mean: NDArray[np.float64] | None
    color_std: NDArray[np.float64] | None
    num_points: int
    rms: float

    @property
    def model(self) -> PlaneModel:
        """The plane as a :class:`PlaneModel`."""
        return PlaneModel(self.normal, self.offset)

    def is_horizontal(self, tolerance: float = ORIENTATION_TOLERANCE_DEG) -> bool:
        """True when the tilt is at most ``tolerance`` degrees (default: ±6°, Table 4.1)."""
        return self.tilt <= tolerance

    def is_vertical(self, tolerance: float = ORIENTATION_TOLERANCE_DEG) -> bool:
        """True when the tilt is at least ``90 - tolerance`` degrees."""
        return self.tilt >= 90.0 - tolerance


@dataclass(frozen=True, eq=False)
class Patch(Plane):
    """A curved surface of a cluster: MSAC planes (its ``members``) that meet along seams
    with normals turning by less than :data:`PATCH_ANGLE` from one to the next, measured
    as one surface (a shell seat, a body-shaped backrest, a sloping cushion).

    Its features are a plane's, fitted to all the members' inliers (the normal is the
    least-spread direction, the mean of a gently curved surface); ``rms`` tells how far
    the surface departs from that plane.

    Attributes
    ----------
    members : tuple of int
        Indices of its planes in the cluster's list.
    spread : float
        Root mean square angle (degrees) between the members' normals and the patch's,
        weighted by the members' areas: 0 for a plane.
    kind : str
        ``"curved"`` (:func:`curved_patches`), ``"lying"`` (:func:`level_surfaces`: level
        pieces of one lying surface, which only the parts that say ``lying`` may take) or
        ``"layer"`` (:func:`seat_layer`: a seat MSAC did not fit, for the parts that say
        ``layer``).
    """

    members: tuple[int, ...] = ()
    spread: float = 0.0
    kind: str = "curved"


def curved_patches(
    points: ArrayLike,
    planes: Sequence[Plane],
    relations: Sequence[PlaneRelation],
    colors: ArrayLike | None = None,
    *,
    floor_z: float = 0.0,
    max_angle: float = PATCH_ANGLE,
    max_gap: float = PATCH_GAP,
    rng: int | np.random.Generator | None = None,
) -> list[Patch]:
    """The curved surfaces among a cluster's planes (:class:`Patch`).

    Planes join when their normals differ by at most ``max_angle`` degrees and they
    come within ``max_gap`` (``relations``, :func:`plane_relations`); each group of
    joined planes whose normals turn by more than :data:`PATCH_MIN_TURN` somewhere is
    one patch. MSAC cuts a curved backrest into strips that each cost as clutter and
    each measure a fraction of the back; the patch measures the back.

    Parameters
    ----------
    points : (n, 3) float
        The points the planes were extracted from (their ``inliers`` index them).
    planes : sequence of Plane
    relations : sequence of PlaneRelation
        Of those planes.
    colors : (n, 3) float, optional
    floor_z : float
        Height of the floor, for the patches' ``height``.
    max_angle, max_gap : float
        Degrees and metres, > 0.
    rng : int or numpy.random.Generator, optional
        For the patches' rectangle fit, as :func:`extract_planes`.

    Returns
    -------
    list of Patch
        By their lowest member.

    Examples
    --------
    >>> pts, gen = [], np.random.default_rng(0)  # a back bent by 10 degrees at 7 seams
    >>> for k, a in enumerate(np.radians(10.0 * np.arange(8))):
    ...     u = gen.uniform(0.0, 0.1, 200)
    ...     x = sum(0.1 * np.cos(np.radians(10.0 * i)) for i in range(k)) + u * np.cos(a)
    ...     z = sum(0.1 * np.sin(np.radians(10.0 * i)) for i in range(k)) + u * np.sin(a)
    ...     pts.append(np.c_[x, gen.uniform(0.0, 0.5, 200), z + 0.4])
    >>> pts = np.vstack(pts)
    >>> planes = extract_planes(pts, threshold=0.005, max_planes=8, rng=0)
    >>> patches = curved_patches(pts, planes, plane_relations(pts, planes), rng=0)
    >>> len(patches), len(patches[0].members) >= 4, patches[0].spread > 10
    (1, True, True)
    """
    pts = _as_points(points)
    max_angle = _positive("max_angle", max_angle)
    max_gap = _positive("max_gap", max_gap, allow_zero=True)
    joined = [
        (r.i, r.j)
        for r in relations
        if float(r.angle) <= max_angle and float(r.distance) <= max_gap
    ]
    return _joined_patches(
        pts, planes, joined, colors, floor_z=floor_z, rng=rng, kind="curved",
        group_ok=lambda normals: _turn(normals) > PATCH_MIN_TURN,
    )  # fmt: skip


def _turn(normals: NDArray[np.float64]) -> float:
    """The largest angle (degrees) between two of the unit ``normals`` (k, 3), unsigned."""
    return float(np.degrees(np.arccos(np.clip(np.abs(normals @ normals.T), 0.0, 1.0))).max())


def _joined_patches(
    pts: NDArray[np.float64],
    planes: Sequence[Plane],
    joined: Sequence[tuple[int, int]],
    colors: ArrayLike | None,
    *,
    floor_z: float,
    rng: int | np.random.Generator | None,
    kind: str,
    group_ok: Callable[[NDArray[np.float64]], bool] = lambda normals: True,
    fit_ok: Callable[[Plane], bool] = lambda fit: True,
) -> list[Patch]:
    """One :class:`Patch` of ``kind`` for every group of two or more planes the ``joined``
    pairs connect, fitted to all their inliers and measured whole, by lowest member;
    ``group_ok`` (on the members' normals) and ``fit_ok`` (on the fit) may turn one down."""
    if not joined:
        return []
    n = len(planes)
    i, j = np.array(joined, dtype=np.int64).T
    _, label = connected_components(coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n)))
    groups = [np.flatnonzero(label == g).tolist() for g in range(int(label.max()) + 1)]
    rgb = None if colors is None else np.asarray(colors, dtype=np.float64)
    gen = np.random.default_rng(rng)
    centroid = _col_mean(pts)
    out: list[Patch] = []
    for members in sorted(groups):
        if len(members) < 2:
            continue
        normals = np.array([planes[i].normal for i in members], dtype=np.float64)
        if not group_ok(normals):
            continue
        idx = np.unique(np.concatenate([np.asarray(planes[i].inliers) for i in members]))
        fit = _describe(
            pts, idx, rgb, floor_z=float(floor_z), cluster_centroid=centroid,
            area_cell=None, rng=gen,
        )  # fmt: skip
        if fit is None or not fit_ok(fit):
            continue
        areas = np.array([float(planes[i].area) for i in members])
        out.append(_patch(fit, normals, tuple(members), kind, weights=areas))
    return out


def _patch(
    fit: Plane,
    normals: NDArray[np.float64],
    members: tuple[int, ...],
    kind: str,
    weights: NDArray[np.float64] | None = None,
) -> Patch:
    """The :class:`Patch` of ``kind`` measured as the plane ``fit``, its ``spread`` the
    root mean square angle (degrees) of ``normals`` about its own (weighed by ``weights``)."""
    cos = np.clip(np.abs(normals @ np.asarray(fit.normal)), 0.0, 1.0)
    spread = float(np.sqrt(np.average(np.degrees(np.arccos(cos)) ** 2, weights=weights)))
    fields = {f.name: getattr(fit, f.name) for f in dataclasses.fields(Plane)}
    return Patch(**fields, members=members, spread=spread, kind=kind)


def level_surfaces(
    points: ArrayLike,
    planes: Sequence[Plane],
    relations: Sequence[PlaneRelation],
    colors: ArrayLike | None = None,
    *,
    floor_z: float = 0.0,
    max_tilt: float = LEVEL_TILT,
    max_step: float = LEVEL_STEP,
    max_gap: float = LEVEL_STEP,
    rng: int | np.random.Generator | None = None,
) -> list[Patch]:
    """The lying surfaces a cluster's level planes piece together (:class:`Patch`).

    Level planes (tilt at most ``max_tilt`` degrees) join when their inliers come within
    ``max_gap`` (``relations``, :func:`plane_relations`; a pillow's edge rests on the
    mattress, a cushion's on the next) and their centroids lie at most ``max_step`` apart
    in height; each group of two or more is one surface, fitted and
    measured whole. MSAC takes the largest flat piece of a made bed, a row of cushions or
    a cluttered top, and the part it stands for then measures a fraction of its length;
    the surface measures all of it.

    Parameters
    ----------
    points : (n, 3) float
        The points the planes were extracted from (their ``inliers`` index them).
    planes : sequence of Plane
    relations : sequence of PlaneRelation
        Of those planes.
    colors : (n, 3) float, optional
    floor_z : float
        Height of the floor, for the surfaces' ``height``.
    max_tilt, max_step, max_gap : float
        Degrees, metres and metres, > 0.
    rng : int or numpy.random.Generator, optional
        For the surfaces' rectangle fit, as :func:`extract_planes`.

    Returns
    -------
    list of Patch
        By their lowest member, of ``kind`` ``"lying"``; ``spread`` is the members' tilt
        about the surface.

    Examples
    --------
    >>> gen = np.random.default_rng(0)  # a 2 m mattress and a pillow 6 cm proud of it
    >>> mattress = np.c_[gen.uniform(0, 1.4, 3000), gen.uniform(0, 1.4, 3000), np.full(3000, 0.5)]
    >>> pillow = np.c_[gen.uniform(1.4, 2.0, 900), gen.uniform(0, 1.4, 900), np.full(900, 0.56)]
    >>> pts = np.vstack([mattress, pillow])
    >>> planes = extract_planes(pts, threshold=0.01, max_planes=4, rng=0)
    >>> [round(p.length, 1) for p in planes]
    [1.4, 1.4]
    >>> surfaces = level_surfaces(pts, planes, plane_relations(pts, planes), rng=0)
    >>> len(surfaces), round(surfaces[0].length, 1), surfaces[0].members
    (1, 2.0, (0, 1))
    """
    pts = _as_points(points)
    max_tilt = _positive("max_tilt", max_tilt)
    max_step = _positive("max_step", max_step, allow_zero=True)
    max_gap = _positive("max_gap", max_gap, allow_zero=True)
    level = [float(p.tilt) <= max_tilt for p in planes]
    joined = [
        (r.i, r.j)
        for r in relations
        if level[r.i]
        and level[r.j]
        and float(r.distance) <= max_gap
        and abs(float(r.vertical_gap)) <= max_step
    ]
    return _joined_patches(
        pts, planes, joined, colors, floor_z=floor_z, rng=rng, kind="lying",
        fit_ok=lambda fit: fit.tilt <= max_tilt,
    )  # fmt: skip


def seat_layer(
    points: ArrayLike,
    planes: Sequence[Plane],
    normals: ArrayLike | Callable[[], ArrayLike],
    colors: ArrayLike | None = None,
    *,
    threshold: float,
    min_points: int,
    connectivity: float,
    floor_z: float = 0.0,
    heights: tuple[float, float] = SEAT_LAYER_HEIGHTS,
    facing: float = SEAT_LAYER_FACING,
    rng: int | np.random.Generator | None = None,
) -> Patch | None:
    """The level surface facing up at seat height that MSAC did not fit as a plane.

    An upholstered, cane or sagging seat is level (Table 4.1: within ±6°) but not flat:
    MSAC's plane with the most inliers then runs slanted through seat and backrest, and the
    seat is never a plane of its own. Its points still face up and pile up at one height.
    Only a cluster that reaches within :data:`SEAT_LAYER_FOOT` of the floor is searched: a
    seat stands on its legs or base. ``normals`` are one per point, or a function that
    gives them, called only when needed. Among the points at ``heights`` whose normals
    are within ``facing`` degrees of the vertical, the densest level layer
    (:func:`level_layers`, ``threshold`` half its height) is taken, its largest
    connected piece (steps of ``connectivity``) fitted and measured whole, when that
    piece holds at least ``min_points`` points and more than
    :data:`SEAT_LAYER_SHARE` of the upward-facing points there, spreads at least
    :data:`LEVEL_MIN_WIDTH` across and fits within :data:`LEVEL_MAX_TILT` of level. Nothing
    is offered where a level plane already lies at those heights.

    Returns
    -------
    Patch or None
        Of ``kind`` ``"layer"``, ``members`` the planes that hold half their inliers or
        more in it (only the parts that say ``layer`` may take it); ``spread`` the rms
        angle of its points' normals about its own.

    Examples
    --------
    >>> gen = np.random.default_rng(0)  # a cushion sagging 2 cm, a backrest behind it
    >>> u, v = gen.uniform(0, 0.45, (2, 900))
    >>> seat = np.c_[u, v, 0.45 - 0.08 * ((u - 0.22) ** 2 + (v - 0.22) ** 2)]
    >>> b, h = gen.uniform(0, 0.45, (2, 600))
    >>> back = np.c_[b, np.full(600, 0.47), 0.5 + h]
    >>> xy = np.repeat([[0.02, 0.02], [0.43, 0.02], [0.02, 0.43], [0.43, 0.43]], 100, axis=0)
    >>> legs = np.c_[xy, gen.uniform(0.0, 0.4, 400)]  # down to the floor
    >>> pts = np.vstack([seat, back, legs])
    >>> nrm = np.repeat([[0.0, 0, 1], [0.0, 1, 0], [1.0, 0, 0]], [900, 600, 400], axis=0)
    >>> layer = seat_layer(pts, [], nrm, threshold=0.01, min_points=20, connectivity=0.05)
    >>> layer.kind, round(layer.height, 2), layer.num_points > 600
    ('layer', 0.45, True)
    >>> seat_layer(pts[:1500], [], nrm[:1500], threshold=0.01, min_points=20,
    ...            connectivity=0.05) is None  # nothing under it to the floor: a pillow
    True
    """
    pts = _as_points(points)
    lo, hi = float(heights[0]) + floor_z, float(heights[1]) + floor_z
    if not len(pts) or float(pts[:, 2].min()) > floor_z + SEAT_LAYER_FOOT:
        return None
    for p in planes:
        if float(p.tilt) <= LEVEL_MAX_TILT and lo <= float(p.centroid[2]) <= hi:
            return None
    nrm = np.asarray(normals() if callable(normals) else normals, dtype=np.float64)
    up = np.abs(nrm[:, 2]) >= math.cos(math.radians(facing))
    cand = np.flatnonzero(up & (pts[:, 2] >= lo) & (pts[:, 2] <= hi))
    if cand.size < min_points:
        return None
    bands = level_layers(pts[cand], threshold=threshold, min_inliers=min_points)
    if not bands:
        return None
    band = cand[bands[0]]
    piece = band[_largest_component(pts[band, :2], connectivity)]
    if piece.size < min_points or piece.size <= SEAT_LAYER_SHARE * cand.size:
        return None
    rgb = None if colors is None else np.asarray(colors, dtype=np.float64)
    fit = _describe(
        pts, piece, rgb, floor_z=float(floor_z), cluster_centroid=_col_mean(pts),
        area_cell=None, rng=np.random.default_rng(rng),
    )  # fmt: skip
    if fit is None or float(fit.tilt) > LEVEL_MAX_TILT or float(fit.width) < LEVEL_MIN_WIDTH:
        return None
    inside = np.zeros(len(pts), dtype=bool)
    inside[piece] = True
    members = tuple(
        k
        for k, p in enumerate(planes)
        if 2 * int(inside[np.asarray(p.inliers)].sum()) >= len(p.inliers)
    )
    return _patch(fit, nrm[piece], members, "layer")


def _in_plane_basis(normal: NDArray[np.float64]) -> NDArray[np.float64]:
    """Two unit vectors (2, 3) completing ``normal`` to an orthonormal basis."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    return np.stack([u, np.cross(normal, u)])


def _cell_table(
    ij: NDArray[np.int64],
) -> tuple[NDArray[np.int64], NDArray[np.intp], NDArray[np.intp], int]:
    """Occupied cells of 2-D integer cell coordinates (k, 2) >= 0.

    Returns the sorted unique cell keys, the cell of every point, the count of
    every cell and the key stride between rows (keys of 4-neighbours differ by 1
    or by the stride, with a margin so that no neighbour wraps around).
    """
    stride = int(ij[:, 1].max()) + 3
    keys = (ij[:, 0] + 1) * stride + (ij[:, 1] + 1)
    cells, which, counts = np.unique(keys, return_inverse=True, return_counts=True)
    return cells, which.reshape(-1), counts, stride


def _occupied_area(uv: NDArray[np.float64], cell: float, full_count: float) -> float:
    """Area covered by 2-D points (k, 2) binned in square cells ``cell`` wide.

    A cell whose four neighbours are occupied is inside the shape and counts in
    full; a border cell counts for the share of a full cell's points it holds
    (capped at :data:`BORDER_CELL_CAP`), a full cell's count being the mean
    count of the inside cells, or ``full_count`` when there are fewer than
    :data:`MIN_INTERIOR_CELLS`. Counting inside cells in full keeps random
    sampling (whose counts scatter around the mean) from shrinking the area.
    """
    ij = np.floor((uv - _col_min(uv)) / cell).astype(np.int64)
    cells, _, counts, stride = _cell_table(ij)
    neighbours = cells[:, None] + np.array([-stride, -1, 1, stride])
    interior = np.isin(neighbours, cells).all(axis=1)
    inside = int(np.count_nonzero(interior))
    if inside >= MIN_INTERIOR_CELLS:
        full_count = float(counts[interior].mean())
    border = np.minimum(counts[~interior] / full_count, BORDER_CELL_CAP).sum()
    return float((inside + border) * cell * cell)


def _extents(uv: NDArray[np.float64]) -> NDArray[np.float64]:
    """Robust extent along each column of (k, 2) in-plane coordinates."""
    lo, hi = np.percentile(uv, [100 * EXTENT_QUANTILE, 100 * (1 - EXTENT_QUANTILE)], axis=0)
    robust = (hi - lo) / (1.0 - 2.0 * EXTENT_QUANTILE)
    return np.minimum(robust, _col_span(uv))


def _rectangle_frame(
    centered: NDArray[np.float64], principal: NDArray[np.float64], rng: np.random.Generator
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """In-plane axes (2, 3) along which the robust extents enclose the least area.

    The principal axes miss the sides of a near-square patch (their direction is
    then decided by sampling noise), so the sides of the smallest rectangle
    around the convex hull are tried too; stray points can tilt that rectangle,
    so the one of the two with the smaller robust extents wins. Returns the axes,
    the in-plane coordinates (k, 2) and the extents (2,).
    """
    uv = centered @ principal.T
    extent = _extents(uv)
    hull_pts = uv
    if len(uv) > HULL_MAX_POINTS:
        hull_pts = uv[rng.integers(0, len(uv), HULL_MAX_POINTS)]
    try:
        hull = hull_pts[ConvexHull(hull_pts).vertices]
    except QhullError:  # a (numerically) flat hull: the principal axes will do
        return principal.copy(), uv, extent
    edges = np.roll(hull, -1, axis=0) - hull
    angles = np.unique(np.mod(np.arctan2(edges[:, 1], edges[:, 0]), np.pi / 2))
    directions = np.column_stack([np.cos(angles), np.sin(angles)])
    along = hull @ directions.T
    across = hull @ np.column_stack([-directions[:, 1], directions[:, 0]]).T
    c, s = directions[int(np.argmin(np.ptp(along, axis=0) * np.ptp(across, axis=0)))]
    if min(abs(c), abs(s)) < SAME_FRAME_SINE:
        return principal.copy(), uv, extent  # the hull's rectangle has the principal axes
    frame = np.array([[c, s], [-s, c]])
    coords = uv @ frame.T
    hull_extent = _extents(coords)
    if hull_extent[0] * hull_extent[1] < extent[0] * extent[1]:
        return frame @ principal, coords, hull_extent
    return principal.copy(), uv, extent


def _describe(
    points: NDArray[np.float64],
    members: NDArray[np.intp],
    colors: NDArray[np.float64] | None,
    *,
    floor_z: float,
    cluster_centroid: NDArray[np.float64],
    area_cell: float | None,
    rng: np.random.Generator,
) -> Plane | None:
    """Fit and measure the plane of ``points[members]``; None if they define no plane."""
    pts = points[members]
    k = len(pts)
    if k < SAMPLE_SIZE:
        return None
    centered, centroid, vectors, degenerate = _principal(pts)
    if degenerate:
        return None
    # The least-spread direction is the normal; the other two are the in-plane principal axes.
    normal = vectors[:, 0].copy()
    tilt = float(np.degrees(np.arccos(np.clip(abs(normal[2]), 0.0, 1.0))))
    if tilt < UP_RULE_MAX_TILT_DEG:
        flip = normal[2] < 0
    else:
        side = float(normal @ (centroid - cluster_centroid))
        # A plane through the cluster's centroid has no outside: fall back on the sign rule.
        flip = side < 0 if side != 0.0 else canonical_sign(normal) < 0
    if flip:
        normal = -normal
    distance = centered @ normal

    axes, uv, extent = _rectangle_frame(centered, vectors[:, :0:-1].T, rng)
    if extent[1] > extent[0]:
        axes, extent, uv = axes[::-1].copy(), extent[::-1], uv[:, ::-1]
    # Deterministic signs: axes[0] oriented by the one sign rule, right-handed frame.
    axes[0] = canonical_sign(axes[0]) * axes[0]
    axes[1] = np.cross(normal, axes[0])
    length, width = float(extent[0]), float(extent[1])

    box = length * width
    if box <= 0.0:
        box = float(np.prod(_col_span(uv)))
    if area_cell is None:
        cell = AREA_CELL_SPACINGS * math.sqrt(box / k)
        full_count = AREA_CELL_SPACINGS**2
    else:
        cell = area_cell
        full_count = k * cell * cell / box
    area = _occupied_area(uv, cell, max(full_count, 1.0))

    color_mean = color_std = None
    if colors is not None:
        c = colors[members]
        color_mean = _readonly(_col_mean(c))
        color_std = _readonly(_col_std(c))
    return Plane(
        normal=_readonly(normal),
        offset=-float(normal @ centroid),
        centroid=_readonly(centroid),
        inliers=_readonly(np.array(members, dtype=np.intp)),
        axes=_readonly(np.ascontiguousarray(axes)),
        length=length,
        width=width,
        area=area,
        tilt=tilt,
        height=float(centroid[2] - floor_z),
        z_min=float(pts[:, 2].min()),
        z_max=float(pts[:, 2].max()),
        density=k / area,
        color_mean=color_mean,
        color_std=color_std,
        num_points=k,
        rms=float(np.sqrt(np.mean(distance * distance))),
    )


def _largest_component(uv: NDArray[np.float64], radius: float) -> NDArray[np.intp]:
    """Positions of the largest set of 2-D points joined by steps of at most ``radius``.

    Up to :data:`CONNECTIVITY_EXACT_MAX_POINTS` points the steps are between the
    points; above, the points are binned in cells ``radius / 3`` wide and the
    steps are between the cells' mean points (any two points less than about
    ``2/3 radius`` apart are joined, none more than about ``radius`` apart are).
    Ties go to the component holding the earliest point.
    """
    if len(uv) <= CONNECTIVITY_EXACT_MAX_POINTS:
        nodes, which = uv, np.arange(len(uv))
    else:
        cell = radius / CONNECTIVITY_CELLS_PER_RADIUS
        ij = np.floor((uv - _col_min(uv)) / cell).astype(np.int64)
        _, which, counts, _ = _cell_table(ij)
        nodes = np.column_stack(
            [np.bincount(which, weights=uv[:, i], minlength=len(counts)) for i in range(2)]
        )
        nodes /= counts[:, None]
    pairs = cKDTree(nodes).query_pairs(radius, output_type="ndarray")
    graph = coo_matrix(
        (np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])),
        shape=(len(nodes), len(nodes)),
    )
    _, labels = connected_components(graph, directed=False)
    point_labels = labels[which]
    sizes = np.bincount(point_labels)
    return np.flatnonzero(point_labels == int(np.argmax(sizes)))


def _level_plane(
    pts: NDArray[np.float64],
    rgb: NDArray[np.float64] | None,
    *,
    threshold: float,
    min_points: int,
    min_extent: float,
    connectivity: float | None,
    floor_z: float,
    cluster_centroid: NDArray[np.float64],
    area_cell: float | None,
    rng: np.random.Generator,
) -> Plane | None:
    """The plane of the densest level layer (:func:`level_layers`) that makes one, for
    ``extract_planes(level_first=True)``; None when no layer does."""
    centered = pts - cluster_centroid
    for band in level_layers(pts, threshold=threshold, min_inliers=min_points):
        # The level plane through the band is MSAC's hypothesis, refined as MSAC refines
        # its best: a seat that tilts back a few degrees is followed whole.
        height = float(np.median(pts[band, 2])) - float(cluster_centroid[2])
        r = centered[:, 2] - height
        normal, _, _, r = _refine(
            centered,
            np.array([0.0, 0.0, 1.0]),
            -height,
            float(np.minimum(r * r, threshold * threshold).sum()),
            threshold,
            LOCAL_REFINE,
        )
        if abs(float(normal[2])) < math.cos(math.radians(LEVEL_MAX_TILT)):
            continue
        near = np.flatnonzero(np.abs(r) <= threshold)
        if connectivity is not None:
            uv = pts[near] @ _in_plane_basis(np.asarray(normal, dtype=np.float64)).T
            near = near[_largest_component(uv, connectivity)]
        if near.size < min_points:
            continue
        plane = _describe(
            pts,
            near,
            rgb,
            floor_z=floor_z,
            cluster_centroid=cluster_centroid,
            area_cell=area_cell,
            rng=rng,
        )
        if (
            plane is not None
            and float(plane.tilt) <= LEVEL_MAX_TILT
            and plane.width >= LEVEL_MIN_WIDTH
            and max(plane.length, plane.width) >= min_extent
        ):
            return plane  # one level layer, the densest that is a plane: the rest is MSAC's
    return None


def extract_planes(
    points: ArrayLike,
    colors: ArrayLike | None = None,
    *,
    threshold: float = 0.01,
    min_points: int = 30,
    min_extent: float = 0.0,
    max_planes: int = 20,
    max_trials: int = 1000,
    connectivity: float | None = None,
    floor_z: float = 0.0,
    area_cell: float | None = None,
    rng: int | np.random.Generator | None = None,
    normals: ArrayLike | None = None,
    variation: ArrayLike | None = None,
    level_first: bool = False,
) -> list[Plane]:
    """Extract the planes of a cluster one after the other with MSAC.

    MSAC runs on the points not yet assigned; a plane is kept when it has at
    least ``min_points`` inliers and ``max(length, width) >= min_extent``, and
    its inliers are then taken out. A candidate that fails these tests has its
    inliers set aside (they belong to no plane) and the search goes on; it stops
    when MSAC finds no plane with ``min_points`` inliers, after ``max_planes``
    planes, or after :data:`MAX_CONSECUTIVE_REJECTIONS` candidates rejected in
    a row. Every plane's inliers are disjoint from the others'.

    Parameters
    ----------
    points : (n, 3) float
        The cluster, metres, z up.
    colors : (n, 3) float or uint8, optional
        Colours (0..255) for the planes' colour statistics.
    threshold : float
        MSAC inlier distance (> 0), metres (Table 4.1: 0.5–1.5 cm).
    min_points : int
        Fewest inliers (>= 3) for a plane.
    min_extent : float
        Shortest accepted ``max(length, width)`` (>= 0), metres.
    max_planes : int
        Most planes returned (>= 0).
    max_trials : int
        Most MSAC samples per plane (>= 1).
    connectivity : float, optional
        Keep only the largest connected piece of a plane's inliers, two points
        being connected when they are at most this far apart in the plane
        (> 0, metres); the other pieces go back to the unassigned points, so two
        coplanar seats side by side become two planes. Default: no splitting.
    floor_z : float
        Height of the floor, for :attr:`Plane.height`.
    area_cell : float, optional
        Cell of the area grid (> 0, metres). Default: three mean point spacings
        of the plane.
    rng : int or numpy.random.Generator, optional
        Seed or generator; the same points and seed give the same planes.
    normals, variation : (n, 3) and (n,) float, optional
        Local normals and surface variation of the points: with them, each plane is
        found by :func:`local_plane` (hypotheses from the surface, no random draw)
        instead of :func:`msac`.
    level_first : bool
        First take the densest level layer (:func:`level_layers`) that makes a plane: the
        level plane at its height, refined on the points as MSAC refines its best plane,
        still level (within :data:`LEVEL_MAX_TILT`), its largest connected piece passing
        the same tests and at least :data:`LEVEL_MIN_WIDTH` across; the rest of the points
        then go to MSAC as usual.

    Returns
    -------
    list of Plane
        In the order found (roughly from the largest; with ``level_first`` the level
        layer first).

    Raises
    ------
    InvalidParameterError
        If a parameter is out of range or the arrays have the wrong shape.

    Notes
    -----
    Results depend on the order of the points (MSAC draws samples by
    position): a permuted input gives the same planes up to sampling noise.

    Examples
    --------
    >>> gen = np.random.default_rng(1)
    >>> seat = np.column_stack([gen.uniform(0, 0.45, (500, 2)), np.full(500, 0.46)])
    >>> back = np.column_stack([gen.uniform(0, 0.45, 400), np.full(400, 0.45),
    ...                         gen.uniform(0.46, 0.9, 400)])
    >>> planes = extract_planes(np.vstack([seat, back]), rng=0)
    >>> [(round(p.tilt), round(p.height, 2), p.num_points) for p in planes]
    [(0, 0.46, 510), (90, 0.68, 390)]
    """
    pts = _as_points(points)
    n = len(pts)
    threshold = _positive("threshold", threshold)
    min_points = _integer("min_points", min_points, SAMPLE_SIZE)
    min_extent = _positive("min_extent", min_extent, allow_zero=True)
    max_planes = _integer("max_planes", max_planes, 0)
    max_trials = _integer("max_trials", max_trials, 1)
    if connectivity is not None:
        connectivity = _positive("connectivity", connectivity)
    if area_cell is not None:
        area_cell = _positive("area_cell", area_cell)
    if not (
        isinstance(floor_z, Real)
        and not isinstance(floor_z, bool)
        and math.isfinite(float(floor_z))
    ):
        raise InvalidParameterError("floor_z", "a finite float", floor_z)
    rgb: NDArray[np.float64] | None = None
    if colors is not None:
        rgb = np.asarray(colors, dtype=np.float64)
        if rgb.shape != (n, 3):
            raise InvalidParameterError(
                "colors", f"an ({n}, 3) array like the points", f"shape {rgb.shape}"
            )
    gen = np.random.default_rng(rng)
    if normals is not None:
        nrm = np.asarray(normals, dtype=np.float64)
        var = np.zeros(n) if variation is None else np.asarray(variation, dtype=np.float64)
        if nrm.shape != (n, 3) or var.shape != (n,):
            raise InvalidParameterError(
                "normals", f"({n}, 3) normals and ({n},) variation", f"shape {nrm.shape}"
            )

    planes: list[Plane] = []
    if n == 0:
        return planes
    cluster_centroid = _col_mean(pts)
    active = np.arange(n)
    if level_first and max_planes > 0:
        level = _level_plane(
            pts,
            rgb,
            threshold=threshold,
            min_points=min_points,
            min_extent=min_extent,
            connectivity=connectivity,
            floor_z=float(floor_z),
            cluster_centroid=cluster_centroid,
            area_cell=area_cell,
            rng=gen,
        )
        if level is not None:
            planes.append(level)
            active = np.setdiff1d(active, level.inliers, assume_unique=True)
    rejections = 0
    with progress("Extracting planes", total=max_planes) as advance:
        while len(planes) < max_planes and active.size >= min_points:
            if normals is not None:
                found = local_plane(
                    pts[active],
                    nrm[active],
                    var[active],
                    threshold=threshold,
                    min_inliers=min_points,
                )
            else:
                found = msac(
                    pts[active],
                    threshold=threshold,
                    max_trials=max_trials,
                    min_inliers=min_points,
                    rng=gen,
                )
            if not found:
                break
            taken = found.inliers  # positions in ``active``
            if connectivity is not None:
                uv = pts[active[taken]] @ _in_plane_basis(found.model.normal).T
                taken = taken[_largest_component(uv, connectivity)]
            plane = None
            if taken.size >= min_points:
                plane = _describe(
                    pts,
                    active[taken],
                    rgb,
                    floor_z=float(floor_z),
                    cluster_centroid=cluster_centroid,
                    area_cell=area_cell,
                    rng=gen,
                )
            if plane is not None and max(plane.length, plane.width) >= min_extent:
                planes.append(plane)
                active = np.delete(active, taken)
                rejections = 0
                advance(1)
                continue
            active = np.delete(active, found.inliers)
            rejections += 1
            if rejections >= MAX_CONSECUTIVE_REJECTIONS:
                break
    return planes


# -- relations between planes --------------------------------------------------------------------


@dataclass(frozen=True)
class PlaneRelation:
    """How two planes of a cluster relate (the geometry P_Pr scores, Eq. 3.3).

    Attributes
    ----------
    i, j : int
        Positions of the two planes in the list given, ``i < j``.
    angle : float
        Angle between the normals, degrees folded to [0, 90] (90: a seat and its backrest).
    distance : float
        Closest distance between the two inlier sets, metres (about 0 when they touch).
    vertical_gap : float
        ``centroid_i.z - centroid_j.z``, metres.
    i_above_j : bool
        Plane i lies above plane j: its centroid is at least :data:`ABOVE_MIN_GAP`
        higher and ``xy_overlap >= ABOVE_MIN_OVERLAP``.
    xy_overlap : float
        Share (0..1) of the smaller xy footprint that the other footprint covers;
        footprints are the cells of an xy grid that hold inliers.
    """

    i: int
    j: int
    angle: float
    distance: float
    vertical_gap: float
    i_above_j: bool
    xy_overlap: float

    @property
    def j_above_i(self) -> bool:
        """Plane j lies above plane i (the same rule as :attr:`i_above_j`, reversed)."""
        return self.vertical_gap <= -ABOVE_MIN_GAP and self.xy_overlap >= ABOVE_MIN_OVERLAP


def plane_relations(
    points: ArrayLike,
    planes: list[Plane],
    *,
    footprint_cell: float = FOOTPRINT_CELL,
    max_points: int = RELATION_MAX_POINTS,
    since: int = 0,
) -> list[PlaneRelation]:
    """Measure every pair of planes: angle, adjacency, vertical order, footprint overlap.

    Parameters
    ----------
    points : (n, 3) float
        The points the planes were extracted from (their ``inliers`` index them).
    planes : list of Plane
        Planes from :func:`extract_planes`.
    footprint_cell : float
        Cell of the xy footprint grid (> 0), metres.
    max_points : int
        Planes with more inliers are thinned to about this many (every k-th inlier
        in input order) for the adjacency distance, which is then approximate
        within the thinned spacing.
    since : int
        Only the pairs whose ``j`` is at least this (>= 0): the planes from ``since`` on
        were added to a list whose pairs were measured already (a pair's relation
        depends on its two planes alone).

    Returns
    -------
    list of PlaneRelation
        One per pair ``i < j`` (with ``j >= since``), in lexicographic order.

    Raises
    ------
    InvalidParameterError
        If a parameter is out of range or a plane's inliers do not index ``points``.

    Examples
    --------
    >>> gen = np.random.default_rng(1)
    >>> seat = np.column_stack([gen.uniform(0, 0.45, (500, 2)), np.full(500, 0.46)])
    >>> back = np.column_stack([gen.uniform(0, 0.45, 400), np.full(400, 0.45),
    ...                         gen.uniform(0.46, 0.9, 400)])
    >>> pts = np.vstack([seat, back])
    >>> rel, = plane_relations(pts, extract_planes(pts, rng=0))
    >>> round(rel.angle), rel.distance < 0.02, rel.j_above_i
    (90, True, True)
    """
    pts = _as_points(points)
    cell = _positive("footprint_cell", footprint_cell)
    max_points = _integer("max_points", max_points, 1)
    since = _integer("since", since, 0)
    samples: list[NDArray[np.float64]] = []
    footprints: list[NDArray[np.int64]] = []
    for k, plane in enumerate(planes):
        idx = np.asarray(plane.inliers)
        if idx.size == 0 or idx.min() < 0 or idx.max() >= len(pts):
            raise InvalidParameterError(
                f"planes[{k}].inliers",
                f"non-empty indices in [0, {len(pts)})",
                f"{idx.size} indices",
            )
        stride = -(-idx.size // max_points)
        samples.append(pts[idx[::stride]])
        ij = np.floor(pts[idx, :2] / cell).astype(np.int64)
        # Two 32-bit halves make one sortable key per cell.
        footprints.append(np.unique((ij[:, 0] << 32) + (ij[:, 1] + (1 << 31))))
    trees: dict[int, cKDTree] = {}
    relations: list[PlaneRelation] = []
    for i in range(len(planes)):
        for j in range(max(i + 1, since), len(planes)):
            if j not in trees:
                trees[j] = cKDTree(samples[j])
            distance = float(trees[j].query(samples[i], k=1)[0].min())
            cos = abs(float(planes[i].normal @ planes[j].normal))
            angle = float(np.degrees(np.arccos(min(cos, 1.0))))
            shared = np.intersect1d(footprints[i], footprints[j], assume_unique=True).size
            overlap = shared / min(footprints[i].size, footprints[j].size)
            gap = float(planes[i].centroid[2] - planes[j].centroid[2])
            relations.append(
                PlaneRelation(
                    i=i,
                    j=j,
                    angle=angle,
                    distance=distance,
                    vertical_gap=gap,
                    i_above_j=gap >= ABOVE_MIN_GAP and overlap >= ABOVE_MIN_OVERLAP,
                    xy_overlap=float(overlap),
                )
            )
    return relations
