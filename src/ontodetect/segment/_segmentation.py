"""Candidate clusters with their planes (Alg. 1 steps 7–9) and the :class:`Segmentation` result."""

from __future__ import annotations

import dataclasses
import math
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import ConvexHull, QhullError

from .._progress import progress
from ..cloud import PointCloud, point_cloud, sensor_position
from ..config import Config
from ..errors import InvalidParameterError
from ..ontology import Ontology, builtin_ontology
from ..preprocess import Ground, PreparedScene, graph_normals, prepare, scene_surface
from ._cluster import (
    core_neighbors,
    dbscan,
    euclidean_clusters,
    mesh_graph,
    radius_graph,
    region_growing,
)
from ._parts import PartSeed, horizontal_parts, seeded_clusters
from .planes import curved_patches, extract_planes, level_surfaces, plane_relations, seat_layer

__all__ = ["Box", "Cluster", "Segmentation", "cluster", "clusters_of_voxels", "segment"]

FORMAT = "ontodetect.segmentation/1"
#: Normals that decide which voxels are flat parts come from neighbours within this many
#: sampling spacings.
PART_NORMAL_SPACINGS = 2.0
#: Normals for parts are computed for voxels this far (m) beyond ``part_height`` too.
PART_BAND_MARGIN = 0.05
#: Long regions are split with links no shorter than this many sampling spacings.
MIN_SPLIT_SPACINGS = 1.5
#: Flags a cluster can carry, with what they mean.
FLAGS = {
    "too_small": "surface below cluster.min_surface",
    "too_short": "longest side below cluster.length[0]",
    "too_long": "a side above cluster.length[1]",
    "few_planes": "fewer MSAC planes than cluster.min_planes",
}
#: Plane attributes written by ``to_dict`` (when the plane object has them).
PLANE_FEATURES = (
    "normal",
    "offset",
    "centroid",
    "axes",
    "length",
    "width",
    "area",
    "tilt",
    "height",
    "z_min",
    "z_max",
    "density",
    "color_mean",
    "color_std",
    "num_points",
    "rms",
)
#: Relation attributes written by ``to_dict``.
RELATION_FEATURES = ("i", "j", "angle", "distance", "vertical_gap", "i_above_j", "xy_overlap")


# -- boxes --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Box:
    """An upright box in the levelled frame.

    Attributes
    ----------
    center : (3,) float
    size : (3,) float
        Length (along ``yaw``), breadth, height; length >= breadth.
    yaw : float
        Angle (radians, in [0, pi)) of the length axis from the x axis.
    """

    center: NDArray[np.float64]
    size: NDArray[np.float64]
    yaw: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "center": [round(float(v), 5) for v in self.center],
            "size": [round(float(v), 5) for v in self.size],
            "yaw": round(self.yaw, 5),
        }


def upright_box(points: ArrayLike) -> Box:
    """The smallest-area upright box around points (rotating calipers on the xy hull).

    Examples
    --------
    >>> import numpy as np
    >>> b = upright_box([[0, 0, 0], [2, 0, 0], [2, 1, 1], [0, 1, 1]])
    >>> b.size.round(3).tolist(), round(b.yaw, 3)
    ([2.0, 1.0, 1.0], 0.0)
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(pts) == 0:
        return Box(np.zeros(3), np.zeros(3), 0.0)
    z0, z1 = float(pts[:, 2].min()), float(pts[:, 2].max())
    xy = np.unique(pts[:, :2], axis=0)
    hull = xy
    if len(xy) >= 3:
        try:
            hull = xy[ConvexHull(xy).vertices]
        except QhullError:  # collinear points
            hull = xy
    if len(hull) >= 2:
        edges = np.diff(np.vstack([hull, hull[:1]]), axis=0)
        angles = np.unique(np.mod(np.arctan2(edges[:, 1], edges[:, 0]), np.pi / 2))
    else:
        angles = np.zeros(1)
    c, s = np.cos(angles), np.sin(angles)
    # (angles, hull points) coordinates along each candidate frame.
    u = hull[:, 0][None] * c[:, None] + hull[:, 1][None] * s[:, None]
    v = -hull[:, 0][None] * s[:, None] + hull[:, 1][None] * c[:, None]
    areas = np.ptp(u, axis=1) * np.ptp(v, axis=1)
    k = int(np.argmin(areas))
    a, lu, lv = float(angles[k]), float(np.ptp(u[k])), float(np.ptp(v[k]))
    cu, cv = (u[k].max() + u[k].min()) / 2, (v[k].max() + v[k].min()) / 2
    cx, cy = cu * math.cos(a) - cv * math.sin(a), cu * math.sin(a) + cv * math.cos(a)
    if lv > lu:
        lu, lv, a = lv, lu, a + math.pi / 2
    return Box(
        np.array([cx, cy, (z0 + z1) / 2]), np.array([lu, lv, z1 - z0]), float(math.fmod(a, math.pi))
    )


# -- clusters -----------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Cluster:
    """A candidate object: its voxels and points, box, MSAC planes and flags.

    Attributes
    ----------
    id : int
        Position in the segmentation (largest cluster first).
    voxels : (k,) int
        Indices into the prepared scene's voxels.
    point_indices : (p,) int
        Indices of the input cloud's points (rows of ``prepared.cloud``).
    centers : (k, 3) float
        Voxel centres, levelled frame.
    box : Box
        Upright box, levelled frame.
    planes : list
        ``ontodetect.segment.planes.Plane`` objects; inliers index ``centers``.
    relations : list
        ``PlaneRelation`` between the planes.
    flags : dict of str to str
        Flag -> reason (see :data:`FLAGS`); empty for a cluster within every limit.
    parts : list of PartSeed
        The horizontal parts it grew from (empty for a density region).
    surface : float
        Estimated surface (m²).
    patches : list
        With ``planes.curved``, its curved surfaces (``ontodetect.segment.planes.Patch``:
        planes joined along seams); the scoring's parts may take them as planes.
    patch_relations : list
        ``PlaneRelation`` between every two of ``planes`` and ``patches`` (empty without
        patches).
    """

    id: int
    voxels: NDArray[np.int64]
    point_indices: NDArray[np.int64]
    centers: NDArray[np.float64]
    box: Box
    planes: list[Any] = field(default_factory=list)
    relations: list[Any] = field(default_factory=list)
    flags: dict[str, str] = field(default_factory=dict)
    parts: list[PartSeed] = field(default_factory=list)
    surface: float = 0.0
    patches: list[Any] = field(default_factory=list)
    patch_relations: list[Any] = field(default_factory=list)

    @property
    def num_points(self) -> int:
        return len(self.point_indices)

    @property
    def length(self) -> float:
        """Longest horizontal side of the box (m)."""
        return float(self.box.size[0])

    @property
    def breadth(self) -> float:
        """Shortest horizontal side of the box (m)."""
        return float(self.box.size[1])

    @property
    def height(self) -> float:
        """Top of the cluster above the floor (m)."""
        return float(self.centers[:, 2].max()) if len(self.centers) else 0.0

    @property
    def bottom(self) -> float:
        """Lowest point of the cluster above the floor (m)."""
        return float(self.centers[:, 2].min()) if len(self.centers) else 0.0

    @property
    def flagged(self) -> bool:
        return bool(self.flags)

    @property
    def relations_by_pair(self) -> dict[tuple[int, int], Any]:
        """Relations keyed by plane pair ``(i, j)`` with i < j."""
        return {(min(r.i, r.j), max(r.i, r.j)): r for r in self.relations}

    @property
    def scored_planes(self) -> list[Any]:
        """What the ontology's parts may take: the planes, then the curved patches."""
        return [*self.planes, *self.patches]

    @property
    def scored_relations(self) -> dict[tuple[int, int], Any]:
        """Relations between every two of :attr:`scored_planes`, keyed ``(i, j)``, i < j."""
        if not self.patches:
            return self.relations_by_pair
        return {(min(r.i, r.j), max(r.i, r.j)): r for r in self.patch_relations}

    def to_dict(self, index: NDArray[np.int64] | None = None) -> dict[str, Any]:
        """JSON-ready; ``point_indices`` are mapped through ``index`` (file rows) if given."""
        pts = self.point_indices if index is None else index[self.point_indices]
        return {
            "id": self.id,
            "num_points": self.num_points,
            "num_voxels": len(self.voxels),
            "surface": round(self.surface, 5),
            "box": self.box.to_dict(),
            "length": round(self.length, 5),
            "breadth": round(self.breadth, 5),
            "height": round(self.height, 5),
            "bottom": round(self.bottom, 5),
            "flags": dict(self.flags),
            "parts": [p.to_dict() for p in self.parts],
            "planes": [plane_to_dict(p) for p in self.planes],
            "relations": [_plain(r, RELATION_FEATURES) for r in self.relations],
            "point_indices": pts.tolist(),
        }


def _jsonable(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return np.round(v, 6).tolist() if v.dtype.kind == "f" else v.tolist()
    if isinstance(v, (np.floating, float)):
        return round(float(v), 6)
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (np.bool_,)):
        return bool(v)
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    return v


def _plain(obj: Any, names: Sequence[str]) -> dict[str, Any]:
    return {k: _jsonable(getattr(obj, k)) for k in names if hasattr(obj, k)}


def plane_to_dict(plane: Any) -> dict[str, Any]:
    """The features of a plane as plain values (its own ``to_dict`` if it has one)."""
    own = getattr(plane, "to_dict", None)
    if callable(own):
        d = dict(own())
        d.pop("inliers", None)
        return {k: _jsonable(v) for k, v in d.items()}
    return _plain(plane, PLANE_FEATURES)


# -- the result ---------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Segmentation(Sequence[Cluster]):
    """Clusters of a prepared scene; a sequence of :class:`Cluster`.

    Attributes
    ----------
    clusters : list of Cluster
    prepared : PreparedScene
    voxel_labels : (m,) int
        Cluster of every voxel of the prepared scene, -1 for none.
    radius : float
        Neighbourhood radius actually used (m).
    method : str
    config : Config
    """

    clusters: list[Cluster]
    prepared: PreparedScene
    voxel_labels: NDArray[np.int64]
    radius: float
    method: str
    config: Config

    def __len__(self) -> int:
        return len(self.clusters)

    def __getitem__(self, i):  # type: ignore[override]
        return self.clusters[i]

    def __iter__(self) -> Iterator[Cluster]:
        return iter(self.clusters)

    def labels_per_point(self) -> NDArray[np.int64]:
        """(n,) int: cluster id of every input point, -1 for none (outliers included)."""
        p2v = self.prepared.point_to_voxel
        lab = np.append(self.voxel_labels, -1)  # index -1 -> the appended "none"
        return lab[p2v]

    def planes_per_point(self) -> NDArray[np.int64]:
        """(n,) int: global plane id of every input point (see ``to_dict``), -1 for none."""
        per_voxel = np.full(len(self.prepared.voxels) + 1, -1, dtype=np.int64)
        pid = 0
        for c in self.clusters:
            for p in c.planes:
                per_voxel[c.voxels[np.asarray(p.inliers, dtype=np.int64)]] = pid
                pid += 1
        return per_voxel[self.prepared.point_to_voxel]

    def to_dict(self, *, with_points: bool = True) -> dict[str, Any]:
        """JSON-ready: clusters, planes with features, relations, frame and configuration.

        ``point_indices`` are rows of the input file (``cloud.index``); plane ids in
        ``planes_per_point`` follow the order of clusters, then planes.
        """
        index = np.asarray(self.prepared.cloud.index)
        clusters = []
        pid = 0
        for c in self.clusters:
            d = c.to_dict(index)
            if not with_points:
                d.pop("point_indices")
            for p in d["planes"]:
                p["id"] = pid
                pid += 1
            d["box_center_input"] = [
                round(float(v), 5) for v in self.prepared.from_level(c.box.center[None])[0]
            ]
            clusters.append(d)
        prep = self.prepared
        return {
            "format": FORMAT,
            "source": prep.cloud.meta.get("source"),
            "num_points": prep.num_points,
            "frame": {
                "up": [float(v) for v in prep.up],
                "ground_z": prep.floor_z,
                "scale": prep.scale,
                "to_level": prep.to_level.tolist(),
            },
            "method": self.method,
            "radius": self.radius,
            "num_clusters": len(self.clusters),
            "num_flagged": sum(c.flagged for c in self.clusters),
            "prepare": prep.summary(),
            "clusters": clusters,
            "config": self.config.to_dict(),
        }


# -- the stage ----------------------------------------------------------------------------
def effective_radius(radius: float, spacing: float, factor: float) -> float:
    """The clustering radius: ``radius``, raised to ``factor * spacing`` for sparse scans.

    Examples
    --------
    >>> effective_radius(0.05, 0.034, 2.5)
    0.085
    """
    return float(max(radius, factor * spacing))


def _flags(surface: float, box: Box, planes: list | None, cfg) -> dict[str, str]:
    flags = {}
    lo, hi = cfg.length
    longest = float(max(box.size))
    if surface < cfg.min_surface:
        flags["too_small"] = f"surface {surface:.3f} m² < {cfg.min_surface:g} m²"
    if longest < lo:
        flags["too_short"] = f"longest side {longest:.2f} m < {lo:g} m"
    if longest > hi:
        flags["too_long"] = f"side {longest:.2f} m > {hi:g} m"
    if planes is not None and len(planes) < cfg.min_planes:
        flags["few_planes"] = f"{len(planes)} planes < {cfg.min_planes}"
    return flags


def _by_size(mode: str, prepared: PreparedScene) -> bool:
    """Whether horizontal parts take their seed style by size as well as height
    (``cluster.seed_by_size``): everywhere, nowhere, or in single views (a scan with its
    sensor's position)."""
    return mode == "on" or (mode == "views" and sensor_position(prepared.cloud) is not None)


def cluster(
    prepared: PreparedScene,
    config: Config | None = None,
    *,
    seed: int | None = 0,
    fit_planes: bool = True,
    ontology: Ontology | None = None,
) -> Segmentation:
    """Cluster the object voxels of a prepared scene and fit planes in each cluster.

    Parameters
    ----------
    prepared : PreparedScene
        From :func:`ontodetect.preprocess.prepare`.
    config : Config, optional
        ``config.cluster`` and ``config.planes`` drive this step; by default the
        configuration the scene was prepared with.
    seed : int, optional
        Seed of the MSAC plane fits (each cluster gets its own stream, so results
        do not depend on the number or order of clusters).
    fit_planes : bool
        Fit MSAC planes in every cluster (False: clusters only, for tuning).
    ontology : Ontology, optional
        Its parts marked ``seed`` say which horizontal patches seed clusters and how
        (``method: parts``); the built-in ontology by default.

    Returns
    -------
    Segmentation
        A sequence of :class:`Cluster`, largest first.
    """
    if not isinstance(prepared, PreparedScene):
        raise InvalidParameterError(
            "prepared", "a PreparedScene (see prepare())", type(prepared).__name__
        )
    config = config or prepared.config
    cc, pc = config.cluster, config.planes
    obj = np.flatnonzero(prepared.object_mask)
    centers = prepared.centers[obj]
    spacing = prepared.spacing
    voxel_area = spacing**2
    radius = effective_radius(cc.radius, spacing, cc.spacing_factor)
    min_pts = core_neighbors(radius, spacing, cc.core_fill)

    with progress("Clustering", total=None):
        graph = radius_graph(centers, radius) if len(centers) > 1 else None
        if graph is not None and cc.adjacency == "mesh":
            # Neighbours along the scanned surface only (Alg. 1 step 2 meshes the scan).
            graph = mesh_graph(centers, scene_surface(prepared, obj), radius, graph=graph)
        seeds: list[PartSeed] = []
        seed_of = np.zeros(0, dtype=np.int64)
        if len(centers) < 2:
            labels = np.zeros(len(centers), dtype=np.int64)
        elif cc.method == "euclidean":
            labels = euclidean_clusters(centers, radius, graph=graph)
        elif cc.method == "dbscan":
            labels = dbscan(centers, radius, min_pts, graph=graph)
        else:
            # The clustering graph lists every voxel's neighbours: normals come free.
            normals, _ = graph_normals(centers, graph)
            if cc.method == "region_growing":
                labels = region_growing(centers, normals, radius, cc.smoothness, graph=graph)
            else:
                core = np.diff(graph.indptr) + 1 >= min_pts
                # Parts end where the surface bends: their voxels need normals from a
                # tighter neighbourhood, which a blend across an edge cannot pass for flat.
                # Only voxels near part height (and their neighbours) need them.
                z = centers[:, 2]
                lo, hi = cc.part_height
                band = np.flatnonzero(
                    (z >= lo - radius - PART_BAND_MARGIN) & (z <= hi + radius + PART_BAND_MARGIN)
                )
                tight = graph[band][:, band]
                tight.data[tight.data > PART_NORMAL_SPACINGS * spacing] = 0.0
                tight.eliminate_zeros()
                part_normals = np.tile([0.0, 0.0, 1.0], (len(centers), 1))
                part_variation = np.full(len(centers), 1.0 / 3.0)
                part_normals[band], part_variation[band] = graph_normals(centers[band], tight)
                rules = ontology or builtin_ontology()
                seeds = horizontal_parts(
                    centers,
                    part_normals,
                    graph,
                    height=cc.part_height,
                    tilt=cc.part_tilt,
                    max_step=cc.max_part_step,
                    min_area=cc.min_part_area,
                    min_width=cc.min_part_width,
                    voxel_area=voxel_area,
                    variation=part_variation,
                    styles=rules.seed_styles(),
                    sizes=rules.seed_sizes() if _by_size(cc.seed_by_size, prepared) else None,
                )
                labels, seed_of = seeded_clusters(
                    centers,
                    normals,
                    graph,
                    core,
                    seeds,
                    max_grow=cc.max_grow,
                    max_length=cc.length[1],
                    min_radius=MIN_SPLIT_SPACINGS * spacing,
                )

    voxel_labels = np.full(len(prepared.voxels), -1, dtype=np.int64)
    k = int(labels.max()) + 1 if len(labels) and (labels >= 0).any() else 0
    if k == 0:
        return Segmentation([], prepared, voxel_labels, radius, cc.method, config)
    order = np.argsort(labels, kind="stable")
    sizes = np.bincount(labels[labels >= 0], minlength=k)
    starts = np.r_[0, np.cumsum(sizes)[:-1]] + int((labels < 0).sum())
    streams = np.random.SeedSequence(seed).spawn(k)
    min_plane_points = max(3, math.ceil(pc.min_area / voxel_area))
    point_groups = _points_by_voxel(prepared)
    clusters: list[Cluster] = []
    with progress("Fitting planes", total=k) as advance:
        for c in range(k):
            local = np.sort(order[starts[c] : starts[c] + sizes[c]])
            parts = [seeds[int(seed_of[c])]] if len(seed_of) > c and seed_of[c] >= 0 else []
            clusters.append(
                _build_cluster(
                    prepared,
                    config,
                    c,
                    obj[local],
                    centers[local],
                    np.random.default_rng(streams[c]),
                    radius,
                    point_groups,
                    parts,
                    fit_planes=fit_planes,
                    min_plane_points=min_plane_points,
                )
            )
            advance(1)
    if cc.drop_flagged:
        clusters = [c for c in clusters if not c.flagged]
        clusters = [dataclasses.replace(c, id=i) for i, c in enumerate(clusters)]
    for c in clusters:
        voxel_labels[c.voxels] = c.id
    return Segmentation(clusters, prepared, voxel_labels, radius, cc.method, config)


def _build_cluster(
    prepared: PreparedScene,
    config: Config,
    cid: int,
    vox: NDArray[np.int64],
    pts: NDArray[np.float64],
    rng: np.random.Generator,
    radius: float,
    point_groups: Any,
    parts: list[PartSeed],
    *,
    fit_planes: bool,
    min_plane_points: int,
) -> Cluster:
    """One cluster of the voxels ``vox`` (centres ``pts``): its box, MSAC planes, flags."""
    cc, pc = config.cluster, config.planes
    cols = None if prepared.colors is None else prepared.colors[vox]
    planes, relations, patches, patch_relations = [], [], [], []
    box = upright_box(pts)
    surface = len(vox) * prepared.spacing**2
    # Clusters flagged too small get no planes: nothing will be made of them.
    if fit_planes and surface >= cc.min_surface:
        normals = variation = None
        if pc.hypotheses == "surface" and len(pts) > 1:
            normals, variation = graph_normals(pts, radius_graph(pts, radius))
        planes = extract_planes(
            pts,
            cols,
            threshold=pc.threshold,
            min_points=min_plane_points,
            min_extent=pc.min_extent,
            max_planes=pc.max_planes,
            max_trials=pc.max_trials,
            floor_z=0.0,
            connectivity=radius,
            rng=rng,
            normals=normals,
            variation=variation,
            level_first=pc.level_first,
        )
        relations = plane_relations(pts, planes) if len(planes) > 1 else []
        if pc.curved and relations:
            patches = curved_patches(pts, planes, relations, cols, rng=rng)
        if pc.level_surfaces and relations:
            patches = [*patches, *level_surfaces(pts, planes, relations, cols, rng=rng)]
        if pc.seat_layer and len(pts) > 1:
            layer = seat_layer(
                pts, planes,
                lambda: graph_normals(pts, radius_graph(pts, radius))[0]
                if normals is None else normals,
                cols, threshold=pc.threshold, min_points=min_plane_points,
                connectivity=radius, rng=rng,
            )  # fmt: skip
            if layer is not None:
                patches = [*patches, layer]
        if patches:
            # The planes' own pairs are measured: only those with a patch are new.
            added = plane_relations(pts, [*planes, *patches], since=len(planes))
            patch_relations = [*relations, *added]
    flags = _flags(surface, box, planes if fit_planes else None, cc)
    return Cluster(
        id=cid,
        voxels=vox,
        point_indices=point_groups(vox),
        centers=pts,
        box=box,
        planes=list(planes),
        relations=list(relations),
        flags=flags,
        parts=parts,
        surface=float(surface),
        patches=patches,
        patch_relations=patch_relations,
    )


def clusters_of_voxels(
    prepared: PreparedScene,
    voxel_sets: Sequence[NDArray[np.int64]],
    config: Config | None = None,
    *,
    seed: int | None = 0,
    radius: float | None = None,
    parts: Sequence[list[PartSeed]] | None = None,
) -> list[Cluster]:
    """A :class:`Cluster` (box, MSAC planes, flags) for each given set of voxels, as
    :func:`cluster` makes them; numbered in order. Each set's plane fits draw from a
    stream seeded by ``seed`` and the set itself, so a candidate gets the same planes
    whatever else is proposed beside it."""
    config = config or prepared.config
    spacing = prepared.spacing
    radius = radius or effective_radius(
        config.cluster.radius, spacing, config.cluster.spacing_factor
    )
    min_plane_points = max(3, math.ceil(config.planes.min_area / spacing**2))
    point_groups = _points_by_voxel(prepared)
    out = []
    for i, vox in enumerate(voxel_sets):
        vox = np.unique(np.asarray(vox, dtype=np.int64))
        key = zlib.crc32(vox.tobytes())
        rng = np.random.default_rng(np.random.SeedSequence([seed or 0, key]))
        out.append(
            _build_cluster(
                prepared,
                config,
                i,
                vox,
                prepared.centers[vox],
                rng,
                radius,
                point_groups,
                list(parts[i]) if parts is not None else [],
                fit_planes=True,
                min_plane_points=min_plane_points,
            )
        )
    return out


def _points_by_voxel(prepared: PreparedScene):
    """A function voxel indices -> sorted input point indices, from one sort of the map."""
    p2v = prepared.point_to_voxel
    order = np.argsort(p2v, kind="stable")
    sorted_v = p2v[order]
    m = len(prepared.voxels)
    starts = np.searchsorted(sorted_v, np.arange(m + 1))

    def points(vox: NDArray[np.int64]) -> NDArray[np.int64]:
        s, e = starts[vox], starts[vox + 1]
        lengths = e - s
        if lengths.sum() == 0:
            return np.zeros(0, dtype=np.int64)
        idx = np.repeat(s - np.r_[0, np.cumsum(lengths)[:-1]], lengths) + np.arange(
            int(lengths.sum())
        )
        return np.sort(order[idx]).astype(np.int64)

    return points


def segment(
    cloud: PointCloud | ArrayLike,
    config: Config | None = None,
    *,
    seed: int | None = 0,
    up: str | ArrayLike | None = None,
    scale: float | None = None,
    fit_planes: bool = True,
    ground: Ground | None = None,
    ontology: Ontology | None = None,
) -> Segmentation:
    """Prepare a scan and cluster it: the one-call API of steps 1–9 of Algorithm 1.

    Parameters
    ----------
    cloud : PointCloud or (n, 3) float
    config : Config, optional
        Defaults from Table 4.1.
    seed : int, optional
        Seed of every random step.
    up : str or (3,) float, optional
        Up axis of the input (``"z"``, ``"-y"``, ``"auto"``...); ``config.prepare.up``
        by default.
    scale : float, optional
        Scale factor ``k_s``.
    fit_planes : bool
        Fit MSAC planes in every cluster.
    ground : Ground, optional
        This cloud's :func:`ontodetect.preprocess.find_ground`, shared by passes that
        differ only in ``prepare.turn`` (see :func:`ontodetect.preprocess.prepare`).
    ontology : Ontology, optional
        Which parts seed clusters (see :func:`cluster`); the built-in one by default.

    Returns
    -------
    Segmentation

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> floor = np.c_[rng.random((20000, 2)) * 4, np.zeros(20000)]
    >>> box = np.c_[rng.random((3000, 2)) * 0.5 + 1, rng.random(3000) * 0.4 + 0.3]
    >>> seg = segment(np.vstack([floor, box]), fit_planes=False)
    >>> len(seg), seg.labels_per_point()[-1]
    (1, np.int64(0))
    """
    config = config or Config()
    if not isinstance(cloud, PointCloud):
        cloud = point_cloud(cloud)
    prepared = prepare(cloud, config, up=up, scale=scale, seed=seed, ground=ground)
    return cluster(prepared, config, seed=seed, fit_planes=fit_planes, ontology=ontology)
