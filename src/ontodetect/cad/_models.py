"""Generic CAD models: a thin profile for matching and a full model for display (thesis §3.7).

A :class:`CadModel` is one generic object of a class (``chair``, ``sofa``,
``table`` ...) in its canonical frame: the origin at the centre of its footprint
on the floor, x to its right, y to its front (the way a person sitting on it
faces), z up, metres. This is the object frame of :mod:`ontodetect.synth`, so a
fitted pose compares directly with a simulated object's pose.

Each model comes in two forms. The sensor sees only some surfaces of a piece of
furniture: the top of a seat, the front and back of a backrest, the top and
edges of a table, never the underside. Matching a solid model would pull the
fit towards surfaces that have no points (thesis §4, Figures 4.9–4.10), so
matching uses the **thin profile** (:attr:`CadModel.thin`: the part of the
surface a sensor walking around the object sees, found by casting rays from a
ring of viewpoints, see :func:`visible_surface`) and display uses the **full**
closed model (:attr:`CadModel.full`).

Models are point-sampled by area (:func:`sample_surface`, seeded) and then
grid-averaged (:func:`grid_downsample`, 0.5 cm by default, the grid of the
thesis's experiment) before matching; samples are cached on the model.

:func:`builtin_library` holds procedural generic models built from the solids
of :mod:`ontodetect.geometry._mesh`: chairs (four-legged, with arms, office
swivel, moulded shell, armchair), sofas (two and three seats), tables (rectangular, square,
round, coffee) and a desk. They are deliberately plain, like the roughly drawn
models of the thesis: dimensions are the middle of the ranges of furniture
standards, and fitting may scale them to the object (:mod:`ontodetect.cad._fit`).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..geometry import _mesh as M
from ..geometry._mesh import Mesh
from ..preprocess import voxelize

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

__all__ = [
    "MODEL_SPACING",
    "CadModel",
    "ModelLibrary",
    "box_model",
    "builtin_library",
    "canonical_mesh",
    "grid_downsample",
    "library_figure",
    "make_model",
    "sample_surface",
    "visible_shell",
    "visible_surface",
]

#: Grid (m) the model samples are averaged on before matching: 0.5 cm, as in the thesis's
#: experiment (§4, "a grid size of 0.5 cm³ was used for both source point cloud and the
#: meshed CAD models").
MODEL_SPACING = 0.005
#: Area samples drawn per grid cell before averaging, so that nearly every cell a surface
#: crosses gets at least one sample.
SAMPLES_PER_CELL = 3.0
#: A face whose normal points further down than this (z component) is never seen by a
#: sensor that stands on the floor: it is left out of the thin profile.
HIDDEN_NORMAL_Z = -0.5
#: Viewpoints of the visibility test (:func:`visible_surface`): a ring this far (m) outside
#: the model's footprint, at these heights (m) above the floor, this many directions around.
VIEW_DISTANCE = 2.0
VIEW_HEIGHTS = (0.8, 1.3, 1.8)
VIEW_AZIMUTHS = 12
#: Triangles are cut until no edge is longer than this (m) before the test, so that a face
#: half hidden (a sofa's frame under its cushions) keeps its visible half.
VISIBILITY_EDGE = 0.10
#: Sensors return nothing where a ray meets a surface more than 75° from its normal (the
#: RGB-D camera of ontodetect.synth drops those returns too).
GRAZING_COS = math.cos(math.radians(75.0))
#: A ray that stops this close (m) before a piece's centre still sees it (float32 rays).
VISIBILITY_TOLERANCE = 1e-3
#: Symmetry orders: 1 none, 2 half a turn (rectangular), 4 a quarter turn (square),
#: 0 any rotation (round).
SYMMETRIES = (0, 1, 2, 4)
#: Default colour of each class when the scan has no colours (sRGB).
LABEL_COLORS: dict[str, tuple[int, int, int]] = {
    "chair": (200, 80, 60),
    "sofa": (70, 110, 170),
    "table": (170, 130, 90),
}
DEFAULT_COLOR = (150, 150, 150)


# ---------------------------------------------------------------------------------------
# Sampling


def grid_downsample(points: ArrayLike, spacing: float = MODEL_SPACING) -> NDArray[np.float64]:
    """(k, 3) float: the grid average of (n, 3) points, one point per occupied cell.

    The result does not depend on the order of the input points.

    Examples
    --------
    >>> grid_downsample([[0.001, 0, 0], [0.003, 0, 0], [0.05, 0, 0]], 0.02).tolist()
    [[0.002, 0.0, 0.0], [0.05, 0.0, 0.0]]
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InvalidParameterError("points", "an array of shape (n, 3)", f"shape {pts.shape}")
    if not (isinstance(spacing, (int, float)) and spacing > 0):
        raise InvalidParameterError("spacing", "a float in the range (0, inf)", spacing)
    if len(pts) == 0:
        return np.zeros((0, 3))
    return np.array(voxelize(pts, float(spacing)).centers)


def _triangle_areas(mesh: Mesh) -> NDArray[np.float64]:
    v = mesh.vertices[mesh.triangles]
    return 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)


def sample_surface(
    mesh: Mesh,
    spacing: float = MODEL_SPACING,
    rng: int | np.random.Generator | None = 0,
) -> NDArray[np.float64]:
    """(k, 3) float: points spread evenly over a mesh's surface, one per grid cell.

    Points are drawn uniformly by area (about three per cell of the grid) and
    then grid-averaged at ``spacing`` (:func:`grid_downsample`). A mesh without
    triangles is a point set: its vertices are grid-averaged.

    Parameters
    ----------
    mesh : Mesh
        Triangles to sample.
    spacing : float
        Grid edge (m).
    rng : int or numpy.random.Generator, optional
        Seed of the area sampling; the same seed gives the same points.

    Examples
    --------
    >>> square = Mesh(np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]),
    ...               np.array([[0, 1, 2], [0, 2, 3]]))
    >>> pts = sample_surface(square, spacing=0.05, rng=0)  # 1 m2: about 400 cells of 25 cm2
    >>> bool(np.all(pts[:, 2] == 0)), 350 < len(pts) <= 441
    (True, True)
    """
    if not (isinstance(spacing, (int, float)) and spacing > 0):
        raise InvalidParameterError("spacing", "a float in the range (0, inf)", spacing)
    if len(mesh.triangles) == 0:
        return grid_downsample(mesh.vertices, spacing)
    gen = np.random.default_rng(rng)
    areas = _triangle_areas(mesh)
    total = float(areas.sum())
    if total <= 0:
        return grid_downsample(mesh.vertices, spacing)
    n = max(1, math.ceil(SAMPLES_PER_CELL * total / spacing**2))
    tri = gen.choice(len(areas), size=n, p=areas / total)
    # Uniform barycentric coordinates: fold the unit square onto the triangle.
    u, v = gen.random(n), gen.random(n)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    corners = mesh.vertices[mesh.triangles[tri]]
    pts = (
        corners[:, 0]
        + u[:, None] * (corners[:, 1] - corners[:, 0])
        + v[:, None] * (corners[:, 2] - corners[:, 0])
    )
    return grid_downsample(pts, spacing)


def visible_shell(mesh: Mesh, hidden_normal_z: float = HIDDEN_NORMAL_Z) -> Mesh:
    """A quick thin profile of a solid: its faces except those that face the floor.

    A sensor standing on the floor sees the top and sides of a seat, both faces
    of a backrest and the top and edges of a table, never their undersides.
    Faces whose outward normal has a z component below ``hidden_normal_z`` are
    dropped. Unlike :func:`visible_surface` it keeps faces hidden by other
    parts (between two cushions, under a seat cushion).

    Examples
    --------
    >>> from ontodetect.geometry._mesh import box
    >>> len(box((1.0, 1.0, 1.0)).triangles), len(visible_shell(box((1.0, 1.0, 1.0))).triangles)
    (12, 10)
    """
    if len(mesh.triangles) == 0:
        return mesh
    v = mesh.vertices[mesh.triangles]
    normal = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    length = np.linalg.norm(normal, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        nz = np.where(length > 0, normal[:, 2] / length, 0.0)
    return Mesh(mesh.vertices, mesh.triangles[nz >= hidden_normal_z])


def _subdivide(triangles: NDArray[np.float64], max_edge: float) -> NDArray[np.float64]:
    """(k, 3, 3) triangles split in four until no edge is longer than ``max_edge``."""
    out = []
    tris = triangles
    while len(tris):
        edge = np.linalg.norm(tris - np.roll(tris, 1, axis=1), axis=2).max(axis=1)
        big = edge > max_edge
        out.append(tris[~big])
        b = tris[big]
        m01, m12, m20 = (b[:, 0] + b[:, 1]) / 2, (b[:, 1] + b[:, 2]) / 2, (b[:, 2] + b[:, 0]) / 2
        tris = np.concatenate(
            [
                np.stack([b[:, 0], m01, m20], axis=1),
                np.stack([m01, b[:, 1], m12], axis=1),
                np.stack([m20, m12, b[:, 2]], axis=1),
                np.stack([m01, m12, m20], axis=1),
            ]
        )
    return np.concatenate(out) if out else np.zeros((0, 3, 3))


def visible_surface(
    mesh: Mesh,
    *,
    distance: float = VIEW_DISTANCE,
    heights: tuple[float, ...] = VIEW_HEIGHTS,
    azimuths: int = VIEW_AZIMUTHS,
    max_edge: float = VISIBILITY_EDGE,
) -> Mesh:
    """The thin profile of a model: the part of its surface a sensor walking around it sees.

    Virtual viewpoints stand on a ring ``distance`` metres outside the model's
    footprint, at ``heights`` above the floor (a hand-held camera, a tripod),
    ``azimuths`` directions around. The triangles are cut until no edge is
    longer than ``max_edge``; a piece is kept when some viewpoint sees its
    centre (it faces the viewpoint within 75° and the first surface the ray
    meets is itself). Undersides, the faces between two cushions and the frame under a
    sofa's cushions drop out; seat tops, both faces of a backrest, table tops and
    their edges stay.

    Parameters
    ----------
    mesh : Mesh
        The full model in its canonical frame (z up, floor at 0).

    Returns
    -------
    Mesh
        The visible pieces (a mesh without triangles is returned as it is).

    Examples
    --------
    >>> from ontodetect.geometry._mesh import box
    >>> thin = visible_surface(box((1.0, 1.0, 0.5), (0.0, 0.0, 0.25)))
    >>> bool(thin.vertices[:, 2].max() == 0.5), bool(thin.vertices[:, 2].min() == 0.0)
    (True, True)
    >>> round(float(_triangle_areas(thin).sum()), 6)  # the top and four sides, not the bottom
    3.0
    """
    if len(mesh.triangles) == 0:
        return mesh
    import open3d as o3d  # lazy: open3d (0.8 s to import) only for visibility tests

    tris = _subdivide(mesh.vertices[mesh.triangles], max_edge)
    centre = tris.mean(axis=1)
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(
        o3d.core.Tensor(mesh.vertices.astype(np.float32)),
        o3d.core.Tensor(mesh.triangles.astype(np.uint32)),
    )
    lo, hi = mesh.bounds
    radius = float(np.hypot(*(hi[:2] - lo[:2]))) / 2 + distance
    mid = (lo + hi) / 2
    seen = np.zeros(len(tris), dtype=bool)
    for h in heights:
        for a in np.linspace(0.0, 2 * np.pi, azimuths, endpoint=False):
            eye = np.array([mid[0] + radius * np.cos(a), mid[1] + radius * np.sin(a), h])
            ray = centre - eye
            length = np.linalg.norm(ray, axis=1)
            ray /= length[:, None]
            facing = np.einsum("ij,ij->i", normal, ray) < -GRAZING_COS
            rays = np.concatenate([np.broadcast_to(eye, ray.shape), ray], axis=1)
            hit = scene.cast_rays(o3d.core.Tensor(rays.astype(np.float32)))["t_hit"].numpy()
            seen |= facing & (hit >= length - VISIBILITY_TOLERANCE)
    kept = tris[seen]
    return Mesh(kept.reshape(-1, 3), np.arange(3 * len(kept), dtype=np.int32).reshape(-1, 3))


def canonical_mesh(mesh: Mesh, reference: Mesh | None = None) -> tuple[Mesh, NDArray[np.float64]]:
    """Move a mesh so that its footprint is centred on the origin and its lowest point is at z = 0.

    Parameters
    ----------
    mesh : Mesh
        The mesh to move.
    reference : Mesh, optional
        The mesh whose bounding box decides the shift (the full model, when
        moving its thin profile along with it); ``mesh`` itself by default.

    Returns
    -------
    mesh : Mesh
    shift : (3,) float
        The translation applied.
    """
    ref = mesh if reference is None else reference
    if len(ref.vertices) == 0:
        return mesh, np.zeros(3)
    lo, hi = ref.bounds
    shift = np.array([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    return mesh.translated(shift), shift


# ---------------------------------------------------------------------------------------
# Models


@dataclass(frozen=True, eq=False)
class CadModel:
    """A generic model of one class, in its canonical frame (metres, z up, y front).

    Attributes
    ----------
    name : str
        Unique name in its library, e.g. ``"chair-4leg"``.
    label : str
        Class it stands for (the ontology's class name).
    full : Mesh
        Display model (closed solids, or a point set when it has no triangles).
    thin : Mesh
        Matching profile: the surfaces a sensor sees.
    dims : mapping of str to float
        ``width`` (x), ``depth`` (y), ``height`` of the full model, and where they
        apply ``seat_height``, ``seat_width``, ``seat_depth`` (seating) or
        ``top_height``, ``top_width``, ``top_depth`` (tables), in metres.
    symmetry : int
        Rotations about z that leave the model unchanged: 1 none, 2 half a
        turn, 4 a quarter turn, 0 any (round).
    anchor : (3,) float or None
        Centre of the top of the seat (seating) or of the table top: fitting
        starts by putting it on the object's.
    color : (3,) int
        Colour used when the scan has none.
    description : str
    source : str
        ``"builtin"`` or the file the model was read from.
    """

    name: str
    label: str
    full: Mesh
    thin: Mesh
    dims: Mapping[str, float]
    symmetry: int = 1
    anchor: tuple[float, float, float] | None = None
    color: tuple[int, int, int] = DEFAULT_COLOR
    description: str = ""
    source: str = "builtin"
    _cache: dict[Any, Any] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.symmetry not in SYMMETRIES:
            raise InvalidParameterError("symmetry", "one of 0, 1, 2, 4", self.symmetry)

    @property
    def seat_height(self) -> float | None:
        return self.dims.get("seat_height")

    @property
    def top_height(self) -> float | None:
        return self.dims.get("top_height")

    @property
    def is_seating(self) -> bool:
        """True for models with a seat (chairs, sofas): they have a front."""
        return "seat_height" in self.dims

    def points(self, spacing: float = MODEL_SPACING, seed: int = 0) -> NDArray[np.float64]:
        """(k, 3) float: the thin profile sampled and grid-averaged at ``spacing`` (cached)."""
        key = ("thin", float(spacing), seed)
        if key not in self._cache:
            pts = sample_surface(self.thin, spacing, seed)
            pts.flags.writeable = False
            self._cache[key] = pts
        return self._cache[key]

    def tree(self, spacing: float = MODEL_SPACING, seed: int = 0) -> cKDTree:
        """A k-d tree of :meth:`points` (cached): one tree serves every object fitted."""
        key = ("tree", float(spacing), seed)
        if key not in self._cache:
            from scipy.spatial import cKDTree  # lazy: scipy.spatial off the import path

            self._cache[key] = cKDTree(self.points(spacing, seed))
        return self._cache[key]

    def display_points(self, spacing: float = 0.01, seed: int = 0) -> NDArray[np.float64]:
        """(k, 3) float: the full model sampled at ``spacing`` (cached), for object maps."""
        key = ("full", float(spacing), seed)
        if key not in self._cache:
            pts = sample_surface(self.full, spacing, seed)
            pts.flags.writeable = False
            self._cache[key] = pts
        return self._cache[key]

    def summary(self) -> dict[str, Any]:
        """JSON-ready description (name, label, sizes, triangle counts, source)."""
        return {
            "name": self.name,
            "label": self.label,
            "dims": {k: round(float(v), 4) for k, v in self.dims.items()},
            "symmetry": self.symmetry,
            "full_triangles": len(self.full.triangles),
            "thin_triangles": len(self.thin.triangles),
            "source": self.source,
            "description": self.description,
        }


def _dims_of(full: Mesh, extra: Mapping[str, float]) -> dict[str, float]:
    lo, hi = full.bounds
    dims = {"width": float(hi[0] - lo[0]), "depth": float(hi[1] - lo[1]), "height": float(hi[2])}
    dims.update({k: float(v) for k, v in extra.items()})
    return dims


def make_model(
    name: str,
    label: str,
    parts: Iterable[Mesh],
    dims: Mapping[str, float],
    *,
    symmetry: int = 1,
    color: tuple[int, int, int] | None = None,
    description: str = "",
    thin_parts: Iterable[Mesh] | None = None,
    anchor: ArrayLike | None = None,
) -> CadModel:
    """A model from solid parts: full = the solids, thin = their :func:`visible_surface`.

    ``dims`` gives the class-specific sizes (``seat_height`` ...); overall width,
    depth and height are measured. The parts (and the ``anchor`` point given in
    their frame) are moved to the canonical frame; ``thin_parts``, when given,
    replace the solids in the visibility test.
    """
    solids = list(parts)
    full, shift = canonical_mesh(M.concatenate(solids))
    thin_src = solids if thin_parts is None else list(thin_parts)
    # Viewpoint heights are above the floor: test visibility in the canonical frame.
    thin = visible_surface(M.concatenate(thin_src).translated(shift))
    moved = (
        None
        if anchor is None
        else tuple(float(v) for v in np.asarray(anchor, dtype=np.float64) + shift)
    )
    # Heights move with the model when putting it on the floor lifts or lowers it.
    heights = {k: v + shift[2] if k.endswith("_height") else v for k, v in dims.items()}
    return CadModel(
        name=name,
        label=label,
        full=full,
        thin=thin,
        dims=_dims_of(full, heights),
        symmetry=symmetry,
        anchor=moved,
        color=color or LABEL_COLORS.get(label, DEFAULT_COLOR),
        description=description,
    )


@functools.lru_cache(maxsize=64)
def box_model(label: str = "object") -> CadModel:
    """The blank model: a unit box standing on the floor, scaled to a detection's box.

    Objects whose probability is too low (thesis §4: "objects with very low
    probabilities are replaced with blank models") or that no model fits get it.
    """
    full = M.box_between((-0.5, -0.5, 0.0), (0.5, 0.5, 1.0))
    return CadModel(
        "box",
        label,
        full,
        full,
        _dims_of(full, {}),
        symmetry=4,
        color=LABEL_COLORS.get(label, DEFAULT_COLOR),
        description="Blank box: the detection's box.",
    )


class ModelLibrary(Mapping[str, CadModel]):
    """Models by name, with the ones of each label in insertion order.

    Examples
    --------
    >>> lib = builtin_library()
    >>> "chair-4leg" in lib, lib["table-round"].symmetry
    (True, 0)
    >>> sorted(lib.labels)
    ['chair', 'sofa', 'table']
    """

    def __init__(self, models: Iterable[CadModel] = ()) -> None:
        self._models: dict[str, CadModel] = {}
        for m in models:
            self._models[m.name] = m

    def __getitem__(self, name: str) -> CadModel:
        try:
            return self._models[name]
        except KeyError:
            raise InvalidParameterError(
                "model", f"one of {', '.join(self._models)}", name
            ) from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._models)

    def __len__(self) -> int:
        return len(self._models)

    def __contains__(self, name: object) -> bool:
        return name in self._models

    def __repr__(self) -> str:
        return f"ModelLibrary({list(self._models)})"

    @property
    def labels(self) -> list[str]:
        """Labels that have at least one model, in order of first appearance."""
        return list(dict.fromkeys(m.label for m in self._models.values()))

    def for_label(self, label: str) -> list[CadModel]:
        """The models of one label (empty when there is none)."""
        return [m for m in self._models.values() if m.label == label]

    def merged(self, other: Iterable[CadModel]) -> ModelLibrary:
        """A new library with ``other``'s models added; a model of the same name replaces ours."""
        return ModelLibrary([*self._models.values(), *other])


# ---------------------------------------------------------------------------------------
# The built-in generic models. Sizes are the middle of the ranges of the standards that
# synth.furniture cites (EN 12520, EN 1335, EN 1730, Neufert), rounded: they are generic,
# not any particular chair.

CHAIR_SEAT = (0.45, 0.43, 0.46)  # width, depth, height of the seat top
SOFA_SEAT_HEIGHT = 0.43
TABLE_HEIGHT = 0.74
COFFEE_TABLE_HEIGHT = 0.45


def _reclined(lo: ArrayLike, hi: ArrayLike, tilt_deg: float, pivot: ArrayLike) -> Mesh:
    """A box given relative to ``pivot`` and reclined by ``tilt_deg`` (top towards -y)."""
    p = np.asarray(pivot, dtype=np.float64)
    box = M.box_between(np.asarray(lo, float) + p, np.asarray(hi, float) + p)
    return box.rotated("x", math.radians(tilt_deg), about=p)


def _four_legs(half_x: float, half_y: float, top: float, width: float) -> list[Mesh]:
    return [
        M.box_between(
            (sx * half_x - width / 2, sy * half_y - width / 2, 0.0),
            (sx * half_x + width / 2, sy * half_y + width / 2, top),
        )
        for sx in (-1, 1)
        for sy in (-1, 1)
    ]


def _chair_4leg(arms: bool) -> CadModel:
    sw, sd, sh = CHAIR_SEAT
    if arms:
        sw = 0.50
    st, lw, tilt = 0.03, 0.04, 10.0
    lx, ly = sw / 2 - 0.01 - lw / 2, sd / 2 - 0.01 - lw / 2
    parts = [M.box_between((-sw / 2, -sd / 2, sh - st), (sw / 2, sd / 2, sh))]
    parts += _four_legs(lx, ly, sh - st, lw)
    pivot = (0.0, -ly, sh - st)
    back = 0.88 - (sh - st)  # top of the backrest at 88 cm
    for sx in (-1, 1):
        parts.append(
            _reclined((sx * lx - lw / 2, -0.018, 0.0), (sx * lx + lw / 2, 0.018, back), tilt, pivot)
        )
    parts.append(_reclined((-lx, -0.011, back - 0.28), (lx, 0.011, back - 0.01), tilt, pivot))
    if arms:
        top = sh + 0.22
        for sx in (-1, 1):
            x = sx * lx
            parts.append(
                M.box_between((x - 0.025, -ly - 0.04, top - 0.025), (x + 0.025, ly + 0.03, top))
            )
            parts.append(
                M.box_between(
                    (x - 0.015, ly - 0.015, sh - st), (x + 0.015, ly + 0.015, top - 0.025)
                )
            )
    name = "chair-4leg-arms" if arms else "chair-4leg"
    text = "Four-legged chair" + (" with armrests" if arms else "") + ", panel backrest."
    return make_model(
        name,
        "chair",
        parts,
        {"seat_height": sh, "seat_width": sw, "seat_depth": sd},
        description=text,
        anchor=(0.0, 0.0, sh),
    )


def _chair_office() -> CadModel:
    sw, sd, sh, st = 0.48, 0.45, 0.47, 0.07
    parts = [M.rounded_box((sw, sd, st), 0.04, center=(0.0, 0.02, sh - st / 2))]
    pivot = np.array([0.0, -sd / 2 + 0.02, sh + 0.05])
    parts.append(
        M.rounded_box(
            (0.45, 0.06, 0.55), 0.05, axis="y", center=pivot + (0.0, -0.03, 0.30)
        ).rotated("x", math.radians(12.0), about=pivot)
    )
    # Spine from under the seat to the backrest.
    parts.append(
        M.box_between((-0.03, -sd / 2 - 0.01, sh - st - 0.03), (0.03, -sd / 2 + 0.05, sh + 0.08))
    )
    parts.append(M.cylinder(0.028, sh - st - 0.10, 16, center=(0.0, 0.0, 0.10)))
    radius = 0.32
    for k in range(5):
        arm = M.box_between((0.0, -0.02, 0.06), (radius, 0.02, 0.10))
        parts.append(arm.rotated("z", math.pi / 2 + 2 * math.pi * k / 5))
        a = math.pi / 2 + 2 * math.pi * k / 5
        parts.append(
            M.cylinder(0.025, 0.06, 12, center=(radius * math.cos(a), radius * math.sin(a), 0.0))
        )
    top = sh + 0.22
    for sx in (-1, 1):
        x = sx * (sw / 2 + 0.02)
        parts.append(M.box_between((x - 0.035, -0.12, top - 0.03), (x + 0.035, 0.16, top)))
        parts.append(M.box_between((x - 0.015, -0.06, sh - st), (x + 0.015, -0.02, top - 0.03)))
    return make_model(
        "chair-office",
        "chair",
        parts,
        {"seat_height": sh, "seat_width": sw, "seat_depth": sd},
        description="Office swivel chair: five-star base, armrests.",
        anchor=(0.0, 0.02, sh),
    )


def _chair_shell() -> CadModel:
    """A moulded shell (seat and back in one curved sheet) on four splayed legs."""
    sw, sd, sh, t, tilt = 0.47, 0.43, 0.45, 0.012, math.radians(15.0)
    zm = sh - t / 2
    corner = np.array([-sd / 2, zm])
    top = corner + 0.40 * np.array([-math.sin(tilt), math.cos(tilt)])
    # Profile (y, z) of the mid-surface: front lip, flat seat, curve up into the back.
    path = M.fillet_path(
        [
            (0, sd / 2 + 0.015, zm - 0.03),
            (0, sd / 2 - 0.02, zm),
            (0, -sd / 2 + 0.06, zm),
            (0, *corner),
            (0, *top),
        ],
        0.06,
        samples=6,
    )[:, 1:]
    across = np.linspace(-sw / 2, sw / 2, 9)
    grid = np.stack(
        np.broadcast_arrays(across[:, None], path[None, :, 0], path[None, :, 1]), axis=-1
    )
    parts = [M.thick_surface(grid, t)]
    ax, ay, splay = sw / 2 - 0.08, sd / 2 - 0.09, 0.045
    for sx in (-1, 1):
        for sy in (-1, 1):
            parts.append(
                M.cylinder_between(
                    (sx * (ax + splay), sy * (ay + splay), 0.0), (sx * ax, sy * ay, zm), 0.017, 12
                )
            )
    return make_model(
        "chair-shell",
        "chair",
        parts,
        {"seat_height": sh, "seat_width": sw, "seat_depth": sd},
        description="Moulded shell chair on four splayed legs.",
        anchor=(0.0, 0.02, sh),
    )


def _upholstered(
    name: str,
    label: str,
    inner: float,
    seats: int,
    arm: float,
    depth: float,
    seat_h: float,
    height: float,
    text: str,
) -> CadModel:
    """Armchair or sofa: a base, seat cushions, a back and two arms, on short feet."""
    W, D, z0 = inner + 2 * arm, depth, 0.06
    back_t, back_cushion = 0.18, 0.14
    ct = 0.13
    parts = [M.box_between((-inner / 2, -D / 2 + back_t, z0), (inner / 2, D / 2, seat_h - ct))]
    edges = np.linspace(-inner / 2, inner / 2, seats + 1)
    y0 = -D / 2 + back_t + back_cushion
    for a, b in itertools.pairwise(edges):
        parts.append(
            M.cushion(
                (b - a - 0.006, D / 2 - y0, ct),
                0.15,
                center=((a + b) / 2, (y0 + D / 2) / 2, seat_h - ct / 2),
            )
        )
        pivot = np.array([(a + b) / 2, -D / 2 + back_t + back_cushion / 2, seat_h - 0.02])
        bh = height - seat_h - 0.04
        cush = M.cushion((b - a - 0.006, back_cushion, bh), 0.25, center=pivot + (0, 0, bh / 2))
        parts.append(cush.rotated("x", math.radians(12.0), about=pivot))
    parts.append(
        M.rounded_box(
            (W, back_t, height - z0),
            0.04,
            axis="x",
            center=(0.0, -D / 2 + back_t / 2, (height + z0) / 2),
        )
    )
    arm_top = seat_h + 0.20
    for sx in (-1, 1):
        parts.append(
            M.rounded_box(
                (arm, D, arm_top - z0),
                min(0.05, arm / 2 - 0.005),
                axis="y",
                center=(sx * (inner / 2 + arm / 2), 0.0, (arm_top + z0) / 2),
            )
        )
    for sx in (-1, 1):
        for sy in (-1, 1):
            parts.append(
                M.cylinder(0.022, z0, 12, center=(sx * (W / 2 - 0.06), sy * (D / 2 - 0.06), 0.0))
            )
    return make_model(
        name,
        label,
        parts,
        {"seat_height": seat_h, "seat_width": inner, "seat_depth": D - back_t - back_cushion},
        description=text,
        anchor=(0.0, (y0 + D / 2) / 2, seat_h),
    )


def _rect_table(
    name: str,
    width: float,
    depth: float,
    height: float,
    symmetry: int,
    text: str,
    apron: bool = True,
) -> CadModel:
    t, lw, inset = 0.03, 0.05, 0.06
    parts = [M.rounded_box((width, depth, t), 0.01, center=(0.0, 0.0, height - t / 2))]
    lx, ly = width / 2 - inset - lw / 2, depth / 2 - inset - lw / 2
    parts += _four_legs(lx, ly, height - t, lw)
    if apron:
        z0, z1 = height - t - 0.08, height - t
        for sy in (-1, 1):
            parts.append(M.box_between((-lx, sy * ly - 0.01, z0), (lx, sy * ly + 0.01, z1)))
        for sx in (-1, 1):
            parts.append(M.box_between((sx * lx - 0.01, -ly, z0), (sx * lx + 0.01, ly, z1)))
    return make_model(
        name,
        "table",
        parts,
        {"top_height": height, "top_width": width, "top_depth": depth},
        symmetry=symmetry,
        description=text,
        anchor=(0.0, 0.0, height),
    )


def _round_table() -> CadModel:
    d, h, t = 1.0, TABLE_HEIGHT, 0.03
    parts = [
        M.cylinder(d / 2, t, 48, center=(0.0, 0.0, h - t)),
        M.cylinder(0.06, h - t - 0.04, 24, center=(0.0, 0.0, 0.04)),
        M.lathe([(0, 0), (0.30, 0), (0.30, 0.015), (0.08, 0.05), (0, 0.05)], 36),
    ]
    return make_model(
        "table-round",
        "table",
        parts,
        {"top_height": h, "top_width": d, "top_depth": d},
        symmetry=0,
        description="Round table on a central pedestal and disc foot.",
        anchor=(0.0, 0.0, h),
    )


def _desk() -> CadModel:
    w, d, h, t = 1.40, 0.70, 0.74, 0.03
    parts = [M.box_between((-w / 2, -d / 2, h - t), (w / 2, d / 2, h))]
    for sx in (-1, 1):
        x = sx * (w / 2 - 0.04)
        parts.append(
            M.box_between((x - 0.0125, -d / 2 + 0.02, 0.0), (x + 0.0125, d / 2 - 0.03, h - t))
        )
    parts.append(
        M.box_between(
            (-w / 2 + 0.06, -d / 2 + 0.06, h - t - 0.40), (w / 2 - 0.06, -d / 2 + 0.078, h - t)
        )
    )
    return make_model(
        "desk",
        "table",
        parts,
        {"top_height": h, "top_width": w, "top_depth": d},
        symmetry=1,
        description="Desk on two panel legs with a modesty panel at the back.",
        anchor=(0.0, 0.0, h),
    )


@functools.lru_cache(maxsize=1)
def builtin_library() -> ModelLibrary:
    """The built-in generic models (cached: their samples and trees are built once).

    Examples
    --------
    >>> [m.name for m in builtin_library().for_label("sofa")]
    ['sofa-2seat', 'sofa-3seat']
    """
    return ModelLibrary(
        [
            _chair_4leg(arms=False),
            _chair_4leg(arms=True),
            _chair_office(),
            _chair_shell(),
            _upholstered(
                "armchair",
                "chair",
                0.56,
                1,
                0.16,
                0.85,
                SOFA_SEAT_HEIGHT,
                0.85,
                "Upholstered armchair.",
            ),
            _upholstered(
                "sofa-2seat",
                "sofa",
                1.20,
                2,
                0.18,
                0.90,
                SOFA_SEAT_HEIGHT,
                0.85,
                "Two-seat sofa with arms.",
            ),
            _upholstered(
                "sofa-3seat",
                "sofa",
                1.80,
                3,
                0.18,
                0.92,
                SOFA_SEAT_HEIGHT,
                0.85,
                "Three-seat sofa with arms.",
            ),
            _rect_table(
                "table-rectangular",
                1.60,
                0.90,
                TABLE_HEIGHT,
                2,
                "Rectangular dining table on four legs with an apron.",
            ),
            _rect_table(
                "table-square",
                0.80,
                0.80,
                TABLE_HEIGHT,
                4,
                "Square table on four legs with an apron.",
            ),
            _round_table(),
            _rect_table(
                "table-coffee",
                1.10,
                0.60,
                COFFEE_TABLE_HEIGHT,
                2,
                "Low coffee table on four legs.",
                apron=False,
            ),
            _desk(),
        ]
    )


# ---------------------------------------------------------------------------------------
# A picture of a library

#: Light direction of the shaded full models, and the view of every panel (degrees).
LIGHT = np.array([0.4, 0.6, 0.7]) / np.linalg.norm([0.4, 0.6, 0.7])
VIEW = (22.0, 55.0)


def library_figure(
    library: ModelLibrary,
    names: Iterable[str] | None = None,
    *,
    spacing: float = 0.015,
    seed: int = 0,
    columns: int = 6,
) -> Any:
    """A Matplotlib figure of models: the thin profile's samples above the shaded full model.

    Parameters
    ----------
    library : ModelLibrary
    names : iterable of str, optional
        Models to draw (all by default).
    spacing : float
        Grid (m) of the drawn samples of the thin profile.
    seed : int
        Seed of the sampling.
    columns : int
        Models per row.

    Returns
    -------
    matplotlib.figure.Figure
        Not attached to any window; save it with ``fig.savefig(path)``.
    """
    from matplotlib.figure import Figure  # lazy: matplotlib only to draw the library
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # lazy: as matplotlib

    chosen = list(library) if names is None else list(names)
    models = [library[n] for n in chosen]
    cols = max(1, min(columns, len(models)))
    groups = math.ceil(len(models) / cols) if models else 1
    fig = Figure(figsize=(2.6 * cols, 5.0 * groups), layout="constrained")
    for k, model in enumerate(models):
        g, c = divmod(k, cols)
        size = float(max(model.dims["width"], model.dims["depth"], model.dims["height"]))
        lo, hi = model.full.bounds
        mid = (lo + hi) / 2
        for row in (0, 1):
            ax = fig.add_subplot(2 * groups, cols, (2 * g + row) * cols + c + 1, projection="3d")
            if row == 0:
                pts = model.points(spacing, seed)
                ax.scatter(
                    pts[:, 0],
                    pts[:, 1],
                    pts[:, 2],
                    s=0.3,
                    c=pts[:, 2],
                    cmap="viridis",
                    linewidths=0,
                )
                ax.set_title(f"{model.name}\nthin ({len(pts):,} pts)", fontsize=8)
            else:
                tri = model.full.vertices[model.full.triangles]
                normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
                normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
                shade = 0.35 + 0.65 * np.clip(normal @ LIGHT, 0.0, 1.0)
                base = np.asarray(model.color, dtype=np.float64) / 255.0
                ax.add_collection3d(
                    Poly3DCollection(
                        tri,
                        facecolors=np.clip(shade[:, None] * base, 0, 1),
                        linewidths=0,
                        zsort="min",
                    )
                )
                ax.set_title(f"full ({len(model.full.triangles):,} triangles)", fontsize=8)
            ax.set_xlim(mid[0] - size / 2, mid[0] + size / 2)
            ax.set_ylim(mid[1] - size / 2, mid[1] + size / 2)
            ax.set_zlim(0.0, size)
            ax.set_box_aspect((1, 1, 1))
            ax.view_init(*VIEW)
            ax.set_axis_off()
    return fig
