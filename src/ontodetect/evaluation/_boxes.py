"""Box average precision at 3D IoU thresholds, as VoteNet and mmdetection3d report it.

Boxes are upright: a centre, a size (length along the heading, width, height) and a yaw
about the vertical. Two IoUs are offered:

- **axis-aligned** (VoteNet's ScanNet protocol): each box is replaced by the axis-aligned
  box around it, then volumes are intersected;
- **oriented**: the footprints (rotated rectangles) are intersected as polygons, times the
  overlap in height.

Matching is per class over all scenes: detections by descending score, each takes the
unmatched ground-truth box of its scene with the highest IoU when that IoU reaches the
threshold (PASCAL VOC / VoteNet ``eval_det``); AP is the all-point area of
:func:`~ontodetect.evaluation.average_precision`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..geometry import box_footprint
from ._metrics import average_precision

__all__ = [
    "BOX_IOU_THRESHOLDS",
    "BoxInstance",
    "box_average_precision",
    "box_iou",
    "boxes_from_instances",
]

#: IoU thresholds of the box AP (VoteNet and mmdetection3d report AP@0.25 and AP@0.5).
BOX_IOU_THRESHOLDS = (0.25, 0.5)


@dataclass(frozen=True)
class BoxInstance:
    """An upright box with a class and a score (1 for ground truth).

    Attributes
    ----------
    label : str
    center : (3,) float
    size : (3,) float
        Length along the heading, width, height.
    yaw : float
        Heading about the vertical, radians.
    score : float
    """

    label: str
    center: NDArray[np.float64]
    size: NDArray[np.float64]
    yaw: float = 0.0
    score: float = 1.0

    @classmethod
    def make(
        cls, label: str, center: ArrayLike, size: ArrayLike, yaw: float = 0.0, score: float = 1.0
    ) -> BoxInstance:
        c = np.asarray(center, dtype=np.float64).reshape(3)
        s = np.abs(np.asarray(size, dtype=np.float64).reshape(3))
        return cls(str(label), c, s, float(yaw), float(score))


def _aligned(box: BoxInstance) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Lower and upper corners of the axis-aligned box around ``box``."""
    foot = box_footprint(box.center, box.size, box.yaw)
    lo = np.r_[foot.min(axis=0), box.center[2] - box.size[2] / 2]
    hi = np.r_[foot.max(axis=0), box.center[2] + box.size[2] / 2]
    return lo, hi


def _clip(subject: NDArray[np.float64], clip: NDArray[np.float64]) -> NDArray[np.float64]:
    """Sutherland-Hodgman: the part of convex polygon ``subject`` inside convex ``clip``
    (both counter-clockwise, (k, 2))."""
    out = subject
    for i in range(len(clip)):
        if not len(out):
            break
        a, b = clip[i], clip[(i + 1) % len(clip)]
        edge = b - a
        side = edge[0] * (out[:, 1] - a[1]) - edge[1] * (out[:, 0] - a[0])
        pts = []
        for j in range(len(out)):
            p, q = out[j], out[(j + 1) % len(out)]
            sp, sq = side[j], side[(j + 1) % len(out)]
            if sp >= 0:
                pts.append(p)
            if (sp >= 0) != (sq >= 0):
                t = sp / (sp - sq)
                pts.append(p + t * (q - p))
        out = np.array(pts).reshape(-1, 2)
    return out


def _area(poly: NDArray[np.float64]) -> float:
    if len(poly) < 3:
        return 0.0
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def box_iou(a: BoxInstance, b: BoxInstance, *, oriented: bool = False) -> float:
    """3D IoU of two upright boxes (axis-aligned envelopes unless ``oriented``).

    Examples
    --------
    >>> a = BoxInstance.make("chair", [0, 0, 0.5], [1, 1, 1])
    >>> b = BoxInstance.make("chair", [0.5, 0, 0.5], [1, 1, 1])
    >>> round(box_iou(a, b), 4)
    0.3333
    >>> c = BoxInstance.make("chair", [0, 0, 0.5], [1, 1, 1], yaw=np.pi / 4)
    >>> round(box_iou(a, c, oriented=True), 4), round(box_iou(a, c), 4)
    (0.7071, 0.5)
    """
    za = (a.center[2] - a.size[2] / 2, a.center[2] + a.size[2] / 2)
    zb = (b.center[2] - b.size[2] / 2, b.center[2] + b.size[2] / 2)
    dz = max(0.0, min(za[1], zb[1]) - max(za[0], zb[0]))
    if oriented:
        fa = box_footprint(a.center, a.size, a.yaw)
        fb = box_footprint(b.center, b.size, b.yaw)
        inter = _area(_clip(fa, fb)) * float(dz)
        va = float(np.prod(a.size))
        vb = float(np.prod(b.size))
    else:
        la, ha = _aligned(a)
        lb, hb = _aligned(b)
        inter = float(np.prod(np.clip(np.minimum(ha, hb) - np.maximum(la, lb), 0, None)))
        va = float(np.prod(ha - la))
        vb = float(np.prod(hb - lb))
    union = va + vb - inter
    return float(inter / union) if union > 0 else 0.0


def box_average_precision(
    scenes: Sequence[tuple[Sequence[BoxInstance], Sequence[BoxInstance]]],
    classes: Sequence[str],
    *,
    iou_threshold: float = 0.25,
    oriented: bool = False,
) -> dict[str, float]:
    """Box AP per class (and ``"mean"`` over classes with ground truth) over many scenes.

    Parameters
    ----------
    scenes : sequence of (predictions, ground truth)
        Each scene's boxes; boxes of classes outside ``classes`` are ignored.
    classes : sequence of str
    iou_threshold : float
    oriented : bool
        Oriented IoU instead of VoteNet's axis-aligned one.

    Returns
    -------
    dict of str to float
        AP per class (NaN for a class without ground truth) and ``"mean"``.

    Examples
    --------
    >>> gt = [BoxInstance.make("chair", [0, 0, 0.5], [1, 1, 1])]
    >>> pred = [BoxInstance.make("chair", [0.1, 0, 0.5], [1, 1, 1], score=0.9),
    ...         BoxInstance.make("chair", [5, 5, 0.5], [1, 1, 1], score=0.95)]
    >>> box_average_precision([(pred, gt)], ["chair"])
    {'chair': 0.5, 'mean': 0.5}
    """
    out: dict[str, float] = {}
    for c in classes:
        entries: list[tuple[float, int, BoxInstance]] = []
        gts: list[list[BoxInstance]] = []
        for k, (preds, truth) in enumerate(scenes):
            entries += [(p.score, k, p) for p in preds if p.label == c]
            gts.append([g for g in truth if g.label == c])
        num_gt = sum(len(g) for g in gts)
        entries.sort(key=lambda e: -e[0])  # stable: ties keep scene order
        used = [np.zeros(len(g), dtype=bool) for g in gts]
        tps = []
        for _, k, p in entries:
            ious = [box_iou(p, g, oriented=oriented) for g in gts[k]]
            free = [(iou, j) for j, iou in enumerate(ious) if not used[k][j]]
            best = max(free, default=(0.0, -1))
            hit = best[1] >= 0 and best[0] >= iou_threshold
            if hit:
                used[k][best[1]] = True
            tps.append(hit)
        scores = np.array([e[0] for e in entries], dtype=np.float64)
        out[c] = average_precision(scores, np.array(tps, dtype=bool), num_gt)
    valid = [v for v in out.values() if not np.isnan(v)]
    out["mean"] = float(np.mean(valid)) if valid else float("nan")
    return out


def boxes_from_instances(
    boxes: Sequence[Mapping[str, Any]] | Sequence[Sequence[float]],
    class_ids: Mapping[int, str],
) -> list[BoxInstance]:
    """Ground-truth boxes of the evaluated classes from a dataset's own box list.

    Accepts VoteNet's ScanNet rows ``[cx, cy, cz, dx, dy, dz, nyu40id]`` (axis-aligned) and
    the simulator's objects (``{"class_id": .., "box": {"center", "size", "yaw"}}``).
    Boxes of classes outside ``class_ids`` are left out.
    """
    out = []
    for b in boxes:
        if isinstance(b, Mapping):
            cid = int(b.get("class_id", -1))
            box = b.get("box") or {}
            if cid in class_ids and box:
                out.append(
                    BoxInstance.make(
                        class_ids[cid], box["center"], box["size"], float(box.get("yaw", 0.0))
                    )
                )
        else:
            row = [float(v) for v in b]
            cid = round(row[6])
            if cid in class_ids:
                out.append(BoxInstance.make(class_ids[cid], row[0:3], row[3:6]))
    return out
