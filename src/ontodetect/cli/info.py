"""``ontodetect info FILE``: what is in a point cloud file."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.table import Table

from ..io import read_cloud, supported_formats
from . import app
from ._console import console, reporting


@app.command()
def info(
    path: Path = typer.Argument(..., help="Point cloud file or scan folder."),
    format: str | None = typer.Option(
        None, "--format", "-f", help=f"Force a format: {', '.join(supported_formats())}."
    ),
    as_json: bool = typer.Option(False, "--json", help="Print machine-readable JSON."),
) -> None:
    """Print number of points, fields, bounds, spacing, and guesses of units and up axis."""
    from ..summary import describe_cloud  # lazy: CLI start-up

    with reporting():
        cloud = read_cloud(path, format=format)
    summary = describe_cloud(cloud)
    if as_json:
        typer.echo(json.dumps(summary.to_dict(), indent=2))
        return
    table = Table(title=str(path), show_header=False, box=None, pad_edge=False)
    table.add_column(style="bold")
    table.add_column()
    fmt3 = lambda v: "  ".join(f"{x:.3f}" for x in v)  # noqa: E731
    table.add_row("format", str(summary.format))
    table.add_row("points", f"{summary.num_points:,}")
    attrs = (
        ["xyz"]
        + (["rgb"] if summary.has_colors else [])
        + (["normals"] if summary.has_normals else [])
        + summary.fields
    )
    table.add_row("fields", ", ".join(attrs))
    table.add_row("bounds min", fmt3(summary.bounds_min))
    table.add_row("bounds max", fmt3(summary.bounds_max))
    table.add_row("extent", fmt3(summary.extent))
    table.add_row("point spacing", f"{summary.spacing:.4g} (median nearest neighbour)")
    table.add_row("density", f"{summary.density:,.0f} points per square unit")
    table.add_row("units (guess)", summary.units)
    tilt = f", tilted {summary.up_tilt:.1f}°" if summary.up_tilt >= 0.5 else ""
    table.add_row(
        "up axis (guess)",
        f"{summary.up_axis}{tilt} (confidence {summary.up_confidence:.2f}): what "
        "'detect --up auto' uses",
    )
    table.add_row(
        "detect's up",
        "auto (an organized or single-view cloud)"
        if summary.up_default == "auto"
        else "z (not a single view; --up auto to estimate it, --up -y... to name it)",
    )
    for k, v in summary.extra.items():
        table.add_row(k, str(v))
    if summary.sensor is not None:
        table.add_row(
            "single view",
            f"sensor at {fmt3(summary.sensor)}: detection smooths its "
            "depth steps and knows what objects hide from it",
        )
    console.print(table)
