"""Segmentation by recognition (issue 20, opt-in: ``detect.proposals: recognition``): many
candidate objects from an over-segmentation (``ontodetect.segment.propose``), each scored
by the ontology against every class and "none", and the non-overlapping set with the
largest summed log-odds against "none" chosen (``ontodetect.labeling.select_candidates``),
instead of the three-pass vote.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import sparse

from ..cloud import PointCloud
from ..config import Config
from ..labeling import (
    LabelChoice,
    conflicts,
    label_probabilities,
    select_candidates,
)
from ..ontology import NONE, ClusterScores, Ontology, score_cluster
from ..preprocess import Ground
from ..segment import (
    Cluster,
    Segmentation,
    clusters_of_voxels,
    cut_shares,
    propose,
    segment,
)
from ..segment._measure import describe_clusters
from ._result import Detection, label_and_detect

__all__ = ["Candidate", "candidate_gain", "recognize"]

#: Probabilities are floored here before their logarithm.
MIN_PROBABILITY = 1e-12
#: A candidate's log-odds count in the selection times its surface (m²) to this power:
#: with plain log-odds (power 0) a chair cut in three plausible pieces outweighs the
#: whole chair; with power 1, two chairs side by side as one sofa outweigh the two.
SIZE_POWER = 0.5


@dataclass(frozen=True)
class Candidate:
    """One scored candidate object (for ``--explain``).

    Attributes
    ----------
    source : str
        The generator that proposed it.
    label : str or None
        Its most likely label (None: "none" is likelier than any label at the threshold).
    gain : float
        Its weight in the selection: the log-odds of that label against "none" times its
        surface to the power ``SIZE_POWER``.
    num_voxels : int
    chosen : bool
    beaten_by : int or None
        The chosen candidate it conflicts with (index into the candidates), if any.
    cluster : int or None
        Its cluster in the result's segmentation when chosen.
    cut : float
        The share of its voxels' graph edges that lead to other object voxels
        (:func:`ontodetect.segment.cut_shares`).
    """

    source: str
    label: str | None
    gain: float
    num_voxels: int
    chosen: bool
    beaten_by: int | None
    cluster: int | None = None
    cut: float = 0.0


def candidate_gain(
    probabilities: Mapping[str, float], ontology: Ontology, threshold: float
) -> tuple[str | None, float]:
    """The most likely detected label of a candidate and its log-odds against "none"
    (0 and None when it does not reach ``threshold`` or "none" is likelier).

    >>> from ontodetect.ontology import builtin_ontology
    >>> label, gain = candidate_gain({"chair": 0.8, "none": 0.2}, builtin_ontology(), 0.15)
    >>> label, round(gain, 3)
    ('chair', 1.386)
    """
    by_label = label_probabilities(probabilities, ontology)
    detected = {o.label for o in ontology.classes if o.detect}
    best = max(sorted(detected), key=lambda lab: by_label.get(lab, 0.0), default=None)
    if best is None:
        return None, 0.0
    p = by_label.get(best, 0.0)
    none = float(probabilities.get(NONE, 0.0))
    if p < threshold:
        return None, 0.0
    gain = math.log(max(p, MIN_PROBABILITY)) - math.log(max(none, MIN_PROBABILITY))
    return (best, gain) if gain > 0 else (None, 0.0)


def recognize(
    cloud: PointCloud,
    config: Config,
    ontology: Ontology,
    priors: Mapping[str, float],
    *,
    seed: int,
    viewpoint: NDArray[np.float64] | None,
    ground: Ground | None,
) -> tuple[
    Segmentation,
    list[ClusterScores],
    list[LabelChoice],
    list[Detection],
    dict[str, float],
    list[Candidate],
]:
    """Propose, score, select and label on one scan.

    Returns the segmentation of the chosen candidates (numbered in order), their scores,
    label choices and detections, the timings and every candidate (:class:`Candidate`).
    """
    d = config.detect
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    today = segment(cloud, config, seed=seed, ground=ground, ontology=ontology)
    prepared = today.prepared
    voxel_sets, sources, proposal = propose(prepared, today)
    clusters = clusters_of_voxels(prepared, voxel_sets, config, seed=seed, radius=today.radius)
    everything = Segmentation(
        clusters,
        prepared,
        np.full(len(prepared.voxels), -1, dtype=np.int64),
        today.radius,
        "recognition",
        config,
    )
    timings["segment"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    all_scores = [
        score_cluster(desc, ontology, priors, none_likelihood=d.none_likelihood)
        for desc in describe_clusters(everything, viewpoint)
    ]
    timings["score"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    best = [candidate_gain(s.probabilities, ontology, d.threshold) for s in all_scores]
    gains = np.array([g for _, g in best], dtype=np.float64)
    eligible = gains > 0
    weight = np.array([c.surface for c in clusters]) ** SIZE_POWER
    cut, contact = cut_shares(proposal.objects, proposal.graph, [c.voxels for c in clusters])
    gains = np.where(eligible, gains - d.cut_cost * cut, 0.0) * weight
    bonus = _touching(contact, eligible, d.cut_cost * weight)
    pairs = conflicts([c.voxels for c in clusters])
    chosen, _ = select_candidates(gains, pairs, bonus=bonus, eligible=eligible)
    keep = np.flatnonzero(chosen)
    # Largest first, as the segmentation numbers its clusters.
    keep = keep[np.argsort([-len(clusters[k].voxels) for k in keep], kind="stable")]
    new_id = {int(k): i for i, k in enumerate(keep)}
    beaten: dict[int, int] = {}
    for a, b in pairs.tolist():
        if a in new_id and b not in new_id:
            beaten.setdefault(b, a)
        elif b in new_id and a not in new_id:
            beaten.setdefault(a, b)
    candidates = [
        Candidate(
            sources[k],
            best[k][0],
            float(gains[k]),
            len(clusters[k].voxels),
            k in new_id,
            beaten.get(k),
            new_id.get(k),
            float(cut[k]),
        )
        for k in range(len(clusters))
    ]
    picked: list[Cluster] = []
    voxel_labels = np.full(len(prepared.voxels), -1, dtype=np.int64)
    for i, k in enumerate(keep):
        c = clusters[k]
        picked.append(dataclasses.replace(c, id=i))
        voxel_labels[c.voxels] = i
    seg = Segmentation(picked, prepared, voxel_labels, today.radius, "recognition", config)
    scores = [all_scores[k] for k in keep]
    timings["select"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    choices, found = label_and_detect(cloud, seg, scores, ontology, d)
    timings["label"] = time.perf_counter() - t0
    return seg, scores, choices, found, timings, candidates


def _touching(
    contact: sparse.csr_matrix, eligible: NDArray[np.bool_], cost: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Rows ``[i, j, value]`` (i < j) for eligible candidates that touch: what both lost to
    their cut where they meet (``cost[i]`` per unit of ``i``'s share), given back when
    both are chosen."""
    c = contact.tocoo()
    ok = eligible[c.row] & eligible[c.col] & (c.row != c.col) & (c.data > 0)
    i, j = c.row[ok].astype(np.int64), c.col[ok].astype(np.int64)
    value = c.data[ok] * cost[i]
    n = len(eligible)
    key, where = np.unique(np.minimum(i, j) * n + np.maximum(i, j), return_inverse=True)
    return np.column_stack([key // n, key % n, np.bincount(where, weights=value)])


def explain_candidates(candidates: Sequence[Candidate], keep_index: Sequence[int]) -> list[str]:
    """Lines saying, for each chosen candidate, which candidates it beat and why."""
    lines = []
    for k in keep_index:
        c = candidates[k]
        lines.append(
            f"candidate {k} ({c.source}, {c.label}, weight {c.gain:.2f}, cut {c.cut:.2f}) beat:"
        )
        for j, o in enumerate(candidates):
            if o.beaten_by == k:
                why = "no label" if o.label is None else f"{o.label}, weight {o.gain:.2f}"
                lines.append(f"  {j} ({o.source}, {o.num_voxels} voxels, cut {o.cut:.2f}): {why}")
    return lines
