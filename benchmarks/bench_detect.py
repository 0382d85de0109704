"""Detection time on real labelled rooms (ScanNet, VoteNet layout), against the plain Open3D recipe.

Run as ``python -m benchmarks.bench_detect DATASET_DIR [--repeat 3] [--votes N]``: every
``*_vert.npy`` scene is read once, then timed end to end through
``ontodetect.pipeline.detect`` (preparation, part-driven clustering, MSAC planes,
scoring, labelling) and through the obvious alternative on the same points:
Open3D statistical outlier removal, the 1.4 m cut-off, DBSCAN (eps 5 cm, Table
4.1) and repeated ``segment_plane`` per cluster (``benchmarks/_open3d_recipe.py``)
— which finds clusters and planes but labels nothing. Medians of ``--repeat``
runs; the ratio is Open3D / ontodetect. ``--votes 1`` times a single pass instead of the
default majority of three (``detect.votes``).
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from benchmarks import _open3d_recipe as o3d_recipe
from ontodetect.config import Config
from ontodetect.io import read_cloud
from ontodetect.pipeline import detect


def open3d_recipe(xyz: np.ndarray) -> int:
    """The plain Open3D recipe on one cloud; returns the number of planes found."""
    import open3d as o3d

    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(xyz))
    pc, labels = o3d_recipe.cluster(pc)
    return o3d_recipe.planes(pc, labels)


def _median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path, help="folder of *_vert.npy scenes")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--votes", type=int, default=None, help="passes per detection (default: detect.votes, 3)"
    )
    args = parser.parse_args(argv)
    scenes = sorted(args.dataset.glob("*_vert.npy"))
    if not scenes:
        raise SystemExit(f"{args.dataset}: no *_vert.npy scenes")
    print(
        f"machine: {platform.processor() or platform.machine()}, "
        f"python {platform.python_version()}, votes {args.votes}"
    )
    print("| scene | points | detections | ontodetect detect (s) | Open3D recipe (s) | ratio |")
    print("|---|---:|---:|---:|---:|---:|")
    config = Config() if args.votes is None else Config().replace(detect={"votes": args.votes})
    ours, theirs = [], []
    for path in scenes:
        cloud = read_cloud(path)
        result = detect(cloud, config=config)  # warm-up, and the count
        t_ours = _median_time(lambda c=cloud: detect(c, config=config), args.repeat)
        t_o3d = _median_time(lambda c=cloud: open3d_recipe(np.array(c.xyz)), args.repeat)
        ours.append(t_ours)
        theirs.append(t_o3d)
        name = path.name.removesuffix("_vert.npy")
        print(
            f"| {name} | {len(cloud):,} | {len(result.detections)} | {t_ours:.2f} | "
            f"{t_o3d:.2f} | {t_o3d / t_ours:.1f}x |"
        )
    print(
        f"| **median** | | | **{statistics.median(ours):.2f}** | "
        f"**{statistics.median(theirs):.2f}** | "
        f"**{statistics.median(theirs) / statistics.median(ours):.1f}x** |"
    )


if __name__ == "__main__":
    main()
