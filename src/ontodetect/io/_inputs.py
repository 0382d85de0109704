"""Many inputs at once: paths, folders of scans and glob patterns, expanded to scans."""

from __future__ import annotations

import glob
import os
from collections.abc import Callable, Iterable
from pathlib import Path

from ..errors import ReadError, UnsupportedFormatError

__all__ = ["expand_inputs"]

#: Characters that make a path that does not exist a glob pattern.
GLOB_CHARS = "*?["
#: Sibling files of a VoteNet ScanNet scan or SUN RGB-D frame that are not scans of their
#: own (the scan is its ``_vert.npy``, the frame its ``_pc.npz``).
_NOT_SCANS = ("_sem_label.npy", "_ins_label.npy", "_bbox.npy", "_votes.npz")


def expand_inputs(
    paths: Iterable[str | os.PathLike[str]], detect_format: Callable[[Path], str]
) -> list[Path]:
    """The scans named by ``paths``, in order, each once.

    A path that exists and is a file, or a folder that is itself a scan (a ScanNet scan,
    an S3DIS room, a 3DTK folder), is one scan; another folder stands for the readable
    files in it (sorted by name); a path that does not exist but holds ``*``, ``?`` or
    ``[`` is a glob pattern (``**`` descends into folders).

    Raises
    ------
    ReadError
        A pattern matches nothing, or a folder holds no readable scan.
    """
    out: list[Path] = []
    for given in paths:
        p = Path(given)
        if not p.exists() and any(ch in str(p) for ch in GLOB_CHARS):
            found = [Path(m) for m in sorted(glob.glob(str(p), recursive=True))]
            scans = [m for m in found if _is_scan(m, detect_format)]
            if not scans:
                raise ReadError(p, "no readable scan matches this pattern")
            out += scans
        elif p.is_dir() and not _is_scan(p, detect_format):
            scans = [f for f in sorted(p.iterdir()) if _is_scan(f, detect_format)]
            if not scans:
                raise ReadError(p, "is a folder with no readable scan in it")
            out += scans
        else:
            out.append(p)
    return list(dict.fromkeys(out))


def _is_scan(path: Path, detect_format: Callable[[Path], str]) -> bool:
    if path.name.endswith(_NOT_SCANS):
        return False
    try:
        detect_format(path)
    except UnsupportedFormatError:
        return False
    return True
