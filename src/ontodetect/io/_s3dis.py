"""S3DIS rooms (Stanford Large-Scale 3D Indoor Spaces).

A room folder looks like::

    Area_1/office_1/office_1.txt            x y z r g b, the whole room
    Area_1/office_1/Annotations/chair_1.txt x y z r g b, one object per file
    Area_1/office_1/Annotations/table_2.txt ...

The reader builds the cloud from the ``Annotations`` files (their union is the
room), so every point gets a class and an instance. S3DIS's 13 classes are
mapped to NYU40 ids (:data:`~ontodetect.io._labels.S3DIS_TO_NYU40`) so that
ScanNet and S3DIS share one ``class_id`` field.

One file of the original release (Area_5/hallway_6) has a stray control
character inside a number line; such lines are repaired (the character is read
as a separator) or skipped, with a :class:`~ontodetect.DataWarning`.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..cloud import DataWarning, PointCloud, point_cloud
from ..errors import CorruptFileError, ReadError
from ._labels import UNANNOTATED, s3dis_class_id
from ._text import _to_colors, load_numeric_table

__all__ = ["read_s3dis"]

ANNOTATIONS = "Annotations"
_ANNOTATION_RE = re.compile(r"^(?P<cls>.+?)_(?P<k>\d+)$")


def _annotation_key(path: Path) -> tuple[str, int, str]:
    m = _ANNOTATION_RE.match(path.stem)
    if m is None:
        return path.stem.lower(), 0, path.name
    return m.group("cls").lower(), int(m.group("k")), path.name


def _read_points(path: Path) -> NDArray[np.float64]:
    table, stats = load_numeric_table(path, repair=True)
    if stats.repaired or stats.skipped:
        parts = []
        if stats.repaired:
            parts.append(
                f"repaired {len(stats.repaired)} line(s) with stray control "
                f"characters (first: line {stats.repaired[0]})"
            )
        if stats.skipped:
            parts.append(
                f"skipped {len(stats.skipped)} unreadable line(s) (first: line {stats.skipped[0]})"
            )
        warnings.warn(f"{path}: {'; '.join(parts)}", DataWarning, stacklevel=3)
    if table.shape[0] == 0:
        raise CorruptFileError(path, "contains no points")
    if table.shape[1] < 3:
        raise CorruptFileError(
            path, f"expected columns x y z r g b, found {table.shape[1]} column(s)"
        )
    return table


def read_s3dis(path: Path, *, labels: bool = True, on_nonfinite: str = "warn") -> PointCloud:
    """Read an S3DIS room with per-point class and instance labels.

    Parameters
    ----------
    path : Path
        The room folder (holding ``Annotations/``), or its ``<room>.txt``.
    labels : bool
        Build the cloud from ``Annotations/<class>_<k>.txt`` (default). False
        reads ``<room>.txt`` alone, without labels.
    on_nonfinite : {"warn", "drop", "raise"}
        Passed to :func:`~ontodetect.point_cloud`.

    Returns
    -------
    PointCloud
        ``xyz``, ``rgb``; with labels, fields ``class_id`` (NYU40 id, int32) and
        ``instance`` (int32, 1..K in the order of the files sorted by class
        name and number). ``meta`` holds ``room``, ``instance_labels`` (instance
        -> S3DIS class), ``instance_class_ids`` and ``unknown_classes`` (file
        names whose class S3DIS does not define; their points get class 0).
        With labels, ``index`` counts points over the annotation files in that
        order.

    Raises
    ------
    ReadError
        No ``Annotations/*.txt`` (or no ``<room>.txt`` with ``labels=False``).
    CorruptFileError
        A file without points or with fewer than three columns.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> room = pathlib.Path(tempfile.mkdtemp()) / "office_1"
    >>> (room / "Annotations").mkdir(parents=True)
    >>> _ = (room / "Annotations" / "chair_1.txt").write_text("1 2 0.4 10 20 30\\n")
    >>> _ = (room / "Annotations" / "floor_1.txt").write_text("1 2 0 90 90 90\\n")
    >>> c = read_s3dis(room)
    >>> c.fields["class_id"].tolist(), c.fields["instance"].tolist()
    ([5, 2], [1, 2])
    """
    path = Path(path)
    room_dir = path if path.is_dir() else path.parent
    room = room_dir.name
    meta: dict[str, Any] = {"source": str(path), "room": room}
    if not labels:
        room_file = path if path.is_file() else room_dir / f"{room}.txt"
        if not room_file.is_file():
            raise ReadError(room_file, "missing: the room's point file is needed with labels=False")
        table = _read_points(room_file)
        rgb = _to_colors(room_file, table[:, 3:6], ["r", "g", "b"]) if table.shape[1] >= 6 else None
        return point_cloud(table[:, :3], rgb=rgb, meta=meta, on_nonfinite=on_nonfinite, copy=False)

    folder = room_dir / ANNOTATIONS
    files = (
        sorted((f for f in folder.glob("*.txt") if f.is_file()), key=_annotation_key)
        if folder.is_dir()
        else []
    )
    if not files:
        raise ReadError(folder, "holds no <class>_<k>.txt annotation files")

    xyz_parts: list[NDArray[np.float64]] = []
    rgb_parts: list[NDArray[np.uint8] | None] = []
    class_parts: list[NDArray[np.int32]] = []
    instance_parts: list[NDArray[np.int32]] = []
    instance_labels: dict[int, str] = {}
    instance_classes: dict[int, int] = {}
    unknown: list[str] = []
    for instance, f in enumerate(files, start=1):
        cls, _, _ = _annotation_key(f)
        class_id = s3dis_class_id(cls)
        if class_id == UNANNOTATED:
            unknown.append(f.name)
        table = _read_points(f)
        n = table.shape[0]
        xyz_parts.append(table[:, :3])
        rgb_parts.append(
            _to_colors(f, table[:, 3:6], ["r", "g", "b"]) if table.shape[1] >= 6 else None
        )
        class_parts.append(np.full(n, class_id, dtype=np.int32))
        instance_parts.append(np.full(n, instance, dtype=np.int32))
        instance_labels[instance] = cls
        instance_classes[instance] = class_id
    rgb = None if any(p is None for p in rgb_parts) else np.concatenate(rgb_parts)
    meta.update(
        {
            "instance_labels": instance_labels,
            "instance_class_ids": instance_classes,
            "unknown_classes": unknown,
        }
    )
    return point_cloud(
        np.concatenate(xyz_parts),
        rgb=rgb,
        fields={
            "class_id": np.concatenate(class_parts),
            "instance": np.concatenate(instance_parts),
        },
        meta=meta,
        on_nonfinite=on_nonfinite,
        copy=False,
    )
