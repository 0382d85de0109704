"""A fitted model as plain numbers: a ``.npz`` archive of numeric arrays and a JSON header.

Nothing in such a file is ever unpickled: the header is a string array holding JSON, every
other member a numeric array, and the reader refuses object arrays before decoding them
(the same bounded reader as point archives). A model file someone sent can therefore be
opened without running code from it. ``numpy.load(path, allow_pickle=False)`` reads it too.
"""

from __future__ import annotations

import io
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import CorruptFileError, WriteError
from ._atomic import atomic_write_bytes
from ._textfile import regular_file

__all__ = ["HEADER_KEY", "read_array_archive", "write_array_archive"]

#: Name of the member holding the JSON header.
HEADER_KEY = "header"


def write_array_archive(
    path: str | os.PathLike[str], header: Mapping[str, Any], arrays: Mapping[str, Any]
) -> Path:
    """Write ``header`` (JSON-serialisable) and numeric ``arrays`` to a ``.npz`` file, atomically.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "m.npz"
    >>> _ = write_array_archive(f, {"format": "demo/1"}, {"w": np.arange(3.0)})
    >>> head, arrays = read_array_archive(f)
    >>> head["format"], arrays["w"].tolist()
    ('demo/1', [0.0, 1.0, 2.0])
    """
    if HEADER_KEY in arrays:
        raise WriteError(path, f"{HEADER_KEY!r} is reserved for the header")
    members: dict[str, NDArray[Any]] = {}
    for name, value in arrays.items():
        arr = np.asarray(value)
        if arr.dtype.hasobject or arr.dtype.kind not in "biuf":
            raise WriteError(path, f"array {name!r} is not numeric ({arr.dtype})")
        members[name] = arr
    try:
        text = json.dumps(header, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise WriteError(path, f"the header cannot be written as JSON ({exc})") from None
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **{HEADER_KEY: np.array(text)}, **members)
    return atomic_write_bytes(path, buffer.getvalue())


def read_array_archive(
    path: str | os.PathLike[str], what: str = "model file"
) -> tuple[dict[str, Any], dict[str, NDArray[Any]]]:
    """The JSON header and the numeric arrays of a file written by :func:`write_array_archive`.

    Raises
    ------
    ReadError
        Missing or unreadable file, or a member holding Python objects.
    CorruptFileError
        Not a ``.npz`` archive, no header, a header that is not a JSON object, or a member
        that is not a numeric array.
    """
    from ._numpy import _npz_arrays  # lazy: the archive reader loads the PLY module (start-up)

    p = Path(path)
    regular_file(p, what)
    arrays = _npz_arrays(p)
    raw = arrays.pop(HEADER_KEY, None)
    if raw is None:
        raise CorruptFileError(p, f"no {HEADER_KEY!r} member - expected a {what}")
    if raw.shape != () or raw.dtype.kind != "U":
        raise CorruptFileError(p, f"the {HEADER_KEY!r} member is not a JSON string")
    try:
        header = json.loads(str(raw[()]))
    except ValueError as exc:
        raise CorruptFileError(p, f"the header is not valid JSON ({exc})") from None
    if not isinstance(header, dict):
        raise CorruptFileError(p, "the header is not a JSON object")
    for name, arr in arrays.items():
        if arr.dtype.kind not in "biuf":
            raise CorruptFileError(p, f"array {name!r} is not numeric ({arr.dtype})")
    return header, arrays
