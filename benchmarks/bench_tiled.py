"""Tiled detection of a simulated building floor on a local Dask cluster of 1 and 2 workers.

The floor: rooms of ``ontodetect.synth`` (laser scanner, ``--points-per-room`` points
each, types cycling through offices, conference and dining rooms, living rooms,
kitchens; seed ``SEED + k`` for room k) side by side on a square grid of rooms, 0.3 m
apart. It is written room by room into a binary PLY (x y z float32, r g b uint8: 15
bytes a point), so that the generator never holds more than one room; the file is kept
in ``--cache DIR`` for later runs.

Then, each in its own subprocess:

- **tiled, N workers** for every N of ``--workers``: ``detect_tiled(FILE, tile=--tile)``
  on ``LocalCluster(n_workers=N, threads_per_worker=1)``: the survey pass (count,
  bounds, a 2-million-point subsample, the shared floor) in the client, the tiles on
  the workers, each reading only its window's chunks of the file. Reported: wall time
  end to end (cluster start excluded), points per second (the file's points over that
  time), the largest peak resident memory of a worker process (``ru_maxrss``, measured
  in the tile task) and of the client, the largest window, tiles, detections;
- **the alternative** on a smaller floor of ``--baseline-points`` (the same rooms,
  fewer of them): ``read_cloud`` + untiled ``detect`` in one process, beside the tiled
  run of that same file with 1 worker: their peak memory and points per second. The
  untiled run is the obvious way, and its memory grows with the file, which is why the
  50-million-point file is not run untiled (it would need about 180 bytes a point).

Prints a Markdown report (and writes it to ``--out``).

Run::

    python -m benchmarks tiled [--points 50000000] [--points-per-room 250000] [--tile 20]
        [--workers 1 2] [--baseline-points 5000000] [--cache DIR] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SEED = 20161221
#: Digits of the vertex count in the header, written before the count is known.
COUNT_DIGITS = 12
MB = 1 << 20
#: The shared floor is found on this many points.
SAMPLE = 2_000_000


# -- the floor -----------------------------------------------------------------------------
def floor_path(cache: Path, points: int, per_room: int) -> Path:
    return cache / f"floor_tls_{points}_{per_room}_seed{SEED}.ply"


def _header(count: int) -> bytes:
    return (
        "ply\nformat binary_little_endian 1.0\ncomment ontodetect building floor, "
        f"seed {SEED}\nelement vertex {count:0{COUNT_DIGITS}d}\nproperty float x\n"
        "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
        "property uchar blue\nend_header\n"
    ).encode("ascii")


def work_generate(points: int, per_room: int, path: Path) -> dict:
    """Write the floor room by room (one room in memory at a time)."""
    from ontodetect.synth.building import iter_floor_rooms

    rooms = math.ceil(points / per_room)
    columns = math.ceil(math.sqrt(rooms))
    record = np.dtype([("xyz", "<f4", 3), ("rgb", "u1", 3)])
    t0 = time.perf_counter()
    written = 0
    tmp = path.with_suffix(".part")
    with open(tmp, "wb") as fh:
        fh.write(_header(0))
        for room in iter_floor_rooms(
            rooms, columns=columns, sensor="tls", points_per_room=per_room, seed=SEED
        ):
            cloud = room.result.cloud
            rows = np.empty(len(cloud), record)
            rows["xyz"] = room.xyz
            rows["rgb"] = cloud.rgb if cloud.rgb is not None else 128
            fh.write(rows.tobytes())
            written += len(rows)
        fh.seek(0)
        fh.write(_header(written))  # the same length: the count has fixed digits
    tmp.replace(path)
    return {
        "points": written,
        "rooms": rooms,
        "seconds": time.perf_counter() - t0,
        "bytes": path.stat().st_size,
        "peak_mb": _peak_mb(),
    }


# -- runs (each in its own subprocess) -----------------------------------------------------
def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def work_tiled(path: Path, workers: int, tile: float) -> dict:
    from ontodetect import detect_tiled
    from ontodetect._executor import open_executor

    with open_executor(workers=workers) as executor:
        t0 = time.perf_counter()
        result = detect_tiled(path, tile=tile, executor=executor, sample_points=SAMPLE)
        seconds = time.perf_counter() - t0
    per_worker: dict[str, int] = {}
    for t in result.tiles:
        per_worker[t.worker] = max(per_worker.get(t.worker, 0), t.peak_rss)
    return {
        "points": result.num_points,
        "seconds": seconds,
        "points_per_s": result.num_points / seconds,
        "survey_s": result.timings["survey"],
        "tiles_s": result.timings["tiles"],
        "tiles": len(result.tiles),
        "largest_window": max(t.points for t in result.tiles),
        "mean_window": float(np.mean([t.points for t in result.tiles])),
        "detections": len(result.detections),
        "merged": result.merged,
        "worker_peak_mb": max(per_worker.values()) / MB,
        "workers_seen": len(per_worker),
        "client_peak_mb": _peak_mb(),
        "labels": {
            k: sum(d.label == k for d in result.detections)
            for k in sorted({d.label for d in result.detections})
        },
    }


def work_untiled(path: Path) -> dict:
    from ontodetect import read_cloud
    from ontodetect.pipeline import detect

    t0 = time.perf_counter()
    cloud = read_cloud(path)
    result = detect(cloud, jobs=1)
    seconds = time.perf_counter() - t0
    return {
        "points": len(cloud),
        "seconds": seconds,
        "points_per_s": len(cloud) / seconds,
        "detections": len(result.detections),
        "peak_mb": _peak_mb(),
    }


def _run(args: list[str], timeout: float) -> dict:
    cmd = [sys.executable, "-m", "benchmarks.bench_tiled", "--worker", *args]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout after {timeout:.0f} s"}
    if out.returncode != 0:
        tail = (out.stderr.strip().splitlines() or ["?"])[-1]
        return {"error": f"failed ({tail[:120]})"}
    return json.loads(out.stdout.strip().splitlines()[-1])


# -- report --------------------------------------------------------------------------------
def _machine() -> str:
    cpu = platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import dask
    import distributed

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (
        f"{os.cpu_count()} CPUs ({cpu}), Python {platform.python_version()}, NumPy "
        f"{np.__version__}, Dask {dask.__version__}, distributed {distributed.__version__}; "
        f"load average {load:.1f} at the start"
    )


def _row(name: str, r: dict) -> str:
    if "error" in r:
        return f"| {name} | {r['error']} |||||||"
    return (
        f"| {name} | {r['points']:,} | {r['seconds']:.1f} | {r['points_per_s']:,.0f} "
        f"| {r.get('worker_peak_mb', r.get('peak_mb', 0)):,.0f} "
        f"| {r.get('client_peak_mb', float('nan')):,.0f} | {r.get('tiles', '-')} "
        f"| {r.get('largest_window', '-'):,} | {r['detections']} |"
        if "tiles" in r
        else f"| {name} | {r['points']:,} | {r['seconds']:.1f} | {r['points_per_s']:,.0f} "
        f"| {r['peak_mb']:,.0f} | - | - | - | {r['detections']} |"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=50_000_000)
    ap.add_argument("--points-per-room", type=int, default=250_000)
    ap.add_argument("--tile", type=float, default=20.0)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--baseline-points", type=int, default=5_000_000)
    ap.add_argument("--cache", type=Path, default=None)
    ap.add_argument("--timeout", type=float, default=7200.0)
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        kind, *rest = args.worker
        if kind == "generate":
            res = work_generate(int(rest[0]), int(rest[1]), Path(rest[2]))
        elif kind == "tiled":
            res = work_tiled(Path(rest[0]), int(rest[1]), float(rest[2]))
        else:
            res = work_untiled(Path(rest[0]))
        print(json.dumps(res))
        return 0

    cache = args.cache or Path(tempfile.mkdtemp(prefix="ontodetect-floor-"))
    cache.mkdir(parents=True, exist_ok=True)
    machine = _machine()
    files = {}
    for n in (args.points, args.baseline_points):
        path = floor_path(cache, n, args.points_per_room)
        if not path.exists():
            gen = _run(["generate", str(n), str(args.points_per_room), str(path)], args.timeout)
            print(f"generated {path.name}: {gen}", file=sys.stderr)
        files[n] = path
    rows = []
    for w in args.workers:
        r = _run(["tiled", str(files[args.points]), str(w), str(args.tile)], args.timeout)
        print(f"tiled {w} workers: {r}", file=sys.stderr)
        rows.append((f"tiled, {w} worker{'s' if w > 1 else ''}", r))
    small_tiled = _run(["tiled", str(files[args.baseline_points]), "1", str(args.tile)], 3600)
    small_whole = _run(["untiled", str(files[args.baseline_points])], 3600)
    print(f"baseline: {small_tiled} {small_whole}", file=sys.stderr)
    rows.append(("tiled, 1 worker (smaller floor)", small_tiled))
    rows.append(("untiled, one process", small_whole))

    lines = [
        f"Floor: {args.points:,} points ({args.points_per_room:,} a room), tile {args.tile:g} m, "
        f"overlap 2.5 m; {machine}.",
        "",
        "| run | points | seconds | points/s | peak RSS of a worker (MB) | client peak RSS (MB) "
        "| tiles | largest window (points) | detections |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
        *(_row(name, r) for name, r in rows),
    ]
    ok = [r for _, r in rows[: len(args.workers)] if "error" not in r]
    if len(ok) >= 2:
        lines.append(
            f"\nSpeed-up from {args.workers[0]} to {args.workers[1]} workers: "
            f"{ok[1]['points_per_s'] / ok[0]['points_per_s']:.2f}x."
        )
    if "error" not in small_tiled and "error" not in small_whole:
        lines.append(
            f"On the smaller floor the untiled run's peak memory is "
            f"{small_whole['peak_mb'] / small_tiled['worker_peak_mb']:.1f}x a tile worker's; "
            f"its speed {small_whole['points_per_s'] / small_tiled['points_per_s']:.2f}x the "
            "tiled run's on 1 worker."
        )
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
