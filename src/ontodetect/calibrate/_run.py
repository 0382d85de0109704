"""The whole calibration of a dataset: split, sample, fit, select, compare."""

from __future__ import annotations

import dataclasses
import functools
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from .._executor import Executor, executor_for
from ..config import SHARE, check_param
from ..errors import InvalidParameterError
from ..evaluation._dataset import (
    DatasetEvaluation,
    _check_detect_options,
    evaluate_dataset,
    map_scenes,
)
from ..io._layouts import SceneSource, discover_scenes
from ..io._textfile import read_text
from ..ontology import parse_ontology
from ._gaussian import ConstraintFit, FitSettings, calibrate_ontology
from ._groups import GroupDecision, select_groups, validation_rooms
from ._samples import ValidationScene, collect_scene_samples
from ._settings import MIN_CLUSTER_IOU, ConstraintPath
from ._split import SceneSplit, split_scenes


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
    executor: Executor | None = None,
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
    executor : Executor, optional
        Where the scenes run (:func:`ontodetect._executor.open_executor`); by default one
        opened for ``jobs`` and shared by the measuring and both evaluations.

    Returns
    -------
    CalibrationResult
    """

    opts = _check_detect_options(detect_options)
    if "ontology" in opts:
        raise InvalidParameterError("detect_options", "without 'ontology' (use base=)", "ontology")
    check_param("min_iou", SHARE, min_iou)
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
    with executor_for(executor, jobs if len(units) > 1 else 1) as pool:
        return _calibrate(
            path, text, source, base_onto, opts, parts, settings, work, evaluate, pool
        )


def _calibrate(path, text, source, base_onto, opts, parts, settings, work, evaluate, pool):
    """:func:`calibrate_dataset` once the scenes are split, with its executor ``pool``."""
    samples = map_scenes(
        work,
        parts.calibration,
        description="Measuring objects",
        executor=pool,
        names=[u.name for u in parts.calibration],
    )
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
            executor=pool,
            detect_options={**opts, "ontology": base_onto},
            scenes=parts.held_out,
            on_error="skip",
        )
        after = evaluate_dataset(
            path,
            executor=pool,
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
