"""``ontodetect info FILE``: what is in a point cloud file."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from typing import Any

import typer
from rich.table import Table

from ..errors import ReadError
from ..io import read_points
from ..io._labels import nyu40_name
from . import app
from ._clouds import FORMAT_HELP, cloud_format
from ._console import console, reporting

#: Layouts of one scan per file, as named in ``--format`` (VoteNet's): a folder of them is a
#: dataset, which ``ontodetect eval`` reads.
SCAN_FILES = {"scannet-votenet": "*_vert.npy", "sunrgbd-votenet": "*_pc.npz"}


def boxes_line(boxes: list[Any]) -> str:
    """The ``boxes`` of a labelled scan in one line: their number and how many per class.

    Rows of ``(K, 7)`` ScanNet boxes end in the NYU40 class id; SUN RGB-D boxes are
    mappings with ``class_id``.

    Examples
    --------
    >>> boxes_line([[0, 0, 0, 1, 1, 1, 5.0], [1, 1, 0, 1, 1, 1, 5.0], {"class_id": 7}])
    '3 (2 chair [5], 1 table [7]; --json lists them)'
    """
    ids = Counter(int(b["class_id"] if isinstance(b, dict) else b[-1]) for b in boxes)
    per_class = ", ".join(f"{n} {nyu40_name(c)} [{c}]" for c, n in sorted(ids.items()))
    return f"{len(boxes)} ({per_class}; --json lists them)" if boxes else "0"


#: Items of a list ``info`` prints in full; --json lists the rest.
MAX_ITEMS = 12


def value_line(value: Any) -> str:
    """An extra field of a scan in one line: a list's items comma-separated (the first
    :data:`MAX_ITEMS`), nested lists in brackets and mappings in braces, numbers short.

    Examples
    --------
    >>> value_line(["x", "y", "z"])
    'x, y, z'
    >>> value_line([[1.0, 0.0], [0.5, 2.25]])
    '[1, 0], [0.5, 2.25]'
    >>> value_line({"width": 640, "size": [0.1, 0.2]})
    'width: 640, size: [0.1, 0.2]'
    >>> value_line(list(range(20)))
    '0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, ... (20 in all; --json lists them)'
    """
    if isinstance(value, dict):
        return ", ".join(f"{k}: {_item(v)}" for k, v in value.items())
    if isinstance(value, (list, tuple)):
        line = ", ".join(_item(v) for v in value[:MAX_ITEMS])
        if len(value) > MAX_ITEMS:
            line += f", ... ({len(value)} in all; --json lists them)"
        return line
    return _item(value)


def _item(value: Any) -> str:
    """One value inside a list or mapping: nested ones bracketed, floats in ``g`` form."""
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_item(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_item(v) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


@app.command()
def info(
    path: Path = typer.Argument(..., help="Point cloud file or scan folder."),
    format: str | None = typer.Option(
        None,
        "--format",
        "-f",
        help=f"{FORMAT_HELP} 'ontodetect eval' reads a dataset folder.",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print machine-readable JSON."),
) -> None:
    """Print number of points, fields, bounds, spacing, and guesses of units and up axis."""
    from ..summary import describe_cloud  # lazy: CLI start-up

    fmt = cloud_format(format, "info")
    if fmt in SCAN_FILES and path.is_dir():
        raise ReadError(
            path,
            f"is a folder, but info reads one scan of the {fmt!r} layout (a "
            f"{SCAN_FILES[fmt]} file); 'ontodetect eval -f {format}' reads a dataset folder",
        )
    with reporting():
        cloud = read_points(path, fmt)
    summary = describe_cloud(cloud)
    if as_json:
        typer.echo(json.dumps(summary.to_dict(), indent=2))
        return
    fmt3 = lambda v: "  ".join(f"{x:.3f}" for x in v)  # noqa: E731
    attrs = (
        ["xyz"]
        + (["rgb"] if summary.has_colors else [])
        + (["normals"] if summary.has_normals else [])
        + summary.fields
    )
    tilt = f", tilted {summary.up_tilt:.1f}°" if summary.up_tilt >= 0.5 else ""
    rows = [
        ("format", str(summary.format)),
        ("points", f"{summary.num_points:,}"),
        ("fields", ", ".join(attrs)),
        ("bounds min", fmt3(summary.bounds_min)),
        ("bounds max", fmt3(summary.bounds_max)),
        ("extent", fmt3(summary.extent)),
        ("point spacing", f"{summary.spacing:.4g} (median nearest neighbour)"),
        ("density", f"{summary.density:,.0f} points per square unit"),
        ("units (guess)", summary.units),
        (
            "up axis (guess)",
            f"{summary.up_axis}{tilt} (confidence {summary.up_confidence:.2f}): what "
            "'detect --up auto' uses",
        ),
        (
            "detect's up",
            "auto (an organized or single-view cloud)"
            if summary.up_default == "auto"
            else "z (not a single view; --up auto to estimate it, --up -y... to name it)",
        ),
    ]
    for k, v in summary.extra.items():
        rows.append((k, boxes_line(v) if k == "boxes" else value_line(v)))
    if summary.sensor is not None:
        rows.append(
            (
                "single view",
                f"sensor at {fmt3(summary.sensor)}: detection smooths its "
                "depth steps and knows what objects hide from it",
            )
        )
    _print_rows(str(path), rows)


def _print_rows(title: str, rows: list[tuple[str, str]]) -> None:
    """A table in a terminal; plain ``key  value`` lines in a pipe or a file, where a
    table would pad every row with blanks to its widest value."""
    if console.is_terminal:
        table = Table(title=title, show_header=False, box=None, pad_edge=False)
        table.add_column(style="bold")
        table.add_column()
        for key, value in rows:
            table.add_row(key, value)
        console.print(table)
        return
    width = max(len(key) for key, _ in rows)
    console.print(title, soft_wrap=True)
    for key, value in rows:
        console.print(f"{key:<{width}}  {value}", soft_wrap=True)
