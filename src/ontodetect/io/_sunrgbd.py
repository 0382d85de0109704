"""SUN RGB-D frames as preprocessed for VoteNet (``sunrgbd/sunrgbd_data.py``).

One depth frame per id, side by side in a folder::

    000001_pc.npz      array "pc", (n, 6): x y z r g b, colours 0..1, in upright depth
                       coordinates (x right, y forward, z up; the camera at the origin,
                       its tilt taken out); 50,000 points drawn at random from the frame
    000001_bbox.npy    (K, 8) boxes [cx cy cz  l w h  heading  class]: the centre, HALF
                       the length, width and height, the heading (the box's corners are
                       ``rotz(-heading)`` of its local ones) and the class's index in
                       VoteNet's ten (bed, table, sofa, chair, toilet, desk, dresser,
                       night_stand, bookshelf, bathtub)
    000001_votes.npz   VoteNet's training votes (not read)

SUN RGB-D labels objects with boxes, not points: a point belongs to the object whose box
holds it (the smallest, where boxes overlap), which is how VoteNet's own votes are made.
The classes become NYU40 ids, as ScanNet's labels are, so one ontology's ``matches``
evaluate both.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..cloud import PointCloud
from ..errors import CorruptFileError, ReadError
from ._labels import nyu40_name
from ._numpy import read_npz
from ._scannet import _box_table, _load_npy

__all__ = ["SUNRGBD_CLASSES", "boxes_to_labels", "read_sunrgbd_votenet"]

#: VoteNet's ten SUN RGB-D classes in index order, with their NYU40 ids.
SUNRGBD_CLASSES: tuple[tuple[str, int], ...] = (
    ("bed", 4),
    ("table", 7),
    ("sofa", 6),
    ("chair", 5),
    ("toilet", 33),
    ("desk", 14),
    ("dresser", 17),
    ("night_stand", 32),
    ("bookshelf", 10),
    ("bathtub", 36),
)
#: Columns of a box row: centre (3), half sizes (3), heading, class index.
BOX_COLUMNS = 8
#: The frame's points, its boxes, VoteNet's training votes.
POINTS, BOXES, VOTES = SUFFIXES = ("_pc.npz", "_bbox.npy", "_votes.npz")


def _nyu40(boxes: NDArray[np.float64]) -> NDArray[np.int64]:
    """The NYU40 id of each box's class."""
    return np.array([nyu for _, nyu in SUNRGBD_CLASSES])[boxes[:, 7].astype(np.int64)]


def boxes_to_labels(
    xyz: NDArray[np.float64], boxes: NDArray[np.float64]
) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
    """Per-point ``instance`` (box row + 1, 0 = none) and NYU40 ``class_id`` from VoteNet
    SUN RGB-D boxes: a point takes the smallest box that holds it.

    Examples
    --------
    >>> pts = np.array([[0.0, 0.0, 0.5], [0.9, 0.0, 0.5], [0.0, 0.9, 0.5]])
    >>> box = np.array([[0, 0, 0.5, 1.0, 0.2, 0.5, np.pi / 2, 3]])  # 2 m along y once turned
    >>> [a.tolist() for a in boxes_to_labels(pts, box)]
    [[1, 0, 1], [5, 0, 5]]
    """
    n = len(xyz)
    instance = np.zeros(n, np.int32)
    class_id = np.zeros(n, np.int32)
    # Largest first, so that a smaller box inside it overwrites: the smallest holder wins.
    order = np.argsort(-np.prod(boxes[:, 3:6], axis=1), kind="stable")
    nyu = _nyu40(boxes)
    for k in order:
        c, half, heading = boxes[k, 0:3], boxes[k, 3:6], boxes[k, 6]
        d = xyz - c
        cs, sn = np.cos(heading), np.sin(heading)
        # Local coordinates: the corners are rotz(-heading) of the local ones, so the
        # local frame is rotz(heading) of the world's.
        lx = d[:, 0] * cs - d[:, 1] * sn
        ly = d[:, 0] * sn + d[:, 1] * cs
        inside = (np.abs(lx) <= half[0]) & (np.abs(ly) <= half[1]) & (np.abs(d[:, 2]) <= half[2])
        instance[inside] = k + 1
        class_id[inside] = nyu[k]
    return instance, class_id


def _read_boxes(path: Path) -> NDArray[np.float64]:
    raw = _load_npy(path)
    if raw.size == 0:
        return np.zeros((0, BOX_COLUMNS))
    boxes = _box_table(path, raw, BOX_COLUMNS, " [cx cy cz l w h heading class]")
    if not np.isfinite(boxes).all():
        raise CorruptFileError(path, "holds NaN or infinite values")
    cls = boxes[:, 7]
    if np.any(cls != np.round(cls)) or cls.min() < 0 or cls.max() >= len(SUNRGBD_CLASSES):
        raise CorruptFileError(
            path,
            f"column 8 (class) should hold VoteNet's class indices 0..{len(SUNRGBD_CLASSES) - 1}"
            f", found {cls.min():g}..{cls.max():g}",
        )
    if np.any(boxes[:, 3:6] < 0):
        raise CorruptFileError(path, "columns 4-6 (half sizes) should not be negative")
    return boxes


def read_sunrgbd_votenet(
    path: Path, *, labels: bool | None = True, on_nonfinite: str = "warn"
) -> PointCloud:
    """Read a SUN RGB-D frame as preprocessed for VoteNet (``<id>_pc.npz`` and siblings).

    Parameters
    ----------
    path : Path
        ``<id>_pc.npz``, or its ``_bbox.npy`` / ``_votes.npz`` sibling.
    labels : bool or None
        Read ``<id>_bbox.npy`` (it must exist) and label the points inside its boxes;
        False reads the points only; None labels them when the box file is there.
    on_nonfinite : {"warn", "drop", "raise"}
        Passed to :func:`~ontodetect.point_cloud`.

    Returns
    -------
    PointCloud
        ``xyz``, ``rgb``; with labels, fields ``class_id`` (NYU40) and ``instance`` (box
        row + 1; 0 = in no box), and ``meta["boxes"]``: each box as ``{"class_id",
        "box": {"center", "size", "yaw"}}`` (full sizes, ``yaw = -heading``).

    Raises
    ------
    ReadError
        Not a file of this layout, or a needed sibling missing (the message names it).
    CorruptFileError
        A damaged archive or box file (the message names the file and what is wrong).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> np.savez_compressed(d / "000001_pc.npz", pc=np.array([[0, 2, 0.4, 0.5, 0.5, 0.5]]))
    >>> np.save(d / "000001_bbox.npy", np.array([[0, 2, 0.4, 0.3, 0.3, 0.45, 0.0, 3]]))
    >>> c = read_sunrgbd_votenet(d / "000001_pc.npz")
    >>> c.fields["class_id"].tolist(), c.meta["instance_labels"], c.rgb.tolist()
    ([5], {1: 'chair'}, [[128, 128, 128]])
    """
    path = Path(path)
    frame = next((path.name[: -len(s)] for s in SUFFIXES if path.name.endswith(s)), None)
    if frame is None:
        raise ReadError(
            path,
            "is not a VoteNet SUN RGB-D file (expected a name ending in "
            f"{', '.join(SUFFIXES[:2])})",
        )
    pc_file = path.parent / f"{frame}{POINTS}"
    if not pc_file.is_file():
        raise ReadError(pc_file, "missing: the points of the frame are needed")
    cloud = read_npz(pc_file, on_nonfinite=on_nonfinite)
    meta: dict[str, Any] = {"source": str(path), "scene_id": frame}
    box_file = path.parent / f"{frame}{BOXES}"
    if labels is None:
        labels = box_file.is_file()
    if not labels:
        return cloud.with_meta(**meta)
    if not box_file.is_file():
        raise ReadError(
            box_file,
            "missing: its boxes label the frame's points (labels=False reads the points only)",
        )
    boxes = _read_boxes(box_file)
    instance, class_id = boxes_to_labels(cloud.xyz, boxes)
    nyu = _nyu40(boxes)
    meta["boxes"] = [
        {
            "class_id": int(cid),
            "box": {"center": b[0:3].tolist(), "size": (2 * b[3:6]).tolist(), "yaw": -b[6]},
        }
        for b, cid in zip(boxes, nyu, strict=True)
    ]
    present = np.unique(instance[instance > 0])
    meta["instance_class_ids"] = {int(i): int(nyu[i - 1]) for i in present}
    meta["instance_labels"] = {i: nyu40_name(c) for i, c in meta["instance_class_ids"].items()}
    fields = {**cloud.fields, "instance": instance, "class_id": class_id}
    return cloud.replace(fields=fields).with_meta(**meta)
