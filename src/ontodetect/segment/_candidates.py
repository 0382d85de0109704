"""Segmentation by recognition, first step (issue 20): an over-segmentation of a prepared
scene into small surface segments, and candidate objects made from it by generators
registered by name (:data:`GENERATORS`).

Every generator takes a :class:`Proposal` (the scene's object voxels, their segments and
today's part-seeded segmentation) and returns sets of object voxels; the candidates are
scored by the ontology and the best consistent set chosen elsewhere
(``ontodetect.labeling.select_candidates``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy import sparse

from ..preprocess import PreparedScene, graph_normals
from ._cluster import euclidean_clusters, radius_graph
from ._segmentation import Segmentation

__all__ = [
    "GENERATORS",
    "Proposal",
    "Segments",
    "cut_shares",
    "felzenszwalb",
    "oversegment",
    "propose",
    "register_generator",
]

#: Scale ``k`` of the Felzenszwalb–Huttenlocher criterion: a segment of n voxels merges
#: across an edge lighter than its own heaviest inner edge plus ``k / n``.
FH_SCALE = 0.5
#: Weight of the colour difference (RGB in 0..1, Euclidean) beside the normals' angle
#: (1 − |cos|) in an edge's weight.
COLOR_WEIGHT = 0.3
#: Segments smaller than this many voxels join their lightest neighbour.
MIN_SEGMENT = 8
#: Radii of the density-cluster generator, in clustering radii.
DENSITY_RADII = (1.0, 2.0)
#: A part hypothesis's prism reaches this far (m) beyond its patch horizontally, ...
PRISM_MARGIN = 0.25
#: ... and this high (m) above it (a backrest above a seat; for a top, clutter on it).
PRISM_ABOVE = (0.7, 0.3)
#: Patches at least this high (m) are tops; lower ones are seats.
TOP_HEIGHT = 0.6
#: A top's prism leaves out the prism of a part at least this much lower (m).
BELOW_TOP = 0.15
#: Most candidates any one generator proposes.
MAX_PER_GENERATOR = 150


@dataclass(frozen=True)
class Segments:
    """An over-segmentation of object voxels.

    Attributes
    ----------
    labels : (m,) int
        Segment of every object voxel (0..k-1).
    centroids : (k, 3) float
    normals : (k, 3) float
        Mean voxel normal of each segment (unit, not oriented).
    counts : (k,) int
    edges : (e, 2) int and weights : (e,) float
        Adjacent segment pairs (i < j) and the lightest voxel edge between them.
    """

    labels: NDArray[np.int64]
    centroids: NDArray[np.float64]
    normals: NDArray[np.float64]
    counts: NDArray[np.int64]
    edges: NDArray[np.int64]
    weights: NDArray[np.float64]

    def __len__(self) -> int:
        return len(self.counts)


def _find(parent: NDArray[np.int64], i: int) -> int:
    root = i
    while parent[root] != root:
        root = parent[root]
    while parent[i] != root:  # path compression
        parent[i], i = root, parent[i]
    return root


def felzenszwalb(
    n: int,
    edges: NDArray[np.int64],
    weights: NDArray[np.float64],
    *,
    scale: float = FH_SCALE,
    min_size: int = MIN_SEGMENT,
) -> NDArray[np.int64]:
    """Felzenszwalb–Huttenlocher graph segmentation of ``n`` nodes (a union-find over the
    edges sorted by weight).

    Parameters
    ----------
    n : int
    edges : (e, 2) int
    weights : (e,) float
    scale : float
        ``k`` of the merge criterion ``w <= min(Int(A) + k/|A|, Int(B) + k/|B|)``.
    min_size : int
        Segments smaller than this join across their lightest edge afterwards.

    Returns
    -------
    (n,) int
        Segment labels 0..k-1, in order of first node.

    Examples
    --------
    >>> e = np.array([[0, 1], [1, 2], [2, 3]]); w = np.array([0.0, 5.0, 0.0])
    >>> felzenszwalb(4, e, w, scale=1.0, min_size=1).tolist()
    [0, 0, 1, 1]
    """
    parent = np.arange(n, dtype=np.int64)
    size = np.ones(n, dtype=np.int64)
    inner = np.zeros(n)
    order = np.argsort(weights, kind="stable")
    es, ws = edges[order].tolist(), weights[order].tolist()
    par = parent  # local names: the loop is the hot path
    for (a, b), w in zip(es, ws):
        ra, rb = _find(par, a), _find(par, b)
        if ra == rb:
            continue
        if w <= min(inner[ra] + scale / size[ra], inner[rb] + scale / size[rb]):
            if size[ra] < size[rb]:
                ra, rb = rb, ra
            par[rb] = ra
            size[ra] += size[rb]
            inner[ra] = max(inner[ra], inner[rb], w)
    for a, b in es:
        ra, rb = _find(par, a), _find(par, b)
        if ra != rb and (size[ra] < min_size or size[rb] < min_size):
            if size[ra] < size[rb]:
                ra, rb = rb, ra
            par[rb] = ra
            size[ra] += size[rb]
    roots = np.array([_find(par, i) for i in range(n)], dtype=np.int64)
    _, labels = np.unique(roots, return_inverse=True)
    first = np.full(labels.max() + 1 if n else 0, n, dtype=np.int64)
    np.minimum.at(first, labels, np.arange(n))
    rank = np.empty_like(first)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[labels]


def oversegment(
    centers: NDArray[np.float64],
    colors: NDArray | None,
    radius: float,
    *,
    scale: float = FH_SCALE,
    min_size: int = MIN_SEGMENT,
    graph: sparse.csr_matrix | None = None,
) -> Segments:
    """Small surface segments of voxels (centres ``(m, 3)``): Felzenszwalb–Huttenlocher on
    the radius graph (``graph`` when it is already made), edges weighted by the normals'
    angle and the colour difference; each segment's centroid, normal and neighbours
    measured once."""
    m = len(centers)
    if m == 0:
        z = np.zeros((0, 3))
        return Segments(
            np.zeros(0, np.int64),
            z,
            z,
            np.zeros(0, np.int64),
            np.zeros((0, 2), np.int64),
            np.zeros(0),
        )
    if graph is None:
        graph = radius_graph(centers, radius)
    normals, _ = graph_normals(centers, graph) if m > 1 else (np.tile([0.0, 0, 1], (m, 1)), None)
    g = sparse.triu(graph, k=1).tocoo()
    i, j = g.row.astype(np.int64), g.col.astype(np.int64)
    w = 1.0 - np.abs(np.einsum("ij,ij->i", normals[i], normals[j]))
    if colors is not None and len(colors) == m:
        rgb = np.asarray(colors, dtype=np.float64).reshape(m, -1)[:, :3] / 255.0
        w = w + COLOR_WEIGHT * np.linalg.norm(rgb[i] - rgb[j], axis=1)
    edges = np.c_[i, j]
    labels = felzenszwalb(m, edges, w, scale=scale, min_size=min_size)
    k = int(labels.max()) + 1 if m else 0
    counts = np.bincount(labels, minlength=k)
    centroids = np.stack([np.bincount(labels, centers[:, d], k) for d in range(3)], 1)
    centroids /= counts[:, None]
    # Normals are unoriented: average their outer products' main axis via the sign of z.
    signed = normals * np.where(normals[:, 2:3] < 0, -1.0, 1.0)
    seg_normals = np.stack([np.bincount(labels, signed[:, d], k) for d in range(3)], 1)
    seg_normals /= np.maximum(np.linalg.norm(seg_normals, axis=1, keepdims=True), 1e-12)
    a, b = labels[i], labels[j]
    cross = a != b
    pairs = np.sort(np.c_[a[cross], b[cross]], axis=1)
    pw = w[cross]
    if len(pairs):
        key = pairs[:, 0] * k + pairs[:, 1]
        order = np.lexsort((pw, key))
        key, pw, pairs = key[order], pw[order], pairs[order]
        first = np.r_[True, key[1:] != key[:-1]]
        pairs, pw = pairs[first], pw[first]
    return Segments(labels, centroids, seg_normals, counts, pairs.astype(np.int64), pw)


@dataclass(frozen=True)
class Proposal:
    """What the candidate generators share about one prepared scene.

    Attributes
    ----------
    prepared : PreparedScene
    seg : Segmentation
        Today's part-seeded segmentation of the same scene.
    objects : (m,) int
        The object voxels (indices into the prepared scene's voxels).
    segments : Segments
        Over-segmentation of the object voxels (labels index ``objects``).
    radius : float
        Clustering radius (m).
    max_length : float
        Longest side a candidate may have (m), ``cluster.length[1]``.
    min_voxels : int
        Fewest voxels of a candidate (``cluster.min_surface``).
    members : list of (k,) int
        Scene voxels of each segment.
    graph : (m, m) sparse, optional
        The object voxels' graph at the clustering radius (rows index ``objects``), made
        once for the over-segmentation, the generators and :func:`cut_shares`.
    """

    prepared: PreparedScene
    seg: Segmentation
    objects: NDArray[np.int64]
    segments: Segments
    radius: float
    max_length: float
    min_voxels: int
    members: list[NDArray[np.int64]] = field(default_factory=list)
    graph: sparse.csr_matrix | None = None

    def voxels_of(self, segment_ids: NDArray[np.int64]) -> NDArray[np.int64]:
        """Scene voxels of the given segments."""
        return np.sort(np.concatenate([self.members[s] for s in segment_ids]))

    def fits(self, vox: NDArray[np.int64]) -> bool:
        """Within the size limits of a candidate object."""
        if len(vox) < self.min_voxels:
            return False
        xy = self.prepared.centers[vox, :2]
        return bool(np.ptp(xy, axis=0).max() <= self.max_length)


#: A candidate generator: a proposal -> sets of scene voxels.
Generator = Callable[[Proposal], list[NDArray[np.int64]]]
#: The candidate generators, by name (PDAL-style registry).
GENERATORS: dict[str, Generator] = {}


def register_generator(name: str) -> Callable[[Generator], Generator]:
    """Register a candidate generator under ``name``."""

    def add(fn: Generator) -> Generator:
        GENERATORS[name] = fn
        return fn

    return add


@register_generator("clusters")
def _today(p: Proposal) -> list[NDArray[np.int64]]:
    """Today's part-seeded clusters: recognition finds at least what they find."""
    return [np.asarray(c.voxels, dtype=np.int64) for c in p.seg]


@register_generator("parts")
def _part_hypotheses(p: Proposal) -> list[NDArray[np.int64]]:
    """Every seat- or table-height patch of today's segmentation, grown with the segments
    whose centroids lie in a prism around it: from the floor to a little above it
    (``PRISM_ABOVE``), ``PRISM_MARGIN`` beyond its box. A top's prism leaves out the
    segments of another part's prism below it (a chair's seat under a desk's top)."""
    seeds = [s for c in p.seg for s in c.parts]
    cent = p.segments.centroids
    out = []
    boxes = []
    for s in seeds:
        d = cent[:, :2] - s.center
        u, v = np.abs(d @ s.axes[0]), np.abs(d @ s.axes[1])
        half = s.extent / 2 + PRISM_MARGIN
        above = PRISM_ABOVE[0] if s.height < TOP_HEIGHT else PRISM_ABOVE[1]
        inside = (u <= half[0]) & (v <= half[1]) & (cent[:, 2] <= s.height + above)
        boxes.append((s, inside))
    for s, inside in boxes:
        keep = inside.copy()
        if s.height >= TOP_HEIGHT:  # a top does not claim a lower part's segments
            for t, other in boxes:
                if t is not s and t.height < s.height - BELOW_TOP:
                    keep &= ~other
        if keep.any():
            out.append(p.voxels_of(np.flatnonzero(keep)))
    return out


@register_generator("merge")
def _merge_tree(p: Proposal) -> list[NDArray[np.int64]]:
    """Every node of a single-linkage merge of adjacent segments (lightest boundary edge
    first) that is large enough and not longer than an object may be."""
    segs = p.segments
    k = len(segs)
    parent = np.arange(k, dtype=np.int64)
    groups = {i: [i] for i in range(k)}
    out = []
    for e in np.argsort(segs.weights, kind="stable"):
        a, b = _find(parent, int(segs.edges[e, 0])), _find(parent, int(segs.edges[e, 1]))
        if a == b:
            continue
        if len(groups[a]) < len(groups[b]):
            a, b = b, a
        parent[b] = a
        groups[a].extend(groups.pop(b))
        vox = p.voxels_of(np.asarray(groups[a]))
        if len(groups[a]) > 1 and p.fits(vox):
            out.append(vox)
    return out


@register_generator("density")
def _density(p: Proposal) -> list[NDArray[np.int64]]:
    """Connected components of the object voxels at a couple of radii."""
    centers = p.prepared.centers[p.objects]
    out = []
    for f in DENSITY_RADII:
        if len(centers) < 2:
            break
        labels = euclidean_clusters(centers, f * p.radius, graph=p.graph if f == 1 else None)
        for c in range(int(labels.max()) + 1):
            out.append(p.objects[labels == c])
    return out


def propose(
    prepared: PreparedScene,
    seg: Segmentation,
    generators: tuple[str, ...] | None = None,
) -> tuple[list[NDArray[np.int64]], list[str], Proposal]:
    """Candidate objects of a prepared scene: the voxel sets of every generator, within
    the size limits, without duplicates (the first generator to propose one names it).

    Returns
    -------
    candidates : list of (k,) int
        Sorted scene voxels of each candidate.
    sources : list of str
        The generator of each.
    proposal : Proposal
    """
    cc = seg.config.cluster
    objects = np.flatnonzero(prepared.object_mask).astype(np.int64)
    radius = seg.radius
    centers = prepared.centers[objects]
    graph = radius_graph(centers, radius)  # an empty graph for fewer than two voxels
    segments = oversegment(
        centers,
        None if prepared.colors is None else prepared.colors[objects],
        radius,
        graph=graph,
    )
    order = np.argsort(segments.labels, kind="stable")
    bounds = np.r_[0, np.cumsum(segments.counts)]
    members = [objects[order[bounds[s] : bounds[s + 1]]] for s in range(len(segments))]
    proposal = Proposal(
        prepared,
        seg,
        objects,
        segments,
        radius,
        float(cc.length[1]),
        max(1, int(np.ceil(cc.min_surface / prepared.spacing**2))),
        members,
        graph,
    )
    seen: set[bytes] = set()
    out, sources = [], []
    for name in generators or tuple(GENERATORS):
        made = 0
        for vox in GENERATORS[name](proposal):
            vox = np.unique(np.asarray(vox, dtype=np.int64))
            key = vox.tobytes()
            if key in seen or not proposal.fits(vox):
                continue
            seen.add(key)
            out.append(vox)
            sources.append(name)
            made += 1
            if made >= MAX_PER_GENERATOR:
                break
    return out, sources, proposal


def cut_shares(
    objects: NDArray[np.int64], graph: sparse.csr_matrix, voxel_sets: list[NDArray[np.int64]]
) -> tuple[NDArray[np.float64], sparse.csr_matrix]:
    """How much of each candidate is cut out of something bigger.

    On the graph joining the scene's object voxels closer than the clustering radius
    (:attr:`Proposal.graph`), a candidate's cut share is the share of its voxels' edges
    that lead to object voxels outside it. A piece of furniture stands apart from what is
    around it but for the floor and the walls it rests on (structure, not in the graph): a
    whole chair has a share near 0, a chair's backrest without its seat, or a desk with a
    chair's legs, a large one.

    Parameters
    ----------
    objects : (m,) int
        The graph's nodes: sorted scene voxels (:attr:`Proposal.objects`).
    graph : (m, m) sparse
        Their graph (:attr:`Proposal.graph`).
    voxel_sets : list of (k,) int
        Each candidate's scene voxels (those not in ``objects`` are left out).

    Returns
    -------
    cut : (n,) float
        Each candidate's cut share (0..1).
    contact : (n, n) sparse float
        ``contact[i, j]``: the share of candidate ``i``'s edges that lead into candidate
        ``j`` (what ``i`` would not have lost had ``j`` been taken too).

    Examples
    --------
    >>> import numpy as np
    >>> line = np.column_stack([np.arange(6) * 0.02, np.zeros(6), np.zeros(6)])
    >>> graph = radius_graph(line, 0.025)
    >>> sets = [np.arange(6), np.arange(3), np.arange(3, 6)]
    >>> cut, contact = cut_shares(np.arange(6), graph, sets)
    >>> cut.round(2).tolist(), round(float(contact[1, 2]), 2)
    ([0.0, 0.2, 0.2], 0.2)
    """
    objects = np.asarray(objects, dtype=np.int64)
    graph = sparse.csr_matrix(graph)
    n, m = len(voxel_sets), len(objects)
    cut = np.zeros(n)
    edges = np.ones(n)
    member_rows, member_cols, out_rows, out_cols = [], [], [], []
    inside = np.zeros(m, dtype=bool)
    for k, vox in enumerate(voxel_sets):
        vox = np.asarray(vox, dtype=np.int64)
        idx = np.minimum(np.searchsorted(objects, vox), max(m - 1, 0))
        idx = idx[objects[idx] == vox] if m else idx[:0]
        if not len(idx):
            continue
        inside[idx] = True
        ends = graph[idx].indices
        leave = ends[~inside[ends]]
        inside[idx] = False
        member_rows.append(np.full(len(idx), k))
        member_cols.append(idx)
        if len(ends):
            edges[k] = len(ends)
            cut[k] = len(leave) / len(ends)
            out_rows.append(np.full(len(leave), k))
            out_cols.append(leave)

    def matrix(rows: list[NDArray], cols: list[NDArray]) -> sparse.csr_matrix:
        r = np.concatenate(rows) if rows else np.zeros(0, np.int64)
        c = np.concatenate(cols) if cols else np.zeros(0, np.int64)
        return sparse.csr_matrix((np.ones(len(r)), (r, c)), shape=(n, m))

    leaving = matrix(out_rows, out_cols)
    member = matrix(member_rows, member_cols)
    contact = sparse.diags(1.0 / edges) @ (leaving @ member.T)
    return cut, sparse.csr_matrix(contact)
