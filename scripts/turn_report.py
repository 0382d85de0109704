"""How much detection depends on how a scan happens to be turned and placed.

Usage::

    .venv/bin/python scripts/turn_report.py DATASET [--turns 0 90 180 270] [--seeds 0]
        [--shift 0] [--votes 3] [--jobs 2] [--json OUT.json]

Every scene of DATASET (any layout ``ontodetect eval`` reads) is detected once per turn
and seed (the seed of the MSAC plane fits):
its points rotated by that many degrees about the vertical axis (and moved by ``--shift``
metres along x and y), point order kept, so the ground truth stays the same. Reported:
precision and recall per class at point IoU >= 0.25 for every turn (over the seeds), and
pooled over all turns and seeds. A scan turned by 90 degrees is the same room; the spread
between turns is how much a figure from one pass over a small dataset can be trusted, and
the pooled figure is the steadier one.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import sys
import warnings
from pathlib import Path

import numpy as np

from ontodetect.cloud import DataWarning
from ontodetect.evaluation import (
    Instance,
    SceneResult,
    discover_scenes,
    evaluate_scenes,
    load_scene,
    map_scenes,
)
from ontodetect.pipeline import detect

CLASSES = ("chair", "sofa", "table")


def turned(xyz: np.ndarray, degrees: float, shift: float) -> np.ndarray:
    """``xyz`` rotated about z by ``degrees`` and moved by ``shift`` along x and y."""
    a = math.radians(degrees)
    rot = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0],
                    [0.0, 0.0, 1.0]])
    return xyz @ rot.T + [shift, shift, 0.0]


def run_one(unit: tuple, *, shift: float, votes: int) -> SceneResult:
    source, degrees, seed = unit
    warnings.simplefilter("ignore", DataWarning)
    scene = load_scene(source)  # ground truth by row: the same whichever way it is turned
    cloud = scene.cloud.replace(xyz=turned(scene.cloud.xyz, degrees, shift))
    result = detect(cloud, seed=seed, votes=votes, jobs=1)  # the scenes use the CPUs
    preds = [Instance.make(d.id, d.label, d.point_indices, d.score) for d in result.detections]
    return SceneResult(f"{source.name}@{degrees:g}s{seed}", preds, scene.gts, 0.0)


def _row(ev) -> dict:
    return {k: {"tp": m.tp, "detections": m.num_pred, "instances": m.num_gt,
                "precision": round(m.precision, 4), "recall": round(m.recall, 4)}
            for k, m in ev.per_class.items()}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--turns", type=float, nargs="+", default=[0.0, 90.0, 180.0, 270.0])
    ap.add_argument("--shift", type=float, default=0.0)
    ap.add_argument("--votes", type=int, default=3, help="passes per detection (detect.votes)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)

    sources = discover_scenes(args.dataset)
    units = [(s, t, seed) for seed in args.seeds for t in args.turns for s in sources]
    results = map_scenes(functools.partial(run_one, shift=args.shift, votes=args.votes), units,
                         jobs=args.jobs, description="Turned scenes")
    report: dict = {"dataset": str(args.dataset), "shift": args.shift, "seeds": args.seeds,
                    "votes": args.votes,
                    "turns": {}}
    print(f"{'turn':>8}  " + "  ".join(f"{c:>22}" for c in CLASSES))
    for t in args.turns:
        ev = evaluate_scenes([r for r in results if f"@{t:g}s" in r.name], CLASSES)
        report["turns"][f"{t:g}"] = _row(ev)
        print(f"{t:>7g}°  " + "  ".join(
            f"P {ev.per_class[c].precision:.2f} R {ev.per_class[c].recall:.2f} "
            f"({ev.per_class[c].tp}/{ev.per_class[c].num_pred}/{ev.per_class[c].num_gt})".rjust(22)
            for c in CLASSES))
    pooled = evaluate_scenes(results, CLASSES)
    report["pooled"] = _row(pooled)
    print(f"{'pooled':>8}  " + "  ".join(
        f"P {pooled.per_class[c].precision:.2f} R {pooled.per_class[c].recall:.2f} "
        f"({pooled.per_class[c].tp}/{pooled.per_class[c].num_pred}/"
        f"{pooled.per_class[c].num_gt})".rjust(22) for c in CLASSES))
    print("(TP/detections/instances at point IoU >= 0.25)")
    if args.json:
        args.json.write_text(json.dumps(report, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
