"""Preparation of a scan for object search (thesis §3.2–3.3, Algorithm 1 steps 1–6).

:func:`prepare` runs every step and returns a :class:`PreparedScene`:

0. a single camera frame only: its depth steps smoothed over the pixel grid
   (:func:`smooth_depth`);
1. scale recovery ``X_sc = k_s X_c`` (:func:`scale_from_travel`, :func:`guess_scale`);
2. denoising on the voxel grid (:func:`denoise`, :func:`statistical_outlier_mask`,
   :func:`radius_outlier_mask`, :func:`far_outlier_mask`);
3. gravity and ground (:func:`estimate_up`, :func:`find_floor`, :func:`level_transform`):
   the cloud is rotated so that z is up and translated so that the floor is at z = 0;
4. voxel grid average (:func:`voxelize`) with a map from every input point to its voxel;
5. planar smoothing (:func:`smooth_surface`), on request, or when the floor scatters so much
   (:func:`surface_scatter`) that more than a quarter of a plane's points would fall outside
   the plane inlier distance;
6. floor, walls and ceiling (:func:`find_structure`), kept apart from objects, and the
   altitude cut-off.

Surface reconstruction (Alg. 1 step 2, :func:`reconstruct_surface`, :func:`scene_surface`)
makes a triangle mesh of the voxel cloud on request: for ``detect --mesh`` and for
``cluster.adjacency: mesh``.

Every step is also a public function on arrays. :func:`find_ground` runs steps 1–3
alone (up to the floor plane, nothing that depends on ``prepare.turn``), so that the
passes of a vote over one scan share them (``prepare(..., ground=...)``).
"""

from __future__ import annotations

from .._units import estimate_spacing, guess_units
from ._denoise import denoise, far_outlier_mask, radius_outlier_mask, statistical_outlier_mask
from ._depth import smooth_depth
from ._floor import FloorMap, floor_height_map
from ._gravity import (
    AXES,
    CellPlanes,
    FloorFit,
    as_direction,
    cell_planes,
    estimate_up,
    find_floor,
    level_transform,
    manhattan_axes,
    rotation_between,
)
from ._prepare import (
    Ground,
    GroundPlane,
    PreparedScene,
    find_ground,
    guess_scale,
    local_origin,
    prepare,
    scale_from_travel,
    surface_spacing,
)
from ._quarter import quarter_matrix, quarter_turns, turn_about_z, turn_quarters, wall_yaw
from ._reconstruct import (
    MESH_METHODS,
    SENSOR_HEIGHT,
    SurfaceMesh,
    reconstruct_surface,
    scene_surface,
)
from ._structure import STRUCTURE_LABELS, StructurePlane, find_structure, floor_area
from ._surface import estimate_normals, graph_normals, smooth_surface, surface_scatter
from ._voxel import VoxelGrid, grouped_covariance, voxelize

__all__ = [
    "AXES",
    "MESH_METHODS",
    "SENSOR_HEIGHT",
    "STRUCTURE_LABELS",
    "CellPlanes",
    "FloorFit",
    "FloorMap",
    "Ground",
    "GroundPlane",
    "PreparedScene",
    "StructurePlane",
    "SurfaceMesh",
    "VoxelGrid",
    "as_direction",
    "cell_planes",
    "denoise",
    "estimate_normals",
    "estimate_spacing",
    "estimate_up",
    "far_outlier_mask",
    "find_floor",
    "find_ground",
    "find_structure",
    "floor_area",
    "floor_height_map",
    "graph_normals",
    "grouped_covariance",
    "guess_scale",
    "guess_units",
    "level_transform",
    "local_origin",
    "manhattan_axes",
    "prepare",
    "quarter_matrix",
    "quarter_turns",
    "radius_outlier_mask",
    "reconstruct_surface",
    "rotation_between",
    "scale_from_travel",
    "scene_surface",
    "smooth_depth",
    "smooth_surface",
    "statistical_outlier_mask",
    "surface_scatter",
    "surface_spacing",
    "turn_about_z",
    "turn_quarters",
    "voxelize",
    "wall_yaw",
]
