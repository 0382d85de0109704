"""``ontodetect view OUT_DIR``: one self-contained HTML page of a detect run."""

from __future__ import annotations

from pathlib import Path

import typer

from . import app
from ._console import console, state


@app.command()
def view(
    out_dir: Path = typer.Argument(..., help="A folder written by 'ontodetect detect'."),
    output: Path | None = typer.Option(
        None, "--output", "-o", help="Page to write (default: OUT_DIR/view.html)."
    ),
    max_points: int = typer.Option(
        250_000, "--max-points", help="Points the page carries at most (decimated above)."
    ),
) -> None:
    """Write view.html: points, boxes with labels and scores, per-class toggles, the CAD
    object map; opens from the file system (three.js inline, no network)."""
    from ..render import write_viewer  # lazy: CLI start-up (the render package)

    page = write_viewer(out_dir, output, max_points=max_points)
    if not state.quiet:
        console.print(f"wrote {page} (open it in a browser)")
