"""How well clusters isolate furniture on labelled ScanNet scans (VoteNet layout).

Usage::

    .venv/bin/python scripts/cluster_report.py DATASET_DIR [--set cluster.radius=0.04 ...]
        [--config cfg.yaml] [--scenes scene0002_00 ...] [--per-scene] [--json OUT.json]

DATASET_DIR holds ``<scene>_vert.npy`` (n, 6) float xyz rgb, ``<scene>_ins_label.npy`` and
``<scene>_sem_label.npy`` (NYU40: chair 5, sofa 6, table 7, desk 14 counted as table).
For every ground-truth chair, sofa and table the best cluster is the one holding most of
its points. Reported per class:

- ``whole``: share of instances with >= 80 % of their points in one cluster;
- ``share``: mean share of an instance's points in its best cluster;
- ``purity``: mean share of the best cluster's points that belong to the instance
  (a cluster swallowing a table and four chairs holds each of them whole, uselessly);
- ``iou25`` / ``iou50``: share of instances whose best cluster has point IoU >= 0.25 /
  0.5 with them (what a detection needs to count as a true positive).

Points are counted over the whole scan, outliers and structure included.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from ontodetect import point_cloud
from ontodetect.cloud import DataWarning
from ontodetect.config import Config
from ontodetect.segment import segment

CLASSES = {5: "chair", 6: "sofa", 7: "table", 14: "table"}
WHOLE = 0.8


def instance_scores(labels: np.ndarray, sem: np.ndarray, ins: np.ndarray) -> list[dict]:
    """Best-cluster share, purity and IoU of every chair, sofa and table instance."""
    out = []
    cluster_sizes = np.bincount(labels[labels >= 0]) if (labels >= 0).any() else np.zeros(0)
    for inst in np.unique(ins[ins > 0]):
        member = ins == inst
        cls = int(np.bincount(sem[member]).argmax())
        if cls not in CLASSES:
            continue
        lab = labels[member]
        n = int(member.sum())
        hit = lab[lab >= 0]
        if len(hit) == 0:
            out.append(
                {
                    "instance": int(inst),
                    "class": CLASSES[cls],
                    "points": n,
                    "share": 0.0,
                    "purity": 0.0,
                    "iou": 0.0,
                    "cluster": -1,
                }
            )
            continue
        counts = np.bincount(hit)
        best = int(counts.argmax())
        inter = int(counts[best])
        size = int(cluster_sizes[best])
        out.append(
            {
                "instance": int(inst),
                "class": CLASSES[cls],
                "points": n,
                "share": inter / n,
                "purity": inter / size,
                "iou": inter / (n + size - inter),
                "cluster": best,
            }
        )
    return out


def summarize(rows: list[dict]) -> dict[str, dict]:
    summary = {}
    for name in ("chair", "sofa", "table", "all"):
        sel = [r for r in rows if name in ("all", r["class"])]
        if not sel:
            continue
        summary[name] = {
            "instances": len(sel),
            "whole": float(np.mean([r["share"] >= WHOLE for r in sel])),
            "share": float(np.mean([r["share"] for r in sel])),
            "purity": float(np.mean([r["purity"] for r in sel])),
            "iou25": float(np.mean([r["iou"] >= 0.25 for r in sel])),
            "iou50": float(np.mean([r["iou"] >= 0.5 for r in sel])),
        }
    return summary


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--config", type=Path)
    ap.add_argument("--set", dest="overrides", action="append", default=[])
    ap.add_argument("--scenes", nargs="*")
    ap.add_argument("--per-scene", action="store_true")
    ap.add_argument("--instances", action="store_true", help="print every instance")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)

    cfg = Config.from_yaml(args.config) if args.config else Config()
    cfg = cfg.with_overrides(args.overrides)
    files = sorted(args.dataset.glob("*_vert.npy"))
    if args.scenes:
        files = [f for f in files if f.name[: -len("_vert.npy")] in args.scenes]
    if not files:
        print(f"no *_vert.npy files in {args.dataset}", file=sys.stderr)
        return 2
    rows: list[dict] = []
    per_scene = {}
    t0 = time.perf_counter()
    for f in files:
        scene = f.name[: -len("_vert.npy")]
        vert = np.load(f)
        sem = np.load(f.with_name(f"{scene}_sem_label.npy")).astype(np.int64)
        ins = np.load(f.with_name(f"{scene}_ins_label.npy")).astype(np.int64)
        cloud = point_cloud(vert[:, :3], vert[:, 3:6], meta={"source": str(f)})
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DataWarning)
            seg = segment(cloud, cfg, seed=0, fit_planes=False)
        labels = seg.labels_per_point()
        scene_rows = instance_scores(labels, sem, ins)
        for r in scene_rows:
            r["scene"] = scene
        rows += scene_rows
        per_scene[scene] = summarize(scene_rows)
        if args.per_scene:
            s = per_scene[scene].get("all")
            print(
                f"{scene}: {len(seg)} clusters, "
                + (
                    f"whole {s['whole']:.2f} purity {s['purity']:.2f} iou25 {s['iou25']:.2f}"
                    if s
                    else "no furniture"
                )
            )
        if args.instances:
            for r in scene_rows:
                print(
                    f"  {scene} {r['class']:5s} #{r['instance']:<3d} {r['points']:5d} pts  "
                    f"share {r['share']:.2f} purity {r['purity']:.2f} iou {r['iou']:.2f} "
                    f"cluster {r['cluster']}"
                )
    elapsed = time.perf_counter() - t0
    summary = summarize(rows)
    print(
        f"{len(files)} scans, {elapsed:.1f} s; a GT instance is 'whole' with >= "
        f"{WHOLE:.0%} of its points in one cluster"
    )
    print(
        f"{'class':6s} {'n':>4s} {'whole':>6s} {'share':>6s} {'purity':>7s} {'iou25':>6s} "
        f"{'iou50':>6s}"
    )
    for name, s in summary.items():
        print(
            f"{name:6s} {s['instances']:4d} {s['whole']:6.2f} {s['share']:6.2f} "
            f"{s['purity']:7.2f} {s['iou25']:6.2f} {s['iou50']:6.2f}"
        )
    if args.json:
        args.json.write_text(
            json.dumps(
                {
                    "summary": summary,
                    "per_scene": per_scene,
                    "instances": rows,
                    "config": cfg.to_dict(),
                },
                indent=1,
            )
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
