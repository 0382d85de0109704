"""Closed triangle meshes of simple solids, the bricks furniture and CAD models are built from.

Every builder returns a :class:`Mesh` that encloses a volume: it is watertight,
its triangles are wound consistently and its normals point outwards (counter-
clockwise seen from outside). Virtual sensors ray-cast these meshes, so each
part of a piece of furniture must be a real solid with a thickness, not a sheet.
The generic CAD models (:mod:`ontodetect.cad`) and the simulator
(:mod:`ontodetect.synth`) share them. Boxes, extrusions, solids of revolution and
tori come from ``trimesh.creation`` (imported when a mesh is first built); the
shapes it lacks (any eight corners, superellipsoids, swept tubes, thick sheets)
are built here.

Builders, all in metres:

- :func:`box`, :func:`box_between`, :func:`hexahedron` (any eight corners, e.g. a
  tapered leg), :func:`tapered_box`;
- :func:`prism` (a convex polygon extruded), :func:`rounded_box` (a box with
  rounded edges along one axis);
- :func:`lathe` (a profile revolved about z: cylinders, cones, pots, bins,
  tori), :func:`cylinder`, :func:`frustum`, :func:`cylinder_between`, :func:`torus`;
- :func:`superellipsoid` and :func:`cushion` (rounded boxes for upholstery),
  :func:`ellipsoid`, :func:`blob` (a lumpy sphere for foliage);
- :func:`tube` (a circle swept along a path: bent tubes, frames, rings) with
  :func:`fillet_path` to round the corners of a polyline;
- :func:`thick_surface` (a curved sheet given a thickness: plastic shells).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError

__all__ = [
    "Mesh",
    "blob",
    "box",
    "box_between",
    "concatenate",
    "cushion",
    "cylinder",
    "cylinder_between",
    "ellipsoid",
    "fillet_path",
    "frustum",
    "hexahedron",
    "lathe",
    "prism",
    "rounded_box",
    "rounded_rectangle",
    "superellipsoid",
    "tapered_box",
    "thick_surface",
    "torus",
    "tube",
]

#: Segments around a full circle for round parts (legs, columns, tubes).
DEFAULT_SEGMENTS = 20
#: Radii below this are taken as lying on the axis of a lathe profile.
_AXIS_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh: ``vertices`` (v, 3) float64 and ``triangles`` (t, 3) int32.

    Meshes are values: every method returns a new mesh.

    Examples
    --------
    >>> m = box((1.0, 2.0, 0.5)).translated((0, 0, 0.25))
    >>> m.bounds.tolist()
    [[-0.5, -1.0, 0.0], [0.5, 1.0, 0.5]]
    >>> round(m.volume, 6)
    1.0
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int32]

    @property
    def bounds(self) -> NDArray[np.float64]:
        """(2, 3) float: lowest and highest corner of the axis-aligned bounding box."""
        return np.stack([self.vertices.min(axis=0), self.vertices.max(axis=0)])

    @property
    def volume(self) -> float:
        """Signed enclosed volume: positive when the normals point outwards."""
        v = self.vertices[self.triangles]
        return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)

    def transformed(self, matrix: ArrayLike) -> Mesh:
        """Apply a (4, 4) affine transform; a mirroring one keeps the normals outwards."""
        T = np.asarray(matrix, dtype=np.float64)
        vertices = self.vertices @ T[:3, :3].T + T[:3, 3]
        triangles = self.triangles
        if np.linalg.det(T[:3, :3]) < 0:
            triangles = triangles[:, ::-1].copy()
        return Mesh(vertices, triangles)

    def translated(self, offset: ArrayLike) -> Mesh:
        """Move by a (3,) offset."""
        return Mesh(self.vertices + np.asarray(offset, dtype=np.float64), self.triangles)

    def scaled(self, factors: ArrayLike) -> Mesh:
        """Scale about the origin by (3,) factors; negative factors mirror."""
        return self.transformed(np.diag([*np.broadcast_to(factors, 3), 1.0]))

    def rotated(self, axis: str, angle: float, about: ArrayLike = (0.0, 0.0, 0.0)) -> Mesh:
        """Rotate by ``angle`` radians about the ``"x"``, ``"y"`` or ``"z"`` axis through ``about``.

        The rotation is right-handed: about x a positive angle takes +y towards +z.
        """
        T = np.eye(4)
        T[:3, :3] = _axis_rotation(axis, angle)
        p = np.asarray(about, dtype=np.float64)
        T[:3, 3] = p - T[:3, :3] @ p
        return self.transformed(T)


def _axis_rotation(axis: str, angle: float) -> NDArray[np.float64]:
    c, s = np.cos(angle), np.sin(angle)
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=np.float64)
    if axis == "y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=np.float64)
    if axis == "z":
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=np.float64)
    raise InvalidParameterError("axis", "one of 'x', 'y', 'z'", axis)


def concatenate(meshes: Sequence[Mesh]) -> Mesh:
    """One mesh holding all the given meshes (their vertices are not merged)."""
    if not meshes:
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int32))
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    return Mesh(
        np.concatenate([m.vertices for m in meshes]),
        np.concatenate([m.triangles + o for m, o in zip(meshes, offsets)]).astype(np.int32),
    )


def _outward(vertices: NDArray[np.float64], triangles: NDArray[np.int64]) -> Mesh:
    """A mesh whose (consistently wound) triangles are flipped if they face inwards."""
    mesh = Mesh(np.asarray(vertices, dtype=np.float64), np.asarray(triangles, dtype=np.int32))
    if mesh.volume < 0:
        mesh = Mesh(mesh.vertices, mesh.triangles[:, ::-1].copy())
    return mesh


def _positive(name: str, value: float | ArrayLike) -> NDArray[np.float64]:
    a = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise InvalidParameterError(name, "finite and greater than 0", value)
    return a


# Corner i of a hexahedron is (x_i, y_i, z_i) with x_i = i & 1, y_i = i >> 1 & 1, z_i = i >> 2.
# fmt: off
_HEX_TRIANGLES = np.array(
    [
        [0, 2, 3], [0, 3, 1],  # z-
        [4, 5, 7], [4, 7, 6],  # z+
        [0, 1, 5], [0, 5, 4],  # y-
        [2, 6, 7], [2, 7, 3],  # y+
        [0, 4, 6], [0, 6, 2],  # x-
        [1, 3, 7], [1, 7, 5],  # x+
    ],
    dtype=np.int32,
)
# fmt: on
_UNIT_CORNERS = np.array([[i & 1, (i >> 1) & 1, i >> 2] for i in range(8)], dtype=np.float64)


def hexahedron(corners: ArrayLike) -> Mesh:
    """A solid with six (possibly non-planar) quadrilateral faces.

    Parameters
    ----------
    corners : (8, 3) float
        Corner ``i`` is the one at (x, y, z) = (``i & 1``, ``i >> 1 & 1``, ``i >> 2``)
        of a unit cube: 0 = low x, low y, low z; 7 = high x, high y, high z.
    """
    c = np.asarray(corners, dtype=np.float64)
    if c.shape != (8, 3):
        raise InvalidParameterError("corners", "an array of shape (8, 3)", c.shape)
    return _outward(c, _HEX_TRIANGLES)


def _from_trimesh(mesh: Any) -> Mesh:
    """A :class:`Mesh` from a ``trimesh.Trimesh``, its normals turned outwards."""
    return _outward(np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces))


def box(size: ArrayLike, center: ArrayLike = (0.0, 0.0, 0.0)) -> Mesh:
    """An axis-aligned box of (3,) ``size`` centred on ``center`` (``trimesh.creation.box``).

    Examples
    --------
    >>> b = box((2.0, 1.0, 1.0))
    >>> len(b.vertices), len(b.triangles), round(b.volume, 6)
    (8, 12, 2.0)
    """
    from trimesh.creation import box as trimesh_box  # lazy: trimesh only to build meshes

    s = _positive("size", size)
    return _from_trimesh(trimesh_box(extents=s)).translated(center)


def box_between(low: ArrayLike, high: ArrayLike) -> Mesh:
    """An axis-aligned box from its (3,) lowest to its (3,) highest corner."""
    lo = np.asarray(low, dtype=np.float64)
    hi = np.asarray(high, dtype=np.float64)
    return box(_positive("high - low", hi - lo), (lo + hi) / 2)


def tapered_box(
    bottom: ArrayLike, top: ArrayLike, height: float, shift: ArrayLike = (0.0, 0.0)
) -> Mesh:
    """A box whose (2,) ``bottom`` footprint (at z = 0) narrows or widens to a (2,) ``top``.

    The top face is centred above ``shift`` (a (2,) xy offset), which makes
    raked legs.
    """
    b = _positive("bottom", bottom)
    t = _positive("top", top)
    h = float(_positive("height", height))
    c = _UNIT_CORNERS - [0.5, 0.5, 0.0]
    xy = np.where(c[:, 2:] > 0, c[:, :2] * t + np.asarray(shift, dtype=np.float64), c[:, :2] * b)
    return hexahedron(np.column_stack([xy, c[:, 2] * h]))


def rounded_rectangle(size: ArrayLike, radius: float, segments: int = 4) -> NDArray[np.float64]:
    """(k, 2) float: counter-clockwise outline of a rectangle with rounded corners.

    ``segments`` is the number of straight pieces per quarter circle; a zero
    ``radius`` gives the plain rectangle.
    """
    w, d = _positive("size", size)
    r = float(np.clip(radius, 0.0, 0.5 * min(w, d) - 1e-6))
    if r <= 0:
        return np.array([[-w / 2, -d / 2], [w / 2, -d / 2], [w / 2, d / 2], [-w / 2, d / 2]])
    centers = [
        (w / 2 - r, -d / 2 + r),
        (w / 2 - r, d / 2 - r),
        (-w / 2 + r, d / 2 - r),
        (-w / 2 + r, -d / 2 + r),
    ]
    points = []
    for k, (cx, cy) in enumerate(centers):
        a = np.linspace(-np.pi / 2 + k * np.pi / 2, k * np.pi / 2, segments + 1)
        points.append(np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)]))
    return np.concatenate(points)


def prism(polygon: ArrayLike, z0: float, z1: float) -> Mesh:
    """A convex (k, 2) ``polygon`` extruded from height ``z0`` to ``z1``.

    Examples
    --------
    >>> tri = prism([[0, 0], [1, 0], [0, 1]], 0.0, 2.0)
    >>> round(tri.volume, 6)
    1.0
    """
    from trimesh.creation import extrude_triangulation  # lazy: trimesh only to build meshes

    p = np.asarray(polygon, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise InvalidParameterError("polygon", "an array of shape (k, 2) with k >= 3", p.shape)
    height = float(_positive("z1 - z0", z1 - z0))
    # A convex polygon is a fan from its first corner; trimesh wants it counter-clockwise.
    (ax, ay), (bx, by) = p[1] - p[0], p[2] - p[0]
    if ax * by - ay * bx < 0:
        p = p[::-1]
    fan = np.arange(1, len(p) - 1)
    faces = np.column_stack([np.zeros(len(fan), int), fan, fan + 1])
    return _from_trimesh(extrude_triangulation(p, faces, height)).translated((0.0, 0.0, z0))


def rounded_box(
    size: ArrayLike,
    radius: float,
    axis: str = "z",
    center: ArrayLike = (0.0, 0.0, 0.0),
    segments: int = 4,
) -> Mesh:
    """A box of (3,) ``size`` whose four edges parallel to ``axis`` are rounded by ``radius``."""
    s = _positive("size", size)
    order = {"x": (1, 2, 0), "y": (2, 0, 1), "z": (0, 1, 2)}
    if axis not in order:
        raise InvalidParameterError("axis", "one of 'x', 'y', 'z'", axis)
    a, b, c = order[axis]
    outline = rounded_rectangle((s[a], s[b]), radius, segments)
    local = prism(outline, -s[c] / 2, s[c] / 2)
    # Map the prism's (u, v, w) axes back onto x, y, z; the permutation is cyclic, so no mirror.
    vertices = np.empty_like(local.vertices)
    vertices[:, [a, b, c]] = local.vertices
    return Mesh(vertices + np.asarray(center, dtype=np.float64), local.triangles)


def _ring_mesh(
    rings: NDArray[np.float64],
    start: NDArray[np.float64] | None = None,
    end: NDArray[np.float64] | None = None,
    closed: bool = False,
) -> Mesh:
    """Solid from (k, s, 3) rings of s points, capped by a point at each end or closed in a loop."""
    k, s = rings.shape[:2]
    vertices = [rings.reshape(-1, 3)]
    tris = []
    j = np.arange(s)
    jn = (j + 1) % s
    pairs = [(i, i + 1) for i in range(k - 1)] + ([(k - 1, 0)] if closed else [])
    for a, b in pairs:
        tris.append(np.column_stack([a * s + j, b * s + j, b * s + jn]))
        tris.append(np.column_stack([a * s + j, b * s + jn, a * s + jn]))
    n = k * s
    if start is not None:
        vertices.append(np.asarray(start, dtype=np.float64)[None])
        tris.append(np.column_stack([np.full(s, n), j, jn]))
        n += 1
    if end is not None:
        vertices.append(np.asarray(end, dtype=np.float64)[None])
        tris.append(np.column_stack([np.full(s, n), (k - 1) * s + jn, (k - 1) * s + j]))
    return _outward(np.concatenate(vertices), np.concatenate(tris))


def lathe(profile: ArrayLike, segments: int = DEFAULT_SEGMENTS, closed: bool = False) -> Mesh:
    """A solid of revolution: a (k, 2) profile of (radius, z) points turned about the z axis.

    An open profile (``closed=False``) must start and end on the axis (radius 0),
    e.g. ``[(0, 0), (r, 0), (r, h), (0, h)]`` is a cylinder. A closed profile
    that stays off the axis makes a ring (a torus when it is a circle).

    Examples
    --------
    >>> cyl = lathe([(0, 0), (1, 0), (1, 1), (0, 1)], segments=64)
    >>> abs(cyl.volume - np.pi) < 0.01
    True
    """
    p = np.asarray(profile, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise InvalidParameterError("profile", "an array of shape (k, 2) with k >= 3", p.shape)
    if np.any(p[:, 0] < 0):
        raise InvalidParameterError("profile", "radii >= 0", p[:, 0].min())
    on_axis = p[:, 0] <= _AXIS_TOLERANCE
    if closed and on_axis.any():
        raise InvalidParameterError("profile", "off the axis when closed", "a point at radius 0")
    if not closed and (not (on_axis[0] and on_axis[-1]) or on_axis[1:-1].any()):
        raise InvalidParameterError(
            "profile", "on the axis (radius 0) at both ends and only there", p[:, 0].tolist()
        )
    from trimesh.creation import revolve  # lazy: trimesh only to build meshes

    line = np.vstack([p, p[:1]]) if closed else p
    return _from_trimesh(revolve(line, sections=segments))


def cylinder(
    radius: float,
    height: float,
    segments: int = DEFAULT_SEGMENTS,
    center: ArrayLike = (0.0, 0.0, 0.0),
) -> Mesh:
    """An upright cylinder standing on ``center`` (its bottom face's centre)."""
    return frustum(radius, radius, height, segments, center)


def frustum(
    radius_bottom: float,
    radius_top: float,
    height: float,
    segments: int = DEFAULT_SEGMENTS,
    center: ArrayLike = (0.0, 0.0, 0.0),
) -> Mesh:
    """An upright truncated cone standing on ``center`` (its bottom face's centre)."""
    r0, r1, h = (float(v) for v in _positive("radius/height", [radius_bottom, radius_top, height]))
    m = lathe([(0, 0), (r0, 0), (r1, h), (0, h)], segments)
    return m.translated(center)


def _frame_for(direction: NDArray[np.float64]) -> NDArray[np.float64]:
    """(3, 3) rotation whose third column is the unit ``direction``."""
    z = direction / np.linalg.norm(direction)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def cylinder_between(
    start: ArrayLike,
    end: ArrayLike,
    radius: float,
    segments: int = DEFAULT_SEGMENTS,
    radius_end: float | None = None,
) -> Mesh:
    """A cylinder (or a frustum, given ``radius_end``) whose axis runs from ``start`` to ``end``."""
    p0 = np.asarray(start, dtype=np.float64)
    axis = np.asarray(end, dtype=np.float64) - p0
    length = float(np.linalg.norm(axis))
    m = frustum(radius, radius if radius_end is None else radius_end, length, segments)
    T = np.eye(4)
    T[:3, :3] = _frame_for(axis)
    T[:3, 3] = p0
    return m.transformed(T)


def torus(
    major_radius: float, minor_radius: float, segments: int = 32, minor_segments: int = 10
) -> Mesh:
    """A ring about the z axis in the plane z = 0 (e.g. the footrest of a bar stool)."""
    from trimesh.creation import torus as trimesh_torus  # lazy: trimesh only to build meshes

    R, r = (float(v) for v in _positive("radius", [major_radius, minor_radius]))
    if r >= R:
        raise InvalidParameterError("minor_radius", f"smaller than major_radius ({R})", r)
    return _from_trimesh(
        trimesh_torus(R, r, major_sections=segments, minor_sections=minor_segments)
    )


def superellipsoid(
    size: ArrayLike,
    exponent: float = 0.25,
    plan_exponent: float | None = None,
    rings: int = 12,
    segments: int = 24,
    center: ArrayLike = (0.0, 0.0, 0.0),
) -> Mesh:
    """A superellipsoid filling a box of (3,) ``size``: a box with rounded edges, or a pebble.

    ``exponent`` shapes the vertical profile and ``plan_exponent`` (default
    ``exponent``) the outline seen from above: near 0 gives sharp edges, 1 round
    ones (``plan_exponent=1`` makes a round cushion). The top and bottom are
    single points at exactly ``center ± size/2`` in z.
    """
    a, b, c = _positive("size", size) / 2
    e1 = float(_positive("exponent", exponent))
    e2 = e1 if plan_exponent is None else float(_positive("plan_exponent", plan_exponent))
    eta = np.linspace(-np.pi / 2, np.pi / 2, rings + 1)[1:-1]
    omega = np.linspace(-np.pi, np.pi, segments, endpoint=False)

    def spow(x: NDArray[np.float64], e: float) -> NDArray[np.float64]:
        return np.sign(x) * np.abs(x) ** e

    ce, se = spow(np.cos(eta), e1)[:, None], spow(np.sin(eta), e1)[:, None]
    co, so = spow(np.cos(omega), e2)[None, :], spow(np.sin(omega), e2)[None, :]
    rings_xyz = np.stack([a * ce * co, b * ce * so, c * se * np.ones_like(co)], axis=-1)
    m = _ring_mesh(rings_xyz, start=[0.0, 0.0, -c], end=[0.0, 0.0, c])
    return m.translated(center)


def cushion(size: ArrayLike, softness: float = 0.2, center: ArrayLike = (0.0, 0.0, 0.0)) -> Mesh:
    """An upholstered cushion filling a box of (3,) ``size``: flat faces, rounded edges.

    ``softness`` in (0, 1]: 0.1 is a firm mattress, 0.3 a plump pillow.
    """
    return superellipsoid(size, softness, softness, rings=12, segments=24, center=center)


def ellipsoid(
    radii: ArrayLike, center: ArrayLike = (0.0, 0.0, 0.0), rings: int = 10, segments: int = 20
) -> Mesh:
    """An ellipsoid with (3,) semi-axes ``radii``."""
    return superellipsoid(2 * _positive("radii", radii), 1.0, 1.0, rings, segments, center)


def blob(
    radii: ArrayLike,
    rng: int | np.random.Generator | None = None,
    lumpiness: float = 0.25,
    lumps: int = 7,
    rings: int = 12,
    segments: int = 20,
    center: ArrayLike = (0.0, 0.0, 0.0),
) -> Mesh:
    """A lumpy ellipsoid (foliage, a heap): (3,) ``radii`` with random bumps.

    Bumps only push the surface outwards along rays from the centre, so the
    surface never folds over itself.
    """
    gen = np.random.default_rng(rng)
    r = _positive("radii", radii)
    theta = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    u = np.stack(
        [
            np.sin(theta)[:, None] * np.cos(phi),
            np.sin(theta)[:, None] * np.sin(phi),
            np.cos(theta)[:, None] * np.ones_like(phi),
        ],
        axis=-1,
    )
    poles = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    dirs = gen.normal(size=(lumps, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    heights = gen.uniform(0.3, 1.0, lumps) * lumpiness
    sharpness = 4.0  # bump width about 30 degrees

    def radius(v: NDArray[np.float64]) -> NDArray[np.float64]:
        return 1.0 + np.exp(sharpness * (v @ dirs.T - 1.0)) @ heights

    rings_xyz = u * radius(u)[..., None] * r / (1 + lumpiness)
    p = poles * radius(poles)[:, None] * r / (1 + lumpiness)
    return _ring_mesh(rings_xyz, start=p[0], end=p[1]).translated(center)


def fillet_path(
    corners: ArrayLike, radius: float, samples: int = 6, closed: bool = False
) -> NDArray[np.float64]:
    """(m, 3) float: a polyline through (k, 3) ``corners`` with each corner rounded off.

    Each interior corner (every corner when ``closed``) is replaced by a curve
    that leaves the straight segments at most ``radius`` from the corner, so
    a tube swept along the result bends smoothly.
    """
    c = np.asarray(corners, dtype=np.float64)
    k = len(c)
    out = []
    idx = range(k) if closed else range(1, k - 1)
    if not closed:
        out.append(c[0])
    for i in idx:
        a, b, n = c[i - 1], c[i], c[(i + 1) % k]
        da, dn = a - b, n - b
        la, ln = np.linalg.norm(da), np.linalg.norm(dn)
        d = min(radius, 0.45 * la, 0.45 * ln)
        p1, p2 = b + da / la * d, b + dn / ln * d
        t = np.linspace(0.0, 1.0, samples)[:, None]
        out.extend((1 - t) ** 2 * p1 + 2 * (1 - t) * t * b + t**2 * p2)
    if not closed:
        out.append(c[-1])
    return np.asarray(out)


def tube(path: ArrayLike, radius: float, segments: int = 12, closed: bool = False) -> Mesh:
    """A round tube of ``radius`` swept along a (k, 3) ``path``; open ends are capped flat.

    Round the path's corners with :func:`fillet_path` first: the cross-section
    is perpendicular to the local direction, so sharp corners pinch the tube.
    """
    p = np.asarray(path, dtype=np.float64)
    r = float(_positive("radius", radius))
    # Drop repeated points: they have no direction.
    keep = np.ones(len(p), bool)
    keep[1:] = np.linalg.norm(np.diff(p, axis=0), axis=1) > 1e-9
    p = p[keep]
    if closed and np.linalg.norm(p[0] - p[-1]) < 1e-9:
        p = p[:-1]
    if len(p) < 2:
        raise InvalidParameterError("path", "at least two distinct points", len(p))
    seg = np.diff(np.concatenate([p, p[:1]]) if closed else p, axis=0)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    if closed:
        tangents = seg + np.roll(seg, 1, axis=0)
    else:
        tangents = np.concatenate([seg[:1], seg[:-1] + seg[1:], seg[-1:]])
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    normal = _frame_for(tangents[0])[:, 0]
    a = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    rings = np.empty((len(p), segments, 3))
    for i, t in enumerate(tangents):
        # Parallel transport keeps the rings from twisting along the path.
        normal = normal - normal @ t * t
        normal /= np.linalg.norm(normal)
        binormal = np.cross(t, normal)
        rings[i] = p[i] + r * (np.cos(a)[:, None] * normal + np.sin(a)[:, None] * binormal)
    if closed:
        return _ring_mesh(rings, closed=True)
    return _ring_mesh(rings, start=p[0], end=p[-1])


def thick_surface(grid: ArrayLike, thickness: float) -> Mesh:
    """A curved sheet given a thickness: a closed solid around a (nu, nv, 3) grid of points.

    The grid is the sheet's mid-surface; each side is offset by half the
    thickness along the surface normal.
    """
    g = np.asarray(grid, dtype=np.float64)
    if g.ndim != 3 or g.shape[2] != 3 or min(g.shape[:2]) < 2:
        raise InvalidParameterError("grid", "an array of shape (nu, nv, 3), nu, nv >= 2", g.shape)
    half = float(_positive("thickness", thickness)) / 2
    du = np.gradient(g, axis=0)
    dv = np.gradient(g, axis=1)
    normal = np.cross(du, dv)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    nu, nv = g.shape[:2]
    top = (g + half * normal).reshape(-1, 3)
    bottom = (g - half * normal).reshape(-1, 3)
    n = nu * nv

    def vid(i: NDArray[np.int64], j: NDArray[np.int64]) -> NDArray[np.int64]:
        return i * nv + j

    i, j = np.meshgrid(np.arange(nu - 1), np.arange(nv - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
    tris = [
        np.column_stack([a, b, c]),
        np.column_stack([a, c, d]),
        np.column_stack([a, c, b]) + n,
        np.column_stack([a, d, c]) + n,
    ]
    # The boundary loop, counter-clockwise in (u, v): the side walls face outwards along it.
    loop = np.concatenate(
        [
            vid(np.arange(nu), np.zeros(nu, int)),
            vid(np.full(nv - 1, nu - 1), np.arange(1, nv)),
            vid(np.arange(nu - 2, -1, -1), np.full(nu - 1, nv - 1)),
            vid(np.zeros(nv - 2, int), np.arange(nv - 2, 0, -1)),
        ]
    )
    p, q = loop, np.roll(loop, -1)
    tris += [np.column_stack([p, p + n, q + n]), np.column_stack([p, q + n, q])]
    return _outward(np.concatenate([top, bottom]), np.concatenate(tris))
