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

Modules, in the order the calibration runs: ``_split`` (:func:`split_scenes`),
``_samples`` (:func:`collect_scene_samples`), ``_gaussian`` (:func:`fit_gaussian`,
:func:`fit_constraints`, :func:`calibrate_ontology`), ``_groups`` (:func:`select_groups`)
and ``_run`` (:func:`calibrate_dataset`); ``_settings`` names their tolerances.
"""

from __future__ import annotations

from ._gaussian import (
    ConstraintFit,
    FitSettings,
    calibrate_ontology,
    constraint_group,
    fit_constraints,
    fit_gaussian,
    sigma_floor,
)
from ._groups import GroupDecision, select_groups, validation_rooms
from ._run import CalibrationResult, calibrate_dataset
from ._samples import (
    SceneSamples,
    ValidationScene,
    best_kind,
    collect_scene_samples,
    constraint_values,
)
from ._settings import (
    MIN_CLUSTER_IOU,
    MIN_GAIN_ROOMS,
    MIN_ROOMS,
    MIN_SAMPLES,
    ONE_SIDED_QUANTILE,
    PRIOR_SIGMA_SHARE,
    PRIOR_STRENGTH,
    ROOM_SAMPLES,
)
from ._split import SceneSplit, split_scenes

__all__ = [
    "MIN_CLUSTER_IOU",
    "MIN_GAIN_ROOMS",
    "MIN_ROOMS",
    "MIN_SAMPLES",
    "ONE_SIDED_QUANTILE",
    "PRIOR_SIGMA_SHARE",
    "PRIOR_STRENGTH",
    "ROOM_SAMPLES",
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
    "sigma_floor",
    "split_scenes",
    "validation_rooms",
]
