"""Seeded fuzzing of every reader and the configuration, ontology and detections loaders.

Each case takes a valid seed file (every point-cloud format ontodetect writes, in its
variants, plus a configuration, an ontology and a detections.json), damages it one way
(a truncation, bit flips, a header number replaced by an extreme, a chunk repeated, Rich
markup or deep nesting inserted) and loads it in this process. A case ends as a
**success** (the loader returned), a **clean refusal** (an ``OntoDetectError`` with a
one-line message) or a **failure** (any other exception, a message of several lines, or
longer than ``--timeout`` seconds). Memory is bounded by the readers' budget, set low here
(``ONTODETECT_MAX_BYTES``, ``ONTODETECT_MAX_POINTS``).

    python -m benchmarks fuzz --cases 10000 --seed 0

The test suite runs a few hundred cases (tests/test_fuzz.py); ``ONTODETECT_FUZZ_CASES``
sets how many there.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
import time
import traceback
import warnings
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from ontodetect import point_cloud
from ontodetect.config import Config
from ontodetect.errors import OntoDetectError
from ontodetect.io import read_cloud, write_cloud
from ontodetect.io._detections import read_detections
from ontodetect.ontology._schema import read_ontology_file

#: Budgets the readers see while fuzzing: small, so that a lie is refused, not honoured.
FUZZ_BUDGET = {"ONTODETECT_MAX_BYTES": str(256 * 2**20), "ONTODETECT_MAX_POINTS": "2000000"}

#: Numbers a header lie puts in place of one of the file's own.
EXTREMES = (
    b"0",
    b"-1",
    b"4294967295",
    b"2147483648",
    b"99999999999999999999",
    b"1e308",
    b"nan",
    b"-inf",
    b"[/x]",
    b"",
)

_NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


@dataclass
class Outcome:
    """Counts of one fuzz run, and the first few failures with their tracebacks."""

    cases: int = 0
    kinds: Counter = field(default_factory=Counter)
    by_seed: dict[str, Counter] = field(default_factory=dict)
    failures: list[str] = field(default_factory=list)

    def add(self, seed: str, kind: str, detail: str | None = None) -> None:
        self.cases += 1
        self.kinds[kind] += 1
        self.by_seed.setdefault(seed, Counter())[kind] += 1
        if kind == "failure" and detail is not None and len(self.failures) < 20:
            self.failures.append(f"{seed}: {detail}")

    def table(self) -> str:
        kinds = ("refused", "success", "failure")
        rows = [f"| seed file | {' | '.join(kinds)} |", "|---|" + "---:|" * len(kinds)]
        for seed, c in sorted(self.by_seed.items()):
            rows.append(f"| {seed} | " + " | ".join(str(c[k]) for k in kinds) + " |")
        rows.append("| **all** | " + " | ".join(f"**{self.kinds[k]}**" for k in kinds) + " |")
        return "\n".join(rows)


def _cloud(n: int = 300, seed: int = 0):
    rng = np.random.default_rng(seed)
    xyz = rng.uniform(0, 4, (n, 3))
    rgb = rng.integers(0, 256, (n, 3), dtype=np.uint8)
    return point_cloud(xyz, rgb=rgb, fields={"label": rng.integers(0, 5, n).astype(np.int32)})


def seed_files(folder: Path) -> dict[str, tuple[Path, Callable[[Path], object]]]:
    """Valid files to damage: name -> (file, loader)."""
    cloud = _cloud()
    out: dict[str, tuple[Path, Callable[[Path], object]]] = {}
    variants = [
        ("ascii.ply", {"ascii": True}),
        ("binary.ply", {}),
        ("ascii.pcd", {"data": "ascii"}),
        ("binary.pcd", {"data": "binary"}),
        ("compressed.pcd", {"data": "binary_compressed"}),
        ("points.xyz", {}),
        ("points.csv", {}),
        ("points.npy", {}),
        ("points.npz", {}),
        ("points.las", {}),
        ("points.laz", {}),
    ]
    for name, options in variants:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # formats that cannot keep the label field
            path = write_cloud(folder / name, cloud, **options)
        out[name] = (path, read_cloud)
    config = folder / "config.yaml"
    Config().to_yaml(config)
    out["config.yaml"] = (config, Config.from_yaml)
    onto = folder / "ontology.yaml"
    onto.write_text(
        resources.files("ontodetect").joinpath("data/furniture.yaml").read_text("utf-8")
    )
    out["ontology.yaml"] = (onto, read_ontology_file)
    det = folder / "detections.json"
    det.write_text(
        '{"format": "ontodetect.detections/1", "num_points": 10, "frame": {"up": [0, 0, 1]},'
        ' "detections": [{"id": 1, "label": "chair", "score": 0.9, "box": {"center": [1, 2,'
        ' 0.5], "size": [0.5, 0.5, 1], "yaw": 0.1}, "point_indices": [1, 2, 3], "parts":'
        ' [{"name": "seat", "normal": [0, 0, 1], "centroid": [1, 2, 0.45]}]}]}\n'
    )
    out["detections.json"] = (det, read_detections)
    return out


def mutate(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    """One damaged copy of ``data`` and the name of what was done."""
    kind = rng.choice(["truncate", "flip", "lie", "repeat", "markup", "nest"])
    n = len(data)
    if kind == "truncate":
        return kind, data[: int(rng.integers(0, n))]
    if kind == "flip":
        buf = bytearray(data)
        # Most damage near the front, where the headers are.
        for _ in range(int(rng.integers(1, 9))):
            at = (
                int(min(n - 1, rng.exponential(256)))
                if rng.random() < 0.7
                else int(rng.integers(0, n))
            )
            buf[at] ^= 1 << int(rng.integers(0, 8))
        return kind, bytes(buf)
    if kind == "lie":
        head = data[:2048]
        numbers = list(_NUMBER.finditer(head))
        if not numbers:
            return "flip", mutate(data, rng)[1]
        m = numbers[int(rng.integers(0, len(numbers)))]
        value = EXTREMES[int(rng.integers(0, len(EXTREMES)))]
        return kind, data[: m.start()] + value + data[m.end() :]
    if kind == "repeat":
        a = int(rng.integers(0, n))
        b = min(n, a + int(rng.integers(1, 4096)))
        return kind, data[:b] + data[a:b] * int(rng.integers(1, 50)) + data[b:]
    if kind == "markup":
        at = int(rng.integers(0, min(n, 512)))
        return kind, data[:at] + b"[/x][bold]" + data[at:]
    at = int(rng.integers(0, n))
    depth = int(rng.integers(50, 5000))
    return kind, data[:at] + b"[" * depth + b"]" * depth + data[at:]


def run_cases(cases: int, seed: int = 0, timeout: float = 10.0) -> Outcome:
    """Run ``cases`` fuzz cases, seeded; the counts and the first failures."""
    outcome = Outcome()
    saved = {k: os.environ.get(k) for k in FUZZ_BUDGET}
    os.environ.update(FUZZ_BUDGET)
    try:
        with tempfile.TemporaryDirectory(prefix="ontodetect-fuzz-") as tmp:
            folder = Path(tmp)
            seeds = seed_files(folder)
            names = sorted(seeds)
            originals = {name: seeds[name][0].read_bytes() for name in names}
            rng = np.random.default_rng(seed)
            for k in range(cases):
                name = names[k % len(names)]
                path, load = seeds[name]
                what, data = mutate(originals[name], rng)
                target = folder / f"case{k % 7}-{path.name}"
                target.write_bytes(data)
                start = time.perf_counter()
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        load(target)
                    kind, detail = "success", None
                except OntoDetectError as exc:
                    one_line = "\n" not in str(exc) and str(exc).strip() != ""
                    kind = "refused" if one_line else "failure"
                    detail = f"{what}: message of several lines: {exc!s:.300}"
                except Exception as exc:  # counting what escapes is the point
                    kind = "failure"
                    detail = f"{what}: {type(exc).__name__}: {exc!s:.200}\n" + "".join(
                        traceback.format_exception(exc)[-3:]
                    )
                elapsed = time.perf_counter() - start
                if elapsed > timeout:
                    kind, detail = "failure", f"{what}: took {elapsed:.1f} s"
                outcome.add(name, kind, detail)
                target.unlink()
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return outcome


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks fuzz", description=__doc__)
    parser.add_argument("--cases", type=int, default=2000, help="How many cases (default 2000).")
    parser.add_argument("--seed", type=int, default=0, help="Seed of the mutations.")
    parser.add_argument("--timeout", type=float, default=10.0, help="Seconds a case may take.")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    outcome = run_cases(args.cases, args.seed, args.timeout)
    print(
        f"{outcome.cases} cases in {time.perf_counter() - start:.0f} s (seed {args.seed}): "
        f"{outcome.kinds['refused']} clean refusals, {outcome.kinds['success']} successes, "
        f"{outcome.kinds['failure']} failures\n"
    )
    print(outcome.table())
    for failure in outcome.failures:
        print("\n" + failure)
    return 1 if outcome.kinds["failure"] else 0


if __name__ == "__main__":
    sys.exit(main())
