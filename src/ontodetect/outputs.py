"""Writing a detection result: detections.json, a labelled PLY and a picture.

The files of one run are written into a staging folder beside the output folder and
swapped in together at the end (:func:`ontodetect.io.staged_folder`): an interrupted or
failed run (a full disk) leaves the previous result as it was, never a mix. The seconds
each stage took go to ``timings.json``, so that detections.json is byte-identical for the
same input and seed.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .io import atomic_write_text, staged_folder, write_cloud
from .io._detections import write_detections
from .pipeline import Result
from .render import BoxDrawing, render_scene

__all__ = ["OutputFiles", "explain", "write_outputs"]


@dataclass(frozen=True)
class OutputFiles:
    """Paths of what :func:`write_outputs` wrote."""

    detections: Path
    labelled: Path
    picture: Path | None


def write_outputs(
    result: Result,
    out_dir: str | os.PathLike[str],
    *,
    picture: bool = True,
    title: str | None = None,
    also: Callable[[Path], object] | None = None,
) -> OutputFiles:
    """Write ``detections.json``, ``timings.json``, ``labelled.ply`` and ``detections.png``
    into ``out_dir``, all or nothing.

    ``labelled.ply`` holds the input points (as read, minus any dropped as NaN)
    with two fields: ``label`` (index into ``result.class_names``, -1 for none)
    and ``instance`` (detection id, 0 for none). ``also(folder)``, when given, writes
    more files of the same run (the CAD object map) into the staging folder, so that
    they are swapped in with the rest.
    """
    final = Path(out_dir)
    with staged_folder(final, "output folder") as stage:
        files = _write_files(result, stage, picture=picture, title=title)
        if also is not None:
            also(stage)
    return OutputFiles(
        final / files.detections.name,
        final / files.labelled.name,
        None if files.picture is None else final / files.picture.name,
    )


def _write_files(result: Result, out: Path, *, picture: bool, title: str | None) -> OutputFiles:
    doc = result.to_dict()
    doc["classes"] = result.class_names
    # Seconds differ between two runs; the contract file does not.
    timings = doc.pop("timings", {})
    det_path = write_detections(out / "detections.json", doc)
    atomic_write_text(out / "timings.json", json.dumps(timings, indent=2) + "\n")
    label, instance = result.point_labels()
    cloud = result.cloud
    labelled = cloud.replace(
        fields={**dict(cloud.fields), "label": label, "instance": instance}, normals=None
    )
    ply_path = write_cloud(out / "labelled.ply", labelled)
    png = None
    if picture:
        names = result.class_names
        point_class = np.array([None, *names], dtype=object)[label + 1]
        counts: dict[str, int] = {}
        for d in result.detections:
            counts[d.label] = counts.get(d.label, 0) + 1
        # Pictures are drawn in the levelled frame (z up, floor at 0), whatever the input's.
        levelled = result.segmentation.prepared.cloud
        boxes = []
        for d in result.detections:
            box = result.segmentation[d.cluster].box
            boxes.append(BoxDrawing(box.center, box.size, box.yaw, d.label, f"{d.score:.2f}"))
        src = Path(str(cloud.meta.get("source", ""))).name or "scan"
        png = render_scene(
            out / "detections.png",
            levelled.xyz,
            rgb=cloud.rgb,
            point_class=point_class,
            boxes=boxes,
            legend_counts=counts,
            title=title or f"{src}: {len(result.detections)} objects",
        )
    return OutputFiles(det_path, ply_path, png)


def explain(result: Result, *, top: int = 3) -> list[dict[str, Any]]:
    """Per cluster: class probabilities, the constraints of the best classes and label costs.

    This is what ``detect --explain`` prints (the thesis's Tables 4.2 and 4.9).
    """
    rows = []
    for k, (c, s, choice) in enumerate(zip(result.segmentation, result.scores, result.choices)):
        ranked = sorted(s.probabilities.items(), key=lambda kv: -kv[1])
        classes = []
        for name, p in ranked[:top]:
            if name == "none":
                classes.append({"class": "none", "probability": p})
                continue
            cs = s.classes[name]
            classes.append(
                {
                    "class": name,
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
                "reason": choice.reason,
                "costs": dict(choice.costs),
                "classes": classes,
            }
        )
    return rows
