"""The multi-pass vote: passes over the scan turned by a fraction of a degree, and a
detection kept when a majority of them finds it (:func:`majority_labels`), with its
probabilities averaged over the passes (:func:`pass_probabilities`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..cloud import PointCloud
from ..errors import InvalidParameterError
from ..geometry import point_overlap
from ..labeling import LabelChoice, label_probability
from ..ontology import ClusterScores, Ontology
from ..segment import Segmentation
from ._result import Detection, _detection

__all__ = [
    "VOTE_IOU",
    "Ballot",
    "PassCluster",
    "class_for_label",
    "majority_labels",
    "pass_ballots",
    "pass_probabilities",
    "vote_turns",
]


#: What the vote needs of a cluster of another pass: its sorted input rows, its
#: P_obj|ont by class (with "none") and its label (None when it is no object).
PassCluster = tuple[NDArray[np.int64], dict[str, float], str | None]


@dataclass(frozen=True)
class Ballot:
    """What one pass made of the points of a cluster of the first pass (``--explain``).

    Attributes
    ----------
    turn : float
        The pass's turn of the scan (degrees; 0 for the first pass).
    label : str or None
        The label of that pass's cluster that covers these points best (None: no object).
    iou : float
        Point IoU of that cluster with the first pass's (0: no cluster shares a point).
    num_points : int
        That cluster's points.
    best : str or None
        Its most probable class other than "none", with ...
    probability : float
        ... that class's P_obj|ont in the pass.
    """

    turn: float
    label: str | None
    iou: float
    num_points: int
    best: str | None
    probability: float

    @property
    def counts(self) -> bool:
        """Whether the pass backs a label here (its cluster covers with IoU >= VOTE_IOU)."""
        return self.label is not None and self.iou >= VOTE_IOU

    def to_dict(self) -> dict[str, Any]:
        return {
            "turn": round(self.turn, 4),
            "label": self.label,
            "iou": round(self.iou, 4),
            "num_points": self.num_points,
            "class": self.best,
            "probability": round(self.probability, 4),
            "counts": self.counts,
        }


def _ballot(
    turn: float, iou: float, rows: NDArray[np.int64], probs: Mapping[str, float], label
) -> Ballot:
    ranked = sorted(((p, n) for n, p in probs.items() if n != "none"), reverse=True)
    p, best = ranked[0] if ranked else (0.0, None)
    return Ballot(float(turn), label, float(iou), len(rows), best, float(p))


def pass_ballots(
    clusters: Mapping[int, NDArray[np.int64]],
    first: Sequence[PassCluster],
    others: Sequence[Sequence[PassCluster]],
    turns: Sequence[float],
) -> dict[int, list[Ballot]]:
    """What every pass made of some clusters of the first pass (``detect --explain``).

    Parameters
    ----------
    clusters : mapping of int to (k,) int
        Sorted point rows of the first pass's clusters to explain, by cluster.
    first : sequence of PassCluster
        Every cluster of the first pass (its rows, probabilities and label).
    others : sequence of sequences of PassCluster
        Every cluster of every other pass.
    turns : sequence of float
        The other passes' turns (degrees), in the order of ``others``.

    Returns
    -------
    dict of int to list of Ballot
        For each cluster: the first pass's ballot, then one per other pass, made by the
        cluster of that pass that shares most of its points (IoU).

    Examples
    --------
    >>> a, b = np.arange(0, 10), np.arange(5, 30)
    >>> out = pass_ballots({0: a}, [(a, {"chair": 0.8, "none": 0.2}, "chair")],
    ...                    [[(b, {"table": 0.6, "none": 0.4}, "table")]], [0.7])
    >>> [(v.turn, v.label, round(v.iou, 2), v.best, v.counts) for v in out[0]]
    [(0.0, 'chair', 1.0, 'chair', True), (0.7, 'table', 0.17, 'table', False)]
    """
    if len(turns) != len(others):
        raise InvalidParameterError("turns", f"one per other pass ({len(others)})", len(turns))
    keys = sorted(clusters)
    mine = [_rows(clusters[k]) for k in keys]
    out = {k: [_ballot(0.0, 1.0, first[k][0], first[k][1], first[k][2])] for k in keys}
    for turn, run in zip(turns, others):
        if not keys:
            break
        theirs = [_rows(rows) for rows, _, _ in run]
        iou = point_overlap(mine, theirs)[0] if theirs else np.zeros((len(mine), 0))
        for i, k in enumerate(keys):
            j = int(np.argmax(iou[i])) if iou.shape[1] else -1
            if j < 0 or iou[i, j] <= 0:
                out[k].append(Ballot(float(turn), None, 0.0, 0, None, 0.0))
                continue
            rows, probs, label = run[j]
            out[k].append(_ballot(turn, iou[i, j], rows, probs, label))
    return out


def vote_turns(votes: int, step: float) -> list[float]:
    """Turns (deg) of the passes after the first: +step, -step, +2 step, -2 step...

    >>> vote_turns(5, 0.7)
    [0.7, -0.7, 1.4, -1.4]
    """
    return [step * ((i + 1) // 2) * (1 if i % 2 else -1) for i in range(1, votes)]


#: A detection of another pass backs a cluster of the first when their points overlap
#: at least this much (IoU), with the same label.
VOTE_IOU = 0.5


def _rows(rows: Any) -> NDArray[np.int64]:
    """Sorted unique int64 point rows, as the point overlap expects them."""
    return np.unique(np.asarray(rows, dtype=np.int64))


def majority_labels(
    clusters: Sequence[NDArray[np.int64]],
    first: Mapping[int, str],
    others: Sequence[Sequence[tuple[str, NDArray[np.int64]]]],
    seen: Sequence[Sequence[NDArray[np.int64]]] | None = None,
) -> dict[int, tuple[str, int]]:
    """The labels a majority of passes gives the clusters of the first pass.

    Parameters
    ----------
    clusters : sequence of (k,) int
        Sorted point rows of each cluster of the first pass.
    first : mapping of int to str
        The first pass's labels, by cluster.
    others : sequence of sequences of (label, rows)
        The detections of every other pass (sorted rows).
    seen : sequence of sequences of (k,) int, optional
        Every cluster of every other pass (objects or not), in the order of ``others``.
        When given, a pass none of whose clusters covers a cluster of the first pass with
        point IoU ≥ ``VOTE_IOU`` abstains on it: its segmentation cut or merged those
        points otherwise, so it cannot say what they are, and the majority is of the
        passes that made the same cluster (the first pass always does).

    Returns
    -------
    dict of int to (label, passes)
        For each cluster that more than half of all passes (of those that do not abstain)
        label alike (a pass counts when one of its detections of the label covers the
        cluster with point IoU ≥ ``VOTE_IOU``): the label and how many passes found it.

    Examples
    --------
    >>> a, b = np.arange(0, 10), np.arange(20, 30)
    >>> majority_labels([a, b], {0: "chair"}, [[("chair", a), ("table", b)], [("table", b[1:])]])
    {0: ('chair', 2), 1: ('table', 2)}

    Both other passes merged the chair into a larger cluster and abstain on it; a pass that
    made the same cluster and found no object there votes against it:

    >>> merged = np.arange(0, 30)
    >>> majority_labels([a], {0: "chair"}, [[], []], seen=[[merged], [merged]])
    {0: ('chair', 1)}
    >>> majority_labels([a], {0: "chair"}, [[], []], seen=[[a], [merged]])
    {}
    """
    mine = [_rows(rows) for rows in clusters]
    voters = np.full(len(clusters), len(others) + 1)
    if seen is not None:
        if len(seen) != len(others):
            raise InvalidParameterError("seen", f"one per other pass ({len(others)})", len(seen))
        for run in seen:
            if run and mine:
                voters -= point_overlap(mine, [_rows(r) for r in run])[0].max(axis=1) < VOTE_IOU
            else:
                voters -= 1
    needs = voters // 2 + 1
    backing: list[dict[str, int]] = [
        {first[k]: 1} if k in first else {} for k in range(len(clusters))
    ]
    dets = [(label, _rows(rows)) for run in others for label, rows in run]
    iou, _ = point_overlap([rows for _, rows in dets], mine)
    run_of = np.repeat(np.arange(len(others)), [len(run) for run in others])
    for r in range(len(others)):
        found = {
            (int(k), dets[i][0])
            for i in np.flatnonzero(run_of == r)
            for k in np.flatnonzero(iou[i] >= VOTE_IOU)
        }
        for k, label in found:
            backing[k][label] = backing[k].get(label, 0) + 1
    out: dict[int, tuple[str, int]] = {}
    for k, votes in enumerate(backing):
        need = int(needs[k])
        winners = sorted(((n, label) for label, n in votes.items() if n >= need), reverse=True)
        if winners:
            out[k] = (winners[0][1], winners[0][0])
    return out


def pass_probabilities(
    clusters: Sequence[NDArray[np.int64]],
    first: Sequence[Mapping[str, float]],
    others: Sequence[Sequence[tuple[NDArray[np.int64], Mapping[str, float]]]],
    abstain: bool = False,
) -> list[dict[str, float]]:
    """P_obj|ont of clusters of the first pass, averaged over all the passes.

    Parameters
    ----------
    clusters : sequence of (k,) int
        Sorted point rows of the clusters of the first pass to average.
    first : sequence of mappings of str to float
        Their probabilities in the first pass (by class, with ``"none"``).
    others : sequence of sequences of (rows, probabilities)
        Every cluster of every other pass.
    abstain : bool
        Leave out a pass with no covering cluster instead of counting it as no object.

    Returns
    -------
    list of dict
        For each cluster, the mean over the passes of the probabilities of the cluster
        of that pass that covers it with point IoU ≥ ``VOTE_IOU``; a pass with no such
        cluster saw no object there and counts as ``{"none": 1}``, or, with ``abstain``,
        is left out of the mean (as :func:`majority_labels` leaves it out of the vote when
        given every cluster).

    Examples
    --------
    >>> a, b = np.arange(0, 10), np.arange(20, 30)
    >>> p = pass_probabilities([a], [{"chair": 0.1, "none": 0.9}],
    ...                        [[(a[1:], {"chair": 0.7, "none": 0.3})], [(b, {"chair": 1.0})]])
    >>> {k: round(v, 3) for k, v in p[0].items()}
    {'chair': 0.267, 'none': 0.733}
    """
    sums = [dict(p) for p in first]
    counts = [len(others) + 1] * len(sums)
    if clusters:
        mine = [_rows(rows) for rows in clusters]
        for run in others:
            theirs = [_rows(rows) for rows, _ in run]
            iou = point_overlap(mine, theirs)[0] if theirs else np.zeros((len(mine), 0))
            for k, total in enumerate(sums):
                j = int(np.argmax(iou[k])) if iou.shape[1] else -1
                covered = j >= 0 and iou[k, j] >= VOTE_IOU
                if abstain and not covered:
                    counts[k] -= 1
                    continue
                seen = run[j][1] if covered else {"none": 1.0}
                for name, p in seen.items():
                    total[name] = total.get(name, 0.0) + float(p)
    return [{name: total / n for name, total in s.items()} for s, n in zip(sums, counts)]


def class_for_label(ontology: Ontology, label: str, costs: Mapping[str, float]) -> str:
    """The reported class written under ``label`` that costs least in ``costs`` (the
    energy's U per class; ties go to the name first in order): the class a cluster the
    first pass left out is reported as when the other passes found it a ``label``."""
    names = [o.name for o in ontology.classes if o.label == label and o.detect]
    if not names:
        raise InvalidParameterError("label", "the label of a reported class", label)
    return min(names, key=lambda n: (costs.get(n, math.inf), n))


def _vote(
    cloud: PointCloud,
    seg: Segmentation,
    scores: list[ClusterScores],
    choices: list[LabelChoice],
    found: list[Detection],
    others: list[list[PassCluster]],
    ontology: Ontology,
    turns: Sequence[float],
    abstain: bool = False,
) -> tuple[list[Detection], list[LabelChoice], dict[int, list[Ballot]]]:
    """Keep what a majority of the passes found (:func:`majority_labels`), on the first
    pass's clusters: a detection only the first pass made goes, and one the first pass
    missed but most of the others made comes back on the first pass's cluster. What is
    kept carries the probabilities averaged over the passes (:func:`pass_probabilities`).
    The ballots (:func:`pass_ballots`) say what every pass made of each cluster that
    some pass found an object in."""
    first = {d.cluster: d for d in found}
    rows = [np.sort(cloud.index[c.point_indices]) for c in seg]
    ballots = pass_ballots(
        {k: rows[k] for k in _found_anywhere(rows, first, others)},
        [(r, s.probabilities, ch.label) for r, s, ch in zip(rows, scores, choices)],
        others,
        turns,
    )
    kept = majority_labels(
        rows,
        {k: d.label for k, d in first.items()},
        [[(label, r) for r, _, label in run if label is not None] for run in others],
        seen=[[r for r, _, _ in run] for run in others] if abstain else None,
    )
    passes = len(others) + 1
    choices = list(choices)
    out: list[Detection] = []
    for k in first:
        if k not in kept:
            choices[k] = LabelChoice(
                None,
                choices[k].costs,
                f"found by fewer than half of {passes} passes",
                {"class": choices[k].extra["class"]},
            )
    ks = sorted(kept)
    means = pass_probabilities(
        [rows[k] for k in ks],
        [scores[k].probabilities for k in ks],
        [[(r, p) for r, p, _ in run] for run in others],
        abstain=abstain,
    )
    for k, mean in zip(ks, means):
        label, n = kept[k]
        probabilities = {name: p for name, p in mean.items() if name != "none"}
        if k in first and first[k].label == label:
            out.append(
                dataclasses.replace(
                    first[k],
                    votes=n,
                    probabilities=probabilities,
                    score=label_probability(probabilities, ontology, label),
                )
            )
            continue
        cls_name = class_for_label(ontology, label, choices[k].costs)
        choices[k] = LabelChoice(label, choices[k].costs, "", {"class": cls_name})
        out.append(
            _detection(
                cloud,
                seg,
                k,
                scores[k],
                label,
                cls_name,
                choices[k].costs,
                ontology,
                votes=n,
                probabilities=mean,
            )
        )
    return out, choices, ballots


def _found_anywhere(
    rows: Sequence[NDArray[np.int64]],
    first: Mapping[int, Detection],
    others: Sequence[Sequence[PassCluster]],
) -> set[int]:
    """The clusters of the first pass that a pass found an object in: the first pass's
    detections, and the cluster sharing most points with each detection of another."""
    keys = set(first)
    dets = [_rows(r) for run in others for r, _, label in run if label is not None]
    if dets and len(rows):
        inter = point_overlap(dets, list(rows))[1]
        keys.update(int(k) for k in np.argmax(inter, axis=1)[inter.max(axis=1) > 0])
    return keys
