"""Clustering on the voxel grid: DBSCAN, Euclidean clustering and smooth region growing.

Everything runs on voxel centres (one point per occupied voxel), so the cost does
not depend on the sensor's density, and on a sparse neighbour graph whose
connected components (``scipy.sparse.csgraph``) are the clusters: linear in the
number of voxels, with no per-point neighbourhood lists kept around as Open3D's
DBSCAN does.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import sparse
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import InvalidParameterError
from ..geometry import as_points

__all__ = [
    "core_neighbors",
    "dbscan",
    "euclidean_clusters",
    "mesh_graph",
    "radius_graph",
    "region_growing",
    "relabel",
]

#: Fewest neighbours (the voxel included) of a DBSCAN core voxel, whatever ``core_fill``.
MIN_CORE_NEIGHBORS = 2
#: Mesh adjacency: a path along the surface may be this much longer than the straight
#: line between two neighbours (it follows a fold, a rounded edge) and still join them.
GEODESIC_SLACK = 1.5
#: Mesh adjacency: a vertex belongs to its nearest point when that is within this many
#: grid cells of it.
ATTACH_CELLS = 1.5
#: Rows of the surface reach computed at a time (bounds the sparse products).
REACH_BLOCK = 50_000


def radius_graph(points: ArrayLike, radius: float) -> sparse.csr_matrix:
    """Symmetric sparse graph joining points closer than ``radius``; weights are distances.

    Zero distances (duplicate points) are stored as a tiny positive weight so that
    the edge is not lost.

    Examples
    --------
    >>> g = radius_graph([[0, 0, 0], [0.03, 0, 0], [1, 0, 0]], 0.05)
    >>> g.nnz, round(float(g[0, 1]), 3)
    (2, 0.03)
    """
    pts = as_points(points)
    if not radius > 0:
        raise InvalidParameterError("radius", "a float in the range (0, inf)", radius)
    m = len(pts)
    if m < 2:
        return sparse.csr_matrix((m, m))
    pairs = cKDTree(pts).query_pairs(radius, output_type="ndarray")
    i, j = pairs[:, 0], pairs[:, 1]
    d = np.linalg.norm(pts[i] - pts[j], axis=1)
    d = np.maximum(d, np.finfo(np.float64).tiny)
    g = sparse.coo_matrix((np.r_[d, d], (np.r_[i, j], np.r_[j, i])), shape=(m, m))
    return g.tocsr()


def mesh_graph(
    points: ArrayLike,
    mesh: Any,
    radius: float,
    *,
    graph: sparse.csr_matrix | None = None,
) -> sparse.csr_matrix:
    """The ``radius`` graph restricted to the pairs of points a surface mesh joins.

    Every vertex of ``mesh`` belongs to its nearest point; two points are adjacent on
    the mesh when vertices of theirs share a triangle (a point that owns no vertex is
    adjacent to the owner of its nearest vertex). A pair of the radius graph is kept
    when the mesh joins its points within ``ceil(GEODESIC_SLACK * radius / mesh.cell)``
    steps: neighbours along the scanned surface stay neighbours, while two objects
    apart through the air (a chair and the table it stands at), which the radius graph
    joins, part. A gap of up to about four cells in one surface looks like a hole
    between samples and the mesh bridges it (:func:`reconstruct_surface` fills
    ``TANGENTIAL_CELLS`` past the last points on each side).

    Parameters
    ----------
    points : (m, 3) float
        The points the mesh was built from (voxel centres).
    mesh : SurfaceMesh
        From :func:`ontodetect.preprocess.reconstruct_surface`; its ``cell`` sets the
        step length.
    radius : float
        Neighbourhood radius (m).
    graph : sparse matrix, optional
        :func:`radius_graph` of the points, if already built.

    Returns
    -------
    sparse (m, m) matrix
        Symmetric, weights are distances: a subgraph of the radius graph.

    Examples
    --------
    >>> import numpy as np
    >>> from ontodetect.preprocess import reconstruct_surface
    >>> g = np.stack(np.meshgrid(np.arange(20), np.arange(20)), -1).reshape(-1, 2) * 0.02
    >>> a = np.c_[g, np.zeros(len(g))]
    >>> pts = np.vstack([a, a + [0.48, 0, 0]])   # two sheets 10 cm apart
    >>> mesh = reconstruct_surface(pts, viewpoint=(0.4, 0.2, 1.0))
    >>> euclidean_clusters(pts, 0.12).max(), euclidean_clusters(
    ...     pts, 0.12, graph=mesh_graph(pts, mesh, 0.12)).max()
    (np.int64(0), np.int64(1))
    """
    pts = as_points(points)
    m = len(pts)
    g = radius_graph(pts, radius) if graph is None else sparse.csr_matrix(graph)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    if m < 2 or len(mesh.triangles) == 0:
        return sparse.csr_matrix((m, m))
    cell = float(mesh.cell) if mesh.cell > 0 else float(radius)
    dist, owner = cKDTree(pts).query(vertices, workers=-1)
    attached = dist <= ATTACH_CELLS * cell
    edges = mesh.edges
    a, b = owner[edges[:, 0]], owner[edges[:, 1]]
    keep = attached[edges[:, 0]] & attached[edges[:, 1]] & (a != b)
    a, b = a[keep], b[keep]
    owns = np.zeros(m, dtype=bool)
    owns[owner[attached]] = True
    lonely = np.flatnonzero(~owns)
    if len(lonely) and attached.any():
        ids = np.flatnonzero(attached)
        d, near = cKDTree(vertices[ids]).query(pts[lonely], workers=-1)
        ok = d <= radius
        a = np.r_[a, lonely[ok]]
        b = np.r_[b, owner[ids[near[ok]]]]
    step = sparse.csr_matrix(
        (np.ones(2 * len(a)), (np.r_[a, b], np.r_[b, a])), shape=(m, m)
    ) + sparse.identity(m, format="csr")
    step.data[:] = 1.0
    hops = max(1, math.ceil(GEODESIC_SLACK * radius / cell))
    blocks = []
    for s in range(0, m, REACH_BLOCK):
        reach = step[s : s + REACH_BLOCK]
        for _ in range(hops - 1):
            reach = reach @ step
            reach.data[:] = 1.0
        blocks.append(g[s : s + REACH_BLOCK].multiply(reach).tocsr())
    out = sparse.vstack(blocks, format="csr")
    out.eliminate_zeros()
    out.sort_indices()
    return out


def relabel(labels: ArrayLike) -> NDArray[np.int64]:
    """Renumber labels 0..k-1 by first appearance order of size (largest first); -1 kept.

    Examples
    --------
    >>> relabel([5, 5, -1, 2, 2, 2]).tolist()
    [1, 1, -1, 0, 0, 0]
    """
    lab = np.asarray(labels, dtype=np.int64)
    out = np.full(lab.shape, -1, dtype=np.int64)
    valid = lab >= 0
    if not valid.any():
        return out
    uniq, inv, counts = np.unique(lab[valid], return_inverse=True, return_counts=True)
    # Largest first; ties by smallest original label, so the order is deterministic.
    order = np.lexsort((uniq, -counts))
    rank = np.empty(len(uniq), dtype=np.int64)
    rank[order] = np.arange(len(uniq))
    out[valid] = rank[inv.reshape(-1)]
    return out


def core_neighbors(radius: float, spacing: float, core_fill: float) -> int:
    """Neighbours (the voxel included) a DBSCAN core voxel needs: a share of a flat disc.

    A surface sampled every ``spacing`` holds about ``pi r² / spacing²`` samples
    within ``r`` of a point; a core voxel sees at least ``core_fill`` of that, so
    the same setting serves sparse and dense scans.

    Examples
    --------
    >>> core_neighbors(0.05, 0.02, 0.2)
    4
    """
    disc = math.pi * radius**2 / max(spacing, 1e-12) ** 2
    return max(MIN_CORE_NEIGHBORS, math.ceil(core_fill * disc))


def dbscan(
    points: ArrayLike,
    radius: float,
    min_neighbors: int,
    *,
    graph: sparse.csr_matrix | None = None,
) -> NDArray[np.int64]:
    """DBSCAN: clusters of core points (``min_neighbors`` within ``radius``) and their borders.

    Parameters
    ----------
    points : (m, 3) float
    radius : float
        Neighbourhood radius.
    min_neighbors : int
        Points within ``radius`` (the point included) that make a core point.
    graph : sparse matrix, optional
        :func:`radius_graph` of the points, if already built.

    Returns
    -------
    (m,) int
        Cluster of each point, largest cluster 0; -1 for noise. A border point
        joins the cluster of its nearest core neighbour.

    Examples
    --------
    >>> import numpy as np
    >>> line = np.c_[np.arange(10) * 0.02, np.zeros(10), np.zeros(10)]
    >>> pts = np.vstack([line, line + [1, 0, 0], [[3, 3, 3]]])
    >>> dbscan(pts, 0.05, 3).tolist()
    [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, -1]
    """
    pts = as_points(points)
    m = len(pts)
    if m == 0:
        return np.zeros(0, dtype=np.int64)
    g = radius_graph(pts, radius) if graph is None else graph.tocsr()
    degree = np.diff(g.indptr) + 1
    core = degree >= int(min_neighbors)
    labels = np.full(m, -1, dtype=np.int64)
    if not core.any():
        return labels
    coo = g.tocoo()
    keep = core[coo.row] & core[coo.col]
    core_graph = sparse.csr_matrix(
        (np.ones(int(keep.sum())), (coo.row[keep], coo.col[keep])), shape=(m, m)
    )
    _, comp = connected_components(core_graph, directed=False)
    labels[core] = comp[core]
    # Border points: nearest core neighbour within the radius.
    border = (~core[coo.row]) & core[coo.col]
    if border.any():
        r, c, d = coo.row[border], coo.col[border], coo.data[border]
        order = np.lexsort((c, d, r))  # by point, then distance, then index (deterministic)
        r, c = r[order], c[order]
        first = np.r_[True, r[1:] != r[:-1]]
        labels[r[first]] = labels[c[first]]
    return relabel(labels)


def euclidean_clusters(
    points: ArrayLike, radius: float, *, graph: sparse.csr_matrix | None = None
) -> NDArray[np.int64]:
    """Euclidean clustering: connected components of the ``radius`` graph.

    Examples
    --------
    >>> euclidean_clusters([[0, 0, 0], [0.04, 0, 0], [0.5, 0, 0]], 0.05).tolist()
    [0, 0, 1]
    """
    pts = as_points(points)
    if len(pts) == 0:
        return np.zeros(0, dtype=np.int64)
    g = radius_graph(pts, radius) if graph is None else graph
    _, comp = connected_components(g, directed=False)
    return relabel(comp)


def region_growing(
    points: ArrayLike,
    normals: ArrayLike,
    radius: float,
    smoothness: float = 15.0,
    *,
    graph: sparse.csr_matrix | None = None,
) -> NDArray[np.int64]:
    """Smooth region growing: neighbours join while their normals differ by < ``smoothness``.

    Regions are connected components of the ``radius`` graph restricted to
    edges between near-parallel normals (sign ignored), so a seat and the
    backrest above it part where the surface folds. Points left alone (edges,
    legs) join the neighbouring region with the closest normal.

    Parameters
    ----------
    points : (m, 3) float
    normals : (m, 3) float
        Unit normals.
    radius : float
    smoothness : float
        Largest angle (deg) between neighbouring normals within a region.

    Returns
    -------
    (m,) int
        Region of every point, largest first.

    Examples
    --------
    >>> import numpy as np
    >>> g = np.stack(np.meshgrid(np.arange(10), np.arange(10)), -1).reshape(-1, 2) * 0.02
    >>> seat = np.c_[g, np.zeros(100)]
    >>> back = np.c_[g[:, 0], np.zeros(100), g[:, 1] + 0.02]
    >>> n = np.repeat([[0, 0, 1], [0, 1, 0]], 100, axis=0)
    >>> lab = region_growing(np.vstack([seat, back]), n, 0.03, 15)
    >>> len(set(lab[:100].tolist())), len(set(lab[100:].tolist())), lab[0] != lab[150]
    (1, 1, np.True_)
    """
    pts = as_points(points)
    nrm = np.asarray(normals, dtype=np.float64)
    if nrm.shape != pts.shape:
        raise InvalidParameterError(
            "normals", f"an array of shape {pts.shape}", f"shape {nrm.shape}"
        )
    m = len(pts)
    if m == 0:
        return np.zeros(0, dtype=np.int64)
    g = (radius_graph(pts, radius) if graph is None else graph).tocoo()
    cos = np.abs((nrm[g.row] * nrm[g.col]).sum(axis=1))
    smooth = cos >= np.cos(np.radians(smoothness))
    sg = sparse.csr_matrix(
        (np.ones(int(smooth.sum())), (g.row[smooth], g.col[smooth])), shape=(m, m)
    )
    _, comp = connected_components(sg, directed=False)
    sizes = np.bincount(comp)
    alone = sizes[comp] == 1
    if alone.any():
        # Singletons join the neighbour whose normal is closest.
        edge = alone[g.row] & ~alone[g.col]
        r, c, k = g.row[edge], g.col[edge], -cos[edge]
        order = np.lexsort((c, k, r))
        r, c = r[order], c[order]
        first = np.r_[True, r[1:] != r[:-1]]
        comp[r[first]] = comp[c[first]]
    return relabel(comp)
