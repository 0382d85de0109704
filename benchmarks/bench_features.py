"""Features: what one measure of the ontology reads on every cluster, by what it really is.

Run as ``python -m benchmarks features --feature NAME (--sim-set DIR | --real DIR) [...]``.

A rule of the ontology is a bound on a measure (docs/ontology.md lists them). Before a bound
is written from a standard or a physical argument, it is worth seeing what the measure reads
on the objects the rule must keep and on those it should turn away: the desks a table's
``open_below`` turns down, the WC seats a chair's seat should not take. Every scan of a
labelled set (a simulated set written by ``python -m benchmarks generalization``, whose
objects have a kind such as ``desk`` or ``chair-office``; real scans in ScanNet's VoteNet
layout, whose objects have an NYU40 class) is segmented and its clusters described as one
pass of the detector makes them (``segment``, ``describe_clusters`` with the sensor's
position for a single view); each cluster is named by the labelled object holding most of
its points (``nothing`` for unlabelled points).

A part feature (``--feature sunk``) gives one value per plane of a cluster that passes
the filters (``--tilt``, ``--height`` above the floor, ``--min-area``); a cluster feature
(``--feature cluster.height``) one value per cluster. The table gives, per kind, how many
values there are, how many were not measured (NaN), their quantiles and, with ``--bound``,
the share inside a bound (``min=0.35``, ``max=0.3``, or both). ``--jsonl FILE`` writes every
value with its scan, cluster, kind and plane, and with what the ontology reads the cluster as
on its own (``read_as``: its most probable class, or ``none``; one pass, no room prior, no
vote). ``--read-as chair,easy_chair`` keeps only the clusters read as one of those classes:
the ones a rule on them can take or give back.

With ``--of CLASS`` the measure is read as that class's score reads it: on its best
assignment of planes to parts in every cluster, ``<part>.<feature>`` on the plane it gives
the part and ``<a>~<b>.<feature>`` (a relation feature, ``behind``, ``gap``...) between
the planes of two parts, not measured where a part has no plane. ``--ontology`` and
``--ontology-only`` take ontology files as ``ontodetect detect`` does.

``--separate KINDS`` ranks measures by what they set apart from those kinds (kind prefixes:
``chair`` takes ``chair-office``): how many clusters of other kinds read outside the range
the clusters of ``KINDS`` read, below and above (:func:`separation`). With ``--of CLASS
--feature all`` every measure of the class's best assignment is read at once
(:func:`assignment_values`), and only that ranking is shown.

Examples::

    python -m benchmarks features --sim-set bench-output/base5/sim-furnished-<digest> \\
        --real path/to/scannet-dev --feature sunk --tilt 0 8 --height 0.3 0.62 --min-area 0.04
    python -m benchmarks features --real path/to/scannet-dev --feature cluster.height \\
        --bound max=1.3 --kinds chair,table
    python -m benchmarks features --real path/to/scannet-dev --of chair \\
        --feature backrest~seat.behind --bound max=-0.1
    python -m benchmarks features --real path/to/scannet-dev --of chair \\
        --feature seat~backrest.aside --read-as chair,easy_chair --bound max=0.25
    python -m benchmarks features --real path/to/scannet-dev --of chair --feature all \\
        --read-as chair,easy_chair --separate chair,armchair,lounge-chair,recliner
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import warnings
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

from benchmarks.bench_generalization import (
    add_rule_options,
    manifest_scans,
    ontology_option,
    scene_labels,
)
from ontodetect.cloud import DataWarning, sensor_position
from ontodetect.config import Config
from ontodetect.errors import InvalidParameterError, OntoDetectError
from ontodetect.evaluation import SceneSource, discover_scenes, load_scene, map_scenes
from ontodetect.ontology import (
    CLUSTER_FEATURES,
    FEATURES,
    NONE,
    PART_FEATURES,
    RELATION_FEATURES,
    part_values,
    score_cluster,
)

#: Prefix of a cluster feature's name on the command line (``cluster.height``).
CLUSTER_PREFIX = "cluster."
#: Quantiles the table shows.
QUANTILES = (0.0, 0.1, 0.5, 0.9, 1.0)
#: What a cluster of unlabelled points is called.
NOTHING = "nothing"
#: The plane filters that let every plane through.
ALL_TILTS = (0.0, 90.0)
ALL_HEIGHTS = (-math.inf, math.inf)
#: ``--feature all``: every feature of a class's best assignment (with ``--of``).
ALL = "all"
#: ``--separate``: a cluster counts for the kind holding at least this share of its points.
SEPARATE_SHARE = 0.5


@dataclass(frozen=True)
class Survey:
    """What to measure and on which planes.

    Attributes
    ----------
    feature : str
        A part feature's name, or ``cluster.<name>`` for a cluster feature. With ``of``,
        ``<part>.<name>`` (a part feature on the plane the class gives that part),
        ``<a>~<b>.<name>`` (a relation feature between the planes of parts a and b), or
        ``all``: every one of those and every cluster feature (:func:`assignment_values`).
    tilt, height : (float, float)
        Planes whose tilt (degrees) and height above the floor (m) lie in these closed
        ranges; part features without ``of`` only.
    min_area : float
        Planes of at least this area (m²); part features without ``of`` only.
    of : str, optional
        A class of the ontology: the feature is read on its best assignment of planes to
        parts in every cluster (NaN where a part has no plane), as its score reads it.
    """

    feature: str
    tilt: tuple[float, float] = ALL_TILTS
    height: tuple[float, float] = ALL_HEIGHTS
    min_area: float = 0.0
    of: str | None = None

    @property
    def scope(self) -> str:
        """``cluster``, ``part``, ``relation`` or ``all``."""
        if self.feature == ALL:
            return ALL
        if self.feature.startswith(CLUSTER_PREFIX):
            return "cluster"
        return "relation" if self.of is not None and "~" in self.feature else "part"

    @property
    def name(self) -> str:
        """The feature's own name."""
        if self.scope == "cluster":
            return self.feature[len(CLUSTER_PREFIX) :]
        return self.feature.rpartition(".")[2] if self.of is not None else self.feature

    @property
    def parts(self) -> tuple[str, ...]:
        """With ``of``: the part, or the two parts of a relation, the feature is read on."""
        if self.of is None or self.scope in ("cluster", ALL):
            return ()
        return tuple(self.feature.rpartition(".")[0].split("~"))

    def check(self, ontology: Any = None) -> Survey:
        """This survey, or InvalidParameterError naming what is wrong (``ontology``: the
        one ``of`` names a class of; the built-in one by default)."""
        if self.scope == ALL:
            if self.of is None:
                raise InvalidParameterError("--feature", "all with --of CLASS", self.feature)
            class_of(self.of, ontology)
            return self
        known = {"cluster": CLUSTER_FEATURES, "part": PART_FEATURES}.get(
            self.scope, RELATION_FEATURES
        )
        if self.name not in known:
            prefix = CLUSTER_PREFIX if self.scope == "cluster" else ""
            raise InvalidParameterError(
                "--feature",
                f"a {self.scope} feature ({', '.join(prefix + n for n in sorted(known))})",
                self.feature,
            )
        for option, (lo, hi) in (("--tilt", self.tilt), ("--height", self.height)):
            if not lo <= hi:
                raise InvalidParameterError(option, "MIN MAX with MIN <= MAX", f"{lo} {hi}")
        if self.of is None:
            return self
        if (self.tilt, self.height, self.min_area) != (ALL_TILTS, ALL_HEIGHTS, 0.0):
            raise InvalidParameterError(
                "--of", "not combined with --tilt, --height or --min-area", self.of
            )
        cls = class_of(self.of, ontology)
        names = [p.name for p in cls.parts]
        if self.scope != "cluster" and (
            not self.parts
            or len(self.parts) != (2 if self.scope == "relation" else 1)
            or any(p not in names for p in self.parts)
        ):
            form = "A~B.feature" if self.scope == "relation" else "PART.feature"
            raise InvalidParameterError(
                "--feature", f"{form} with parts of {self.of} ({', '.join(names)})", self.feature
            )
        return self


def class_of(name: str, ontology: Any = None) -> Any:
    """The class ``name`` of ``ontology`` (the built-in one by default), or
    InvalidParameterError naming the classes there are."""
    from ontodetect.ontology import builtin_ontology

    rules = ontology or builtin_ontology()
    if name not in rules:
        raise InvalidParameterError("--of", f"a class ({', '.join(rules.names)})", name)
    return rules[name]


def parse_bound(text: str | None) -> tuple[float, float] | None:
    """``min=A``, ``max=B`` or ``min=A,max=B`` as (low, high); None for no bound.

    >>> parse_bound("min=0.35"), parse_bound("max=0.3,min=0.1"), parse_bound(None)
    ((0.35, inf), (0.1, 0.3), None)
    """
    if text is None:
        return None
    low, high = -math.inf, math.inf
    for item in text.split(","):
        key, _, value = item.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if key.strip() not in ("min", "max") or not math.isfinite(number):
            raise InvalidParameterError("--bound", "min=A, max=B or min=A,max=B", text)
        if key.strip() == "min":
            low = number
        else:
            high = number
    if low > high:
        raise InvalidParameterError("--bound", "min <= max", text)
    return low, high


def cluster_names(source: SceneSource, cloud: Any, seg: Any) -> list[tuple[str, float]]:
    """What each cluster of ``seg`` really is, by the labelled object holding most of its
    points (the kind in a simulated set, the class in a real one), and that object's share
    of the cluster's points."""
    instance, what = scene_labels(source, cloud)
    rows = np.arange(len(cloud)) if cloud.index is None else np.asarray(cloud.index)
    out = []
    for c in seg:
        ids = instance[rows[np.asarray(c.point_indices)]]
        if not len(ids):
            out.append((NOTHING, 0.0))
            continue
        values, counts = np.unique(ids, return_counts=True)
        best = int(values[int(np.argmax(counts))])
        name = NOTHING if best <= 0 else what.get(best, (NOTHING, NOTHING))[1]
        out.append((name, float(counts.max() / counts.sum())))
    return out


def survey_values(
    desc: Any, survey: Survey, assignment: Mapping[str, int | None] | None = None
) -> list[tuple[int | None, float]]:
    """(plane index or None, value) of one cluster description: every plane that passes
    the survey's filters for a part feature, the cluster itself for a cluster feature;
    with ``survey.of``, the plane the class's best ``assignment`` of planes to parts gives
    the part (None and NaN where it gives none) or the relation between its two parts'
    planes (index None)."""
    if survey.scope == "cluster":
        return [(None, float(FEATURES["cluster"][survey.name].cluster(desc)))]
    if survey.of is not None:
        planes = [(assignment or {}).get(p) for p in survey.parts]
        if any(i is None for i in planes):
            return [(None, math.nan)]
        if survey.scope == "relation":
            return [(None, float(FEATURES["relation"][survey.name].relation(desc, *planes)))]
        return [(planes[0], float(part_values(desc, survey.name)[planes[0]]))]
    values = part_values(desc, survey.name)
    out = []
    for i, plane in enumerate(desc.planes):
        if (
            survey.tilt[0] <= float(plane.tilt) <= survey.tilt[1]
            and survey.height[0] <= float(plane.height) <= survey.height[1]
            and float(plane.area) >= survey.min_area
        ):
            out.append((i, float(values[i])))
    return out


def assignment_values(desc: Any, assignment: Mapping[str, int | None]) -> dict[str, float]:
    """Every feature a class's best ``assignment`` of planes to parts gives one cluster,
    named as ``--feature`` names them: ``<part>.<name>`` for each part with a plane,
    ``<a>~<b>.<name>`` for each ordered pair of them (a relation may read differently
    from b, ``behind``), and ``cluster.<name>``; NaN where a measure is not taken."""
    out: dict[str, float] = {}
    planes = {part: i for part, i in assignment.items() if i is not None}
    for name in PART_FEATURES:
        values = part_values(desc, name)  # every plane's, once
        for part, i in planes.items():
            out[f"{part}.{name}"] = float(values[i])
    for a, i in planes.items():
        for b, j in planes.items():
            if a != b:
                for name in RELATION_FEATURES:
                    value = FEATURES["relation"][name].relation(desc, i, j)
                    out[f"{a}~{b}.{name}"] = float(value)
    for name in CLUSTER_FEATURES:
        out[CLUSTER_PREFIX + name] = float(FEATURES["cluster"][name].cluster(desc))
    return out


def measure_scan(
    source: SceneSource,
    survey: Survey,
    overrides: Sequence[str] = (),
    ontology: tuple[tuple[str, ...], bool] = ((), False),
) -> list[dict[str, Any]]:
    """Every value of the survey on one labelled scan (a unit of work for ``map_scenes``);
    ``ontology``: files and whether they replace the built-in ontology (``--ontology``,
    ``--ontology-only``), which segments the scan and holds ``survey.of``."""
    from ontodetect.ontology import builtin_ontology, load_ontology
    from ontodetect.segment import describe_clusters, segment

    files, only = ontology
    rules = load_ontology(*files, replace=only) if files else builtin_ontology()
    survey.check(rules)  # the class ``of`` names is one of these rules'
    config = Config().with_overrides(list(overrides))
    cloud = load_scene(source).cloud
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataWarning)
        seg = segment(cloud, config, ontology=rules)
        descs = describe_clusters(seg, sensor_position(cloud))
    rows = []
    for k, ((name, share), desc) in enumerate(zip(cluster_names(source, cloud, seg), descs)):
        # Every class scored once: what the cluster is read as, and the assignment ``of`` reads.
        scores = score_cluster(desc, rules)
        assignment = scores.classes[survey.of].assignment if survey.of is not None else None
        if survey.scope == ALL:
            assert assignment is not None  # checked: all needs of
            values = [(f, None, v) for f, v in assignment_values(desc, assignment).items()]
        else:
            values = [(survey.feature, i, v) for i, v in survey_values(desc, survey, assignment)]
        for feature, plane, value in values:
            rows.append(
                {
                    "scene": source.name,
                    "cluster": k,
                    "feature": feature,
                    "plane": plane,
                    "kind": name,
                    "share": round(share, 4),
                    "read_as": scores.best,
                    "value": None if math.isnan(value) else value,
                }
            )
    return rows


def names_option(text: str) -> tuple[str, ...]:
    """The names of a comma-separated option, stripped, empty ones left out.

    >>> names_option(" chair, ,armchair")
    ('chair', 'armchair')
    """
    return tuple(n.strip() for n in text.split(",") if n.strip())


def read_as_option(text: str | None, ontology: Any = None) -> frozenset[str] | None:
    """The classes of ``--read-as CLASS,...`` (``none`` too), checked against ``ontology``
    (the built-in one by default); None when the option is not given.

    >>> sorted(read_as_option("chair, none"))
    ['chair', 'none']
    """
    if text is None:
        return None
    from ontodetect.ontology import builtin_ontology

    names = set((ontology or builtin_ontology()).names) | {NONE}
    wanted = frozenset(names_option(text))
    if not wanted or not wanted <= names:
        raise InvalidParameterError("--read-as", f"classes ({', '.join(sorted(names))})", text)
    return wanted


def summarize(
    rows: Sequence[Mapping[str, Any]], bound: tuple[float, float] | None = None
) -> dict[str, dict[str, Any]]:
    """Per kind (most measured values first): how many values, how many not measured, their
    quantiles (:data:`QUANTILES`) and, with ``bound``, how many lie inside it.

    >>> rows = [{"kind": "desk", "value": v} for v in (0.0, 0.1, 0.5)] + [
    ...     {"kind": "table", "value": None}]
    >>> s = summarize(rows, (0.35, math.inf))
    >>> s["desk"]["n"], s["desk"]["inside"], s["desk"]["quantiles"][2], s["table"]["nan"]
    (3, 1, 0.1, 1)
    """
    by: dict[str, list[float]] = {}
    for r in rows:
        by.setdefault(str(r["kind"]), []).append(math.nan if r["value"] is None else r["value"])
    out = {}
    measured = {k: sum(not math.isnan(x) for x in v) for k, v in by.items()}
    for kind, values in sorted(by.items(), key=lambda kv: (-measured[kv[0]], -len(kv[1]), kv[0])):
        v = np.asarray(values, dtype=np.float64)
        known = v[~np.isnan(v)]
        out[kind] = {
            "n": len(v),
            "nan": int(len(v) - len(known)),
            "quantiles": [float(q) for q in np.quantile(known, QUANTILES)] if len(known) else [],
            "inside": None
            if bound is None
            else int(np.count_nonzero((known >= bound[0]) & (known <= bound[1]))),
        }
    return out


def summary_table(
    title: str, summary: Mapping[str, Mapping[str, Any]], bound: tuple[float, float] | None
) -> Table:
    table = Table(title=title)
    table.add_column("really is", no_wrap=True)
    for name in ("values", "NaN", "min", "10 %", "median", "90 %", "max"):
        table.add_column(name, justify="right")
    if bound is not None:
        table.add_column(f"in [{bound[0]:g}, {bound[1]:g}]", justify="right", no_wrap=True)
    for kind, s in summary.items():
        qs = [f"{q:.3g}" for q in s["quantiles"]] or ["-"] * len(QUANTILES)
        cells = [kind, str(s["n"]), str(s["nan"]), *qs]
        if bound is not None:
            known = s["n"] - s["nan"]
            cells.append(f"{s['inside']} of {known}" if known else "-")
        table.add_row(*cells)
    return table


def separation(rows: Sequence[Mapping[str, Any]], kinds: Sequence[str]) -> list[dict[str, Any]]:
    """Per feature, how the clusters of other kinds fall against the range the clusters of
    ``kinds`` (kind prefixes: ``chair`` takes ``chair-office``) read: the values of those
    outside it, below and above, worst first. A bound at the edge of the range would take
    away exactly those and keep every cluster of ``kinds``; a feature no cluster of
    ``kinds`` measures is left out. A cluster counts for the kind holding at least
    :data:`SEPARATE_SHARE` of its points, and not at all below that.

    >>> rows = [{"feature": "h", "kind": k, "share": 1.0, "value": v}
    ...         for k, v in [("chair-a", 0.4), ("chair-b", 0.5), ("wc", 0.3), ("desk", 0.7)]]
    >>> [(s["feature"], s["range"], s["below"], s["above"]) for s in separation(rows, ["chair"])]
    [('h', (0.4, 0.5), [(0.3, 'wc')], [(0.7, 'desk')])]
    """
    kept: dict[str, list[float]] = {}
    other: dict[str, list[tuple[float, str]]] = {}
    for r in rows:
        if r["value"] is None or r["share"] < SEPARATE_SHARE:
            continue
        kind = str(r["kind"])
        if any(kind.startswith(k) for k in kinds):
            kept.setdefault(r["feature"], []).append(float(r["value"]))
        else:
            other.setdefault(r["feature"], []).append((float(r["value"]), kind))
    out = []
    for feature, values in kept.items():
        lo, hi = min(values), max(values)
        rest = sorted(other.get(feature, []))
        out.append(
            {
                "feature": feature,
                "range": (lo, hi),
                "kept": len(values),
                "others": len(rest),
                "below": [x for x in rest if x[0] < lo],
                "above": [x for x in rest if x[0] > hi],
            }
        )
    out.sort(key=lambda s: (-(len(s["below"]) + len(s["above"])), s["feature"]))
    return out


def separation_table(title: str, rows: Sequence[Mapping[str, Any]], top: int) -> Table:
    """The ``top`` features of :func:`separation` that set most clusters apart."""
    table = Table(title=title)
    table.add_column("feature", no_wrap=True)
    for name in ("kept", "range", "others", "below", "above"):
        table.add_column(name, justify="right", no_wrap=True)
    table.add_column("set apart (kind: count)")
    for s in rows[:top]:
        apart = Counter(kind for _, kind in s["below"] + s["above"])
        lo, hi = s["range"]
        table.add_row(
            s["feature"],
            str(s["kept"]),
            f"{lo:.3g} – {hi:.3g}",
            str(s["others"]),
            str(len(s["below"])),
            str(len(s["above"])),
            ", ".join(f"{k}: {n}" for k, n in apart.most_common(6)),
        )
    return table


def scan_sources(sim_set: Path | None, real: Path | None) -> list[SceneSource]:
    """The labelled scans of a simulated set (its manifest's scans) and of a real folder."""
    sources = []
    if sim_set is not None:
        names = sorted(manifest_scans(sim_set))
        if not names:
            raise InvalidParameterError(
                "--sim-set", "a simulated set's folder (manifest.json)", sim_set
            )
        sources += [SceneSource(n, str(sim_set / n), "ontodetect", n) for n in names]
    if real is not None:
        sources += discover_scenes(real, "scannet-votenet")
    return sources


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks features", description=__doc__.splitlines()[0]
    )
    ap.add_argument(
        "--feature",
        required=True,
        help="a part feature, or cluster.<name>; with --of, <part>.<name>, <a>~<b>.<name> or all",
    )
    ap.add_argument("--of", metavar="CLASS", help="read it on this class's best assignment")
    ap.add_argument("--sim-set", type=Path, help="a simulated set written by the benchmark")
    ap.add_argument("--real", type=Path, help="labelled real scans (ScanNet, VoteNet layout)")
    ap.add_argument("--tilt", type=float, nargs=2, default=ALL_TILTS, metavar=("MIN", "MAX"))
    ap.add_argument("--height", type=float, nargs=2, default=ALL_HEIGHTS, metavar=("MIN", "MAX"))
    ap.add_argument("--min-area", type=float, default=0.0, help="smallest plane (m²)")
    ap.add_argument("--bound", help="count the values inside min=A, max=B or min=A,max=B")
    ap.add_argument("--kinds", help="only these kinds, comma-separated")
    ap.add_argument(
        "--read-as",
        metavar="CLASSES",
        help="only clusters the ontology reads as one of these classes (or none), on their own",
    )
    ap.add_argument(
        "--separate",
        metavar="KINDS",
        help="rank the features by how many clusters of other kinds lie outside the range "
        "these kinds read (kind prefixes, comma-separated: chair takes chair-office)",
    )
    ap.add_argument("--top", type=int, default=15, help="features --separate shows")
    add_rule_options(ap)
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (0: one per CPU)")
    ap.add_argument("--jsonl", type=Path, help="write every value to this file")
    args = ap.parse_args(argv)
    try:
        rules = ontology_option(args.ontologies, args.ontology_only)
        survey = Survey(
            args.feature, tuple(args.tilt), tuple(args.height), args.min_area, args.of
        ).check(rules)
        bound = parse_bound(args.bound)
        read_as = read_as_option(args.read_as, rules)
        separate = separate_option(args.separate)
        if survey.scope == ALL and separate is None:
            raise InvalidParameterError("--feature", "all with --separate KINDS", survey.feature)
        if args.top < 1:
            raise InvalidParameterError("--top", "an integer >= 1", args.top)
        Config().with_overrides(args.overrides)
        if args.sim_set is None and args.real is None:
            raise InvalidParameterError("--sim-set", "a simulated set, --real, or both", None)
        sources = scan_sources(args.sim_set, args.real)
        ontology = (tuple(str(f) for f in args.ontologies), args.ontology_only)
        units = [(s, survey, tuple(args.overrides), ontology) for s in sources]
        runs = map_scenes(_unit, units, jobs=args.jobs, description="Measuring clusters")
    except OntoDetectError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    rows = [r for run in runs for r in run]
    if args.kinds:
        keep = set(names_option(args.kinds))
        rows = [r for r in rows if r["kind"] in keep]
    if read_as is not None:
        rows = [r for r in rows if r["read_as"] in read_as]
    if args.jsonl is not None:
        args.jsonl.write_text("".join(json.dumps(r) + "\n" for r in rows))
    of = f" of {survey.of}" if survey.of is not None else ""
    seen = f", read as {args.read_as}" if read_as is not None else ""
    console = Console()
    if survey.scope != ALL:
        title = f"{survey.feature}{of} on {len(sources)} scans{seen}, by what the cluster really is"
        console.print(summary_table(title, summarize(rows, bound), bound))
    if separate is not None:
        title = (
            f"features{of} on {len(sources)} scans{seen} that set other kinds apart from "
            f"{', '.join(separate)}"
        )
        console.print(separation_table(title, separation(rows, separate), args.top))
    return 0


def separate_option(text: str | None) -> tuple[str, ...] | None:
    """The kind prefixes of ``--separate KIND,...``; None when the option is not given.

    >>> separate_option("chair, armchair"), separate_option(None)
    (('chair', 'armchair'), None)
    """
    if text is None:
        return None
    kinds = names_option(text)
    if not kinds:
        raise InvalidParameterError("--separate", "kinds, comma-separated", text)
    return kinds


def _unit(unit: tuple[Any, ...]) -> list[dict[str, Any]]:
    return measure_scan(*unit)


if __name__ == "__main__":
    raise SystemExit(main())
