"""The built-in example: simulate a furnished office, detect its furniture, score the result.

:func:`run_demo` is what ``make demo`` and ``ontodetect demo`` run. It needs no
input: the simulator builds an office with desks, office chairs, cabinets and
clutter, walks a Kinect-like camera through it, and the detector then works on
that scan exactly as on a real one. Because the simulator knows the truth, the
demo ends with precision and recall.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .cad import ObjectMapFiles, fit_detections, write_object_map
from .errors import InvalidParameterError
from .evaluation import (
    Evaluation,
    Instance,
    SceneResult,
    evaluate_scenes,
    instances_from_labels,
)
from .ontology import room_distribution
from .outputs import OutputFiles, write_outputs
from .pipeline import Result, detect, with_cad
from .synth import synthesize, write_synth

__all__ = ["DEMO_ROOM", "DEMO_SEED", "DemoResult", "run_demo"]

DEMO_ROOM = "office"
DEMO_SEED = 3
#: Simulated ground-truth classes evaluated, by NYU40 id (desks count as tables).
_EVALUATED = {5: "chair", 6: "sofa", 7: "table", 14: "table"}


@dataclass(frozen=True)
class DemoResult:
    """What the demo produced."""

    scan_dir: Path
    files: OutputFiles
    result: Result
    evaluation: Evaluation
    object_map: Any = None


def run_demo(
    out_dir: str | os.PathLike[str],
    *,
    room: str = DEMO_ROOM,
    seed: int = DEMO_SEED,
    sensor: str = "rgbd",
) -> DemoResult:
    """Simulate a scan, detect objects in it and evaluate them against the simulator's truth.

    Writes ``OUT/scan/`` (the simulated scan in the project's dataset layout),
    ``OUT/detections.json`` (with fitted CAD poses), ``OUT/labelled.ply``,
    ``OUT/detections.png`` and the object map ``OUT/object_map.ply`` / ``.glb``.
    """
    out = Path(out_dir)
    synth = synthesize(room, sensor, seed)
    scan_dir = write_synth(synth, out / "scan")
    cloud = synth.cloud.with_meta(source=str(scan_dir / "cloud.ply"))
    # The simulator's room types double as environment categories where Places205 has them.
    try:
        prior_room: str | None = room if room_distribution(room) else None
    except InvalidParameterError:
        prior_room = None
    result = detect(cloud, room=prior_room, seed=seed)
    fits = fit_detections(result, seed=seed)
    result = with_cad(result, fits)
    staged: list[ObjectMapFiles] = []
    files = write_outputs(
        result,
        out,
        title=f"simulated {room} (seed {seed}): {len(result.detections)} objects",
        # The object map joins the run's other files: swapped in with them.
        also=lambda folder: staged.append(write_object_map(fits, folder, seed=seed)),
    )
    written = staged[0]
    object_map = ObjectMapFiles(
        points=out / written.points.name,
        glb=None if written.glb is None else out / written.glb.name,
        mesh=None if written.mesh is None else out / written.mesh.name,
    )
    gts = instances_from_labels(
        cloud.fields["instance"], cloud.fields["class_id"], _EVALUATED, index=cloud.index
    )
    preds = [Instance.make(d.id, d.label, d.point_indices, d.score) for d in result.detections]
    evaluation = evaluate_scenes([SceneResult(f"{room}-{seed}", preds, gts)])
    return DemoResult(scan_dir, files, result, evaluation, object_map)
