"""``ontodetect cad fit DETECTIONS INPUT -o OUT`` and ``ontodetect cad models``."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from rich.table import Table

from ..errors import InvalidParameterError
from ..io import atomic_write, check_output_folder, read_points, staged_folder
from ..io._detections import read_detections, write_detections
from . import app
from ._clouds import FORMAT_HELP, cloud_format
from ._console import console, reporting, state
from ._defaults import KERNELS, MIN_SCORE

cad_app = typer.Typer(
    name="cad",
    help="Generic CAD models: fit them to detections (object map), list the library.",
    no_args_is_help=True,
    context_settings={"help_option_names": ["-h", "--help"]},
)
app.add_typer(cad_app, name="cad")

if TYPE_CHECKING:
    from ..cad import ModelLibrary


def load_library(manifests: list[Path], only: bool) -> ModelLibrary:
    """The built-in models with ``--models`` manifests merged in (or only theirs)."""
    from ..cad import ModelLibrary, builtin_library, load_manifest  # lazy: CLI start-up

    if only and not manifests:
        raise InvalidParameterError(
            "--models-only", "used with at least one --models FILE", "no file"
        )
    lib = ModelLibrary() if only else builtin_library()
    for path in manifests:
        lib = lib.merged(load_manifest(path).values())
    return lib


@cad_app.command("fit")
def fit(
    detections: Path = typer.Argument(
        ..., metavar="DETECTIONS", help="detections.json or the folder holding it."
    ),
    path: Path = typer.Argument(
        ..., metavar="INPUT", help="The point cloud the detections were made on."
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output folder."),
    format: str | None = typer.Option(None, "--format", "-f", help=FORMAT_HELP),
    models: list[Path] = typer.Option([], "--models", help="Model manifest YAML (repeatable)."),
    models_only: bool = typer.Option(
        False, "--models-only", help="Use only the --models manifests, not the built-ins."
    ),
    min_score: float = typer.Option(
        MIN_SCORE, "--min-score", help="Below this probability an object gets a blank box."
    ),
    scale: bool = typer.Option(
        True, "--scale/--no-scale", help="Stretch models to the measured seat or top."
    ),
    kernel: str = typer.Option(
        "tukey", "--kernel", help="Robust kernel: " + ", ".join(KERNELS) + "."
    ),
    spacing: float = typer.Option(0.01, "--spacing", help="Sample spacing (m) of object_map.ply."),
    glb: bool = typer.Option(True, "--glb/--no-glb", help="Write object_map.glb."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random step."),
) -> None:
    """Fit models to stored detections; write detections.json (with cad) and the object map."""
    from ..cad import cad_dict, fit_document, write_object_map  # lazy: CLI start-up

    check_output_folder(out)  # before any work
    fmt = cloud_format(format, "cad fit")
    lib = load_library(models, models_only)
    doc = read_detections(detections)
    with reporting():
        cloud = read_points(path, fmt)
        fits = fit_document(
            doc, cloud, lib, min_score=min_score, seed=seed, scale_to_object=scale, kernel=kernel
        )
        for det, f in zip(doc["detections"], fits):
            det["cad"] = cad_dict(f)
        # Written beside the detect run's files when -o is its folder: they stay.
        with staged_folder(out, "output folder", keep_earlier=True) as stage:
            write_detections(stage / "detections.json", doc)
            staged = write_object_map(fits, stage, spacing=spacing, seed=seed, glb=glb)
        js = out / "detections.json"
        written = [js] + [
            out / Path(p).name for p in (staged.points, staged.glb, staged.mesh) if p is not None
        ]
    if state.quiet:
        return
    table = Table(title=f"{path.name}: {len(fits)} objects")
    for col in ("id", "label", "model", "yaw (deg)", "rms (cm)", "matched", "note"):
        table.add_column(col, justify="left" if col in ("label", "model", "note") else "right")
    for f in fits:
        rms = "" if not math.isfinite(f.rms) else f"{100 * f.rms:.1f}"
        table.add_row(
            str(f.id),
            f.label,
            f.model,
            f"{math.degrees(f.yaw):.1f}",
            rms,
            f"{f.inlier_fraction:.0%}",
            f.reason,
        )
    console.print(table)
    console.print("wrote " + ", ".join(str(p) for p in written))


@cad_app.command("models")
def models_command(
    models: list[Path] = typer.Option([], "--models", help="Model manifest YAML (repeatable)."),
    models_only: bool = typer.Option(
        False, "--models-only", help="List only the --models manifests' models."
    ),
    picture: Path | None = typer.Option(
        None, "--picture", help="Draw the models (thin profile and full) to a PNG."
    ),
) -> None:
    """List the model library: name, label, size and where each model comes from."""
    from ..cad import library_figure  # lazy: CLI start-up

    lib = load_library(models, models_only)
    if picture is not None:
        fig = library_figure(lib)
        with atomic_write(picture, "wb") as fh:
            fig.savefig(fh, format="png", dpi=90)
    # The list is the command's result: printed under -q too, like info's description.
    table = Table(title=f"{len(lib)} models")
    for col in ("name", "label", "w × d × h (m)", "seat/top", "turns", "source"):
        table.add_column(col, no_wrap=col != "source")
    for m in lib.values():
        d = m.dims
        key = d.get("seat_height", d.get("top_height"))
        table.add_row(
            m.name,
            m.label,
            f"{d['width']:.2f} × {d['depth']:.2f} × {d['height']:.2f}",
            "" if key is None else f"{key:.2f}",
            {0: "any", 1: "-", 2: "180°", 4: "90°"}[m.symmetry],
            m.source,
        )
    console.print(table)
    if picture is not None and not state.quiet:
        console.print(f"wrote {picture}")
