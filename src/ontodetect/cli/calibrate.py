"""``ontodetect calibrate DATASET -o my-ontology.yaml``: fit an ontology's Gaussians to labels."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.table import Table
from rich.text import Text

from ..io import atomic_write_text
from ..io._layouts import DATASET_FORMATS
from . import app
from ._common import (
    SCHEDULER_HELP,
    WORKERS_HELP,
    check_up_option,
    executor_option,
    load_config,
)
from ._console import console, err_console, reporting, state
from ._defaults import (
    MIN_GAIN_ROOMS,
    MIN_ROOMS,
    ONE_SIDED_QUANTILE,
    PRIOR_SIGMA_SHARE,
    PRIOR_STRENGTH,
)


def _pct(x: float) -> str:
    return f"{100 * x:.1f}"


@app.command()
def calibrate(
    dataset: Path = typer.Argument(..., help="Labelled dataset folder."),
    out: Path = typer.Option(..., "--out", "-o", help="Calibrated ontology YAML to write."),
    ontology: Path | None = typer.Option(
        None, "--ontology", help="Ontology file to calibrate (default: the built-in one)."
    ),
    split: float = typer.Option(
        0.5, "--split", help="Share of the rooms used for calibration; the rest is held out."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the split."),
    format: str = typer.Option(
        "auto", "--format", "-f", help=f"Dataset layout: {', '.join(DATASET_FORMATS)}."
    ),
    jobs: int = typer.Option(
        1, "--jobs", "-j", help="Scenes in parallel on a local cluster (0: one per CPU)."
    ),
    workers: int | None = typer.Option(None, "--workers", metavar="N", help=WORKERS_HELP),
    scheduler: str | None = typer.Option(
        None, "--scheduler", metavar="tcp://HOST:PORT", help=SCHEDULER_HELP
    ),
    sigma_floor: float = typer.Option(
        PRIOR_SIGMA_SHARE,
        "--sigma-floor",
        help="A calibrated sigma is at least this share of the original sigma.",
    ),
    quantile: float = typer.Option(
        ONE_SIDED_QUANTILE,
        "--quantile",
        help="One-sided bounds and plateau ends move to this "
        "quantile of the measured values (0: the extreme value).",
    ),
    min_rooms: int = typer.Option(
        MIN_ROOMS,
        "--min-rooms",
        help="Keep a constraint unless objects of this many rooms measured it.",
    ),
    prior_strength: float = typer.Option(
        PRIOR_STRENGTH,
        "--prior-strength",
        help="Weight of the original values, in objects (0: plain maximum likelihood).",
    ),
    validate: bool = typer.Option(
        True,
        "--validate/--no-validate",
        help="Keep a fitted part only if it passes the nested check on calibration rooms "
        "left out in turn (see --min-gain-rooms).",
    ),
    min_gain_rooms: int = typer.Option(
        MIN_GAIN_ROOMS,
        "--min-gain-rooms",
        help="Keep a fitted part only if F1 rises in this many calibration rooms "
        "left out in turn (and falls in none); fewer rooms: nothing changes.",
    ),
    report: Path | None = typer.Option(
        None,
        "--report",
        help="Also write the split, every constraint before/after and the "
        "held-out comparison as JSON.",
    ),
    evaluate: bool = typer.Option(
        True,
        "--evaluate/--no-evaluate",
        help="Compare detection before/after on the held-out scenes.",
    ),
    config: Path | None = typer.Option(None, "--config", "-c", help="Configuration YAML."),
    set_: list[str] = typer.Option(
        [],
        "--set",
        metavar="KEY=VALUE",
        help="Override one parameter, e.g. --set cluster.radius=0.04",
    ),
    room: str | None = typer.Option(
        None, "--room", help="Room category for the prior in the held-out comparison."
    ),
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
) -> None:
    """Estimate each constraint's mean and sigma from labelled objects; check on held-out rooms."""
    from ..calibrate import FitSettings, calibrate_dataset  # lazy: CLI start-up

    check_up_option(up)
    opts: dict = {
        "config": load_config(config, set_, up=up, scale=scale, threshold=threshold),
        "seed": 0,
    }
    if room is not None:
        opts["room"] = room
    settings = FitSettings(
        prior_share=sigma_floor,
        quantile=quantile,
        min_rooms=min_rooms,
        prior_strength=prior_strength,
        validate=validate,
        min_gain_rooms=min_gain_rooms,
    )
    with reporting(), executor_option(scheduler, workers, jobs) as executor:
        result = calibrate_dataset(
            dataset,
            base=ontology,
            format=format,
            split=split,
            seed=seed,
            detect_options=opts,
            evaluate=evaluate,
            settings=settings,
            executor=executor,
        )
    atomic_write_text(out, result.text)
    if report is not None:
        atomic_write_text(report, json.dumps(result.to_dict(), indent=1) + "\n")
    if result.too_few_rooms:
        # Even with --quiet: the file written equals the original, which must not pass
        # for a calibrated one.
        err_console.print(f"warning: nested check {result.check}", highlight=False)
    if state.quiet:
        return
    console.print(result.split.describe())
    used = ", ".join(f"{n} {c}" for c, n in sorted(result.used.items())) or "none"
    skipped = ", ".join(f"{n} {c}" for c, n in sorted(result.skipped.items()))
    console.print(
        f"measured objects: {used}"
        + (f" (no cluster with IoU >= 0.25: {skipped})" if skipped else "")
    )
    for line in result.failed:
        console.print(Text.assemble(("skipped", "yellow"), f" {line}"))
    kept = [d.name for d in result.decisions if d.accepted]
    if not result.too_few_rooms:
        # Said in every case: a file that silently equals the original reads as calibrated.
        style = "bold yellow" if result.settings.validate and not kept else "bold"
        console.print(
            Text.assemble(
                ("nested check:", style),
                f" {result.check}" + (f" Kept: {', '.join(kept)}." if kept else ""),
            ),
            highlight=False,
        )
    if state.verbose:
        for d in result.decisions:
            mark = ("kept", "green") if d.accepted else "rejected"
            console.print(Text.assemble("  ", mark, f" {d.name}: {d.reason}"), highlight=False)
    changed = [f for f in result.fits if f.changed]
    table = Table(title=f"{len(changed)} of {len(result.fits)} constraints calibrated")
    for col in ("constraint", "n", "before", "after"):
        table.add_column(col, justify="right" if col == "n" else "left")
    for f in changed if state.verbose else changed[:40]:
        table.add_row(f.name, str(f.samples), f.before.describe(), f.after.describe())
    console.print(table)
    rows = result.comparison()
    if rows:
        comp = Table(title="held-out scenes, point IoU >= 0.25")
        cols = ("class", "GT", "P before %", "P after %", "R before %", "R after %")
        for col in (*cols, "F1 before %", "F1 after %"):
            comp.add_column(col, justify="left" if col == "class" else "right")
        for r in rows:
            comp.add_row(
                r["class"],
                str(r["ground_truth"]),
                _pct(r["precision_before"]),
                _pct(r["precision_after"]),
                _pct(r["recall_before"]),
                _pct(r["recall_after"]),
                _pct(r["f1_before"]),
                _pct(r["f1_after"]),
            )
        console.print(comp)
    console.print(f"wrote {out}" + (f", {report}" if report is not None else ""))
