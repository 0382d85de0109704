"""Chairs found in single frames stored as bare points, against the same frames with their
metadata (docs/benchmarks.md, "A depth frame stored as bare points").

Every frame of a generated set (``ontodetect synth ... --sensor rgbd-frame``, or the
generalization benchmark's frames set) is detected three ways: as stored, with its sensor's
position and pixel grid; moved so that its sensor is at the origin and stored with its
coordinates and colours only, with ``detect.infer_view`` off (a bare frame as it was
taken before); and the same bare frame with ``detect.infer_view`` on. ``--points N ...``
adds the bare frame cut to N points drawn at random (seed 0), as VoteNet stores SUN RGB-D's
frames (50,000 points; 20,000 in its training). The chair detections
are matched to the chair instances of at least 50 points at point IoU 0.25
(``ontodetect.evaluation.match_instances``: one to one, best score first).

    python scripts/bare_frames.py FRAMES_DIR [--jobs 2] [--points 50000 20000]
"""

from __future__ import annotations

import argparse
import functools
import warnings
from multiprocessing import Pool
from pathlib import Path

import numpy as np

MIN_POINTS = 50
IOU = 0.25
WAYS = {
    "with metadata": [],
    "bare, as before": ["detect.infer_view=false"],
    "bare, taken as one view": [],
}


def _chairs_found(result, instance, chairs) -> tuple[int, int]:
    from ontodetect.evaluation import Instance, match_instances

    dets = [
        Instance.make(d.id, "chair", d.point_indices, d.score)
        for d in result.detections
        if d.label == "chair"
    ]
    gts = [Instance.make(i, "chair", np.flatnonzero(instance == i)) for i in sorted(chairs)]
    found = match_instances(dets, gts, iou_threshold=IOU).pred_match
    return int((found >= 0).sum()), len(dets)


def one_frame(
    folder: str, points: tuple[int, ...] = ()
) -> tuple[str, int, dict[str, tuple[int, int]]]:
    warnings.simplefilter("ignore")
    from ontodetect import point_cloud
    from ontodetect.config import Config
    from ontodetect.pipeline import detect
    from ontodetect.synth import load_synth

    cloud, objects, _ = load_synth(folder)
    eye = np.asarray(cloud.meta["sensor_position"], dtype=np.float64)
    instance = np.asarray(cloud.fields["instance"])
    chairs = {
        int(o["id"])
        for o in objects
        if o["class"] == "chair" and int((instance == int(o["id"])).sum()) >= MIN_POINTS
    }
    bare = point_cloud(np.asarray(cloud.xyz) - eye, rgb=cloud.rgb)
    out = {}
    for way, sets in WAYS.items():
        c = cloud if way == "with metadata" else bare
        result = detect(c, config=Config().with_overrides(sets), seed=0, jobs=1)
        out[way] = _chairs_found(result, instance, chairs)
    for n in points:
        rows = np.arange(len(bare))
        if n < len(bare):
            rows = np.sort(np.random.default_rng(0).choice(len(bare), n, replace=False))
        cut = point_cloud(bare.xyz[rows], rgb=bare.rgb[rows])  # rows 0..n-1, as stored
        result = detect(cut, seed=0, jobs=1)
        out[_way(n)] = _chairs_found(result, instance[rows], chairs)
    return Path(folder).name, len(chairs), out


def _way(points: int) -> str:
    return f"bare, {points:,} points at random, taken as one view"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("frames", help="a folder of generated frames (each with scene.json)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--points", type=int, nargs="*", default=[], help="also cut to N points")
    args = ap.parse_args()
    folders = sorted(str(p.parent) for p in Path(args.frames).glob("*/scene.json"))
    totals = {way: [0, 0] for way in [*WAYS, *map(_way, args.points)]}
    gt = 0
    with Pool(max(1, args.jobs)) as pool:
        work = functools.partial(one_frame, points=tuple(args.points))
        for _, chairs, found in pool.imap_unordered(work, folders):
            gt += chairs
            for way, (tp, det) in found.items():
                totals[way][0] += tp
                totals[way][1] += det
    print(f"{len(folders)} frames, {gt} chairs of {MIN_POINTS} points or more")
    for way, (tp, det) in totals.items():
        print(f"{way}: {tp}/{det}")


if __name__ == "__main__":
    main()
