"""Choosing the best consistent set of candidate objects (issue 20): the candidates that
overlap each other by at most a small share of points and maximise the summed log-odds
against "none" — exact with an integer program (``scipy.optimize.milp``, HiGHS) on the
conflict graph, greedy with suppression when the problem is big.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["MAX_EXACT", "OVERLAP_SHARE", "conflicts", "select_candidates"]

#: Two candidates conflict when they share more than this share of the smaller one's points.
OVERLAP_SHARE = 0.1
#: Above this many candidates with a positive gain, the greedy choice is used.
MAX_EXACT = 2000


def conflicts(members: Sequence[ArrayLike], share: float = OVERLAP_SHARE) -> NDArray[np.int64]:
    """(c, 2) pairs i < j of candidates (sets of integer ids) that share more than
    ``share`` of the smaller one's ids.

    >>> conflicts([[0, 1, 2], [2, 3, 4], [5]], share=0.0).tolist()
    [[0, 1]]
    """
    sets = [np.unique(np.asarray(m, dtype=np.int64)) for m in members]
    if not sets:
        return np.zeros((0, 2), dtype=np.int64)
    owner = np.concatenate([np.full(len(s), k) for k, s in enumerate(sets)])
    ids = np.concatenate(sets)
    order = np.argsort(ids, kind="stable")
    ids, owner = ids[order], owner[order]
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])
    shared: dict[tuple[int, int], int] = {}
    for s, e in zip(starts, np.r_[starts[1:], len(ids)]):
        if e - s < 2:
            continue
        who = owner[s:e].tolist()
        for a in range(len(who)):
            for b in range(a + 1, len(who)):
                key = (who[a], who[b]) if who[a] < who[b] else (who[b], who[a])
                shared[key] = shared.get(key, 0) + 1
    sizes = [len(s) for s in sets]
    out = [key for key, n in shared.items() if n > share * min(sizes[key[0]], sizes[key[1]])]
    return np.array(sorted(out), dtype=np.int64).reshape(-1, 2)


def _greedy(gains: NDArray, pairs: NDArray, use: NDArray) -> NDArray[np.bool_]:
    chosen = np.zeros(len(gains), dtype=bool)
    blocked = np.zeros(len(gains), dtype=bool)
    nbrs: dict[int, list[int]] = {}
    for a, b in pairs.tolist():
        nbrs.setdefault(a, []).append(b)
        nbrs.setdefault(b, []).append(a)
    for k in sorted(np.flatnonzero(use).tolist(), key=lambda k: (-gains[k], k)):
        if not blocked[k]:
            chosen[k] = True
            blocked[nbrs.get(k, [])] = True
    return chosen


def select_candidates(
    gains: ArrayLike,
    pairs: ArrayLike,
    *,
    max_exact: int = MAX_EXACT,
    bonus: ArrayLike | None = None,
    eligible: ArrayLike | None = None,
) -> tuple[NDArray[np.bool_], str]:
    """The subset of candidates with no conflicting pair and the largest summed gain.

    Parameters
    ----------
    gains : (n,) float
        Each candidate's log-odds against "none" (only positive ones can be chosen, or
        the ``eligible`` ones).
    pairs : (c, 2) int
        Conflicting candidate pairs (:func:`conflicts`).
    max_exact : int
        Above this many eligible candidates, greedy with suppression (best first, its
        conflicts dropped; ``bonus`` left out) instead of the integer program.
    bonus : (b, 3) float, optional
        Rows ``[i, j, value]``: ``value`` is added to the total when candidates ``i`` and
        ``j`` are both chosen (two objects that touch: what each lost to its cut where it
        meets the other is given back).
    eligible : (n,) bool, optional
        The candidates that may be chosen (default: those with a positive gain); with
        ``bonus``, one whose gain is negative on its own may still pay with its
        neighbours.

    Returns
    -------
    chosen : (n,) bool
    method : str
        ``"milp"``, ``"greedy"`` or ``"none"``.

    Examples
    --------
    >>> chosen, how = select_candidates([2.0, 1.5, 1.5], [[0, 1], [0, 2]])
    >>> chosen.tolist(), how
    ([False, True, True], 'milp')

    Two chairs that touch, each cut where it meets the other, against both as one:

    >>> chosen, _ = select_candidates(
    ...     [1.0, 0.2, 0.2], [[0, 1], [0, 2]], bonus=[[1, 2, 1.0]], eligible=[True] * 3
    ... )
    >>> chosen.tolist()
    [False, True, True]
    """
    gains = np.asarray(gains, dtype=np.float64).reshape(-1)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    use = gains > 0 if eligible is None else np.asarray(eligible, dtype=bool).reshape(-1)
    extra = np.zeros((0, 3)) if bonus is None else np.asarray(bonus, np.float64).reshape(-1, 3)
    ij = extra[:, :2].astype(np.int64)
    if len(extra):
        keep_bonus = use[ij[:, 0]] & use[ij[:, 1]] & (extra[:, 2] > 0)
        extra, ij = extra[keep_bonus], ij[keep_bonus]
    if not use.any():
        return np.zeros(len(gains), dtype=bool), "none"
    keep = use[pairs[:, 0]] & use[pairs[:, 1]] if len(pairs) else np.zeros(0, bool)
    pairs = pairs[keep]
    positive = use & (gains > 0)  # what the greedy choice, which knows no bonus, may take
    if int(use.sum()) > max_exact:
        return _greedy(gains, pairs, positive), "greedy"
    from scipy.optimize import Bounds, LinearConstraint, milp  # lazy: start-up
    from scipy.sparse import coo_matrix  # lazy: start-up

    idx = np.flatnonzero(use)
    where = np.full(len(gains), -1)
    where[idx] = np.arange(len(idx))
    n, m = len(idx), len(extra)
    constraints = []
    if len(pairs):
        rows = np.repeat(np.arange(len(pairs)), 2)
        cols = where[pairs].reshape(-1)
        a = coo_matrix((np.ones(len(cols)), (rows, cols)), shape=(len(pairs), n + m)).tocsr()
        constraints.append(LinearConstraint(a, -np.inf, 1.0))
    if m:
        # A pair's bonus y_k counts only when both are chosen: y_k <= x_i, y_k <= x_j.
        ends = where[ij].reshape(-1)
        rows = np.repeat(np.arange(2 * m), 2)
        cols = np.column_stack([np.repeat(n + np.arange(m), 2), ends]).reshape(-1)
        vals = np.tile([1.0, -1.0], 2 * m)
        b = coo_matrix((vals, (rows, cols)), shape=(2 * m, n + m)).tocsr()
        constraints.append(LinearConstraint(b, -np.inf, 0.0))
    res = milp(
        -np.r_[gains[idx], extra[:, 2]],
        constraints=constraints,
        integrality=np.r_[np.ones(n), np.zeros(m)],
        bounds=Bounds(0.0, 1.0),
    )
    if res.x is None:  # solver failed: the greedy choice still is consistent
        return _greedy(gains, pairs, positive), "greedy"
    chosen = np.zeros(len(gains), dtype=bool)
    chosen[idx[np.round(res.x[:n]) > 0.5]] = True
    return chosen, "milp"
