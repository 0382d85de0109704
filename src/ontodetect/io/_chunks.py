"""Decoding fixed-size binary records from a file, chunk by chunk, on two threads.

Binary PLY vertices and binary PCD points are rows of a fixed layout. The
fastest way found to turn 10 million of them into float64 coordinates and uint8
colours (see ``docs/benchmarks.md``) is to read about a megabyte of records
(:data:`CHUNK_BYTES`) into a buffer that stays in the CPU caches, cast each field
from it straight into the final arrays, and let two threads do this on
alternate chunks: file reads and NumPy copies release the GIL, so one thread
reads while the other converts, and each pays for faulting in its own share of
the freshly allocated result. Chunks are handed out one at a time in file order,
so the file is still read almost sequentially (which a cold page cache needs)
and a thread slowed down by another process on its core simply takes fewer
chunks.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._parallel import cpu_count
from .._progress import progress
from ..errors import CorruptFileError, InvalidParameterError, ReadError

__all__ = ["CHUNK_BYTES", "PARALLEL_MIN_BYTES", "READ_THREADS", "Copy", "Span", "read_records"]

#: Bytes of records read and converted per step. The buffer stays in a core's L2
#: cache; smaller chunks lose more to per-call overhead than they gain in cache hits
#: (10 million 15-byte records took 1.4x as long in 256 KiB chunks as in 1-2 MiB
#: ones, 1.1x in 4 MiB ones).
CHUNK_BYTES = 1 << 20
#: Below this many bytes of records one thread is used: a second costs more than it saves.
PARALLEL_MIN_BYTES = 4 << 20
#: Threads decoding large files (file reads and NumPy casts release the GIL).
READ_THREADS = 2


class Span(NamedTuple):
    """The bytes of every record from ``offset`` on, read as one ``dtype`` value.

    A span may run past the end of its record into the next one (the bytes
    after the last record are those that follow it in the file, or zeros at the
    end of the file), so that, for example, three consecutive uint8 colours can
    be moved as one 4-byte value.
    """

    offset: int
    dtype: np.dtype


#: Where one field of the records goes: ``(array, column or None, field name or Span)``.
Copy = tuple[NDArray[Any], int | None, str | Span]


def _positive(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise InvalidParameterError(name, "a whole number >= 1", value)
    return int(value)


def read_records(
    path: Path,
    offset: int,
    record: np.dtype,
    count: int,
    copies: Sequence[Copy],
    xyz: NDArray[np.float64],
    *,
    chunk_rows: int | None = None,
    threads: int | None = None,
) -> bool:
    """Decode ``count`` fixed-size binary records from ``path`` into the final arrays.

    Parameters
    ----------
    path : Path
        The file; the records start at byte ``offset``.
    offset : int
        Byte offset of the first record.
    record : numpy.dtype
        Structured type of one record (only the fields to keep need be named;
        its ``itemsize`` is the size of a whole row).
    count : int
        Number of records.
    copies : sequence of (array, column or None, field name or Span)
        Where every field goes: ``array[rows, column] = records[name]`` (or
        ``array[rows] = records[name]`` when column is None); byte order and
        type conversions happen in the copy, exactly as NumPy casts. A
        :class:`Span` instead of a name reads raw bytes of the record.
    xyz : (count, 3) float64
        The coordinate array among the targets, checked for NaN/Inf on the way.
    chunk_rows : int, optional
        Records per chunk; by default as many as fit in :data:`CHUNK_BYTES`.
    threads : int, optional
        Threads to use; by default :data:`READ_THREADS` (at most the number of
        usable CPUs) when the records fill :data:`PARALLEL_MIN_BYTES`, else one.

    Returns
    -------
    bool
        Whether every coordinate is finite (False as soon as one chunk holds a
        NaN or an infinity; the caller then finds which points).

    Raises
    ------
    CorruptFileError
        The file ends before the last record.
    ReadError
        The file cannot be read.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> rec = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("red", "u1")])
    >>> rows = np.zeros(5, rec)
    >>> rows["x"] = np.arange(5)
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "rows.bin"
    >>> _ = f.write_bytes(b"head" + rows.tobytes())
    >>> xyz = np.empty((5, 3))
    >>> copies = [(xyz, i, c) for i, c in enumerate("xyz")]
    >>> read_records(f, 4, rec, 5, copies, xyz, chunk_rows=2)
    True
    >>> xyz[:, 0].tolist()
    [0.0, 1.0, 2.0, 3.0, 4.0]
    """
    size = record.itemsize
    if count <= 0:
        return True
    if chunk_rows is None:
        chunk_rows = max(1, CHUNK_BYTES // max(size, 1))
    chunk_rows = min(_positive("chunk_rows", chunk_rows), count)
    if threads is None:
        threads = READ_THREADS if count * size >= PARALLEL_MIN_BYTES else 1
        threads = min(threads, cpu_count())
    chunks = -(-count // chunk_rows)
    threads = min(_positive("threads", threads), chunks)

    lock = threading.Lock()
    state = {"next": 0, "stop": False}

    with progress(f"Reading {path.name}", total=count) as advance:

        def claim(done: int) -> int | None:
            """Report ``done`` decoded rows and take the next chunk (None when none is left)."""
            with lock:
                if done:
                    advance(done)
                k = state["next"]
                if state["stop"] or k >= chunks:
                    return None
                state["next"] = k + 1
                return k

        def worker() -> bool:
            try:
                return _decode_chunks(path, offset, record, count, copies, xyz, chunk_rows, claim)
            except BaseException:
                state["stop"] = True  # the other threads finish their chunk and return
                raise

        try:
            if threads == 1:
                return worker()
            # The calling thread decodes too, alongside threads - 1 helpers.
            with ThreadPoolExecutor(threads - 1, thread_name_prefix="ontodetect-read") as pool:
                helpers = [pool.submit(worker) for _ in range(threads - 1)]
                finite = worker()
            for helper in helpers:
                finite = helper.result() and finite  # re-raises a helper's error
            return finite
        except OSError as exc:
            raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc


def _decode_chunks(
    path: Path,
    offset: int,
    record: np.dtype,
    count: int,
    copies: Sequence[Copy],
    xyz: NDArray[np.float64],
    chunk_rows: int,
    claim: Callable[[int], int | None],
) -> bool:
    """One thread's share: claim chunks until none is left, read and convert each."""
    size = record.itemsize
    # Spans running past the last record of a chunk read these extra bytes.
    pad = max(
        [0] + [s.offset + s.dtype.itemsize - size for _, _, s in copies if isinstance(s, Span)]
    )
    buf = np.empty(chunk_rows * size + pad, dtype=np.uint8)
    view = memoryview(buf)
    # Views over the buffer, made once: each chunk only slices them.
    sources = _pairs(buf, record, chunk_rows, copies)
    ok = np.empty((chunk_rows, 3), dtype=bool)  # reused: no allocation a chunk
    finite = True
    done = 0
    with open(path, "rb", buffering=0) as fh, np.errstate(invalid="ignore", over="ignore"):
        # (Signalling NaNs in float32 data raise "invalid" when widened.)
        while (k := claim(done)) is not None:
            start = k * chunk_rows
            m = min(chunk_rows, count - start)
            want = m * size
            fh.seek(offset + start * size)
            got = 0
            while got < want + pad:
                n = fh.readinto(view[got : want + pad])
                if not n:
                    break
                got += n
            if got < want:
                raise CorruptFileError(
                    path, f"ends inside the data at byte {offset + start * size + got}"
                )
            buf[got : want + pad] = 0  # past the end of the file
            stop = start + m
            for dest, src in sources:
                dest[start:stop] = src[:m]
            # Checked while the chunk is in the cache; one bad chunk settles it.
            finite = finite and bool(np.isfinite(xyz[start:stop], out=ok[:m]).all())
            done = m
    return finite


def _pairs(
    buf: NDArray[np.uint8], record: np.dtype, rows: int, copies: Sequence[Copy]
) -> list[tuple[NDArray[Any], NDArray[Any]]]:
    """(target, source) views such that ``target[a:b] = source[:b - a]`` does ``copies``.

    ``buf`` holds ``rows`` records (and the bytes spans need after them). The
    columns 0, 1, 2... of one C-ordered array, filled in that order, are moved
    in one assignment rather than column by column, which NumPy runs 3x (raw
    bytes) or 10 % (casts) faster; anything else is copied field by field. The
    values are NumPy's casts, bit for bit, either way.
    """
    records = buf[: rows * record.itemsize].view(record)
    pairs: list[tuple[NDArray[Any], NDArray[Any]]] = []
    i = 0
    while i < len(copies):
        dest, col, name = copies[i]
        if isinstance(name, Span):
            pairs.append((dest if col is None else dest[:, col], _span(buf, record, rows, name)))
            i += 1
            continue
        group = [name]
        if col == 0 and dest.ndim == 2 and dest.flags.c_contiguous:
            while (
                len(group) < dest.shape[1]
                and i + len(group) < len(copies)
                and copies[i + len(group)][0] is dest
                and copies[i + len(group)][1] == len(group)
                and isinstance(copies[i + len(group)][2], str)
            ):
                group.append(copies[i + len(group)][2])  # type: ignore[arg-type]
        whole = None
        if dest.ndim == 2 and len(group) == dest.shape[1] > 1:
            whole = _whole_rows(record, group, dest)
        if whole is None:
            pairs.append((dest if col is None else dest[:, col], records[name]))
            i += 1
            continue
        target, how = whole
        source = _span(buf, record, rows, how) if isinstance(how, Span) else records[how]
        pairs.append((target, source))
        i += len(group)
    return pairs


def _span(buf: NDArray[np.uint8], record: np.dtype, rows: int, span: Span) -> NDArray[Any]:
    return np.ndarray((rows,), span.dtype, buf, span.offset, (record.itemsize,))


def _whole_rows(
    record: np.dtype, names: list[str], dest: NDArray[Any]
) -> tuple[NDArray[Any], Span | list[str]] | None:
    """One assignment filling whole rows of ``dest`` from fields ``names``, if one helps.

    Returns the target view of ``dest`` and its source: a :class:`Span` when
    the fields are laid out exactly like a row of ``dest`` (float64 x y z one
    after the other: raw bytes, 3x faster than three column copies), or the
    field names when they are native-order values to be cast to float (float32
    to float64: a structured assignment casts every field in one call). None for
    anything else (byte-swapped fields gain nothing from either).
    """
    if len(set(names)) != len(names):
        return None
    kinds = [record.fields[n][0] for n in names]
    offsets = [record.fields[n][1] for n in names]
    width = dest.dtype.itemsize
    if all(k == dest.dtype for k in kinds) and offsets == [
        offsets[0] + j * width for j in range(len(names))
    ]:
        raw = np.dtype(f"V{width * len(names)}")
        return dest.view(raw).reshape(-1), Span(offsets[0], raw)
    if dest.dtype.kind == "f" and all(k.isnative and k != dest.dtype for k in kinds):
        row = np.dtype([(f"f{j}", dest.dtype) for j in range(len(names))])
        return dest.view(row).reshape(-1), names
    return None
