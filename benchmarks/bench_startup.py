"""How long the command line takes to start: --help, --version and info on a small PLY.

Each command runs as a whole new process (``python -m ontodetect ...``), as a user
starts it, ``--repeat`` times; the table gives the minimum, median and maximum wall
time. Beside them, in the same run, the floors and the obvious alternative:

- ``python -c pass``: the interpreter alone, which no command can beat;
- ``python -c "import numpy"``: what any command that reads a cloud needs;
- ``python -c "import open3d"``: what a tool built directly on Open3D pays before
  it does anything (the obvious alternative to a lazily importing CLI).

The ratio column is each command's median over the interpreter's. Runs alternate
between the commands so that a change in the machine's load touches all alike.
Also gives the cumulative import time of ``ontodetect.cli`` (``python -X importtime``) and
lists which heavy libraries it loads (none should). ``--src`` points at another source tree
(``PYTHONPATH``) to measure another version on the same machine, for before/after figures.

Run::

    python -m benchmarks startup [--repeat 9] [--target 0.3] [--src DIR]
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

#: The target of issue "set-up": --help, --version and info start in under this (s).
TARGET_SECONDS = 0.3
HEAVY = ("open3d", "matplotlib", "trimesh", "laspy", "sklearn", "scipy.spatial", "dask")


def _small_ply(folder: Path) -> Path:
    """A 1,000-point ASCII PLY written without importing the library under test."""
    path = folder / "small.ply"
    lines = [
        "ply",
        "format ascii 1.0",
        "element vertex 1000",
        "property float x",
        "property float y",
        "property float z",
        "end_header",
    ]
    lines += [
        f"{i % 10 * 0.1:.3f} {i // 10 % 10 * 0.1:.3f} {i // 100 * 0.1:.3f}" for i in range(1000)
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


def _time(cmd: list[str], env: dict[str, str]) -> float:
    start = time.perf_counter()
    done = subprocess.run(
        cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=False
    )
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {done.stderr.decode(errors='replace')[-400:]}")
    return elapsed


def heavy_modules_on_import(env: dict[str, str]) -> list[str]:
    """Heavy libraries a fresh interpreter holds after ``import ontodetect.cli``."""
    code = f"import sys, ontodetect.cli; print(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return out.stdout.split()


def import_ms(env: dict[str, str]) -> float:
    """Cumulative import time (ms) of ``ontodetect.cli`` in a fresh interpreter."""
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
    parser.add_argument("--repeat", type=int, default=9, help="runs of each command")
    parser.add_argument("--target", type=float, default=TARGET_SECONDS, help="target (s)")
    parser.add_argument(
        "--src", type=Path, default=Path(__file__).parents[1] / "src", help="source tree"
    )
    args = parser.parse_args(argv)
    py = sys.executable
    env = {**os.environ, "PYTHONPATH": str(args.src.resolve())}
    with tempfile.TemporaryDirectory() as tmp:
        ply = _small_ply(Path(tmp))
        commands = {
            "python -c pass (floor)": [py, "-c", "pass"],
            "python -c 'import numpy'": [py, "-c", "import numpy"],
            "python -c 'import open3d' (alternative)": [py, "-c", "import open3d"],
            "ontodetect --help": [py, "-m", "ontodetect", "--help"],
            "ontodetect --version": [py, "-m", "ontodetect", "--version"],
            "ontodetect info small.ply": [py, "-m", "ontodetect", "info", str(ply)],
        }
        times: dict[str, list[float]] = {name: [] for name in commands}
        for name, cmd in commands.items():  # one untimed run each: page cache, .pyc files
            try:
                _time(cmd, env)
            except SystemExit as exc:
                print(f"skipping {name}: {exc}", file=sys.stderr)
                times.pop(name)
        for _ in range(args.repeat):
            for name in times:
                times[name].append(_time(commands[name], env))
    floor = statistics.median(times["python -c pass (floor)"])
    print(f"Start-up, {args.repeat} runs each, whole processes (s); target {args.target:g} s\n")
    print("| command | min | median | max | median / interpreter |")
    print("|---|---:|---:|---:|---:|")
    for name, t in times.items():
        med = statistics.median(t)
        print(f"| {name} | {min(t):.3f} | {med:.3f} | {max(t):.3f} | {med / floor:.1f} |")
    print(f"\n`import ontodetect.cli`: {import_ms(env):.0f} ms cumulative (python -X importtime)")
    heavy = heavy_modules_on_import(env)
    print(f"heavy libraries loaded by `import ontodetect.cli`: {', '.join(heavy) or 'none'}")
    slow = [
        n for n in times if n.startswith("ontodetect") and statistics.median(times[n]) > args.target
    ]
    if slow:
        print(f"over the {args.target:g} s target: {', '.join(slow)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
