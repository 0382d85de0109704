"""The one cloud or scan a command reads: the names ``--format`` takes, and the labelled
VoteNet layouts read without their labels when only the points are needed."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import InvalidParameterError, OntoDetectError
from ..io import detect_format, read_cloud, supported_formats
from ..io._layouts import DATASET_FORMATS, FORMAT_ALIASES

if TYPE_CHECKING:
    from ..cloud import PointCloud

#: Help of ``--format`` for the commands that read one cloud per input.
FORMAT_HELP = (
    f"Force the input format: {', '.join(supported_formats())} (sunrgbd and votenet name "
    "the VoteNet layouts)."
)


def cloud_format(format: str | None, command: str) -> str | None:
    """The reader ``--format`` names: one of :func:`~ontodetect.io.supported_formats`, or
    a layout's other name in ``eval -f`` (``sunrgbd``, ``votenet``) when it names one;
    errors name ``--format`` and say what ``command`` reads.

    Examples
    --------
    >>> cloud_format("sunrgbd", "info"), cloud_format("PLY", "info"), cloud_format(None, "info")
    ('sunrgbd-votenet', 'ply', None)
    """
    if format is None:
        return None
    name = format.strip().lower()
    name = FORMAT_ALIASES.get(name, name)
    readable = supported_formats()
    if name in readable:
        return name
    rule = "one of " + ", ".join(readable) + f" ({command} reads one cloud or scan)"
    if name in DATASET_FORMATS:
        rule += f"; {format!r} is a dataset layout: 'ontodetect eval -f {format}' reads it"
    raise InvalidParameterError("--format", rule, format)


def read_scan(path: Path, format: str | None = None) -> PointCloud:
    """``read_cloud(path, format=format)``, but a scan of a VoteNet layout whose label
    files are missing (a ScanNet test scan, a frame without boxes) is read without its
    labels: every command but ``eval`` needs only the points.

    ``format`` is a reader's name (:func:`cloud_format`) or None (guessed from the path).
    """
    from ..io._scannet import votenet_label_files  # lazy: CLI start-up
    from ..io._sunrgbd import sunrgbd_label_files  # lazy: CLI start-up

    label_files = {
        "scannet-votenet": votenet_label_files,
        "sunrgbd-votenet": sunrgbd_label_files,
    }
    if not _is_file(path):  # read_cloud says what is wrong with it
        return read_cloud(path, format=format)
    layout = format
    if layout is None:
        try:
            layout = detect_format(path)
        except OntoDetectError:  # read_cloud says it, after its own checks of the path
            return read_cloud(path, format=format)
    needed = label_files[layout](path) if layout in label_files else []
    if not all(_is_file(f) for f in needed):
        return read_cloud(path, format=format, labels=False)
    return read_cloud(path, format=format)


def _is_file(path: Path) -> bool:
    """``path.is_file()``, False where it cannot be looked at (a folder on the way that
    cannot be entered raises PermissionError from ``is_file``)."""
    try:
        return path.is_file()
    except OSError:
        return False
