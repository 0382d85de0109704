"""``ontodetect detect INPUT -o OUT``: the whole pipeline on one scan."""

from __future__ import annotations

import json
from pathlib import Path

import typer
from rich.table import Table
from rich.text import Text

from ..cloud import as_position
from ..io import read_cloud
from . import app
from ._common import load_config, load_ontology_option, number_list, room_option
from ._console import console, reporting, state


@app.command()
def detect(
    path: Path = typer.Argument(..., help="Point cloud file or scan folder."),
    out: Path = typer.Option(..., "--out", "-o", help="Output folder."),
    format: str | None = typer.Option(None, "--format", "-f", help="Force the input format."),
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
        help="Room category for the prior, e.g. office, living_room, conference (Places205).",
    ),
    room_probs: Path | None = typer.Option(
        None, "--room-probs", help="YAML/JSON mapping room category -> probability."
    ),
    indoor: float | None = typer.Option(None, "--indoor", help="P(indoor), Eq. 3.5."),
    up: str | None = typer.Option(None, "--up", help="Up axis: z (default), auto, y, -y, ..."),
    scale: float | None = typer.Option(None, "--scale", help="Scale factor k_s to metres."),
    viewpoint: str | None = typer.Option(
        None,
        "--viewpoint",
        metavar="X,Y,Z",
        help="Where the sensor stood, in the input's frame and units, when INPUT is one "
        "camera frame: a part the object itself hides (a seat behind its backrest) counts as "
        "occluded. Organized PCD frames give it by their VIEWPOINT.",
    ),
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
        help="Passes over the scan, a majority keeps a detection "
        "(detect.votes, default 3; 1: one pass, about half the time).",
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of every random step."),
    explain_: bool = typer.Option(
        False, "--explain", help="Print every constraint's probability and the label costs."
    ),
    picture: bool = typer.Option(True, "--picture/--no-picture", help="Write detections.png."),
    cad: bool = typer.Option(
        False,
        "--cad",
        help="Fit generic CAD models; write the object map "
        "(object_map.ply, object_map.glb) and add 'cad' to detections.json.",
    ),
) -> None:
    """Detect objects; write detections.json, labelled.ply and detections.png."""
    from ..outputs import write_outputs  # lazy: CLI start-up
    from ..pipeline import detect as run_detect  # lazy: CLI start-up

    cfg = load_config(
        config,
        set_,
        up=up,
        scale=scale,
        threshold=threshold,
        beta=beta,
        context=context,
        votes=votes,
    )
    onto = load_ontology_option(ontology, ontology_only)
    room_arg = room_option(room, room_probs)
    eye = number_list(viewpoint, float, "--viewpoint")
    if eye is not None:
        eye = as_position(eye, "--viewpoint")
    with reporting():
        cloud = read_cloud(path, format=format)
        result = run_detect(
            cloud,
            config=cfg,
            ontology=onto,
            room=room_arg,
            indoor=indoor,
            seed=seed,
            viewpoint=eye,
        )
        object_map = None
        if cad:
            from ..cad import fit_detections, write_object_map  # lazy: CLI start-up
            from ..pipeline import with_cad  # lazy: CLI start-up

            fits = fit_detections(result, seed=seed, ontology=onto)
            result = with_cad(result, fits)

            def also(folder: Path) -> object:
                return write_object_map(fits, folder, seed=seed)
        else:
            also = None
        files = write_outputs(result, out, picture=picture, also=also)
        object_map = also
    if explain_:
        _print_explain(result)
    if state.quiet:
        return
    table = Table(
        title=f"{path.name}: {len(result.detections)} objects ({len(result.segmentation)} clusters)"
    )
    for col in ("id", "label", "score", "points", "center", "size"):
        table.add_column(col, justify="right" if col in ("id", "score", "points") else "left")
    for d in result.detections:
        table.add_row(
            str(d.id),
            d.label,
            f"{d.score:.3f}",
            f"{len(d.point_indices):,}",
            " ".join(f"{v:.2f}" for v in d.center),
            " ".join(f"{v:.2f}" for v in d.size),
        )
    console.print(table)
    console.print(
        f"wrote {files.detections}, {files.labelled}"
        + (f", {files.picture}" if files.picture else "")
        + (", object_map.ply, object_map.glb" if object_map is not None else "")
    )
    if state.verbose:
        console.print(json.dumps(result.to_dict()["timings"]), soft_wrap=True)


def _print_explain(result) -> None:
    from ..outputs import explain  # lazy: CLI start-up

    for row in explain(result):
        head = (
            f"cluster {row['cluster']}: {row['num_points']} points, {row['planes']} planes"
            f" -> {row['label'] or 'no label'}" + (f" ({row['reason']})" if row["reason"] else "")
        )
        console.print(Text(head, style="bold"))
        probs = Table(show_header=True, box=None, pad_edge=False)
        probs.add_column("class")
        probs.add_column("P_obj|ont", justify="right")
        probs.add_column("cost U", justify="right")
        for c in row["classes"]:
            cost = row["costs"].get(c["class"])
            probs.add_row(
                c["class"], f"{c['probability']:.3g}", "" if cost is None else f"{cost:.3f}"
            )
        console.print(probs)
        best = next((c for c in row["classes"] if c["class"] != "none"), None)
        if best is None:
            continue
        cons = Table(title=f"constraints of {best['class']}", box=None, pad_edge=False)
        for col in ("part", "feature", "factor group", "value", "rule", "probability"):
            cons.add_column(col)
        for v in best["constraints"]:
            value = (
                f"{v['value']:.3g}"
                if v["value"] is not None
                else ("missing" if v["feature"] == "missing" else "not measured")
            )
            cons.add_row(
                v["part"], v["feature"], v["group"], value, v["rule"], f"{v['factor']:.3g}"
            )
        console.print(cons)
