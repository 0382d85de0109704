"""Check that two runs found the same detections, byte for byte but for timings.

Compares every ``<scene>/detections.json`` under two folders written by
``ontodetect eval DATASET -o REPORT --save-detections`` (or by ``detect``), after
dropping the ``timings`` key and the ``source`` path. Prints one line per scene that
differs and exits 1 if any does; 0 when every scene is the same.

    python scripts/same_detections.py BEFORE/detections AFTER/detections
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

IGNORED = ("timings", "source")


def canonical(path: Path) -> str:
    doc = json.loads(path.read_text())
    for key in IGNORED:
        doc.pop(key, None)
    return json.dumps(doc, sort_keys=True)


def main(before: str, after: str) -> int:
    a = {p.relative_to(before): p for p in Path(before).rglob("detections.json")}
    b = {p.relative_to(after): p for p in Path(after).rglob("detections.json")}
    if not a:
        print(f"{before}: no detections.json found", file=sys.stderr)
        return 2
    differ = sorted(set(a) ^ set(b))
    for rel in differ:
        print(f"{rel}: only in {'before' if rel in a else 'after'}")
    changed = [rel for rel in sorted(set(a) & set(b)) if canonical(a[rel]) != canonical(b[rel])]
    for rel in changed:
        print(f"{rel}: detections differ")
    print(f"{len(a)} scenes compared, {len(changed) + len(differ)} differ")
    return 1 if changed or differ else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1], sys.argv[2]))
