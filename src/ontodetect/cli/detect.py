"""``ontodetect detect INPUT -o OUT``: the whole pipeline on one scan."""

from __future__ import annotations

import functools
import json
from pathlib import Path

import typer
from rich.table import Table
from rich.text import Text

from ..cloud import as_position
from ..errors import OntoDetectError
from ..geometry import jsonable
from ..io import MIN_SCAN_POINTS, check_output_folder, expand_inputs, read_points
from . import app
from ._clouds import FORMAT_HELP, cloud_format
from ._common import (
    SCHEDULER_HELP,
    WORKERS_HELP,
    check_executor_options,
    check_up_option,
    executor_option,
    load_config,
    load_ontology_option,
    number_list,
    refuse_executor_options,
    room_option,
)
from ._console import console, err_console, reporting, showing_progress, state
from .env import scene_image_room


@app.command()
def detect(
    paths: list[Path] = typer.Argument(
        ...,
        metavar="INPUT...",
        help="Point cloud files, scan folders, folders of scans or quoted glob patterns "
        "('scans/*.ply'); with more than one scan, each gets OUT/<name>/.",
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Output folder."),
    jobs: int = typer.Option(
        1,
        "--jobs",
        "-j",
        help="Scans (or tiles, with --tile) in parallel on a local cluster (0: one per CPU).",
    ),
    tile: float | None = typer.Option(
        None,
        "--tile",
        metavar="METRES",
        help="Cut one large scan (a building floor) into tiles of this edge on the floor "
        "plane and detect tile by tile; writes detections.json and the exports "
        "(docs/cluster.md).",
    ),
    overlap: float | None = typer.Option(
        None,
        "--overlap",
        metavar="METRES",
        help="With --tile: how far each tile reads beyond its core (default 2.5, at least "
        "half the longest object the ontology allows plus 0.5).",
    ),
    workers: int | None = typer.Option(None, "--workers", metavar="N", help=WORKERS_HELP),
    scheduler: str | None = typer.Option(
        None, "--scheduler", metavar="tcp://HOST:PORT", help=SCHEDULER_HELP
    ),
    format: str | None = typer.Option(None, "--format", "-f", help=FORMAT_HELP),
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
        help="Room category for the prior, e.g. office, living_room, bathroom (Places205 and "
        "bathroom, bedroom); auto (default): estimated from the scan; none: no prior.",
    ),
    room_probs: Path | None = typer.Option(
        None, "--room-probs", help="YAML/JSON mapping room category -> probability."
    ),
    scene_image: Path | None = typer.Option(
        None,
        "--scene-image",
        metavar="IMAGE_OR_DIR",
        help="Photograph(s) of the scene: the room prior P_N from them (frames averaged); "
        "with --env-model.",
    ),
    env_model: Path | None = typer.Option(
        None, "--env-model", metavar="MODEL", help="Model file from 'ontodetect env train'."
    ),
    indoor: float | None = typer.Option(None, "--indoor", help="P(indoor), Eq. 3.5."),
    up: str | None = typer.Option(
        None,
        "--up",
        help="Up axis: z, -y, ..., auto (estimate it), or auto-frame (default: auto for "
        "an organized or single-view cloud, z otherwise).",
    ),
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
    proposals: str | None = typer.Option(
        None,
        "--proposals",
        help="Object proposals: vote (default) or recognition (experimental, off by default; "
        "detect.proposals).",
    ),
    classes: str | None = typer.Option(
        None,
        "--classes",
        help="Classes reported: 'all' adds the competing classes (toilet, sink, bed, "
        "nightstand...), or a comma-separated list (detect.classes; default: chair, sofa, table).",
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of every random step."),
    explain_: str | None = typer.Option(
        None,
        "--explain",
        metavar="[CLASSES]",
        help="Print every constraint's probability and the label costs, for every cluster "
        "or those of CLASSES (comma-separated: --explain chair,table); with --json, as "
        "'explain' in the document.",
    ),
    min_points: int = typer.Option(
        10,
        "--min-points",
        help="With --explain: leave out clusters with fewer points (one-point noise).",
    ),
    picture: bool = typer.Option(True, "--picture/--no-picture", help="Write detections.png."),
    as_json: bool = typer.Option(
        False,
        "--json",
        help="Print the detections.json document (with 'files': what was written) on stdout "
        "instead of the table.",
    ),
    labelled_format: str = typer.Option(
        "ply",
        "--labelled-format",
        help="Labelled cloud: ply (labelled.ply) or laz/las (labelled.laz, ASPRS "
        "classification codes from 64 up; docs/outputs.md).",
    ),
    export: str = typer.Option(
        "boxes",
        "--export",
        metavar="NAMES",
        help="Comma-separated exports beside detections.json: boxes (boxes.txt, "
        "OpenPCDet/mmdetection3d layout), scannet (ScanNet benchmark instance files); "
        "'' for none.",
    ),
    mesh: bool = typer.Option(
        False,
        "--mesh",
        help="Also write mesh.ply: a triangle mesh of the scan (marching cubes on the voxel "
        "cloud, vertex colours; docs/outputs.md).",
    ),
    cad: bool = typer.Option(
        False,
        "--cad",
        help="Fit generic CAD models; write the object map "
        "(object_map.ply, object_map.glb) and add 'cad' to detections.json.",
    ),
) -> None:
    """Detect objects; write detections.json, labelled.ply, boxes.txt and detections.png
    (and mesh.ply with --mesh)."""
    from ..outputs import (  # lazy: CLI start-up
        check_explain_options,
        check_output_options,
        explain,
        write_outputs,
    )
    from ..pipeline import detect as run_detect  # lazy: CLI start-up

    exports = tuple(n.strip() for n in export.split(",") if n.strip())
    explain_classes = None
    if explain_ is not None and explain_ != "all":
        explain_classes = [n.strip() for n in explain_.split(",") if n.strip()]
    check_output_options(labelled_format.lower(), exports)
    check_output_folder(out)  # before any work, not after the detection
    check_executor_options(scheduler, workers, jobs)
    check_up_option(up)
    fmt = cloud_format(format, "detect")
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
        classes=classes,
    )
    onto = load_ontology_option(ontology, ontology_only)
    # Before any work: a misspelt class would show nothing, after the whole detection.
    check_explain_options(onto, explain_classes, min_points, ("--explain", "--min-points"))
    room_arg = room_option(room, room_probs)
    scene_rooms = scene_image_room(scene_image, env_model, room, room_probs)
    eye = number_list(viewpoint, float, "--viewpoint")
    if eye is not None:
        eye = as_position(eye, "--viewpoint")
    inputs = expand_inputs(paths)
    options = {"config": cfg, "ontology": onto, "room": room_arg, "indoor": indoor, "seed": seed}
    if tile is not None:
        if len(inputs) > 1 or cad or mesh or explain_ is not None:
            raise typer.BadParameter(
                "takes one scan, without --cad, --mesh and --explain", param_hint="--tile"
            )
        _detect_tiled(
            inputs[0],
            out,
            tile=tile,
            overlap=overlap,
            executor=(scheduler, workers, jobs),
            as_json=as_json,
            format=fmt,
            exports=exports,
            detect_options=options,
        )
        return
    if overlap is not None:
        raise typer.BadParameter("needs --tile", param_hint="--overlap")
    if len(inputs) > 1 or inputs[0] not in paths:
        if cad or explain_ is not None:
            raise typer.BadParameter("--cad and --explain take one scan", param_hint="INPUT...")
        _detect_many(
            inputs,
            out,
            executor=(scheduler, workers, jobs),
            as_json=as_json,
            format=fmt,
            detect_options={**options, "viewpoint": eye, "scene_rooms": scene_rooms},
            picture=picture,
            labelled_format=labelled_format.lower(),
            exports=exports,
            mesh=mesh,
        )
        return
    refuse_executor_options(scheduler, workers, jobs)  # before reading the scan
    path = inputs[0]
    with reporting():
        cloud = read_points(path, fmt, min_points=MIN_SCAN_POINTS)
        result = run_detect(
            cloud,
            config=cfg,
            ontology=onto,
            room=room_arg,
            indoor=indoor,
            seed=seed,
            viewpoint=eye,
            scene_rooms=scene_rooms,
        )
        # The object map's files, written into the staging folder: their names, in OUT.
        object_map: list[Path] = []
        if cad:
            from ..cad import fit_detections, write_object_map  # lazy: CLI start-up
            from ..pipeline import with_cad  # lazy: CLI start-up

            fits = fit_detections(result, seed=seed, ontology=onto)
            result = with_cad(result, fits)

            def also(folder: Path) -> object:
                staged = write_object_map(fits, folder, seed=seed)
                written = (staged.points, staged.glb, staged.mesh)
                object_map.extend(out / Path(p).name for p in written if p is not None)
                return staged
        else:
            also = None
        files = write_outputs(
            result,
            out,
            picture=picture,
            labelled_format=labelled_format.lower(),
            exports=exports,
            also=also,
            mesh=mesh,
        )
    if as_json:
        doc = result.to_dict()
        doc.pop("timings", None)
        doc["classes"] = result.class_names
        doc["files"] = [
            str(p)
            for p in (files.detections, files.labelled, *files.exports, files.picture, files.mesh)
            if p is not None
        ] + [str(p) for p in object_map]
        if explain_ is not None:
            doc["explain"] = explain(result, classes=explain_classes, min_points=min_points)
        typer.echo(json.dumps(jsonable(doc)))
        return
    if explain_ is not None:
        _print_explain(explain(result, classes=explain_classes, min_points=min_points))
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
        + "".join(f", {p}" for p in files.exports)
        + (f", {files.picture}" if files.picture else "")
        + (f", {files.mesh}" if files.mesh else "")
        + "".join(f", {p}" for p in object_map)
    )
    if state.verbose:
        console.print(json.dumps(result.to_dict()["timings"]), soft_wrap=True)


def _scan_names(inputs: list[Path]) -> list[str]:
    """A folder name per scan: its stem, made unique with ``_2``, ``_3``..."""
    names: list[str] = []
    for p in inputs:
        stem = p.name[: -len("_vert.npy")] if p.name.endswith("_vert.npy") else p.stem
        name, k = stem or "scan", 1
        while name in names:
            k += 1
            name = f"{stem}_{k}"
        names.append(name)
    return names


def _detect_unit(
    unit: tuple[Path, Path], format, detect_options, write_options, stages=None
) -> dict:
    """One scan of a batch (module level: picklable for worker processes); its stages go
    to ``stages`` (a queue) when progress rows are shown."""
    from .._progress import use_reporter  # lazy: CLI start-up
    from ..outputs import detect_file  # lazy: CLI start-up
    from ._scans import StageSender  # lazy: only with progress rows

    path, folder = unit
    sender = None if stages is None else StageSender(stages, folder.name)
    if sender is not None:
        sender.begin()
    try:
        with use_reporter(sender):
            files = detect_file(
                path, folder, format=format, detect_options=detect_options, **write_options
            )
    except OntoDetectError as exc:
        return {"input": str(path), "out": str(folder), "error": str(exc)}
    finally:
        if sender is not None:
            sender.end()
    doc = json.loads(files.detections.read_text(encoding="utf-8"))
    return {
        "input": str(path),
        "out": str(folder),
        "objects": len(doc["detections"]),
        "labels": sorted({d["label"] for d in doc["detections"]}),
    }


def _detect_many(inputs, out, *, executor, as_json, format, detect_options, **write_options):
    from .._executor import InProcess  # lazy: CLI start-up
    from ..evaluation import map_scenes  # lazy: CLI start-up

    units = [(p, out / name) for p, name in zip(inputs, _scan_names(inputs))]
    with executor_option(*executor) as pool:
        if not isinstance(pool, InProcess):
            detect_options = {**detect_options, "jobs": 1}  # the scans use the CPUs
        fn = functools.partial(
            _detect_unit, format=format, detect_options=detect_options, write_options=write_options
        )
        names = [str(p) for p in inputs]
        if showing_progress():
            rows = _detect_with_rows(fn, units, pool, names)
        else:
            with reporting():
                rows = map_scenes(fn, units, description="Scans", executor=pool, names=names)
    failed = [r for r in rows if "error" in r]
    if as_json:
        typer.echo(json.dumps(rows))
    elif not state.quiet:
        table = Table(title=f"{len(rows)} scans -> {out}")
        for col in ("input", "objects", "output"):
            table.add_column(col, justify="right" if col == "objects" else "left")
        for r in rows:
            table.add_row(r["input"], str(r.get("objects", "failed")), r["out"])
        console.print(table)
    for r in failed:  # on stderr: stdout holds the table or the JSON rows
        err_console.print(Text.assemble(("failed", "red"), f" {r['input']}: {r['error']}"))
    if failed:
        raise typer.Exit(2)


def _detect_with_rows(fn, units, pool, names) -> list[dict]:
    """``map_scenes`` with a progress row per scan in flight (its stage) and an overall row;
    the scans send their stages through the executor's channel."""
    from .._progress import use_reporter  # lazy: CLI start-up
    from ..evaluation import map_scenes  # lazy: CLI start-up
    from ._scans import scan_rows  # lazy: only with progress rows

    channel = pool.channel()
    with scan_rows(channel) as shown, use_reporter(shown):
        return map_scenes(
            functools.partial(fn, stages=channel),
            units,
            description="Scans",
            executor=pool,
            names=names,
        )


def _detect_tiled(path, out, *, tile, overlap, executor, as_json, format, exports, detect_options):
    """``detect --tile``: one large scan tile by tile; detections.json and the exports."""
    from ..io import (  # lazy: CLI start-up
        export_detections,
        staged_folder,
        write_detections,
        write_timings,
    )
    from ..pipeline import detect_tiled  # lazy: CLI start-up

    with reporting(), executor_option(*executor) as pool:
        result = detect_tiled(
            path, tile=tile, overlap=overlap, executor=pool, format=format, **detect_options
        )
    doc = result.to_dict()
    contract, timings = _tiled_timings(doc)
    with staged_folder(out, "output folder") as stage:
        write_detections(stage / "detections.json", contract)
        write_timings(stage / "timings.json", timings)
        exported = export_detections(stage, contract, exports)
    written = [out / "detections.json", out / "timings.json"]
    written += [out / p.relative_to(stage) for p in exported]
    if as_json:
        doc["files"] = [str(p) for p in written]
        typer.echo(json.dumps(jsonable(doc)))
        return
    if state.quiet:
        return
    seconds = sum(result.timings.values())
    console.print(
        f"{path.name}: {len(result.detections)} objects in {len(result.tiles)} tiles "
        f"({result.merged} duplicates merged), {result.num_points:,} points in {seconds:.1f} s "
        f"on {result.workers} worker{'s' if result.workers != 1 else ''} "
        f"({result.num_points / max(seconds, 1e-9):,.0f} points/s), "
        f"peak memory of a worker {result.peak_rss / 2**20:,.0f} MiB"
    )
    by_label: dict[str, int] = {}
    for d in result.detections:
        by_label[d.label] = by_label.get(d.label, 0) + 1
    if by_label:
        console.print(", ".join(f"{n} {label}" for label, n in sorted(by_label.items())))
    console.print("wrote " + ", ".join(str(p) for p in written))


#: What a tile's row in detections.json says of the run rather than of the scan: it goes
#: to timings.json, so that the same input and seed write the same detections.json.
TILE_RUN_KEYS = ("seconds", "peak_rss", "worker")


def _tiled_timings(doc: dict) -> tuple[dict, dict]:
    """A tiled run's document split into the contract (detections.json) and what
    differs from run to run (timings.json: the stages' seconds, each tile's seconds,
    peak memory and worker)."""
    tiling = dict(doc["tiling"])
    tiling["tiles"] = [
        {k: v for k, v in t.items() if k not in TILE_RUN_KEYS} for t in doc["tiling"]["tiles"]
    ]
    contract = {k: v for k, v in doc.items() if k != "timings"} | {"tiling": tiling}
    timings = dict(doc.get("timings", {})) | {
        "tile_runs": [
            {"name": t["name"], **{k: t[k] for k in TILE_RUN_KEYS if k in t}}
            for t in doc["tiling"]["tiles"]
        ]
    }
    return contract, timings


def _ballot_line(b: dict) -> str:
    """One pass of the vote, as ``--explain`` prints it."""
    where = "first pass" if b["turn"] == 0 else f"pass turned {b['turn']:+g}°"
    if b["num_points"] == 0:  # no cluster of this pass shares a point with it
        return f"{where}: no cluster here"
    what = b["label"] or "no object"
    best = "" if b["class"] is None else f", best {b['class']} {b['probability']:.2f}"
    share = "" if b["turn"] == 0 else f", point IoU {b['iou']:.2f}"
    counts = "" if b["turn"] == 0 or b["label"] is None or b["counts"] else ", too little to count"
    return f"{where}: {what}{best} ({b['num_points']} points{share}{counts})"


def _print_explain(rows) -> None:
    for row in rows:
        head = (
            f"cluster {row['cluster']}: {row['num_points']} points, {row['planes']} planes"
            f" -> {row['label'] or 'no label'}" + (f" ({row['reason']})" if row["reason"] else "")
        )
        console.print(Text(head, style="bold"))
        if row.get("explained_away"):
            console.print(
                f"  explained away: {', '.join(row['explained_away'])}, by a likelier"
                f" {row['explained_by']} in a room whose prior favours it"
            )
        for b in row.get("passes", []):
            console.print("  " + _ballot_line(b))
        for o in row.get("beat", []):
            why = "no label" if o["label"] is None else f"{o['label']}, weight {o['weight']:.2f}"
            console.print(f"  beat a candidate of {o['source']} ({o['num_voxels']} voxels): {why}")
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
        best = next((c for c in row["classes"] if c["class"] == row.get("class")), None)
        best = best or next((c for c in row["classes"] if c["class"] != "none"), None)
        if best is None:
            continue
        # The best class's constraints, then those of every other class asked for by name.
        named = [c for c in row["classes"] if c.get("named") and c["class"] != best["class"]]
        for shown in (best, *named):
            console.print(_constraints_table(shown))


def _constraints_table(cls: dict) -> Table:
    """One class's constraints on a cluster, as ``--explain`` prints them."""
    cons = Table(title=f"constraints of {cls['class']}", box=None, pad_edge=False)
    for col in ("part", "feature", "factor group", "value", "rule", "probability"):
        cons.add_column(col)
    for v in cls["constraints"]:
        value = (
            f"{v['value']:.3g}"
            if v["value"] is not None
            else ("missing" if v["feature"] == "missing" else "not measured")
        )
        cons.add_row(v["part"], v["feature"], v["group"], value, v["rule"], f"{v['factor']:.3g}")
    return cons
