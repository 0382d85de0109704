"""Energy labelling: one label (or none) per cluster (thesis Eq. 3.6–3.8).

For cluster c and label l the unary energy is

    U(c, l) = 1 − β / (1 + e^(−p)) − γ / (1 + e^(−f(c, l))),     β + γ = 1     (Eq. 3.7)

with p the class probability P_obj|ont of l and f(c, l) the product over the
cluster's planes of the label's colour and plane-size Gaussians (Eq. 3.8). As in
Algorithm 1, only clusters whose best class probability reaches the decision
threshold are labelled, and only with labels at or above it. Classes written under
one label (a side table and a table) are kinds of one object: p, the threshold and
the "none" test use the label's probability, the sum of theirs.

Two pairwise terms make the labelling a small random field, solved exactly by
enumeration per connected group of interacting clusters (greedy refinement only
when a group is too large to enumerate):

- exclusion: two clusters that share points (overlapping hypotheses from the
  segmentation) cannot both be labelled;
- context: a class near one its ontology lists under ``context`` is a little more
  likely (a chair pulled up to a desk), an optional bonus ``-context · exp(-d² / 2 s²)``.
"""

from ._energy import (
    LabelChoice,
    energy,
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
    "label_clusters",
    "label_costs",
    "label_fit",
    "label_probabilities",
    "label_probability",
    "select_candidates",
]
