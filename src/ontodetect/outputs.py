"""Writing a detection result: detections.json, a labelled cloud (PLY or LAZ) and a picture.

The files of one run are written into a staging folder beside the output folder and
swapped in together at the end (:func:`ontodetect.io.staged_folder`): an interrupted or
failed run (a full disk) leaves the previous result as it was, never a mix. The seconds
each stage took go to ``timings.json``, so that detections.json is byte-identical for the
same input and seed.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .cloud import PointCloud
from .errors import InvalidParameterError
from .io import (
    EXPORTERS,
    MIN_SCAN_POINTS,
    export_detections,
    read_points,
    staged_folder,
    write_cloud,
    write_mesh,
    write_timings,
)
from .io._detections import write_detections
from .pipeline import Result, detect
from .preprocess import SurfaceMesh, scene_surface, turn_about_z, turn_quarters
from .render import BoxDrawing, class_color, render_scene

__all__ = [
    "LABELLED_FORMATS",
    "LAS_CLASS_BASE",
    "LAS_UNCLASSIFIED",
    "OutputFiles",
    "check_explain_options",
    "check_output_options",
    "detect_file",
    "explain",
    "labelled_cloud",
    "labelled_comments",
    "surface_mesh",
    "write_outputs",
]

#: File name of the labelled cloud for each ``labelled_format`` of :func:`write_outputs`.
LABELLED_FORMATS = {"ply": "labelled.ply", "laz": "labelled.laz", "las": "labelled.las"}
#: LAS classification code of our first class; ASPRS reserves 0-63 (LAS 1.4, Table 17) and
#: leaves 64-255 to users, so class ``i`` of ``Result.class_names`` is code ``64 + i``.
LAS_CLASS_BASE = 64
#: LAS classification code of points no detection covers (ASPRS 1, "unclassified").
LAS_UNCLASSIFIED = 1
#: Grey of the points no detection covers when the input has no colours.
UNLABELLED_GREY = 128
#: Share of their own colour the points no detection covers keep (the rest is grey), so
#: that objects stand out in any viewer while the room stays recognisable.
UNLABELLED_FADE = 0.5
#: The names of our per-point fields (CloudCompare loads ``scalar_*`` PLY properties).
SCALAR_FIELDS = ("scalar_label", "scalar_instance", "scalar_score")
#: File name of the surface mesh (``write_outputs(mesh=True)``, ``detect --mesh``).
MESH_FILE = "mesh.ply"
#: Points coloured at a time for the labelled cloud.
COLOR_BLOCK = 1 << 20


@dataclass(frozen=True)
class OutputFiles:
    """Paths of what :func:`write_outputs` wrote."""

    detections: Path
    labelled: Path
    picture: Path | None
    exports: tuple[Path, ...] = ()
    mesh: Path | None = None


def _free_name(name: str, taken: set[str]) -> str:
    """``name``, or ``name_1``, ``name_2``... when the input already has a field so named."""
    out, k = name, 0
    while out in taken:
        k += 1
        out = f"{name}_{k}"
    return out


def labelled_cloud(result: Result, *, format: str = "ply") -> PointCloud:
    """The input points coloured by class, with the detector's per-point fields added.

    Parameters
    ----------
    result : Result
        A detection result.
    format : {"ply", "laz", "las"}
        The file the cloud is meant for. For PLY the fields are ``scalar_label`` (index
        into ``result.class_names``, -1 for none), ``scalar_instance`` (detection id, 0 for
        none) and ``scalar_score`` (the detection's score, 0 for none). For LAS/LAZ the
        class also goes into ``classification``: ``LAS_CLASS_BASE + index``, or
        ``LAS_UNCLASSIFIED`` for none; an input ``classification`` is kept as
        ``input_classification``.

    Returns
    -------
    PointCloud
        Same points and rows as ``result.cloud``; colours by class (the rest in its own
        colours, faded to grey); the input's colours kept as ``input_red``,
        ``input_green``, ``input_blue``; every input field kept under its own name (our
        fields take a ``_1`` suffix when the input already has one so named).
    """
    if format not in LABELLED_FORMATS:
        raise InvalidParameterError("format", f"one of {sorted(LABELLED_FORMATS)}", format)
    cloud = result.cloud
    label, instance = result.point_labels()
    names = result.class_names
    score = np.zeros(len(cloud), dtype=np.float32)
    for d in result.detections:
        score[instance == d.id] = d.score
    fields = dict(cloud.fields)
    if format != "ply" and "classification" in fields:
        fields[_free_name("input_classification", set(fields))] = fields.pop("classification")
    if cloud.rgb is not None:
        for i, c in enumerate(("red", "green", "blue")):
            fields[_free_name(f"input_{c}", set(fields))] = cloud.rgb[:, i]
    palette = np.array([[round(255 * v) for v in class_color(n)] for n in names], np.float64)
    rgb = np.empty((len(cloud), 3), dtype=np.uint8)
    # Block by block: the float64 temporaries of a block, not of the whole cloud (about
    # 1 GB at 10 million points).
    for start in range(0, len(cloud), COLOR_BLOCK):
        rows = slice(start, start + COLOR_BLOCK)
        own = None if cloud.rgb is None else cloud.rgb[rows]
        rgb[rows] = _class_colors(label[rows], own, palette)
    ours = [label, instance, score]
    for name, values in zip(SCALAR_FIELDS, ours):
        fields[_free_name(name, set(fields))] = values
    if format != "ply":
        fields["classification"] = np.where(
            label >= 0, LAS_CLASS_BASE + label, LAS_UNCLASSIFIED
        ).astype(np.uint8)
    return cloud.replace(rgb=rgb, fields=fields, normals=None)


def _class_colors(
    label: NDArray[np.int64], rgb: NDArray[np.uint8] | None, palette: NDArray[np.float64]
) -> NDArray[np.uint8]:
    """(k, 3) colours of labelled.ply for points of class ``label`` (-1: none, their own
    ``rgb`` faded towards grey, or grey)."""
    if rgb is not None:
        grey = rgb.astype(np.float64).mean(axis=1, keepdims=True)
        base = UNLABELLED_FADE * rgb + (1 - UNLABELLED_FADE) * grey
    else:
        base = np.full((len(label), 3), UNLABELLED_GREY, dtype=np.float64)
    out = np.where((label >= 0)[:, None], palette[np.maximum(label, 0)], base)
    return np.clip(np.round(out), 0, 255).astype(np.uint8)


def labelled_comments(result: Result, cloud: PointCloud) -> list[str]:
    """Header comments of labelled.ply: which field is which, and the id -> class map."""
    taken = [n for n in cloud.fields if n.startswith(SCALAR_FIELDS)]
    lines = [f"ontodetect fields {' '.join(taken)}", "ontodetect label -1 none"]
    lines += [f"ontodetect label {i} {name}" for i, name in enumerate(result.class_names)]
    return lines


def surface_mesh(result: Result, *, method: str = "marching_cubes") -> SurfaceMesh:
    """A triangle mesh of the whole scan, in the input file's frame and units.

    The voxel cloud of the result's prepared scene meshed by
    :func:`ontodetect.preprocess.scene_surface` (marching cubes at the scene's sampling
    spacing, vertex colours when the scan has colours), then moved back from the levelled
    frame as boxes and parts are.
    """
    prepared = result.segmentation.prepared
    levelled = scene_surface(prepared, method=method)
    vertices = (
        prepared.from_level(levelled.vertices) if len(levelled.vertices) else levelled.vertices
    )
    mirrored = np.linalg.det(np.asarray(prepared.to_level)[:3, :3]) < 0
    triangles = levelled.triangles[:, ::-1].copy() if mirrored else levelled.triangles
    return SurfaceMesh(vertices, triangles, levelled.colors, levelled.cell, dict(levelled.info))


def check_output_options(labelled_format: str, exports: tuple[str, ...]) -> None:
    """Refuse an unknown labelled format or exporter before any work is done."""
    if labelled_format not in LABELLED_FORMATS:
        raise InvalidParameterError(
            "labelled_format", f"one of {sorted(LABELLED_FORMATS)}", labelled_format
        )
    unknown = [n for n in exports if n not in EXPORTERS]
    if unknown:
        raise InvalidParameterError("exports", f"among {sorted(EXPORTERS)}", unknown[0])


def write_outputs(
    result: Result,
    out_dir: str | os.PathLike[str],
    *,
    picture: bool = True,
    title: str | None = None,
    labelled_format: str = "ply",
    exports: tuple[str, ...] = ("boxes",),
    also: Callable[[Path], object] | None = None,
    mesh: bool = False,
) -> OutputFiles:
    """Write ``detections.json``, ``timings.json``, the labelled cloud, the exports and
    ``detections.png`` into ``out_dir``, all or nothing.

    The labelled cloud (``labelled.ply``, or ``labelled.laz`` / ``labelled.las`` with
    ``labelled_format``) holds the input points (as read, minus any dropped as NaN)
    coloured by class, with the fields of :func:`labelled_cloud`; the PLY header names
    every class id (``comment ontodetect label 0 chair``). ``exports`` names the
    :data:`ontodetect.io.EXPORTERS` to run beside detections.json (``boxes``: boxes.txt;
    ``scannet``: the ScanNet benchmark's instance files). ``also(folder)``, when given,
    writes more files of the same run (the CAD object map) into the staging folder, so
    that they are swapped in with the rest. ``mesh`` adds ``mesh.ply``, a triangle mesh of
    the scan (:func:`surface_mesh`). docs/outputs.md lists every file.
    """
    check_output_options(labelled_format, exports)
    final = Path(out_dir)
    with staged_folder(final, "output folder") as stage:
        files = _write_files(
            result,
            stage,
            picture=picture,
            title=title,
            labelled_format=labelled_format,
            exports=exports,
        )
        mesh_path = None
        if mesh:
            surface = surface_mesh(result)
            mesh_path = write_mesh(
                stage / MESH_FILE,
                surface.vertices,
                surface.triangles,
                surface.colors,
                comments=[
                    f"ontodetect mesh {surface.info.get('method', '')} cell {surface.cell:.6g}"
                ],
            )
        if also is not None:
            also(stage)
    return OutputFiles(
        final / files.detections.name,
        final / files.labelled.name,
        None if files.picture is None else final / files.picture.name,
        tuple(final / p.relative_to(stage) for p in files.exports),
        None if mesh_path is None else final / mesh_path.name,
    )


def _picture_frame(result: Result) -> tuple[np.ndarray, list[BoxDrawing]]:
    """The points and the detections' boxes as the picture draws them: in the levelled frame
    (z up, floor at 0), whatever the input's, turned back by the quarter turns the scan was
    prepared in (``prepare.quarter_turns``) and the walls' turn (``prepare.walls_to_axes``),
    so that the top view keeps the file's heading."""
    prepared = result.segmentation.prepared
    quarters = -int(prepared.info.get("quarter_turns", 0))
    walls = float(prepared.info.get("walls_yaw", 0.0))  # prepare.walls_to_axes

    def back(xyz: np.ndarray) -> np.ndarray:
        turned = turn_quarters(xyz, quarters)
        return turn_about_z(turned, walls) if walls else turned

    boxes = []
    for d in result.detections:
        box = result.segmentation[d.cluster].box
        center = back(np.asarray(box.center, dtype=np.float64))
        yaw = float(box.yaw) + quarters * math.pi / 2 + walls
        boxes.append(BoxDrawing(center, box.size, yaw, d.label, f"{d.score:.2f}"))
    return back(prepared.cloud.xyz), boxes


def _write_files(
    result: Result,
    out: Path,
    *,
    picture: bool,
    title: str | None,
    labelled_format: str,
    exports: tuple[str, ...],
) -> OutputFiles:
    doc = result.to_dict()
    doc["classes"] = result.class_names
    # Seconds differ between two runs; the contract file does not.
    timings = doc.pop("timings", {})
    det_path = write_detections(out / "detections.json", doc)
    write_timings(out / "timings.json", timings)
    exported = export_detections(out, doc, tuple(exports))
    label, _ = result.point_labels()
    cloud = result.cloud
    labelled = labelled_cloud(result, format=labelled_format)
    options = {"comments": labelled_comments(result, labelled)} if labelled_format == "ply" else {}
    ply_path = write_cloud(out / LABELLED_FORMATS[labelled_format], labelled, **options)
    del labelled  # written: its copy of every point need not live on while the picture is drawn
    png = None
    if picture:
        names = result.class_names
        point_class = np.array([None, *names], dtype=object)[label + 1]
        counts: dict[str, int] = {}
        for d in result.detections:
            counts[d.label] = counts.get(d.label, 0) + 1
        xyz, boxes = _picture_frame(result)
        src = Path(str(cloud.meta.get("source", ""))).name or "scan"
        png = render_scene(
            out / "detections.png",
            xyz,
            rgb=cloud.rgb,
            point_class=point_class,
            boxes=boxes,
            legend_counts=counts,
            title=title or f"{src}: {len(result.detections)} objects",
        )
    return OutputFiles(det_path, ply_path, png, tuple(exported))


def detect_file(
    path: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    format: str | None = None,
    detect_options: dict[str, Any] | None = None,
    **write_options: Any,
) -> OutputFiles:
    """Read one scan, detect, and write its files: one unit of a batch run.

    ``detect_options`` are keyword arguments of :func:`ontodetect.pipeline.detect`
    (``config``, ``ontology``, ``room``, ``seed``...); ``write_options`` those of
    :func:`write_outputs`. Picklable arguments in, paths out: any map over scans
    (``ontodetect.evaluation.map_scenes``, ``detect --jobs``) can run it. A scan with
    fewer than :data:`~ontodetect.io.MIN_SCAN_POINTS` points is refused
    (:class:`~ontodetect.errors.ReadError`).
    """
    cloud = read_points(path, format=format, min_points=MIN_SCAN_POINTS)
    result = detect(cloud, **(detect_options or {}))
    return write_outputs(result, out_dir, **write_options)


def check_explain_options(
    ontology: Any,
    classes: Sequence[str] | None,
    min_points: int,
    names: tuple[str, str] = ("classes", "min_points"),
) -> None:
    """Refuse what :func:`explain` would refuse, before any work is done: raise
    :class:`InvalidParameterError`, naming the parameter by ``names``, when one of
    ``classes`` is neither a class nor a label of ``ontology`` (a misspelt class would
    explain nothing) or ``min_points`` is not an integer >= 0.

    Examples
    --------
    >>> from ontodetect.ontology import builtin_ontology
    >>> check_explain_options(builtin_ontology(), ["chair", "toilet"], 0)
    >>> check_explain_options(builtin_ontology(), ["chiar"], 0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ontodetect.errors.InvalidParameterError: The 'classes' parameter must be class names ...
    """
    if isinstance(min_points, bool) or not isinstance(min_points, int) or min_points < 0:
        raise InvalidParameterError(names[1], "an integer >= 0", min_points)
    if classes is None:
        return
    known = {c.name for c in ontology.classes} | {c.label for c in ontology.classes}
    unknown = sorted(set(classes) - known)
    if unknown:
        raise InvalidParameterError(
            names[0],
            f"class names of the ontology ({', '.join(ontology.names)})",
            ",".join(unknown),
        )


def explain(
    result: Result,
    *,
    top: int = 3,
    classes: Sequence[str] | None = None,
    min_points: int = 0,
) -> list[dict[str, Any]]:
    """Per cluster: class probabilities, the constraints of the best classes and label costs.

    This is what ``detect --explain`` prints (the thesis's Tables 4.2 and 4.9). With the
    vote, a cluster some pass found an object in also has ``passes``: per pass, its turn
    and the label, best class and probability of its cluster sharing most of these
    points, with their point IoU (the vote counts a pass at IoU 0.5 or more). With
    segmentation by recognition, a chosen candidate has ``beat``: the candidates it beat.

    Parameters
    ----------
    top : int
        Classes shown per cluster, most probable first; the class the labelling chose
        (``class``) is shown as well when it is not among them.
    classes : sequence of str, optional
        Keep only the clusters labelled with one of these, or whose most probable class
        (other than none) is one of these; each of these classes is shown on them too,
        however unlikely, marked ``named`` (why a WC read as a chair is not a toilet:
        ``classes=["chair", "toilet"]``).
    min_points : int
        Keep only the clusters with at least this many points (most clusters of a real
        scan are a few points of noise).
    """
    check_explain_options(result.ontology, classes, min_points)
    wanted = None if classes is None else set(classes)
    wanted_order = [] if classes is None else list(dict.fromkeys(classes))
    rows = []
    cands = result.candidates
    origin = {c.cluster: i for i, c in enumerate(cands) if c.cluster is not None}
    for k, (c, s, choice) in enumerate(zip(result.segmentation, result.scores, result.choices)):
        if c.num_points < min_points:
            continue
        ranked = sorted(s.probabilities.items(), key=lambda kv: -kv[1])
        if wanted is not None:
            best = next((name for name, _ in ranked if name != "none"), None)
            if choice.label not in wanted and best not in wanted:
                continue
        # The class the labelling chose may not be among the most probable (the energy
        # weighs its discriminative term too; a variant takes its label's probability).
        chosen = choice.extra.get("class")
        shown = ranked[:top]
        for name in [chosen, *wanted_order]:
            if name is not None and name in s.classes and all(n != name for n, _ in shown):
                shown = [*shown, (name, s.probabilities[name])]
        classes = []
        for name, p in shown:
            if name == "none":
                classes.append({"class": "none", "probability": p})
                continue
            cs = s.classes[name]
            classes.append(
                {
                    "class": name,
                    "named": wanted is not None and name in wanted,
                    "probability": p,
                    "likelihood": cs.likelihood,
                    "prior": float(np.exp(cs.log_prior)),
                    "assignment": dict(cs.assignment),
                    "factors": {part: dict(f) for part, f in cs.factors.items()},
                    "constraints": [
                        {
                            "part": v.part,
                            "feature": v.feature,
                            "group": v.group,
                            "value": v.value,
                            "rule": v.gaussian.describe() if v.gaussian else "",
                            "factor": v.factor,
                        }
                        for v in cs.constraints
                    ],
                }
            )
        rows.append(
            {
                "cluster": k,
                "num_points": c.num_points,
                "box": c.box.to_dict(),
                "planes": len(c.planes),
                "flags": dict(c.flags),
                "label": choice.label,
                "class": chosen,
                "reason": choice.reason,
                "explained_away": list(choice.extra.get("explained_away", [])),
                "explained_by": choice.extra.get("explained_by"),
                "costs": dict(choice.costs),
                "classes": classes,
            }
        )
        if k in result.ballots:  # the vote: what every pass made of these points
            rows[-1]["passes"] = [b.to_dict() for b in result.ballots[k]]
        if k in origin:  # segmentation by recognition: the candidates this one beat
            rows[-1]["beat"] = [
                {
                    "source": o.source,
                    "label": o.label,
                    "weight": o.gain,
                    "num_voxels": o.num_voxels,
                    "cut": o.cut,
                }
                for o in cands
                if o.beaten_by == origin[k]
            ]
    return rows
