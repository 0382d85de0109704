"""How long the simulator takes to make and write scans, from a unit-test room to a 10M-point scan.

Usage::

    .venv/bin/python -m benchmarks.bench_synth [--tls-points 10000000] [--out DIR]

Prints a Markdown table: for each case the number of points, the time of
:func:`ontodetect.synth.synthesize` and of :func:`ontodetect.synth.write_synth`
(median of ``--repeat`` runs for the small cases, one run for the large ones),
the size of the folder written, and the peak resident memory of the process
after the case.
"""

from __future__ import annotations

import argparse
import resource
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from ontodetect.synth import synthesize, write_synth


def _peak_mb() -> float:
    # ru_maxrss is in kilobytes on Linux.
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _folder_mb(folder: Path) -> float:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file()) / 2**20


def run_case(room: str, sensor: str, points: int | None, repeat: int, out: Path) -> dict:
    synth_times, write_times = [], []
    for k in range(repeat):
        start = time.perf_counter()
        result = synthesize(room, sensor, seed=1, points=points)
        synth_times.append(time.perf_counter() - start)
        folder = out / f"{room}-{sensor}-{k}"
        start = time.perf_counter()
        write_synth(result, folder)
        write_times.append(time.perf_counter() - start)
        size = _folder_mb(folder)
        shutil.rmtree(folder)
    return {
        "case": f"{room} {sensor}" + (f" (points={points:,})" if points else " (defaults)"),
        "points": len(result.cloud),
        "synthesize": statistics.median(synth_times),
        "write": statistics.median(write_times),
        "size": size,
        "peak": _peak_mb(),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tls-points", type=int, default=10_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None, help="scratch folder (default: temp)")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="bench_synth_"))
    out.mkdir(parents=True, exist_ok=True)
    cases = [
        ("tiny", "rgbd", 10_000, args.repeat),
        ("office", "rgbd", None, args.repeat),
        ("office", "rgbd", 1_000_000, 1),
        ("office", "rgbd-frame", None, args.repeat),
        ("bedroom", "monocular", None, 1),
        ("conference", "tls", None, 1),
        ("conference", "tls", args.tls_points, 1),
    ]
    rows = [run_case(room, sensor, points, rep, out) for room, sensor, points, rep in cases]
    print("| case | points | synthesize (s) | write (s) | folder (MB) | peak RSS so far (MB) |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in rows:
        print(
            f"| {r['case']} | {r['points']:,} | {r['synthesize']:.2f} | {r['write']:.2f} "
            f"| {r['size']:.1f} | {r['peak']:.0f} |"
        )
    if args.out is None:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
