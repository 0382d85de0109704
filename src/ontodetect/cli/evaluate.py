"""``ontodetect eval DATASET [-o REPORT_DIR]``: detect in every scene and score against labels."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.table import Table
from rich.text import Text

from ..io._layouts import DATASET_FORMATS
from . import app
from ._common import (
    SCHEDULER_HELP,
    WORKERS_HELP,
    check_up_option,
    executor_option,
    load_config,
    load_ontology_option,
    number_list,
    room_option,
)
from ._console import console, reporting, state


def _pct(x: float) -> str:
    return f"{100 * x:.1f}"


@app.command("eval")
def eval_(
    dataset: Path = typer.Argument(..., help="Labelled dataset folder, or one scene."),
    out: Path | None = typer.Option(
        None,
        "--out",
        "-o",
        help="Report folder: report.md, report.json, pr_curves.png, confusion.png.",
    ),
    format: str = typer.Option(
        "auto", "--format", "-f", help=f"Dataset layout: {', '.join(DATASET_FORMATS)}."
    ),
    detections: Path | None = typer.Option(
        None,
        "--detections",
        help="Score stored detections DIR/<scene>/detections.json instead of detecting.",
    ),
    save_detections: bool = typer.Option(
        False,
        "--save-detections",
        help="Also write REPORT_DIR/detections/<scene>/detections.json (usable with --detections).",
    ),
    jobs: int = typer.Option(
        1, "--jobs", "-j", help="Scenes in parallel on a local cluster (0: one per CPU)."
    ),
    workers: int | None = typer.Option(None, "--workers", metavar="N", help=WORKERS_HELP),
    scheduler: str | None = typer.Option(
        None, "--scheduler", metavar="tcp://HOST:PORT", help=SCHEDULER_HELP
    ),
    skip_failed: bool = typer.Option(
        False, "--skip-failed", help="Leave out scenes that cannot be read, and list them."
    ),
    as_json: bool = typer.Option(
        False, "--json", help="Print the report.json document on stdout instead of the tables."
    ),
    config: Path | None = typer.Option(None, "--config", "-c", help="Configuration YAML."),
    set_: list[str] = typer.Option(
        [],
        "--set",
        metavar="KEY=VALUE",
        help="Override one parameter, e.g. --set cluster.radius=0.04",
    ),
    ontology: list[Path] = typer.Option(
        [], "--ontology", help="Ontology YAML to add (repeatable)."
    ),
    ontology_only: bool = typer.Option(
        False, "--ontology-only", help="Use only the --ontology files, not the built-ins."
    ),
    room: str | None = typer.Option(
        None,
        "--room",
        help="Room category for the prior (Places205), the same for every scene; auto "
        "(default): estimated from each scan; none: no prior.",
    ),
    room_probs: Path | None = typer.Option(
        None, "--room-probs", help="YAML/JSON mapping room category -> probability."
    ),
    indoor: float | None = typer.Option(None, "--indoor", help="P(indoor), Eq. 3.5."),
    up: str | None = typer.Option(
        None,
        "--up",
        help="Up axis: z, -y, ..., auto (estimate it), or auto-frame (default: auto for "
        "an organized or single-view cloud, z otherwise).",
    ),
    scale: float | None = typer.Option(None, "--scale", help="Scale factor k_s to metres."),
    threshold: float | None = typer.Option(
        None, "--threshold", help="Decision threshold (detect.threshold; Table 4.1: 0.15)."
    ),
    beta: float | None = typer.Option(
        None, "--beta", help="Energy weight of the class probability (detect.beta)."
    ),
    context: float | None = typer.Option(
        None, "--context", help="Seat-near-table pairwise strength (detect.context)."
    ),
    votes: int | None = typer.Option(
        None,
        "--votes",
        help="Passes over each scan, a majority keeps a detection (detect.votes, default 3).",
    ),
    proposals: str | None = typer.Option(
        None,
        "--proposals",
        help="Object proposals: vote (default) or recognition (experimental, off by default; "
        "detect.proposals).",
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of every random step."),
    turns: str | None = typer.Option(
        None,
        "--turns",
        metavar="DEG,DEG,...",
        help="Detect every scene once per turn about the vertical (e.g. 0,90,180,270) and "
        "report each turn and the pooled figure.",
    ),
    seeds: str | None = typer.Option(
        None,
        "--seeds",
        metavar="N,N,...",
        help="Detect every scene (and turn) once per seed (e.g. 0,1,2), instead of --seed.",
    ),
) -> None:
    """Evaluate detection on a labelled dataset: P, R, F1, AP per class, confusion, times."""
    from ..evaluation import evaluate_dataset, write_report  # lazy: CLI start-up
    from ..evaluation._report import CRITERION_NAMES, report_document  # lazy: CLI start-up

    check_up_option(up)
    cfg = load_config(
        config,
        set_,
        up=up,
        scale=scale,
        threshold=threshold,
        beta=beta,
        context=context,
        votes=votes,
        proposals=proposals,
    )
    opts: dict = {"config": cfg, "seed": seed}
    if ontology or ontology_only:
        opts["ontology"] = load_ontology_option(ontology, ontology_only)
    given = {"room": room_option(room, room_probs), "indoor": indoor}
    opts.update({k: v for k, v in given.items() if v is not None})
    turn_list = number_list(turns, float, "--turns")
    seed_list = number_list(seeds, int, "--seeds")
    if save_detections and out is None:
        raise typer.BadParameter("needs --out REPORT_DIR", param_hint="--save-detections")
    save_dir = out / "detections" if (save_detections and out is not None) else None
    with reporting(), executor_option(scheduler, workers, jobs) as executor:
        result = evaluate_dataset(
            dataset,
            format=format,
            detect_options=opts,
            detections_dir=detections,
            save_detections=save_dir,
            on_error="skip" if skip_failed else "raise",
            turns=turn_list,
            seeds=seed_list,
            executor=executor,
        )
        files = write_report(result, out) if out is not None else None
    if as_json:
        typer.echo(json.dumps(report_document(result), ensure_ascii=False))
        return
    if state.quiet:
        return
    ev = result.primary
    runs = f"{len(result.scenes)} scenes"
    if result.by_variant:
        runs = f"{len({s.source.name for s in result.scenes})} scenes, {len(result.scenes)} runs"
    table = Table(title=f"{dataset.name}: {runs}, {CRITERION_NAMES['iou@0.25']}")
    for col in ("class", "GT", "det", "TP", "P %", "R %", "F1 %", "AP %"):
        table.add_column(col, justify="left" if col == "class" else "right")
    for m in [*(ev.per_class[c] for c in ev.classes), ev.overall]:
        ap = "-" if m.ap != m.ap else _pct(m.ap)  # NaN: no ground truth
        table.add_row(
            m.label,
            str(m.num_gt),
            str(m.num_pred),
            str(m.tp),
            _pct(m.precision),
            _pct(m.recall),
            _pct(m.f1),
            ap,
        )
    console.print(table)
    for run, rev in result.by_variant.items():
        console.print(
            f"{run}: "
            + ", ".join(
                f"{c} P {_pct(m.precision)} R {_pct(m.recall)} ({m.tp}/{m.num_pred}/{m.num_gt})"
                for c, m in ((c, rev.per_class[c]) for c in rev.classes)
            )
        )
    for key in ("iou@0.5", "distance"):
        m = result.evaluations[key].overall
        console.print(
            f"{CRITERION_NAMES[key]}: precision {_pct(m.precision)} %, recall {_pct(m.recall)} %"
        )
    for key, ap in result.box_ap.items():
        console.print(
            f"box AP {key}: "
            + ", ".join(f"{c} {'-' if v != v else _pct(v)}" for c, v in ap.items())
        )
    t = result.scene_seconds()
    console.print(
        f"detection per scene: mean {t['mean']:.2f} s, max {t['max']:.2f} s; "
        f"{result.seconds:.1f} s in all ({result.jobs} worker"
        f"{'s' if result.jobs != 1 else ''})"
    )
    for s in result.failed:
        console.print(Text.assemble(("skipped", "yellow"), f" {s.name}: {s.error}"))
    if files is not None:
        console.print(f"wrote {files.markdown}, {files.json}, {files.pr_curves}, {files.confusion}")
