"""Detections in community layouts, written beside ``detections.json`` (which stays the contract).

- **Box table** (``boxes.txt``): one line per detection, ``x y z dx dy dz yaw class score``,
  the layout of OpenPCDet's and mmdetection3d's box arrays: ``(x, y, z)`` the box centre,
  ``dx`` the length along the heading ``yaw`` (radians, about the up axis, counter-clockwise),
  ``dy`` the width, ``dz`` the height. mmdetection3d's LiDAR boxes put ``z`` at the bottom:
  subtract ``dz / 2``.
- **ScanNet benchmark instances** (``scannet/<scene>.txt`` and ``scannet/pred_mask/``): the
  summary file lists ``pred_mask/<scene>_<k>.txt <nyu40 id> <confidence>``, one line per
  instance; each mask file holds one ``0``/``1`` per point of the input, in file order.

Every writer takes a ``detections.json`` document (a dict) and writes atomically;
:data:`EXPORTERS` finds them by name.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import CorruptFileError, InvalidParameterError
from ._atomic import atomic_write_text, make_folder
from ._labels import NYU40_NAMES
from ._textfile import read_text

__all__ = [
    "BOX_COLUMNS",
    "EXPORTERS",
    "OTHER_FURNITURE",
    "export_detections",
    "read_box_table",
    "read_scannet_instances",
    "scannet_label_id",
    "write_box_table",
    "write_scannet_instances",
]

#: Columns of the box table, in order.
BOX_COLUMNS = ("x", "y", "z", "dx", "dy", "dz", "yaw", "class", "score")
#: NYU40 id given to a class NYU40 does not name ("otherfurniture").
OTHER_FURNITURE = 39
_NYU40_IDS = {name: k for k, name in NYU40_NAMES.items()}
#: Decimals of the coordinates, sizes and angles in the box table (0.1 mm, 1e-6 rad).
_DECIMALS = 6


def scannet_label_id(label: str) -> int:
    """The NYU40 id ScanNet's benchmark uses for a class label (39 when NYU40 lacks it).

    Examples
    --------
    >>> scannet_label_id("chair"), scannet_label_id("stool")
    (5, 39)
    """
    return _NYU40_IDS.get(label, OTHER_FURNITURE)


def write_box_table(path: str | os.PathLike[str], document: Mapping[str, Any]) -> Path:
    """Write the detections' boxes as a whitespace-separated table (see the module docstring).

    The first line is a comment naming the columns; class names have no spaces (a space
    becomes ``_``).
    """
    lines = ["# " + " ".join(BOX_COLUMNS)]
    for d in document["detections"]:
        box = d["box"]
        nums = [*box["center"], *box["size"], box["yaw"]]
        text = " ".join(f"{float(v):.{_DECIMALS}f}" for v in nums)
        lines.append(f"{text} {str(d['label']).replace(' ', '_')} {float(d['score']):.4f}")
    return atomic_write_text(path, "\n".join(lines) + "\n")


def read_box_table(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """Read a box table back: one dict per line with ``center``, ``size``, ``yaw``, ``label``,
    ``score``."""
    p = Path(path)
    rows = []
    for number, line in enumerate(read_text(p).splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        parts = line.split()
        if len(parts) != len(BOX_COLUMNS):
            raise CorruptFileError(
                p, f"line {number}: expected {len(BOX_COLUMNS)} columns, found {len(parts)}"
            )
        try:
            nums = [float(v) for v in parts[:7]]
            score = float(parts[8])
        except ValueError as exc:
            raise CorruptFileError(p, f"line {number}: {exc}") from exc
        rows.append(
            {
                "center": nums[0:3],
                "size": nums[3:6],
                "yaw": nums[6],
                "label": parts[7],
                "score": score,
            }
        )
    return rows


#: File-name endings of ScanNet scans that are not part of the scene id.
_SCANNET_ENDINGS = ("_vert.npy", "_vh_clean_2.ply")


def _scene_name(source: str) -> str:
    """The scene id of an input file: ``scene0000_00`` for ScanNet's files, else the stem.

    Examples
    --------
    >>> _scene_name("a/scene0000_00_vert.npy"), _scene_name("room.ply")
    ('scene0000_00', 'room')
    """
    name = Path(source).name
    for ending in _SCANNET_ENDINGS:
        if name.endswith(ending) and len(name) > len(ending):
            return name[: -len(ending)]
    return Path(name).stem or "scene"


def write_scannet_instances(
    folder: str | os.PathLike[str], document: Mapping[str, Any], scene: str | None = None
) -> Path:
    """Write the ScanNet benchmark's instance files for one scene; return the summary file.

    ``folder/<scene>.txt`` lists ``pred_mask/<scene>_<k>.txt <nyu40 id> <score>``, and each
    mask file holds ``num_points`` lines of ``0`` or ``1``. ``scene`` defaults to the
    scene id of the document's ``source`` (``scene0000_00`` for ``scene0000_00_vert.npy``
    or ``scene0000_00_vh_clean_2.ply``, the stem otherwise).
    """
    if scene is None:
        scene = _scene_name(str(document.get("source", "") or "scene"))
    if not scene or "/" in scene or scene.startswith("."):
        raise InvalidParameterError("scene", "a plain file name", scene)
    root = make_folder(folder, "ScanNet export folder")
    masks = make_folder(root / "pred_mask", "ScanNet mask folder")
    n = int(document["num_points"])
    summary = []
    for k, d in enumerate(document["detections"]):
        mask = np.zeros(n, dtype=np.uint8)
        mask[np.asarray(d["point_indices"], dtype=np.int64)] = 1
        name = f"{scene}_{k:03d}.txt"
        atomic_write_text(masks / name, "\n".join(map(str, mask.tolist())) + ("\n" if n else ""))
        summary.append(
            f"pred_mask/{name} {scannet_label_id(str(d['label']))} {float(d['score']):.4f}"
        )
    return atomic_write_text(root / f"{scene}.txt", "".join(f"{s}\n" for s in summary))


def read_scannet_instances(
    summary: str | os.PathLike[str],
) -> list[tuple[int, float, NDArray[np.bool_]]]:
    """Read a ScanNet benchmark summary file: ``(nyu40 id, confidence, mask)`` per instance."""
    p = Path(summary)
    out = []
    for number, line in enumerate(read_text(p).splitlines(), 1):
        if not line.strip():
            continue
        parts = line.split()
        if len(parts) != 3:
            raise CorruptFileError(p, f"line {number}: expected 'MASK_FILE LABEL_ID CONFIDENCE'")
        try:
            label, conf = int(parts[1]), float(parts[2])
        except ValueError as exc:
            raise CorruptFileError(p, f"line {number}: {exc}") from exc
        mask_path = p.parent / parts[0]
        values = read_text(mask_path).split()
        if any(v not in ("0", "1") for v in values):
            raise CorruptFileError(mask_path, "expected one 0 or 1 per line")
        out.append((label, conf, np.array(values, dtype=np.uint8).astype(bool)))
    return out


def _export_boxes(folder: Path, document: Mapping[str, Any]) -> list[Path]:
    return [write_box_table(folder / "boxes.txt", document)]


def _export_scannet(folder: Path, document: Mapping[str, Any]) -> list[Path]:
    return [write_scannet_instances(folder / "scannet", document)]


#: Exporter name -> function(out_dir, detections document) -> written files.
EXPORTERS: Mapping[str, Callable[[Path, Mapping[str, Any]], list[Path]]] = MappingProxyType(
    {"boxes": _export_boxes, "scannet": _export_scannet}
)


def export_detections(
    folder: str | os.PathLike[str], document: Mapping[str, Any], names: tuple[str, ...]
) -> list[Path]:
    """Run the exporters ``names`` (keys of :data:`EXPORTERS`) into ``folder``.

    Examples
    --------
    >>> import tempfile
    >>> doc = {"num_points": 2, "detections": [{"label": "chair", "score": 0.5,
    ...        "box": {"center": [0, 0, 0.4], "size": [0.5, 0.5, 0.8], "yaw": 0.0},
    ...        "point_indices": [1]}]}
    >>> [p.name for p in export_detections(tempfile.mkdtemp(), doc, ("boxes",))]
    ['boxes.txt']
    """
    unknown = [n for n in names if n not in EXPORTERS]
    if unknown:
        raise InvalidParameterError("exports", f"among {sorted(EXPORTERS)}", unknown[0])
    root = Path(folder)
    written: list[Path] = []
    for name in names:
        written += EXPORTERS[name](root, document)
    return written
