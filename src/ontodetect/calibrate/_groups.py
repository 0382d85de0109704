"""Keeping a fitted group of constraints only where it helps rooms it was not fitted on."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._progress import progress
from ..config import Config
from ..evaluation._match import Instance, match_instances
from ..io._layouts import natural_key
from ..io._yaml import load_yaml
from ..labeling import label_clusters
from ..ontology import class_priors, parse_ontology, score_cluster
from ._gaussian import (
    FitSettings,
    _constraint_paths,
    _dotted,
    _render,
    constraint_group,
    fit_constraints,
)
from ._samples import ValidationScene
from ._settings import F1_TOLERANCE, MIN_CLUSTER_IOU, ConstraintPath


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
        explain_away=params["explain_away"],
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

    opts = dict(detect_options)
    d = (opts.get("config") or Config()).detect
    keys = ("threshold", "beta", "none_likelihood", "context", "explain_away")
    params = {k: getattr(d, k) for k in keys}
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

    settings = settings or FitSettings()
    accepted: set[ConstraintPath] = set()
    decisions: list[GroupDecision] = []
    held_rooms = validation_rooms(room_values, scenes)
    if len(held_rooms) < settings.validation_rooms:
        return accepted, decisions
    base = parse_ontology(text, source)
    data = load_yaml(text)
    classes = [c.label for c in base.classes if c.detect]
    classes = list(dict.fromkeys(classes))
    params = _detection_params(base, detect_options or {})
    rooms = sorted(room_values, key=natural_key)
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
    return [r for r in sorted(room_values, key=natural_key) if scenes.get(r)]


# -- the whole procedure -------------------------------------------------------------------
