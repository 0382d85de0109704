"""Detection time on real labelled rooms (ScanNet, VoteNet layout), against the plain Open3D recipe.

Run as ``python -m benchmarks.bench_detect DATASET_DIR [--repeat 3]``: every
``*_vert.npy`` scene is read once, then timed end to end through
``ontodetect.pipeline.detect`` (preparation, part-driven clustering, MSAC planes,
scoring, labelling) and through the obvious alternative on the same points:
Open3D statistical outlier removal, DBSCAN (eps 5 cm, Table 4.1) and repeated
``segment_plane`` per cluster — which finds clusters and planes but labels
nothing. Medians of ``--repeat`` runs; the ratio is Open3D / ontodetect.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from ontodetect.io import read_cloud
from ontodetect.pipeline import detect

#: Open3D recipe parameters: Table 4.1's radius and inlier distance.
O3D_EPS = 0.05
O3D_MIN_POINTS = 10
O3D_PLANE_DISTANCE = 0.01
O3D_MIN_PLANE_POINTS = 30
O3D_MAX_PLANES = 8


def open3d_recipe(xyz: np.ndarray) -> int:
    """Statistical outlier removal + DBSCAN + repeated RANSAC planes; returns the plane count."""
    import open3d as o3d

    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(xyz))
    pc, _ = pc.remove_statistical_outlier(nb_neighbors=20, std_ratio=2.0)
    labels = np.asarray(pc.cluster_dbscan(eps=O3D_EPS, min_points=O3D_MIN_POINTS))
    pts = np.asarray(pc.points)
    planes = 0
    for k in range(labels.max() + 1 if labels.size else 0):
        rest = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts[labels == k]))
        for _ in range(O3D_MAX_PLANES):
            if len(rest.points) < O3D_MIN_PLANE_POINTS:
                break
            _, inliers = rest.segment_plane(O3D_PLANE_DISTANCE, 3, 200)
            if len(inliers) < O3D_MIN_PLANE_POINTS:
                break
            planes += 1
            rest = rest.select_by_index(inliers, invert=True)
    return planes


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
    args = parser.parse_args(argv)
    scenes = sorted(args.dataset.glob("*_vert.npy"))
    if not scenes:
        raise SystemExit(f"{args.dataset}: no *_vert.npy scenes")
    print(f"machine: {platform.processor() or platform.machine()}, "
          f"python {platform.python_version()}")
    print("| scene | points | detections | ontodetect detect (s) | Open3D recipe (s) | ratio |")
    print("|---|---:|---:|---:|---:|---:|")
    ours, theirs = [], []
    for path in scenes:
        cloud = read_cloud(path)
        result = detect(cloud)  # warm-up, and the count
        t_ours = _median_time(lambda c=cloud: detect(c), args.repeat)
        t_o3d = _median_time(lambda c=cloud: open3d_recipe(np.array(c.xyz)), args.repeat)
        ours.append(t_ours)
        theirs.append(t_o3d)
        name = path.name.removesuffix("_vert.npy")
        print(f"| {name} | {len(cloud):,} | {len(result.detections)} | {t_ours:.2f} | "
              f"{t_o3d:.2f} | {t_o3d / t_ours:.1f}x |")
    print(f"| **median** | | | **{statistics.median(ours):.2f}** | "
          f"**{statistics.median(theirs):.2f}** | "
          f"**{statistics.median(theirs) / statistics.median(ours):.1f}x** |")


if __name__ == "__main__":
    main()
