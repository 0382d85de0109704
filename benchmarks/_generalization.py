"""The reusable parts of the generalization benchmark, small enough to test on hand-made data.

- :func:`reappearance` / :func:`lost_references`: how many reference detections come back
  after the input changed, and which do not;
- :data:`STABILITY_TRANSFORMS` / :func:`stability_transforms`: the changes of input a
  detector should not notice (turns, a large offset, rounding, jitter, a shuffle, a subsample);
- :func:`robustness_changes`: what sensors and pipelines do to real scans beyond that
  (a centimetre of noise, a floor barely seen, two registrations of one scan merged);
- :func:`false_detection_causes`: what a false detection really is (the ground-truth object
  holding most of its points, or nothing);
- :func:`recall_by_group`: recall of the ground-truth objects per group (furniture family);
- :func:`instance_names`: instance id -> (class, kind) from per-point labels.

Everything here takes detections and ground truth as :class:`ontodetect.evaluation.Instance`
(point indices are rows of the scan's file) and plain arrays; nothing reads files.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ontodetect.cloud import PointCloud, point_cloud, sensor_position
from ontodetect.evaluation import Instance, match_instances, turn_cloud
from ontodetect.geometry import point_overlap
from ontodetect.preprocess import turn_quarters

__all__ = [
    "DOUBLE_JITTER",
    "FLOOR_LOSS",
    "JITTER_SIGMA",
    "MISSED_CAUSES",
    "NOISE_SIGMA",
    "NOTHING",
    "OFFSET",
    "ROUNDING",
    "STABILITY_IOU",
    "STABILITY_TURNS",
    "SUBSAMPLE_SHARE",
    "false_detection_causes",
    "instance_names",
    "lost_references",
    "missed_causes",
    "reappearance",
    "recall_by_group",
    "robustness_changes",
    "rows_to_values",
    "stability_transforms",
]

#: A reference detection reappears when a detection of the same label overlaps it this much.
STABILITY_IOU = 0.5
#: Turns about the vertical (degrees): the quarter turns a voxel grid should not notice, and
#: angles in between that meet other voxel boundaries.
STABILITY_TURNS = (90.0, 180.0, 270.0, 15.0, 30.0, 45.0, 60.0)
#: A large horizontal offset (m), as a scan georeferenced in UTM coordinates carries.
OFFSET = (4.0e5, 4.0e5, 0.0)
#: Rounding of the coordinates (m): 1 mm, as many exchange formats store them.
ROUNDING = 1e-3
#: Std of a Gaussian jitter of every coordinate (m): 0.5 mm, below any sensor's noise.
JITTER_SIGMA = 5e-4
#: Share of the points kept by the subsample.
SUBSAMPLE_SHARE = 0.8
#: What a false detection is when most of its points belong to no labelled object.
NOTHING = "nothing"


# -- stability -----------------------------------------------------------------------------
def lost_references(
    reference: Sequence[Instance],
    other: Sequence[Instance],
    *,
    iou_threshold: float = STABILITY_IOU,
    kept: ArrayLike | None = None,
) -> list[int]:
    """Positions in ``reference`` of the detections that do not reappear among ``other``.

    A reference detection reappears when a detection of the same label overlaps it with
    point IoU >= ``iou_threshold``; pairs are made one to one, greedily by descending score
    of ``other`` (:func:`ontodetect.evaluation.match_instances`), so one detection cannot
    stand for two.

    Parameters
    ----------
    reference, other : sequences of Instance
        Detections on the scan as is and on a changed copy; points are rows of the
        original scan (a subsample keeps its points' original rows).
    iou_threshold : float
    kept : (k,) int, optional
        Rows of the original scan present in the changed copy (a subsample): reference
        detections are cut to these rows first, so that a detection found again on every
        point still there counts, whatever share of its points the subsample dropped.

    Examples
    --------
    >>> ref = [Instance.make(1, "chair", range(10)), Instance.make(2, "table", range(20, 40))]
    >>> new = [Instance.make(1, "chair", range(2, 12)), Instance.make(2, "sofa", range(20, 40))]
    >>> lost_references(ref, new)  # the chair: IoU 8/12; the table came back as a sofa
    [1]
    """
    refs = list(reference)
    if kept is not None:
        rows = np.unique(np.asarray(kept, dtype=np.int64))
        refs = [
            Instance.make(r.id, r.label, np.intersect1d(r.points, rows), r.score, r.center)
            for r in refs
        ]
    if not refs:
        return []
    m = match_instances(list(other), refs, iou_threshold=iou_threshold)
    return [int(i) for i in np.flatnonzero(np.asarray(m.gt_match) < 0)]


def reappearance(
    reference: Sequence[Instance],
    other: Sequence[Instance],
    *,
    iou_threshold: float = STABILITY_IOU,
    kept: ArrayLike | None = None,
) -> tuple[int, int]:
    """How many reference detections reappear among ``other`` (:func:`lost_references`,
    whose parameters it takes): ``(reappeared, total)``, ``total`` being ``len(reference)``.

    Examples
    --------
    >>> ref = [Instance.make(1, "chair", range(10)), Instance.make(2, "table", range(20, 40))]
    >>> new = [Instance.make(1, "chair", range(2, 12)), Instance.make(2, "sofa", range(20, 40))]
    >>> reappearance(ref, new)
    (1, 2)
    """
    total = len(reference)
    lost = lost_references(reference, other, iou_threshold=iou_threshold, kept=kept)
    return total - len(lost), total


def _turn(degrees: float) -> Callable[[PointCloud, np.random.Generator], PointCloud]:
    def fn(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
        return turn_cloud(cloud, degrees)

    return fn


def _offset(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    shift = np.asarray(OFFSET)
    out = cloud.replace(xyz=cloud.xyz + shift)
    eye = sensor_position(cloud)
    return out if eye is None else out.with_meta(sensor_position=(eye + shift).tolist())


def _round(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    return cloud.replace(xyz=np.round(cloud.xyz / ROUNDING) * ROUNDING)


def _jitter(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    return cloud.replace(xyz=cloud.xyz + rng.normal(0.0, JITTER_SIGMA, cloud.xyz.shape))


def _shuffle(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    return cloud.select(rng.permutation(len(cloud)))


def _subsample(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    keep = rng.choice(len(cloud), round(SUBSAMPLE_SHARE * len(cloud)), replace=False)
    return cloud.select(np.sort(keep))


def stability_transforms(
    turns: Sequence[float] = STABILITY_TURNS,
) -> dict[str, Callable[[PointCloud, np.random.Generator], PointCloud]]:
    """Name -> ``fn(cloud, rng)`` giving a changed copy of a scan that keeps its rows.

    Every copy keeps each point's row (``index``), so detections on it are compared with
    those on the original over the original rows: turns about the vertical by ``turns``
    degrees, an offset of :data:`OFFSET`, rounding to :data:`ROUNDING`, a Gaussian jitter
    of :data:`JITTER_SIGMA`, the points shuffled, and :data:`SUBSAMPLE_SHARE` of them kept.

    Examples
    --------
    >>> list(stability_transforms([90]))
    ['turn 90°', 'offset 400000 m', 'round 1 mm', 'jitter 0.5 mm', 'shuffle', 'subsample 80 %']
    """
    out: dict[str, Callable[[PointCloud, np.random.Generator], PointCloud]] = {
        f"turn {t:g}°": _turn(float(t)) for t in turns
    }
    out[f"offset {OFFSET[0]:g} m"] = _offset
    out[f"round {ROUNDING * 1e3:g} mm"] = _round
    out[f"jitter {JITTER_SIGMA * 1e3:g} mm"] = _jitter
    out["shuffle"] = _shuffle
    out[f"subsample {SUBSAMPLE_SHARE * 100:.0f} %"] = _subsample
    return out


#: Every transform of the benchmark, by name.
STABILITY_TRANSFORMS = stability_transforms()


# -- robustness ----------------------------------------------------------------------------
#: Std (m) of the noise added to every coordinate: a consumer depth camera's at 2-3 m
#: (Nguyen, Izadi & Lovell 2012: 1.2 + 1.9 (z - 0.4)^2 mm along the ray, 9.6 mm at 2.5 m).
NOISE_SIGMA = 0.01
#: Share of the floor's points a copy loses: a floor the sensor met only at grazing angles.
FLOOR_LOSS = 0.8
#: NYU40 id of the floor (ScanNet's labels, the simulator's too).
FLOOR_CLASS = 2
#: Std (m) of the jitter of the second copy of every point: two registrations of one scan
#: merged, 5 mm apart.
DOUBLE_JITTER = 0.005
#: Share of the points a copy keeps: a fixed-size subsample (ScanNet's 50,000 vertices per
#: room, as VoteNet prepares them) of a room with twice the surface, or a sparser sensor.
HALF_SHARE = 0.5
#: ... and a room with four times the surface (a 50 m² room's 50,000 points spread over a
#: 200 m² hall or open-plan floor).
QUARTER_SHARE = 0.25


def _noise(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    return cloud.replace(xyz=cloud.xyz + rng.normal(0.0, NOISE_SIGMA, cloud.xyz.shape))


def _floor_unseen(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    floor = np.asarray(cloud.fields["class_id"]) == FLOOR_CLASS
    return cloud.select(np.flatnonzero(~(floor & (rng.random(len(cloud)) < FLOOR_LOSS))))


def _doubled(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
    copy = cloud.xyz + rng.normal(0.0, DOUBLE_JITTER, cloud.xyz.shape)
    return point_cloud(
        np.vstack([cloud.xyz, copy]),
        rgb=None if cloud.rgb is None else np.vstack([cloud.rgb, cloud.rgb]),
        fields={k: np.concatenate([v, v]) for k, v in cloud.fields.items()},
    )


def _kept(share: float) -> Callable[[PointCloud, np.random.Generator], PointCloud]:
    def keep(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
        return cloud.select(np.flatnonzero(rng.random(len(cloud)) < share))

    return keep


#: Quarter turns of the file's axes about z (exact: axes swapped and negated), a scan
#: written by a tool with other axes: beside the scans as they are, how much of their
#: figures is the draw of their files' axes.
AXES_TURNS = (1, 2, 3)


def _axes_turned(quarters: int) -> Callable[[PointCloud, np.random.Generator], PointCloud]:
    def turn(cloud: PointCloud, rng: np.random.Generator) -> PointCloud:
        normals = None if cloud.normals is None else turn_quarters(cloud.normals, quarters)
        out = cloud.replace(xyz=turn_quarters(cloud.xyz, quarters), normals=normals)
        eye = sensor_position(cloud)
        if eye is None:
            return out
        return out.with_meta(sensor_position=turn_quarters(eye, quarters).tolist())

    return turn


def robustness_changes() -> dict[str, Callable[[PointCloud, np.random.Generator], PointCloud]]:
    """Name -> ``fn(cloud, rng)``: a labelled scan changed as sensors and pipelines change
    real scans, beyond what the stability changes do (those keep the scan as it was made).

    Every copy keeps the per-point labels (``instance``, ``class_id``), so it is scored
    against its own ground truth: Gaussian noise of :data:`NOISE_SIGMA` on every
    coordinate, :data:`FLOOR_LOSS` of the floor's points (class :data:`FLOOR_CLASS`)
    removed, every point twice, the copy jittered by :data:`DOUBLE_JITTER` (new rows),
    each point kept with probability :data:`HALF_SHARE`, or :data:`QUARTER_SHARE`, and the
    file's axes turned by :data:`AXES_TURNS` quarter turns about z.

    Examples
    --------
    >>> list(robustness_changes())  # doctest: +NORMALIZE_WHITESPACE
    ['noise 1 cm', 'floor 80 % unseen', 'points doubled', 'half the points',
     'a quarter of the points', 'axes turned 90°', 'axes turned 180°', 'axes turned 270°']
    """
    return {
        f"noise {NOISE_SIGMA * 100:g} cm": _noise,
        f"floor {FLOOR_LOSS * 100:.0f} % unseen": _floor_unseen,
        "points doubled": _doubled,
        "half the points": _kept(HALF_SHARE),
        "a quarter of the points": _kept(QUARTER_SHARE),
        **{f"axes turned {90 * q}°": _axes_turned(q) for q in AXES_TURNS},
    }


#: The robustness row of the real scans as they are and their files' axes turned, pooled.
POOLED = "as they are and axes turned, pooled"


def pooled_orientations(
    real: Mapping[str, Mapping[str, Any]] | None, changes: Mapping[str, Mapping[str, Any]]
) -> dict[str, dict[str, float]] | None:
    """TP/det/GT per class summed over the real scans as they are and their files' axes
    turned by :data:`AXES_TURNS`: the real figure with the draw of the files' axes pooled
    (``None`` unless all four were measured).

    The same 13 scans read in four orientations are 52 readings of one room set: a change
    judged on the scans as they are alone is judged on one draw of four, which moves the
    chairs found by two with nothing but the axes.

    Examples
    --------
    >>> one = {"chair": {"tp": 2, "det": 3, "gt": 4}}
    >>> turned = {f"axes turned {90 * q}°": {"per_class": one} for q in AXES_TURNS}
    >>> pooled_orientations(one, turned)["chair"]
    {'tp': 8, 'det': 12, 'gt': 16, 'precision': 0.6667, 'recall': 0.5}
    >>> pooled_orientations(one, turned)["overall"]["tp"]  # the classes summed
    8
    >>> pooled_orientations(one, {}) is None
    True
    """
    names = [f"axes turned {90 * q}°" for q in AXES_TURNS]
    if real is None or any(n not in changes for n in names):
        return None
    figs = [real] + [changes[n].get("per_class", {}) for n in names]
    classes = sorted({c for f in figs for c in f} - {"overall"})
    out: dict[str, dict[str, float]] = {}
    for c in [*classes, "overall"]:
        tp, det, gt = (
            sum(
                int(f.get(k, {}).get(key, 0))
                for f in figs
                for k in (classes if c == "overall" else [c])
            )
            for key in ("tp", "det", "gt")
        )
        out[c] = class_figures(tp, det, gt)
    return out


def class_figures(tp: int, det: int, gt: int) -> dict[str, float]:
    """One class's figures as generalization.json holds them: TP, detections, ground truth,
    precision and recall (0 where there is nothing to divide by), to four places.

    >>> class_figures(2, 3, 4)
    {'tp': 2, 'det': 3, 'gt': 4, 'precision': 0.6667, 'recall': 0.5}
    """
    return {
        "tp": tp,
        "det": det,
        "gt": gt,
        "precision": round(tp / det, 4) if det else 0.0,
        "recall": round(tp / gt, 4) if gt else 0.0,
    }


# -- what the detections hit ---------------------------------------------------------------
def rows_to_values(index: ArrayLike, values: ArrayLike, fill: int = 0) -> NDArray[np.int64]:
    """A per-row array: ``values`` placed at the rows ``index`` names, ``fill`` elsewhere.

    Examples
    --------
    >>> rows_to_values([2, 0], [7, 5]).tolist()
    [5, 0, 7]
    """
    idx = np.asarray(index, dtype=np.int64)
    out = np.full(int(idx.max()) + 1 if len(idx) else 0, fill, dtype=np.int64)
    out[idx] = np.asarray(values, dtype=np.int64)
    return out


def instance_names(
    instance: ArrayLike, class_id: ArrayLike, names: Mapping[int, str]
) -> dict[int, tuple[str, str]]:
    """Instance id -> (class name, kind) from per-point labels, for real scans.

    The class is the most common class id among the instance's points (as
    :func:`ontodetect.evaluation.instances_from_labels` decides); a real scan has no kind,
    so the kind is the class name again. Unknown ids are named ``class <id>``.

    Examples
    --------
    >>> instance_names([1, 1, 1, 2], [5, 5, 3, 1], {5: "chair", 1: "wall"})
    {1: ('chair', 'chair'), 2: ('wall', 'wall')}
    """
    inst = np.asarray(instance, dtype=np.int64)
    cls = np.asarray(class_id, dtype=np.int64)
    out: dict[int, tuple[str, str]] = {}
    pairs, counts = np.unique(np.stack([inst, cls], 1), axis=0, return_counts=True)
    for iid in np.unique(inst):
        if iid <= 0:
            continue
        mine = pairs[:, 0] == iid
        cid = int(pairs[mine][np.argmax(counts[mine]), 1])
        name = names.get(cid, f"class {cid}")
        out[int(iid)] = (name, name)
    return out


def false_detection_causes(
    preds: Sequence[Instance],
    gts: Sequence[Instance],
    instance_by_row: ArrayLike,
    what: Mapping[int, tuple[str, str]],
    *,
    iou_threshold: float = 0.25,
) -> list[dict[str, Any]]:
    """What each false detection really is.

    Detections are matched to the ground truth as the evaluation does (same class, point
    IoU >= ``iou_threshold``, greedily by score); for every detection left unmatched, the
    labelled object holding most of its points is looked up in ``what``. Points of no object
    (instance 0, or rows beyond the labels) count for :data:`NOTHING`; ties go to the lower
    instance id.

    Parameters
    ----------
    preds, gts : sequences of Instance
        Detections and the evaluated ground-truth objects (rows of the scan).
    instance_by_row : (n,) int
        Instance id of every row of the scan, 0 for none.
    what : mapping of int to (str, str)
        Instance id -> (class, kind) of every labelled object (structure too: wall, floor).

    Returns
    -------
    list of dict
        Per false detection, in the order of ``preds``: ``id``, ``label`` (what it was
        detected as), ``is`` (class of the object holding most of its points, or
        ``nothing``), ``kind``, ``instance`` (0 for nothing) and ``share`` (of its points
        on that object).

    Examples
    --------
    >>> inst = np.array([0, 0, 1, 1, 1, 2, 2, 2, 2, 2])
    >>> gts = [Instance.make(2, "chair", [5, 6, 7, 8, 9])]
    >>> dets = [Instance.make(1, "chair", [5, 6, 7, 8], 0.9),
    ...         Instance.make(2, "chair", [0, 1, 2, 3, 4], 0.8)]
    >>> [(f["id"], f["is"], f["share"]) for f in false_detection_causes(
    ...     dets, gts, inst, {1: ("cabinet", "nightstand"), 2: ("chair", "chair-office")})]
    [(2, 'cabinet', 0.6)]
    """
    owners = np.asarray(instance_by_row, dtype=np.int64)
    preds = list(preds)
    m = match_instances(preds, list(gts), iou_threshold=iou_threshold)
    out = []
    for p, k in zip(preds, m.pred_match):
        if k >= 0:
            continue
        pts = p.points
        ids = np.where(pts < len(owners), owners[np.minimum(pts, max(len(owners) - 1, 0))], 0)
        if not len(ids):
            values, counts = np.array([0]), np.array([0])
        else:
            values, counts = np.unique(ids, return_counts=True)
        best = int(values[np.argmax(counts)])  # unique sorts: ties go to the lower id
        cls, kind = (NOTHING, NOTHING) if best <= 0 else what.get(best, (NOTHING, NOTHING))
        share = float(counts.max()) / len(pts) if len(pts) else 0.0
        out.append(
            {
                "id": p.id,
                "label": p.label,
                "is": cls,
                "kind": kind,
                "instance": best if cls != NOTHING else 0,
                "share": round(share, 4),
            }
        )
    return out


def recall_by_group(
    preds: Sequence[Instance],
    gts: Sequence[Instance],
    group_of: Mapping[int, str],
    *,
    iou_threshold: float = 0.25,
) -> dict[str, list[int]]:
    """Found and total ground-truth objects per group (a furniture family, a kind).

    Objects are matched as the evaluation matches them (same class, point IoU >=
    ``iou_threshold``, greedily by score); an object whose id ``group_of`` does not
    know goes to the group named by its class.

    Returns
    -------
    dict of str to [found, total]
        In order of first appearance among ``gts``.

    Examples
    --------
    >>> gts = [Instance.make(1, "chair", range(10)), Instance.make(2, "chair", range(10, 20))]
    >>> dets = [Instance.make(1, "chair", range(10), 0.9)]
    >>> recall_by_group(dets, gts, {1: "chair-office", 2: "chair-armchair"})
    {'chair-office': [1, 1], 'chair-armchair': [0, 1]}
    """
    gts = list(gts)
    m = match_instances(list(preds), gts, iou_threshold=iou_threshold)
    out: dict[str, list[int]] = {}
    for g, k in zip(gts, m.gt_match):
        tally = out.setdefault(group_of.get(g.id, g.label), [0, 0])
        tally[0] += int(k >= 0)
        tally[1] += 1
    return out


#: Why a ground-truth object was missed (:func:`missed_causes`), in the order a pass's
#: steps would lose it.
MISSED_CAUSES = ("not clustered", "split", "merged", "scored", "vote")


def missed_causes(
    preds: Sequence[Instance],
    gts: Sequence[Instance],
    clusters: Sequence[Instance],
    *,
    iou_threshold: float = 0.25,
    lacks: Sequence[Mapping[str, str]] = (),
) -> list[dict[str, Any]]:
    """Where each missed ground-truth object was lost: segmentation, scoring or the vote.

    Objects are matched as the evaluation matches them; for every object left unmatched,
    the first pass's cluster sharing most of its points decides:

    - ``not clustered``: no cluster holds any of its points;
    - ``split``: that cluster holds less than half of the object;
    - ``merged``: it holds half or more, but with so much else that the point IoU is
      below ``iou_threshold``;
    - ``scored``: it is the object (IoU at the threshold or more) and the first pass
      labelled it otherwise (another class, or nothing);
    - ``vote``: the first pass labelled it right and the other passes did not agree.

    Parameters
    ----------
    preds, gts : sequences of Instance
        Detections and the evaluated ground-truth objects (rows of the scan).
    clusters : sequence of Instance
        The first pass's clusters (rows of the scan), each with the label the first pass
        gave it ("" for none): :attr:`ontodetect.evaluation.SceneOutcome.clusters`.
    lacks : sequence of mapping, optional
        Per cluster, what its reading as each label lacked most
        (:attr:`ontodetect.evaluation.SceneOutcome.cluster_lacks`).

    Returns
    -------
    list of dict
        Per missed object, in the order of ``gts``: ``id``, ``label``, ``cause``, ``iou``
        and ``cover`` (share of the object in the cluster) of the best cluster, the
        cluster's ``as`` (its first-pass label, "" for none) and, for an object lost to
        the scoring, ``lacks``: the factor that weighed most against reading the cluster
        as the object's class ("" otherwise, or without ``lacks``).

    Examples
    --------
    >>> gts = [Instance.make(1, "chair", range(10)), Instance.make(2, "chair", range(10, 20)),
    ...        Instance.make(3, "table", range(60, 70))]
    >>> clusters = [Instance.make(0, "chair", range(10)), Instance.make(1, "", range(10, 60)),
    ...             Instance.make(2, "chair", range(60, 70))]
    >>> [(m["id"], m["cause"], m["as"]) for m in missed_causes([], gts, clusters)]
    [(1, 'vote', 'chair'), (2, 'merged', ''), (3, 'scored', 'chair')]
    >>> lacks = [{}, {}, {"table": "top.open_below"}]
    >>> [m["lacks"] for m in missed_causes([], gts, clusters, lacks=lacks)]
    ['', '', 'top.open_below']
    """
    gts = list(gts)
    m = match_instances(list(preds), gts, iou_threshold=iou_threshold)
    missed = [g for g, k in zip(gts, m.gt_match) if k < 0]
    if not missed:
        return []
    iou, inter = point_overlap([g.points for g in missed], [c.points for c in clusters])
    out = []
    for i, g in enumerate(missed):
        if not len(clusters) or inter[i].max() == 0:
            out.append({"id": g.id, "label": g.label, "cause": "not clustered",
                        "iou": 0.0, "cover": 0.0, "as": "", "lacks": ""})  # fmt: skip
            continue
        j = int(np.argmax(inter[i]))
        cover = float(inter[i, j]) / len(g.points)
        if iou[i, j] >= iou_threshold:
            cause = "vote" if clusters[j].label == g.label else "scored"
        else:
            cause = "merged" if cover >= 0.5 else "split"
        out.append(
            {
                "id": g.id,
                "label": g.label,
                "cause": cause,
                "iou": round(float(iou[i, j]), 4),
                "cover": round(cover, 4),
                "as": clusters[j].label,
                "lacks": lacks[j].get(g.label, "") if cause == "scored" and lacks else "",
            }
        )
    return out
