"""Labelling: one label (or none) per cluster, and one consistent set of candidates.

- ``_energy``: the energy of thesis Eq. 3.6–3.8 (unary terms, exclusion and context),
  minimised per group of interacting clusters (:func:`label_clusters`).
- ``_select``: the non-overlapping candidates of largest summed weight
  (:func:`select_candidates`), for segmentation by recognition.
"""

from ._energy import (
    LabelChoice,
    energy,
    explained_away,
    label_clusters,
    label_costs,
    label_fit,
    label_probabilities,
    label_probability,
)
from ._select import conflicts, select_candidates

__all__ = [
    "LabelChoice",
    "conflicts",
    "energy",
    "explained_away",
    "label_clusters",
    "label_costs",
    "label_fit",
    "label_probabilities",
    "label_probability",
    "select_candidates",
]
