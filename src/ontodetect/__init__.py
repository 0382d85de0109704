"""ontodetect: furniture detection in indoor point clouds with probabilistic ontological priors.

Subpackages, in the order the data flows:

- ``io``: read and write point clouds and labelled scans (PLY, PCD, LAS/LAZ, text, NumPy,
  3DTK, ScanNet, S3DIS).
- ``synth``: simulated rooms with furniture and virtual sensors, with ground truth.
- ``preprocess``: scale, denoise, level, voxelize; floor, walls and ceiling.
- ``segment``: candidate clusters and their MSAC planes with features.
- ``ontology``: probabilistic ontological scoring of clusters against object classes.
- ``environment``: the room prior P_N from photographs (GIST and a calibrated SVM), and
  how it combines with P_N from the scan.
- ``labeling``: energy minimisation that picks one label per cluster.
- ``cad``: generic CAD models fitted with ground-constrained ICP; the object map.
- ``pipeline``: :func:`detect`, the whole method in one call, and its output types.
- ``evaluation``: precision, recall and reports against ground truth.
- ``calibrate``: an ontology's Gaussians fitted to labelled scans.
- ``geometry``: transforms, boxes, point-set overlap and shape checks several stages share.
"""

from __future__ import annotations

from ._version import __version__
from .cloud import DataWarning, PointCloud, point_cloud
from .errors import (
    CorruptFileError,
    InvalidOntologyError,
    InvalidParameterError,
    OntoDetectError,
    ReadError,
    UnsupportedFormatError,
    WriteError,
)
from .io import read_cloud, write_cloud

__all__ = [
    "Config",
    "CorruptFileError",
    "DataWarning",
    "Detection",
    "EnvironmentModel",
    "InvalidOntologyError",
    "InvalidParameterError",
    "OntoDetectError",
    "PointCloud",
    "ReadError",
    "Result",
    "TiledResult",
    "UnsupportedFormatError",
    "WriteError",
    "__version__",
    "combine_room_priors",
    "detect",
    "detect_tiled",
    "point_cloud",
    "predict_environment",
    "read_cloud",
    "train_environment",
    "write_cloud",
]

#: Names re-exported from ``pipeline``, imported when first used: ``import ontodetect``
#: stays light (the CLI's start-up), ``from ontodetect import detect`` works.
_FROM_PIPELINE = ("Detection", "Result", "TiledResult", "detect", "detect_tiled")
#: Names re-exported from ``environment``, imported when first used (start-up, as above).
_FROM_ENVIRONMENT = (
    "EnvironmentModel",
    "combine_room_priors",
    "predict_environment",
    "train_environment",
)


def __getattr__(name: str):
    if name in _FROM_PIPELINE:
        from . import pipeline  # lazy: import ontodetect without the stages (start-up)

        return getattr(pipeline, name)
    if name in _FROM_ENVIRONMENT:
        from . import environment  # lazy: import ontodetect without the stages (start-up)

        return getattr(environment, name)
    if name == "Config":
        from .config import Config  # lazy: `info` needs no configuration (start-up)

        return Config
    raise AttributeError(f"module 'ontodetect' has no attribute {name!r}")
