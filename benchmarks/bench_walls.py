"""How far the walls preparation finds move when the scan is turned by the vote's 0.7 degrees.

The vote (``detect.votes``) segments the scan three times, turned by 0 and by plus and
minus ``detect.vote_turn`` degrees about the vertical (``pipeline.vote_turns``). A wall
does not depend on the turn, so neither should the points taken as wall: what one pass
takes and another does not joins, or leaves, the furniture beside it. For every scan this
prepares the scan (:func:`ontodetect.preprocess.prepare`) at the vote's turns and reports,
for each turned pass, the share of the points taken as wall by one of the two passes and
not by the other (points compared through ``point_to_voxel``; 0: the same wall points),
then the mean over the scans and how many exceed 0.1.

Scans: ScanNet scenes in VoteNet's layout (``--real DIR``: ``*_vert.npy``) and the
generalization benchmark's simulated rooms (``--sim DIR``: one folder per scan with
``cloud.ply``), every ``--every``-th of them. ``--set KEY=VALUE`` changes the
configuration as ``detect --set`` does. No timing is reported.

Run::

    python -m benchmarks walls --real path/to/scannet-dev [--sim DIR --every 3] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import numpy as np


def wall_points(cloud, config) -> np.ndarray:
    """Whether each point of ``cloud`` is taken as wall by preparation under ``config``."""
    from ontodetect.preprocess import STRUCTURE_LABELS, prepare

    wall = next(k for k, v in STRUCTURE_LABELS.items() if v == "wall")
    scene = prepare(cloud, config)
    labels = np.append(scene.structure_label, -1)
    return labels[scene.point_to_voxel] == wall


def disagreement(a: np.ndarray, b: np.ndarray) -> float:
    """Share of the points either mask holds that only one of them holds."""
    union = np.count_nonzero(a | b)
    return float(np.count_nonzero(a ^ b)) / union if union else 0.0


def scans(real: Path | None, sim: Path | None, every: int) -> list[tuple[str, Path]]:
    out = []
    if real is not None:
        out += [(p.name.removesuffix("_vert.npy"), p) for p in sorted(real.glob("*_vert.npy"))]
    if sim is not None:
        found = sorted(p for p in sim.iterdir() if (p / "cloud.ply").is_file())
        out += [(p.name, p / "cloud.ply") for p in found[::every]]
    return out


def main(argv: list[str]) -> int:
    from ontodetect import read_cloud
    from ontodetect.config import Config
    from ontodetect.pipeline import vote_turns

    ap = argparse.ArgumentParser(prog="python -m benchmarks walls", description=__doc__)
    ap.add_argument("--real", type=Path, help="ScanNet scenes (*_vert.npy)")
    ap.add_argument("--sim", type=Path, help="simulated scans (folders with cloud.ply)")
    ap.add_argument("--every", type=int, default=1, help="every n-th simulated scan")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--out", type=Path, help="write the figures as JSON")
    args = ap.parse_args(argv)
    if args.real is None and args.sim is None:
        ap.error("give --real DIR, --sim DIR or both")
    base = Config().with_overrides(args.set)
    turn = base.detect.vote_turn
    turns = [0.0, *vote_turns(max(2, base.detect.votes), turn)]
    rows = []
    for name, path in scans(args.real, args.sim, max(1, args.every)):
        cloud = read_cloud(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a scan without a floor says so; not counted here
            masks = [
                wall_points(cloud, base.replace(prepare={"turn": base.prepare.turn + t}))
                for t in turns
            ]
        moved = [disagreement(masks[0], m) for m in masks[1:]]
        rows.append({"scan": name, "wall_points": int(masks[0].sum()), "moved": moved})
        print(
            f"{name:28s} wall points {rows[-1]['wall_points']:7d}   moved "
            f"{moved[0]:.3f} {moved[1]:.3f}",
            flush=True,
        )
    means = [float(np.mean(r["moved"])) for r in rows]
    summary = {
        "turn": turn,
        "scans": len(rows),
        "mean": round(float(np.mean(means)), 4) if means else None,
        "over_0.1": sum(m > 0.1 for m in means),
        "settings": args.set,
    }
    print(
        f"mean share of wall points moved {summary['mean']}; "
        f"scans over 0.1: {summary['over_0.1']} of {len(rows)}"
    )
    if args.out is not None:
        args.out.write_text(json.dumps({"summary": summary, "scans": rows}, indent=1) + "\n")
    return 0
