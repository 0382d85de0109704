"""``ontodetect demo -o OUT``: the whole method on a built-in simulated office."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from . import app
from ._console import console, reporting, state
from ._defaults import DEMO_ROOM, DEMO_SEED


@app.command()
def demo(
    out: Path = typer.Option(Path("demo-output"), "--out", "-o", help="Output folder."),
    room: str = typer.Option(DEMO_ROOM, "--room", help="Room type to simulate."),
    seed: int = typer.Option(DEMO_SEED, "--seed", help="Seed of the simulation and detection."),
) -> None:
    """Simulate a furnished room, detect its furniture and compare with the truth (no input)."""
    from ..demo import run_demo  # lazy: CLI start-up

    with reporting():
        d = run_demo(out, room=room, seed=seed)
    if state.quiet:
        return
    table = Table(title=f"simulated {room} (seed {seed}): {len(d.result.detections)} detections")
    for col in ("class", "truth", "detected", "correct", "precision", "recall"):
        table.add_column(col, justify="left" if col == "class" else "right")
    for name, m in d.evaluation.per_class.items():
        if m.num_gt == 0 and m.num_pred == 0:
            continue  # nothing of this class in the room, nothing claimed
        table.add_row(
            name, str(m.num_gt), str(m.num_pred), str(m.tp), f"{m.precision:.2f}", f"{m.recall:.2f}"
        )
    console.print(table)
    console.print("correct = point IoU >= 0.25 with a ground-truth object of the same class")
    console.print(f"scan:    {d.scan_dir}/cloud.ply (+ objects.json, scene.json)")
    console.print(f"results: {d.files.detections}, {d.files.labelled}, {d.files.picture}")
    console.print(f"object map (generic CAD models): {out}/object_map.ply, {out}/object_map.glb")
