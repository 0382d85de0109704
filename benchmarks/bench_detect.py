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

``--cli`` times the command line instead, each run a whole new process as a user starts it:
``ontodetect detect SCENE -o OUT -q`` (start-up, reading, detection, and writing
detections.json, labelled.ply and detections.png) against ``python -m
benchmarks._open3d_recipe SCENE`` (start-up, reading, the recipe), in turn, A B A B...;
``--src DIR`` (repeatable) adds the command line of another source tree to the turn, for
before/after figures in one run. Each row gives the median wall and CPU (user + system,
the process and its children) seconds and the ratio of the medians.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
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


def _run(cmd: list[str], env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU seconds (user + system, with children) of one whole process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def cli_main(scenes: list[Path], repeat: int, sources: list[Path]) -> None:
    """The command line end to end against the Open3D recipe as a process (``--cli``)."""
    here = Path(__file__).resolve().parents[1]
    py = sys.executable
    trees = {"ontodetect detect": here / "src"}
    trees.update({f"ontodetect detect ({s})": s.resolve() for s in sources})
    print(f"load average at the start: {os.getloadavg()[0]:.2f}, {repeat} runs each")
    print("| scene | command | wall median (s) | min–max | CPU median (s) | / Open3D recipe |")
    print("|---|---|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:
            name = scene.name.removesuffix("_vert.npy")
            commands = {
                label: (
                    [py, "-m", "ontodetect", "detect", str(scene), "-o", f"{tmp}/out", "-q"],
                    {**os.environ, "PYTHONPATH": str(src)},
                )
                for label, src in trees.items()
            }
            commands["Open3D recipe"] = (
                [py, "-m", "benchmarks._open3d_recipe", str(scene)],
                {**os.environ, "PYTHONPATH": f"{here}{os.pathsep}{here / 'src'}"},
            )
            for cmd, env in commands.values():  # untimed: page cache, .pyc files
                _run(cmd, env)
            runs: dict[str, list[tuple[float, float]]] = {label: [] for label in commands}
            for _ in range(repeat):
                for label, (cmd, env) in commands.items():
                    runs[label].append(_run(cmd, env))
            recipe = statistics.median(w for w, _ in runs["Open3D recipe"])
            for label, times in runs.items():
                walls = [w for w, _ in times]
                wall = statistics.median(walls)
                print(
                    f"| {name} | {label} | {wall:.2f} | {min(walls):.2f}–{max(walls):.2f} | "
                    f"{statistics.median(c for _, c in times):.2f} | {wall / recipe:.1f}x |"
                )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset", type=Path, help="folder of *_vert.npy scenes")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--votes", type=int, default=None, help="passes per detection (default: detect.votes, 3)"
    )
    parser.add_argument(
        "--cli", action="store_true", help="time the command line end to end, whole processes"
    )
    parser.add_argument(
        "--src", type=Path, action="append", default=[], help="with --cli: another source tree"
    )
    parser.add_argument("--scenes", nargs="+", default=None, help="only these scene names")
    args = parser.parse_args(argv)
    scenes = sorted(args.dataset.glob("*_vert.npy"))
    if args.scenes:
        scenes = [s for s in scenes if s.name.removesuffix("_vert.npy") in args.scenes]
    if not scenes:
        raise SystemExit(f"{args.dataset}: no *_vert.npy scenes")
    if args.cli:
        cli_main(scenes, args.repeat, args.src)
        return
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
