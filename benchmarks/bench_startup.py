"""How fast the command line starts: ``--help``, ``--version`` and ``info`` on a small PLY.

Usage::

    .venv/bin/python -m benchmarks.bench_startup [--repeat 5] [--points 10000] [--src DIR]

Each command runs in a fresh interpreter (``python -m ontodetect ...``), ``--repeat``
times; the table gives the median and the range of the wall-clock times, and the
cumulative import time of ``ontodetect.cli`` from ``python -X importtime``. ``--src``
points at another source tree (``PYTHONPATH``) to compare two versions on one machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _run(cmd: list[str], env: dict[str, str]) -> tuple[float, bool]:
    start = time.perf_counter()
    done = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start, done.returncode == 0


def _import_ms(env: dict[str, str]) -> float:
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", "import ontodetect.cli"],
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    last = done.stderr.strip().splitlines()[-1]  # "import time: self | cumulative | name"
    return int(last.split("|")[1]) / 1000


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--src", type=Path, default=Path(__file__).parents[1] / "src")
    args = parser.parse_args(argv)
    env = {**os.environ, "PYTHONPATH": str(args.src.resolve())}
    with tempfile.TemporaryDirectory() as tmp:
        ply = Path(tmp) / "small.ply"
        rng = np.random.default_rng(0)
        points = rng.uniform(0, 4, (args.points, 3)).round(4)
        lines = "".join(f"{x} {y} {z}\n" for x, y, z in points)
        header = (
            f"ply\nformat ascii 1.0\nelement vertex {args.points}\n"
            "property float x\nproperty float y\nproperty float z\nend_header\n"
        )
        ply.write_text(header + lines)
        print(f"source: {args.src}, {args.repeat} runs each, python {sys.version.split()[0]}")
        print(f"import ontodetect.cli (cumulative, -X importtime): {_import_ms(env):.0f} ms\n")
        print("| command | median (s) | min–max (s) |")
        print("|---|---:|---:|")
        for what in (["--help"], ["--version"], ["info", str(ply)]):
            cmd = [sys.executable, "-m", "ontodetect", *what]
            runs = [_run(cmd, env) for _ in range(args.repeat)]
            times = [t for t, _ in runs]
            label = " ".join(what).replace(str(ply), f"small.ply ({args.points:,} points)")
            failed = "" if all(ok for _, ok in runs) else " (exit status not 0)"
            print(
                f"| `ontodetect {label}`{failed} | {statistics.median(times):.2f} "
                f"| {min(times):.2f}–{max(times):.2f} |"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
