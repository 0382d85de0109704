"""Compare two runs of the generalization benchmark: every figure before → after.

Run as ``python -m benchmarks compare BEFORE.json AFTER.json [--iou 0.25]``, with two
``generalization.json`` files written by ``python -m benchmarks generalization``. A change to
the method is kept only when it helps the simulated rooms, costs nothing on the real scans
and keeps stability (docs/ontology.md, "How a prior is chosen"); this prints the three side
by side, so that the note of a change can give all three:

- real and simulated scans and the simulated single frames: TP / detections / ground truth,
  precision and recall per class;
- simulated scans and frames by room type: TP / detections per reported class;
- the false detections by what they really are, the objects missed by where they were
  lost (not clustered, split, merged into another object's cluster, scored as another class,
  lost in the vote), and the chair groups' recall;
- robustness: TP / detections / ground truth and precision and recall per class on the real
  scans changed as sensors change them (noise, a floor unseen, points doubled, half the
  points);
- sparse: the same on the simulated fused scans with half and a quarter of their points;
- stability: mean and worst, and per change of the scan; the reference detections some
  change lost, by scan and by what they really are, and how many changes lost each;
- the objects that changed, one by one (for runs that list their ``mistakes``), in each part
  and under each robustness change: which missed object of which scan is found now or lost
  now, and which false detections came or went.

A part one of the runs did not measure (``--only``) is left out, and said so. Rows that did
not change are printed dim; ``--changed`` prints only the rows that did. ``--markdown``
prints Markdown tables instead, to paste into a note or docs/benchmarks.md.

Either side may be several runs, comma-separated (the same change under detection seeds
0, 1 and 2: ``--seed``): they are pooled (:func:`pool_runs`), every count summed, so that a
change is judged over several draws of MSAC's samples rather than one. The objects one by
one and stability, which belong to one run, are left out of a pooled side.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from ._generalization import MISSED_CAUSES, POOLED, class_figures, pooled_orientations
from .bench_generalization import THRESHOLDS

console = Console(highlight=False)
err = Console(stderr=True, highlight=False)

#: The generalization benchmark's file format this reads (``format`` in the JSON).
FORMATS = ("ontodetect.bench.generalization/1",)


class CompareError(Exception):
    """A file that is not a generalization benchmark result: one line for the user."""


def load_runs(paths: str) -> dict[str, Any]:
    """One ``generalization.json``, or several comma-separated ones pooled (:func:`pool_runs`)."""
    docs = [load_run(Path(p)) for p in paths.split(",") if p.strip()]
    if not docs:
        raise CompareError(f"{paths!r}: no generalization.json named")
    return docs[0] if len(docs) == 1 else pool_runs(docs)


def load_run(path: Path) -> dict[str, Any]:
    """A ``generalization.json``, checked enough to compare (:class:`CompareError` if not)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise CompareError(f"{path}: cannot read it ({exc.strerror or exc})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CompareError(f"{path}: not JSON (line {exc.lineno}: {exc.msg})") from None
    parts = ("real", "robustness", "simulated", "stability", "frames", "sparse")
    if not isinstance(doc, dict) or not any(k in doc for k in parts):
        raise CompareError(
            f"{path}: not a generalization benchmark result (no 'real', 'robustness', "
            "'simulated', 'stability', 'frames' or 'sparse' part)"
        )
    fmt = doc.get("format")
    if fmt is not None and fmt not in FORMATS:
        raise CompareError(f"{path}: format {fmt!r}, expected one of {', '.join(FORMATS)}")
    return doc


#: Parts and lists that belong to one run: left out of pooled runs.
PER_RUN = frozenset({"stability", "mistakes"})
#: Subtrees whose numbers are counts of objects: summed when runs are pooled.
COUNTS = frozenset({"missed", "false_detections"})


def pool_runs(docs: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Several runs of the benchmark as one: every class's TP, detections and ground truth
    summed (precision and recall from the sums), and the counts of the missed objects and
    false detections, in every part all the runs measured; the rest as the first run has
    it, but for :data:`PER_RUN`.

    >>> one = {"real": {"per_class": {"iou@0.25": {"chair": {"tp": 2, "det": 3, "gt": 4}}}}}
    >>> pool_runs([one, one])["real"]["per_class"]["iou@0.25"]["chair"]
    {'tp': 4, 'det': 6, 'gt': 8, 'precision': 0.6667, 'recall': 0.5}
    """
    return _pooled(list(docs), counts=False, top=True)


def _pooled(objs: list[Any], *, counts: bool, top: bool = False) -> Any:
    first = objs[0]
    if isinstance(first, Mapping):
        if {"tp", "det", "gt"} <= set(first) and all(isinstance(o, Mapping) for o in objs):
            tp, det, gt = (sum(int(o.get(k, 0)) for o in objs) for k in ("tp", "det", "gt"))
            return class_figures(tp, det, gt)
        maps = [o for o in objs if isinstance(o, Mapping)]
        # Counts: a kind one run never met counts 0 there. Anything else: what every run has.
        keys = dict.fromkeys(k for o in maps for k in o) if counts else first
        return {
            k: _pooled([o[k] for o in maps if k in o], counts=counts or k in COUNTS)
            for k in keys
            if not (k in PER_RUN or (top and k == "pooled_runs"))
            and (counts or all(isinstance(o, Mapping) and k in o for o in objs))
        } | ({"pooled_runs": len(objs)} if top else {})
    if counts and all(isinstance(o, int) and not isinstance(o, bool) for o in objs):
        return sum(objs)
    return first


def _key(iou: float) -> str:
    return f"iou@{iou:g}"


def _cell(fig: Mapping[str, Any] | None) -> str:
    """``TP/det/GT`` of one class's figures; ``-`` when the run has none."""
    if not fig:
        return "-"
    return f"{fig.get('tp', 0)}/{fig.get('det', 0)}/{fig.get('gt', 0)}"


def _pr(fig: Mapping[str, Any] | None) -> str:
    if not fig:
        return "-"
    return f"{fig.get('precision', 0.0):.2f} / {fig.get('recall', 0.0):.2f}"


def class_rows(
    before: Mapping[str, Any] | None, after: Mapping[str, Any] | None
) -> list[tuple[str, str, str, str, str]]:
    """Per class: name, TP/det/GT before and after, P / R before and after."""
    before, after = before or {}, after or {}
    names = _ordered(list(before) + list(after))
    return [
        (c, _cell(before.get(c)), _cell(after.get(c)), _pr(before.get(c)), _pr(after.get(c)))
        for c in names
    ]


def _ordered(names: Iterable[str]) -> list[str]:
    """Unique names in first-seen order, ``overall`` last."""
    seen = list(dict.fromkeys(names))
    return [n for n in seen if n != "overall"] + (["overall"] if "overall" in seen else [])


def room_rows(
    before: Mapping[str, Any], after: Mapping[str, Any], key: str
) -> tuple[list[str], list[tuple[str, ...]]]:
    """Per simulated room type, TP/det of each reported class before and after: the
    classes, and rows ``(room, class 1 before, class 1 after, class 2 before, ...)``."""
    rooms = _ordered(list(before) + list(after))
    classes = _ordered(c for figs in (*before.values(), *after.values()) for c in figs.get(key, {}))
    classes = [c for c in classes if c != "overall"]

    def cell(figs: Mapping[str, Any] | None, c: str) -> str:
        f = (figs or {}).get(key, {}).get(c)
        return "-" if f is None else f"{f.get('tp', 0)}/{f.get('det', 0)}"

    rows = [
        (r, *(v for c in classes for v in (cell(before.get(r), c), cell(after.get(r), c))))
        for r in rooms
    ]
    return classes, rows


def false_rows(
    before: Mapping[str, Any], after: Mapping[str, Any]
) -> list[tuple[str, int, int, str, str]]:
    """Per kind of false detection (what it really is): total before, after, and as what
    it was detected; most frequent first."""
    kinds = _ordered(list(before) + list(after))

    def total(d: Mapping[str, Any], k: str) -> int:
        return int(d.get(k, {}).get("total", 0))

    def as_(d: Mapping[str, Any], k: str) -> str:
        parts = d.get(k, {}).get("as", {})
        return ", ".join(f"{n} {c}" for n, c in sorted(parts.items(), key=lambda kv: -kv[1]) if c)

    rows = [(k, total(before, k), total(after, k), as_(before, k), as_(after, k)) for k in kinds]
    return sorted(rows, key=lambda r: (-max(r[1], r[2]), r[0]))


def missed_rows(before: Mapping[str, Any], after: Mapping[str, Any]) -> list[tuple[str, int, int]]:
    """Per class, the objects missed before and after: the total, then each cause (where
    the object was lost: ``missed_causes`` of the benchmark), in the benchmark's order,
    then the scored ones by what their class's reading lacked most, the commonest first.

    >>> b = {"chair": {"total": 2, "causes": {"scored": 2}, "lacks": {"seat.missing": 2}}}
    >>> missed_rows(b, {"chair": {"total": 1, "causes": {"scored": 1}}})[-1]
    ('chair, scored, lacking seat.missing', 2, 0)
    """
    rows = []
    for c in _ordered(list(before) + list(after)):
        b, a = before.get(c, {}), after.get(c, {})
        rows.append((f"{c}, all", int(b.get("total", 0)), int(a.get("total", 0))))
        cb, ca = b.get("causes", {}), a.get("causes", {})
        known = [k for k in MISSED_CAUSES if k in cb or k in ca]
        for k in known + _ordered(k for k in (*cb, *ca) if k not in MISSED_CAUSES):
            rows.append((f"{c}, {k}", int(cb.get(k, 0)), int(ca.get(k, 0))))
        lb, la = b.get("lacks", {}), a.get("lacks", {})
        for k in sorted({*lb, *la}, key=lambda k: (-max(lb.get(k, 0), la.get(k, 0)), k)):
            rows.append((f"{c}, scored, lacking {k}", int(lb.get(k, 0)), int(la.get(k, 0))))
    return rows


def object_rows(
    before: Mapping[str, Any] | None, after: Mapping[str, Any] | None
) -> list[tuple[str, str, str]] | None:
    """The objects whose outcome differs between two runs, from their ``mistakes`` at one
    threshold (None when a run has none: written before the benchmark kept them): per
    missed object of either run, ``scan: kind #id`` and what each run made of it (found, or
    where it was lost and as what); per false detection of either run, ``scan: kind #instance
    as label`` and how many there were in each. Sorted by scan.

    >>> b = {"missed": [{"scene": "s1", "id": 4, "label": "chair", "kind": "chair-dining",
    ...                  "cause": "scored", "as": "table"}],
    ...      "false": [{"scene": "s2", "label": "chair", "is": "sink", "kind": "sink",
    ...                 "instance": 9}]}
    >>> for row in object_rows(b, {"missed": [], "false": []}):
    ...     print(row)
    ('s1: chair-dining #4', 'missed (scored, as table)', 'found')
    ('s2: sink #9 as chair', 'false', '-')
    """
    if before is None or after is None:
        return None

    def missed(items: Iterable[Mapping[str, Any]]) -> dict[tuple[str, str], str]:
        out = {}
        for m in items:
            what = m.get("cause", "?") + (f", as {m['as']}" if m.get("as") else "")
            key = (m["scene"], f"{m.get('kind') or m.get('label')} #{m.get('id')}")
            out[key] = f"missed ({what})"
        return out

    def false(items: Iterable[Mapping[str, Any]]) -> dict[tuple[str, str], int]:
        out: dict[tuple[str, str], int] = {}
        for f in items:
            who = f"#{f['instance']}" if f.get("instance") else "(no object)"
            key = (f["scene"], f"{f.get('kind') or f.get('is')} {who} as {f.get('label')}")
            out[key] = out.get(key, 0) + 1
        return out

    rows: list[tuple[str, str, str, str]] = []
    mb, ma = missed(before.get("missed", [])), missed(after.get("missed", []))
    for key in set(mb) | set(ma):
        if mb.get(key) != ma.get(key):
            rows.append((*key, mb.get(key, "found"), ma.get(key, "found")))
    fb, fa = false(before.get("false", [])), false(after.get("false", []))
    for key in set(fb) | set(fa):
        nb, na = fb.get(key, 0), fa.get(key, 0)
        if nb != na:
            rows.append((*key, _times("false", nb), _times("false", na)))
    return [(f"{scene}: {obj}", b, a) for scene, obj, b, a in sorted(rows)]


def _times(word: str, n: int) -> str:
    """'-', the word, or the word and a count."""
    return "-" if n == 0 else word if n == 1 else f"{word} x{n}"


def stability_rows(
    before: Mapping[str, Any], after: Mapping[str, Any]
) -> list[tuple[str, str, str]]:
    """Mean / worst reappearance, overall and per change of the scan, before and after."""

    def fig(s: Mapping[str, Any] | None) -> str:
        if not s or s.get("mean") is None:
            return "-"
        return f"{s['mean']:.4f} / {s['worst']:.4f}"

    rows = [("all", fig(before), fig(after))]
    per_b, per_a = before.get("per_transform", {}), after.get("per_transform", {})
    for name in _ordered(list(per_b) + list(per_a)):
        rows.append((name, fig(per_b.get(name)), fig(per_a.get(name))))
    return rows


def stability_objects(
    before: Mapping[str, Any], after: Mapping[str, Any]
) -> list[tuple[str, str, str]]:
    """The reference detections that some change lost (``unsteady``), before and after:
    per scan, label and what it really is, how many changes lost each such detection,
    where that differs ("-": none was lost). Detections are not matched across runs by
    id (a new detection renumbers the rest), only counted by what they are."""

    def lost(part: Mapping[str, Any]) -> dict[tuple[str, str], list[int]]:
        out: dict[tuple[str, str], list[int]] = {}
        for u in part.get("unsteady", []):
            out.setdefault((u["scene"], f"{u['label']} ({u['is']})"), []).append(
                len(u["lost_under"])
            )
        return {k: sorted(v, reverse=True) for k, v in out.items()}

    total = max(len(before.get("transforms", [])), len(after.get("transforms", [])))

    def cell(counts: list[int] | None) -> str:
        return ", ".join(f"lost {n}/{total}" for n in counts) if counts else "-"

    lb, la = lost(before), lost(after)
    keys = sorted(k for k in set(lb) | set(la) if lb.get(k) != la.get(k))
    return [
        (f"{scene}: {what}", cell(lb.get((scene, what))), cell(la.get((scene, what))))
        for scene, what in keys
    ]


def robustness_rows(
    before: Mapping[str, Any],
    after: Mapping[str, Any],
    real_before: Mapping[str, Any] | None = None,
    real_after: Mapping[str, Any] | None = None,
) -> list[tuple[str, str, str, str, str]]:
    """Per change of the real scans and class: TP/det/GT and P / R, before and after (the
    robustness part is measured at point IoU 0.25 only); with the real part's figures at
    point IoU 0.25, the scans as they are and their axes turned pooled last
    (:func:`pooled_orientations`)."""
    rows = []
    ch_b, ch_a = before.get("changes", {}), after.get("changes", {})
    per_name = {
        name: (ch_b.get(name, {}).get("per_class", {}), ch_a.get(name, {}).get("per_class", {}))
        for name in _ordered(list(ch_b) + list(ch_a))
    }
    pooled = (pooled_orientations(real_before, ch_b), pooled_orientations(real_after, ch_a))
    if any(p is not None for p in pooled):
        per_name[POOLED] = (pooled[0] or {}, pooled[1] or {})
    for name, (fb, fa) in per_name.items():
        for c in _ordered(list(fb) + list(fa)):
            b, a = fb.get(c), fa.get(c)
            rows.append((f"{name}, {c}", _cell(b), _cell(a), _pr(b), _pr(a)))
    return rows


def _table(
    title: str, columns: list[str], rows: list[tuple[Any, ...]], changed: bool
) -> Table | str:
    """The rows as a table, unchanged ones dim (left out with ``changed``), or a line
    saying there is no change when no row is left."""
    if changed or not rows:
        rows = [row for row in rows if not _same(row)]
        if not rows:
            return f"{title}: no change"
    table = Table(title=title, title_justify="left")
    for i, name in enumerate(columns):
        table.add_column(name, justify="left" if i == 0 else "right", no_wrap=i == 0)
    for row in rows:
        table.add_row(*(str(v) for v in row), style="dim" if _same(row) else None)
    return table


def _same(row: tuple[Any, ...]) -> bool:
    """A row is unchanged when its "before" and "after" cells agree pairwise."""
    values = row[1:]
    return all(values[i] == values[i + 1] for i in range(0, len(values) - 1, 2))


def _real(doc: Mapping[str, Any]) -> Mapping[str, Any] | None:
    """The real part's per-class figures at point IoU 0.25 (the robustness part's IoU)."""
    return (doc.get("real") or {}).get("per_class", {}).get("iou@0.25")


def compare(
    before: Mapping[str, Any], after: Mapping[str, Any], *, iou: float = 0.25, changed: bool = False
) -> list[Table | str]:
    """The tables of a comparison (and lines for what cannot be compared)."""
    key = _key(iou)
    out: list[Table | str] = []
    for part, title in (
        ("real", "Real scans"),
        ("simulated", "Simulated rooms"),
        ("frames", "Single frames"),
    ):
        b, a = before.get(part), after.get(part)
        if b is None or a is None:
            out.append(f"{title}: not in {'the first' if b is None else 'the second'} run")
            continue
        out.append(
            _table(
                f"{title}, TP/det/GT at point IoU {iou:g}",
                ["class", "before", "after", "P / R before", "P / R after"],
                class_rows(b["per_class"].get(key), a["per_class"].get(key)),
                changed,
            )
        )
        if part in ("simulated", "frames"):
            classes, rows = room_rows(b.get("by_room_type", {}), a.get("by_room_type", {}), key)
            out.append(
                _table(
                    f"{title} by room type, TP/det",
                    ["room", *(f"{c} {w}" for c in classes for w in ("before", "after"))],
                    rows,
                    changed,
                )
            )
            groups_b = b.get("chair_groups", {}).get(key, {})
            groups_a = a.get("chair_groups", {}).get(key, {})
            out.append(
                _table(
                    f"{title}: chairs by group, found/GT",
                    ["group", "before", "after"],
                    [
                        (
                            g,
                            _found(groups_b.get(g)),
                            _found(groups_a.get(g)),
                        )
                        for g in _ordered(list(groups_b) + list(groups_a))
                    ],
                    changed,
                )
            )
        out.append(
            _table(
                f"{title}: missed, by cause",
                ["class, lost", "before", "after"],
                missed_rows(b.get("missed", {}).get(key, {}), a.get("missed", {}).get(key, {})),
                changed,
            )
        )
        out.append(
            _table(
                f"{title}: what the false detections are",
                ["really is", "before", "after", "detected as, before", "detected as, after"],
                [
                    (k, tb, ta, sb, sa)
                    for k, tb, ta, sb, sa in false_rows(
                        b.get("false_detections", {}).get(key, {}),
                        a.get("false_detections", {}).get(key, {}),
                    )
                ],
                changed,
            )
        )
        lists = b.get("mistakes", {}).get(key), a.get("mistakes", {}).get(key)
        out += _objects(
            title,
            [x is not None for x in lists],
            object_rows(*lists),
            "scan: object",
            changed,
        )
    for part, title, heading, columns, rows in (
        (
            "robustness",
            "Robustness",
            "the real scans changed, TP/det/GT at point IoU 0.25",
            ["change, class", "before", "after", "P / R before", "P / R after"],
            lambda b, a: robustness_rows(b, a, _real(before), _real(after)),
        ),
        (
            "sparse",
            "Sparse",
            "the simulated fused scans with fewer points, TP/det/GT at point IoU 0.25",
            ["change, class", "before", "after", "P / R before", "P / R after"],
            lambda b, a: robustness_rows(b, a),
        ),
        (
            "stability",
            "Stability",
            "detections that reappear, mean / worst",
            ["change of the scan", "before", "after"],
            stability_rows,
        ),
    ):
        b, a = before.get(part), after.get(part)
        if b is None or a is None:
            out.append(f"{title}: not in {'the first' if b is None else 'the second'} run")
        else:
            out.append(_table(f"{title}: {heading}", columns, rows(b, a), changed))
    steady = before.get("stability"), after.get("stability")
    if None not in steady:
        out += _objects(
            "Stability",
            ["unsteady" in st for st in steady],
            stability_objects(*steady),
            "scan: detection (really is)",
            changed,
        )
    for part, title in (("robustness", "Robustness"), ("sparse", "Sparse")):
        runs = before.get(part), after.get(part)
        if None not in runs:
            out += _objects(
                title,
                [_lists_robustness(r) for r in runs],
                robustness_objects(*runs),
                "change / scan: object",
                changed,
            )
    return out


def _objects(
    title: str,
    listed: Sequence[bool],
    rows: list[tuple[str, str, str]] | None,
    first: str,
    changed: bool,
) -> list[Table | str]:
    """A part's "objects that changed": the table of ``rows`` when both runs list their
    mistakes, a line naming the run that does not when only one does, nothing when neither
    does (runs written before the lists)."""
    named = f"{title}: the objects that changed"
    if all(listed):
        return [_table(named, [first, "before", "after"], rows or [], changed)]
    if any(listed):
        return [f"{named}: not listed in the {'second' if listed[0] else 'first'} run"]
    return []


def _lists_robustness(part: Mapping[str, Any]) -> bool:
    """Whether a run's robustness part lists its mistakes."""
    return any("mistakes" in ch for ch in part.get("changes", {}).values())


def robustness_objects(
    before: Mapping[str, Any], after: Mapping[str, Any]
) -> list[tuple[str, str, str]] | None:
    """:func:`object_rows` of every change of the robustness part both runs made and
    listed, each row named by its change; None when neither run lists any."""
    rows: list[tuple[str, str, str]] = []
    listed = False
    ch_b, ch_a = before.get("changes", {}), after.get("changes", {})
    for name in _ordered(list(ch_b) + list(ch_a)):
        lists = [ch.get(name, {}).get("mistakes", {}).get("iou@0.25") for ch in (ch_b, ch_a)]
        if None in lists:
            continue
        listed = True
        rows += [(f"{name} / {obj}", b, a) for obj, b, a in object_rows(*lists) or []]
    return rows if listed else None


def markdown(items: Iterable[Table | str]) -> str:
    """The comparison as Markdown (a heading and a pipe table for each table, a paragraph
    for each line), to paste into a change's note or docs/benchmarks.md."""
    out: list[str] = []
    for item in items:
        if isinstance(item, str):
            out += [item, ""]
            continue
        columns = item.columns
        header = [str(c.header).replace("\n", " ") for c in columns]
        rows = list(zip(*(list(c.cells) for c in columns)))
        align = ["---" if i == 0 else "---:" for i in range(len(columns))]
        out += [f"**{item.title}**", ""]
        out += ["| " + " | ".join(line) + " |" for line in (header, align)]
        out += ["| " + " | ".join(str(v).replace("|", "\\|") for v in row) + " |" for row in rows]
        out.append("")
    return "\n".join(out).rstrip("\n") + "\n"


def _found(g: Mapping[str, Any] | None) -> str:
    return "-" if not g else f"{g.get('found', 0)}/{g.get('gt', 0)}"


def _settings(doc: Mapping[str, Any]) -> str:
    bits = [f"room {doc.get('room', '?')}"]
    if doc.get("overrides"):
        bits.append("--set " + " --set ".join(doc["overrides"]))
    files = doc.get("ontology") or []
    if any(o.get("only") for o in files):
        bits.append("--ontology-only")
    for o in files:
        bits.append(f"--ontology {o.get('path')} (sha256 {str(o.get('sha256'))[:12]})")
    if doc.get("quick"):
        bits.append("quick")
    if doc.get("pooled_runs"):
        bits.append(f"{doc['pooled_runs']} runs pooled")
    return ", ".join(bits)


def main(argv: list[str] | None = None) -> int:
    """Parse, load both files (one line and status 2 when one is bad), print."""
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks compare", description=__doc__.splitlines()[0]
    )
    ap.add_argument(
        "before",
        help="generalization.json of the run before the change (several, comma-separated: pooled)",
    )
    ap.add_argument("after", help="generalization.json of the run after it (the same)")
    ious = " or ".join(f"{t:g}" for t in THRESHOLDS.values())
    ap.add_argument("--iou", type=float, default=0.25, help=f"point IoU of the figures: {ious}")
    ap.add_argument("--changed", action="store_true", help="print only the rows that changed")
    ap.add_argument(
        "--markdown", action="store_true", help="print Markdown tables (for a note or the docs)"
    )
    args = ap.parse_args(argv)
    if _key(args.iou) not in THRESHOLDS:
        err.print(f"--iou must be {ious}, got {args.iou:g}", soft_wrap=True)
        return 2
    try:
        before, after = load_runs(args.before), load_runs(args.after)
    except CompareError as exc:
        err.print(str(exc), soft_wrap=True)
        return 2
    items = compare(before, after, iou=args.iou, changed=args.changed)
    heading = [
        f"before: {args.before} ({_settings(before)})",
        f"after: {args.after} ({_settings(after)})",
    ]
    if args.markdown:
        sys.stdout.write(markdown([*heading, *items]))
        return 0
    for item in [*heading, *items]:
        console.print(item)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
