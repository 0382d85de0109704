"""How fast ontodetect reads large binary point clouds.

Generates a cloud (xyz float32 + rgb uint8, 10 million points by default),
writes it as binary little-endian PLY and times

- ``numpy.fromfile`` of the same bytes with the vertex's structured type after
  the header: the floor of any reader that returns the file's records;
- :func:`ontodetect.read_cloud`, which also converts to float64 coordinates and
  uint8 colours (the row index is built only when first used);
- merely filling arrays of the size of that result, without touching any file,
  on one thread and on two (each filling half): lower bounds for every reader
  that returns a float64 cloud;
- ``open3d.io.read_point_cloud`` on the same file, the obvious alternative;

then writes the same cloud as PCL ``binary_compressed`` PCD and times reading it
back. Times are medians of ``--repeat`` rounds; each round runs every reader
once, one after the other, so that a change in the machine's load touches all
of them alike. On Linux a round starts only once the CPUs have been idle for
half a second (or ``--wait-idle`` seconds have passed), allocates and frees an
untimed block of memory first (see :func:`_warm_up`), and is run again if other
processes took more than a fifth of a CPU while it ran (see :func:`_rounds`).
Rounds are on a warm page cache (the files were just written) and, where the
system allows it, cold (the file's own pages evicted with ``posix_fadvise``
before each run). The share of the CPUs that other processes used during the
counted rounds is printed with the table. Peak memory is measured with
:mod:`tracemalloc` in a separate run, which sees NumPy's allocations. Prints a
Markdown table.

Run::

    python -m benchmarks io [--points 10000000] [--out DIR] [--repeat 5]
"""

from __future__ import annotations

import argparse
import itertools
import os
import platform
import statistics
import tempfile
import threading
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
#: The machine counts as idle when this share of its CPU time is idle...
IDLE_SHARE = 0.9
#: ...over this many seconds.
IDLE_WINDOW_S = 0.5
#: A round is run again when other processes kept more CPUs than this busy during it...
BUSY_CPUS = 0.2
#: ...up to this many times ``--repeat`` rounds in all.
MAX_TRIES = 3


def _cpu_jiffies() -> tuple[int, int] | None:
    """(idle, total) CPU time of the whole machine since boot, in ticks (Linux only)."""
    try:
        with open("/proc/stat") as fh:
            values = [int(v) for v in fh.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    return values[3] + values[4], sum(values)  # idle + iowait


def _wait_until_idle(limit_s: float) -> None:
    """Return once the CPUs were idle over a short window, or after ``limit_s``."""
    deadline = time.monotonic() + limit_s
    while time.monotonic() < deadline:
        before = _cpu_jiffies()
        time.sleep(IDLE_WINDOW_S)
        after = _cpu_jiffies()
        if before is None or after is None:
            return
        if (after[0] - before[0]) >= IDLE_SHARE * max(after[1] - before[1], 1):
            return


class _OthersLoad:
    """CPU time used by other processes while the timed runs go on."""

    def __init__(self) -> None:
        self.busy_s = 0.0
        self.wall_s = 0.0
        self.ticks = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100

    def measure(self, fn: Callable[[], Any]) -> tuple[float, Any]:
        jiffies, own = _cpu_jiffies(), os.times()
        start = time.perf_counter()
        result = fn()
        wall = time.perf_counter() - start
        after, own_after = _cpu_jiffies(), os.times()
        if jiffies is not None and after is not None:
            busy = ((after[1] - after[0]) - (jiffies[1] - jiffies[0])) / self.ticks
            mine = (own_after.user - own.user) + (own_after.system - own.system)
            self.busy_s += max(busy - mine, 0.0)
            self.wall_s += wall
        return wall, result

    def add(self, other: _OthersLoad) -> None:
        self.busy_s += other.busy_s
        self.wall_s += other.wall_s

    def share(self) -> float | None:
        """Average number of CPUs other processes kept busy during the runs."""
        return self.busy_s / self.wall_s if self.wall_s else None


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


def _warm_up(nbytes: int) -> None:
    """Allocate and write ``nbytes``, then free them.

    On a virtual machine whose host reclaims the guest's free memory (virtio
    free page reporting, a few seconds after it is freed), the first large
    allocation after a pause pays for the host giving the pages back: up to
    0.6 s for 300 MB on the machine of ``docs/benchmarks.md``, whoever allocates.
    Doing it here, untimed, keeps that cost out of the run that happens to come
    first in a round.
    """
    block = np.ones(nbytes, dtype=np.uint8)
    del block


def _rounds(
    runs: dict[str, Callable[[], Any]],
    repeat: int,
    wait_s: float,
    load: _OthersLoad,
    warm_up_bytes: int,
    cold: dict[str, Path] | None = None,
) -> tuple[dict[str, float], int]:
    """Median wall time of every run, in rounds that run each once, one after the other.

    A round during which other processes kept more than :data:`BUSY_CPUS` CPUs
    busy is set aside and run again, :data:`MAX_TRIES` x ``repeat`` rounds at
    most; set-aside rounds fill in only if too few quiet ones were seen. With
    ``cold``, a run's file is evicted from the page cache just before it.
    Returns the medians and the number of rounds set aside.
    """
    quiet: list[dict[str, float]] = []
    busy: list[tuple[dict[str, float], _OthersLoad]] = []
    while len(quiet) < repeat and len(quiet) + len(busy) < MAX_TRIES * repeat:
        _wait_until_idle(wait_s)
        _warm_up(warm_up_bytes)
        this = _OthersLoad()
        walls = {}
        for name, fn in runs.items():
            if cold is not None:
                _evict(cold[name])
            walls[name], result = this.measure(fn)
            del result  # free it before the next run allocates
        others = this.share()
        if others is not None and others > BUSY_CPUS:
            busy.append((walls, this))
            continue
        quiet.append(walls)
        load.add(this)
    for walls, this in busy[: repeat - len(quiet)]:
        quiet.append(walls)
        load.add(this)
    medians = {name: statistics.median(r[name] for r in quiet) for name in runs}
    return medians, len(busy)


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


def _fill(n: int, threads: int) -> Callable[[], Any]:
    """Allocate and write arrays shaped like the cloud (float64 xyz, uint8 rgb)."""

    def run() -> Any:
        xyz, rgb = np.empty((n, 3)), np.empty((n, 3), np.uint8)
        spans = list(itertools.pairwise(np.linspace(0, n, threads + 1).astype(int).tolist()))

        def part(lo: int, hi: int) -> None:
            xyz[lo:hi] = 1.0
            rgb[lo:hi] = 1

        workers = [threading.Thread(target=part, args=span) for span in spans[1:]]
        for w in workers:
            w.start()
        part(*spans[0])
        for w in workers:
            w.join()
        return xyz, rgb

    return run


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
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument(
        "--wait-idle",
        type=float,
        default=30.0,
        help="seconds to wait at most, before each round, for the CPUs to be idle",
    )
    parser.add_argument("--no-open3d", action="store_true", help="skip the Open3D timings")
    args = parser.parse_args(argv)
    n, repeat = args.points, args.repeat

    rng = np.random.default_rng(SEED)
    xyz = (rng.random((n, 3), dtype=np.float32) * ROOM.astype(np.float32)).astype(np.float64)
    rgb = rng.integers(0, 256, (n, 3), dtype=np.uint8)
    cloud = point_cloud(xyz, rgb=rgb, copy=False)
    del xyz, rgb
    load = _OthersLoad()

    with tempfile.TemporaryDirectory(dir=args.out) as tmp:
        folder = Path(tmp)
        ply, pcd = folder / "bench.ply", folder / "bench.pcd"
        start = time.perf_counter()
        write_ply(ply, cloud, dtype="float32")
        write_ply_s = time.perf_counter() - start
        start = time.perf_counter()
        write_pcd(pcd, cloud, data="binary_compressed")
        write_pcd_s = time.perf_counter() - start
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
        for path in (ply, pcd):
            got = read_cloud(path)
            if not (
                len(got) == n
                and np.array_equal(got.xyz, cloud.xyz)
                and np.array_equal(got.rgb, cloud.rgb)
            ):
                raise SystemExit(f"read_cloud did not return the points written to {path.name}")
            del got

        def fromfile() -> Any:
            return np.fromfile(ply, dtype=record, count=n, offset=offset)

        runs: dict[str, Callable[[], Any]] = {
            "`numpy.fromfile` (structured, PLY body)": fromfile,
            "filling the output arrays only (no file access)": _fill(n, 1),
            "filling the output arrays, two threads (no file access)": _fill(n, 2),
            "`read_cloud` binary PLY": lambda: read_cloud(ply),
            "`read_cloud` PCD binary_compressed": lambda: read_cloud(pcd),
        }
        files = {
            "`numpy.fromfile` (structured, PLY body)": ply,
            "`read_cloud` binary PLY": ply,
            "`read_cloud` PCD binary_compressed": pcd,
        }
        if not args.no_open3d:
            import open3d as o3d

            pc = o3d.io.read_point_cloud(str(ply))
            if len(pc.points) != n:
                raise SystemExit(f"Open3D read {len(pc.points)} points instead of {n}")
            del pc
            runs["`open3d.io.read_point_cloud` binary PLY"] = lambda: o3d.io.read_point_cloud(
                str(ply)
            )
            runs["`open3d.io.read_point_cloud` PCD binary_compressed"] = lambda: (
                o3d.io.read_point_cloud(str(pcd))
            )
            files["`open3d.io.read_point_cloud` binary PLY"] = ply
            files["`open3d.io.read_point_cloud` PCD binary_compressed"] = pcd
        # Enough for the largest run (the PCD reader holds the compressed data, the
        # decompressed bytes and the cloud).
        warm_up = 2 * (ply.stat().st_size + pcd.stat().st_size)
        warm, set_aside = _rounds(runs, repeat, args.wait_idle, load, warm_up)
        cold: dict[str, float] = {}
        if _evict(ply):
            cold_runs = {k: runs[k] for k in files}
            cold, more = _rounds(cold_runs, repeat, args.wait_idle, load, warm_up, files)
            set_aside += more
        peaks = {
            name: _peak_mb(runs[name])
            for name in runs
            if not name.startswith("`open3d")  # Open3D allocates outside Python
        }
        sizes = {"ply": ply.stat().st_size / MB, "pcd": pcd.stat().st_size / MB}

    base_name = "`numpy.fromfile` (structured, PLY body)"
    base_s, base_cold = warm[base_name], cold.get(base_name)
    ratio = warm["`read_cloud` binary PLY"] / base_s
    output_mb = n * (3 * 8 + 3) / MB
    print(
        f"Machine: {_cpu_model()}, {os.cpu_count()} logical CPUs; Python "
        f"{platform.python_version()}, NumPy {np.__version__}\n"
    )
    print(
        f"{n:,} points (xyz float32 + rgb uint8); binary PLY {sizes['ply']:.0f} MB "
        f"(written in {write_ply_s:.2f} s), binary_compressed PCD {sizes['pcd']:.0f} MB "
        f"(written in {write_pcd_s:.2f} s); the cloud in memory (float64 xyz, uint8 rgb) "
        f"is {output_mb:.0f} MB, plus {n * 8 / MB:.0f} MB once its row index is used. "
        f"Median of {repeat} rounds.\n"
    )
    print(
        "| reader | warm (s) | warm vs `fromfile` | cold (s) | cold vs `fromfile` "
        "| peak memory (MB) |"
    )
    print("|---|---:|---:|---:|---:|---:|")
    for name, warm_s in warm.items():
        cold_s = cold.get(name)
        if cold_s is None or base_cold is None:
            cold_txt = "- | -"
        else:
            cold_txt = f"{cold_s:.3f} | {cold_s / base_cold:.1f}x"
        peak = peaks.get(name)
        mem = "-" if peak is None else f"{peak:.0f}"
        print(f"| {name} | {warm_s:.3f} | {warm_s / base_s:.1f}x | {cold_txt} | {mem} |")
    if cold:
        print(
            "\nCold: the file's pages were evicted from the page cache "
            "(posix_fadvise DONTNEED) before each run."
        )
    others = load.share()
    if others is not None:
        print(
            f"\nOther processes kept {others:.2f} of the {os.cpu_count()} CPUs busy "
            f"on average during the rounds counted; {set_aside} rounds were set aside "
            f"and run again because they kept more than {BUSY_CPUS} busy."
        )
    verdict = "meets" if ratio <= TARGET_RATIO else "misses"
    print(
        f"\nread_cloud / numpy.fromfile = {ratio:.2f} ({verdict} the target of {TARGET_RATIO:.1f})"
    )
    return 0 if ratio <= TARGET_RATIO else 1


if __name__ == "__main__":
    raise SystemExit(main())
