"""End to end: read, detect and write a simulated scan at 100k, 1M and 10M points, against Open3D.

For each size, a simulated office scanned by the virtual laser scanner
(``ontodetect.synth``, seed :data:`SEED`) is written once as a binary PLY (x y z
and colours), in ``--cache DIR`` when given so that later runs reuse it, and
each method runs in its own subprocess, which reports times and resident memory:

- **ontodetect**: what ``ontodetect detect SCAN -o OUT`` does: ``read_cloud``,
  ``pipeline.detect`` (prepare + segment, score, label; the stage times come from
  ``Result.timings``) and ``write_outputs`` (detections.json, labelled.ply,
  detections.png);
- **Open3D recipe** on the same file: ``read_point_cloud``, statistical outlier
  removal, the altitude cut-off z < 1.4 m (Table 4.1), ``cluster_dbscan`` and
  ``segment_plane`` repeated in every cluster, with the parameters of
  ``bench_geometry`` (clusters and planes only: no labels, nothing written).

Peak memory per stage is the largest resident set seen by a thread that samples
``/proc/self/statm`` every few milliseconds while the stage runs; the peak of the
whole run is ``getrusage(RUSAGE_SELF).ru_maxrss``, and that of the forked workers
that make the extra passes of a vote ``getrusage(RUSAGE_CHILDREN).ru_maxrss``. Sizes below
:data:`REPEAT_BELOW` points take the best of ``--repeat`` runs (other users' load
only adds time); larger ones run once. Every subprocess has a time limit and an
address-space limit, so a slow or huge Open3D DBSCAN at 10 million points is
reported as a timeout or as out of memory instead of hanging the run or the
machine. Prints a Markdown report (and writes it to ``--out``).

Run::

    python -m benchmarks.bench_pipeline [--sizes 100000 1000000 10000000] [--cache DIR]
        [--repeat 3] [--timeout 1800] [--o3d-timeout 300] [--mem-limit-gb 8] [--out FILE]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from benchmarks import _open3d_recipe as o3d_recipe
from benchmarks._open3d_recipe import (
    CUTOFF,
    O3D_DBSCAN,
    O3D_MAX_PLANES,
    O3D_MIN_CLUSTER,
    O3D_PLANE,
    O3D_SOR,
)

SEED = 20161221
#: Default sizes (points).
SIZES = (100_000, 1_000_000, 10_000_000)
#: Sizes below this take the best of ``--repeat`` runs; larger ones run once.
REPEAT_BELOW = 5_000_000
#: Seconds between two samples of the resident set.
RSS_INTERVAL = 0.005
#: Open3D recipe, as in bench_geometry (Table 4.1: DBSCAN radius 2-5 cm, inlier distance 1 cm).
MB = 1 << 20
#: Stages of the ontodetect run, in order.
STAGES = ("read", "segment", "score", "label", "write")


# -- memory --------------------------------------------------------------------------------
def _rss_bytes() -> int:
    with open("/proc/self/statm", "rb") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


class RssSampler:
    """Samples the resident set in a thread; :meth:`peak` gives the largest in a time window."""

    def __init__(self, interval: float = RSS_INTERVAL) -> None:
        self.interval = interval
        self.samples: list[tuple[float, int]] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self.available = os.path.exists("/proc/self/statm")

    def _run(self) -> None:
        while not self._stop.is_set():
            self.mark()
            self._stop.wait(self.interval)

    def mark(self) -> None:
        """Take one sample now (at the end of a stage too short for the thread to see)."""
        if self.available:
            self.samples.append((time.perf_counter(), _rss_bytes()))

    def __enter__(self) -> RssSampler:
        if self.available:
            self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self.available:
            self._thread.join()

    def peak(self, start: float, end: float) -> float | None:
        """Largest resident set (MB) sampled in [start, end], or None without samples."""
        inside = [rss for t, rss in self.samples if start <= t <= end]
        return max(inside) / MB if inside else None


# -- scenes --------------------------------------------------------------------------------
def scene_path(cache: Path, n: int) -> Path:
    return cache / f"office_tls_{n}_seed{SEED}.ply"


def work_generate(n: int, path: Path) -> dict:
    """Simulate the office at ``n`` points and write it as binary PLY (xyz + rgb)."""
    from ontodetect import point_cloud, write_cloud
    from ontodetect.synth import synthesize

    t0 = time.perf_counter()
    result = synthesize("office", "tls", seed=SEED, points=n)
    cloud = result.cloud
    t1 = time.perf_counter()
    rgb = cloud.rgb if cloud.rgb is not None else np.full((len(cloud), 3), 128, np.uint8)
    write_cloud(path, point_cloud(cloud.xyz, rgb, copy=False), dtype="float32")
    return {
        "points": len(cloud),
        "synthesize": t1 - t0,
        "write": time.perf_counter() - t1,
        "peak_mb": _peak_mb(),
    }


# -- workers (each in its own subprocess) --------------------------------------------------
def work_ours(path: Path, repeat: int) -> dict:
    import warnings

    from ontodetect.cloud import DataWarning
    from ontodetect.io import read_cloud
    from ontodetect.outputs import write_outputs
    from ontodetect.pipeline import detect

    base_mb = _rss_bytes() / MB
    runs = []
    for _ in range(repeat):
        with (
            tempfile.TemporaryDirectory(prefix="bench_pipeline_") as out,
            RssSampler() as rss,
            warnings.catch_warnings(),
        ):
            warnings.simplefilter("ignore", DataWarning)
            t0 = time.perf_counter()
            cloud = read_cloud(path)
            rss.mark()
            t1 = time.perf_counter()
            # As the command line does; the memory sampler's thread would keep the passes
            # of a vote in this process unless workers are asked for.
            result = detect(cloud, seed=0, jobs=0)  # 0: one worker per usable CPU
            t2 = time.perf_counter()
            write_outputs(result, out)
            rss.mark()
            t3 = time.perf_counter()
        tm = result.timings
        # Stage windows: detect runs segment, score and label back to back.
        bounds = [t0, t1, t1 + tm["segment"], t1 + tm["segment"] + tm["score"], t2, t3]
        runs.append(
            {
                "read": t1 - t0,
                "segment": tm["segment"],
                "score": tm["score"],
                "label": tm["label"],
                "votes": tm.get("votes", 0.0),
                "detect": t2 - t1,
                "write": t3 - t2,
                "total": t3 - t0,
                "stage_mb": {s: rss.peak(a, b) for s, a, b in zip(STAGES, bounds, bounds[1:])},
                "clusters": len(result.segmentation),
                "detections": len(result.detections),
            }
        )
        del cloud, result
    best = min(runs, key=lambda r: r["total"])
    # Memory from the first run: later runs start with the heap the earlier ones left.
    return {
        **best,
        "stage_mb": runs[0]["stage_mb"],
        "runs": len(runs),
        "base_mb": base_mb,
        "peak_mb": _peak_mb(),
        # The passes of a vote after the first run in forked workers: their own peak.
        "workers_mb": resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0,
    }


def work_o3d(path: Path, repeat: int) -> dict:
    import open3d as o3d

    runs = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        pc = o3d.io.read_point_cloud(str(path))
        t1 = time.perf_counter()
        pc, labels = o3d_recipe.cluster(pc)
        t2 = time.perf_counter()
        planes = o3d_recipe.planes(pc, labels)
        t3 = time.perf_counter()
        runs.append(
            {
                "read": t1 - t0,
                "dbscan": t2 - t1,
                "planes_s": t3 - t2,
                "recipe": t3 - t1,
                "total": t3 - t0,
                "clusters": int(labels.max()) + 1 if labels.size else 0,
                "planes": planes,
            }
        )
        del pc, labels
    best = min(runs, key=lambda r: r["total"])
    return {**best, "runs": len(runs), "peak_mb": _peak_mb()}


def _limit_memory(gigabytes: float) -> None:
    limit = int(gigabytes * (1 << 30))
    with contextlib.suppress(ValueError, OSError):
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def _run_worker(args: list[str], timeout: float, mem_gb: float) -> dict:
    cmd = [
        sys.executable,
        "-m",
        "benchmarks.bench_pipeline",
        "--mem-limit-gb",
        str(mem_gb),
        "--worker",
        *args,
    ]
    start = time.perf_counter()
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout after {timeout:.0f} s"}
    if out.returncode != 0:
        wall = time.perf_counter() - start
        tail = (out.stderr.strip().splitlines() or ["?"])[-1]
        if "MemoryError" in out.stderr or "bad_alloc" in out.stderr or out.returncode in (-6, -9):
            return {"error": f"out of memory (limit {mem_gb:g} GB) after {wall:.0f} s"}
        return {"error": f"failed after {wall:.0f} s ({tail[:80]})"}
    return json.loads(out.stdout.strip().splitlines()[-1])


# -- report --------------------------------------------------------------------------------
def _fmt(r: dict, key: str, spec: str = ".2f") -> str:
    if "error" in r:
        return r["error"]
    v = r.get(key)
    return "-" if v is None else format(v, spec)


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    mem = ""
    with contextlib.suppress(OSError, ValueError, IndexError):
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                mem = f", {int(line.split()[1]) / (1 << 20):.0f} GB RAM"
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    import open3d

    return (
        f"{os.cpu_count()} CPUs ({cpu}){mem}, {platform.system()}, Python "
        f"{platform.python_version()}, NumPy {np.__version__}, Open3D {open3d.__version__}; "
        f"load average {load:.1f} at the start"
    )


def report(rows: list[tuple[int, dict, dict, dict]], args: argparse.Namespace, machine: str) -> str:
    lines = [
        "| points | read (s) | prepare + segment (s) | score (s) | label (s) | extra passes (s) "
        "| write (s) | end to end (s) | peak RSS (MB) | worker peak RSS (MB) | clusters "
        "| detections | Open3D read (s) "
        "| Open3D SOR + DBSCAN (s) | Open3D planes (s) | Open3D total (s) | Open3D peak RSS (MB) "
        "| Open3D / ontodetect, end to end | Open3D recipe / prepare + segment |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:"
        "|---:|",
    ]
    for n, _, ours, o3d in rows:
        ok = "error" not in ours and "error" not in o3d
        ratio = f"{o3d['total'] / ours['total']:.1f}x" if ok else "-"
        ratio_seg = f"{o3d['recipe'] / ours['segment']:.1f}x" if ok else "-"
        cells = [
            _fmt(ours, "read", ".3f"), _fmt(ours, "segment"), _fmt(ours, "score"),
            _fmt(ours, "label", ".3f"), _fmt(ours, "votes"), _fmt(ours, "write"),
            _fmt(ours, "total"), _fmt(ours, "peak_mb", ".0f"), _fmt(ours, "workers_mb", ".0f"),
            _fmt(ours, "clusters", "d"),
            _fmt(ours, "detections", "d"), _fmt(o3d, "read", ".3f"), _fmt(o3d, "dbscan"),
            _fmt(o3d, "planes_s"), _fmt(o3d, "total"), _fmt(o3d, "peak_mb", ".0f"), ratio,
            ratio_seg,
        ]  # fmt: skip
        lines.append(f"| {n:,} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "Peak resident memory of ontodetect during each stage (MB; the process holds about "
        "the first column before reading):",
        "",
        "| points | before reading | read | prepare + segment | score | label | write |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for n, _, ours, _ in rows:
        if "error" in ours:
            lines.append(f"| {n:,} | {ours['error']} | | | | | |")
            continue
        st = ours["stage_mb"]
        cells = " | ".join("-" if st.get(s) is None else f"{st[s]:.0f}" for s in STAGES)
        lines.append(f"| {n:,} | {ours['base_mb']:.0f} | {cells} |")
    lines += [
        "",
        "Simulated scans (generated once, reused from the cache):",
        "",
        "| points | synthesize (s) | write PLY (s) | generator peak RSS (MB) |",
        "|---:|---:|---:|---:|",
    ]
    for n, gen, _, _ in rows:
        lines.append(
            f"| {n:,} | {_fmt(gen, 'synthesize')} | {_fmt(gen, 'write')} "
            f"| {_fmt(gen, 'peak_mb', '.0f')} |"
        )
    lines += [
        "",
        f"Machine: {machine}. Sizes below {REPEAT_BELOW:,} points: best of {args.repeat} runs; "
        f"larger: one run. Limits per subprocess: {args.timeout:.0f} s (ontodetect), "
        f"{args.o3d_timeout:.0f} s (Open3D), {args.mem_limit_gb:g} GB of address space. "
        f"Open3D recipe: SOR {O3D_SOR}, cut-off z < {CUTOFF} m, DBSCAN {O3D_DBSCAN}, "
        f"segment_plane {O3D_PLANE} up to {O3D_MAX_PLANES} planes per cluster of "
        f">= {O3D_MIN_CLUSTER} points.",
    ]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=list(SIZES))
    ap.add_argument(
        "--cache",
        type=Path,
        default=None,
        help="folder for the simulated scans, reused by later runs",
    )
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--timeout", type=float, default=1800.0, help="s per ontodetect run")
    ap.add_argument("--o3d-timeout", type=float, default=300.0, help="s per Open3D run")
    ap.add_argument(
        "--mem-limit-gb", type=float, default=8.0, help="address-space limit of every subprocess"
    )
    ap.add_argument("--no-open3d", action="store_true", help="skip the Open3D recipe")
    ap.add_argument("--out", type=Path, default=None, help="also write the report here")
    ap.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.worker:
        # The worker limits itself: an allocation beyond the limit fails instead of swapping.
        _limit_memory(args.mem_limit_gb)
        kind, *rest = args.worker
        if kind == "generate":
            result = work_generate(int(rest[0]), Path(rest[1]))
        elif kind == "ours":
            result = work_ours(Path(rest[0]), int(rest[1]))
        else:
            result = work_o3d(Path(rest[0]), int(rest[1]))
        print(json.dumps(result))
        return 0

    machine = _machine()
    tmp = None
    if args.cache is None:
        tmp = tempfile.mkdtemp(prefix="bench_pipeline_")
        cache = Path(tmp)
    else:
        cache = args.cache
        cache.mkdir(parents=True, exist_ok=True)
    rows = []
    try:
        for n in sorted(args.sizes):
            path = scene_path(cache, n)
            gen: dict = {"synthesize": None, "write": None, "peak_mb": None}
            if not path.is_file():
                gen = _run_worker(["generate", str(n), str(path)], args.timeout, args.mem_limit_gb)
            repeat = args.repeat if n < REPEAT_BELOW else 1
            ours = _run_worker(["ours", str(path), str(repeat)], args.timeout, args.mem_limit_gb)
            o3d = (
                {"error": "not run"}
                if args.no_open3d
                else _run_worker(
                    ["o3d", str(path), str(repeat)], args.o3d_timeout, args.mem_limit_gb
                )
            )
            rows.append((n, gen, ours, o3d))
            print(
                f"{n:>10,d}: ontodetect {_fmt(ours, 'total')} s ({_fmt(ours, 'peak_mb', '.0f')}"
                f" MB), Open3D {_fmt(o3d, 'total')} s",
                file=sys.stderr,
            )
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
    text = report(rows, args, machine)
    print(text)
    if args.out:
        args.out.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
