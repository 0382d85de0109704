"""``ontodetect segment INPUT -o OUT``: candidate clusters and their planes, for tuning."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import typer
from rich.table import Table

from ..io import (
    MIN_SCAN_POINTS,
    atomic_write_text,
    check_output_folder,
    read_points,
    staged_folder,
    write_cloud,
    write_timings,
)
from . import app
from ._clouds import FORMAT_HELP, cloud_format
from ._common import check_up_option, load_config
from ._console import console, reporting, state

#: Colour of points in no cluster.
NONE_COLOR = (160, 160, 160)

if TYPE_CHECKING:
    from ..segment import Segmentation


def cluster_colors(labels: np.ndarray, seed: int = 0) -> np.ndarray:
    """(n, 3) uint8: a distinct colour per cluster id, grey for -1."""
    k = int(labels.max()) + 1 if labels.size and labels.max() >= 0 else 0
    palette = np.random.default_rng(seed).integers(40, 256, size=(max(k, 1), 3)).astype(np.uint8)
    out = np.empty((len(labels), 3), dtype=np.uint8)
    out[:] = NONE_COLOR
    has = labels >= 0
    out[has] = palette[labels[has]]
    return out


def write_segmentation(seg: Segmentation, out: Path) -> tuple[Path, Path]:
    """Write ``segments.ply`` (input points coloured by cluster, fields ``cluster`` and
    ``plane``), ``planes.json`` (clusters, planes, relations, configuration) and
    ``timings.json`` (the preparation's seconds per stage, which differ from run to run:
    planes.json does not), as one unit (:func:`~ontodetect.io.staged_folder`)."""
    labels = seg.labels_per_point()
    planes = seg.planes_per_point()
    source = seg.prepared.cloud
    # The input frame and units, not the levelled frame: the file overlays the input.
    cloud = source.replace(
        xyz=seg.prepared.from_level(source.xyz),
        normals=None,
        rgb=cluster_colors(labels),
        fields={
            **dict(source.fields),
            "cluster": labels.astype(np.int32),
            "plane": planes.astype(np.int32),
        },
    )
    # Point lists live in segments.ply; the JSON stays small enough to read.
    doc = seg.to_dict(with_points=False)
    timings = doc["prepare"].pop("timings", {})
    with staged_folder(out, "output folder") as stage:
        write_cloud(stage / "segments.ply", cloud)
        atomic_write_text(stage / "planes.json", json.dumps(doc, indent=1))
        write_timings(stage / "timings.json", timings)
    return out / "segments.ply", out / "planes.json"


@app.command()
def segment(
    path: Path = typer.Argument(..., help="Point cloud file or scan folder."),
    out: Path = typer.Option(..., "--out", "-o", help="Output folder."),
    format: str | None = typer.Option(None, "--format", "-f", help=FORMAT_HELP),
    config: Path | None = typer.Option(None, "--config", "-c", help="Configuration YAML."),
    set_: list[str] = typer.Option(
        [],
        "--set",
        metavar="KEY=VALUE",
        help="Override one parameter, e.g. --set cluster.radius=0.04",
    ),
    up: str | None = typer.Option(
        None,
        "--up",
        help="Up axis: z, -y, ..., auto (estimate it), or auto-frame (default: auto for "
        "an organized or single-view cloud, z otherwise).",
    ),
    scale: float | None = typer.Option(None, "--scale", help="Scale factor k_s to metres."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random step."),
) -> None:
    """Prepare and cluster a scan; write segments.ply and planes.json and print a summary."""
    from ..segment import segment as run_segment  # lazy: CLI start-up

    check_up_option(up)
    fmt = cloud_format(format, "segment")
    cfg = load_config(config, set_)
    check_output_folder(out)  # before any work
    with reporting():
        cloud = read_points(path, fmt, min_points=MIN_SCAN_POINTS)
        seg = run_segment(cloud, cfg, seed=seed, up=up, scale=scale)
        ply, js = write_segmentation(seg, out)
    if state.quiet:
        return
    prep = seg.prepared
    console.print(
        f"{path.name}: {prep.num_points:,} points, {len(prep.voxels):,} voxels "
        f"({int(prep.object_mask.sum()):,} searched), floor "
        f"{'found' if prep.floor_found else 'NOT found'}, radius {seg.radius:.3f} m, "
        f"{len(seg)} clusters ({sum(c.flagged for c in seg)} flagged)"
    )
    table = Table(show_header=True, box=None, pad_edge=False)
    for col in ("id", "points", "size l×b×h (m)", "bottom", "planes", "parts", "flags"):
        table.add_column(col, justify="right" if col in ("id", "points", "planes") else "left")
    shown = seg.clusters if state.verbose else [c for c in seg if not c.flagged] or seg.clusters
    for c in shown:
        table.add_row(
            str(c.id),
            f"{c.num_points:,}",
            "×".join(f"{v:.2f}" for v in c.box.size),
            f"{c.bottom:.2f}",
            str(len(c.planes)),
            ", ".join(f"{p.kind}@{p.height:.2f}" for p in c.parts),
            ", ".join(c.flags),
        )
    console.print(table)
    if not state.verbose and len(shown) < len(seg):
        console.print(f"({len(seg) - len(shown)} flagged clusters hidden; -v shows them)")
    console.print(f"wrote {ply}, {js}")
