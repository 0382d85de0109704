"""Evaluation reports: Markdown tables, a JSON document and two pictures.

:func:`write_report` writes, into one folder and each file atomically,

- ``report.md``: per class and overall precision, recall, F1 and AP at point IoU 0.25,
  every criterion side by side, the confusion matrix, time per scene, one row per scene,
  and the figures published in the literature (measured on other datasets);
- ``report.json``: the same numbers, with the precision–recall curves;
- ``pr_curves.png``: precision against recall per class, one panel per criterion;
- ``confusion.png``: the confusion matrix at point IoU 0.25.
"""

from __future__ import annotations

import functools
import io
import json
import math
import os
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ..errors import CorruptFileError, WriteError
from ..io import atomic_write_bytes, atomic_write_text, make_folder
from ._dataset import CRITERIA, PRIMARY, DatasetEvaluation
from ._match import DISTANCE_THRESHOLDS
from ._metrics import ClassMetrics, Evaluation

__all__ = [
    "ReportFiles",
    "box_ap_table",
    "literature_comparisons",
    "markdown_report",
    "write_report",
]

#: Format tag of ``data/literature.yaml``.
LITERATURE_FORMAT = "ontodetect.literature/1"
#: Human names of the criteria of :data:`CRITERIA`.
CRITERION_NAMES = {
    "iou@0.25": "point IoU ≥ 0.25",
    "iou@0.5": "point IoU ≥ 0.5",
    "distance": "centre distance (Günther et al.)",
}
#: Picture resolution (dots per inch).
DPI = 110
#: Decimals of the curves stored in report.json.
CURVE_DECIMALS = 4


@dataclass(frozen=True)
class ReportFiles:
    """Paths of what :func:`write_report` wrote."""

    markdown: Path
    json: Path
    pr_curves: Path
    confusion: Path


@functools.cache
def _literature_text() -> str:
    return resources.files("ontodetect").joinpath("data/literature.yaml").read_text("utf-8")


def literature_comparisons() -> list[dict[str, Any]]:
    """The published figures of ``data/literature.yaml`` (thesis Tables 4.14–4.16).

    Returns
    -------
    list of dict
        One per dataset: ``dataset``, ``description``, ``source`` and ``results``
        (each ``method``, ``precision``, ``recall`` as fractions).

    Examples
    --------
    >>> rows = literature_comparisons()
    >>> rows[0]["dataset"], rows[0]["results"][0]["precision"]
    ('Seminar room of Günther et al.', 0.901)
    """
    source = "builtin:literature.yaml"
    data = yaml.safe_load(_literature_text())
    if not isinstance(data, dict) or data.get("format") != LITERATURE_FORMAT:
        raise CorruptFileError(source, f"expected format: {LITERATURE_FORMAT}")
    out = data.get("comparisons")
    if not isinstance(out, list):
        raise CorruptFileError(source, "expected a list under 'comparisons'")
    return out


# -- Markdown ------------------------------------------------------------------------------
def _pct(x: float) -> str:
    return "–" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{100 * x:.1f}"


def _table(header: list[str], rows: list[list[str]], align: str | None = None) -> list[str]:
    align = align or "l" + "r" * (len(header) - 1)
    marks = {"l": "---", "r": "---:"}
    return [
        "| " + " | ".join(header) + " |",
        "|" + "|".join(marks[a] for a in align) + "|",
        *("| " + " | ".join(r) + " |" for r in rows),
    ]


def _metric_row(m: ClassMetrics, bold: bool = False) -> list[str]:
    name = f"**{m.label}**" if bold else m.label
    return [
        name,
        str(m.num_gt),
        str(m.num_pred),
        str(m.tp),
        str(m.fp),
        str(m.fn),
        _pct(m.precision),
        _pct(m.recall),
        _pct(m.f1),
        _pct(m.ap),
    ]


def _class_table(ev: Evaluation) -> list[str]:
    header = [
        "class",
        "ground truth",
        "detections",
        "TP",
        "FP",
        "FN",
        "precision %",
        "recall %",
        "F1 %",
        "AP %",
    ]
    rows = [_metric_row(ev.per_class[c]) for c in ev.classes]
    rows.append(_metric_row(ev.overall, bold=True))
    return _table(header, rows)


def box_ap_table(evaluation: DatasetEvaluation) -> list[str]:
    """Box AP % per class and mean, one column per IoU kind and threshold."""
    keys = list(evaluation.box_ap)
    if not keys:
        return ["(no box AP)"]
    names = [*evaluation.classes, "mean"]
    rows = []
    for c in names:
        cells = []
        for k in keys:
            v = evaluation.box_ap[k].get(c, float("nan"))
            cells.append("-" if v != v else _pct(v))
        rows.append([f"**{c}**" if c == "mean" else c, *cells])
    return _table(["class", *(f"AP {k} %" for k in keys)], rows)


def _variant_table(evaluation: DatasetEvaluation) -> list[str]:
    """Precision / recall (TP / detections / ground truth) per class for every turn or seed."""
    classes = evaluation.primary.classes

    def cells(ev: Evaluation) -> list[str]:
        return [
            f"{_pct(m.precision)} / {_pct(m.recall)} ({m.tp}/{m.num_pred}/{m.num_gt})"
            for m in [*(ev.per_class[c] for c in classes), ev.overall]
        ]

    header = ["run", *(f"{c}: P / R %" for c in classes), "overall: P / R %"]
    rows = [[key, *cells(ev)] for key, ev in evaluation.by_variant.items()]
    rows.append(["**pooled**", *cells(evaluation.primary)])
    return _table(header, rows)


def _criteria_table(evaluation: DatasetEvaluation) -> list[str]:
    header = ["class", *(f"{CRITERION_NAMES.get(k, k)}: P / R %" for k in evaluation.evaluations)]
    rows = []
    for c in [*evaluation.classes, "overall"]:
        row = [f"**{c}**" if c == "overall" else c]
        for ev in evaluation.evaluations.values():
            m = ev.overall if c == "overall" else ev.per_class[c]
            row.append(f"{_pct(m.precision)} / {_pct(m.recall)}")
        rows.append(row)
    return _table(header, rows)


def _confusion_table(ev: Evaluation) -> list[str]:
    cols = [*ev.classes, "missed"]
    header = ["ground truth ↓ / detected →", *cols]
    rows = [
        [label, *(str(int(v)) for v in ev.confusion[i])]
        for i, label in enumerate(ev.confusion_labels)
    ]
    rows[-1][-1] = ""  # a false alarm cannot be missed
    return _table(header, rows)


def _scene_table(evaluation: DatasetEvaluation) -> list[str]:
    """One row per scene; the runs of a turned or reseeded scene are summed in one row
    (report.json keeps every run)."""
    classes = evaluation.classes
    per_scene = {r["scene"]: r for r in evaluation.primary.per_scene}
    rows: dict[str, dict[str, Any]] = {}
    for s in evaluation.scenes:
        row = rows.setdefault(
            s.source.name, {"runs": 0, "points": s.num_points, "seconds": 0.0, "counts": {}}
        )
        row["runs"] += 1
        row["seconds"] += s.seconds
        r = per_scene.get(s.name, {})
        for c in classes:
            v = r.get(c, {"gt": 0, "pred": 0, "tp": 0})
            total = row["counts"].setdefault(c, [0, 0, 0])
            for i, key in enumerate(("gt", "pred", "tp")):
                total[i] += v[key]
    runs = bool(evaluation.by_variant)
    header = [
        "scene",
        *(["runs"] if runs else []),
        "points",
        "seconds per run" if runs else "seconds",
        *(f"{c} (gt/det/TP)" for c in classes),
    ]
    table = [
        [
            name,
            *([str(row["runs"])] if runs else []),
            f"{row['points']:,}",
            f"{row['seconds'] / row['runs']:.2f}",
            *("/".join(str(n) for n in row["counts"][c]) for c in classes),
        ]
        for name, row in rows.items()
    ]
    return _table(header, table, "l" + ("r" if runs else "") + "rr" + "r" * len(classes))


def _options_line(options: dict[str, Any]) -> str:
    if "detections" in options:
        return f"stored detections from `{options['detections']}`"
    if not options:
        return "`detect` with its defaults"
    parts = []
    for k, v in options.items():
        if k == "ontology":
            v = ", ".join(v.get("classes", [])) + (f" ({v['source']})" if v.get("source") else "")
        elif isinstance(v, dict):
            v = ", ".join(f"{a}={b}" for a, b in v.items())
        parts.append(f"{k}: {v}")
    return "`detect` with " + "; ".join(parts)


def _distance_rule() -> str:
    return ", ".join(f"{c} {100 * d:.0f} cm" for c, d in DISTANCE_THRESHOLDS.items())


def _literature_section(evaluation: DatasetEvaluation) -> list[str]:
    lines = [
        "## Comparison with the literature",
        "",
        "> **Measured on other datasets.** The thesis and the works it compares with "
        "published these figures for their own scans, ground truth and matching rules "
        "(thesis Tables 4.14–4.16). They show what the method reached there; they are "
        "not scores on this dataset and are not comparable one to one with the rows of "
        "this run.",
        "",
    ]
    rows = []
    for comp in literature_comparisons():
        where = f"{comp['dataset']}: {comp.get('description', '')}"
        for k, r in enumerate(comp.get("results", [])):
            rows.append(
                [
                    where if k == 0 else "",
                    str(r["method"]),
                    _pct(r["precision"]),
                    _pct(r["recall"]),
                    str(comp.get("source", "")) if k == 0 else "",
                ]
            )
    name = Path(evaluation.dataset).name or evaluation.dataset
    for key in ("iou@0.25", "distance"):
        if key in evaluation.evaluations:
            m = evaluation.evaluations[key].overall
            rows.append(
                [
                    f"**this run**: {name} ({len(evaluation.scenes)} scenes)",
                    f"ontodetect, {CRITERION_NAMES[key]}",
                    _pct(m.precision),
                    _pct(m.recall),
                    "this report",
                ]
            )
    lines += _table(["dataset", "method", "precision %", "recall %", "source"], rows, "llrrl")
    return lines


def _variant_section(evaluation: DatasetEvaluation) -> list[str]:
    if not evaluation.by_variant:
        return []
    turns, seeds = evaluation.options.get("turns"), evaluation.options.get("seeds")
    runs = " and ".join(
        text
        for text, given in (
            (f"turned by {', '.join(f'{t:g}' for t in turns or [])}° about the vertical", turns),
            (f"with seeds {', '.join(str(k) for k in seeds or [])}", seeds),
        )
        if given
    )
    return [
        "## By run",
        "",
        f"Every scene was detected {runs}; the tables above pool all the runs. A turned scan "
        "is the same room met by other voxel boundaries: the spread between the rows is how "
        "far one run over this dataset can be trusted. TP / detections / ground truth in "
        "brackets, point IoU ≥ 0.25.",
        "",
        *_variant_table(evaluation),
        "",
    ]


def markdown_report(evaluation: DatasetEvaluation) -> str:
    """The text of ``report.md``."""
    ev = evaluation.primary
    name = Path(evaluation.dataset).name or evaluation.dataset
    formats = sorted({s.source.format for s in evaluation.scenes})
    t = evaluation.scene_seconds()
    lines = [
        f"# Evaluation: {name}",
        "",
        f"{len(evaluation.scenes)} scenes ({', '.join(formats) or 'none'}), "
        f"{ev.overall.num_gt} ground-truth objects, {ev.overall.num_pred} detections. "
        f"Detections: {_options_line(evaluation.options)}.",
        "",
        "A detection is a true positive when its points overlap an unmatched ground-truth "
        "object of the same class with IoU ≥ 0.25, matched greedily by descending score; "
        "desks count as tables. Precision = TP / detections, recall = TP / ground truth, "
        "AP = area under the interpolated precision–recall curve.",
        "",
        "## Per class at point IoU ≥ 0.25",
        "",
        *_class_table(ev),
        "",
        *_variant_section(evaluation),
        "## Box AP",
        "",
        "Average precision of the detections' boxes against the ground-truth boxes the "
        "dataset carries (VoteNet's ScanNet `*_bbox.npy`, the simulator's objects.json; "
        "otherwise the box around each instance's points), at 3D IoU ≥ 0.25 and ≥ 0.5, "
        "axis-aligned (VoteNet's protocol) and oriented.",
        "",
        *box_ap_table(evaluation),
        "",
        "## Every criterion",
        "",
        f"Point IoU ≥ 0.25 and ≥ 0.5, and the centre distance of Günther et al. "
        f"(horizontal distance between centres within {_distance_rule()}).",
        "",
        *_criteria_table(evaluation),
        "",
        "![Precision–recall curves](pr_curves.png)",
        "",
        "## Confusion matrix at point IoU ≥ 0.25",
        "",
        "Detections matched to ground truth regardless of class. Row *false alarm*: "
        "detections that overlap no object; column *missed*: objects no detection found.",
        "",
        *_confusion_table(ev),
        "",
        "![Confusion matrix](confusion.png)",
        "",
        "## Time",
        "",
        f"Detection per scene: mean {t['mean']:.2f} s, median {t['median']:.2f} s, "
        f"max {t['max']:.2f} s (reading the scene not included). Whole evaluation: "
        f"{evaluation.seconds:.1f} s with {evaluation.jobs} worker process"
        f"{'es' if evaluation.jobs != 1 else ''}.",
        "",
        "## Per scene (point IoU ≥ 0.25)",
        "",
        *(
            ["Summed over the runs of each scene; report.json lists every run.", ""]
            if evaluation.by_variant
            else []
        ),
        *_scene_table(evaluation),
        "",
    ]
    if evaluation.failed:
        lines += [
            "## Failed scenes",
            "",
            *_table(["scene", "error"], [[s.name, s.error or ""] for s in evaluation.failed], "ll"),
            "",
        ]
    lines += [*_literature_section(evaluation), ""]
    return "\n".join(lines)


# -- JSON ----------------------------------------------------------------------------------
def _finite(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def report_document(evaluation: DatasetEvaluation) -> dict[str, Any]:
    """The ``report.json`` document: :meth:`DatasetEvaluation.to_dict`, curves, literature."""
    doc = evaluation.to_dict()
    doc["curves"] = {
        key: {
            c: {
                "precision": np.round(p, CURVE_DECIMALS).tolist(),
                "recall": np.round(r, CURVE_DECIMALS).tolist(),
            }
            for c, (p, r) in ev.curves.items()
        }
        for key, ev in evaluation.evaluations.items()
    }
    doc["literature"] = {
        "note": "measured on other datasets by the thesis and the works it cites",
        "comparisons": literature_comparisons(),
    }
    return _finite(doc)


# -- pictures ------------------------------------------------------------------------------
def _figure(width: float, height: float) -> Any:
    # A bare Figure with an Agg canvas: no pyplot state, safe in worker processes.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=DPI)
    FigureCanvasAgg(fig)
    return fig


def _png(fig: Any) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, metadata={"Software": None})
    return buf.getvalue()


def pr_curves_png(evaluation: DatasetEvaluation) -> bytes:
    """Precision against recall, one line per class, one panel per criterion."""
    keys = list(evaluation.evaluations)
    fig = _figure(4.2 * len(keys), 4.0)
    axes = fig.subplots(1, len(keys), squeeze=False)[0]
    for ax, key in zip(axes, keys):
        ev = evaluation.evaluations[key]
        for c in ev.classes:
            p, r = ev.curves[c]
            m = ev.per_class[c]
            if m.num_gt == 0 and m.num_pred == 0:
                continue
            # Start at recall 0 with the first precision so a single point still draws.
            rr = np.concatenate([[0.0], r]) if len(r) else np.zeros(1)
            pp = np.concatenate([p[:1], p]) if len(p) else np.zeros(1)
            ap = "–" if math.isnan(m.ap) else f"{m.ap:.2f}"
            ax.step(rr, pp, where="post", label=f"{c} (AP {ap}, n={m.num_gt})")
        ax.set_xlim(0, 1.02)
        ax.set_ylim(0, 1.02)
        ax.set_xlabel("recall")
        ax.set_ylabel("precision")
        ax.set_title(CRITERION_NAMES.get(key, key), fontsize=10)
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    return _png(fig)


def confusion_png(ev: Evaluation) -> bytes:
    """The confusion matrix as a heat map with the counts written in."""
    mat = np.asarray(ev.confusion, dtype=np.float64)
    cols = [*ev.classes, "missed"]
    fig = _figure(1.2 + 1.1 * len(cols), 1.0 + 0.9 * len(ev.confusion_labels))
    ax = fig.subplots()
    ax.imshow(mat, cmap="Blues", vmin=0, vmax=max(float(mat.max()), 1.0))
    ax.set_xticks(range(len(cols)), cols, rotation=30, ha="right")
    ax.set_yticks(range(len(ev.confusion_labels)), ev.confusion_labels)
    ax.set_xlabel("detected")
    ax.set_ylabel("ground truth")
    ax.set_title(f"Confusion at {CRITERION_NAMES.get(PRIMARY, PRIMARY)}", fontsize=10)
    half = mat.max() / 2 if mat.size else 0
    for (i, j), v in np.ndenumerate(mat):
        if i == len(ev.confusion_labels) - 1 and j == len(cols) - 1:
            continue  # a false alarm cannot be missed: the corner is empty by definition
        ax.text(
            j,
            i,
            f"{int(v)}",
            ha="center",
            va="center",
            color="white" if v > half and v > 0 else "black",
        )
    fig.tight_layout()
    return _png(fig)


# -- everything ----------------------------------------------------------------------------
def write_report(evaluation: DatasetEvaluation, out_dir: str | os.PathLike[str]) -> ReportFiles:
    """Write ``report.md``, ``report.json``, ``pr_curves.png`` and ``confusion.png``.

    Parameters
    ----------
    evaluation : DatasetEvaluation
        From :func:`~ontodetect.evaluation.evaluate_dataset` (or
        :func:`~ontodetect.evaluation.summarize_outcomes`).
    out_dir : str or PathLike
        Folder to write into (created if needed); each file is written atomically.

    Returns
    -------
    ReportFiles
    """
    out = make_folder(out_dir, "report folder")
    for key in CRITERIA:
        if key not in evaluation.evaluations:
            raise WriteError(out, f"the evaluation lacks the {key!r} criterion")
    md = atomic_write_text(out / "report.md", markdown_report(evaluation))
    js = atomic_write_text(
        out / "report.json",
        json.dumps(report_document(evaluation), indent=1, ensure_ascii=False) + "\n",
    )
    pr = atomic_write_bytes(out / "pr_curves.png", pr_curves_png(evaluation))
    cm = atomic_write_bytes(out / "confusion.png", confusion_png(evaluation.primary))
    return ReportFiles(md, js, pr, cm)
