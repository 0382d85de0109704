"""Point-set overlap: intersection and IoU between sets of point rows."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["point_overlap"]


def point_overlap(
    a: Sequence[NDArray[np.int64]], b: Sequence[NDArray[np.int64]]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """(len(a), len(b)) point IoU and intersection counts between sets of point rows.

    Parameters
    ----------
    a, b : sequences of (k,) int
        Point rows of each set, sorted and unique (``np.unique``).

    Returns
    -------
    iou : (p, g) float
    intersection : (p, g) int

    Examples
    --------
    >>> iou, inter = point_overlap([np.arange(4)], [np.arange(2, 6), np.arange(10, 12)])
    >>> iou.round(3).tolist(), inter.tolist()
    ([[0.333, 0.0]], [[2, 0]])
    """
    iou = np.zeros((len(a), len(b)))
    inter = np.zeros((len(a), len(b)), dtype=np.int64)
    if not len(a) or not len(b):
        return iou, inter
    all_b = np.concatenate(list(b))
    owner = np.concatenate([np.full(len(s), k) for k, s in enumerate(b)])
    order = np.argsort(all_b, kind="stable")
    all_b, owner = all_b[order], owner[order]
    b_sizes = np.array([len(s) for s in b])
    for i, rows in enumerate(a):
        lo = np.searchsorted(all_b, rows, "left")
        hi = np.searchsorted(all_b, rows, "right")
        hits = hi > lo
        if not hits.any():
            continue
        # Sets of ``b`` may share points only in malformed data; count each hit.
        idx = np.concatenate([np.arange(s, e) for s, e in zip(lo[hits], hi[hits])])
        counts = np.bincount(owner[idx], minlength=len(b))
        inter[i] = counts
        union = len(rows) + b_sizes - counts
        iou[i] = np.where(union > 0, counts / np.maximum(union, 1), 0.0)
    return iou, inter
