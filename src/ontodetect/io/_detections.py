"""``detections.json``: the contract between ontodetect and whoever uses its results.

The layout is documented key by key in docs/detections-format.md (format
``ontodetect.detections/1``), with a JSON Schema shipped in the package
(:func:`detections_schema`); extra keys are allowed, the listed ones keep their
meaning. :func:`read_detections` checks every required key so that evaluation of
stored results fails with a clear message instead of a wrong score.
"""

from __future__ import annotations

import json
import os
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import CorruptFileError
from ..geometry import jsonable
from ._atomic import atomic_write_text
from ._budget import MAX_COORDINATE, MAX_EXTENT
from ._textfile import read_text

__all__ = [
    "DETECTIONS_FORMAT",
    "detections_schema",
    "read_detections",
    "validate_detections",
    "write_detections",
    "write_timings",
]

#: Format tag of detections.json, the one definition (``pipeline.Result.to_dict`` uses it).
DETECTIONS_FORMAT = "ontodetect.detections/1"


def detections_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of ``detections.json``, shipped in the package.

    A fresh dictionary on every call. Validate with any JSON Schema library, e.g.
    ``jsonschema.validate(doc, detections_schema())``.

    Examples
    --------
    >>> detections_schema()["properties"]["format"]["const"] == DETECTIONS_FORMAT
    True
    """
    text = resources.files("ontodetect").joinpath("data/detections.schema.json").read_text("utf-8")
    return json.loads(text)


def write_detections(path: str | os.PathLike[str], document: dict[str, Any]) -> Path:
    """Validate and write a detections document atomically (compact point lists, indented rest)."""
    doc = jsonable(document)
    validate_detections(doc, str(path))
    # Index lists go on one line each: readable, and a tenth of the size of one number a line.
    marked = {
        **doc,
        "detections": [
            {**d, "point_indices": f"@@points{k}@@"} for k, d in enumerate(doc["detections"])
        ],
    }
    text = json.dumps(marked, indent=2)
    for k, d in enumerate(doc["detections"]):
        text = text.replace(f'"@@points{k}@@"', json.dumps(d["point_indices"]), 1)
    return atomic_write_text(path, text + "\n")


def write_timings(path: str | os.PathLike[str], timings: dict[str, Any]) -> Path:
    """Write ``timings.json`` atomically: what differs from run to run (seconds per stage,
    a tiled run's seconds, memory and worker per tile), kept out of detections.json and
    planes.json so that those are byte-identical for the same input and seed.

    Keys in the order given, two spaces of indentation, a final newline.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> f = write_timings(pathlib.Path(tempfile.mkdtemp()) / "timings.json", {"voxels": 0.5})
    >>> print(f.read_text(), end="")
    {
      "voxels": 0.5
    }
    """
    return atomic_write_text(path, json.dumps(timings, indent=2) + "\n")


def _fail(source: str, where: str, problem: str) -> CorruptFileError:
    return CorruptFileError(source, f"{where}: {problem}")


def _vec(v: Any, n: int) -> bool:
    return (
        isinstance(v, list)
        and len(v) == n
        and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)
    )


def validate_detections(doc: Any, source: str = "detections.json") -> None:
    """Raise CorruptFileError naming the key when ``doc`` breaks the contract."""
    if not isinstance(doc, dict):
        raise _fail(source, "top level", "expected a JSON object")
    if doc.get("format") != DETECTIONS_FORMAT:
        raise _fail(source, "format", f"expected {DETECTIONS_FORMAT!r}, got {doc.get('format')!r}")
    if not isinstance(doc.get("num_points"), int) or doc["num_points"] < 0:
        raise _fail(source, "num_points", f"expected a count, got {doc.get('num_points')!r}")
    frame = doc.get("frame")
    if not isinstance(frame, dict) or not _vec(frame.get("up"), 3):
        raise _fail(source, "frame", "expected {up: [x, y, z], ground_z, scale}")
    dets = doc.get("detections")
    if not isinstance(dets, list):
        raise _fail(source, "detections", "expected a list")
    n = doc["num_points"]
    for k, det in enumerate(dets):
        where = f"detections[{k}]"
        if not isinstance(det, dict):
            raise _fail(source, where, "expected an object")
        for key, kind in (("id", int), ("label", str), ("score", (int, float))):
            if not isinstance(det.get(key), kind) or isinstance(det.get(key), bool):
                raise _fail(
                    source, f"{where}.{key}", f"missing or of the wrong type: {det.get(key)!r}"
                )
        box = det.get("box")
        if (
            not isinstance(box, dict)
            or not _vec(box.get("center"), 3)
            or not _vec(box.get("size"), 3)
            or not isinstance(box.get("yaw"), (int, float))
        ):
            raise _fail(source, f"{where}.box", "expected {center: [3], size: [3], yaw}")
        if not all(abs(v) <= MAX_COORDINATE for v in [*box["center"], box["yaw"]]):
            raise _fail(
                source,
                f"{where}.box",
                f"center and yaw must be finite and within {MAX_COORDINATE:.0e}, got "
                f"{box['center']!r} and {box['yaw']!r}",
            )
        if not all(0 <= v <= MAX_EXTENT for v in box["size"]):
            raise _fail(
                source,
                f"{where}.box.size",
                f"each side must lie in [0, {MAX_EXTENT:.0e}] (what a building can span), "
                f"got {box['size']!r}",
            )
        parts = det.get("parts", [])
        if not isinstance(parts, list) or not all(
            isinstance(p, dict) and isinstance(p.get("name"), str) for p in parts
        ):
            raise _fail(
                source, f"{where}.parts", f"expected a list of {{name, ...}}, got {parts!r}"
            )
        for j, part in enumerate(parts):
            for key, size in (("normal", 3), ("centroid", 3), ("extent", 2)):
                if key in part and not _vec(part[key], size):
                    raise _fail(
                        source,
                        f"{where}.parts[{j}].{key}",
                        f"expected {size} numbers, got {part[key]!r}",
                    )
        pts = det.get("point_indices")
        if not isinstance(pts, list) or not all(isinstance(i, int) for i in pts):
            raise _fail(source, f"{where}.point_indices", "expected a list of integers")
        if pts and (min(pts) < 0 or max(pts) >= n):
            raise _fail(
                source, f"{where}.point_indices", f"indices must lie in [0, {n}) (num_points)"
            )
        for key in ("probabilities", "costs"):
            if key in det and not isinstance(det[key], dict):
                raise _fail(source, f"{where}.{key}", "expected an object")


def read_detections(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read and validate a ``detections.json``."""
    p = Path(path)
    if p.is_dir():
        p = p / "detections.json"
    text = read_text(p)
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise CorruptFileError(p, f"not valid JSON: {exc.msg} at line {exc.lineno}") from exc
    except RecursionError:
        raise CorruptFileError(p, "not valid JSON: nested too deeply") from None
    validate_detections(doc, str(p))
    return doc
