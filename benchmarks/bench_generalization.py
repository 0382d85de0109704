"""Generalization: real development scans, simulated furnished rooms, stability, robustness.

Run as ``python -m benchmarks generalization --real DIR [--out DIR] [--jobs 2] [--quick]``.
Six measurements, (a), (b), (c) and (e) at point IoU 0.25 and 0.5, (d) and (f) at 0.25
(docs/benchmarks.md, "Generalization benchmark"):

(a) **real**: precision and recall per class on the labelled scans in ``--real`` (ScanNet,
    VoteNet layout), with ``ontodetect.evaluation.evaluate_dataset``, and what the false
    detections really are;
(b) **simulated**: the same on a fixed set of furnished rooms (room types x seeds, an RGB-D
    walk fused on a 1.5 cm grid and sampled to 50,000 points as ScanNet's files were, some
    with a drifted second floor layer, holes or a tilt, some single RGB-D frames), generated
    once and cached in ``--out`` under a hash of the generator's settings and sources; broken
    down by room type, by sensor/artefact, by furniture family (recall of the ground-truth
    objects of each kind) and by what each false detection really is;
(c) **stability**: on a few real and simulated scans, the share of the detections on the
    scan as is that reappear (same label, point IoU >= 0.5 over the original rows) after a
    turn about the vertical, a large offset, 1 mm rounding, 0.5 mm jitter, a shuffle and an
    80 % subsample;
(d) **robustness**: precision and recall on the real scans again after what sensors and
    pipelines do to scans (1 cm of noise, most of the floor unseen, every point twice, half
    the points: a room twice the size in as many points), each copy scored against its own
    labels;
(e) **frames**: precision and recall on single RGB-D frames of the simulated rooms (every
    room type x 7 seeds, one frame each, the sensor's position known), as SUN RGB-D's
    frames and a robot's camera see a room, broken down as the simulated set is;
(f) **sparse**: the fused scans of (b) again with half and a quarter of their points, as
    ScanNet's files sample rooms twice and four times their size (50,000 points whatever
    the room): the sparse rooms (d) measures on 26 real chairs, on the simulated set's.

The simulated rooms come from ``ontodetect.synth.furnished.furnished_scene`` (Sweet Home 3D
catalogue furniture) when that module exists, else from the parametric rooms of
``ontodetect.synth.build_room``, with a warning; the JSON says which. Prints Rich tables and
writes everything to ``--out/generalization.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import hashlib
import json
import math
import sys
import time
import warnings
import zlib
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

from benchmarks._generalization import (
    MISSED_CAUSES,
    POOLED,
    STABILITY_IOU,
    STABILITY_TURNS,
    class_figures,
    false_detection_causes,
    instance_names,
    lost_references,
    missed_causes,
    pooled_orientations,
    recall_by_group,
    robustness_changes,
    rows_to_values,
    stability_transforms,
)
from ontodetect import __version__
from ontodetect.cloud import DataWarning
from ontodetect.config import Config
from ontodetect.errors import InvalidParameterError, OntoDetectError
from ontodetect.evaluation import (
    DatasetEvaluation,
    Evaluation,
    Instance,
    SceneOutcome,
    SceneSource,
    discover_scenes,
    evaluate_dataset,
    evaluate_scenes,
    evaluation_classes,
    first_pass_clusters,
    first_pass_lacks,
    instances_from_labels,
    load_scene,
    map_scenes,
    match_instances,
)

#: Format tag of generalization.json.
FORMAT = "ontodetect.bench.generalization/1"
#: The two point-IoU thresholds every figure is given at (DESIGN.md).
THRESHOLDS = {"iou@0.25": 0.25, "iou@0.5": 0.5}
#: Evaluated classes, in the order of the tables.
CLASSES = ("chair", "sofa", "table")
#: At least this many furnished rooms in the simulated set (fused scans, one per room).
MIN_ROOMS = 60
#: Seeds per room type: at least 7, more when there are few types (ceil(60 / types)).
MIN_SEEDS = 7
#: Fused RGB-D walk averaged on this grid (m) stands in for ScanNet's reconstructed mesh,
#: whose vertices VoteNet's files sample: ~1.5 cm apart, 250-350k points in a 20 m² room.
DENSE_VOXEL = 0.015
#: Options of the ``rgbd`` sensor for the dense fused scan (its defaults otherwise: 24 frames).
DENSE_SCAN: dict[str, Any] = {"voxel": DENSE_VOXEL}
#: Points of a ScanNet-like scan and of a single frame (the frame's stride comes closest).
POINTS = 50_000
#: Variants of a room's scan: name -> (sensor, artefacts applied to the dense fused scan).
VARIANTS: dict[str, tuple[str, tuple[str, ...]]] = {
    "fused": ("rgbd", ()),
    "floor-layer": ("rgbd", ("duplicate_floor_layer",)),
    "holes": ("rgbd", ("punch_holes",)),
    "tilt": ("rgbd", ("tilt",)),
    "frame": ("rgbd-frame", ()),
}
#: Which seed of every room type is also scanned with each extra variant.
VARIANT_SEED = {"floor-layer": 0, "holes": 1, "tilt": 2, "frame": 3}
#: (e) frames: every room type seen in one single RGB-D frame for each of this many seeds
#: (the simulated set has one frame per room type, seed 3's, too few to measure single
#: views by: 26 chairs).
FRAME_SEEDS = 7
#: The measurements ``--only`` chooses from, in the order they run.
PARTS = ("real", "robustness", "frames", "sim", "sparse", "stability")
#: (f) sparse: the changes of :func:`robustness_changes` made to the simulated fused scans.
SPARSE_CHANGES = ("half the points", "a quarter of the points")
#: Stability: real and simulated scans (those with the most objects), and in --quick.
STABILITY_SCANS = 3
QUICK_STABILITY_TURNS = (90.0, 30.0)
#: Parametric room types used when the furnished rooms are not available ("tiny" is a test room).
PARAMETRIC_ROOMS = (
    "office",
    "conference",
    "living_room",
    "home_office",
    "dining_room",
    "bedroom",
    "kitchen",
    "corridor",
)

#: Tables are wide; a pipe or a file gets this many columns instead of Rich's 80.
WIDTH = 160
console = Console(highlight=False, width=None if sys.stdout.isatty() else WIDTH)
err = Console(stderr=True, highlight=False)


# -- where the simulated rooms come from ---------------------------------------------------
def _parametric_scene(room: str, seed: int) -> Any:
    from ontodetect.synth import build_room

    return build_room(room, seed)


def _furnished_scene(room: str, seed: int) -> Any:
    from ontodetect.synth.furnished import furnished_scene

    return furnished_scene(room, seed)


#: Scene source name -> ``build(room_type, seed) -> Scene``.
GENERATORS: dict[str, Callable[[str, int], Any]] = {
    "furnished": _furnished_scene,
    "parametric": _parametric_scene,
}


@dataclass(frozen=True)
class RoomSource:
    """Where the simulated rooms come from: a :data:`GENERATORS` name and its room types."""

    name: str
    room_types: tuple[str, ...]
    note: str


def room_source(prefer: str = "furnished") -> RoomSource:
    """The furnished Sweet Home 3D rooms when ``ontodetect.synth.furnished`` exists, else the
    parametric rooms, with a warning on stderr."""
    if prefer == "furnished":
        try:
            from ontodetect.synth.furnished import FURNISHED_ROOM_TYPES
        except ImportError as exc:
            note = (
                f"ontodetect.synth.furnished is not available ({exc}); the simulated set uses "
                "the parametric rooms of ontodetect.synth.build_room instead"
            )
            err.print(f"[yellow]warning:[/] {note}")
            return RoomSource("parametric", PARAMETRIC_ROOMS, note)
        return RoomSource(
            "furnished", tuple(FURNISHED_ROOM_TYPES), "Sweet Home 3D catalogue furniture"
        )
    return RoomSource("parametric", PARAMETRIC_ROOMS, "parametric rooms (build_room)")


@dataclass(frozen=True)
class SimScan:
    """One scan of the simulated set: a room (type, seed) seen by one variant."""

    room: str
    seed: int
    variant: str

    @property
    def name(self) -> str:
        return f"{self.room}-s{self.seed}-{self.variant}"


def simulated_set(
    room_types: Sequence[str], *, quick: bool = False, first_seed: int = 0
) -> list[SimScan]:
    """The fixed list of simulated scans: every room fused, some rooms also with variants.

    Full: ``max(7, ceil(60 / types))`` seeds of every type, fused; seed 0 of every type also
    with a second floor layer, seed 1 with holes, seed 2 tilted and seed 3 as a single
    frame. Quick: seed 0 of up to four types, fused, and one type per extra variant. Every
    seed counts from ``first_seed`` (``--sim-seeds``): other rooms of the same kinds.

    Examples
    --------
    >>> [s.name for s in simulated_set(["office"], first_seed=7)][:2]
    ['office-s7-fused', 'office-s8-fused']
    """
    types = list(room_types)
    if quick:
        types = types[:4]
        scans = [SimScan(r, first_seed, "fused") for r in types]
        for k, variant in enumerate(VARIANT_SEED):
            scans.append(SimScan(types[k % len(types)], first_seed, variant))
        return scans
    seeds = max(MIN_SEEDS, math.ceil(MIN_ROOMS / len(types)))
    scans = [SimScan(r, first_seed + s, "fused") for r in types for s in range(seeds)]
    for variant, seed in VARIANT_SEED.items():
        scans += [SimScan(r, first_seed + seed, variant) for r in types]
    return scans


def frames_set(
    room_types: Sequence[str], *, quick: bool = False, first_seed: int = 0
) -> list[SimScan]:
    """The fixed list of single frames of (e): seeds ``first_seed`` to ``first_seed +
    FRAME_SEEDS - 1`` of every room type, one RGB-D frame each (quick: the first seed of two
    types)."""
    types = list(room_types)
    if quick:
        return [SimScan(r, first_seed, "frame") for r in types[:2]]
    return [SimScan(r, first_seed + s, "frame") for r in types for s in range(FRAME_SEEDS)]


def _source_digest() -> str:
    """Digest of the simulator's sources and class tables: a changed generator makes a new
    cache."""
    import ontodetect.synth

    synth = Path(ontodetect.synth.__file__).parent
    files = sorted(synth.glob("*.py")) + sorted((synth.parent / "data").glob("sh3d*"))
    h = hashlib.sha256()
    for path in files:
        h.update(path.name.encode() + b"\0" + path.read_bytes())
    return h.hexdigest()[:16]


def _catalogues(source: RoomSource) -> list[list[Any]]:
    """Name, size and modification time of every furniture catalogue the furnished rooms read."""
    if source.name != "furnished":
        return []
    try:
        from ontodetect.synth.sh3d import default_catalog_dir

        folder = default_catalog_dir()
    except (ImportError, OntoDetectError):
        return []  # furnished_scene will say what is missing when it runs
    return [
        [p.name, p.stat().st_size, int(p.stat().st_mtime)] for p in sorted(folder.glob("*.sh3f"))
    ]


def cache_key(source: RoomSource, scans: Sequence[SimScan]) -> dict[str, Any]:
    """Everything the simulated set depends on; its hash names the cache folder."""
    return {
        "generator": source.name,
        "room_types": list(source.room_types),
        "scans": [s.name for s in scans],
        "variants": {k: [v[0], list(v[1])] for k, v in VARIANTS.items()},
        "dense_scan": DENSE_SCAN,
        "points": POINTS,
        "ontodetect": __version__,
        "synth_sources": _source_digest(),
        "catalogues": _catalogues(source),
    }


def _artefact_rng(scan: SimScan) -> np.random.Generator:
    return np.random.default_rng([scan.seed, zlib.crc32(scan.name.encode())])


def generate_scan(unit: tuple[str, SimScan, str]) -> dict[str, Any]:
    """Build, scan and write one simulated scan (a unit of work for :func:`map_scenes`)."""
    from ontodetect.synth import artefacts as A
    from ontodetect.synth import synthesize, write_synth

    generator, scan, folder = unit
    scene = GENERATORS[generator](scan.room, scan.seed)
    sensor, steps = VARIANTS[scan.variant]
    if sensor == "rgbd-frame":
        result = synthesize(scene, sensor, seed=scan.seed, points=POINTS)
    else:
        result = synthesize(scene, sensor, seed=scan.seed, **DENSE_SCAN)
        rng = _artefact_rng(scan)
        out = result.output
        # The triangle each point came from rides along as a field, so objects.json's
        # per-part counts stay right after points are added, removed and reordered.
        cloud = out.cloud.with_fields(triangle=out.triangle)
        for step in steps:
            cloud = getattr(A, step)(cloud, rng)
        cloud = A.scannet_sampling(cloud, rng, points=POINTS)
        fields = dict(cloud.fields)
        triangle = np.asarray(fields.pop("triangle"), dtype=np.int32)
        params = {**out.parameters, "artefacts": list(cloud.meta["artefacts"])}
        cloud = cloud.replace(fields=fields, index=None)
        output = dataclasses.replace(out, cloud=cloud, triangle=triangle, parameters=params)
        result = dataclasses.replace(result, output=output)
    write_synth(result, folder)
    return {"scan": scan.name, "points": len(result.cloud), **result.objects_by_class()}


def build_simulated_set(
    out: Path, source: RoomSource, scans: Sequence[SimScan], jobs: int
) -> tuple[Path, list[SceneSource], bool]:
    """The cached simulated set (generated when missing): folder, scenes, reused or not."""
    key = cache_key(source, scans)
    digest = hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:12]
    folder = out / f"sim-{source.name}-{digest}"
    manifest = folder / "manifest.json"
    sources = _sources(folder, scans)
    if manifest.is_file() and json.loads(manifest.read_text()).get("key") == key:
        return folder, sources, True
    folder.mkdir(parents=True, exist_ok=True)
    units = [(source.name, s, str(folder / s.name)) for s in scans]
    summaries = map_scenes(generate_scan, units, jobs=jobs, description="Simulating rooms")
    manifest.write_text(json.dumps({"key": key, "scans": summaries}, indent=1) + "\n")
    return folder, sources, False


def pinned_simulated_set(
    folder: Path, scans: Sequence[SimScan], *, option: str = "--sim-set"
) -> tuple[Path, list[SceneSource]]:
    """A simulated set generated earlier (``--sim-set``, or ``option``), used even if the
    generator has changed since, so that two versions of the detector are measured on the
    same rooms."""
    if not (folder / "manifest.json").is_file():
        raise InvalidParameterError(option, "a simulated set's folder (manifest.json)", folder)
    have = manifest_scans(folder)
    missing = [s.name for s in scans if s.name not in have]
    if missing:
        raise InvalidParameterError(option, "a set with every scan of this run", missing[:3])
    return folder, _sources(folder, scans)


def manifest_scans(folder: Path) -> set[str]:
    """The names of the scans a generated set's manifest lists (none when it has no
    readable manifest)."""
    try:
        key = json.loads((folder / "manifest.json").read_text()).get("key", {})
    except (OSError, ValueError):
        return set()
    return set(key.get("scans", []))


def _sources(folder: Path, scans: Sequence[SimScan]) -> list[SceneSource]:
    return [
        SceneSource(s.name, str(folder / s.name), "ontodetect", f"{s.room}-s{s.seed}")
        for s in scans
    ]


# -- figures -------------------------------------------------------------------------------
def per_class(results: Sequence[Any]) -> dict[str, dict[str, dict[str, Any]]]:
    """Threshold -> class (and overall) -> gt, det, tp, precision, recall."""
    out = {}
    for key, thr in THRESHOLDS.items():
        ev = evaluate_scenes(results, CLASSES, criterion="iou", iou_threshold=thr)
        out[key] = _class_figures(ev)
    return out


def _class_figures(ev: Evaluation) -> dict[str, dict[str, Any]]:
    rows = {**ev.per_class, "overall": ev.overall}
    return {
        c: {
            "gt": m.num_gt,
            "det": m.num_pred,
            "tp": m.tp,
            "precision": round(m.precision, 4),
            "recall": round(m.recall, 4),
        }
        for c, m in rows.items()
    }


def dataset_figures(ev: DatasetEvaluation) -> dict[str, dict[str, dict[str, Any]]]:
    """Threshold -> class (and overall) -> gt, det, tp, precision, recall of an evaluation."""
    return {key: _class_figures(ev.evaluations[key]) for key in THRESHOLDS}


def grouped(outcomes: Sequence[SceneOutcome], group: Callable[[SceneOutcome], str]) -> dict:
    """Per-class figures of every group of scenes."""
    groups: dict[str, list[Any]] = {}
    for o in outcomes:
        groups.setdefault(group(o), []).append(o.scene_result())
    return {g: per_class(rs) for g, rs in groups.items()}


def scene_labels(
    source: SceneSource, cloud: Any = None
) -> tuple[np.ndarray, dict[int, tuple[str, str]]]:
    """Instance id of every row, and instance id -> (class, kind), of a labelled scene;
    ``cloud``: the scan as :func:`load_scene` read it, or a changed copy that keeps its
    labelled rows, when it is already in hand (a simulated scan carries its objects there,
    ``meta["boxes"]``; a copy made anew is read again for them), else it is read."""
    if cloud is None:
        cloud = load_scene(source).cloud
    if source.format == "ontodetect":
        objects = cloud.meta.get("boxes") or load_scene(source).cloud.meta["boxes"]
        what = {int(o["id"]): (str(o["class"]), str(o.get("kind") or o["class"])) for o in objects}
    else:
        from ontodetect.io._labels import NYU40_NAMES

        what = instance_names(cloud.fields["instance"], cloud.fields["class_id"], NYU40_NAMES)
    return rows_to_values(cloud.index, cloud.fields["instance"]), what


def labelled_objects(cloud: Any) -> list[Instance]:
    """The evaluated objects (:func:`evaluation_classes`) of a scan read with its per-point
    labels, as rows of its file."""
    fields = cloud.fields
    return instances_from_labels(
        fields["instance"], fields["class_id"], evaluation_classes(), index=cloud.index
    )


def scene_mistakes(
    name: str,
    preds: Sequence[Instance],
    gts: Sequence[Instance],
    clusters: Sequence[Instance],
    labels: tuple[np.ndarray, Mapping[int, tuple[str, str]]],
    iou_threshold: float,
    lacks: Sequence[Mapping[str, str]] = (),
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """One scan's false detections (:func:`false_detection_causes`) and missed objects
    (:func:`missed_causes`, with their kind; none without the first pass's clusters),
    each with the scan's name; ``labels`` is :func:`scene_labels` of the scan, ``lacks``
    the clusters' :attr:`~ontodetect.evaluation.SceneOutcome.cluster_lacks`."""
    rows, what = labels
    kinds = {iid: kind for iid, (_, kind) in what.items()}
    false = false_detection_causes(preds, gts, rows, what, iou_threshold=iou_threshold)
    missed = (
        missed_causes(preds, gts, clusters, iou_threshold=iou_threshold, lacks=lacks)
        if clusters
        else []
    )
    return (
        [{"scene": name, **f} for f in false],
        [{"scene": name, "kind": kinds.get(m["id"], m["label"]), **m} for m in missed],
    )


def mistakes_and_families(
    outcomes: Sequence[SceneOutcome],
) -> tuple[
    dict[str, list[dict[str, Any]]],
    dict[str, dict[str, list[int]]],
    dict[str, str],
    dict[str, list[dict[str, Any]]],
]:
    """False detections (per threshold), recall per family (kind), and the missed objects
    with where they were lost (per threshold, with their kind) over scenes."""
    false: dict[str, list[dict[str, Any]]] = {k: [] for k in THRESHOLDS}
    missed: dict[str, list[dict[str, Any]]] = {k: [] for k in THRESHOLDS}
    families: dict[str, dict[str, list[int]]] = {k: {} for k in THRESHOLDS}
    family_class: dict[str, str] = {}
    for o in outcomes:
        rows, what = scene_labels(o.source)
        kinds = {iid: kind for iid, (_, kind) in what.items()}
        for g in o.gts:
            family_class.setdefault(kinds.get(g.id, g.label), g.label)
        for key, thr in THRESHOLDS.items():
            f, m = scene_mistakes(
                o.name, o.preds, o.gts, o.clusters, (rows, what), thr, o.cluster_lacks
            )
            false[key] += f
            missed[key] += m
            for fam, (found, total) in recall_by_group(
                o.preds, o.gts, kinds, iou_threshold=thr
            ).items():
                tally = families[key].setdefault(fam, [0, 0])
                tally[0] += found
                tally[1] += total
    return false, families, family_class, missed


#: What a false detection and a missed object are written with in ``mistakes``: the scan and
#: what names the object across runs (the labelled instance, the ground-truth id), and why.
FALSE_FIELDS = ("scene", "label", "is", "kind", "instance", "share")
MISSED_FIELDS = ("scene", "id", "label", "kind", "cause", "iou", "as", "lacks")


def mistake_items(
    false: Mapping[str, list[dict[str, Any]]], missed: Mapping[str, list[dict[str, Any]]]
) -> dict[str, dict[str, list[dict[str, Any]]]]:
    """Threshold -> every false detection and every missed object, one by one, by scan:
    what ``python -m benchmarks compare`` lists when two runs differ (which object of which
    scan was gained or lost), so that a change is judged on the objects, not only on counts.

    >>> f = {"scene": "s", "id": 3, "label": "chair", "is": "sink", "kind": "sink",
    ...      "instance": 7, "share": 0.9}
    >>> mistake_items({"iou@0.25": [f]}, {"iou@0.25": []})["iou@0.25"]["false"][0]["instance"]
    7
    """
    return {
        key: {
            "false": [{f: item.get(f) for f in FALSE_FIELDS} for item in false.get(key, [])],
            "missed": [{f: item.get(f) for f in MISSED_FIELDS} for item in missed.get(key, [])],
        }
        for key in THRESHOLDS
        if key in false or key in missed
    }


def missed_summary(missed: Mapping[str, list[dict[str, Any]]]) -> dict[str, dict[str, Any]]:
    """Threshold -> class -> how many objects were missed, by cause
    (:func:`benchmarks._generalization.missed_causes`), by kind and cause, and, of those
    lost to the scoring, by what their class's reading lacked most (``lacks``)."""
    out: dict[str, dict[str, Any]] = {k: {} for k in missed}
    for key, items in missed.items():
        for m in items:
            row = out[key].setdefault(
                m["label"], {"total": 0, "causes": Counter(), "kinds": {}, "lacks": Counter()}
            )
            row["total"] += 1
            row["causes"][m["cause"]] += 1
            row["kinds"].setdefault(m["kind"], Counter())[m["cause"]] += 1
            if m.get("lacks"):
                row["lacks"][m["lacks"]] += 1
    return {
        key: {
            c: {
                "total": v["total"],
                "causes": {k: v["causes"][k] for k in MISSED_CAUSES if v["causes"][k]},
                "kinds": {k: dict(n) for k, n in sorted(v["kinds"].items())},
                "lacks": dict(sorted(v["lacks"].items(), key=lambda kv: (-kv[1], kv[0]))),
            }
            for c, v in sorted(rows.items())
        }
        for key, rows in out.items()
    }


def missed_table(title: str, summary: Mapping[str, Any]) -> Table:
    """Missed objects by where they were lost (from :func:`missed_summary`)."""
    t = Table(title=title, title_justify="left")
    t.add_column("class")
    t.add_column("missed @.25", justify="right")
    for cause in MISSED_CAUSES:
        t.add_column(cause, justify="right")
    t.add_column("missed @.5", justify="right")
    lo, hi = summary["iou@0.25"], summary["iou@0.5"]
    for c in CLASSES:
        a = lo.get(c, {"total": 0, "causes": {}})
        b = hi.get(c, {"total": 0})
        t.add_row(
            c,
            str(a["total"]),
            *[str(a["causes"].get(k, 0)) for k in MISSED_CAUSES],
            str(b["total"]),
        )
    return t


#: How many of the factors that most often sank a scored miss :func:`lacks_table` lists.
LACKS_SHOWN = 6


def lacks_table(title: str, summary: Mapping[str, Any]) -> Table:
    """Of the objects lost to the scoring (a cluster holds them, the first pass read it
    otherwise), what their class's reading lacked most, per class (:func:`missed_summary`):
    the ``part.feature`` whose factor was smallest, the commonest first."""
    t = Table(title=title, title_justify="left")
    t.add_column("class")
    t.add_column("scored", justify="right")
    t.add_column("what the reading as the class lacked most (objects)")
    lo = summary["iou@0.25"]
    for c in CLASSES:
        row = lo.get(c, {})
        lacks = row.get("lacks", {})
        shown = ", ".join(f"{k} {n}" for k, n in list(lacks.items())[:LACKS_SHOWN])
        rest = sum(list(lacks.values())[LACKS_SHOWN:])
        t.add_row(
            c,
            str(row.get("causes", {}).get("scored", 0)),
            shown + (f", other {rest}" if rest else ""),
        )
    return t


def false_summary(false: Mapping[str, list[dict[str, Any]]]) -> dict[str, dict[str, Any]]:
    """Threshold -> what it really is -> counts by detected label, and the kinds."""
    out: dict[str, dict[str, Any]] = {}
    for key, items in false.items():
        rows: dict[str, dict[str, Any]] = {}
        for f in items:
            row = rows.setdefault(f["is"], {"total": 0, "as": Counter(), "kinds": Counter()})
            row["total"] += 1
            row["as"][f["label"]] += 1
            row["kinds"][f["kind"]] += 1
        out[key] = {
            k: {"total": v["total"], "as": dict(v["as"]), "kinds": dict(v["kinds"].most_common())}
            for k, v in sorted(rows.items(), key=lambda kv: (-kv[1]["total"], kv[0]))
        }
    return out


# -- stability -----------------------------------------------------------------------------
def _detect_changed(
    source: SceneSource,
    name: str | None,
    change: Callable[[Any, np.random.Generator], Any] | None,
    detect_options: Mapping[str, Any],
) -> tuple[Any, Any, list[Instance], float]:
    """Read a scan, change it by ``change`` (seeded by the scan's and the change's name;
    ``None``: as is) and detect: the cloud, the result, its reported detections and the
    seconds detection took."""
    from ontodetect.pipeline import detect

    cloud = load_scene(source).cloud
    if change is not None:
        cloud = change(cloud, np.random.default_rng(zlib.crc32(f"{source.name}/{name}".encode())))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataWarning)
        result = detect(cloud, **detect_options)
    seconds = time.perf_counter() - t0
    dets = [
        Instance.make(d.id, d.label, d.point_indices, d.score, d.center)
        for d in result.detections
        if d.label in CLASSES
    ]
    return cloud, result, dets, seconds


def stability_unit(
    unit: tuple[SceneSource, str | None, tuple[float, ...]], detect_options: Mapping[str, Any]
) -> dict[str, Any]:
    """Detect on one scan, as is (transform None) or changed; a unit of work. Detections on
    the scan as is come with what each really is (:func:`reference_kinds`)."""
    source, name, turns = unit
    change = None if name is None else stability_transforms(turns)[name]
    cloud, _, dets, seconds = _detect_changed(source, name, change, detect_options)
    return {
        "scene": source.name,
        "transform": name,
        "detections": dets,
        "kept": None if name is None else np.asarray(cloud.index),
        "kinds": reference_kinds(source, cloud, dets) if name is None else None,
        "seconds": seconds,
    }


def reference_kinds(source: SceneSource, cloud: Any, dets: Sequence[Instance]) -> list[str]:
    """What each detection really is, in order: its own label when it matches a labelled
    object of that class at point IoU 0.25, else ``false: <class> (<kind>)`` of the object
    holding most of its points (:func:`false_detection_causes`; the kind where it is not the
    class's name); ``?`` without labels."""
    if "instance" not in cloud.fields or "class_id" not in cloud.fields:
        return ["?"] * len(dets)
    gts = labelled_objects(cloud)
    rows, what = scene_labels(source, cloud)
    false = {
        f["id"]: f
        for f in false_detection_causes(dets, gts, rows, what, iou_threshold=THRESHOLDS["iou@0.25"])
    }
    out = []
    for d in dets:
        f = false.get(d.id)
        if f is None:
            out.append(d.label)
        else:  # the kind only where it says more than the class: "false: chair (chair-shell)"
            kind = f" ({f['kind']})" if f["kind"] != f["is"] else ""
            out.append(f"false: {f['is']}{kind}")
    return out


def stability(
    scans: Sequence[SceneSource],
    turns: Sequence[float],
    jobs: int,
    opts: Mapping[str, Any],
) -> dict[str, Any]:
    """Share of reference detections that reappear, per transform and scan (detected with
    ``opts``, the same detect options as the other parts: seed, room prior, configuration
    and ontology), and each reference detection that did not come back under some change
    (``unsteady``: what it is and the changes it was lost under)."""
    names = list(stability_transforms(turns))
    units = [(s, t, tuple(turns)) for s in scans for t in [None, *names]]
    options = {**opts, "jobs": 1}
    work = functools.partial(stability_unit, detect_options=options)
    runs = map_scenes(work, units, jobs=jobs, description="Stability runs")
    return stability_figures([s.name for s in scans], names, runs)


def stability_figures(
    scans: Sequence[str], names: Sequence[str], runs: Sequence[Mapping[str, Any]]
) -> dict[str, Any]:
    """:func:`stability`'s result from its runs (:func:`stability_unit`'s, one per scan and
    change, and one per scan as is)."""
    ref = {r["scene"]: r for r in runs if r["transform"] is None}
    table: dict[str, dict[str, list[int]]] = {n: {} for n in names}
    counts: dict[str, dict[str, int]] = {n: {} for n in names}
    lost_under: dict[tuple[str, int], list[str]] = {}
    for r in runs:
        if r["transform"] is not None:
            counts[r["transform"]][r["scene"]] = len(r["detections"])
            refs = ref[r["scene"]]["detections"]
            lost = lost_references(
                refs, r["detections"], iou_threshold=STABILITY_IOU, kept=r["kept"]
            )
            for i in lost:
                lost_under.setdefault((r["scene"], i), []).append(r["transform"])
            table[r["transform"]][r["scene"]] = [len(refs) - len(lost), len(refs)]
    shares = {
        n: {s: (f / t if t else None) for s, (f, t) in per.items()} for n, per in table.items()
    }
    summary = {
        n: {"mean": _known(np.mean, per.values()), "worst": _known(np.min, per.values())}
        for n, per in shares.items()
    }
    every = [v for per in shares.values() for v in per.values()]
    unsteady = [
        {
            "scene": s,
            "id": d.id,
            "label": d.label,
            "score": round(float(d.score), 3),
            "is": ref[s]["kinds"][i],
            "lost_under": lost_under[(s, i)],
        }
        for s in scans
        for i, d in enumerate(ref[s]["detections"])
        if (s, i) in lost_under
    ]
    return {
        "scans": list(scans),
        "transforms": list(names),
        "iou": STABILITY_IOU,
        "reference_detections": {s: len(r["detections"]) for s, r in ref.items()},
        "reappeared": table,
        "detections": counts,
        "per_transform": summary,
        "mean": _known(np.mean, every),
        "worst": _known(np.min, every),
        "unsteady": sorted(unsteady, key=lambda u: -len(u["lost_under"])),
        "detect_seconds": round(sum(r["seconds"] for r in runs), 1),
    }


def _known(stat: Callable, values: Iterable[float | None]) -> float | None:
    """``stat`` (``np.mean``, ``np.min``) of the values that are not None, to four places;
    None when there are none."""
    known = [v for v in values if v is not None]
    return round(float(stat(known)), 4) if known else None


def pooled_seeds(runs: Mapping[int, Mapping[str, Any]]) -> dict[str, Any]:
    """:func:`stability` run with several detection seeds, as one result: found / reference
    detections summed over the seeds per change and scan, each change's and the overall mean
    the mean of the seeds' means and the worst the lowest of their worsts; each seed's own
    result under ``by_seed``. The seed alone moves the six-scan mean by 0.02-0.04
    (docs/benchmarks.md, "Easy chairs built in"): a change is read on more than one draw.
    """
    results = list(runs.values())
    first = results[0]
    names, scans = first["transforms"], first["scans"]
    return {
        "scans": scans,
        "transforms": names,
        "iou": first["iou"],
        "seeds": list(runs),
        "reference_detections": {
            s: sum(r["reference_detections"][s] for r in results) for s in scans
        },
        "reappeared": {
            n: {s: [sum(r["reappeared"][n][s][k] for r in results) for k in (0, 1)] for s in scans}
            for n in names
        },
        "detections": {
            n: {s: sum(r["detections"][n][s] for r in results) for s in scans} for n in names
        },
        "per_transform": {
            n: {
                "mean": _known(np.mean, [r["per_transform"][n]["mean"] for r in results]),
                "worst": _known(np.min, [r["per_transform"][n]["worst"] for r in results]),
            }
            for n in names
        },
        "mean": _known(np.mean, [r["mean"] for r in results]),
        "worst": _known(np.min, [r["worst"] for r in results]),
        "unsteady": sorted(
            ({**u, "seed": k} for k, r in runs.items() for u in r.get("unsteady", [])),
            key=lambda u: -len(u["lost_under"]),
        ),
        "detect_seconds": round(sum(r["detect_seconds"] for r in results), 1),
        "by_seed": {str(k): dict(r) for k, r in runs.items()},
    }


def richest(outcomes: Sequence[SceneOutcome], count: int, *, one_per: Callable | None = None):
    """The ``count`` scenes with the most evaluated objects (ties: name), one per group."""
    ranked = sorted(outcomes, key=lambda o: (-len(o.gts), o.name))
    chosen, groups = [], set()
    for o in ranked:
        g = one_per(o) if one_per else o.name
        if g in groups:
            continue
        groups.add(g)
        chosen.append(o.source)
        if len(chosen) == count:
            break
    return chosen


# -- printing ------------------------------------------------------------------------------
def _pr(fig: Mapping[str, Any]) -> str:
    """``P / R``; a precision without detections and a recall without objects are ``-``."""
    if not fig["gt"] and not fig["det"]:
        return "-"
    p = f"{fig['precision']:.2f}" if fig["det"] else "-"
    r = f"{fig['recall']:.2f}" if fig["gt"] else "-"
    return f"{p} / {r}"


def class_table(title: str, figures: Mapping[str, Mapping[str, Any]]) -> Table:
    """Per-class counts, precision and recall at both thresholds (from :func:`per_class`)."""
    t = Table(title=title, title_justify="left")
    t.add_column("class")
    for col in ("GT", "det @.25", "TP @.25", "P / R @.25", "det @.5", "TP @.5", "P / R @.5"):
        t.add_column(col, justify="right")
    lo, hi = figures["iou@0.25"], figures["iou@0.5"]
    for c in [*CLASSES, "overall"]:
        a, b = lo[c], hi[c]
        t.add_row(
            c,
            str(a["gt"]),
            str(a["det"]),
            str(a["tp"]),
            _pr(a),
            str(b["det"]),
            str(b["tp"]),
            _pr(b),
        )
    return t


def group_table(
    title: str, label: str, groups: Mapping[str, Any], counts: Mapping[str, int]
) -> Table:
    """One row per group of scans (from :func:`grouped`): ground truth and P / R per class."""
    t = Table(title=title, title_justify="left")
    t.add_column(label)
    t.add_column("scans", justify="right")
    for c in CLASSES:
        t.add_column(f"{c} GT", justify="right")
        t.add_column(f"{c} P/R @.25", justify="right")
        t.add_column(f"{c} P/R @.5", justify="right")
    for g, figs in groups.items():
        cells = [g, str(counts[g])]
        for c in CLASSES:
            a, b = figs["iou@0.25"][c], figs["iou@0.5"][c]
            cells += [str(a["gt"]), _pr(a), _pr(b)]
        t.add_row(*cells)
    return t


#: Chair families that are easy chairs (armchairs, lounge chairs, recliners, shell chairs),
#: reported apart from upright chairs (office, dining, stacking, folding, classroom).
EASY_CHAIRS = ("armchair-club", "armchair-wingback", "lounge-chair", "recliner", "chair-shell")


def chair_groups(families: Mapping[str, Mapping[str, tuple[int, int]]]) -> dict[str, Any]:
    """Recall of easy chairs and of upright chairs, apart, at each threshold."""
    out: dict[str, Any] = {}
    for iou, fams in families.items():
        groups = {"easy chairs": [0, 0], "upright chairs": [0, 0]}
        for fam, (found, gt) in fams.items():
            if fam in EASY_CHAIRS:
                group = "easy chairs"
            elif fam.startswith("chair-"):
                group = "upright chairs"
            else:
                continue
            groups[group][0] += found
            groups[group][1] += gt
        out[iou] = {
            g: {"found": f, "gt": n, "recall": round(f / n, 4) if n else 0.0}
            for g, (f, n) in groups.items()
        }
    return out


def family_table(
    families: Mapping[str, Any], family_class: Mapping[str, str], *, title: str = "Simulated"
) -> Table:
    """Recall per furniture family (kind) at both thresholds, grouped by class."""
    t = Table(title=f"{title}: recall per furniture family", title_justify="left")
    for col in ("class", "family", "GT", "found @.25", "recall @.25", "found @.5", "recall @.5"):
        t.add_column(col, justify="left" if col in ("class", "family") else "right")
    lo, hi = families["iou@0.25"], families["iou@0.5"]
    for fam in sorted(lo, key=lambda f: (family_class.get(f, ""), f)):
        (f1, n), (f2, _) = lo[fam], hi[fam]
        t.add_row(
            family_class.get(fam, ""),
            fam,
            str(n),
            str(f1),
            f"{f1 / n:.2f}",
            str(f2),
            f"{f2 / n:.2f}",
        )
    groups = chair_groups(families)
    for group in groups["iou@0.25"]:
        a, b = groups["iou@0.25"][group], groups["iou@0.5"][group]
        if a["gt"]:
            t.add_row(
                "chair", f"[bold]all {group}[/]", str(a["gt"]), str(a["found"]),
                f"{a['recall']:.2f}", str(b["found"]), f"{b['recall']:.2f}",
            )  # fmt: skip
    return t


def false_table(title: str, summary: Mapping[str, Any]) -> Table:
    """False detections by what they really are (from :func:`false_summary`)."""
    t = Table(title=title, title_justify="left")
    t.add_column("really is")
    for c in CLASSES:
        t.add_column(f"as {c} @.25", justify="right")
    t.add_column("all @.25", justify="right")
    t.add_column("all @.5", justify="right")
    t.add_column("kinds (@.25)")
    lo, hi = summary["iou@0.25"], summary["iou@0.5"]
    for what in dict.fromkeys([*lo, *hi]):
        a = lo.get(what, {"total": 0, "as": {}, "kinds": {}})
        b = hi.get(what, {"total": 0})
        kinds = ", ".join(f"{k} {n}" for k, n in list(a["kinds"].items())[:4] if k != what)
        t.add_row(
            what,
            *[str(a["as"].get(c, 0)) for c in CLASSES],
            str(a["total"]),
            str(b["total"]),
            kinds,
        )
    return t


def stability_table(title: str, res: Mapping[str, Any]) -> Table:
    """Found / reference detections per change and scan, with the mean and the worst."""
    t = Table(title=title, title_justify="left")
    t.add_column("transform")
    for s in res["scans"]:
        t.add_column(f"{s} ({res['reference_detections'][s]})", justify="right")
    t.add_column("mean", justify="right")
    t.add_column("worst", justify="right")
    for n in res["transforms"]:
        cells = [n]
        for s in res["scans"]:
            found, total = res["reappeared"][n][s]
            cells.append(f"{found}/{total}" if total else "-")
        m = res["per_transform"][n]
        cells += ["-" if m["mean"] is None else f"{m['mean']:.2f}"]
        cells += ["-" if m["worst"] is None else f"{m['worst']:.2f}"]
        t.add_row(*cells)
    mean = "-" if res["mean"] is None else f"{res['mean']:.2f}"
    worst = "-" if res["worst"] is None else f"{res['worst']:.2f}"
    t.add_row("[bold]all[/]", *[""] * len(res["scans"]), mean, worst)
    return t


def unsteady_table(title: str, res: Mapping[str, Any]) -> Table:
    """The reference detections that did not come back under every change: the scan, the
    detection (its label, score and what it really is) and the changes that lost it."""
    t = Table(title=title, title_justify="left")
    for name, justify in (("scan", "left"), ("detection", "left"), ("score", "right")):
        t.add_column(name, justify=justify)
    t.add_column("really is")
    t.add_column("lost", justify="right")
    t.add_column("under")
    total = len(res["transforms"])
    for u in res.get("unsteady", []):
        seed = f", seed {u['seed']}" if "seed" in u else ""
        t.add_row(
            u["scene"],
            f"#{u['id']} {u['label']}{seed}",
            f"{u['score']:.2f}",
            u["is"],
            f"{len(u['lost_under'])}/{total}",
            ", ".join(u["lost_under"]),
        )
    return t


# -- robustness ----------------------------------------------------------------------------
def robustness_unit(
    unit: tuple[SceneSource, str], detect_options: Mapping[str, Any]
) -> dict[str, Any]:
    """Detect on one labelled scan changed by one of :func:`robustness_changes`; a unit of
    work: TP/det/GT per class at point IoU 0.25, the scan's measured floor scatter, and its
    false detections and missed objects (as :func:`mistakes_and_families` gives them)."""
    source, name = unit
    cloud, result, preds, _ = _detect_changed(
        source, name, robustness_changes()[name], detect_options
    )
    gts = labelled_objects(cloud)
    thr = THRESHOLDS["iou@0.25"]
    matched = match_instances(preds, gts, iou_threshold=thr).pred_match
    clusters = first_pass_clusters(result)
    labels = scene_labels(source, cloud)  # the changed copy: its rows, a doubled point's too
    false, missed = scene_mistakes(
        source.name, preds, gts, clusters, labels, thr, first_pass_lacks(result)
    )
    counts = {
        c: [
            sum(1 for p, m in zip(preds, matched) if p.label == c and m >= 0),
            sum(1 for p in preds if p.label == c),
            sum(1 for g in gts if g.label == c),
        ]
        for c in CLASSES
    }
    return {
        "scene": source.name,
        "change": name,
        "counts": counts,
        "floor_scatter": result.frame["floor_scatter"],
        "false": false,
        "missed": missed,
    }


def robustness(
    scans: Sequence[SceneSource],
    jobs: int,
    opts: Mapping[str, Any],
    names: Sequence[str] | None = None,
) -> dict:
    """Per change of :func:`robustness_changes` (those of ``names``; all by default):
    TP/det/GT, precision and recall per class at point IoU 0.25, summed over ``scans``,
    and the median floor scatter measured."""
    names = list(robustness_changes()) if names is None else list(names)
    options = {**opts, "jobs": 1}
    work = functools.partial(robustness_unit, detect_options=options)
    runs = map_scenes(
        work, [(s, n) for s in scans for n in names], jobs=jobs, description="Robustness runs"
    )
    out: dict[str, Any] = {"scans": [s.name for s in scans], "changes": {}}
    for n in names:
        mine = [r for r in runs if r["change"] == n]
        per_class = {}
        for c in CLASSES:
            per_class[c] = class_figures(*(sum(r["counts"][c][k] for r in mine) for k in range(3)))
        scatter = [r["floor_scatter"] for r in mine if r["floor_scatter"] is not None]
        out["changes"][n] = {
            "per_class": per_class,
            "floor_scatter": round(float(np.median(scatter)), 5) if scatter else None,
            "mistakes": mistake_items(
                {"iou@0.25": [f for r in mine for f in r["false"]]},
                {"iou@0.25": [m for r in mine for m in r["missed"]]},
            ),
        }
    return out


def robustness_table(
    res: Mapping[str, Any],
    real: Mapping[str, Any] | None,
    title: str = "Robustness: the real scans changed, TP/det/GT at point IoU 0.25",
) -> Table:
    """TP/det/GT and precision / recall per class and change, the scans as they are first."""
    t = Table(title=title, title_justify="left")
    t.add_column("change")
    for c in CLASSES:
        t.add_column(c, justify="right")
        t.add_column("P / R", justify="right")
    t.add_column("floor scatter", justify="right")
    as_they_are = (real or {}).get("iou@0.25")
    rows = [("as they are", as_they_are, None)]
    rows += [(n, v["per_class"], v["floor_scatter"]) for n, v in res["changes"].items()]
    pooled = pooled_orientations(as_they_are, res["changes"])
    if pooled is not None:
        rows.append((POOLED, pooled, None))
    for name, figs, scatter in rows:
        cells = [name]
        for c in CLASSES:
            f = (figs or {}).get(c)
            cells += ["-", "-"] if f is None else [f"{f['tp']}/{f['det']}/{f['gt']}", _pr(f)]
        cells.append("-" if scatter is None else f"{scatter * 1e3:.1f} mm")
        t.add_row(*cells)
    return t


# -- the run -------------------------------------------------------------------------------
def _real_scenes(path: Path, quick: bool) -> list[SceneSource]:
    """The labelled real scans of ``path`` (the first three with ``quick``)."""
    scenes = discover_scenes(path, "scannet-votenet")
    return scenes[:3] if quick else scenes


def main(argv: list[str] | None = None) -> int:
    """Parse the options, check ``--real`` (one line and status 2 when it is bad), run."""
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks generalization", description=__doc__.splitlines()[0]
    )
    ap.add_argument(
        "--real", type=Path, required=True, help="labelled real scans (ScanNet, VoteNet layout)"
    )
    ap.add_argument(
        "--out",
        type=Path,
        default=Path("bench-output/generalization"),
        help="generalization.json and the simulated set's cache (default: %(default)s)",
    )
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (0: one per CPU)")
    ap.add_argument("--quick", action="store_true", help="a small smoke run")
    ap.add_argument("--seed", type=int, default=0, help="seed of detection (default 0)")
    add_rule_options(ap)
    ap.add_argument(
        "--room",
        default="auto",
        help="the room prior of every detection: auto (estimated from the scan, the default), "
        "none (no prior), or a room category such as office",
    )
    ap.add_argument(
        "--source",
        choices=("furnished", "parametric"),
        default="furnished",
        help="simulated rooms: furnished (falls back to parametric when missing) or parametric",
    )
    ap.add_argument(
        "--sim-set",
        type=Path,
        default=None,
        help="a simulated set generated earlier (a sim-* folder of --out), used as it is even "
        "if the generator changed: two versions measured on the same rooms",
    )
    ap.add_argument(
        "--frames-set",
        type=Path,
        default=None,
        help="the single frames of (e) generated earlier (a sim-* folder of --out), used as "
        "they are even if the generator changed",
    )
    ap.add_argument(
        "--sim-seeds",
        type=int,
        default=0,
        metavar="FIRST",
        help="the simulated rooms and frames count their seeds from FIRST (default 0): with 7, "
        "rooms of the same kinds that the pinned set (seeds 0-6) never showed",
    )
    ap.add_argument(
        "--only",
        default=",".join(PARTS),
        help="which measurements to run, of " + ", ".join(PARTS) + " (default: all six; "
        "stability needs real and sim)",
    )
    ap.add_argument(
        "--rooms",
        default=None,
        help="evaluate only the simulated scans of these room types (comma-separated); the "
        "cached set stays whole",
    )
    ap.add_argument(
        "--stability-scans",
        default=None,
        help="with --only stability: the scans to turn, move and round (comma-separated "
        "names of real scans and simulated scans, e.g. scene0002_01,classroom-s5-fused) "
        "instead of the richest ones of the real and simulated runs",
    )
    ap.add_argument(
        "--stability-seeds",
        default=None,
        help="stability: detection seeds (comma-separated, e.g. 0,1), each run whole and the "
        "figures pooled (the seed alone moves the mean by 0.02-0.04); default: --seed",
    )
    ap.add_argument(
        "--turns",
        default=None,
        help="stability: the turns (degrees, comma-separated) instead of "
        + ", ".join(f"{t:g}" for t in STABILITY_TURNS),
    )
    args = ap.parse_args(argv)
    if args.sim_seeds < 0:
        ap.error(f"--sim-seeds takes a seed of 0 or more, got {args.sim_seeds}")
    if args.turns is not None:
        try:
            args.turns = tuple(float(t) for t in args.turns.split(",") if t.strip())
        except ValueError:
            ap.error(f"--turns takes degrees separated by commas, got {args.turns!r}")
    if args.stability_seeds is not None:
        try:
            args.stability_seeds = tuple(
                dict.fromkeys(int(k) for k in args.stability_seeds.split(",") if k.strip())
            )
        except ValueError:
            ap.error(
                f"--stability-seeds takes integers separated by commas, got "
                f"{args.stability_seeds!r}"
            )
        if not args.stability_seeds:
            ap.error("--stability-seeds names no seed")
    parts = {p.strip() for p in args.only.split(",") if p.strip()}
    if not parts or parts - set(PARTS):
        ap.error(f"--only takes {', '.join(PARTS)}, got {args.only!r}")
    whole = {"real", "sim", "stability"} <= parts
    alone = parts == {"stability"} and args.stability_scans
    if "stability" in parts and not (whole or alone):
        ap.error("--only stability needs real and sim too, or --stability-scans")
    args.only = parts
    if args.jobs < 0:
        ap.error(f"--jobs must be >= 0, got {args.jobs}")
    try:
        args.ontology = ontology_option(args.ontologies, args.ontology_only)
    except OntoDetectError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        real_scenes = _real_scenes(args.real, args.quick)
    except OntoDetectError as exc:
        print(f"error: --real {args.real}: {exc}", file=sys.stderr)
        return 2
    try:
        return run(args, real_scenes)
    except OntoDetectError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


def add_rule_options(ap: argparse.ArgumentParser) -> None:
    """``--set`` (``overrides``), ``--ontology`` (``ontologies``) and ``--ontology-only``:
    the configuration and the rules a benchmark runs the detector with, as ``ontodetect
    detect`` takes them."""
    ap.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a configuration value for detection, e.g. detect.proposals=recognition (repeatable)",
    )
    ap.add_argument(
        "--ontology",
        dest="ontologies",
        action="append",
        default=[],
        type=Path,
        metavar="FILE",
        help="an ontology YAML merged into the built-in one, as `ontodetect detect --ontology` "
        "takes it (repeatable): an edited class measured before it is built in",
    )
    ap.add_argument(
        "--ontology-only",
        action="store_true",
        help="use only the --ontology files, not the built-in ontology (an edited copy of it)",
    )


def ontology_option(files: Sequence[Path], only: bool) -> Any:
    """``--ontology`` / ``--ontology-only`` as ``ontodetect detect`` reads them (None: the
    built-in ontology), checked before any scan is read."""
    if not files and not only:
        return None
    from ontodetect.cli._common import load_ontology_option

    return load_ontology_option(list(files), only)


def _ontology_record(files: Sequence[Path], only: bool) -> list[dict[str, Any]]:
    """What generalization.json records of the ontology files: name and SHA-256, so that
    two runs say whether they measured the same rules."""
    return [
        {"path": str(f), "sha256": hashlib.sha256(Path(f).read_bytes()).hexdigest(), "only": only}
        for f in files
    ]


def _room_option(room: str) -> str | None:
    """``--room`` as :func:`ontodetect.pipeline.detect` takes it ("none": no prior)."""
    return None if room.strip().lower() == "none" else room


def run(args: argparse.Namespace, real_scenes: list[SceneSource]) -> int:
    """The measurements, printed and written to ``args.out/generalization.json``."""
    from ontodetect._progress import use_reporter
    from ontodetect.cli._console import RichReporter

    start = time.perf_counter()
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    jobs = args.jobs
    opts: dict[str, Any] = {"seed": args.seed, "room": _room_option(args.room)}
    if args.overrides:
        opts["config"] = Config().with_overrides(args.overrides)
    if args.ontology is not None:
        opts["ontology"] = args.ontology
    source = room_source(args.source)
    reporter = RichReporter() if err.is_terminal else None
    doc: dict[str, Any] = {
        "format": FORMAT,
        "ontodetect": __version__,
        "quick": bool(args.quick),
        "jobs": jobs,
        "seed": args.seed,
        "overrides": list(args.overrides),
        "ontology": _ontology_record(args.ontologies, args.ontology_only),
        "room": args.room,
        "scene_source": dataclasses.asdict(source),
        "sim_seeds": args.sim_seeds,
    }
    console.print(
        f"simulated rooms: [bold]{source.name}[/], {len(source.room_types)} room types"
        + (" (Sweet Home 3D catalogue furniture)" if source.name == "furnished" else "")
    )
    with use_reporter(reporter):
        if args.only == {"stability"}:
            picked = _named_scans(args, real_scenes, source)
            return _run_stability(args, picked, jobs, opts, doc, start)
        # (a) real development scans
        if "real" in args.only:
            real = _run_real(args, real_scenes, jobs, opts, doc)
        # (d) the same scans as sensors and pipelines change them
        if "robustness" in args.only:
            t0 = time.perf_counter()
            doc["robustness"] = robustness(real_scenes, jobs, opts)
            doc["robustness"]["seconds"] = round(time.perf_counter() - t0, 1)
            console.print(robustness_table(doc["robustness"], doc.get("real", {}).get("per_class")))
        # (e) single frames
        if "frames" in args.only:
            _run_frames(args, source, jobs, opts, doc)

        # (b) the simulated set
        if not {"sim", "sparse"} & args.only:
            return _finish(out, doc, start)
        t0 = time.perf_counter()
        scans = simulated_set(source.room_types, quick=args.quick, first_seed=args.sim_seeds)
        if args.sim_set is not None:
            folder, sim_sources = pinned_simulated_set(args.sim_set, scans)
            reused = True
        else:
            folder, sim_sources, reused = build_simulated_set(out, source, scans, jobs)
        t_gen = time.perf_counter() - t0
        t0 = time.perf_counter()
        if args.rooms:
            wanted = {r.strip() for r in args.rooms.split(",")}
            unknown = wanted - set(source.room_types)
            if unknown:
                raise InvalidParameterError(
                    "--rooms", f"room types of {sorted(source.room_types)}", sorted(unknown)
                )
            keep = {s.name for s in scans if s.room in wanted}
            scans = [s for s in scans if s.name in keep]
            sim_sources = [s for s in sim_sources if s.name in keep]
            doc["rooms"] = sorted(wanted)
        by_name = {s.name: s for s in scans}
        if "sim" not in args.only:
            _run_sparse(sim_sources, by_name, jobs, opts, doc, None)
            return _finish(out, doc, start)
        sim = evaluate_dataset(folder, scenes=sim_sources, jobs=jobs, detect_options=opts)
        figures, families, family_class = simulated_figures(sim, scans)
        doc["simulated"] = {
            "cache": str(folder),
            "reused_cache": reused,
            "generate_seconds": round(t_gen, 1),
            "rooms": len({(s.room, s.seed) for s in scans}),
            "scans": [s.name for s in scans],
            **figures,
            "seconds": round(time.perf_counter() - t0, 1),
        }
        rooms = doc["simulated"]["rooms"]
        what = "reused from" if reused else "generated in"
        console.print(f"simulated set: {len(scans)} scans of {rooms} rooms, {what} {folder}")
        print_simulated(
            "Simulated",
            f"{len(sim.scenes)} scans of {rooms} rooms",
            sim,
            scans,
            figures,
            families,
            family_class,
            variants=True,
        )
        # (f) the fused scans, sparser
        if "sparse" in args.only:
            as_they_are = figures.get("by_variant", {}).get("fused", {}).get("iou@0.25")
            _run_sparse(sim_sources, by_name, jobs, opts, doc, as_they_are)

        # (c) stability
        if "stability" not in args.only:
            return _finish(out, doc, start)
        count = 1 if args.quick else STABILITY_SCANS
        fused = [o for o in sim.scenes if by_name[o.name].variant == "fused"]
        picked = richest(real.scenes, count, one_per=lambda o: o.source.group)
        picked += richest(fused, count, one_per=lambda o: by_name[o.name].room)
        return _run_stability(args, picked, jobs, opts, doc, start)


def _run_sparse(
    sources: Sequence[SceneSource],
    by_name: Mapping[str, SimScan],
    jobs: int,
    opts: Mapping[str, Any],
    doc: dict[str, Any],
    as_they_are: Mapping[str, Any] | None,
) -> None:
    """(f): the fused scans of the simulated set with half and a quarter of their points,
    scored as the robustness part scores the real scans (``doc["sparse"]``)."""
    t0 = time.perf_counter()
    fused = [s for s in sources if by_name[s.name].variant == "fused"]
    doc["sparse"] = robustness(fused, jobs, opts, SPARSE_CHANGES)
    doc["sparse"]["seconds"] = round(time.perf_counter() - t0, 1)
    title = (
        f"Sparse: the {len(fused)} fused simulated scans with fewer points, "
        "TP/det/GT at point IoU 0.25"
    )
    console.print(robustness_table(doc["sparse"], {"iou@0.25": as_they_are}, title))


def simulated_figures(
    ev: DatasetEvaluation, scans: Sequence[SimScan]
) -> tuple[dict[str, Any], dict[str, Any], dict[str, str]]:
    """The figures of simulated scans (per class, by room type, by variant, by family, the
    chair groups, the false detections and the missed objects), with the families and the
    class of each family for the tables."""
    by_name = {s.name: s for s in scans}
    false, families, family_class, missed = mistakes_and_families(ev.scenes)
    figures = {
        "per_class": dataset_figures(ev),
        "by_room_type": grouped(ev.scenes, lambda o: by_name[o.name].room),
        "by_variant": grouped(ev.scenes, lambda o: by_name[o.name].variant),
        "by_family": {
            k: {f: {"class": family_class.get(f), "found": a, "gt": b} for f, (a, b) in v.items()}
            for k, v in families.items()
        },
        "chair_groups": chair_groups(families),
        "false_detections": false_summary(false),
        "missed": missed_summary(missed),
        "mistakes": mistake_items(false, missed),
    }
    return figures, families, family_class


def _run_frames(
    args: argparse.Namespace,
    source: RoomSource,
    jobs: int,
    opts: dict[str, Any],
    doc: dict[str, Any],
) -> None:
    """(e): single frames of the simulated rooms, printed and put in ``doc["frames"]``."""
    t0 = time.perf_counter()
    scans = frames_set(source.room_types, quick=args.quick, first_seed=args.sim_seeds)
    if args.frames_set is not None:
        folder, sources = pinned_simulated_set(args.frames_set, scans, option="--frames-set")
        reused = True
    else:
        folder, sources, reused = build_simulated_set(args.out, source, scans, jobs)
    t_gen = time.perf_counter() - t0
    t0 = time.perf_counter()
    ev = evaluate_dataset(folder, scenes=sources, jobs=jobs, detect_options=opts)
    figures, families, family_class = simulated_figures(ev, scans)
    doc["frames"] = {
        "cache": str(folder),
        "reused_cache": reused,
        "generate_seconds": round(t_gen, 1),
        "scans": [s.name for s in scans],
        **figures,
        "seconds": round(time.perf_counter() - t0, 1),
    }
    what = "reused from" if reused else "generated in"
    console.print(f"single frames: {len(scans)} frames, {what} {folder}")
    print_simulated(
        "Single frames", f"{len(ev.scenes)} frames", ev, scans, figures, families, family_class
    )


def print_simulated(
    title: str,
    what: str,
    ev: DatasetEvaluation,
    scans: Sequence[SimScan],
    figures: Mapping[str, Any],
    families: Mapping[str, Any],
    family_class: Mapping[str, str],
    *,
    variants: bool = False,
) -> None:
    """The tables of :func:`simulated_figures` (with ``variants``, by sensor and artefact
    too), each titled ``title``."""
    by_name = {s.name: s for s in scans}
    console.print(class_table(f"{title}: {what}", figures["per_class"]))
    rooms = Counter(by_name[o.name].room for o in ev.scenes)
    console.print(
        group_table(f"{title}: by room type", "room type", figures["by_room_type"], rooms)
    )
    if variants:
        kinds = Counter(by_name[o.name].variant for o in ev.scenes)
        console.print(
            group_table(f"{title}: by sensor and artefact", "scan", figures["by_variant"], kinds)
        )
    console.print(family_table(families, family_class, title=title))
    console.print(
        false_table(f"{title}: what the false detections are", figures["false_detections"])
    )
    console.print(missed_table(f"{title}: where the missed objects were lost", figures["missed"]))
    console.print(lacks_table(f"{title}: what the scored misses lacked", figures["missed"]))


def _named_scans(
    args: argparse.Namespace, real_scenes: list[SceneSource], source: RoomSource
) -> list[SceneSource]:
    """``--stability-scans``: real scans of ``--real`` and simulated scans of the set."""
    names = [n.strip() for n in args.stability_scans.split(",") if n.strip()]
    real = {s.name: s for s in real_scenes}
    scans = simulated_set(source.room_types, first_seed=args.sim_seeds)
    folder = args.sim_set or args.out
    if args.sim_set is None:
        # --out may hold the single frames' set beside the simulated set: the one that has
        # the simulated set's scans.
        wanted = {s.name for s in scans}
        folder = next(
            (
                f
                for f in sorted(args.out.glob(f"sim-{source.name}-*"))
                if wanted <= manifest_scans(f)
            ),
            args.out,
        )
    sim = {s.name: s for s in _sources(folder, scans)}
    unknown = [n for n in names if n not in real and n not in sim]
    if unknown:
        raise InvalidParameterError(
            "--stability-scans", "names of real scans or of the simulated set's scans", unknown
        )
    return [real[n] if n in real else sim[n] for n in names]


def _run_stability(
    args: argparse.Namespace,
    picked: list[SceneSource],
    jobs: int,
    opts: dict[str, Any],
    doc: dict[str, Any],
    start: float,
) -> int:
    """(c): the picked scans turned, moved and rounded, printed and put in ``doc``."""
    turns = args.turns or (QUICK_STABILITY_TURNS if args.quick else STABILITY_TURNS)
    t0 = time.perf_counter()
    seeds = args.stability_seeds or (opts["seed"],)
    runs = {k: stability(picked, turns, jobs, {**opts, "seed": k}) for k in seeds}
    stab = runs[seeds[0]] if len(seeds) == 1 else pooled_seeds(runs)
    stab["seconds"] = round(time.perf_counter() - t0, 1)
    doc["stability"] = stab
    console.print(
        stability_table(
            f"Stability: detections that reappear (same label, IoU >= {STABILITY_IOU})"
            + (f", detection seeds {', '.join(map(str, seeds))}" if len(seeds) > 1 else ""),
            stab,
        )
    )
    if stab.get("unsteady"):
        console.print(
            unsteady_table("Stability: the reference detections that did not always reappear", stab)
        )
    return _finish(args.out, doc, start)


def _run_real(
    args: argparse.Namespace,
    real_scenes: list[SceneSource],
    jobs: int,
    opts: dict[str, Any],
    doc: dict[str, Any],
) -> DatasetEvaluation:
    """(a): the real development scans, printed and put in ``doc["real"]``."""
    t0 = time.perf_counter()
    real = evaluate_dataset(args.real, scenes=real_scenes, jobs=jobs, detect_options=opts)
    real_false, _, _, real_missed = mistakes_and_families(real.scenes)
    doc["real"] = {
        "scans": [s.name for s in real.scenes],
        "per_class": dataset_figures(real),
        "false_detections": false_summary(real_false),
        "missed": missed_summary(real_missed),
        "mistakes": mistake_items(real_false, real_missed),
        "seconds": round(time.perf_counter() - t0, 1),
    }
    console.print(
        class_table(f"Real: {len(real.scenes)} development scans", doc["real"]["per_class"])
    )
    console.print(
        false_table("Real: what the false detections are", doc["real"]["false_detections"])
    )
    console.print(missed_table("Real: where the missed objects were lost", doc["real"]["missed"]))
    console.print(lacks_table("Real: what the scored misses lacked", doc["real"]["missed"]))
    return real


def _finish(out: Path, doc: dict[str, Any], start: float) -> int:
    """Write ``out/generalization.json`` and say how long each measurement took."""
    doc["seconds"] = round(time.perf_counter() - start, 1)
    path = out / "generalization.json"
    path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    parts = ", ".join(
        f"{key} {doc[key]['seconds']:.0f} s"
        for key in ("real", "robustness", "frames", "simulated", "sparse", "stability")
        if key in doc
    )
    console.print(f"wall time {doc['seconds']:.0f} s ({parts}); written to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
