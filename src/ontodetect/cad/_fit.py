"""Choosing and fitting generic models to detected objects, and the object map (thesis §3.7).

For each detected object:

1. its points are moved to the levelled frame (z up, floor at z = 0) and
   grid-averaged at 0.5 cm, like the models (thesis §4);
2. what is known of it is gathered in :class:`ObjectHints`: the seat and the
   backrest (seating) or the top (tables) from the detection's parts, completed
   from the points themselves (:func:`hints_from_points`);
3. every model of the label is scaled to the object's measured dimensions
   (seat height and seat size, or top height and top size; the thesis left this
   as future work) and fitted by ground-constrained ICP
   (:func:`~ontodetect.cad.ground_icp`) from a few starting yaws: the front
   given by the backrest-to-seat direction for seating, the main axis of the top
   for tables; a coarse pass ranks the (model, start) pairs and a fine pass
   refines the best ones;
4. the model with the lowest truncated cost (it rewards a high share of matched
   points and a low RMS distance, the two criteria of the thesis) wins; objects
   whose probability is below ``min_score``, or that no model fits, get a blank
   box (the detection's box) instead;
5. the pose is reported in the input file's frame, and the colour is the mean
   colour of the object's points.

:func:`write_object_map` writes the fitted full models as one coloured point
cloud (PLY) and as a mesh scene (GLB, and PLY) that common viewers open.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._progress import progress
from ..cloud import PointCloud, point_cloud
from ..errors import InvalidParameterError
from ..geometry import LevelFrame
from ..geometry._mesh import Mesh
from ..io import atomic_write_bytes, make_folder, write_cloud
from ..ontology import Ontology, builtin_ontology
from ..preprocess import rotation_between
from ._icp import INLIER_DISTANCE, KERNELS, ground_icp, pose_matrix
from ._models import (
    DEFAULT_COLOR,
    LABEL_COLORS,
    MODEL_SPACING,
    CadModel,
    ModelLibrary,
    box_model,
    builtin_library,
    grid_downsample,
    sample_surface,
)

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

__all__ = [
    "MIN_SCORE",
    "CadFit",
    "LevelFrame",
    "ObjectHints",
    "ObjectMapFiles",
    "cad_dict",
    "fit_detections",
    "fit_document",
    "fit_object",
    "hints_from_points",
    "model_scale",
    "object_map_cloud",
    "object_map_meshes",
    "write_object_map",
]

#: Objects whose probability P_obj|ont is below this get the blank box (thesis §4: "objects
#: with very low probabilities are replaced with blank models"); the decision threshold of
#: Table 4.1 is 15 %.
MIN_SCORE = 0.2
#: A best fit matching fewer of the object's points than this is no fit: blank box.
MIN_INLIER_FRACTION = 0.25
#: Fewer points than this cannot be fitted.
MIN_POINTS = 20

# -- the search ----------------------------------------------------------------------------
#: Model grid (m) and data points of the coarse pass, which tries every (model, start).
COARSE_SPACING = 0.02
COARSE_POINTS = 150
COARSE_ITERATIONS = 6
#: Models refined by the fine pass (on the 0.5 cm model grid), and its data points.
FINE_MODELS = 2
FINE_POINTS = 400
FINE_ITERATIONS = 30
#: The second model is refined only when its coarse score is within this of the best one's.
REFINE_MARGIN = 0.25
#: The coarse pass leaves the model within a few centimetres: the fine pass looks for
#: correspondences this close (m), which also bounds the cost of a tree query.
FINE_MAX_DISTANCE = 0.10
#: Coverage test: model grid (m), at most this many of its points, the distance (m) within
#: which a data point covers a model point, and the weight of uncovered model surface in the
#: choice of the model (a big model swallows any points, but much of it then stays bare).
COVER_SPACING = 0.04
COVER_POINTS = 1500
COVER_DISTANCE = 0.04
COVERAGE_WEIGHT = 0.5
#: Starting yaws when nothing says where an object faces.
BLIND_STARTS = 8

# -- hints from the points -----------------------------------------------------------------
#: Grid (m) of the points the hints are measured on.
HINT_SPACING = 0.01
#: Height bins (m) of the search for horizontal layers (seat, table top), and the
#: half-thickness of a layer.
LAYER_BIN = 0.01
LAYER_HALF = 0.025
#: Layers at least this dense (share of the densest) count: the seat is the lowest of them
#: (armrests and a sofa's arms are higher), the top of a table the highest (a shelf is lower).
LAYER_SHARE = 0.5
#: Where a seat and a table top are sought, which parts of a detection give the seat and
#: the backrest, and how far a model's footprint may stretch come from the ontology: its
#: parts' ``cad`` roles and its classes' ``cad.scale`` (data/furniture.yaml).
#: The hint each CAD role of a detection's part gives (the top is measured on the points:
#: a cluttered top splits into several planes).
PART_HINTS = {"seat": "seat_center", "back": "backrest_center"}
#: Backrest points are those the ontology's ``back`` part's ``above_seat`` (built in 27 cm,
#: above the armrests) above the seat, so that arms do not pull its centre sideways.
#: A backrest needs at least this many points, and its centre this far (m) from the seat's.
MIN_BACK_POINTS = 10
MIN_BACK_OFFSET = 0.04
#: Grid (m) of the surface test of a seat layer, and the share of the layer's points the
#: test must keep to be trusted.
LAYER_CELL = 0.04
MIN_SURFACE_SHARE = 0.6
#: Percentiles taken as the extremes of a layer (robust to stray points).
EXTENT_PERCENTILES = (1.0, 99.0)
MIN_LAYER_POINTS = 10

# -- scaling the model to the object -------------------------------------------------------
#: Bounds of the scale factor of the height of a seat or top (those of a footprint are the
#: class's ``cad.scale`` in the ontology).
HEIGHT_SCALE = (0.75, 1.35)
#: A seat longer than this many times its depth is a sofa's: scaled along its length.
LONG_SEAT = 1.5


# ---------------------------------------------------------------------------------------
# What is known of an object


@dataclass(frozen=True)
class ObjectHints:
    """What is known of an object before fitting, in the levelled frame (metres, radians).

    Attributes
    ----------
    seat_center, top_center : (3,) float or None
        Centre of the top of the seat or of the table top (z is its height).
    seat_extent, top_extent : (2,) float or None
        Length and width of the seat or top (length >= width).
    backrest_center : (3,) float or None
    axis_yaw : float or None
        Direction of the long horizontal axis of the top (or seat).
    front_yaw : float or None
        Direction the object faces: from the backrest towards the seat.
    height : float or None
        Top of the object.
    """

    seat_center: NDArray[np.float64] | None = None
    seat_extent: NDArray[np.float64] | None = None
    backrest_center: NDArray[np.float64] | None = None
    top_center: NDArray[np.float64] | None = None
    top_extent: NDArray[np.float64] | None = None
    axis_yaw: float | None = None
    front_yaw: float | None = None
    height: float | None = None

    def merged(self, other: ObjectHints) -> ObjectHints:
        """These hints with the gaps filled from ``other``; the front is re-derived from the
        seat and backrest when both are known."""
        values = {
            k: (getattr(self, k) if getattr(self, k) is not None else getattr(other, k))
            for k in self.__dataclass_fields__
        }
        out = ObjectHints(**values)
        if (
            self.front_yaw is None
            and out.seat_center is not None
            and out.backrest_center is not None
            and self.backrest_center is not None
        ):
            out = replace(out, front_yaw=_front(out.seat_center, out.backrest_center))
        return out


def _front(seat: NDArray[np.float64], back: NDArray[np.float64]) -> float | None:
    d = np.asarray(seat[:2]) - np.asarray(back[:2])
    if np.hypot(*d) < MIN_BACK_OFFSET:
        return None
    return math.atan2(d[1], d[0])


def _layer(z: NDArray[np.float64], lo: float, hi: float, lowest: bool) -> float | None:
    """Height of the lowest (or highest) dense horizontal layer between lo and hi."""
    edges = np.arange(lo, hi + LAYER_BIN, LAYER_BIN)
    counts, _ = np.histogram(z, edges)
    if counts.sum() < MIN_LAYER_POINTS:
        return None
    # A layer is a few centimetres thick (noise, cushions): count over a sliding window.
    width = round(2 * LAYER_HALF / LAYER_BIN)
    smooth = np.convolve(counts, np.ones(width), mode="same")
    padded = np.r_[-1.0, smooth, -1.0]
    peak = (smooth >= padded[:-2]) & (smooth >= padded[2:]) & (smooth >= LAYER_SHARE * smooth.max())
    ks = np.flatnonzero(peak)
    k = int(ks[0] if lowest else ks[-1])
    sel = (z >= edges[k] - LAYER_HALF) & (z < edges[k + 1] + LAYER_HALF)
    if sel.sum() < MIN_LAYER_POINTS:
        return None
    # The top surface of the layer: what one sits on or puts things on.
    return float(np.percentile(z[sel], 90))


def _rectangle(
    xy: NDArray[np.float64], yaw: float | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """Centre, extent (long, short) and long-axis yaw of the rectangle around 2D points.

    The axes are the given ``yaw`` (and its perpendicular) or those of the
    smallest rectangle around the convex hull (unlike principal axes, they do
    not wander on a square); the extent is taken between robust percentiles.
    """
    if len(xy) < 3:
        return xy.mean(axis=0), np.zeros(2), 0.0 if yaw is None else yaw
    if yaw is None:
        from scipy.spatial import ConvexHull, QhullError  # lazy: scipy.spatial off the import path

        try:
            hull = xy[ConvexHull(xy).vertices]
        except QhullError:
            hull = xy
        edges = np.diff(np.vstack([hull, hull[:1]]), axis=0)
        angles = np.arctan2(edges[:, 1], edges[:, 0]) % (np.pi / 2)
        c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
        u = hull[None, :, 0] * c + hull[None, :, 1] * s
        v = -hull[None, :, 0] * s + hull[None, :, 1] * c
        area = np.ptp(u, axis=1) * np.ptp(v, axis=1)
        yaw = float(angles[int(np.argmin(area))])
    axis = np.array([math.cos(yaw), math.sin(yaw)])
    frame = np.stack([axis, [-axis[1], axis[0]]])
    mean = xy.mean(axis=0)
    local = (xy - mean) @ frame.T
    lo, hi = np.percentile(local, EXTENT_PERCENTILES, axis=0)
    center = mean + ((lo + hi) / 2) @ frame
    extent = hi - lo
    if extent[1] > extent[0]:
        extent, yaw = extent[::-1], yaw + np.pi / 2
    return center, extent, float(np.angle(np.exp(1j * yaw)))


def _surface_only(xy: NDArray[np.float64]) -> NDArray[np.float64]:
    """The points of a layer that lie on a horizontal surface, not on a vertical face.

    Vertical faces that cross the layer (the inner sides of a sofa's arms, the front
    of its back) leave thin lines when the points are marked on a grid, surfaces
    leave filled areas: a morphological opening keeps the areas. When it would
    remove most points the layer is too sparse to tell, and all are kept.
    """
    if len(xy) < MIN_LAYER_POINTS:
        return xy
    ij = np.floor((xy - xy.min(axis=0)) / LAYER_CELL).astype(np.int64)
    grid = np.zeros(ij.max(axis=0) + 1, dtype=bool)
    grid[ij[:, 0], ij[:, 1]] = True
    from scipy import ndimage  # lazy: scipy.ndimage off the import path

    opened = ndimage.binary_opening(grid, structure=np.ones((3, 3), dtype=bool))
    keep = opened[ij[:, 0], ij[:, 1]]
    return xy[keep] if keep.mean() >= MIN_SURFACE_SHARE else xy


def hints_from_points(
    points: ArrayLike, label: str | None = None, ontology: Ontology | None = None
) -> ObjectHints:
    """Seat, backrest and top of an object from its levelled points alone.

    A horizontal surface puts many points at one height, legs and backrests
    spread theirs: the seat is the lowest dense layer at seat height (armrests
    are higher) and the top the highest one at top height (a shelf is lower);
    dense means at least half as many points as the densest layer. The heights
    are the ontology's ``cad.search`` of the parts with the roles ``seat`` and
    ``top`` (the built-in ontology: seats 30–75 cm, tops 30 cm–1.15 m). The
    backrest is what rises more than the ``back`` part's ``above_seat`` above the
    seat (built in: 27 cm); the front is the direction from the backrest's centre
    to the seat's.

    Parameters
    ----------
    points : (n, 3) float
        The object's points, levelled (z up, floor at 0, metres).
    label : str, optional
        Its label: the search heights of that label's classes, those of all
        classes when it has none.
    ontology : Ontology, optional
        The built-in ontology by default.

    Returns
    -------
    ObjectHints

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> seat = np.c_[rng.random((500, 2)) * 0.45, np.full(500, 0.45)]
    >>> back = np.c_[rng.random(300) * 0.45, np.zeros(300), 0.5 + rng.random(300) * 0.4]
    >>> h = hints_from_points(np.vstack([seat, back]))
    >>> round(float(h.seat_center[2]), 2), abs(math.degrees(h.front_yaw) - 90) < 2  # faces +y
    (0.45, True)
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InvalidParameterError("points", "an array of shape (n, 3)", f"shape {pts.shape}")
    if len(pts) < MIN_LAYER_POINTS:
        return ObjectHints()
    z = pts[:, 2]
    onto = builtin_ontology() if ontology is None else ontology
    out: dict[str, Any] = {"height": float(np.percentile(z, 99))}
    seat_range = onto.cad_search("seat", label)
    seat_h = None if seat_range is None else _layer(z, *seat_range, lowest=True)
    if seat_h is not None:
        xy = _surface_only(pts[np.abs(z - seat_h) <= LAYER_HALF, :2])
        above = onto.cad_above_seat(label)
        back = z > seat_h + (np.inf if above is None else above)
        front = None
        if back.sum() >= MIN_BACK_POINTS:
            out["backrest_center"] = pts[back].mean(axis=0)
            front = _front(np.r_[np.median(xy, axis=0), seat_h], out["backrest_center"])
        # A seat is measured across and along the way it faces.
        center, extent, axis = _rectangle(xy, None if front is None else front)
        out["seat_center"] = np.array([center[0], center[1], seat_h])
        out["seat_extent"] = extent
        out["axis_yaw"] = axis
        if front is not None:
            out["front_yaw"] = _front(out["seat_center"], out["backrest_center"])
    top_range = onto.cad_search("top", label)
    top_h = None if top_range is None else _layer(z, *top_range, lowest=False)
    if top_h is not None:
        center, extent, axis = _rectangle(pts[np.abs(z - top_h) <= LAYER_HALF, :2])
        out["top_center"] = np.array([center[0], center[1], top_h])
        out["top_extent"] = extent
        out["axis_yaw"] = axis
    return ObjectHints(**out)


def _hints_from_parts(
    parts: Sequence[Mapping[str, Any]], frame: LevelFrame, roles: Mapping[str, str]
) -> ObjectHints:
    """The seat and backrest of a detection's parts (input frame) in the levelled frame.

    ``roles`` maps part names to their CAD roles (:meth:`Ontology.cad_parts`). Seat and
    backrest give the front of seating. A table's top plane can be a piece of the
    top (a cluttered top splits into several planes), so the top is measured on
    the points instead (:func:`hints_from_points`); so are seat sizes.
    """
    out: dict[str, Any] = {}
    for p in parts or ():
        key = PART_HINTS.get(roles.get(str(p.get("name")), ""))
        centroid = p.get("centroid")
        if key is None or centroid is None or key in out:
            continue
        out[key] = frame.level(np.asarray(centroid, dtype=np.float64))[0]
    if "seat_center" in out and "backrest_center" in out:
        out["front_yaw"] = _front(out["seat_center"], out["backrest_center"])
    return ObjectHints(**out)


# ---------------------------------------------------------------------------------------
# Fitting one object


@dataclass(frozen=True, eq=False)
class CadFit:
    """A model placed on one object.

    The model's canonical vertices ``v`` (metres) land in the input file's frame
    at ``pose @ [scale * v, 1]`` (:attr:`transform`).

    Attributes
    ----------
    id : int
        The detection's id (0 when fitted alone).
    label : str
    model : str
        Name of the chosen model, ``"box"`` for the blank model.
    pose : (4, 4) float
        Model frame -> input frame: a rotation about the input's up direction
        and a translation (times 1/k_s when the input is not in metres).
    level_pose : (4, 4) float
        Model frame -> levelled frame: rotation by :attr:`yaw` about z,
        translation (x, y, 0): roll, pitch and height are those of the floor.
    scale : (3,) float
        Factors applied to the model along its x, y, z first.
    rms : float
        RMS distance (m) of the object's matched points to the model (NaN for a blank
        box), measured on the fine pass's points (up to 400 of the object's).
    inlier_fraction : float
        Share of those points within the inlier distance (3 cm) of the model.
    color : (3,) uint8
        Mean colour of the object's points.
    blank : bool
        True when the detection's box stands in for a model; :attr:`reason` says why.
    reason : str
    num_points : int
        Points of the object.
    candidates : dict
        Every model tried: ``{name: {"rms", "inlier_fraction", "cost"}}``.
    up : (3,) float
        Up direction of the input frame.
    cad_model : CadModel
        The chosen model itself (for drawing the object map).
    """

    id: int
    label: str
    model: str
    pose: NDArray[np.float64]
    level_pose: NDArray[np.float64]
    scale: NDArray[np.float64]
    rms: float
    inlier_fraction: float
    color: NDArray[np.uint8]
    blank: bool = False
    reason: str = ""
    num_points: int = 0
    candidates: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    up: NDArray[np.float64] = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    cad_model: CadModel | None = field(default=None, repr=False)

    @property
    def x(self) -> float:
        return float(self.level_pose[0, 3])

    @property
    def y(self) -> float:
        return float(self.level_pose[1, 3])

    @property
    def yaw(self) -> float:
        """Yaw of the model's x axis about z in the levelled frame (radians)."""
        return float(math.atan2(self.level_pose[1, 0], self.level_pose[0, 0]))

    @property
    def transform(self) -> NDArray[np.float64]:
        """(4, 4) model vertices -> input frame, scale included."""
        return self.pose @ np.diag([*self.scale, 1.0])

    def to_dict(self) -> dict[str, Any]:
        return cad_dict(self)


def cad_dict(fit: CadFit) -> dict[str, Any]:
    """The ``cad`` entry of a detection in detections.json.

    Examples
    --------
    >>> import numpy as np
    >>> fit = CadFit(1, "chair", "chair-4leg", np.eye(4), np.eye(4), np.ones(3), 0.0123456,
    ...              0.9, np.array([10, 20, 30], np.uint8))
    >>> d = cad_dict(fit)
    >>> d["model"], d["rms"], d["pose"][0]
    ('chair-4leg', 0.01235, [1.0, 0.0, 0.0, 0.0])
    """
    out: dict[str, Any] = {
        "model": fit.model,
        "pose": [[round(float(v), 6) for v in row] for row in fit.pose],
        "scale": [round(float(v), 4) for v in fit.scale],
        "rms": round(float(fit.rms), 5) if math.isfinite(fit.rms) else None,
        "inlier_fraction": round(float(fit.inlier_fraction), 4),
        "color": [int(v) for v in fit.color],
        "blank": bool(fit.blank),
    }
    if fit.reason:
        out["reason"] = fit.reason
    return out


def _clip(v: float, bounds: tuple[float, float]) -> float:
    return float(np.clip(v, *bounds))


def model_scale(
    model: CadModel, hints: ObjectHints, ontology: Ontology | None = None
) -> NDArray[np.float64]:
    """(3,) factors that stretch a model to the object's measured seat or top (1 if unknown).

    Heights follow the seat or top within ``HEIGHT_SCALE``; a footprint stretches within
    the ``cad.scale`` of the model's class in ``ontology`` (the built-in one by default),
    and keeps its generic size when the class gives none.
    """
    s = np.ones(3)
    dims = model.dims
    bounds = (builtin_ontology() if ontology is None else ontology).cad_scale(model.label)
    if model.is_seating:
        if hints.seat_center is not None:
            s[2] = _clip(hints.seat_center[2] / dims["seat_height"], HEIGHT_SCALE)
        e = hints.seat_extent
        sw, sd = dims.get("seat_width"), dims.get("seat_depth")
        # A chair's seat is too small, and too often hidden under a table, for its
        # measured size to beat the generic one; a sofa's length varies far more.
        if e is not None and sw and sd and sw > LONG_SEAT * sd and bounds is not None:
            s[0] = _clip(e[0] / sw, bounds)
    elif "top_height" in dims:
        if hints.top_center is not None:
            s[2] = _clip(hints.top_center[2] / dims["top_height"], HEIGHT_SCALE)
        e = hints.top_extent
        tw, td = dims.get("top_width"), dims.get("top_depth")
        if e is not None and tw and td and bounds is not None:
            if model.symmetry == 0:
                s[0] = s[1] = _clip(float(np.mean(e)) / tw, bounds)
            elif model.symmetry == 4:
                s[0] = s[1] = _clip(math.sqrt(e[0] * e[1]) / tw, bounds)
            else:
                s[0] = _clip(e[0] / tw, bounds)
                s[1] = _clip(e[1] / td, bounds)
    return s


def _start_yaws(model: CadModel, hints: ObjectHints) -> NDArray[np.float64]:
    quarter = np.arange(4) * (np.pi / 2)
    if model.symmetry == 0:
        return np.zeros(1)
    if model.is_seating and hints.front_yaw is not None:
        # The model faces +y: turn it so that +y points where the seat faces. The backrest
        # leaves no doubt about the front, and ICP corrects the rest.
        return np.array([hints.front_yaw - np.pi / 2])
    if hints.axis_yaw is not None:
        if model.symmetry == 4:
            return np.array([hints.axis_yaw])
        if model.symmetry == 2:
            return hints.axis_yaw + quarter[:2]
        return hints.axis_yaw + quarter
    return np.arange(BLIND_STARTS) * (2 * np.pi / BLIND_STARTS)


def _anchor(
    model: CadModel, hints: ObjectHints
) -> tuple[NDArray[np.float64] | None, NDArray[np.float64] | None]:
    """A point of the model and where it should land: the seat or the top centre."""
    if model.anchor is None:
        return None, None
    target = hints.seat_center if model.is_seating else hints.top_center
    if target is None:
        return None, None
    return np.asarray(model.anchor, dtype=np.float64), np.asarray(target, dtype=np.float64)


def _starts(
    model: CadModel,
    hints: ObjectHints,
    data: NDArray[np.float64],
    model_points: NDArray[np.float64],
    scale: NDArray[np.float64],
) -> NDArray[np.float64]:
    yaws = _start_yaws(model, hints)
    anchor, target = _anchor(model, hints)
    if anchor is None:
        anchor = model_points.mean(axis=0)
        target = data.mean(axis=0)
    a = anchor[:2] * scale[:2]
    c, s = np.cos(yaws), np.sin(yaws)
    x = target[0] - (c * a[0] - s * a[1])
    y = target[1] - (s * a[0] + c * a[1])
    return np.column_stack([x, y, yaws])


def _coverage(
    model: CadModel, scale: NDArray[np.float64], pose: NDArray[np.float64], data_tree: cKDTree
) -> float:
    """Share of the model's thin profile that has a data point near it at this pose."""
    grid = model.points(COVER_SPACING)
    # An even thinning measures the same share; big models (sofas) would cost more.
    pts = _apply(pose, grid[:: max(1, len(grid) // COVER_POINTS)] * scale)
    dist, _ = data_tree.query(pts, k=1, distance_upper_bound=COVER_DISTANCE)
    return float(np.mean(np.isfinite(dist)))


def _choice(cost: float, coverage: float) -> float:
    """What ranks models: unmatched data (the ICP cost) plus unmatched model surface."""
    return cost + COVERAGE_WEIGHT * (1.0 - coverage)


def _subset(points: NDArray[np.float64], n: int, rng: np.random.Generator) -> NDArray[np.float64]:
    if len(points) <= n:
        return points
    return points[np.sort(rng.choice(len(points), n, replace=False))]


def _mean_color(colors: ArrayLike | None, label: str) -> NDArray[np.uint8]:
    if colors is not None:
        c = np.asarray(colors)
        if c.ndim == 2 and len(c):
            return np.clip(np.rint(c[:, :3].astype(np.float64).mean(axis=0)), 0, 255).astype(
                np.uint8
            )
    return np.asarray(LABEL_COLORS.get(label, DEFAULT_COLOR), dtype=np.uint8)


def _points_box(
    points: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """Upright box (centre, size, yaw) around levelled points, along their main axis."""
    if len(points) == 0:
        return np.zeros(3), np.full(3, 0.1), 0.0
    center, extent, yaw = _rectangle(points[:, :2])
    lo, hi = float(points[:, 2].min()), float(points[:, 2].max())
    return (
        np.array([center[0], center[1], (lo + hi) / 2]),
        np.array([max(extent[0], 0.01), max(extent[1], 0.01), max(hi - lo, 0.01)]),
        yaw,
    )


def _blank(
    fid: int,
    label: str,
    box: tuple[NDArray, NDArray, float] | None,
    points: NDArray[np.float64],
    frame: LevelFrame,
    color: NDArray[np.uint8],
    reason: str,
    candidates: Mapping[str, Mapping[str, float]] | None = None,
) -> CadFit:
    """The blank model standing in for an object: its box (or a box around its points)."""
    center, size, yaw = _points_box(points) if box is None else box
    level_pose = pose_matrix(center[0], center[1], yaw, center[2] - size[2] / 2)
    return CadFit(
        id=fid,
        label=label,
        model="box",
        pose=frame.pose_to_input(level_pose),
        level_pose=level_pose,
        scale=np.asarray(size, dtype=np.float64),
        rms=math.nan,
        inlier_fraction=0.0,
        color=color,
        blank=True,
        reason=reason,
        num_points=len(points),
        candidates=dict(candidates or {}),
        up=frame.up,
        cad_model=box_model(label),
    )


def fit_object(
    points: ArrayLike,
    label: str,
    library: ModelLibrary | None = None,
    *,
    hints: ObjectHints | None = None,
    colors: ArrayLike | None = None,
    frame: LevelFrame | None = None,
    box: tuple[ArrayLike, ArrayLike, float] | None = None,
    object_id: int = 0,
    scale_to_object: bool = True,
    kernel: str = "tukey",
    inlier_distance: float = INLIER_DISTANCE,
    seed: int | np.random.Generator | None = 0,
    ontology: Ontology | None = None,
) -> CadFit:
    """Choose and fit the generic model of ``label`` that best explains an object's points.

    Parameters
    ----------
    points : (n, 3) float
        The object's points in the levelled frame (z up, floor at z = 0, metres).
    label : str
        Its class; the library's models of that label are tried.
    library : ModelLibrary, optional
        Models; :func:`~ontodetect.cad.builtin_library` by default.
    hints : ObjectHints, optional
        Seat, backrest, top (e.g. from a detection's parts); what they leave open
        is estimated from the points (:func:`hints_from_points`).
    colors : (n, 3) uint8, optional
        The points' colours; their mean colours the model.
    frame : LevelFrame, optional
        Where the input frame is; the pose is reported there (identity by default).
    box : (center (3,), size (3,), yaw), optional
        The detection's box in the levelled frame, used as the blank model when no
        model fits (a box around the points by default).
    object_id : int
        Copied to :attr:`CadFit.id`.
    scale_to_object : bool
        Stretch each model to the object's measured seat or top (:func:`model_scale`).
    kernel : {"tukey", "huber", "cauchy", "l2"}
        Robust kernel of the ICP.
    inlier_distance : float
        Distance (m) within which a point counts as matched.
    seed : int or numpy.random.Generator, optional
        Seed of the point subsets the search uses.
    ontology : Ontology, optional
        Where seats and tops are sought (its parts' ``cad`` roles) and how far a
        footprint stretches (its classes' ``cad.scale``); the built-in one by default.

    Returns
    -------
    CadFit

    Examples
    --------
    >>> from ontodetect.cad import builtin_library
    >>> lib = builtin_library()
    >>> chair = lib["chair-4leg"]
    >>> pts = chair.points(0.01) @ np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]]).T + [2, 1, 0]
    >>> fit = fit_object(pts, "chair", lib)
    >>> fit.model, round(math.degrees(fit.yaw)), np.round([fit.x, fit.y], 2).tolist()
    ('chair-4leg', 90, [2.0, 1.0])
    """
    lib = builtin_library() if library is None else library
    if not isinstance(lib, ModelLibrary):
        raise InvalidParameterError("library", "a ModelLibrary", type(lib).__name__)
    if kernel not in KERNELS:
        raise InvalidParameterError("kernel", "one of " + ", ".join(map(repr, KERNELS)), kernel)
    if not (isinstance(inlier_distance, (int, float)) and inlier_distance > 0):
        raise InvalidParameterError(
            "inlier_distance", "a float in the range (0, inf)", inlier_distance
        )
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InvalidParameterError("points", "an array of shape (n, 3)", f"shape {pts.shape}")
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    frame = frame or LevelFrame.identity()
    color = _mean_color(colors, label)
    the_box = None
    if box is not None:
        the_box = (
            np.asarray(box[0], dtype=np.float64),
            np.asarray(box[1], dtype=np.float64),
            float(box[2]),
        )
    models = lib.for_label(label)
    if not models:
        return _blank(object_id, label, the_box, pts, frame, color, f"no model for label {label!r}")
    if len(pts) < MIN_POINTS:
        return _blank(
            object_id,
            label,
            the_box,
            pts,
            frame,
            color,
            f"{len(pts)} points (fewer than {MIN_POINTS})",
        )
    rng = np.random.default_rng(seed)
    data = grid_downsample(pts, MODEL_SPACING)
    # Layers and outlines need no finer grid than a centimetre; a dense scan has 25 times
    # more points on the 0.5 cm grid.
    found = hints_from_points(grid_downsample(data, HINT_SPACING), label, ontology)
    hints = found if hints is None else hints.merged(found)
    coarse_data = _subset(data, COARSE_POINTS, rng)
    fine_data = _subset(data, FINE_POINTS, rng)

    # Coarse pass: every model from every start, a few steps on a 2 cm model grid; each
    # model keeps its best start.
    from scipy.spatial import cKDTree  # lazy: scipy.spatial off the import path

    data_tree = cKDTree(grid_downsample(data, COVER_SPACING / 2))
    trials = []
    for model in models:
        scale = model_scale(model, hints, ontology) if scale_to_object else np.ones(3)
        mpts = model.points(COARSE_SPACING)
        starts = _starts(model, hints, data, mpts, scale)
        res = ground_icp(
            coarse_data,
            mpts,
            starts,
            tree=model.tree(COARSE_SPACING),
            scale=scale,
            kernel=kernel,
            max_iterations=COARSE_ITERATIONS,
            inlier_distance=max(inlier_distance, COARSE_SPACING),
        )
        k = res.best
        pose = res.pose(k)
        trials.append(
            (
                _choice(float(res.cost[k]), _coverage(model, scale, pose, data_tree)),
                model,
                scale,
                np.array([res.x[k], res.y[k], res.yaw[k]]),
            )
        )
    trials.sort(key=lambda t: t[0])

    # Fine pass on the 0.5 cm grid for the most promising models.
    candidates: dict[str, dict[str, float]] = {}
    best = None
    refine = [t for t in trials[:FINE_MODELS] if t[0] <= trials[0][0] + REFINE_MARGIN]
    for _, model, scale, start in refine:
        res = ground_icp(
            fine_data,
            model.points(MODEL_SPACING),
            start,
            tree=model.tree(MODEL_SPACING),
            scale=scale,
            kernel=kernel,
            max_iterations=FINE_ITERATIONS,
            max_distance=FINE_MAX_DISTANCE,
            inlier_distance=inlier_distance,
        )
        coverage = _coverage(model, scale, res.pose(0), data_tree)
        entry = {
            "rms": float(res.rms[0]),
            "inlier_fraction": float(res.inlier_fraction[0]),
            "coverage": coverage,
            "cost": _choice(float(res.cost[0]), coverage),
        }
        candidates[model.name] = entry
        if best is None or entry["cost"] < best[0]["cost"]:
            best = (entry, model, scale, res)
    for cost, model, _, _ in trials[len(refine) :]:
        candidates[model.name] = {"coarse_cost": cost}
    entry, model, scale, res = best  # type: ignore[misc]  # at least one model was tried
    if entry["inlier_fraction"] < MIN_INLIER_FRACTION:
        return _blank(
            object_id,
            label,
            the_box,
            pts,
            frame,
            color,
            f"best model {model.name!r} matches {entry['inlier_fraction']:.0%} of "
            f"the points (fewer than {MIN_INLIER_FRACTION:.0%})",
            candidates,
        )
    level_pose = res.pose(0)
    return CadFit(
        id=object_id,
        label=label,
        model=model.name,
        pose=frame.pose_to_input(level_pose),
        level_pose=level_pose,
        scale=scale,
        rms=entry["rms"],
        inlier_fraction=entry["inlier_fraction"],
        color=color,
        num_points=len(pts),
        candidates=candidates,
        up=frame.up,
        cad_model=model,
    )


# ---------------------------------------------------------------------------------------
# Fitting detections


def _rows_of(cloud: PointCloud, file_rows: ArrayLike) -> NDArray[np.int64]:
    """Positions in ``cloud`` of the points whose file rows are given (missing rows skipped)."""
    rows = np.asarray(file_rows, dtype=np.int64).reshape(-1)
    if cloud.is_complete:
        return rows[(rows >= 0) & (rows < len(cloud))]
    index = cloud.index
    lookup = np.full(int(index.max()) + 1 if len(index) else 0, -1, dtype=np.int64)
    lookup[index] = np.arange(len(index))
    rows = rows[(rows >= 0) & (rows < len(lookup))]
    pos = lookup[rows]
    return pos[pos >= 0]


def _check_common(min_score: float) -> None:
    if (
        isinstance(min_score, bool)
        or not isinstance(min_score, (int, float))
        or not 0.0 <= min_score <= 1.0
    ):
        raise InvalidParameterError("min_score", "a number in [0, 1]", min_score)


def _fit_entries(
    entries: Sequence[dict[str, Any]],
    level_xyz: Any,
    rgb: NDArray[np.uint8] | None,
    frame: LevelFrame,
    library: ModelLibrary | None,
    min_score: float,
    seed: int,
    options: dict[str, Any],
) -> list[CadFit]:
    lib = builtin_library() if library is None else library
    onto = options.get("ontology") or builtin_ontology()
    fits = []
    with progress("Fitting CAD models", total=len(entries)) as advance:
        for e in entries:
            rows = e["rows"]
            pts = level_xyz(rows)
            colors = None if rgb is None else rgb[rows]
            center, size, yaw = e["box"]
            box = (
                frame.level(np.asarray(center, dtype=np.float64))[0],
                np.asarray(size, dtype=np.float64) * frame.scale,
                frame.yaw_to_level(yaw),
            )
            if e["score"] < min_score:
                fits.append(
                    _blank(
                        e["id"],
                        e["label"],
                        box,
                        pts,
                        frame,
                        _mean_color(colors, e["label"]),
                        f"score {e['score']:.3f} below min_score {min_score:g}",
                    )
                )
            else:
                hints = _hints_from_parts(e["parts"], frame, onto.cad_parts(e["label"]))
                fits.append(
                    fit_object(
                        pts,
                        e["label"],
                        lib,
                        hints=hints,
                        colors=colors,
                        frame=frame,
                        box=box,
                        object_id=e["id"],
                        seed=np.random.default_rng([seed, e["id"]]),
                        **options,
                    )
                )
            advance(1)
    return fits


def fit_detections(
    result: Any,
    library: ModelLibrary | None = None,
    *,
    min_score: float = MIN_SCORE,
    seed: int = 0,
    scale_to_object: bool = True,
    kernel: str = "tukey",
    inlier_distance: float = INLIER_DISTANCE,
    ontology: Ontology | None = None,
) -> list[CadFit]:
    """Fit a generic model to every detection of a :func:`~ontodetect.pipeline.detect` result.

    Parameters
    ----------
    result : ontodetect.pipeline.Result
        Detections, the input cloud and its preparation (levelled frame).
    library : ModelLibrary, optional
        Models to choose from (built-in ones by default).
    min_score : float
        Detections with a lower probability get the blank box (their detection box).
    seed : int
        Seed of every random step; the same result and seed give the same fits.
    scale_to_object, kernel, inlier_distance :
        See :func:`fit_object`.
    ontology : Ontology, optional
        Which parts give the seat and backrest, where seats and tops are sought and
        how far footprints stretch (see :func:`fit_object`); the built-in one by default.

    Returns
    -------
    list of CadFit
        One per detection, in the order of ``result.detections``; ``cad_dict(fit)``
        is the detection's ``cad`` entry of detections.json.
    """
    _check_common(min_score)
    prep = result.segmentation.prepared
    cloud = result.cloud
    frame = prep.frame
    levelled = prep.cloud.xyz
    entries = [
        {
            "id": int(d.id),
            "label": d.label,
            "score": float(d.score),
            "rows": _rows_of(cloud, d.point_indices),
            "parts": d.parts,
            "box": (np.asarray(d.center), np.asarray(d.size), float(d.yaw)),
        }
        for d in result.detections
    ]
    options = {
        "scale_to_object": scale_to_object,
        "kernel": kernel,
        "inlier_distance": inlier_distance,
        "ontology": ontology,
    }
    return _fit_entries(
        entries, lambda rows: levelled[rows], cloud.rgb, frame, library, min_score, seed, options
    )


def fit_document(
    document: Mapping[str, Any],
    cloud: PointCloud,
    library: ModelLibrary | None = None,
    *,
    min_score: float = MIN_SCORE,
    seed: int = 0,
    scale_to_object: bool = True,
    kernel: str = "tukey",
    inlier_distance: float = INLIER_DISTANCE,
    ontology: Ontology | None = None,
) -> list[CadFit]:
    """Fit models to the detections of a detections.json document and its input cloud.

    The levelled frame is rebuilt from the document's ``frame`` (up, ground_z,
    scale); a bent floor's correction, which detections.json does not keep, is
    left out.

    Parameters
    ----------
    document : mapping
        A validated detections.json (:func:`ontodetect.io.read_detections`).
    cloud : PointCloud
        The input file the detections were made on (``point_indices`` are its rows).
    library, min_score, seed, scale_to_object, kernel, inlier_distance, ontology :
        See :func:`fit_detections`.

    Returns
    -------
    list of CadFit
        One per detection, in the document's order.
    """
    _check_common(min_score)
    if not isinstance(cloud, PointCloud):
        raise InvalidParameterError("cloud", "a PointCloud", type(cloud).__name__)
    n_doc = int(document.get("num_points", len(cloud)))
    n_file = int(cloud.index.max()) + 1 if len(cloud) else 0
    if n_doc != n_file:
        raise InvalidParameterError(
            "cloud",
            f"the input the detections were made on ({n_doc} points)",
            f"a cloud of {n_file} points",
        )
    frame = LevelFrame.from_dict(document["frame"])
    entries = []
    for d in document["detections"]:
        b = d["box"]
        entries.append(
            {
                "id": int(d["id"]),
                "label": str(d["label"]),
                "score": float(d["score"]),
                "rows": _rows_of(cloud, d["point_indices"]),
                "parts": d.get("parts") or [],
                "box": (
                    np.asarray(b["center"], dtype=np.float64),
                    np.asarray(b["size"], dtype=np.float64),
                    float(b["yaw"]),
                ),
            }
        )
    options = {
        "scale_to_object": scale_to_object,
        "kernel": kernel,
        "inlier_distance": inlier_distance,
        "ontology": ontology,
    }
    xyz = cloud.xyz
    return _fit_entries(
        entries,
        lambda rows: frame.level(xyz[rows]),
        cloud.rgb,
        frame,
        library,
        min_score,
        seed,
        options,
    )


# ---------------------------------------------------------------------------------------
# The object map


def _model_of(fit: CadFit) -> CadModel:
    return fit.cad_model if fit.cad_model is not None else box_model(fit.label)


def _apply(T: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
    return points @ T[:3, :3].T + T[:3, 3]


def object_map_cloud(fits: Sequence[CadFit], *, spacing: float = 0.01, seed: int = 0) -> PointCloud:
    """The object map as one point cloud: every fitted full model, sampled and coloured.

    Points are in the input file's frame, coloured by the object's mean colour
    (thesis §3.7: "the final map is the collection of all the transformed CAD
    models grouped into a single point cloud"), with the field ``object`` (the
    detection id).

    Parameters
    ----------
    fits : sequence of CadFit
    spacing : float
        Grid (m) of the samples on each model.
    seed : int
        Seed of the sampling.
    """
    xyz, rgb, ids = [], [], []
    for f in fits:
        if f.blank:
            # A box is stretched far more than a model: sample it at its real size.
            box = _model_of(f).full
            pts = _apply(
                f.pose, sample_surface(Mesh(box.vertices * f.scale, box.triangles), spacing, seed)
            )
        else:
            pts = _apply(f.transform, _model_of(f).display_points(spacing, seed))
        xyz.append(pts)
        rgb.append(np.broadcast_to(f.color, (len(pts), 3)))
        ids.append(np.full(len(pts), f.id, dtype=np.int32))
    if not xyz:
        return point_cloud(
            np.zeros((0, 3)), np.zeros((0, 3), np.uint8), fields={"object": np.zeros(0, np.int32)}
        )
    return point_cloud(
        np.concatenate(xyz), np.concatenate(rgb), fields={"object": np.concatenate(ids)}
    )


def object_map_meshes(
    fits: Sequence[CadFit],
) -> list[tuple[str, NDArray[np.float64], NDArray[np.int32], NDArray[np.uint8]]]:
    """Every fitted full model as (name, vertices in the input frame, triangles, colour)."""
    out = []
    for f in fits:
        m = _model_of(f).full
        vertices = _apply(f.transform, m.vertices)
        triangles = m.triangles
        if np.linalg.det(f.transform[:3, :3]) < 0:  # a mirroring frame turns faces inside out
            triangles = triangles[:, ::-1]
        out.append(
            (
                f"{f.id}-{f.label}-{f.model}",
                vertices,
                np.ascontiguousarray(triangles),
                np.asarray(f.color, dtype=np.uint8),
            )
        )
    return out


@dataclass(frozen=True)
class ObjectMapFiles:
    """Paths written by :func:`write_object_map` (None for a file not asked for)."""

    points: Path
    glb: Path | None
    mesh: Path | None


def _y_up(up: NDArray[np.float64]) -> NDArray[np.float64]:
    """4x4 rotation taking the input's up direction to +y (glTF's up)."""
    T = np.eye(4)
    T[:3, :3] = rotation_between(up, (0.0, 1.0, 0.0))
    return T


def write_object_map(
    fits: Sequence[CadFit],
    out_dir: str | Path,
    *,
    spacing: float = 0.01,
    seed: int = 0,
    glb: bool = True,
    mesh: bool = True,
) -> ObjectMapFiles:
    """Write the object map as ``object_map.ply``, ``object_map.glb`` and ``object_map_mesh.ply``.

    ``object_map.ply`` is :func:`object_map_cloud` and ``object_map_mesh.ply``
    the full models as one coloured triangle mesh, both in the input file's
    frame so that they overlay the scan. ``object_map.glb`` is a glTF scene with
    one named node per object (``<id>-<label>-<model>``); glTF's up axis is +y,
    so the scene is turned to put the scan's up there.

    Parameters
    ----------
    fits : sequence of CadFit
    out_dir : str or Path
        Folder (created if needed).
    spacing, seed :
        Sampling of the point map (:func:`object_map_cloud`).
    glb, mesh : bool
        Write the GLB scene (not when there is no object) and the PLY mesh.

    Returns
    -------
    ObjectMapFiles
    """
    import trimesh  # lazy: trimesh only to write the object map

    out = make_folder(out_dir, "output folder")
    points_path = write_cloud(
        out / "object_map.ply", object_map_cloud(fits, spacing=spacing, seed=seed)
    )
    parts = object_map_meshes(fits)
    glb_path = mesh_path = None
    if glb and parts:  # glTF readers take an empty scene, trimesh will not write one
        up = fits[0].up if fits else np.array([0.0, 0.0, 1.0])
        to_gltf = _y_up(np.asarray(up, dtype=np.float64))
        scene = trimesh.Scene()
        for name, vertices, triangles, color in parts:
            geom = _trimesh_geometry(trimesh, _apply(to_gltf, vertices), triangles, color)
            scene.add_geometry(geom, node_name=name, geom_name=name)
        glb_path = atomic_write_bytes(out / "object_map.glb", scene.export(file_type="glb"))
    if mesh:
        meshes = [_trimesh_geometry(trimesh, v, t, c) for _, v, t, c in parts if len(t)]
        combined = trimesh.util.concatenate(meshes) if meshes else trimesh.Trimesh()
        mesh_path = atomic_write_bytes(
            out / "object_map_mesh.ply", combined.export(file_type="ply")
        )
    return ObjectMapFiles(points_path, glb_path, mesh_path)


def _trimesh_geometry(
    trimesh: Any,
    vertices: NDArray[np.float64],
    triangles: NDArray[np.int32],
    color: NDArray[np.uint8],
) -> Any:
    rgba = np.tile(np.r_[color, 255].astype(np.uint8), (len(vertices), 1))
    if len(triangles) == 0:
        return trimesh.PointCloud(vertices, colors=rgba)
    return trimesh.Trimesh(vertices=vertices, faces=triangles, vertex_colors=rgba, process=False)
