"""ontodetect: furniture detection in indoor point clouds with probabilistic ontological priors.

Subpackages, in the order the data flows:

- ``io``: read and write point clouds and labelled scans (PLY, PCD, LAS/LAZ, text, NumPy,
  3DTK, ScanNet, S3DIS).
- ``synth``: simulated rooms with furniture and virtual sensors, with ground truth.
- ``preprocess``: scale, denoise, level, voxelize; floor, walls and ceiling.
- ``segment``: candidate clusters and their MSAC planes with features.
- ``ontology``: probabilistic ontological scoring of clusters against object classes.
- ``labeling``: energy minimisation that picks one label per cluster.
- ``cad``: generic CAD models fitted with ground-constrained ICP; the object map.
- ``evaluation``: precision, recall and reports against ground truth.
"""

from __future__ import annotations

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

__version__ = "0.1.0"

__all__ = [
    "CorruptFileError",
    "DataWarning",
    "InvalidOntologyError",
    "InvalidParameterError",
    "OntoDetectError",
    "PointCloud",
    "ReadError",
    "UnsupportedFormatError",
    "WriteError",
    "__version__",
    "point_cloud",
    "read_cloud",
    "write_cloud",
]
