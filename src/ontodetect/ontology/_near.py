"""Relations between objects: a class scored by what stands beside it (``near`` in an
ontology file), once every cluster of a scene has been scored on its own.

A nightstand is a small box at a mattress's height; a chair without its backrest seen,
an upholstered stool or a waste bin with a lid look the same. What makes it a
nightstand is the bed whose head it stands beside. For a class with a rule ``near:
[{class: bed, distance: ..., missing: m}]`` a cluster's likelihood of the class is
multiplied by

    max(m, max_j P_j(bed) · G(d_ij))

over the other clusters j, with P_j(bed) their probability of being a bed on their own
and G the rule's Gaussian of the horizontal gap d_ij between the two footprints: a
likely bed beside it costs nothing; no bed costs ``m``. One step, from the scores
every cluster has on its own, so that the order of the clusters does not matter and
no pair reinforces itself.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

from ..errors import InvalidOntologyError
from ..geometry import box_footprint, footprint_gap
from ._schema import Ontology
from ._score import ClusterScores, ConstraintValue, _posterior

__all__ = ["score_near"]


def score_near(
    scores: Sequence[ClusterScores],
    boxes: Sequence[Any],
    ontology: Ontology,
    *,
    none_likelihood: float = 0.05,
    none_prior: float = 1.0,
) -> list[ClusterScores]:
    """The scores of a scene's clusters with the ontology's ``near`` rules applied.

    Parameters
    ----------
    scores : sequence of ClusterScores
        Every cluster of the scene scored on its own (:func:`score_cluster`).
    boxes : sequence of boxes
        The clusters' upright boxes (``center``, ``size``, ``yaw``), in the same order.
    ontology : Ontology
    none_likelihood, none_prior : float
        As for :func:`score_cluster`: the posterior is normalised again.

    Returns
    -------
    list of ClusterScores
        The same scores where no class has a rule; each rule's factor is recorded as a
        constraint (``part`` "near bed", ``feature`` "distance", the gap to the object
        that gave the factor, or ``None`` when ``missing`` did).

    Examples
    --------
    >>> from types import SimpleNamespace as Box
    >>> from ontodetect.ontology import parse_ontology, score_cluster
    >>> from ontodetect.ontology._score import ClassScore
    >>> onto = parse_ontology('''
    ... format: ontodetect.ontology/1
    ... classes:
    ...   bed: {parts: {mattress: {height: [0.3, 0.6]}}}
    ...   stand:
    ...     parts: {top: {height: [0.4, 0.7]}}
    ...     near: [{class: bed, distance: {max: 0.3, soft: 0.2}, missing: 0.2}]
    ... ''')
    >>> def scored(bed, stand):
    ...     return _posterior({"bed": ClassScore("bed", math.log(bed), 0.0, {}, {}, ()),
    ...                        "stand": ClassScore("stand", math.log(stand), 0.0, {}, {}, ())},
    ...                       math.log(0.05))
    >>> bed, stand = scored(0.9, 0.01), scored(0.01, 0.5)
    >>> beside = [Box(center=(0, 0, 0.3), size=(2, 1, 0.6), yaw=0.0),
    ...           Box(center=(1.25, 0, 0.3), size=(0.4, 0.4, 0.6), yaw=0.0)]
    >>> far = [beside[0], Box(center=(3.5, 0, 0.3), size=(0.4, 0.4, 0.6), yaw=0.0)]
    >>> near = score_near([bed, stand], beside, onto)[1].classes["stand"]
    >>> alone = score_near([bed, stand], far, onto)[1].classes["stand"]
    >>> round(math.exp(near.log_likelihood), 3), round(math.exp(alone.log_likelihood), 3)
    (0.469, 0.1)
    """
    rules = {c.name: c.near for c in ontology.classes if c.near}
    if not rules or not scores:
        return list(scores)
    for name, near in rules.items():
        for rule in near:
            if rule.target not in ontology:
                raise InvalidOntologyError(
                    ontology.source,
                    f"class {name!r} stands near {rule.target!r}, which is no class of the "
                    f"ontology ({', '.join(ontology.names)})",
                    key=f"classes.{name}.near",
                )
    prints = [box_footprint(b.center, b.size, float(b.yaw)) for b in boxes]
    gaps: dict[tuple[int, int], float] = {}

    def gap(i: int, j: int) -> float:
        key = (min(i, j), max(i, j))
        if key not in gaps:
            gaps[key] = footprint_gap(prints[i], prints[j])
        return gaps[key]

    none_log = math.log(none_likelihood) + math.log(none_prior)
    out = []
    for i, s in enumerate(scores):
        changed = {}
        for name, near in rules.items():
            cls_score = s.classes.get(name)
            if cls_score is None or cls_score.log_likelihood == -math.inf:
                continue
            log_factor = 0.0
            added = []
            for rule in near:
                best, at = rule.missing, None
                for j, other in enumerate(scores):
                    p = float(other.probabilities.get(rule.target, 0.0)) if j != i else 0.0
                    if p <= best:  # G <= 1: this one cannot do better
                        continue
                    d = gap(i, j)
                    f = p * float(rule.distance(d))
                    if f > best:
                        best, at = f, d
                log_factor += math.log(best)
                added.append(
                    ConstraintValue(
                        f"near {rule.target}", "distance", "Pr", at, rule.distance, best
                    )
                )
            changed[name] = dataclasses.replace(
                cls_score,
                log_likelihood=cls_score.log_likelihood + log_factor,
                constraints=(*cls_score.constraints, *added),
            )
        if not changed:
            out.append(s)
            continue
        posterior = _posterior({**s.classes, **changed}, none_log)
        out.append(dataclasses.replace(posterior, extra=dict(s.extra)))
    return out
