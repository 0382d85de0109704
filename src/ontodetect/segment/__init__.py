"""Candidate object clusters and their planes (thesis §3.3, Algorithm 1 steps 7–9).

:func:`segment` prepares a scan and clusters it in one call; :func:`cluster` works on
a :class:`~ontodetect.preprocess.PreparedScene`. Clustering runs on the voxel grid:
DBSCAN, Euclidean clustering or smooth region growing (:func:`dbscan`,
:func:`euclidean_clusters`, :func:`region_growing`), or, by default, density
regions split around seat and table-top hypotheses (:func:`horizontal_parts`,
:func:`seeded_clusters`), which keeps chairs tucked under a table apart from it.
Every cluster gets its MSAC planes (``ontodetect.segment.planes``) and the relations
between them, an upright box, and flags when it breaks the limits of Table 4.1.
"""

from __future__ import annotations

from ._candidates import (
    GENERATORS,
    Proposal,
    Segments,
    cut_shares,
    felzenszwalb,
    oversegment,
    propose,
)
from ._cluster import (
    core_neighbors,
    dbscan,
    euclidean_clusters,
    mesh_graph,
    radius_graph,
    region_growing,
    relabel,
)
from ._measure import (
    covered_above,
    describe_cluster,
    describe_clusters,
    hidden_heights,
    open_below,
    runs_on,
    seen_below,
    shelter_heights,
    sight_shelters,
    standing_base,
    sunk_below,
    wall_gaps,
)
from ._parts import PartSeed, horizontal_parts, seed_style, seeded_clusters
from ._segmentation import (
    FLAGS,
    Box,
    Cluster,
    Segmentation,
    cluster,
    clusters_of_voxels,
    effective_radius,
    plane_to_dict,
    segment,
    upright_box,
)

__all__ = [
    "FLAGS",
    "GENERATORS",
    "Box",
    "Cluster",
    "PartSeed",
    "Proposal",
    "Segmentation",
    "Segments",
    "cluster",
    "clusters_of_voxels",
    "core_neighbors",
    "covered_above",
    "cut_shares",
    "dbscan",
    "describe_cluster",
    "describe_clusters",
    "effective_radius",
    "euclidean_clusters",
    "felzenszwalb",
    "hidden_heights",
    "horizontal_parts",
    "mesh_graph",
    "open_below",
    "oversegment",
    "plane_to_dict",
    "propose",
    "radius_graph",
    "region_growing",
    "relabel",
    "runs_on",
    "seed_style",
    "seeded_clusters",
    "seen_below",
    "segment",
    "shelter_heights",
    "sight_shelters",
    "standing_base",
    "sunk_below",
    "upright_box",
    "wall_gaps",
]
