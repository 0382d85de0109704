"""Generic CAD model replacement (thesis §3.7): fit upright generic models to detected objects.

- :mod:`~ontodetect.cad._models`: :class:`CadModel` (a thin profile for matching, a
  full model for display), :class:`ModelLibrary`, :func:`builtin_library` (chairs,
  armchair, sofas, tables, desk), seeded surface sampling and grid averaging.
- :mod:`~ontodetect.cad._manifest`: your own STL/OBJ/PLY/GLB models through a YAML
  manifest (:func:`load_manifest`).
- :mod:`~ontodetect.cad._icp`: ground-constrained ICP (:func:`ground_icp`): x, y and
  yaw only, solved in closed form at every step (:func:`yaw_procrustes`) with robust
  weights (:func:`robust_weights`).
- :mod:`~ontodetect.cad._fit`: choosing and fitting models (:func:`fit_object`,
  :func:`fit_detections`, :func:`fit_document`), the ``cad`` entry of detections.json
  (:func:`cad_dict`) and the object map (:func:`write_object_map`).

Examples
--------
>>> import numpy as np
>>> from ontodetect.cad import builtin_library, fit_object
>>> table = builtin_library()["table-rectangular"]
>>> pts = table.points(0.01) + [3.0, 2.0, 0.0]          # a table at (3, 2), yaw 0
>>> fit = fit_object(pts, "table")
>>> fit.model, np.round([fit.x, fit.y], 2).tolist()
('table-rectangular', [3.0, 2.0])
"""

from __future__ import annotations

from ._fit import (
    MIN_SCORE,
    CadFit,
    LevelFrame,
    ObjectHints,
    ObjectMapFiles,
    cad_dict,
    fit_detections,
    fit_document,
    fit_object,
    hints_from_points,
    model_scale,
    object_map_cloud,
    object_map_meshes,
    write_object_map,
)
from ._icp import (
    INLIER_DISTANCE,
    KERNELS,
    GroundIcpResult,
    ground_icp,
    pose_matrix,
    robust_weights,
    yaw_procrustes,
)
from ._manifest import MANIFEST_FORMAT, UNITS, load_manifest, load_mesh, orientation
from ._models import (
    MODEL_SPACING,
    CadModel,
    ModelLibrary,
    box_model,
    builtin_library,
    canonical_mesh,
    grid_downsample,
    library_figure,
    make_model,
    sample_surface,
    visible_shell,
    visible_surface,
)

__all__ = [
    "INLIER_DISTANCE",
    "KERNELS",
    "MANIFEST_FORMAT",
    "MIN_SCORE",
    "MODEL_SPACING",
    "UNITS",
    "CadFit",
    "CadModel",
    "GroundIcpResult",
    "LevelFrame",
    "ModelLibrary",
    "ObjectHints",
    "ObjectMapFiles",
    "box_model",
    "builtin_library",
    "cad_dict",
    "canonical_mesh",
    "fit_detections",
    "fit_document",
    "fit_object",
    "grid_downsample",
    "ground_icp",
    "hints_from_points",
    "library_figure",
    "load_manifest",
    "load_mesh",
    "make_model",
    "model_scale",
    "object_map_cloud",
    "object_map_meshes",
    "orientation",
    "pose_matrix",
    "robust_weights",
    "sample_surface",
    "visible_shell",
    "visible_surface",
    "write_object_map",
    "yaw_procrustes",
]
