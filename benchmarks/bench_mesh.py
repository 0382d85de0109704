"""How fast and lean the surface mesh is (``detect --mesh``), against Open3D's Poisson.

A simulated office scanned by the virtual laser scanner (``ontodetect.synth``) is
prepared once (:func:`ontodetect.preprocess.prepare`: levelled, denoised, voxel grid
average at 2 cm) and its voxel cloud saved; then each method meshes that voxel cloud in
its own subprocess, which reports its time (best of ``--repeat``) and its peak resident
memory above what loading the voxel cloud, NumPy, SciPy and Open3D took:

- **marching cubes**: :func:`ontodetect.preprocess.reconstruct_surface`, the default
  (sparse signed-distance grid at the scene's sampling spacing, normals from the 12
  nearest voxels turned to face a sensor 1.5 m above the middle of the room);
- **Open3D Poisson**: ``reconstruct_surface(method="poisson")``, the same normals,
  Open3D's ``create_from_point_cloud_poisson`` at the octree depth of the same cell
  (one thread, as the rest of a run), 5 % least supported vertices trimmed.

Both get the same points, cell and normal estimate (inside the timed region for both);
the report gives the ratios and the meshes' sizes. Prints a Markdown report and writes it
to ``--out``.

Run::

    python -m benchmarks mesh [--points 1000000] [--repeat 2] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SEED = 20161221
METHODS = ("marching_cubes", "poisson")


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def make_voxels(n: int, path: Path) -> dict:
    """Prepare an ``n``-point simulated office; save its voxel cloud to ``path`` (.npz)."""
    from ontodetect.preprocess import SENSOR_HEIGHT, prepare
    from ontodetect.synth import synthesize

    scan = synthesize("office", "tls", seed=SEED, points=n)
    prepared = prepare(scan.cloud)
    c = prepared.centers
    lo, hi = c.min(axis=0), c.max(axis=0)
    eye = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, SENSOR_HEIGHT])
    rgb = prepared.colors if prepared.colors is not None else np.zeros((len(c), 3), np.uint8)
    np.savez(path, xyz=c, rgb=rgb, eye=eye, cell=prepared.spacing)
    return {"points": len(scan.cloud), "voxels": len(c), "cell": float(prepared.spacing)}


def work(path: Path, method: str, repeat: int) -> dict:
    """Mesh the saved voxel cloud ``repeat`` times (run in a subprocess)."""
    import open3d  # noqa: F401 - both libraries loaded before the baseline, for both methods
    import scipy.spatial  # noqa: F401

    from ontodetect.preprocess import reconstruct_surface

    data = np.load(path)
    xyz, rgb, eye, cell = data["xyz"], data["rgb"], data["eye"], float(data["cell"])
    base = _peak_mb()
    times, mesh = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        mesh = reconstruct_surface(xyz, colors=rgb, cell=cell, method=method, viewpoint=eye)
        times.append(time.perf_counter() - t0)
    assert mesh is not None
    return {
        "method": method,
        "seconds": min(times),
        "peak_mb_above_input": _peak_mb() - base,
        "vertices": len(mesh.vertices),
        "triangles": len(mesh.triangles),
        "area": mesh.area,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks mesh", description=__doc__)
    ap.add_argument("--points", type=int, default=1_000_000, help="points of the scan")
    ap.add_argument("--repeat", type=int, default=2, help="runs per method (the best counts)")
    ap.add_argument("--out", type=Path, default=Path("bench-output/mesh.md"))
    ap.add_argument("--worker", nargs=2, metavar=("NPZ", "METHOD"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        print(json.dumps(work(Path(args.worker[0]), args.worker[1], args.repeat)))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        npz = Path(tmp) / "voxels.npz"
        scene = make_voxels(args.points, npz)
        rows = {}
        for method in METHODS:
            out = subprocess.run(
                [sys.executable, "-m", "benchmarks", "mesh", "--repeat", str(args.repeat),
                 "--worker", str(npz), method],
                check=True, capture_output=True, text=True,
            )  # fmt: skip
            rows[method] = json.loads(out.stdout.strip().splitlines()[-1])
    mc, po = rows["marching_cubes"], rows["poisson"]
    lines = [
        f"Simulated office, {scene['points']:,} points -> {scene['voxels']:,} voxels, "
        f"cell {scene['cell'] * 100:.1f} cm (best of {args.repeat})",
        "",
        "| method | time | peak memory above the input | vertices | triangles | area (m²) |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for r in (mc, po):
        lines.append(
            f"| {r['method']} | {r['seconds']:.2f} s | {r['peak_mb_above_input']:.0f} MB | "
            f"{r['vertices']:,} | {r['triangles']:,} | {r['area']:.1f} |"
        )
    lines += [
        "",
        f"Poisson / marching cubes: time x{po['seconds'] / mc['seconds']:.1f}, "
        f"memory x{po['peak_mb_above_input'] / max(mc['peak_mb_above_input'], 1.0):.1f}",
    ]
    report = "\n".join(lines)
    print(report)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(report + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
