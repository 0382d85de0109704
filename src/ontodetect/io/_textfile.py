"""Reading the small text files around point clouds (configurations, manifests, JSON).

Every input is checked before it is opened: only a regular file is read (a FIFO would
block, ``/dev/zero`` never ends), and a text file larger than :data:`MAX_TEXT_BYTES` is
refused before a byte of it is taken into memory.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ..errors import ReadError

__all__ = ["MAX_TEXT_BYTES", "read_text", "regular_file"]

#: The largest configuration, ontology, manifest or JSON file read (64 MiB): ours are a
#: few kilobytes, so anything near this is a mistake, not a document.
MAX_TEXT_BYTES = 64 * 2**20


def regular_file(path: str | os.PathLike[str], what: str = "file") -> int:
    """The size in bytes of ``path`` after checking, without opening it, that it is a
    regular file that can be read; a :class:`ReadError` otherwise.

    Examples
    --------
    >>> try:
    ...     regular_file("/dev/null", "configuration file")
    ... except ReadError as exc:
    ...     print(exc)
    /dev/null: not a regular file (a device) - expected a configuration file
    """
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise ReadError(p, f"no such {what}") from None
    except PermissionError:
        raise ReadError(p, "permission denied (a folder on the way cannot be entered)") from None
    except OSError as exc:
        raise ReadError(p, f"cannot look at the {what} ({exc.strerror or exc})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ReadError(p, f"a folder, not a {what}")
    if not stat.S_ISREG(st.st_mode):
        kind = (
            "a named pipe (FIFO)"
            if stat.S_ISFIFO(st.st_mode)
            else "a socket"
            if stat.S_ISSOCK(st.st_mode)
            else "a device"
        )
        raise ReadError(p, f"not a regular file ({kind}) - expected a {what}")
    if not os.access(p, os.R_OK):
        raise ReadError(p, f"permission denied (the {what} cannot be read)")
    return int(st.st_size)


def read_text(
    path: str | os.PathLike[str], what: str = "file", *, limit: int = MAX_TEXT_BYTES
) -> str:
    """The UTF-8 text of ``path``, or a :class:`ReadError` that names it and ``what`` it is.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.yaml"
    >>> _ = f.write_text("seed: 3\\n", encoding="utf-8")
    >>> read_text(f)
    'seed: 3\\n'
    >>> try:
    ...     read_text(f.with_name("b.yaml"), "configuration file")
    ... except ReadError as exc:
    ...     print(str(exc).endswith("no such configuration file"))
    True
    """
    p = Path(path)
    size = regular_file(p, what)
    if size > limit:
        raise ReadError(
            p, f"{size:,} bytes is more than a {what} may hold (at most {limit:,} bytes)"
        )
    try:
        with open(p, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise ReadError(p, f"cannot read the {what} ({exc.strerror or exc})") from None
    if len(data) > limit:
        raise ReadError(p, f"grew past {limit:,} bytes while being read - expected a {what}")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ReadError(p, f"not UTF-8 text (byte {exc.start}) - expected a {what}") from None
