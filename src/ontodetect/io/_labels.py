"""Class names and label mappings shared by the labelled-dataset readers.

Every labelled reader writes the same two per-point fields:

- ``class_id`` (int32): an NYU40 class id, 0 = unannotated;
- ``instance`` (int32): an object instance id, 1..K, 0 = none.

ScanNet already speaks NYU40 (through the ``nyu40id`` column of its label
table); S3DIS has its own 13 classes, mapped here to the nearest NYU40 id so
that one evaluation serves both datasets.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from types import MappingProxyType

from ..errors import CorruptFileError, ReadError

__all__ = [
    "NYU40_NAMES",
    "S3DIS_TO_NYU40",
    "UNANNOTATED",
    "nyu40_name",
    "read_scannet_label_map",
    "s3dis_class_id",
]

#: ``class_id`` of points that no annotation covers.
UNANNOTATED = 0

#: NYU40 class id -> name (Gupta et al. 2013, as used by ScanNet's ``nyu40class``).
NYU40_NAMES: MappingProxyType[int, str] = MappingProxyType(
    {
        0: "unannotated",
        1: "wall",
        2: "floor",
        3: "cabinet",
        4: "bed",
        5: "chair",
        6: "sofa",
        7: "table",
        8: "door",
        9: "window",
        10: "bookshelf",
        11: "picture",
        12: "counter",
        13: "blinds",
        14: "desk",
        15: "shelves",
        16: "curtain",
        17: "dresser",
        18: "pillow",
        19: "mirror",
        20: "floor mat",
        21: "clothes",
        22: "ceiling",
        23: "books",
        24: "refrigerator",
        25: "television",
        26: "paper",
        27: "towel",
        28: "shower curtain",
        29: "box",
        30: "whiteboard",
        31: "person",
        32: "night stand",
        33: "toilet",
        34: "sink",
        35: "lamp",
        36: "bathtub",
        37: "bag",
        38: "otherstructure",
        39: "otherfurniture",
        40: "otherprop",
    }
)

#: S3DIS class name (``Annotations/<class>_<k>.txt``) -> NYU40 id.
#: The 13 S3DIS classes have no official NYU40 mapping; each goes to the NYU40 class
#: with the same meaning. Choices that are not literal:
#: ``board`` (whiteboards, notice boards on walls) -> 30 whiteboard;
#: ``beam`` and ``column`` (parts of the building, not furniture) -> 38 otherstructure;
#: ``stairs`` (present in a few rooms, merged into clutter by the 13-class benchmark)
#: -> 38 otherstructure; ``clutter`` -> 40 otherprop; ``bookcase`` -> 10 bookshelf.
S3DIS_TO_NYU40: MappingProxyType[str, int] = MappingProxyType(
    {
        "ceiling": 22,
        "floor": 2,
        "wall": 1,
        "beam": 38,
        "column": 38,
        "window": 9,
        "door": 8,
        "table": 7,
        "chair": 5,
        "sofa": 6,
        "bookcase": 10,
        "board": 30,
        "clutter": 40,
        "stairs": 38,
    }
)

#: Columns of ScanNet's ``scannetv2-labels.combined.tsv`` used by default.
SCANNET_LABEL_FROM = "raw_category"
SCANNET_LABEL_TO = "nyu40id"


def nyu40_name(class_id: int) -> str:
    """Name of an NYU40 class id (``"class 57"`` for ids outside 0..40).

    Examples
    --------
    >>> nyu40_name(5), nyu40_name(14)
    ('chair', 'desk')
    """
    return NYU40_NAMES.get(int(class_id), f"class {int(class_id)}")


def s3dis_class_id(name: str) -> int:
    """NYU40 id of an S3DIS class name; :data:`UNANNOTATED` for unknown names.

    Examples
    --------
    >>> s3dis_class_id("chair"), s3dis_class_id("Sofa"), s3dis_class_id("robot")
    (5, 6, 0)
    """
    return S3DIS_TO_NYU40.get(name.strip().lower(), UNANNOTATED)


def read_scannet_label_map(
    path: str | Path, label_from: str = SCANNET_LABEL_FROM, label_to: str = SCANNET_LABEL_TO
) -> dict[str, int]:
    """Read ScanNet's label table: raw category name -> NYU40 id.

    Parameters
    ----------
    path : str or Path
        ``scannetv2-labels.combined.tsv`` (tab separated, one header row).
    label_from, label_to : str
        Column names of the key and of the integer value.

    Returns
    -------
    dict of str to int
        Rows whose value is empty are left out (as in ScanNet's own scripts).

    Raises
    ------
    ReadError
        The file cannot be opened.
    CorruptFileError
        A column is missing or a value is not an integer; the message names the line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "labels.tsv"
    >>> _ = f.write_text("id\\traw_category\\tnyu40id\\n1\\tchair\\t5\\n2\\tcouch\\t6\\n")
    >>> read_scannet_label_map(f)
    {'chair': 5, 'couch': 6}
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise ReadError(p, f"cannot read the label table ({exc.strerror or exc})") from exc
    text = raw.decode("utf-8", errors="replace")
    reader = csv.reader(io.StringIO(text), delimiter="\t")
    try:
        header = next(reader)
    except StopIteration:
        raise CorruptFileError(p, "the label table is empty") from None
    except csv.Error as exc:
        raise CorruptFileError(p, f"line 1: {exc}") from exc
    missing = [c for c in (label_from, label_to) if c not in header]
    if missing:
        raise CorruptFileError(
            p, f"the label table has no column {missing[0]!r} (found {', '.join(header[:8])})"
        )
    i_from, i_to = header.index(label_from), header.index(label_to)
    mapping: dict[str, int] = {}
    try:
        for line_no, row in enumerate(reader, start=2):
            if not row or len(row) <= max(i_from, i_to):
                continue
            value = row[i_to].strip()
            if not value:
                continue
            try:
                mapping[row[i_from]] = int(value)
            except ValueError:
                raise CorruptFileError(
                    p, f"line {line_no}: {label_to} should be an integer, found {value!r}"
                ) from None
    except csv.Error as exc:
        raise CorruptFileError(p, f"{exc}") from exc
    return mapping
