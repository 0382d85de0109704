"""How fast ontodetect reads large binary point clouds.

Generates a cloud (xyz float32 + rgb uint8, 10 million points by default),
writes it as binary little-endian PLY and times

- ``numpy.fromfile`` of the same bytes with the vertex's structured type after
  the header: the floor of any reader that returns the file's records;
- :func:`ontodetect.read_cloud`, which also converts to float64 coordinates,
  uint8 colours and a row index;
- merely filling arrays of the size of that result, without touching any file:
  a lower bound for every reader that returns a float64 cloud;
- ``open3d.io.read_point_cloud`` on the same file, the obvious alternative;

then writes the same cloud as PCL ``binary_compressed`` PCD and times reading it
back. Times are medians of ``--repeat`` runs, on a warm page cache (the files
were just written) and, where the system allows it, cold (the file's own pages
evicted with ``posix_fadvise`` before each run). Peak memory is measured with
:mod:`tracemalloc` in a separate run, which sees NumPy's allocations. Prints a
Markdown table.

Run::

    python -m benchmarks.bench_io [--points 10000000] [--out DIR] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import tempfile
import time
import tracemalloc
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ontodetect import point_cloud, read_cloud
from ontodetect.io._pcd import write_pcd
from ontodetect.io._ply import write_ply

#: The target of the PLY reader: at most this many times ``numpy.fromfile``.
TARGET_RATIO = 2.0
SEED = 20161221
#: A room-sized box, in metres.
ROOM = np.array([10.0, 8.0, 3.0])
MB = 1 << 20


def _evict(path: Path) -> bool:
    """Drop one file's pages from the page cache (only that file); False if unsupported."""
    if not hasattr(os, "posix_fadvise"):
        return False
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
    finally:
        os.close(fd)
    return True


def _median_time(fn: Callable[[], Any], repeat: int, cold: Path | None = None) -> tuple[float, Any]:
    """Median wall time of ``fn``; with ``cold``, that file is evicted before each run."""
    times, result = [], None
    for _ in range(repeat):
        result = None  # free the previous result before timing the next run
        if cold is not None:
            _evict(cold)
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def _peak_mb(fn: Callable[[], Any]) -> float:
    tracemalloc.start()
    try:
        result = fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    del result
    return peak / MB


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def _ply_vertex_offset(path: Path) -> int:
    with open(path, "rb") as fh:
        head = fh.read(1 << 16)
    return head.index(b"end_header\n") + len(b"end_header\n")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the benchmark and print a Markdown table; returns 1 if the PLY target is missed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10_000_000)
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        help="folder for the generated files (default: a temporary folder)",
    )
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-open3d", action="store_true", help="skip the Open3D timings")
    args = parser.parse_args(argv)
    n, repeat = args.points, args.repeat

    rng = np.random.default_rng(SEED)
    xyz = (rng.random((n, 3), dtype=np.float32) * ROOM.astype(np.float32)).astype(np.float64)
    rgb = rng.integers(0, 256, (n, 3), dtype=np.uint8)
    cloud = point_cloud(xyz, rgb=rgb, copy=False)
    del xyz, rgb

    with tempfile.TemporaryDirectory(dir=args.out) as tmp:
        folder = Path(tmp)
        ply, pcd = folder / "bench.ply", folder / "bench.pcd"
        write_ply_s, _ = _median_time(lambda: write_ply(ply, cloud, dtype="float32"), 1)
        write_pcd_s, _ = _median_time(lambda: write_pcd(pcd, cloud, data="binary_compressed"), 1)
        offset = _ply_vertex_offset(ply)
        record = np.dtype(
            [
                ("x", "<f4"),
                ("y", "<f4"),
                ("z", "<f4"),
                ("red", "u1"),
                ("green", "u1"),
                ("blue", "u1"),
            ]
        )

        def fromfile() -> Any:
            return np.fromfile(ply, dtype=record, count=n, offset=offset)

        base_s, raw = _median_time(fromfile, repeat)
        del raw
        ours_s, got = _median_time(lambda: read_cloud(ply), repeat)
        if not (
            len(got) == n
            and np.array_equal(got.xyz, cloud.xyz)
            and np.array_equal(got.rgb, cloud.rgb)
        ):
            raise SystemExit("read_cloud did not return the points that were written")
        del got
        pcd_s, got = _median_time(lambda: read_cloud(pcd), repeat)
        if not np.array_equal(got.xyz, cloud.xyz):
            raise SystemExit("read_cloud did not return the PCD points that were written")
        del got
        can_evict = _evict(ply)
        # Each row: name, warm seconds, cold seconds (or None), peak MB (or None).
        rows: list[tuple[str, float, float | None, float | None]] = []

        def cold(fn: Callable[[], Any], path: Path) -> float | None:
            return _median_time(fn, repeat, cold=path)[0] if can_evict else None

        base_cold = cold(fromfile, ply)
        rows.append(
            ("`numpy.fromfile` (structured, PLY body)", base_s, base_cold, _peak_mb(fromfile))
        )

        def fill_outputs() -> Any:
            # What any reader returning a PointCloud must at least do: write its arrays.
            return (np.ones((n, 3)), np.ones((n, 3), np.uint8), np.arange(n, dtype=np.int64))

        rows.append(
            (
                "filling the output arrays only (no file access)",
                _median_time(fill_outputs, repeat)[0],
                None,
                _peak_mb(fill_outputs),
            )
        )
        rows.append(
            (
                "`read_cloud` binary PLY",
                ours_s,
                cold(lambda: read_cloud(ply), ply),
                _peak_mb(lambda: read_cloud(ply)),
            )
        )
        if not args.no_open3d:
            import open3d as o3d

            o3d_s, pc = _median_time(lambda: o3d.io.read_point_cloud(str(ply)), repeat)
            if len(pc.points) != n:
                raise SystemExit(f"Open3D read {len(pc.points)} points instead of {n}")
            del pc
            rows.append(
                (
                    "`open3d.io.read_point_cloud` binary PLY",
                    o3d_s,
                    cold(lambda: o3d.io.read_point_cloud(str(ply)), ply),
                    None,
                )
            )
        rows.append(
            (
                "`read_cloud` PCD binary_compressed",
                pcd_s,
                cold(lambda: read_cloud(pcd), pcd),
                _peak_mb(lambda: read_cloud(pcd)),
            )
        )
        if not args.no_open3d:
            o3d_pcd_s, pc = _median_time(lambda: o3d.io.read_point_cloud(str(pcd)), repeat)
            del pc
            rows.append(
                (
                    "`open3d.io.read_point_cloud` PCD binary_compressed",
                    o3d_pcd_s,
                    cold(lambda: o3d.io.read_point_cloud(str(pcd)), pcd),
                    None,
                )
            )
        sizes = {"ply": ply.stat().st_size / MB, "pcd": pcd.stat().st_size / MB}

    ratio = ours_s / base_s
    output_mb = n * (3 * 8 + 3 + 8) / MB
    print(
        f"Machine: {_cpu_model()}, {os.cpu_count()} logical CPUs; Python "
        f"{platform.python_version()}, NumPy {np.__version__}\n"
    )
    print(
        f"{n:,} points (xyz float32 + rgb uint8); binary PLY {sizes['ply']:.0f} MB "
        f"(written in {write_ply_s:.2f} s), binary_compressed PCD {sizes['pcd']:.0f} MB "
        f"(written in {write_pcd_s:.2f} s); the cloud in memory (float64 xyz, uint8 rgb, "
        f"int64 index) is {output_mb:.0f} MB. Median of {repeat} runs.\n"
    )
    print(
        "| reader | warm (s) | warm vs `fromfile` | cold (s) | cold vs `fromfile` "
        "| peak memory (MB) |"
    )
    print("|---|---:|---:|---:|---:|---:|")
    for name, warm, cold_s, peak in rows:
        if cold_s is None or base_cold is None:
            cold_txt = "- | -"
        else:
            cold_txt = f"{cold_s:.3f} | {cold_s / base_cold:.1f}x"
        mem = "-" if peak is None else f"{peak:.0f}"
        print(f"| {name} | {warm:.3f} | {warm / base_s:.1f}x | {cold_txt} | {mem} |")
    if base_cold is not None:
        print(
            "\nCold: the file's pages were evicted from the page cache "
            "(posix_fadvise DONTNEED) before each run."
        )
    verdict = "meets" if ratio <= TARGET_RATIO else "misses"
    print(
        f"\nread_cloud / numpy.fromfile = {ratio:.2f} ({verdict} the target of {TARGET_RATIO:.1f})"
    )
    return 0 if ratio <= TARGET_RATIO else 1


if __name__ == "__main__":
    raise SystemExit(main())
