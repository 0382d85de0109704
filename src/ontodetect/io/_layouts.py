"""Names of the labelled dataset layouts the library reads (docs/evaluation.md)."""

from __future__ import annotations

__all__ = ["DATASET_FORMATS"]

#: Dataset layouts: "auto" finds out which of the others a folder is.
DATASET_FORMATS = ("auto", "ontodetect", "scannet", "scannet-votenet", "s3dis")
