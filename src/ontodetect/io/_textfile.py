"""Reading the small text files around point clouds (configurations, manifests, JSON)."""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import ReadError

__all__ = ["read_text"]


def read_text(path: str | os.PathLike[str], what: str = "file") -> str:
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
    try:
        return p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ReadError(p, f"no such {what}") from None
    except IsADirectoryError:
        raise ReadError(p, f"a folder, not a {what}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ReadError(p, f"cannot read the {what} ({exc})") from exc
