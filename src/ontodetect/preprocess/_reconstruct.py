"""Surface reconstruction of a scan (thesis Algorithm 1 step 2): a triangle mesh of the
voxel cloud, by marching cubes on a truncated signed-distance grid, or by Open3D's
screened Poisson reconstruction.

The thesis meshed its scans with LVR's marching cubes; this is the same method. The signed
distance of a grid node is the distance to the tangent planes of the nearest voxel centres
(Hoppe et al. 1992), their normals turned towards a viewpoint; it is defined only close to
the points (a sparse grid: nodes within a few cells of a point, kept as sorted integer
keys), so that memory follows the scanned surface, not the scan's bounding box. The
marching cubes are scikit-image's (Lewiner et al. 2003: ambiguous faces and cubes resolved
from the distances, with no cracks), run block by block over the occupied part of the grid
and welded where the blocks meet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from itertools import pairwise
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._rules import Interval, OneOf, check_param
from ..errors import InvalidParameterError
from ..geometry import as_points
from ._surface import estimate_normals

__all__ = [
    "MESH_METHODS",
    "SurfaceMesh",
    "reconstruct_surface",
    "scene_surface",
]

#: Methods of :func:`reconstruct_surface`.
MESH_METHODS = ("marching_cubes", "poisson")
#: A grid node gets a signed distance from the points within this many cells of it.
SUPPORT_CELLS = 2.0
#: ... and only where its nearest point's tangent plane passes within this many cells of
#: it sideways: an open surface (a table top) ends about a cell past its last point
#: instead of running on along its plane (Hoppe et al. 1992, "projection onto the plane").
TANGENTIAL_CELLS = 1.5
#: Points averaged into a node's signed distance and into a vertex's colour.
SDF_NEIGHBORS = 8
#: Neighbours of the normal estimate of each point, when the points have no normals.
NORMAL_NEIGHBORS = 12
#: Height (m) above the scene's lowest point of the default viewpoint of
#: :func:`scene_surface`: a hand-held or robot sensor's height in a room.
SENSOR_HEIGHT = 1.5
#: Most occupied cells meshed at the requested cell size; beyond it the cell grows (the
#: number of occupied cells of a surface goes with 1 / cell²) until the scan fits.
MAX_CELLS = 2_000_000
#: Cells whose nodes are generated at a time (bounds the temporary arrays).
NODE_BLOCK = 100_000
#: Nodes whose signed distance is computed at a time.
QUERY_BLOCK = 200_000
#: The grid's first node lies this many cells below the lowest point.
GRID_MARGIN = 2.5
#: Marching cubes runs on dense blocks of this many cells a side (one 65³ float32 array
#: at a time: memory follows the surface, not the scan's bounding box).
MC_BLOCK = 64
#: Signed distances (in cells) nearer zero than this are moved out to it, their sign kept:
#: no vertex falls on a grid node (within float32 precision of the block coordinates).
MIN_DISTANCE = 1e-4
#: Bits per axis of a packed grid key (a cube of 2^21 cells a side: 20 km at 1 cm).
_KEY_BITS = 21
#: Poisson: octree depth cap (a 2^10 grid a side), and the share of vertices with the
#: least supporting points that is trimmed (Poisson closes every surface; where no point
#: was, the density of its vertices is low).
POISSON_MAX_DEPTH = 10
POISSON_TRIM = 0.05


@dataclass(frozen=True, eq=False)
class SurfaceMesh:
    """A triangle mesh of a scanned surface.

    Attributes
    ----------
    vertices : (v, 3) float
    triangles : (t, 3) int32
        Wound counter-clockwise seen from the side the normals of the points face.
    colors : (v, 3) uint8 or None
        Mean colour of the points around each vertex, when the points have colours.
    cell : float
        Grid cell (m) the mesh was built at (larger than asked when the scan was capped).
    info : dict
        Method, grid nodes, whether the cell was raised.
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int32]
    colors: NDArray[np.uint8] | None = None
    cell: float = 0.0
    info: dict[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.triangles)

    @property
    def area(self) -> float:
        """Total area of the triangles (m²)."""
        v = self.vertices[self.triangles]
        return float(
            0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum()
        )

    @property
    def edges(self) -> NDArray[np.int64]:
        """(e, 2) int: every edge of a triangle once, smaller vertex first, sorted."""
        t = self.triangles.astype(np.int64)
        e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
        e = np.sort(e, axis=1)
        return np.unique(e, axis=0) if len(e) else np.zeros((0, 2), np.int64)

    def transformed(self, matrix: ArrayLike) -> SurfaceMesh:
        """The mesh moved by a (4, 4) affine transform; a mirroring one keeps the winding."""
        T = np.asarray(matrix, dtype=np.float64)
        vertices = self.vertices @ T[:3, :3].T + T[:3, 3]
        flip = np.linalg.det(T[:3, :3]) < 0
        triangles = self.triangles[:, ::-1].copy() if flip else self.triangles
        return SurfaceMesh(vertices, triangles, self.colors, self.cell, dict(self.info))


# -- the sparse grid ------------------------------------------------------------------------
#: The eight corners of a cube, corner c at (c & 1, c >> 1 & 1, c >> 2 & 1).
_CORNERS = np.array([[c & 1, c >> 1 & 1, c >> 2 & 1] for c in range(8)], dtype=np.int64)


def _pack(ijk: NDArray[np.int64]) -> NDArray[np.int64]:
    return (ijk[:, 0] << (2 * _KEY_BITS)) | (ijk[:, 1] << _KEY_BITS) | ijk[:, 2]


def _unpack(key: NDArray[np.int64]) -> NDArray[np.int64]:
    mask = (1 << _KEY_BITS) - 1
    return np.stack([key >> (2 * _KEY_BITS), (key >> _KEY_BITS) & mask, key & mask], axis=1)


def _grid_nodes(cells: NDArray[np.int64]) -> NDArray[np.int64]:
    """Sorted keys of the corners of the occupied ``cells`` and of the cells around them."""
    offsets = np.stack(np.meshgrid(*[np.arange(-1, 3)] * 3, indexing="ij"), -1).reshape(-1, 3)
    offset_keys = _pack(offsets + 1) - _pack(np.ones((1, 3), np.int64))
    cell_keys = _pack(cells)
    parts = [
        np.unique((cell_keys[s : s + NODE_BLOCK, None] + offset_keys[None, :]).ravel())
        for s in range(0, len(cell_keys), NODE_BLOCK)
    ]
    return np.unique(np.concatenate(parts)) if parts else np.zeros(0, np.int64)


def _signed_distance(
    nodes: NDArray[np.float64],
    tree: Any,
    points: NDArray[np.float64],
    normals: NDArray[np.float64],
    cell: float,
) -> NDArray[np.float64]:
    """Signed distance of each node to the tangent planes of its nearest points (Gaussian
    weights of width one cell); NaN where no point is near or where the node lies past the
    end of the surface."""
    support = SUPPORT_CELLS * cell
    k = min(SDF_NEIGHBORS, len(points))
    out = np.full(len(nodes), np.nan)
    for s in range(0, len(nodes), QUERY_BLOCK):
        x = nodes[s : s + QUERY_BLOCK]
        dist, idx = tree.query(x, k=k, distance_upper_bound=support, workers=-1)
        dist, idx = dist.reshape(len(x), k), idx.reshape(len(x), k)
        found = idx < len(points)
        safe = np.where(found, idx, 0)
        diff = x[:, None, :] - points[safe]
        plane = np.einsum("nki,nki->nk", diff, normals[safe])
        w = np.where(found, np.exp(-0.5 * (dist / cell) ** 2), 0.0)
        total = w.sum(axis=1)
        sdf = np.divide(
            (w * plane).sum(axis=1), total, out=np.full(len(x), np.nan), where=total > 0
        )
        # Sideways distance to the nearest point's plane: past the rim of an open surface.
        near = diff[:, 0, :]
        side = np.linalg.norm(near - plane[:, :1] * normals[safe[:, 0]], axis=1)
        sdf[~found[:, 0] | (side > TANGENTIAL_CELLS * cell)] = np.nan
        out[s : s + QUERY_BLOCK] = sdf
    return out


def _marching_cubes(
    keys: NDArray[np.int64], values: NDArray[np.float64], origin: NDArray[np.float64], cell: float
) -> tuple[NDArray[np.float64], NDArray[np.int32]]:
    """Marching cubes (scikit-image's, Lewiner et al. 2003) on the sparse grid of sorted
    ``keys`` with ``values`` (NaN: unknown); a cube is meshed only when its eight corners
    are known.

    The grid is cut into dense blocks of ``MC_BLOCK`` cells a side whose nodes overlap by
    one layer, so that each cube lies in one block and the blocks' meshes meet on the faces
    they share. scikit-image gives a block's vertices in float32 block coordinates: they
    only name the grid edge each vertex lies on (or, for the few vertices some cases add
    inside a cube, that cube). The vertices of every block are then merged by that edge
    and placed in float64 from the signed distances at its two ends, so a vertex on a face
    two blocks share comes out once, at the same place, whichever block found it.
    """
    from skimage.measure import marching_cubes  # heavy: imported when used (start-up)

    known = ~np.isnan(values)
    keys, values = keys[known], values[known]
    if len(keys) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int32)
    # In cells, and kept off zero (sign kept, 0 counted outside): no vertex falls on a grid
    # node, so each lies strictly inside its edge even in float32, and its edge is known.
    dist = values / cell
    near = np.flatnonzero(np.abs(dist) < MIN_DISTANCE)
    dist[near] = np.where(dist[near] < 0, -MIN_DISTANCE, MIN_DISTANCE)
    dist32 = dist.astype(np.float32)
    del values
    size = MC_BLOCK
    node_block, node_local, node_index = _blocks(keys, size)
    starts = np.flatnonzero(np.r_[True, node_block[1:] != node_block[:-1], True])

    lower: list[NDArray[np.int64]] = []  # per vertex: key of its edge's lower node
    kind: list[NDArray[np.int64]] = []  # per vertex: its edge's axis, or 3
    centre_at: list[NDArray[np.float64]] = []  # per vertex: grid coordinates (inside a cube)
    faces: list[NDArray[np.int64]] = []
    count = 0
    for s, e in pairwise(starts):
        loc = node_local[s:e]
        lo = loc.min(axis=0)
        shape = loc.max(axis=0) - lo + 1
        if (shape < 2).any():
            continue
        idx = tuple((loc - lo).T)
        grid = np.zeros(shape, np.float32)
        grid[idx] = dist32[node_index[s:e]]
        have = np.zeros(shape, bool)
        have[idx] = True
        out = grid > 0
        # Cubes (by lower corner) whose eight corners are known and not all on one side.
        cubes = _all_corners(have) & ~_all_corners(out) & ~_all_corners(~out)
        if not cubes.any():
            continue
        mask = np.zeros(shape, bool)
        mask[1:, 1:, 1:] = cubes  # scikit-image masks a cube by its upper corner
        verts, tris, _, _ = marching_cubes(grid, 0.0, mask=mask)
        base = _unpack(node_block[s : s + 1])[0] * size + lo
        node = np.floor(verts)
        off = verts != node
        on_edge = off.sum(axis=1) == 1
        lower.append(_pack(node.astype(np.int64) + base))
        kind.append(np.where(on_edge, np.argmax(off, axis=1), 3))  # 3: inside a cube
        centre_at.append(np.where(on_edge[:, None], 0.0, base + verts.astype(np.float64)))
        faces.append(tris.astype(np.int64) + count)
        count += len(verts)
    del node_block, node_local, node_index, dist32
    if not faces:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int32)
    # Weld: one vertex per grid edge, named by the rank of its lower node and its axis; a
    # cube's centre vertex is its block's own (named after all edges, in block order).
    lower_key, axis = np.concatenate(lower), np.concatenate(kind)
    del lower, kind
    edge = axis < 3
    name = np.arange(len(axis)) + 3 * len(keys)
    name[edge] = _find(keys, lower_key[edge]) * 3 + axis[edge]
    uniq, first, inverse = np.unique(name, return_index=True, return_inverse=True)
    triangles = inverse.reshape(-1)[np.concatenate(faces)].astype(np.int32)
    del faces, inverse, name, lower_key, axis, edge
    pos = np.concatenate(centre_at)[first]
    del centre_at, first
    # On an edge: linear interpolation of the signed distance between its two nodes.
    on_edge = np.flatnonzero(uniq < 3 * len(keys))
    r0, a = uniq[on_edge] // 3, uniq[on_edge] % 3
    r1 = _find(keys, keys[r0] + np.array([1 << (2 * _KEY_BITS), 1 << _KEY_BITS, 1])[a])
    v0, v1 = dist[r0], dist[r1]
    edge_pos = _unpack(keys[r0]).astype(np.float64)
    edge_pos[np.arange(len(a)), a] += v0 / (v0 - v1)
    pos[on_edge] = edge_pos
    return origin + pos * cell, triangles


def _blocks(
    keys: NDArray[np.int64], size: int
) -> tuple[NDArray[np.int64], NDArray[np.int16], NDArray[np.int64]]:
    """The nodes of each block of ``size`` cells a side, blocks in key order: the block's
    packed key, the node's place in it (0 to ``size``) and the node's index in ``keys``.

    A node on the lower face of its block is also on the upper face of the block below
    (or of the blocks below, at an edge or a corner of its block): it comes once for each.
    """
    node_block = np.zeros(len(keys), np.int64)
    local = np.empty((len(keys), 3), np.int16)
    for a, shift in enumerate((2 * _KEY_BITS, _KEY_BITS, 0)):
        coord = (keys >> shift) & ((1 << _KEY_BITS) - 1)
        b = coord // size
        local[:, a] = coord - b * size
        node_block |= b << shift
    del coord, b
    on_face = (local[:, 0] == 0) + 2 * (local[:, 1] == 0) + 4 * (local[:, 2] == 0)
    shared = np.flatnonzero(on_face)
    shared_block = _unpack(node_block[shared])
    parts = [(node_block, local, np.arange(len(keys)))]
    for c in range(1, 8):
        below = ((on_face[shared] & c) == c) & (shared_block >= _CORNERS[c]).all(axis=1)
        at = shared[below]
        corner = _CORNERS[c]
        parts.append((node_block[at] - _pack(corner[None])[0], local[at] + size * corner, at))
    del on_face, shared, shared_block, node_block, local
    node_block, node_local, node_index = (np.concatenate(p) for p in zip(*parts))
    del parts
    order = np.argsort(node_block, kind="stable")
    return node_block[order], node_local[order], node_index[order]


def _all_corners(a: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Of each cube of a dense grid (by its lower corner): whether ``a`` holds at all eight
    of its corners."""
    a = a[:-1] & a[1:]
    a = a[:, :-1] & a[:, 1:]
    return a[:, :, :-1] & a[:, :, 1:]


def _find(keys: NDArray[np.int64], wanted: NDArray[np.int64]) -> NDArray[np.int64]:
    """Where each of ``wanted`` is in the sorted ``keys``, all of which it must be among."""
    at = np.minimum(np.searchsorted(keys, wanted), len(keys) - 1)
    if not (keys[at] == wanted).all():
        raise RuntimeError("marching cubes met a cube with a corner of unknown distance")
    return at


def _vertex_colors(
    vertices: NDArray[np.float64], tree: Any, colors: NDArray[np.uint8], cell: float
) -> NDArray[np.uint8]:
    """Gaussian-weighted mean colour of the points nearest to each vertex."""
    k = min(SDF_NEIGHBORS, tree.n)
    out = np.empty((len(vertices), 3), dtype=np.uint8)
    rgb = np.asarray(colors, dtype=np.float64)
    for s in range(0, len(vertices), QUERY_BLOCK):
        x = vertices[s : s + QUERY_BLOCK]
        dist, idx = tree.query(x, k=k, workers=-1)
        dist, idx = dist.reshape(len(x), k), idx.reshape(len(x), k)
        w = np.exp(-0.5 * ((dist - dist[:, :1]) / cell) ** 2)
        mean = np.einsum("nk,nki->ni", w, rgb[idx]) / w.sum(axis=1, keepdims=True)
        out[s : s + QUERY_BLOCK] = np.clip(np.round(mean), 0, 255).astype(np.uint8)
    return out


def _oriented_normals(
    pts: NDArray[np.float64], normals: ArrayLike | None, viewpoint: ArrayLike | None
) -> NDArray[np.float64]:
    """Unit normals of the points, turned to face ``viewpoint`` (the points' centroid by
    default) unless they were given."""
    if normals is not None:
        nrm = as_points(normals, "normals", n=len(pts), finite=True)
        length = np.linalg.norm(nrm, axis=1, keepdims=True)
        return nrm / np.maximum(length, 1e-300)
    nrm, _ = estimate_normals(pts, NORMAL_NEIGHBORS, up=None)
    eye = pts.mean(axis=0) if viewpoint is None else np.asarray(viewpoint, dtype=np.float64)
    if eye.shape != (3,) or not np.isfinite(eye).all():
        raise InvalidParameterError("viewpoint", "3 finite coordinates", viewpoint)
    away = np.einsum("ij,ij->i", nrm, eye - pts) < 0
    nrm[away] *= -1.0
    return nrm


def reconstruct_surface(
    points: ArrayLike,
    normals: ArrayLike | None = None,
    colors: ArrayLike | None = None,
    *,
    cell: float = 0.02,
    method: str = "marching_cubes",
    viewpoint: ArrayLike | None = None,
    max_cells: int = MAX_CELLS,
) -> SurfaceMesh:
    """A triangle mesh of the surface a (voxelised) point cloud samples (Alg. 1 step 2).

    ``marching_cubes``: the signed distance to the tangent planes of the nearest points
    (Gaussian weights of one cell; normals facing ``viewpoint``) is sampled on the grid
    nodes within ``SUPPORT_CELLS`` cells of a point, and marching cubes extracts its zero
    set. Only nodes near points are stored, and the cubes whose eight corners are known
    are meshed, so the mesh ends where the scan ends. ``poisson``: Open3D's screened
    Poisson reconstruction at the octree depth of the cell, one thread, the 5 % least
    supported vertices trimmed.

    Parameters
    ----------
    points : (n, 3) float
        Best a voxel cloud (one point per occupied voxel), metres.
    normals : (n, 3) float, optional
        Oriented normals; estimated from the ``NORMAL_NEIGHBORS`` nearest points and
        turned to face ``viewpoint`` when not given.
    colors : (n, 3) uint8, optional
        Colour of each point; the mesh's vertices get the weighted mean of their
        neighbours'.
    cell : float
        Grid cell (m): the voxel size or the scan's sampling spacing.
    method : {"marching_cubes", "poisson"}
    viewpoint : (3,) float, optional
        Where the sensor was: normals face it. The points' centroid by default (a room
        scanned from within).
    max_cells : int
        Most occupied cells; a larger scan is meshed at a coarser cell, in steps of
        ``sqrt(cells / max_cells)``, and ``info["capped"]`` says so.

    Returns
    -------
    SurfaceMesh
        The same input gives the same mesh, byte for byte.

    Raises
    ------
    InvalidParameterError
        For a bad parameter, naming it.

    Examples
    --------
    >>> import numpy as np
    >>> g = np.stack(np.meshgrid(np.arange(50), np.arange(50)), -1).reshape(-1, 2) * 0.02
    >>> mesh = reconstruct_surface(np.c_[g, np.zeros(len(g))], viewpoint=(0.5, 0.5, 1.0))
    >>> round(mesh.area, 1), bool(np.abs(mesh.vertices[:, 2]).max() < 1e-9)
    (1.0, True)
    """
    pts = as_points(points, finite=True)
    cell = check_param("cell", Interval(0.0, math.inf, "neither"), cell)
    method = check_param("method", OneOf(MESH_METHODS), method)
    max_cells = check_param("max_cells", Interval(1, math.inf, "left", integer=True), max_cells)
    rgb = None
    if colors is not None:
        rgb = np.asarray(colors)
        if rgb.shape != pts.shape:
            raise InvalidParameterError("colors", f"an array of shape {pts.shape}", rgb.shape)
        rgb = rgb.astype(np.uint8)
    if len(pts) < 3:
        empty = np.zeros((0, 3), np.uint8) if rgb is not None else None
        return SurfaceMesh(
            np.zeros((0, 3)), np.zeros((0, 3), np.int32), empty, cell, {"method": method}
        )
    nrm = _oriented_normals(pts, normals, viewpoint)
    if method == "poisson":
        return _poisson(pts, nrm, rgb, cell)
    from scipy.spatial import cKDTree  # heavy: imported when used (start-up)

    # The grid is laid from the points' own lowest corner, as the voxel grid is: a scan
    # moved by any offset meets the same grid, where multiples of the cell from 0 would cut
    # it elsewhere. Two and a half cells below it: keys stay non-negative, and a flat bottom
    # (a floor, a box's face) lies halfway between nodes, not on them, where the sign of
    # a distance of 0 would decide.
    low = pts.min(axis=0)
    origin = low - GRID_MARGIN * cell
    requested, capped = cell, False
    while True:
        ijk = np.floor((pts - origin) / cell).astype(np.int64)
        if ijk.max() + 4 >= 1 << _KEY_BITS:
            raise InvalidParameterError(
                "cell",
                f"at least {np.ptp(pts, axis=0).max() / (1 << _KEY_BITS - 3):.3g} m "
                "for this scan's extent",
                cell,
            )
        cells = np.unique(_pack(ijk))
        if len(cells) <= max_cells:
            break
        cell *= math.sqrt(len(cells) / max_cells) * 1.05
        origin = low - GRID_MARGIN * cell
        capped = True
    keys = _grid_nodes(_unpack(cells))
    tree = cKDTree(pts)
    values = _signed_distance(origin + _unpack(keys) * cell, tree, pts, nrm, cell)
    vertices, triangles = _marching_cubes(keys, values, origin, cell)
    vcol = None if rgb is None else _vertex_colors(vertices, tree, rgb, cell)
    info = {
        "method": method,
        "cell": cell,
        "requested_cell": requested,
        "capped": capped,
        "occupied_cells": len(cells),
        "grid_nodes": int(np.count_nonzero(~np.isnan(values))),
    }
    return SurfaceMesh(vertices, triangles, vcol, cell, info)


def _poisson(
    pts: NDArray[np.float64], nrm: NDArray[np.float64], rgb: NDArray[np.uint8] | None, cell: float
) -> SurfaceMesh:
    import open3d as o3d  # heavy: imported when used (start-up)

    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
    pcd.normals = o3d.utility.Vector3dVector(nrm)
    if rgb is not None:
        pcd.colors = o3d.utility.Vector3dVector(rgb / 255.0)
    extent = float(np.ptp(pts, axis=0).max())
    depth = int(min(POISSON_MAX_DEPTH, max(1, math.ceil(math.log2(max(extent / cell, 2.0))))))
    with o3d.utility.VerbosityContextManager(o3d.utility.VerbosityLevel.Error):
        mesh, density = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(
            pcd, depth=depth, n_threads=1
        )
    density = np.asarray(density)
    if len(density):
        mesh.remove_vertices_by_mask(density < np.quantile(density, POISSON_TRIM))
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    triangles = np.asarray(mesh.triangles, dtype=np.int32)
    vcol = None
    if rgb is not None:
        vcol = np.clip(np.round(np.asarray(mesh.vertex_colors) * 255.0), 0, 255).astype(np.uint8)
    info = {"method": "poisson", "cell": cell, "depth": depth, "capped": False}
    return SurfaceMesh(vertices, triangles, vcol, cell, info)


def scene_surface(
    prepared: Any,
    voxels: ArrayLike | None = None,
    *,
    method: str = "marching_cubes",
    cell: float | None = None,
    max_cells: int = MAX_CELLS,
) -> SurfaceMesh:
    """A mesh of a prepared scene's voxel cloud, in its levelled frame.

    Parameters
    ----------
    prepared : PreparedScene
    voxels : (k,) int, optional
        Which voxels to mesh (e.g. the object voxels); all by default.
    method : {"marching_cubes", "poisson"}
    cell : float, optional
        Grid cell (m); the scene's sampling spacing by default (at least the voxel size).
    max_cells : int
        See :func:`reconstruct_surface`.

    Returns
    -------
    SurfaceMesh
        In the levelled frame (z up, floor at 0); ``mesh.transformed(prepared.from_level)``
        puts it in the input file's frame. Normals face a sensor ``SENSOR_HEIGHT`` above
        the floor over the middle of the scan.

    Examples
    --------
    >>> import numpy as np
    >>> from ontodetect import point_cloud
    >>> from ontodetect.preprocess import prepare
    >>> floor = np.c_[np.random.default_rng(0).random((20000, 2)) * 4, np.zeros(20000)]
    >>> round(scene_surface(prepare(point_cloud(floor))).area)
    16
    """
    idx = np.arange(len(prepared.voxels)) if voxels is None else np.asarray(voxels, np.int64)
    centers = prepared.centers[idx]
    colors = None if prepared.colors is None else prepared.colors[idx]
    eye = None
    if len(centers):
        lo, hi = prepared.centers.min(axis=0), prepared.centers.max(axis=0)
        eye = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, SENSOR_HEIGHT])
    return reconstruct_surface(
        centers,
        colors=colors,
        cell=prepared.spacing if cell is None else cell,
        method=method,
        viewpoint=eye,
        max_cells=max_cells,
    )
