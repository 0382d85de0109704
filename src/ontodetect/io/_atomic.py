"""Atomic writes: a file through a temporary file beside it and a rename; a folder of
files (one run's outputs) through a staging folder beside it that is swapped in whole."""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from ..errors import WriteError

__all__ = [
    "RUN_MARKER",
    "atomic_write",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_output_folder",
    "make_folder",
    "staged_folder",
]

#: Written into an output folder by :func:`staged_folder`: the names of the files of the
#: run that wrote it, one a line. A folder holding nothing else is replaced whole.
RUN_MARKER = ".ontodetect-run"


def make_folder(path: str | os.PathLike[str], what: str = "folder") -> Path:
    """Create the folder ``path`` (and its parents) if needed; a failure is a WriteError
    that names the folder as ``what`` ("output folder", "report folder"...).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> make_folder(pathlib.Path(tempfile.mkdtemp()) / "a" / "b").is_dir()
    True
    """
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WriteError(out, f"cannot create the {what} ({exc.strerror})") from exc
    return out


def check_output_folder(path: str | os.PathLike[str], what: str = "output folder") -> Path:
    """Before any work: ``path`` is a folder or can become one, and the runs that write
    it can (the folder it is made in, where a run stages its files, and the folder itself
    when it exists are writable); a WriteError names it otherwise.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> base = pathlib.Path(tempfile.mkdtemp())
    >>> check_output_folder(base / "new" / "out") == base / "new" / "out"
    True
    >>> (base / "f").write_text("")
    0
    >>> check_output_folder(base / "f")
    Traceback (most recent call last):
    ...
    ontodetect.errors.WriteError: ...f: the output folder is a file, not a folder
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise WriteError(out, f"the {what} is a file, not a folder")
    above = next((p for p in out.parents if p.exists()), Path("."))
    if not above.is_dir():
        raise WriteError(out, f"cannot create the {what}: {str(above)!r} is a file")
    for folder in (out, above) if out.exists() else (above,):
        if not os.access(folder, os.W_OK | os.X_OK):
            raise WriteError(out, f"cannot write the {what} (permission denied on {str(folder)!r})")
    return out


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike[str], mode: str = "wb") -> Iterator[IO]:
    """Open a temporary file next to ``path``; on success it replaces ``path``.

    If the block raises, the temporary file is removed and ``path`` is left as it
    was, so a reader never sees a half-written file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
    >>> with atomic_write(target, "w") as fh:
    ...     _ = fh.write("done")
    >>> target.read_text()
    'done'
    """
    target = Path(path)
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise WriteError(target, f"folder {str(parent)!r} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=parent)
    except OSError as exc:
        raise WriteError(target, f"cannot create a file there ({exc.strerror})") from exc
    try:
        with os.fdopen(fd, mode) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        # mkstemp makes the file private; give it the permissions a plain open() would.
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and not isinstance(exc, WriteError):
            # A full disk, a quota, a folder where the file should go: one line that names
            # the file; the old file (if any) is untouched.
            raise WriteError(target, f"cannot write ({exc.strerror or exc})") from None
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically and return the path."""
    with atomic_write(path, "wb") as fh:
        fh.write(data)
    return Path(path)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically and return the path."""
    with atomic_write(path, "w") as fh:
        fh.write(text)
    return Path(path)


def _remove_stale(parent: Path, name: str) -> None:
    """Remove what an interrupted run left beside ``parent / name``: staging folders, and
    the previous result moved aside (put back when the new one never arrived)."""
    out = parent / name
    stale = sorted(parent.glob(f".{name}.staging-*")) + sorted(parent.glob(f".{name}.old-*"))
    for entry in stale:
        if entry.name.startswith(f".{name}.old-") and not out.exists():
            with contextlib.suppress(OSError):
                os.rename(entry, out)
                continue
        _remove(entry)


def _run_files(folder: Path) -> set[str] | None:
    """Names listed by the folder's run marker; None without a readable marker."""
    try:
        text = (folder / RUN_MARKER).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    return {line for line in text.splitlines() if line}


def _commit(stage: Path, out: Path, what: str, keep_earlier: bool = False) -> None:
    names = sorted(p.name for p in stage.iterdir())
    if not out.exists() and not out.is_symlink():
        _write_marker(stage, names)
        os.rename(stage, out)
        return
    if not out.is_dir() or out.is_symlink():
        raise WriteError(out, f"the {what} is not a folder")
    present = {p.name for p in out.iterdir()}
    ours = _run_files(out) or set()
    # With keep_earlier, an earlier run's files this run does not write stay, and the
    # marker lists them too: the next run of the earlier kind replaces them all.
    kept = sorted((ours & present) - set(names) - {RUN_MARKER}) if keep_earlier else []
    _write_marker(stage, names + kept)
    if not keep_earlier and ours and present <= ours | {RUN_MARKER}:
        # Only an earlier run's files: swap the folders. Killed between the two renames,
        # the next run puts the old folder back (_remove_stale).
        _swap_folder(stage, out)
        return
    # A folder with other files too (the user's): replace our files one by one, checked
    # first so that nothing is changed when one cannot be, and the marker last. A folder
    # an earlier run wrote (an export) is ours to replace; any other is the user's.
    for n in names:
        target = out / n
        if target.is_dir() and not target.is_symlink() and n not in ours:
            raise WriteError(target, "a folder is in the way of this output file")
    for n in names:
        target = out / n
        if target.is_dir() and not target.is_symlink():
            _swap_folder(stage / n, target)
        else:
            os.replace(stage / n, target)
    for n in sorted(ours - set(names) - set(kept) - {RUN_MARKER}):
        _remove(out / n)
    os.replace(stage / RUN_MARKER, out / RUN_MARKER)
    shutil.rmtree(stage, ignore_errors=True)


def _swap_folder(new: Path, target: Path) -> None:
    """``new`` in the place of the folder ``target``: the old one moved aside first (as
    ``.NAME.old-*``, which :func:`_remove_stale` puts back if a kill comes between the two
    renames), then removed."""
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
    os.rmdir(old)
    os.rename(target, old)
    os.rename(new, target)
    shutil.rmtree(old, ignore_errors=True)


def _write_marker(stage: Path, names: list[str]) -> None:
    (stage / RUN_MARKER).write_text("".join(f"{n}\n" for n in names), encoding="utf-8")


def _remove(path: Path) -> None:
    """An earlier run's file or folder, gone (quietly: it may already be)."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(OSError):
            path.unlink()


@contextlib.contextmanager
def staged_folder(
    path: str | os.PathLike[str], what: str = "output folder", *, keep_earlier: bool = False
) -> Iterator[Path]:
    """Write the files of one run into a staging folder beside ``path``; on success they
    replace ``path``'s as one unit, on any failure nothing in ``path`` has changed.

    A folder that holds only an earlier run's files (listed in its :data:`RUN_MARKER`) is
    swapped whole; a folder with other files keeps them, and our files (and folders an
    earlier run wrote) are replaced after checking that each can be. With
    ``keep_earlier`` (a run that adds to an earlier one's results, such as CAD models
    fitted to stored detections) the earlier run's other files stay. Staging folders left
    by a killed run are removed first.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "result"
    >>> with staged_folder(out) as stage:
    ...     _ = (stage / "a.txt").write_text("new")
    >>> sorted(p.name for p in out.iterdir())
    ['.ontodetect-run', 'a.txt']
    """
    out = Path(path)
    parent = make_folder(out.parent if str(out.parent) else Path("."), what)
    _remove_stale(parent, out.name)
    if out.exists() and not out.is_dir():
        raise WriteError(out, f"the {what} is a file, not a folder")
    try:
        stage = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=parent))
    except OSError as exc:
        raise WriteError(out, f"cannot create the {what} ({exc.strerror or exc})") from None
    try:
        # mkdtemp makes the folder private; give it the permissions mkdir would.
        os.chmod(stage, 0o777 & ~_umask())
        yield stage
        _commit(stage, out, what, keep_earlier)
    except BaseException as exc:
        shutil.rmtree(stage, ignore_errors=True)
        if isinstance(exc, OSError) and not isinstance(exc, WriteError):
            full = " (the disk is full)" if exc.errno == errno.ENOSPC else ""
            where = str(exc.filename or out).replace(str(stage), str(out))
            raise WriteError(
                where, f"cannot write the {what}{full} ({exc.strerror or exc})"
            ) from None
        raise
