"""Part-driven clustering: density regions split around seat and table-top hypotheses.

Plain density clustering cannot isolate furniture in a crowded room: at a small
radius a sparse chair falls apart, at a larger one it merges with the table it is
tucked under. Top-down knowledge helps (the thesis's point): seats and table tops
are horizontal patches at known heights, and every other part of a chair, sofa or
table hangs from one - legs below it, a backrest above its back edge, armrests
beside it - within a short distance of its outline. So:

1. horizontal patches at part height (Table 4.1: seats at 35–75 cm; table tops a
   little higher), flat and at least as wide as a seat, are found; touching patches
   at one height (sofa cushions) are one part, and narrow patches a little above a
   seat within its outline (armrests, the top of a sofa's back; narrow meaning no
   wider anywhere than an arm, so that the U of a back's and arms' tops counts) join
   it, and so does the flat top of a thick upholstered back a little further behind a
   long seat; each part is a seed;
2. each seed claims the voxels of its *prism* that it reaches along the surface
   within a path length. A seat's prism is its outline grown by 30 cm, up to 80 cm
   above it (backrest, legs, armrests); a top's is its outline grown by 5 cm below
   it and the outline itself above it (legs and apron are under a table; the
   backrest of a chair pushed against its edge is not the table). Where prisms
   overlap (a chair tucked under a table) the voxel goes to the shorter path;
   folding from one surface onto another costs extra, and so does every metre
   outside a top's outline;
3. what no seed claims forms connected pieces; pieces longer than a cluster may be
   are split again with shorter links (walls with doors and shelves link a whole
   room), and pieces lying mostly in a part's prism next to its cluster (a backrest
   or a swivel base cut off by a gap in a sparse scan) join it. For a low seat the
   prism may also be drawn around its cluster's box, or a little around what it
   claimed at its own height: a sparse seat is found as a patch, and the back and
   arms of its sofa stand beyond the patch's reach.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage, sparse
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree

from ..ontology import Gaussian, SeedStyle, builtin_ontology
from ._cluster import relabel

__all__ = ["PartSeed", "horizontal_parts", "seed_style", "seeded_clusters"]

#: Extra cost of a step between neighbours whose normals differ, per unit of
#: (1 - |cos angle|): moving from a seat onto the table beside it crosses folds.
FOLD_PENALTY = 2.0
#: Horizontal parts may lie this much (m) outside ``part_height`` (a sagging cushion,
#: a floor height map a few centimetres off).
HEIGHT_MARGIN = 0.03
#: Voxels whose neighbourhood is less flat than this (smallest eigenvalue over the sum)
#: are edges or corners and do not belong to a horizontal part.
MAX_PART_VARIATION = 0.08
#: Patches at heights within this (m) and this close (m) are one part (sofa cushions,
#: the two leaves of a table).
MERGE_STEP = 0.05
MERGE_GAP = 0.06
#: Heights within this (m) above a part count as the part itself (noise, thickness);
#: above a top, only what lies this far inside its outline is the table's.
ABOVE_TOLERANCE = 0.02
#: A fragment no part reached joins a part's cluster when it is this close (m) to it
#: and at least this share of it lies in the part's prism.
JOIN_DISTANCE = 0.25
JOIN_SHARE = 0.6
#: Points this close (m) to a voxel of a part, about the gaps of a sparse scan, lie on
#: it: armrests and backrest tops stand outside a seat's box, and the box of an L-shaped
#: seat is a diagonal rectangle that misses the ends of its arms.
FOOTPRINT_GAP = 0.05
#: Long regions are split by dividing the longest link they keep by this, repeatedly.
SPLIT_STEP = 1.25


@dataclass(frozen=True)
class PartSeed:
    """A horizontal patch at part height that seeds a cluster.

    Attributes
    ----------
    voxels : (k,) int
        Indices (into the clustered voxels) of the patch.
    height : float
        Median height above the floor (m).
    area : float
        Estimated surface (m²).
    center : (2,) float
        Centre of its horizontal box.
    axes : (2, 2) float
        Rows: direction of the long and the short side.
    extent : (2,) float
        Long and short side of its horizontal box (m).
    attached : (j, 2) float, optional
        Horizontal positions of the armrests and backrest top that joined a seat:
        its prism reaches around them as well as around its box.
    style : SeedStyle, optional
        How it claims its object (the ontology's seed styles); ``None``: the built-in
        ontology's style for its height (:func:`seed_style`).
    """

    voxels: NDArray[np.int64]
    height: float
    area: float
    center: NDArray[np.float64]
    axes: NDArray[np.float64]
    extent: NDArray[np.float64]
    attached: NDArray[np.float64] | None = field(default=None, repr=False, compare=False)
    style: SeedStyle | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.style is None:
            object.__setattr__(self, "style", seed_style(self.height))

    @cached_property
    def _attached_tree(self) -> cKDTree | None:
        if self.style.attach is None or self.attached is None or len(self.attached) == 0:
            return None
        return cKDTree(self.attached)

    @property
    def kind(self) -> str:
        """The name of its seed style: with the built-in ontology "seat" at seat height
        (Table 4.1: 35–75 cm), "top" above it."""
        return self.style.name

    @property
    def rise(self) -> float:
        """How high (m) above the part its object may reach."""
        return self.style.rise

    @property
    def margin(self) -> float:
        """How far (m) outside the part's outline its object may reach."""
        return self.style.margin

    @property
    def outside_cost(self) -> float:
        """Extra path cost per metre a voxel lies outside the outline."""
        return self.style.outside_cost

    def outside(self, points: NDArray[np.float64], signed: bool = False) -> NDArray[np.float64]:
        """(k,) float: horizontal distance (m) of points outside the outline.

        0 inside, or with ``signed`` minus the distance to the nearest side. For a
        seat with attached armrests, at most the distance to the nearest of their
        voxels beyond ``FOOTPRINT_GAP``.
        """
        out = self._outside_outline(points, signed)
        tree = self._attached_tree
        if tree is not None:
            dist, _ = tree.query(points[:, :2], k=1)
            out = np.minimum(out, np.maximum(dist - FOOTPRINT_GAP, 0.0))
        return out

    def _outside_outline(self, points: NDArray[np.float64], signed: bool) -> NDArray[np.float64]:
        """(k,) float: :meth:`outside` for the part's own outline, attached parts left out."""
        d = np.abs((points[:, :2] - self.center) @ self.axes.T) - self.extent / 2
        out = np.linalg.norm(np.maximum(d, 0.0), axis=1)
        return np.where(out > 0, out, d.max(axis=1)) if signed else out

    def in_prism(
        self, points: NDArray[np.float64], margin: float | None = None
    ) -> NDArray[np.bool_]:
        """(k,) bool: points within ``margin`` of the outline and below ``height + rise``.

        Above a table top only its outline counts: what stands beside it and rises
        above it (a chair's backrest against its edge) is something else. Around the
        armrests and back top attached to a seat, the style's ``attach.outer_margin`` applies.
        """
        margin = self.margin if margin is None else margin
        out = self._outside_outline(points, signed=True)
        above = points[:, 2] > self.height + ABOVE_TOLERANCE
        # The outline of a patch is known to about a voxel: above a top, only what is
        # clearly inside it counts.
        allowed = np.where(above & self.style.inside_above, -ABOVE_TOLERANCE, margin)
        inside = out <= allowed
        tree = self._attached_tree
        if tree is not None:
            # The outer faces of arms and of a thick back drop from their tops: what
            # stands further out (a console table behind the sofa) is something else.
            dist, _ = tree.query(points[:, :2], k=1)
            inside |= dist <= FOOTPRINT_GAP + min(margin, self.style.attach.outer_margin)
        return inside & (points[:, 2] <= self.height + self.rise)

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "height": round(self.height, 4),
            "area": round(self.area, 4),
            "center": [round(float(v), 4) for v in self.center],
            "extent": [round(float(v), 4) for v in self.extent],
            "num_voxels": len(self.voxels),
        }


def seed_style(
    height: float,
    styles: Sequence[tuple[SeedStyle, float]] | None = None,
    *,
    extent: Sequence[float] | None = None,
    sizes: Mapping[str, Sequence[Mapping[str, Gaussian]]] | None = None,
) -> SeedStyle:
    """The seed style a horizontal part at ``height`` (m) takes: the first of ``styles``
    (``(style, highest height)``, lowest first: :meth:`Ontology.seed_styles`) whose height
    reaches it, the last when none does; ``styles`` defaults to the built-in ontology's.

    With ``extent`` (the part's length and width, m) and ``sizes`` (each style's seed
    parts' height, length and width constraints: :meth:`Ontology.seed_sizes`), the first
    style whose height reaches it and one of whose seed parts allows its height, length
    and width within one σ: a conference table's 2.4 × 1.0 m top at 0.74 m is no seat,
    though seats reach 0.75 m (Table 4.1). When no style allows its size, by height alone.

    Examples
    --------
    >>> seed_style(0.46).name, seed_style(0.74).name, seed_style(0.8).name
    ('seat', 'seat', 'top')
    >>> sizes = builtin_ontology().seed_sizes()
    >>> seed_style(0.74, extent=(2.4, 1.0), sizes=sizes).name
    'top'
    >>> seed_style(0.74, extent=(0.5, 0.45), sizes=sizes).name  # a bar chair's seat
    'seat'
    """
    styles = builtin_ontology().seed_styles() if styles is None else styles
    if not styles:
        raise ValueError("no seed styles: the ontology marks no part as a seed")
    if extent is not None and sizes is not None:
        measured = {"height": height, "length": extent[0], "width": extent[1]}
        for style, top in styles:
            if height <= top and any(
                all(abs(float(g.z(measured[k]))) <= 1.0 for k, g in part.items())
                for part in sizes.get(style.name, ())
            ):
                return style
    for style, top in styles:
        if height <= top:
            return style
    return styles[-1][0]


def _outline(xy: NDArray[np.float64]):
    if len(xy) < 3:
        c = xy.mean(axis=0) if len(xy) else np.zeros(2)
        return c, np.eye(2), np.zeros(2)
    mu = xy.mean(axis=0)
    d = xy - mu
    _, vecs = np.linalg.eigh(d.T @ d)
    axes = vecs[:, ::-1].T  # long side first
    proj = d @ axes.T
    lo, hi = proj.min(axis=0), proj.max(axis=0)
    center = mu + ((lo + hi) / 2) @ axes
    return center, axes, hi - lo


def _seed(vox, centers, voxel_area, styles, sizes=None) -> PartSeed:
    vox = np.sort(vox).astype(np.int64)
    c, axes, ext = _outline(centers[vox, :2])
    height = float(np.median(centers[vox, 2]))
    return PartSeed(
        vox,
        height,
        float(len(vox) * voxel_area),
        c,
        axes,
        ext,
        style=seed_style(height, styles, extent=ext, sizes=sizes),
    )


def horizontal_parts(
    centers: NDArray[np.float64],
    normals: NDArray[np.float64],
    graph: sparse.csr_matrix,
    *,
    height: tuple[float, float],
    tilt: float,
    max_step: float,
    min_area: float,
    min_width: float,
    voxel_area: float,
    variation: NDArray[np.float64] | None = None,
    styles: Sequence[tuple[SeedStyle, float]] | None = None,
    sizes: Mapping[str, Sequence[Mapping[str, Gaussian]]] | None = None,
) -> list[PartSeed]:
    """Horizontal patches at part height, largest first.

    Parameters
    ----------
    centers : (m, 3) float
        Voxel centres, levelled (z = height above the floor).
    normals : (m, 3) float
        Voxel normals.
    graph : sparse (m, m)
        Neighbour graph of the voxels.
    height : (float, float)
        Heights (m) where parts are sought.
    tilt : float
        Largest angle (deg) between a voxel normal and vertical.
    max_step : float
        Largest height difference (m) between neighbours of one patch.
    min_area : float
        Smallest patch surface (m²).
    min_width : float
        Smallest short side (m): armrests and the top rails of backrests are
        narrower than any seat or table top.
    voxel_area : float
        Surface (m²) one voxel stands for.
    variation : (m,) float, optional
        Surface variation of each voxel's neighbourhood (see ``estimate_normals``):
        voxels on edges and corners, whose normals are a blend, do not seed parts.
    styles : sequence of (SeedStyle, float), optional
        The ontology's seed styles (:meth:`~ontodetect.ontology.Ontology.seed_styles`),
        which say how each patch claims its object; the built-in ontology's by default.
        No styles, no seeds.
    sizes : mapping, optional
        Each style's seed parts' sizes (:meth:`~ontodetect.ontology.Ontology.seed_sizes`):
        a patch takes its style by its height and size (:func:`seed_style`); ``None``: by
        its height alone.
    """
    styles = builtin_ontology().seed_styles() if styles is None else list(styles)
    if not styles:
        return []
    z = centers[:, 2]
    flat = (
        (np.abs(normals[:, 2]) >= np.cos(np.radians(tilt)))
        & (z >= height[0] - HEIGHT_MARGIN)
        & (z <= height[1] + HEIGHT_MARGIN)
    )
    if variation is not None:
        flat &= variation <= MAX_PART_VARIATION
    m = len(centers)
    coo = graph.tocoo()
    keep = flat[coo.row] & flat[coo.col] & (np.abs(z[coo.row] - z[coo.col]) <= max_step)
    g = sparse.csr_matrix((np.ones(int(keep.sum())), (coo.row[keep], coo.col[keep])), shape=(m, m))
    _, comp = connected_components(g, directed=False)
    comp = relabel(np.where(flat, comp, -1))
    patches = _groups(comp)
    # Patches at one height that (nearly) touch are one part: cushions of a sofa.
    patches = _merge_close(patches, centers)
    seeds = [_seed(p, centers, voxel_area, styles, sizes) for p in patches]
    seeds = [s for s in seeds if s.area >= min_area and s.extent[1] >= min_width]
    seeds = _merge_armrests(seeds, centers, voxel_area, styles)
    seeds.sort(key=lambda s: (-s.area, int(s.voxels[0])))
    return seeds


def _merge_armrests(seeds: list[PartSeed], centers, voxel_area, styles) -> list[PartSeed]:
    """Narrow parts a little above a seat and within its prism are its armrests or back top.

    A part whose style ``attach``es them (a seat) takes, as :class:`Attach` says, parts
    10–45 cm above it and narrower than an arm, mostly within its outline grown a little,
    and the flat top of a thick upholstered back behind a long seat.
    """
    seeds = sorted(seeds, key=lambda s: (-s.area, int(s.voxels[0])))
    merged: dict[int, list[int]] = {}
    taken = set()
    cell = float(np.sqrt(voxel_area))
    for i, low in enumerate(seeds):
        arm = low.style.attach
        if arm is None or i in taken:
            continue
        # Near the seat's voxels counts as on it even outside its box (L-shaped seats).
        low_tree = cKDTree(centers[low.voxels, :2])
        for j, high in enumerate(seeds):
            if j == i or j in taken or j in merged:
                continue
            rise = high.height - low.height
            if not arm.rise[0] <= rise <= arm.rise[1]:
                continue
            if high.extent[1] > arm.width and _width(centers[high.voxels, :2], cell) > arm.width:
                continue
            near, _ = low_tree.query(centers[high.voxels, :2], k=1)
            out = np.minimum(low.outside(centers[high.voxels]), near - FOOTPRINT_GAP)
            beside = np.mean(out <= arm.margin) >= arm.share
            back = (
                low.extent[0] >= arm.back_seat_length
                and high.height <= arm.back_top
                and np.mean(out <= arm.back_reach) >= arm.share
                and arm.back_span * low.extent[0]
                <= high.extent[0]
                <= low.extent[0] + arm.back_overhang
            )
            if beside or back:
                merged.setdefault(i, []).append(j)
                taken.add(j)
    out = []
    for i, sd in enumerate(seeds):
        if i in taken:
            continue
        if i in merged:
            vox = np.concatenate([sd.voxels] + [seeds[j].voxels for j in merged[i]])
            grown = _seed(vox, centers, voxel_area, styles)
            # Keep the seat's own height and outline: the armrests only join its cluster.
            sd = PartSeed(
                grown.voxels,
                sd.height,
                grown.area,
                sd.center,
                sd.axes,
                sd.extent,
                centers[np.concatenate([seeds[j].voxels for j in merged[i]]), :2],
                style=sd.style,
            )
        out.append(sd)
    return out


def _width(xy: NDArray[np.float64], cell: float) -> float:
    """Diameter (m) of the widest disc inside a patch sampled every ``cell`` m.

    Gaps up to ``FOOTPRINT_GAP`` (a sparse scan) are closed first, so a table top
    with holes is still as wide as its short side.
    """
    if len(xy) == 0 or cell <= 0:
        return 0.0
    close = max(1, int(np.ceil(FOOTPRINT_GAP / cell)))
    ij = np.floor((xy - xy.min(axis=0)) / cell).astype(np.int64) + close + 1
    grid = np.zeros(tuple(ij.max(axis=0) + close + 2), dtype=bool)
    grid[ij[:, 0], ij[:, 1]] = True
    grid = ndimage.binary_closing(grid, iterations=close)
    # A strip w cells wide has its largest distance to the outside at about (w + 1) / 2.
    return float(max(2.0 * ndimage.distance_transform_edt(grid).max() - 1.0, 1.0) * cell)


def _groups(labels: NDArray[np.int64]) -> list[NDArray[np.int64]]:
    valid = labels >= 0
    if not valid.any():
        return []
    idx = np.flatnonzero(valid)
    order = np.argsort(labels[idx], kind="stable")
    idx = idx[order]
    cuts = np.flatnonzero(np.diff(labels[idx])) + 1
    return np.split(idx, cuts)


def _merge_close(patches: list[NDArray[np.int64]], centers: NDArray[np.float64]):
    if len(patches) < 2:
        return patches
    heights = np.array([np.median(centers[p, 2]) for p in patches])
    owner = np.concatenate([np.full(len(p), k) for k, p in enumerate(patches)])
    allv = np.concatenate(patches)
    pairs = cKDTree(centers[allv]).query_pairs(MERGE_GAP, output_type="ndarray")
    if len(pairs) == 0:
        return patches
    a, b = owner[pairs[:, 0]], owner[pairs[:, 1]]
    ok = (a != b) & (np.abs(heights[a] - heights[b]) <= MERGE_STEP)
    if not ok.any():
        return patches
    k = len(patches)
    g = sparse.csr_matrix((np.ones(int(ok.sum())), (a[ok], b[ok])), shape=(k, k))
    _, comp = connected_components(g, directed=False)
    merged = {}
    for i, c in enumerate(comp):
        merged.setdefault(int(c), []).append(patches[i])
    return [np.concatenate(v) for _, v in sorted(merged.items())]


def seeded_clusters(
    centers: NDArray[np.float64],
    normals: NDArray[np.float64],
    graph: sparse.csr_matrix,
    core: NDArray[np.bool_],
    seeds: list[PartSeed],
    *,
    max_grow: float,
    max_length: float = np.inf,
    min_radius: float = 0.0,
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Give voxels to the seed closest along the surface within its prism; the rest to regions.

    Parameters
    ----------
    centers, normals : (m, 3) float
    graph : sparse (m, m)
        Neighbour graph with distances.
    core : (m,) bool
        DBSCAN core voxels: only they carry paths (border voxels join their
        nearest core neighbour; voxels with neither are noise).
    seeds : list of PartSeed
    max_grow : float
        Longest path (m) from a seed.
    max_length : float
        Regions no part claimed that are longer than this (m) are split again with
        ever shorter links (down to ``min_radius``): walls with doors, curtains
        and shelves link a whole room, and whatever touches them.
    min_radius : float
        Shortest link (m) when splitting long regions.

    Returns
    -------
    labels : (m,) int
        Cluster per voxel, -1 for noise; clusters numbered largest first.
    seed_of_cluster : (k,) int
        For each cluster, the seed it grew from, or -1 for a region without a part.
    """
    m = len(centers)
    coo = graph.tocoo()
    both = core[coo.row] & core[coo.col]
    r, c, d = coo.row[both], coo.col[both], coo.data[both]
    cos = np.abs((normals[r] * normals[c]).sum(axis=1))
    w = d * (1.0 + FOLD_PENALTY * (1.0 - cos))
    g = sparse.csr_matrix((w, (r, c)), shape=(m, m))

    best = np.full(m, np.inf)
    labels = np.full(m, -1, dtype=np.int64)
    xy_tree = cKDTree(centers[:, :2]) if m else None
    for k, s in enumerate(seeds):
        reach = float(np.hypot(*(s.extent / 2 + s.margin)))
        if s.attached is not None and len(s.attached):
            # Armrests and backrest tops that joined a seat lie beyond its box.
            far = float(np.linalg.norm(s.attached - s.center, axis=1).max())
            reach = max(reach, far + s.margin + FOOTPRINT_GAP)
        near = np.asarray(xy_tree.query_ball_point(s.center, reach), dtype=np.int64)
        near = np.sort(near[core[near]])
        near = near[s.in_prism(centers[near])]
        src = np.flatnonzero(np.isin(near, s.voxels))
        if len(src) == 0:
            continue
        sub = g[near][:, near]
        dist = dijkstra(sub, directed=False, indices=src, min_only=True, limit=max_grow)
        dist = dist + s.outside_cost * s.outside(centers[near])
        better = dist < best[near]
        best[near[better]] = dist[better]
        labels[near[better]] = k
    n_seeds = len(seeds)
    # Core voxels no seed claimed: connected pieces of what is left.
    rest = core & (labels < 0)
    if rest.any():
        keep = rest[r] & rest[c]
        rg = sparse.csr_matrix((np.ones(int(keep.sum())), (r[keep], c[keep])), shape=(m, m))
        _, comp = connected_components(rg, directed=False)
        comp_rest = relabel(np.where(rest, comp, -1))
        comp_rest = _split_long(
            comp_rest, centers, r[keep], c[keep], d[keep], max_length, min_radius
        )
        labels[rest] = comp_rest[rest] + n_seeds
        _join_fragments(labels, centers, seeds, n_seeds)
    # Border voxels: nearest labelled core neighbour.
    border = (~core[coo.row]) & core[coo.col] & (labels[coo.col] >= 0)
    if border.any():
        br, bc, bd = coo.row[border], coo.col[border], coo.data[border]
        order = np.lexsort((bc, bd, br))
        br, bc = br[order], bc[order]
        first = np.r_[True, br[1:] != br[:-1]]
        labels[br[first]] = labels[bc[first]]
    final = relabel(labels)
    k = int(final.max()) + 1 if (final >= 0).any() else 0
    seed_of = np.full(k, -1, dtype=np.int64)
    has = final >= 0
    pairs = np.unique(np.c_[final[has], labels[has]], axis=0)
    seed_of[pairs[:, 0]] = np.where(pairs[:, 1] < n_seeds, pairs[:, 1], -1)
    return final, seed_of


def _longest_side(xy: NDArray[np.float64]) -> float:
    if len(xy) < 2:
        return 0.0
    d = xy - xy.mean(axis=0)
    _, vecs = np.linalg.eigh(d.T @ d)
    return float(np.ptp(d @ vecs, axis=0).max())


def _split_long(labels, centers, r, c, d, max_length, min_radius):
    """Split groups longer than ``max_length`` by dropping their longest links, repeatedly."""
    if not np.isfinite(max_length):
        return labels
    labels = labels.copy()
    m = len(labels)
    next_id = int(labels.max()) + 1 if (labels >= 0).any() else 0
    todo = [(g, float(d.max()) if len(d) else 0.0) for g in _groups(labels)]
    while todo:
        group, link = todo.pop()
        if _longest_side(centers[group, :2]) <= max_length:
            continue
        link /= SPLIT_STEP
        if link < min_radius:
            continue
        inside = np.zeros(m, dtype=bool)
        inside[group] = True
        keep = inside[r] & inside[c] & (d <= link)
        g = sparse.csr_matrix((np.ones(int(keep.sum())), (r[keep], c[keep])), shape=(m, m))
        _, comp = connected_components(g, directed=False)
        parts = _groups(relabel(np.where(inside, comp, -1)))
        for k, part in enumerate(parts):
            if k > 0:
                labels[part] = next_id
                next_id += 1
            todo.append((part, link))
    return relabel(labels)


def _join_fragments(labels, centers, seeds, n_seeds) -> None:
    """Fragments lying mostly in a part's prism, close to its cluster, join that cluster.

    A seat's cluster reaches past the seat's prism when its arms do: the part of a
    sofa's back between two arms, or an arm at the far end of a sparse seat of which
    only a patch was found, lies within the box of what the seat claimed.
    """
    claimed = labels >= 0
    seeded = claimed & (labels < n_seeds)
    if not seeded.any():
        return
    tree = cKDTree(centers[seeded])
    owner = labels[seeded]
    boxes: dict[int, tuple[PartSeed, PartSeed]] = {}

    def footprints(k: int) -> tuple[PartSeed, PartSeed]:
        # The seat's prism around the box of its whole cluster, and around the box
        # of what it claimed at its own height (the seat as scanned, of which the
        # part may be only a dense patch).
        if k not in boxes:
            s = seeds[k]
            mine = centers[labels == k]
            level = mine[np.abs(mine[:, 2] - s.height) <= s.style.low.level]
            boxes[k] = tuple(
                PartSeed(s.voxels, s.height, s.area, *_outline(pts[:, :2]), style=s.style)
                for pts in (mine, level if len(level) else mine)
            )
        return boxes[k]

    for frag in _groups(np.where(labels >= n_seeds, labels, -1)):
        dist, idx = tree.query(centers[frag], k=1, distance_upper_bound=JOIN_DISTANCE)
        hit = np.isfinite(dist)
        if not hit.any():
            continue
        candidates = np.unique(owner[idx[hit]])
        best, best_d = -1, np.inf
        for k in candidates:
            inside = seeds[k].in_prism(centers[frag])
            low = seeds[k].style.low
            if low is not None and seeds[k].height <= low.up_to:
                # Within FOOTPRINT_GAP of its whole box (a back between two arms), or within
                # ``low.margin`` of what it claimed at its own height.
                whole, level = footprints(int(k))
                inside |= whole.in_prism(centers[frag], margin=FOOTPRINT_GAP)
                inside |= level.in_prism(centers[frag], margin=low.margin)
            share = float(np.mean(inside))
            dk = float(dist[hit][owner[idx[hit]] == k].min())
            if share >= JOIN_SHARE and dk < best_d:
                best, best_d = int(k), dk
        if best >= 0:
            labels[frag] = best
