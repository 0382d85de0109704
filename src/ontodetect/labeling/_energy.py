"""Energy labelling: the unary energy and the labelling of a scene (thesis Eq. 3.6–3.8).

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

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InvalidParameterError
from ..ontology import NONE, ClusterScores, LabelModel, Ontology

__all__ = [
    "LabelChoice",
    "energy",
    "explained_away",
    "label_clusters",
    "label_costs",
    "label_fit",
    "label_probabilities",
    "label_probability",
]

#: Largest number of joint labellings enumerated exactly in one group of clusters.
MAX_ENUMERATION = 200_000
#: Cost of leaving a candidate cluster unlabelled when exclusion forces it (U ranges in [0, 1]).
NONE_COST = 1.0
#: Horizontal distance scale of the context bonus (m).
CONTEXT_SCALE = 0.8


def _sigmoid(x: float) -> float:
    return 1.0 / (1.0 + math.exp(-x))


def energy(p: float, f: float, *, beta: float = 0.5, gamma: float = 0.5) -> float:
    """U = 1 − β/(1+e^(−p)) − γ/(1+e^(−f))  (Eq. 3.7).

    Examples
    --------
    >>> round(energy(0.604, 1.0), 4)
    0.3112
    """
    if not math.isclose(beta + gamma, 1.0, abs_tol=1e-9):
        raise InvalidParameterError("beta + gamma", "equal to 1", beta + gamma)
    return 1.0 - beta * _sigmoid(p) - gamma * _sigmoid(f)


def label_fit(planes: Sequence[Any], model: LabelModel) -> float:
    """f(c, l): product over the cluster's planes of F_I|l (colour) · F_m|l (size)  (Eq. 3.8).

    Plane size is the plane's larger extent ``max(length, width)``; colour is the
    plane's mean colour against the label's mean with an isotropic σ. A label
    without a colour or size model contributes 1 for that factor.
    """
    f = 1.0
    for plane in planes:
        if model.plane_size is not None:
            f *= float(model.plane_size(max(float(plane.length), float(plane.width))))
        if model.color is not None and getattr(plane, "color_mean", None) is not None:
            mean, sigma = model.color
            d2 = float(np.sum((np.asarray(plane.color_mean, float) - np.asarray(mean)) ** 2))
            f *= math.exp(-0.5 * d2 / sigma**2)
    return f


def label_probability(probabilities: Mapping[str, float], ontology: Ontology, label: str) -> float:
    """How likely a cluster is a ``label``: the probabilities of the classes written under
    that label, summed (the built-in side table and table are both "table").

    Examples
    --------
    >>> from ontodetect.ontology import builtin_ontology
    >>> label_probability({"table": 0.3, "side_table": 0.25, "chair": 0.1},
    ...                   builtin_ontology(), "table")
    0.55
    """
    return label_probabilities(probabilities, ontology).get(label, 0.0)


def label_probabilities(probabilities: Mapping[str, float], ontology: Ontology) -> dict[str, float]:
    """:func:`label_probability` of every label of the ontology, in one pass."""
    out: dict[str, float] = {}
    for c in ontology.classes:
        out[c.label] = out.get(c.label, 0.0) + float(probabilities.get(c.name, 0.0))
    return out


def label_costs(
    scores: ClusterScores,
    planes: Sequence[Any],
    ontology: Ontology,
    *,
    beta: float = 0.5,
    gamma: float = 0.5,
) -> dict[str, float]:
    """U(c, l) for every class of the ontology (Table 4.9 shows such costs).

    p is the probability of the class's label (:func:`label_probability`): classes that
    share a label are kinds of one object, so a side table does not lose the cluster to a
    chair because the cluster's table-ness is split between "table" and "side_table".
    """
    return _costs(
        label_probabilities(scores.probabilities, ontology), planes, ontology, beta, gamma
    )


def _costs(
    by_label: Mapping[str, float],
    planes: Sequence[Any],
    ontology: Ontology,
    beta: float,
    gamma: float,
) -> dict[str, float]:
    """:func:`label_costs` from the cluster's :func:`label_probabilities`."""
    return {
        cls.name: energy(
            by_label[cls.label], label_fit(planes, cls.labeling), beta=beta, gamma=gamma
        )
        for cls in ontology.classes
    }


@dataclass(frozen=True)
class LabelChoice:
    """The label picked for one cluster, or None, with its costs."""

    label: str | None
    costs: Mapping[str, float]
    reason: str = ""
    extra: dict[str, Any] = field(default_factory=dict)


def _check(name: str, value: float, low: float, high: float) -> None:
    if not (low <= value <= high):
        raise InvalidParameterError(name, f"a number in [{low}, {high}]", value)


def _kinds(ontology: Ontology, label: str) -> set[str]:
    """The room-prior tables (``prior: {rooms: ...}``) of the classes written under ``label``:
    what kind of furniture the label is (seating, table, toilet...)."""
    return {
        c.prior_rooms if isinstance(c.prior_rooms, str) else c.name
        for c in ontology.classes
        if c.label == label
    }


def _label_prior(scores: ClusterScores, ontology: Ontology, label: str) -> float:
    """log P_obj of ``label`` on this cluster: the largest of its classes' that the scores
    hold (0, a prior of 1, when they hold none)."""
    return max(
        (
            scores.classes[c.name].log_prior
            for c in ontology.classes
            if c.label == label and c.name in scores.classes
        ),
        default=0.0,
    )


def explained_away(
    scores: ClusterScores, by_label: Mapping[str, float], ontology: Ontology, name: str
) -> bool:
    """Whether class ``name``'s label is barred on a cluster because a competing object
    explains it: the cluster's likeliest label (``by_label``: :func:`label_probabilities`)
    is one of the competing classes (written ``detect: false``, whether or not ``--classes``
    reports it now), of another kind of furniture, and the room prior makes it likelier than
    ``name``'s label before any measure of the cluster. Only the classes written to be
    reported are barred, so reporting more classes never changes which chairs, sofas and
    tables are found.

    A sink the ontology finds likelier than a chair, in a room read as a bathroom, explains
    the cluster; the plane-size term of Eq. 3.7 does not give it back to the chair (the
    thesis's Tables 4.14-4.16: a chair found in an unlikely room holds a higher cost).
    Where the room does not favour the competitor (a room of unknown kind, or one where
    both are as likely, as a chair and a radiator in a classroom), the energy decides as
    before: a competitor likelier on the cluster's shape alone has taken true chairs seen
    from behind in one view. A stool, an ottoman or a bench never explains a chair away:
    they are seating as the chair is (Table 4.10's seating row holds them all), and a chair
    whose backrest the scan lost reads as one.

    Examples
    --------
    >>> import math
    >>> from ontodetect.ontology import builtin_ontology, ClassScore, ClusterScores
    >>> onto = builtin_ontology()
    >>> def cluster(**priors):
    ...     classes = {k: ClassScore(k, 0.0, math.log(p), {}, {}, ()) for k, p in priors.items()}
    ...     return ClusterScores(classes, {}, "none")
    >>> bathroom = cluster(chair=0.3, sink=1.0, stool=0.3)
    >>> explained_away(bathroom, {"chair": 0.2, "sink": 0.4}, onto, "chair")
    True
    >>> explained_away(cluster(chair=1.0, sink=1.0), {"chair": 0.2, "sink": 0.4}, onto, "chair")
    False
    >>> explained_away(bathroom, {"chair": 0.2, "stool": 0.4}, onto, "chair")
    False
    """
    explainer = _explainer(by_label, ontology)
    return explainer is not None and _bars(scores, ontology, explainer, name)


def _explainer(by_label: Mapping[str, float], ontology: Ontology) -> str | None:
    """The cluster's likeliest label when it is one of the competing classes', else None."""
    best = max(by_label, key=lambda k: (by_label[k], k), default=None)
    if best is None or not all(c.competing for c in ontology.classes if c.label == best):
        return None
    return best


def _bars(scores: ClusterScores, ontology: Ontology, explainer: str, name: str) -> bool:
    """Whether the competing label ``explainer`` bars class ``name`` (:func:`explained_away`)."""
    cls = ontology[name]
    if cls.competing or cls.label == explainer:
        return False
    if _kinds(ontology, explainer) & _kinds(ontology, cls.label):
        return False
    return _label_prior(scores, ontology, explainer) > _label_prior(scores, ontology, cls.label)


def label_clusters(
    scores: Sequence[ClusterScores],
    planes: Sequence[Sequence[Any]],
    ontology: Ontology,
    *,
    beta: float = 0.5,
    threshold: float = 0.15,
    centers: np.ndarray | None = None,
    overlaps: Mapping[tuple[int, int], float] | None = None,
    context: float = 0.0,
    explain_away: bool = False,
) -> list[LabelChoice]:
    """Choose one label or none per cluster by minimising the total energy.

    Parameters
    ----------
    scores : sequence of ClusterScores
        One per cluster, from :func:`ontodetect.ontology.score_cluster`.
    planes : sequence of sequences of planes
        Each cluster's planes (for f(c, l)).
    ontology : Ontology
        The classes; those with ``detect: false`` may win a cluster but yield no label.
    beta : float
        Weight β of the class probability; γ = 1 − β.
    threshold : float
        Decision threshold on the class probability (Table 4.1: 15 %).
    centers : (k, 3) float, optional
        Cluster centres, for the context term.
    overlaps : mapping of (i, j) to float, optional
        Pairs of clusters that share points; they are never both labelled.
    context : float
        Strength of the bonus for two clusters whose classes are each other's context
        (the ontology's ``context``: a chair near a table); 0 turns it off.

    Returns
    -------
    list of LabelChoice
    """
    _check("beta", beta, 0.0, 1.0)
    _check("threshold", threshold, 0.0, 1.0)
    if context < 0:
        raise InvalidParameterError("context", "a number >= 0", context)
    gamma = 1.0 - beta
    n = len(scores)
    labels = [label_probabilities(s.probabilities, ontology) for s in scores]
    costs = [_costs(by, pl, ontology, beta, gamma) for by, pl in zip(labels, planes)]
    options: list[list[str | None]] = []
    nothing: list[bool] = []
    barred: list[list[str]] = []
    explainers: list[str | None] = []
    for s, c, by_label in zip(scores, costs, labels):
        barred.append([])
        explainers.append(_explainer(by_label, ontology) if explain_away else None)
        # Algorithm 1: the cluster is kept when its best label passes the threshold; and a
        # cluster that "none of the classes" explains better than any label is not an object.
        nothing.append(s.probabilities.get(NONE, 0.0) > max(by_label.values(), default=0.0))
        if nothing[-1]:
            options.append([None])
            continue
        allowed = [k for k in c if by_label[ontology[k].label] >= threshold]
        if explainers[-1] is not None:
            barred[-1] = [k for k in allowed if _bars(s, ontology, explainers[-1], k)]
            allowed = [k for k in allowed if k not in barred[-1]]
        allowed.sort(key=lambda k: (c[k], k))
        options.append([*allowed, None] if allowed else [None])

    pairs: dict[tuple[int, int], str] = {}
    for (i, j), value in (overlaps or {}).items():
        if value > 0 and i != j:
            pairs[(min(i, j), max(i, j))] = "exclude"
    if context > 0 and centers is not None and n > 1:
        c = np.asarray(centers, dtype=np.float64)[:, :2]
        d = np.linalg.norm(c[:, None] - c[None], axis=2)
        for i, j in zip(*np.nonzero(d < 3 * CONTEXT_SCALE)):
            if i < j:
                pairs.setdefault((int(i), int(j)), "context")

    near = ontology.context_pairs()

    def unary(i: int, label: str | None) -> float:
        return NONE_COST if label is None else costs[i][label]

    def pairwise(i: int, li: str | None, j: int, lj: str | None, kind: str) -> float:
        if li is None or lj is None:
            return 0.0
        if kind == "exclude":
            return math.inf
        if (li, lj) in near:
            dist = float(np.linalg.norm(np.asarray(centers)[i, :2] - np.asarray(centers)[j, :2]))
            return -context * math.exp(-0.5 * (dist / CONTEXT_SCALE) ** 2)
        return 0.0

    chosen: list[str | None] = [o[0] for o in options]
    if pairs:
        from scipy.sparse import coo_matrix  # lazy: scipy.sparse off the import path
        from scipy.sparse.csgraph import connected_components  # lazy: as coo_matrix

        rows = [i for i, _ in pairs]
        cols = [j for _, j in pairs]
        graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
        _, comp = connected_components(graph, directed=False)
        for g in np.unique(comp):
            members = [int(i) for i in np.nonzero(comp == g)[0]]
            if len(members) == 1:
                continue
            local = [(i, j, k) for (i, j), k in pairs.items() if comp[i] == g]
            sizes = [len(options[i]) for i in members]
            if math.prod(sizes) <= MAX_ENUMERATION:
                best, best_e = None, math.inf
                for combo in itertools.product(*(options[i] for i in members)):
                    lab = dict(zip(members, combo))
                    e = sum(unary(i, lab[i]) for i in members)
                    if e >= best_e + 1.0:  # pairwise bonuses are bounded; prune hopeless ones
                        continue
                    e += sum(pairwise(i, lab[i], j, lab[j], k) for i, j, k in local)
                    if e < best_e:
                        best, best_e = lab, e
                assert best is not None
                for i in members:
                    chosen[i] = best[i]
            else:  # iterated conditional modes from the unary optimum
                for _ in range(20):
                    changed = False
                    for i in members:

                        def local_e(label: str | None, i: int = i, local: list = local) -> float:
                            e = unary(i, label)
                            for a, b, k in local:
                                if a == i:
                                    e += pairwise(i, label, b, chosen[b], k)
                                elif b == i:
                                    e += pairwise(a, chosen[a], i, label, k)
                            return e

                        best_label = min(options[i], key=lambda lab: (local_e(lab), str(lab)))
                        if best_label != chosen[i]:
                            chosen[i], changed = best_label, True
                    if not changed:
                        break

    out = []
    for i, label in enumerate(chosen):
        # The labels a competitor explained away, and the competitor (its label), for
        # --explain.
        away: dict[str, Any] = {}
        if barred[i]:
            away = {
                "explained_away": sorted({ontology[k].label for k in barred[i]}),
                "explained_by": explainers[i],
            }
        if label is None:
            reason = "below threshold" if options[i] == [None] else "excluded by an overlap"
            if nothing[i]:
                reason = "none of the classes"
            out.append(LabelChoice(None, costs[i], reason, away))
            continue
        if not ontology[label].detect:
            reason = f"{label} (not reported)"
            out.append(LabelChoice(None, costs[i], reason, {"class": label, **away}))
            continue
        out.append(LabelChoice(ontology[label].label, costs[i], "", {"class": label, **away}))
    return out
