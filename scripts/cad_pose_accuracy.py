"""How accurately generic CAD models are posed on simulated scenes with ground-truth poses.

Usage::

    .venv/bin/python scripts/cad_pose_accuracy.py [--scenes 24] [--seed 100]
        [--rooms office,conference,dining_room,living_room,home_office,kitchen]
        [--sensor rgbd] [--points 200000] [--no-detector] [--no-scale] [--json OUT.json]

Scene ``i`` is room ``rooms[i % len(rooms)]`` simulated with seed ``seed + i``
(:func:`ontodetect.synth.synthesize`). Every chair, sofa, table and desk (desks
count as tables) with at least ``--min-points`` points is fitted twice:

- **ground-truth points**: the object's own points (per-point ``instance``) are
  the "detection", so the figures measure fitting alone, not detection;
- **through the detector**: :func:`ontodetect.pipeline.detect` runs on the scan,
  each detection is matched to the ground-truth instance of its class with the
  highest point IoU (at least 0.25), and :func:`ontodetect.cad.fit_detections`
  fits it with the detection's parts as hints.

Errors are against the pose in ``objects.json`` (object frame: origin at the
centre of the footprint on the floor, y to the front). The yaw error is taken
modulo the object's symmetry: none for seating, half a turn for rectangular
tables and desks, a quarter turn for square tables (sides within 5 %), and
round tables have no yaw error. Prints a Markdown table per mode; the targets
are a median yaw error of at most 5° and a median position error of at most
3 cm for chairs and tables.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from ontodetect.cad import builtin_library, fit_detections, fit_object
from ontodetect.synth import synthesize

CLASSES = {"chair": "chair", "sofa": "sofa", "table": "table", "desk": "table"}
ROOMS = "office,conference,dining_room,living_room,home_office,kitchen"
#: Sides within this share of each other make a square table (yaw modulo 90 degrees).
SQUARE = 0.05
#: Matching a detection to a ground-truth instance (docs/evaluation.md: point IoU >= 0.25).
MIN_IOU = 0.25
TARGET_YAW_DEG = 5.0
TARGET_POSITION_M = 0.03


def symmetry_period(obj) -> float | None:
    """Yaw period of a ground-truth object (None: any yaw)."""
    if CLASSES[obj.class_name] != "table":
        return 2 * math.pi
    if "round" in obj.kind:
        return None
    w, d = obj.dimensions["width"], obj.dimensions["depth"]
    return math.pi / 2 if abs(w - d) <= SQUARE * max(w, d) else math.pi


def errors(obj, x: float, y: float, yaw: float) -> tuple[float | None, float]:
    """(yaw error in degrees modulo symmetry or None, position error in metres)."""
    period = symmetry_period(obj)
    yaw_err = None
    if period is not None:
        d = (yaw - obj.yaw) % period
        yaw_err = math.degrees(min(d, period - d))
    return yaw_err, math.hypot(x - obj.pose[0, 3], y - obj.pose[1, 3])


def match(
    detection_rows: np.ndarray, instance: np.ndarray, candidates: dict[int, object], label: str
) -> int | None:
    """Ground-truth instance of the detection's class with the best point IoU (>= 0.25)."""
    best, best_iou = None, MIN_IOU
    ids, counts = np.unique(instance[detection_rows], return_counts=True)
    for i, inter in zip(ids.tolist(), counts.tolist()):
        obj = candidates.get(i)
        if obj is None or CLASSES[obj.class_name] != label:
            continue
        union = len(detection_rows) + int((instance == i).sum()) - inter
        iou = inter / union
        if iou >= best_iou:
            best, best_iou = i, iou
    return best


def summarize(rows: list[dict]) -> list[dict]:
    by = defaultdict(list)
    for r in rows:
        by[r["class"]].append(r)
    out = []
    for cls in ("chair", "table", "sofa"):
        rs = by.get(cls, [])
        if not rs:
            continue
        yaw = np.array([r["yaw_error"] for r in rs if r["yaw_error"] is not None])
        pos = np.array([r["position_error"] for r in rs])
        ms = np.array([r["ms"] for r in rs if r.get("ms") is not None])
        entry = {
            "class": cls,
            "objects": len(rs),
            "median_yaw_deg": float(np.median(yaw)) if len(yaw) else float("nan"),
            "p90_yaw_deg": float(np.percentile(yaw, 90)) if len(yaw) else float("nan"),
            "yaw_within_10deg": float(np.mean(yaw <= 10.0)) if len(yaw) else float("nan"),
            "median_position_cm": 100 * float(np.median(pos)),
            "p90_position_cm": 100 * float(np.percentile(pos, 90)),
            "median_ms": float(np.median(ms)) if len(ms) else float("nan"),
        }
        if cls in ("chair", "table"):
            entry["target_met"] = bool(
                entry["median_yaw_deg"] <= TARGET_YAW_DEG
                and entry["median_position_cm"] <= 100 * TARGET_POSITION_M
            )
        out.append(entry)
    return out


def table(title: str, summary: list[dict]) -> str:
    lines = [
        f"### {title}",
        "",
        "| class | objects | median yaw err (°) | p90 yaw (°) | yaw ≤ 10° "
        "| median pos err (cm) | p90 pos (cm) | median ms/object | target |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for s in summary:
        target = {True: "met", False: "MISSED"}.get(s.get("target_met"), "-")
        lines.append(
            f"| {s['class']} | {s['objects']} | {s['median_yaw_deg']:.2f} | {s['p90_yaw_deg']:.1f}"
            f" | {100 * s['yaw_within_10deg']:.0f} % | {s['median_position_cm']:.2f}"
            f" | {s['p90_position_cm']:.1f} | {s['median_ms']:.1f} | {target} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=24)
    ap.add_argument("--seed", type=int, default=100)
    ap.add_argument("--rooms", default=ROOMS)
    ap.add_argument("--sensor", default="rgbd")
    ap.add_argument("--points", type=int, default=200_000)
    ap.add_argument("--min-points", type=int, default=200)
    ap.add_argument("--no-detector", action="store_true", help="Skip the detector run.")
    ap.add_argument("--no-scale", action="store_true", help="Do not scale models to objects.")
    ap.add_argument("--json", type=Path, help="Also write every object's errors here.")
    args = ap.parse_args(argv)
    rooms = args.rooms.split(",")
    lib = builtin_library()
    t0 = time.perf_counter()
    for m in lib.values():  # the one-off cost of sampling every model and building its trees
        for spacing in (0.005, 0.02, 0.04):
            m.tree(spacing)
    library_s = time.perf_counter() - t0
    gt_rows: list[dict] = []
    det_rows: list[dict] = []
    missed = defaultdict(int)
    for i in range(args.scenes):
        room, seed = rooms[i % len(rooms)], args.seed + i
        r = synthesize(room, args.sensor, seed=seed, points=args.points)
        cloud = r.cloud
        instance = np.asarray(cloud.fields["instance"])
        objects = {o.instance_id: o for o in r.scene.objects if o.class_name in CLASSES}
        for obj in objects.values():
            sel = instance == obj.instance_id
            if sel.sum() < args.min_points:
                continue
            label = CLASSES[obj.class_name]
            t = time.perf_counter()
            fit = fit_object(
                cloud.xyz[sel],
                label,
                lib,
                colors=cloud.rgb[sel],
                seed=0,
                scale_to_object=not args.no_scale,
            )
            ms = 1000 * (time.perf_counter() - t)
            yaw_err, pos_err = errors(obj, fit.x, fit.y, fit.yaw)
            gt_rows.append(
                {
                    "room": room,
                    "seed": seed,
                    "instance": obj.instance_id,
                    "kind": obj.kind,
                    "class": label,
                    "points": int(sel.sum()),
                    "model": fit.model,
                    "yaw_error": yaw_err,
                    "position_error": pos_err,
                    "rms": fit.rms,
                    "inlier_fraction": fit.inlier_fraction,
                    "ms": ms,
                }
            )
        if args.no_detector:
            continue
        from ontodetect.pipeline import detect

        result = detect(cloud, seed=0)
        t = time.perf_counter()
        fits = fit_detections(result, lib, min_score=0.0, seed=0, scale_to_object=not args.no_scale)
        ms = 1000 * (time.perf_counter() - t) / max(len(fits), 1)
        matched = set()
        for d, fit in zip(result.detections, fits):
            rows = np.asarray(d.point_indices)
            gid = match(rows, instance, objects, d.label)
            if gid is None or fit.blank:
                continue
            matched.add(gid)
            obj = objects[gid]
            yaw_err, pos_err = errors(obj, fit.x, fit.y, fit.yaw)
            det_rows.append(
                {
                    "room": room,
                    "seed": seed,
                    "instance": gid,
                    "kind": obj.kind,
                    "class": d.label,
                    "model": fit.model,
                    "yaw_error": yaw_err,
                    "position_error": pos_err,
                    "rms": fit.rms,
                    "inlier_fraction": fit.inlier_fraction,
                    "ms": ms,
                }
            )
        for gid, obj in objects.items():
            if gid not in matched and (instance == gid).sum() >= args.min_points:
                missed[CLASSES[obj.class_name]] += 1
        print(f"scene {i + 1}/{args.scenes}: {room} seed {seed}", file=sys.stderr)
    gt_summary = summarize(gt_rows)
    print(
        f"{args.scenes} scenes ({args.rooms}; {args.sensor}, {args.points:,} points, "
        f"seeds {args.seed}..{args.seed + args.scenes - 1}); models "
        f"{'scaled to the objects' if not args.no_scale else 'unscaled'}; "
        f"library sampled in {library_s:.2f} s (once).\n"
    )
    print(table("Ground-truth points as the detection", gt_summary))
    det_summary = []
    if not args.no_detector:
        det_summary = summarize(det_rows)
        print()
        print(table("Through the detector (matched detections, point IoU >= 0.25)", det_summary))
        print(
            "\nGround-truth objects not detected: "
            + ", ".join(f"{k} {v}" for k, v in sorted(missed.items()))
        )
    if args.json:
        args.json.write_text(
            json.dumps(
                {
                    "ground_truth": gt_rows,
                    "detector": det_rows,
                    "summary": {"ground_truth": gt_summary, "detector": det_summary},
                },
                indent=1,
            )
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
