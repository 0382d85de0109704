"""Calibrating an ontology's Gaussians on labelled scans, checked on scans kept aside.

For every ground-truth object of a class in the calibration scenes, the segmentation
cluster that overlaps it most (point IoU, at least :data:`MIN_CLUSTER_IOU`) is scored
against the class with :func:`~ontodetect.ontology.score_class` (where several classes
match one ground truth, such as a table and a side table, against the one that explains
the cluster best: :func:`best_kind`); the best assignment of its planes to the class's
parts gives one measured value of every constraint of the class (part, relation and
cluster features).

Each Gaussian is then re-estimated as the posterior of a conjugate normal model whose
prior is the ontology's own constraint, worth :data:`PRIOR_STRENGTH` objects
(:class:`FitSettings`, :func:`fit_gaussian`). Objects of one room count as at most
:data:`ROOM_SAMPLES` independent samples (a room's chairs are often copies of one model),
so with few objects or rooms the estimate stays near the prior:

- two-sided ``{mean, sigma}`` and ranges ``[low, high]``: μ and σ² are the blends
  ``(1 − w) μ0 + w x̄`` and ``(1 − w) σ0² + w s² + w (1 − w) (x̄ − μ0)²`` with
  ``w = n / (κ0 + n)``; the last term widens σ when the data disagree with the prior;
  σ is at least :data:`PRIOR_SIGMA_SHARE` × the prior's σ and a per-feature floor; a
  range is written back as [μ − σ, μ + σ];
- one-sided ``{min: a}`` / ``{max: b}`` stay one-sided and plateaus
  ``{min: a, max: b, soft: s}`` stay plateaus: the data's estimate of an end is the
  extreme value (or the :data:`ONE_SIDED_QUANTILE` quantile) pushed outwards by the
  expected gap between the extreme of ``n`` samples and the end of their support,
  ``range / (n − 1)``, and blended with the prior's end by the same ``w``. An end thus
  never moves inside what the samples support; ``soft`` (where the file has it) blends
  the prior's softness with the sample spread, with the same floors, and like the bound
  only ever loosens.

Constraints with fewer than :data:`MIN_SAMPLES` values, or with values from fewer than
:data:`MIN_ROOMS` rooms (rescans of a room measure the same objects again), keep their
prior.

A fitted change is only kept where it does not hurt detection on rooms it was not fitted
on, judged inside the calibration rooms alone (:func:`select_groups`): constraints are
grouped by class and part (or relation, or cluster rules); each calibration room in turn
is detected on with an ontology fitted on the other calibration rooms, and, group by
group in file order, a group's change is accepted only if it lowers no F1 (per class or
overall, pooled or in any single validation room) and raises one in at least
:data:`MIN_GAIN_ROOMS` validation rooms, a one-sided sign test over the rooms. With fewer
calibration rooms than that, nothing can be validated and nothing changes. The held-out
rooms are never looked at.

The YAML keeps its structure (same classes, parts, relations and keys; only numbers
change); comments are not kept.

Scenes are split by :func:`split_scenes` into a calibration and a held-out set by room,
so rescans of one room never sit on both sides; the held-out scenes are only used to
compare detection before and after.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
import os
import textwrap
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .._progress import progress
from ..errors import InvalidParameterError
from ..io._textfile import read_text
from ._dataset import (
    DatasetEvaluation,
    SceneSource,
    _check_detect_options,
    _class_id_lists,
    _class_ids,
    _natural_key,
    discover_scenes,
    evaluate_dataset,
    map_scenes,
    read_scene_cloud,
    scene_group,
)
from ._match import Instance, instances_from_labels, overlap_matrix

__all__ = [
    "CalibrationResult",
    "ConstraintFit",
    "FitSettings",
    "GroupDecision",
    "SceneSamples",
    "SceneSplit",
    "ValidationScene",
    "best_kind",
    "calibrate_dataset",
    "calibrate_ontology",
    "collect_scene_samples",
    "constraint_group",
    "constraint_values",
    "fit_constraints",
    "fit_gaussian",
    "select_groups",
    "split_scenes",
    "validation_rooms",
]

#: A ground-truth object calibrates only through a cluster with at least this point IoU
#: (the overlap a detection needs to count, DESIGN.md).
MIN_CLUSTER_IOU = 0.25
#: Constraints measured fewer times than this keep their prior...
MIN_SAMPLES = 3
#: ...and so do constraints measured in fewer rooms than this.
MIN_ROOMS = 2
#: σ is never below this share of the prior's σ... On held-out ScanNet rooms a quarter let
#: σ shrink so far that objects of other rooms failed several constraints at once (every
#: factor multiplies); half kept recall.
PRIOR_SIGMA_SHARE = 0.5
#: Weight of the ontology's own value, in objects (κ0 = ν0 of the conjugate normal prior):
#: the rules were written for every chair, a few dozen measured chairs of a handful of
#: rooms should move them only part of the way.
PRIOR_STRENGTH = 8.0
#: The objects of one room count as at most this many independent samples: a room's
#: chairs are often copies of one model, seen under the same sensor noise.
ROOM_SAMPLES = 3
#: A validation F1 "does not fall" when it is lower by at most this (float noise).
F1_TOLERANCE = 1e-9
#: The nested check keeps a group only when its gain shows in at least this many
#: calibration rooms left out in turn, with no loss in any: a one-sided sign test over
#: the left-out rooms. A change that does nothing, helping or hurting each room by
#: chance, gains in k rooms and loses in none with probability 2^-k: 4 rooms is the
#: least for 90 % confidence (p = 0.0625; 3 rooms give only 0.125). On ScanNet rooms a
#: gain in 2 of 3 rooms (p = 0.25) came from one or two detections per room and cost
#: recall on held-out rooms. With fewer calibration rooms to leave out, nothing can be
#: validated and the original is kept.
MIN_GAIN_ROOMS = 4
#: ...nor below these absolute floors (units of the feature: m, degrees, m², ratios).
ABS_SIGMA_FLOOR: dict[str, float] = {
    "tilt": 1.0,
    "angle": 2.0,
    "height": 0.02,
    "top": 0.02,
    "bottom": 0.02,
    "gap": 0.02,
    "distance": 0.01,
    "length": 0.03,
    "width": 0.03,
    "breadth": 0.03,
    "area": 0.01,
    "fill": 0.03,
    "open_below": 0.03,
    "overlap": 0.03,
    "rise": 0.02,
    "planes": 0.5,
}
#: A one-sided bound or plateau end moves to this quantile of the values (``min``; 1 - it
#: for ``max``). 0 takes the extreme value, the maximum-likelihood end of a flat range; a
#: larger share ignores outliers but, with a few dozen objects, cuts off real ones.
ONE_SIDED_QUANTILE = 0.0
#: Significant digits of the numbers written to the calibrated file (more when needed).
DIGITS = 4
MAX_DIGITS = 15
#: Strings longer than this are written as folded blocks.
LONG_TEXT = 60
#: Width of the lines of the written file.
LINE_WIDTH = 96

#: A constraint's place in the YAML: (class, "parts", part, feature),
#: (class, "relations", index, feature) or (class, "cluster", feature).
ConstraintPath = tuple[Any, ...]


# -- split ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class SceneSplit:
    """Scenes for calibration and scenes kept aside, split by room.

    Attributes
    ----------
    calibration, held_out : list
        The scenes (SceneSource or names), each in the order given.
    fraction : float
        Share of the rooms asked for calibration.
    seed : int
        Seed of the split.
    """

    calibration: list[Any]
    held_out: list[Any]
    fraction: float
    seed: int

    def groups(self, side: str) -> list[str]:
        """Rooms on one side (``"calibration"`` or ``"held_out"``)."""
        items = getattr(self, side)
        return sorted({_group_of(s) for s in items}, key=_natural_key)

    def describe(self) -> str:
        """One line naming the rooms of each side and how they were drawn."""
        cal, held = self.groups("calibration"), self.groups("held_out")
        return (
            f"split seed {self.seed}, {self.fraction:g} of the rooms for calibration: "
            f"calibration {', '.join(cal)} ({len(self.calibration)} scenes); held out "
            f"{', '.join(held) or 'none'} ({len(self.held_out)} scenes)"
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "fraction": self.fraction,
            "seed": self.seed,
            "calibration": [_name_of(s) for s in self.calibration],
            "held_out": [_name_of(s) for s in self.held_out],
            "calibration_rooms": self.groups("calibration"),
            "held_out_rooms": self.groups("held_out"),
        }


def _name_of(scene: Any) -> str:
    return scene.name if isinstance(scene, SceneSource) else str(scene)


def _group_of(scene: Any) -> str:
    return scene.group if isinstance(scene, SceneSource) else scene_group(str(scene))


def split_scenes(scenes: Sequence[Any], fraction: float = 0.5, seed: int = 0) -> SceneSplit:
    """Split scenes into calibration and held-out sets, keeping each room on one side.

    Rooms (:func:`~ontodetect.evaluation.scene_group`: ``scene0000_00``, ``_01`` and
    ``_02`` are one room) are put in natural order and shuffled with ``seed``; the
    first ``round(fraction × rooms)`` go to calibration (at least one room on each
    side when ``fraction < 1``; ``fraction = 1`` keeps nothing aside).

    Parameters
    ----------
    scenes : sequence of SceneSource or str
    fraction : float
        Share of the rooms used for calibration, in (0, 1].
    seed : int

    Examples
    --------
    >>> s = split_scenes(["scene0000_00", "scene0000_01", "scene0002_00", "scene0003_00"],
    ...                  0.5, seed=1)
    >>> sorted(s.groups("calibration") + s.groups("held_out"))
    ['scene0000', 'scene0002', 'scene0003']
    """
    if (
        isinstance(fraction, bool)
        or not isinstance(fraction, (int, float))
        or not (0.0 < fraction <= 1.0)
    ):
        raise InvalidParameterError("split", "a share of the rooms in (0, 1]", fraction)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidParameterError("seed", "a non-negative integer", seed)
    items = list(scenes)
    groups = sorted({_group_of(s) for s in items}, key=_natural_key)
    if not groups:
        raise InvalidParameterError("scenes", "at least one scene", "none")
    if fraction < 1.0 and len(groups) < 2:
        raise InvalidParameterError(
            "split", "1 (no held-out scenes) for a dataset of a single room", fraction
        )
    order = np.random.default_rng(int(seed)).permutation(len(groups))
    k = (
        len(groups)
        if fraction >= 1.0
        else int(np.clip(round(fraction * len(groups)), 1, len(groups) - 1))
    )
    chosen = {groups[i] for i in order[:k]}
    return SceneSplit(
        [s for s in items if _group_of(s) in chosen],
        [s for s in items if _group_of(s) not in chosen],
        float(fraction),
        int(seed),
    )


# -- measuring -----------------------------------------------------------------------------
def constraint_values(cls: Any, score: Any) -> dict[ConstraintPath, float]:
    """The measured value of every constraint of a :class:`~ontodetect.ontology.ClassScore`.

    Parameters
    ----------
    cls : ObjectClass
        The class scored.
    score : ClassScore
        ``score_class(cls, description)``: its constraints hold the values of the best
        assignment (parts without a plane and relations involving them have none).

    Returns
    -------
    dict
        Constraint path -> finite value.
    """
    parts = {p.name for p in cls.parts}
    used: set[tuple[int, str]] = set()
    out: dict[ConstraintPath, float] = {}
    for cv in score.constraints:
        if cv.gaussian is None or cv.value is None or not math.isfinite(cv.value):
            continue
        path: ConstraintPath | None = None
        if cv.part == "cluster":
            path = (cls.name, "cluster", cv.feature)
        elif cv.part in parts:
            path = (cls.name, "parts", cv.part, cv.feature)
        else:
            for i, rel in enumerate(cls.relations):
                if (
                    f"{rel.a}~{rel.b}" == cv.part
                    and cv.feature in rel.constraints
                    and (i, cv.feature) not in used
                ):
                    used.add((i, cv.feature))
                    path = (cls.name, "relations", i, cv.feature)
                    break
        if path is not None:
            out[path] = float(cv.value)
    return out


@dataclass(frozen=True)
class ValidationScene:
    """What re-detecting a calibration scene with another ontology needs.

    Segmentation does not depend on the ontology, so a scene is segmented once and its
    clusters are scored and labelled again for every candidate ontology.

    Attributes
    ----------
    name : str
    descriptions : tuple of ClusterDescription
        One per cluster.
    centers : (k, 3) float
        Cluster box centres (for the labelling's context term).
    members : tuple of (m,) int arrays
        Each cluster's points as rows of the input file.
    gts : tuple of Instance
        Ground truth of the reported classes, as rows of the input file.
    """

    name: str
    descriptions: tuple[Any, ...]
    centers: np.ndarray
    members: tuple[np.ndarray, ...]
    gts: tuple[Instance, ...]


@dataclass(frozen=True)
class SceneSamples:
    """Constraint values measured in one calibration scene.

    Attributes
    ----------
    name : str
    values : dict
        Constraint path -> list of values (one per object that calibrated it).
    used, skipped : dict of str to int
        Objects per class that gave values, and that had no cluster with point IoU
        >= :data:`MIN_CLUSTER_IOU`.
    error : str or None
    scene : ValidationScene or None
        The scene's clusters and ground truth, when asked for (``keep_clusters``).
    """

    name: str
    values: dict[ConstraintPath, list[float]] = field(default_factory=dict)
    used: dict[str, int] = field(default_factory=dict)
    skipped: dict[str, int] = field(default_factory=dict)
    error: str | None = None
    scene: ValidationScene | None = None


def best_kind(ontology: Any, names: Sequence[str], description: Any) -> tuple[Any, Any]:
    """Of the classes ``names`` (kinds of one ground-truth class, such as a table and a side
    table), the one whose likelihood on the cluster ``description`` is highest, with its
    :class:`ontodetect.ontology.ClassScore`; the first of equals."""
    from ..ontology import score_class

    if not names:
        raise InvalidParameterError("names", "at least one class name", names)
    scored = [(ontology[n], score_class(ontology[n], description)) for n in names]
    return max(scored, key=lambda t: t[1].log_likelihood)


def collect_scene_samples(
    source: SceneSource,
    ontology: Any,
    *,
    class_ids: Mapping[int, str] | None = None,
    segment_options: Mapping[str, Any] | None = None,
    min_iou: float = MIN_CLUSTER_IOU,
    keep_clusters: bool = False,
) -> SceneSamples:
    """Measure every constraint on the ground-truth objects of one scene.

    Parameters
    ----------
    source : SceneSource
    ontology : Ontology
        The classes whose constraints are measured.
    class_ids : mapping of int to str, optional
        Ground-truth class id -> ontology class name; from the classes' ``matches`` by
        default (including classes that are not reported, such as stools). Where several
        classes match one ground truth (a table and a side table), each object is measured
        against the one whose likelihood on its cluster is highest.
    segment_options : mapping, optional
        ``config``, ``seed``, ``up``, ``scale`` of :func:`ontodetect.segment.segment`.
    min_iou : float
        Least point IoU between an object and its cluster.
    keep_clusters : bool
        Also return the clusters and the reported classes' ground truth
        (:class:`ValidationScene`) for the nested check of :func:`select_groups`.
    """
    from ..errors import OntoDetectError
    from ..pipeline import describe_clusters
    from ..segment import segment

    opts = dict(segment_options or {})
    ids = _class_ids(ontology, reported_only=False, attr="name") if class_ids is None else class_ids
    # Classes that match the same ground truth (a table and a side table) are kinds of it:
    # each object is measured against the kind that explains its cluster best.
    kinds: dict[str, list[str]] = {}
    for names in _class_id_lists(ontology, reported_only=False, attr="name").values():
        group = kinds.setdefault(names[0], [])
        group.extend(n for n in names if n not in group)
    try:
        cloud = read_scene_cloud(source)
        gts = instances_from_labels(cloud.fields["instance"], cloud.fields["class_id"], ids)
        if not gts and not keep_clusters:
            return SceneSamples(source.name)
        seg = segment(
            cloud,
            opts.get("config"),
            seed=opts.get("seed", 0),
            up=opts.get("up"),
            scale=opts.get("scale"),
        )
    except OntoDetectError as exc:
        return SceneSamples(source.name, error=str(exc))
    clusters = [Instance.make(k, "cluster", c.point_indices) for k, c in enumerate(seg)]
    iou, _ = overlap_matrix(clusters, gts)
    values: dict[ConstraintPath, list[float]] = {}
    used: dict[str, int] = {}
    skipped: dict[str, int] = {}
    # Described as detect describes them, with what stands beside each cluster.
    descriptions = describe_clusters(seg)
    for g, gt in enumerate(gts):
        if not clusters or iou[:, g].max() < min_iou:
            skipped[gt.label] = skipped.get(gt.label, 0) + 1
            continue
        k = int(np.argmax(iou[:, g]))
        cls, score = best_kind(ontology, kinds.get(gt.label, [gt.label]), descriptions[k])
        for path, v in constraint_values(cls, score).items():
            values.setdefault(path, []).append(v)
        used[cls.name] = used.get(cls.name, 0) + 1
    scene = None
    if keep_clusters:
        # The same ground truth and point rows as evaluate_scene uses for detections.
        reported = _class_ids(ontology, reported_only=True, attr="label")
        eval_gts = instances_from_labels(
            cloud.fields["instance"],
            cloud.fields["class_id"],
            reported,
            xyz=cloud.xyz,
            index=cloud.index,
        )
        centers = np.array([c.box.center for c in seg]) if len(seg) else np.zeros((0, 3))
        scene = ValidationScene(
            source.name,
            tuple(descriptions),
            np.asarray(centers, dtype=np.float64),
            tuple(np.sort(cloud.index[c.point_indices]) for c in seg),
            tuple(eval_gts),
        )
    return SceneSamples(source.name, values, used, skipped, scene=scene)


# -- fitting -------------------------------------------------------------------------------
@dataclass(frozen=True)
class FitSettings:
    """How constraints are re-estimated and checked (see the module docstring).

    Attributes
    ----------
    prior_share : float
        σ is at least this share of the prior's σ (:data:`PRIOR_SIGMA_SHARE`).
    quantile : float
        One-sided bounds and plateau ends start from this quantile of the values (and
        1 − it); 0 is the smallest (largest) value (:data:`ONE_SIDED_QUANTILE`).
    min_samples : int
        Fewer values keep the prior (:data:`MIN_SAMPLES`).
    min_rooms : int
        Values from fewer rooms keep the prior (:data:`MIN_ROOMS`): rescans of one
        room measure the same objects again, so they say little about other rooms.
    prior_strength : float
        Weight of the prior, in objects (:data:`PRIOR_STRENGTH`); 0 is the plain
        maximum-likelihood fit.
    room_samples : int
        The objects of one room count as at most this many samples (:data:`ROOM_SAMPLES`).
    validate : bool
        Keep a fitted group of constraints only where the nested check inside the
        calibration rooms (:func:`select_groups`) finds that it does not lower F1.
    accept_ties : bool
        Also keep a group that changes no validation F1 (by default a change needs
        some evidence: it must raise one F1 and lower none).
    min_gain_rooms : int
        A group is kept only when F1 rises in at least this many calibration rooms
        left out in turn and falls in none (:data:`MIN_GAIN_ROOMS`); with fewer
        calibration rooms to leave out, nothing is validated and nothing changes.
    """

    prior_share: float = PRIOR_SIGMA_SHARE
    quantile: float = ONE_SIDED_QUANTILE
    min_samples: int = MIN_SAMPLES
    min_rooms: int = MIN_ROOMS
    prior_strength: float = PRIOR_STRENGTH
    room_samples: int = ROOM_SAMPLES
    validate: bool = True
    accept_ties: bool = False
    min_gain_rooms: int = MIN_GAIN_ROOMS

    def __post_init__(self) -> None:
        for name in ("prior_share", "prior_strength"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (
                isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0
            ):
                raise InvalidParameterError(name, "a finite number >= 0", value)
        if not (isinstance(self.quantile, (int, float)) and 0.0 <= self.quantile < 0.5):
            raise InvalidParameterError("quantile", "a number in [0, 0.5)", self.quantile)
        for name in ("min_samples", "min_rooms", "room_samples", "min_gain_rooms"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InvalidParameterError(name, "a positive integer", value)
        for name in ("validate", "accept_ties"):
            if not isinstance(getattr(self, name), bool):
                raise InvalidParameterError(name, "True or False", getattr(self, name))

    @property
    def validation_rooms(self) -> int:
        """Calibration rooms the nested check needs before it can accept any change."""
        # Leaving one room out needs another to fit on, and the gain must show in
        # min_gain_rooms of them.
        return max(2, self.min_gain_rooms)


def sigma_floor(prior: Any, feature: str, prior_share: float = PRIOR_SIGMA_SHARE) -> float:
    """The least σ a calibrated constraint may have."""
    return max(prior_share * prior.sigma, ABS_SIGMA_FLOOR.get(feature, 0.0))


def fit_gaussian(
    prior: Any,
    values: Sequence[float],
    feature: str,
    *,
    prior_share: float = PRIOR_SIGMA_SHARE,
    quantile: float = ONE_SIDED_QUANTILE,
    min_samples: int = MIN_SAMPLES,
    prior_strength: float = PRIOR_STRENGTH,
    effective_samples: float | None = None,
) -> Any:
    """Posterior re-estimate of one constraint, shrunk to the prior, with floors; keeps its side.

    Parameters
    ----------
    prior : Gaussian
        The constraint as the ontology has it.
    values : sequence of float
        Measured values.
    feature : str
        Feature name (selects the absolute σ floor).
    prior_share : float
        σ is at least this share of the prior's σ.
    quantile : float
        Where the data's estimate of one-sided bounds and plateau ends starts (0: the
        extreme value).
    min_samples : int
        Fewer finite values keep the prior.
    prior_strength : float
        κ0, the prior's weight in objects; 0 gives the maximum-likelihood fit.
    effective_samples : float, optional
        How many independent samples the values are worth (at most their number);
        all of them by default.

    Returns
    -------
    Gaussian
        The prior itself when there are too few values or its form is not known.

    Examples
    --------
    >>> from ontodetect.ontology import Gaussian
    >>> prior = Gaussian(0.55, 0.2)
    >>> g = fit_gaussian(prior, [0.44, 0.46, 0.48], "height", prior_strength=0)
    >>> round(g.mean, 3), round(g.sigma, 3)   # ML; the std 0.016 is below half of 0.2
    (0.46, 0.1)
    >>> g = fit_gaussian(prior, [0.44, 0.46, 0.48], "height", prior_strength=9)
    >>> round(g.mean, 3), round(g.sigma, 3)   # 3 objects against 9: a quarter of the way
    (0.528, 0.185)
    >>> g = fit_gaussian(Gaussian(0.45, 0.2, "min"), [0.3, 0.4, 0.5], "fill", prior_strength=0)
    >>> g.side, round(g.mean, 2)              # stays one-sided; 0.3 minus the expected gap
    ('min', 0.2)
    >>> g = fit_gaussian(Gaussian(0.45, 0.2, "min"), [0.7, 0.8, 0.9], "fill", prior_strength=0)
    >>> round(g.mean, 2)                      # objects inside a bound never tighten it
    0.45
    """
    from ..ontology import Gaussian

    x = np.asarray(values, dtype=np.float64)
    x = x[np.isfinite(x)]
    if len(x) < max(min_samples, 1):
        return prior
    n = float(len(x)) if effective_samples is None else min(float(len(x)), effective_samples)
    # Share of the data in the conjugate posterior (κ0 = ν0 = prior_strength).
    w = n / (prior_strength + n) if prior_strength + n > 0 else 1.0
    floor = sigma_floor(prior, feature, prior_share)
    spread = float(x.var())
    # The posterior predictive of a new object is wider than the posterior by
    # 1 + 1 / κn: with few objects σ widens rather than narrows.
    predictive = 1.0 + 1.0 / max(prior_strength + n, 1.0)
    if prior.side == "both":
        shift = float(x.mean()) - prior.mean
        var = (1.0 - w) * prior.sigma**2 + w * spread + w * (1.0 - w) * shift**2
        return Gaussian(prior.mean + w * shift, max(math.sqrt(var * predictive), floor))
    if prior.side not in ("min", "max", "plateau"):
        return prior  # a form this version does not know how to fit
    # The softness of a bound loosens like the bound: values well inside it say nothing
    # of how sharply objects beyond it fall off.
    sigma = max(
        math.sqrt(((1.0 - w) * prior.sigma**2 + w * spread) * predictive), floor, prior.sigma
    )
    low = float(np.quantile(x, quantile))
    high = float(np.quantile(x, 1.0 - quantile))
    # The support of n samples reaches beyond their extremes by about range / (n - 1)
    # (the unbiased end points of a uniform law): an end never moves inside it.
    gap = (high - low) / max(n - 1.0, 1.0)
    # Objects beyond a bound show it is too tight; objects inside it do not show that
    # others are not beyond it, so bounds only ever loosen.
    low = min(prior.mean + w * (low - gap - prior.mean), prior.mean)
    if prior.side == "min":
        return Gaussian(low, sigma, "min")
    upper = prior.mean if prior.side == "max" else prior.upper
    high = max(upper + w * (high + gap - upper), upper)
    if prior.side == "max":
        return Gaussian(high, sigma, "max")
    if high - low < floor:
        # Values (nearly) all alike: a plateau as wide as the σ floor around them.
        mid = (low + high) / 2
        low, high = mid - floor / 2, mid + floor / 2
    return Gaussian.plateau(low, high, sigma)


@dataclass(frozen=True)
class ConstraintFit:
    """One constraint before and after calibration.

    Attributes
    ----------
    path : tuple
        Place in the file (see :func:`constraint_values`).
    before, after : Gaussian
        The prior and what was written (the prior itself when unchanged).
    samples : int
        Values measured.
    proposed : Gaussian or None
        The fit before the nested check (``after`` when it was kept).
    note : str
        Why the constraint kept its prior, if it did.
    """

    path: ConstraintPath
    before: Any
    after: Any
    samples: int
    proposed: Any = None
    note: str = ""

    @property
    def name(self) -> str:
        """Dotted place in the file: ``chair.parts.seat.height``, ``chair.relations[0].gap``."""
        return _dotted(self.path)

    @property
    def changed(self) -> bool:
        return self.after is not self.before

    def to_dict(self) -> dict[str, Any]:
        def g(x: Any) -> dict[str, Any]:
            out = {"mean": x.mean, "sigma": x.sigma, "side": x.side}
            if getattr(x, "upper", None) is not None:
                out["upper"] = x.upper
            return out

        out = {
            "constraint": self.name,
            "samples": self.samples,
            "before": g(self.before),
            "after": g(self.after),
        }
        if self.proposed is not None and self.proposed is not self.after:
            out["proposed"] = g(self.proposed)
        if self.note:
            out["note"] = self.note
        return out


def _dotted(path: Sequence[Any]) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def constraint_group(path: ConstraintPath) -> ConstraintPath:
    """The group a constraint is accepted or rejected with: its class and part.

    ``(class, "parts", part)``, ``(class, "relations", index)`` or ``(class, "cluster")``.

    Examples
    --------
    >>> constraint_group(("chair", "parts", "seat", "height"))
    ('chair', 'parts', 'seat')
    >>> constraint_group(("chair", "cluster", "length"))
    ('chair', 'cluster')
    """
    return tuple(path[:2]) if path[1] == "cluster" else tuple(path[:3])


def _round(v: float, digits: int = DIGITS) -> float:
    r = float(f"{v:.{digits}g}")
    return 0.0 if r == 0 else r


def _spec_with(spec: Any, g: Any, digits: int) -> Any | None:
    """``spec`` in its own form with ``g``'s numbers; None if rounding collapses it."""
    if isinstance(spec, list) or (isinstance(spec, dict) and "range" in spec):
        lo, hi = _round(g.mean - g.sigma, digits), _round(g.mean + g.sigma, digits)
        if hi <= lo:
            return None
        return [lo, hi] if isinstance(spec, list) else {**spec, "range": [lo, hi]}
    if not isinstance(spec, dict):
        return spec
    if "mean" in spec:
        sigma = _round(g.sigma, digits)
        return {**spec, "mean": _round(g.mean, digits), "sigma": sigma} if sigma > 0 else None
    out = dict(spec)
    if "min" in spec and "max" in spec:
        out["min"], out["max"] = _round(g.mean, digits), _round(g.upper, digits)
        if out["max"] <= out["min"]:
            return None
    elif "min" in spec or "max" in spec:
        out["min" if "min" in spec else "max"] = _round(g.mean, digits)
    else:
        return spec
    if "soft" in spec:
        out["soft"] = _round(g.sigma, digits)
        if out["soft"] <= 0:
            return None
    return out


def _write_spec(spec: Any, g: Any) -> Any:
    """The YAML value of a constraint in its original form, with ``g``'s numbers."""
    # More digits when rounding would collapse a narrow range or a small sigma to nothing.
    for digits in range(DIGITS, MAX_DIGITS + 1):
        out = _spec_with(spec, g, digits)
        if out is not None:
            return out
    return spec


def _spec_at(data: dict[str, Any], path: ConstraintPath) -> tuple[Any, Any]:
    """(container, key) of a constraint's value in the parsed YAML."""
    cls = data["classes"][path[0]]
    if path[1] == "cluster":
        return cls["cluster"], path[2]
    if path[1] == "parts":
        return cls["parts"][path[2]], path[3]
    return cls["relations"][path[2]], path[3]


class _Dumper(yaml.SafeDumper):
    """Flow style for constraint mappings and number lists, block style around them."""


def _represent_dict(dumper: yaml.SafeDumper, data: dict[str, Any]) -> yaml.Node:
    flow = (
        all(
            not isinstance(v, dict)
            and not (isinstance(v, list) and any(isinstance(x, (dict, list)) for x in v))
            for v in data.values()
        )
        and len(data) <= 4
    )
    return dumper.represent_mapping("tag:yaml.org,2002:map", data, flow_style=flow)


def _represent_list(dumper: yaml.SafeDumper, data: list[Any]) -> yaml.Node:
    flow = all(not isinstance(v, (dict, list)) for v in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


def _represent_str(dumper: yaml.SafeDumper, data: str) -> yaml.Node:
    # Long descriptions as folded blocks (``>``), as people write them.
    style = ">" if len(data) > LONG_TEXT or "\n" in data.rstrip("\n") else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", data, style=style)


_Dumper.add_representer(dict, _represent_dict)
_Dumper.add_representer(str, _represent_str)
_Dumper.add_representer(list, _represent_list)


def _constraint_paths(ontology: Any) -> list[tuple[ConstraintPath, Any]]:
    out = []
    for cls in ontology.classes:
        for feature, g in cls.cluster.constraints.items():
            out.append(((cls.name, "cluster", feature), g))
        for part in cls.parts:
            for feature, g in part.constraints.items():
                out.append(((cls.name, "parts", part.name, feature), g))
        for i, rel in enumerate(cls.relations):
            for feature, g in rel.constraints.items():
                out.append(((cls.name, "relations", i, feature), g))
    return out


def _effective(
    path: ConstraintPath, rooms: Mapping[ConstraintPath, int] | None, settings: FitSettings
) -> float | None:
    return None if rooms is None else float(rooms.get(path, 0) * settings.room_samples)


def fit_constraints(
    ontology: Any,
    values: Mapping[ConstraintPath, Sequence[float]],
    rooms: Mapping[ConstraintPath, int] | None = None,
    settings: FitSettings | None = None,
) -> dict[ConstraintPath, Any]:
    """The re-estimated constraints of an ontology, before any check.

    Parameters
    ----------
    ontology : Ontology
    values : mapping
        Constraint path -> measured values.
    rooms : mapping, optional
        Constraint path -> number of rooms its values come from (not checked when
        omitted; each room's values then count in full).
    settings : FitSettings, optional

    Returns
    -------
    dict
        Constraint path -> new Gaussian, for the constraints that changed.
    """
    settings = settings or FitSettings()
    out = {}
    for path, prior in _constraint_paths(ontology):
        if rooms is not None and rooms.get(path, 0) < settings.min_rooms:
            continue
        after = fit_gaussian(
            prior,
            list(values.get(path, ())),
            path[-1],
            prior_share=settings.prior_share,
            quantile=settings.quantile,
            min_samples=settings.min_samples,
            prior_strength=settings.prior_strength,
            effective_samples=_effective(path, rooms, settings),
        )
        if after is not prior:
            out[path] = after
    return out


def _render(data: Mapping[str, Any], fits: Mapping[ConstraintPath, Any], comment: str = "") -> str:
    """The ontology YAML ``data`` with the constraints of ``fits`` rewritten in their form."""
    data = copy.deepcopy(dict(data))
    for path, g in fits.items():
        container, key = _spec_at(data, path)
        container[key] = _write_spec(container[key], g)
    body = yaml.dump(data, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=LINE_WIDTH)
    lines = [
        w for line in comment.splitlines() for w in (textwrap.wrap(line, LINE_WIDTH - 2) or [""])
    ]
    return "".join(f"# {line}\n" if line else "#\n" for line in lines) + body


def calibrate_ontology(
    text: str,
    values: Mapping[ConstraintPath, Sequence[float]],
    *,
    rooms: Mapping[ConstraintPath, int] | None = None,
    settings: FitSettings | None = None,
    source: str | None = None,
    comment: str | None = None,
    groups: Collection[ConstraintPath] | None = None,
) -> tuple[str, list[ConstraintFit]]:
    """Re-estimate an ontology file's constraints from measured values.

    Parameters
    ----------
    text : str
        The ontology's YAML.
    values : mapping
        Constraint path (see :func:`constraint_values`) -> measured values.
    rooms : mapping, optional
        Constraint path -> number of rooms its values come from; constraints measured
        in fewer than ``settings.min_rooms`` keep their prior, and a room's values
        count as at most ``settings.room_samples`` samples. Not checked when omitted.
    settings : FitSettings, optional
        Floors, quantile, prior strength and minimum counts (defaults: the module
        constants). ``settings.validate`` is not used here (see :func:`select_groups`).
    source : str, optional
        Name of the file, for error messages.
    comment : str, optional
        Written as ``#`` lines at the top of the new file.
    groups : collection of group paths, optional
        Only constraints of these groups (:func:`constraint_group`) change; all by
        default.

    Returns
    -------
    text : str
        The calibrated YAML: same classes, parts, relations and keys, new numbers;
        comments of the original are not kept.
    fits : list of ConstraintFit
        Every constraint, in file order, before and after.
    """
    from ..ontology import parse_ontology

    ontology = parse_ontology(text, source)
    data = yaml.safe_load(text)
    settings = settings or FitSettings()
    proposed = fit_constraints(ontology, values, rooms, settings)
    kept = {p: g for p, g in proposed.items() if groups is None or constraint_group(p) in groups}
    fits = []
    for path, prior in _constraint_paths(ontology):
        note = ""
        if path not in proposed:
            if rooms is not None and rooms.get(path, 0) < settings.min_rooms:
                note = f"measured in fewer than {settings.min_rooms} rooms"
            elif len(values.get(path, ())) < settings.min_samples:
                note = f"fewer than {settings.min_samples} values"
        elif path not in kept:
            note = "its group was not accepted by the nested check"
        fits.append(
            ConstraintFit(
                path,
                prior,
                kept.get(path, prior),
                len(values.get(path, ())),
                proposed.get(path),
                note,
            )
        )
    new_text = _render(data, kept, comment or "")
    parse_ontology(new_text, source)  # the result must be a valid ontology
    return new_text, fits


# -- the nested check ----------------------------------------------------------------------
@dataclass(frozen=True)
class GroupDecision:
    """Whether one group of fitted constraints passed the nested check.

    Attributes
    ----------
    group : tuple
        :func:`constraint_group` path.
    accepted : bool
    f1_before, f1_after : dict of str to float
        Validation F1 per reported class and ``"overall"`` without and with the group
        (on top of the groups accepted before it), pooled over the validation rooms.
    rooms_gained, rooms_lost : tuple of str
        Left-out calibration rooms where some F1 rose with the group and fell in none
        / where an F1 or the number of objects found fell.
    reason : str
        Why the group was accepted or rejected, in words.
    """

    group: ConstraintPath
    accepted: bool
    f1_before: dict[str, float]
    f1_after: dict[str, float]
    rooms_gained: tuple[str, ...] = ()
    rooms_lost: tuple[str, ...] = ()
    reason: str = ""

    @property
    def name(self) -> str:
        return _dotted(self.group)

    def to_dict(self) -> dict[str, Any]:
        return {
            "group": self.name,
            "accepted": self.accepted,
            "f1_before": self.f1_before,
            "f1_after": self.f1_after,
            "rooms_gained": list(self.rooms_gained),
            "rooms_lost": list(self.rooms_lost),
            "reason": self.reason,
        }


def _f1(tp: int, fp: int, fn: int) -> float:
    return 2 * tp / (2 * tp + fp + fn) if tp else 0.0


def _room_sign(new: np.ndarray, old: np.ndarray) -> int:
    """Whether one class's (TP, FP, FN) in one room got better (1), worse (-1) or neither.

    F1 decides; when it ties, fewer false positives are better: with no true positive
    F1 is 0 whatever the false alarms, and one fewer is still a gain.
    """
    f_new, f_old = _f1(*map(int, new)), _f1(*map(int, old))
    if abs(f_new - f_old) > F1_TOLERANCE:
        return 1 if f_new > f_old else -1
    return int(np.sign(int(old[1]) - int(new[1])))


def _detect_counts(
    scene: ValidationScene,
    ontology: Any,
    params: Mapping[str, Any],
    classes: Sequence[str],
) -> dict[str, np.ndarray]:
    """TP, FP, FN per class of detecting ``scene``'s clusters with ``ontology``."""
    from ..labeling import label_clusters
    from ..ontology import score_cluster
    from ._match import match_instances

    scores = [
        score_cluster(d, ontology, params["priors"], none_likelihood=params["none_likelihood"])
        for d in scene.descriptions
    ]
    choices = label_clusters(
        scores,
        [d.planes for d in scene.descriptions],
        ontology,
        beta=params["beta"],
        threshold=params["threshold"],
        centers=scene.centers,
        context=params["context"],
    )
    preds = [
        Instance.make(
            k,
            ch.label,
            scene.members[k],
            float(s.probabilities[ch.extra["class"]]),
            scene.centers[k],
        )
        for k, (s, ch) in enumerate(zip(scores, choices))
        if ch.label is not None and ch.label in classes
    ]
    gts = [g for g in scene.gts if g.label in classes]
    m = match_instances(preds, gts, iou_threshold=MIN_CLUSTER_IOU)
    out = {}
    for c in classes:
        hit = [m.pred_match[i] >= 0 for i, p in enumerate(preds) if p.label == c]
        n_gt = sum(g.label == c for g in gts)
        tp = int(sum(hit))
        out[c] = np.array([tp, len(hit) - tp, n_gt - tp])
    return out


def _detection_params(ontology: Any, detect_options: Mapping[str, Any]) -> dict[str, Any]:
    """The scoring and labelling settings :func:`ontodetect.pipeline.detect` would use."""
    from ..config import Config
    from ..ontology import class_priors

    opts = dict(detect_options)
    d = (opts.get("config") or Config()).detect
    params = {
        k: d.__getattribute__(k) if opts.get(k) is None else opts[k]
        for k in ("threshold", "beta", "none_likelihood", "context")
    }
    params["priors"] = class_priors(ontology, opts.get("room"), opts.get("indoor"))
    return params


def select_groups(
    text: str,
    room_values: Mapping[str, Mapping[ConstraintPath, Sequence[float]]],
    scenes: Mapping[str, Sequence[ValidationScene]],
    *,
    settings: FitSettings | None = None,
    detect_options: Mapping[str, Any] | None = None,
    source: str | None = None,
) -> tuple[set[ConstraintPath], list[GroupDecision]]:
    """Which groups of fitted constraints help calibration rooms left out, and hurt none.

    Every calibration room in turn is a validation room: the constraints are fitted
    (:func:`fit_constraints`) on the values of the other rooms, and its scenes are
    detected on again with the base ontology changed by a set of groups. Starting from
    no change, the groups that any fold changes are tried one by one in file order on
    top of those accepted so far. A group is accepted when

    - in no validation room does any reported class's F1, the overall F1 or the number
      of objects found fall (nor, where F1 is 0 either way, do false positives rise);
    - neither any class's F1 nor the overall F1 pooled over the validation rooms falls;
    - the room gains in at least ``settings.min_gain_rooms`` validation rooms: some F1
      rises (or, at equal F1, false positives fall). This is a one-sided sign test over
      the rooms (see :data:`MIN_GAIN_ROOMS`): a gain seen in a single room rests on one
      or two detections and says nothing about other rooms.

    With ``settings.accept_ties`` the last rule is dropped (a change without evidence
    is kept when it hurts nothing). With fewer validation rooms than
    ``settings.validation_rooms`` nothing can be checked and nothing is accepted.

    Parameters
    ----------
    text : str
        The base ontology's YAML.
    room_values : mapping of str to mapping
        Room -> constraint path -> values measured in that room's scenes.
    scenes : mapping of str to sequence of ValidationScene
        Room -> its scenes' clusters and ground truth (rooms without scenes are not
        validated on but still give values).
    settings : FitSettings, optional
    detect_options : mapping, optional
        ``config``, ``room``, ``indoor``, ``threshold``, ``beta``, ``none_likelihood``,
        ``context`` of :func:`ontodetect.pipeline.detect`.
    source : str, optional
        Name of the ontology file, for error messages.

    Returns
    -------
    accepted : set of group paths
    decisions : list of GroupDecision
        One per group tried, in order. Empty when fewer than
        ``settings.validation_rooms`` rooms can be left out (nothing can be checked,
        so nothing is accepted; see :func:`validation_rooms`).
    """
    from ..ontology import parse_ontology

    settings = settings or FitSettings()
    accepted: set[ConstraintPath] = set()
    decisions: list[GroupDecision] = []
    held_rooms = validation_rooms(room_values, scenes)
    if len(held_rooms) < settings.validation_rooms:
        return accepted, decisions
    base = parse_ontology(text, source)
    data = yaml.safe_load(text)
    classes = [c.label for c in base.classes if c.detect]
    classes = list(dict.fromkeys(classes))
    params = _detection_params(base, detect_options or {})
    rooms = sorted(room_values, key=_natural_key)
    folds = []
    for held in held_rooms:
        values: dict[ConstraintPath, list[float]] = {}
        counts: dict[ConstraintPath, int] = {}
        for r in rooms:
            if r == held:
                continue
            for p, v in room_values[r].items():
                values.setdefault(p, []).extend(v)
                counts[p] = counts.get(p, 0) + 1
        folds.append((list(scenes[held]), fit_constraints(base, values, counts, settings)))
    order = {
        g: i
        for i, g in enumerate(
            dict.fromkeys(constraint_group(p) for p, _ in _constraint_paths(base))
        )
    }
    candidates = sorted({constraint_group(p) for _, fits in folds for p in fits}, key=order.get)

    def evaluate(
        chosen: set[ConstraintPath],
    ) -> tuple[dict[str, float], list[dict[str, np.ndarray]]]:
        """F1 pooled over the validation rooms, and TP, FP, FN in each of them."""
        total = {c: np.zeros(3, dtype=np.int64) for c in classes}
        per_fold = []
        for fold_scenes, fits in folds:
            used = {p: g for p, g in fits.items() if constraint_group(p) in chosen}
            onto = parse_ontology(_render(data, used), source) if used else base
            fold = {c: np.zeros(3, dtype=np.int64) for c in classes}
            for scene in fold_scenes:
                for c, v in _detect_counts(scene, onto, params, classes).items():
                    fold[c] += v
            for c in classes:
                total[c] += fold[c]
            per_fold.append({**fold, "overall": sum(fold.values())})
        f1 = {c: _f1(*map(int, v)) for c, v in total.items()}
        f1["overall"] = _f1(*map(int, sum(total.values())))
        return f1, per_fold

    def no_worse(new: Mapping[str, float], old: Mapping[str, float]) -> bool:
        return all(new[k] >= old[k] - F1_TOLERANCE for k in old)

    def room_change(new: Mapping[str, np.ndarray], old: Mapping[str, np.ndarray]) -> int:
        """-1 if the room lost (an F1 or objects found fell), 1 if it gained, else 0."""
        signs = [_room_sign(new[k], old[k]) for k in old]
        # Objects found: the held-out rooms lost recall, not precision.
        if min(signs) < 0 or any(new[c][0] < old[c][0] for c in classes):
            return -1
        return int(max(signs) > 0)

    current, current_folds = evaluate(accepted)
    with progress("Checking calibrated groups", total=len(candidates)) as advance:
        for group in candidates:
            trial, trial_folds = evaluate(accepted | {group})
            # Room by room: a change that helps one room and hurts another depends on
            # the rooms, not on the class.
            change = [room_change(t, c) for t, c in zip(trial_folds, current_folds)]
            lost = tuple(r for r, d in zip(held_rooms, change) if d < 0)
            gained = tuple(r for r, d in zip(held_rooms, change) if d > 0)
            if lost:
                ok, reason = False, f"lowers F1 or objects found in {', '.join(lost)}"
            elif not no_worse(trial, current):
                ok, reason = False, "lowers a pooled F1"
            elif settings.accept_ties:
                ok, reason = True, "lowers no F1"
            elif len(gained) >= settings.min_gain_rooms:
                ok, reason = True, f"raises F1 in {', '.join(gained)}, lowers none"
            elif gained:
                ok, reason = (
                    False,
                    (
                        f"raises F1 only in {', '.join(gained)}: needs a gain in "
                        f"{settings.min_gain_rooms} rooms"
                    ),
                )
            else:
                ok, reason = False, "changes no F1"
            decisions.append(GroupDecision(group, ok, current, trial, gained, lost, reason))
            if ok:
                accepted.add(group)
                current, current_folds = trial, trial_folds
            advance(1)
    return accepted, decisions


def validation_rooms(
    room_values: Mapping[str, Any], scenes: Mapping[str, Sequence[ValidationScene]]
) -> list[str]:
    """The calibration rooms the nested check can leave out in turn, in natural order.

    A room needs scenes to detect on and at least one other measured room to fit on.

    Examples
    --------
    >>> validation_rooms({"scene0001": {}, "scene0002": {}}, {"scene0002": ["s"]})
    ['scene0002']
    >>> validation_rooms({"scene0001": {}}, {"scene0001": ["s"]})
    []
    """
    if len(room_values) < 2:
        return []
    return [r for r in sorted(room_values, key=_natural_key) if scenes.get(r)]


# -- the whole procedure -------------------------------------------------------------------
@dataclass(frozen=True)
class CalibrationResult:
    """A calibrated ontology and how it was made and checked.

    Attributes
    ----------
    text : str
        The calibrated ontology file.
    ontology : Ontology
        Parsed from ``text``.
    base : Ontology
        The ontology calibrated.
    split : SceneSplit
    fits : list of ConstraintFit
    used, skipped : dict of str to int
        Ground-truth objects per class that gave values / had no cluster to measure.
    before, after : DatasetEvaluation or None
        Detection on the held-out scenes with ``base`` and with ``ontology``.
    failed : list of str
        Calibration scenes that could not be read, with the reason.
    settings : FitSettings
    decisions : list of GroupDecision
        The nested check of every group of fitted constraints, in order (empty when
        ``settings.validate`` is off or too few rooms could be left out).
    check : str
        What the nested check did, in one sentence (says so when too few calibration
        rooms left nothing to validate and the original was kept).
    validation_rooms : list of str
        The calibration rooms the nested check left out in turn (none when too few).
    """

    text: str
    ontology: Any
    base: Any
    split: SceneSplit
    fits: list[ConstraintFit]
    used: dict[str, int]
    skipped: dict[str, int]
    before: DatasetEvaluation | None = None
    after: DatasetEvaluation | None = None
    failed: list[str] = field(default_factory=list)
    settings: FitSettings = field(default_factory=FitSettings)
    decisions: list[GroupDecision] = field(default_factory=list)
    check: str = ""
    validation_rooms: list[str] = field(default_factory=list)

    @property
    def too_few_rooms(self) -> bool:
        """True when the nested check was asked for but had too few rooms to leave out."""
        return self.settings.validate and len(self.validation_rooms) < (
            self.settings.validation_rooms
        )

    def comparison(self) -> list[dict[str, Any]]:
        """Per class and overall: precision, recall and F1 on the held-out scenes, before/after."""
        if self.before is None or self.after is None:
            return []
        rows = []
        b, a = self.before.primary, self.after.primary
        for c in [*b.classes, "overall"]:
            mb = b.overall if c == "overall" else b.per_class[c]
            ma = a.overall if c == "overall" else a.per_class[c]
            rows.append(
                {
                    "class": c,
                    "ground_truth": mb.num_gt,
                    "precision_before": mb.precision,
                    "recall_before": mb.recall,
                    "precision_after": ma.precision,
                    "recall_after": ma.recall,
                    "f1_before": mb.f1,
                    "f1_after": ma.f1,
                    "detections_before": mb.num_pred,
                    "detections_after": ma.num_pred,
                }
            )
        return rows

    def to_dict(self) -> dict[str, Any]:
        return {
            "split": self.split.to_dict(),
            "settings": dataclasses.asdict(self.settings),
            "used": self.used,
            "skipped": self.skipped,
            "failed": self.failed,
            "constraints": [f.to_dict() for f in self.fits],
            "nested_check": [d.to_dict() for d in self.decisions],
            "check": self.check,
            "validation_rooms": self.validation_rooms,
            "held_out": self.comparison(),
            "criterion": "point IoU >= 0.25",
        }


@functools.cache
def _builtin_text() -> str:
    return resources.files("ontodetect").joinpath("data/furniture.yaml").read_text("utf-8")


def calibrate_dataset(
    path: str | os.PathLike[str],
    *,
    base: str | os.PathLike[str] | None = None,
    format: str = "auto",
    split: float = 0.5,
    seed: int = 0,
    jobs: int = 1,
    detect_options: Mapping[str, Any] | None = None,
    min_iou: float = MIN_CLUSTER_IOU,
    settings: FitSettings | None = None,
    evaluate: bool = True,
    scenes: Sequence[SceneSource] | None = None,
) -> CalibrationResult:
    """Calibrate an ontology on part of a labelled dataset; compare on the rest.

    Parameters
    ----------
    path : str or PathLike
        Labelled dataset (see :func:`~ontodetect.evaluation.discover_scenes`).
    base : path, optional
        Ontology file to calibrate; the built-in furniture ontology by default.
    format : str
        Dataset layout or "auto".
    split : float
        Share of the rooms used for calibration (see :func:`split_scenes`).
    seed : int
        Seed of the split.
    jobs : int
        Worker processes.
    detect_options : mapping, optional
        Keyword arguments of :func:`ontodetect.pipeline.detect` (not ``ontology``):
        ``config``, ``seed``, ``up`` and ``scale`` also drive the segmentation that
        calibration measures.
    min_iou : float
        Least point IoU between an object and the cluster that measures it.
    settings : FitSettings, optional
        σ floor, quantile and minimum counts of the fit.
    evaluate : bool
        Detect on the held-out scenes with the base and the calibrated ontology.
    scenes : sequence of SceneSource, optional
        Use these instead of discovering ``path``'s scenes.

    Returns
    -------
    CalibrationResult
    """
    from ..ontology import parse_ontology

    opts = _check_detect_options(detect_options)
    if "ontology" in opts:
        raise InvalidParameterError("detect_options", "without 'ontology' (use base=)", "ontology")
    if not 0.0 < min_iou <= 1.0:
        raise InvalidParameterError("min_iou", "a number in (0, 1]", min_iou)
    text = _builtin_text() if base is None else read_text(base, "ontology file")
    source = "builtin:furniture.yaml" if base is None else str(base)
    base_onto = parse_ontology(text, source)
    units = list(scenes) if scenes is not None else discover_scenes(path, format)
    parts = split_scenes(units, split, seed)

    settings = settings or FitSettings()
    seg_opts = {k: opts[k] for k in ("config", "seed", "up", "scale") if k in opts}
    work = functools.partial(
        collect_scene_samples,
        ontology=base_onto,
        segment_options=seg_opts,
        min_iou=min_iou,
        keep_clusters=settings.validate,
    )
    samples = map_scenes(work, parts.calibration, jobs=jobs, description="Measuring objects")
    values: dict[ConstraintPath, list[float]] = {}
    rooms: dict[ConstraintPath, set[str]] = {}
    room_values: dict[str, dict[ConstraintPath, list[float]]] = {}
    room_scenes: dict[str, list[ValidationScene]] = {}
    used: dict[str, int] = {}
    skipped: dict[str, int] = {}
    failed = []
    for unit, s in zip(parts.calibration, samples):
        # Scene order: the same values in the same order for any ``jobs``.
        if s.error is not None:
            failed.append(f"{s.name}: {s.error}")
            continue
        per_room = room_values.setdefault(unit.group, {})
        for p, v in s.values.items():
            values.setdefault(p, []).extend(v)
            per_room.setdefault(p, []).extend(v)
            rooms.setdefault(p, set()).add(unit.group)
        if s.scene is not None:
            room_scenes.setdefault(unit.group, []).append(s.scene)
        for d, src in ((used, s.used), (skipped, s.skipped)):
            for k, n in src.items():
                d[k] = d.get(k, 0) + n
    groups: set[ConstraintPath] | None = None
    decisions: list[GroupDecision] = []
    if settings.validate:
        groups, decisions = select_groups(
            text,
            room_values,
            room_scenes,
            settings=settings,
            detect_options=opts,
            source=source,
        )
    left_out = validation_rooms(room_values, room_scenes) if settings.validate else []
    # A lone room cannot be left out (nothing to fit on), but it is the room to count.
    check = _describe_check(settings, left_out or sorted(room_scenes), decisions)
    name = Path(path).name or str(path)
    counts = ", ".join(f"{n} {c}" for c, n in sorted(used.items())) or "none"
    comment = (
        f"Calibrated by 'ontodetect calibrate' from {source} on {name}:\n"
        f"{sum(used.values())} objects ({counts}) in {len(parts.calibration)} scenes;\n"
        f"{parts.describe()}.\n"
        f"Shrunk to the original with a weight of {settings.prior_strength:g} objects, "
        f"a room counting as at most {settings.room_samples} objects; "
        f"sigma >= {settings.prior_share:g} x the original, bounds from quantile "
        f"{settings.quantile:g}, at least {settings.min_samples} values from "
        f"{settings.min_rooms} rooms; nested check: {check}\n"
        "Only numbers changed; the comments of the original file are not kept."
    )
    new_text, fits = calibrate_ontology(
        text,
        values,
        rooms={p: len(r) for p, r in rooms.items()},
        settings=settings,
        source=source,
        comment=comment,
        groups=groups,
    )
    new_onto = parse_ontology(new_text, source)
    before = after = None
    if evaluate and parts.held_out:
        before = evaluate_dataset(
            path,
            jobs=jobs,
            detect_options={**opts, "ontology": base_onto},
            scenes=parts.held_out,
            on_error="skip",
        )
        after = evaluate_dataset(
            path,
            jobs=jobs,
            detect_options={**opts, "ontology": new_onto},
            scenes=parts.held_out,
            on_error="skip",
        )
    return CalibrationResult(
        new_text,
        new_onto,
        base_onto,
        parts,
        fits,
        used,
        skipped,
        before,
        after,
        failed,
        settings,
        decisions,
        check,
        left_out if len(left_out) >= settings.validation_rooms else [],
    )


def _describe_check(
    settings: FitSettings, rooms: Sequence[str], decisions: Sequence[GroupDecision]
) -> str:
    """One sentence on what the nested check did."""
    if not settings.validate:
        return "off (--no-validate): every fitted constraint is written."
    need = settings.validation_rooms
    if len(rooms) < need:
        return (
            f"NOT POSSIBLE, only {len(rooms)} calibration room(s) to leave out in turn and "
            f"at least {need} are needed (a gain must show in {settings.min_gain_rooms} "
            "rooms); nothing could be validated, so the file keeps the original values."
        )
    kept = [d for d in decisions if d.accepted]
    rule = (
        "lower no F1"
        if settings.accept_ties
        else f"raise F1 in at least {settings.min_gain_rooms} rooms and lower none"
    )
    return (
        f"{len(rooms)} calibration rooms left out in turn; kept {len(kept)} of "
        f"{len(decisions)} fitted groups, those that {rule}"
        + (" (none: the file keeps the original values)." if not kept else ".")
    )
