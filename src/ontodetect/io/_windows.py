"""Reading a cloud too large for one process piece by piece: its points in chunks, a
subsample of them, or only those inside a window on the floor plane.

Binary PLY is read a block of vertex rows at a time; LAS and LAZ through laspy's
chunk iterator (LAZ is decompressed chunk by chunk). Either way at most one chunk of the
file (:data:`WINDOW_CHUNK_POINTS` rows) is decoded at a time, and what is kept is the
window's points with their rows in the file (``PointCloud.index``), so that detections
in a window index the whole file. Any other format is read whole and then cut: it works,
but it does not bound memory (convert such clouds to binary PLY or LAZ first).

A window keeps coordinates, colours and (PLY) normals: what detection uses. Per-point
fields (labels, intensity) are not read. Colours of a LAS file are 16-bit: a window
shifts them to 8 bits unless every colour of the window is at most 255, as
:func:`~ontodetect.io.read_cloud` decides for the whole file.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..cloud import PointCloud, point_cloud
from ..errors import CorruptFileError, InvalidParameterError, ReadError
from ._budget import MIN_SCAN_POINTS, check_enough_points
from ._las import MAX_COLOR8, _BoundedFile, _check_header, _laspy, _laspy_errors
from ._ply import _plan_for, _read_header, file_size

__all__ = [
    "STREAMED_FORMATS",
    "WINDOW_CHUNK_POINTS",
    "CloudSurvey",
    "Window",
    "iter_chunks",
    "read_window",
    "survey_cloud",
]

#: Rows decoded at a time: about 40 MB of float64 coordinates and colours.
WINDOW_CHUNK_POINTS = 1 << 20
#: Formats read chunk by chunk (others are read whole, then cut).
STREAMED_FORMATS = ("ply", "las")


@dataclass(frozen=True)
class Chunk:
    """Consecutive rows of a file: ``xyz`` (m, 3) float64 of rows ``start .. start + m``,
    colours (m, 3) as stored (uint8, uint16...) or None, normals (m, 3) or None."""

    start: int
    xyz: NDArray[np.float64]
    rgb: NDArray[Any] | None
    normals: NDArray[np.float64] | None


@dataclass(frozen=True)
class Window:
    """The points whose coordinates on two axes lie in a box: ``lo <= xyz @ axes.T < hi``.

    Attributes
    ----------
    axes : (2, 3) float
        Two orthonormal directions of the floor plane.
    lo, hi : (2,) float
        Bounds on them (``-inf`` / ``inf`` for an open side).
    """

    axes: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]

    def contains(self, xyz: ArrayLike) -> NDArray[np.bool_]:
        """(n,) bool: which points of ``xyz`` (n, 3) lie in the window."""
        uv = np.asarray(xyz, dtype=np.float64) @ self.axes.T
        return np.all((uv >= self.lo) & (uv < self.hi), axis=1)

    def misses(self, boxes: ArrayLike) -> NDArray[np.bool_]:
        """(k,) bool: which boxes (k, 2, 3) (low and high corners; NaN: empty) surely hold
        no point of the window (their corners' span on the axes does not meet it)."""
        boxes = np.asarray(boxes, dtype=np.float64)
        corners = np.stack(
            [boxes[:, [i, j, m], [0, 1, 2]] for i in (0, 1) for j in (0, 1) for m in (0, 1)],
            axis=1,
        )  # (k, 8, 3)
        uv = corners @ self.axes.T
        with np.errstate(invalid="ignore"):
            empty = np.isnan(boxes).any(axis=(1, 2))
            low, high = uv.min(axis=1), uv.max(axis=1)
            apart = np.any((high < self.lo) | (low >= self.hi), axis=1)
        return empty | apart


def _format(path: Path, format: str | None) -> str:
    from . import detect_format  # lazy: the registry imports this module's readers by name

    return format.lower() if format else detect_format(path)


def iter_chunks(
    path: str | Path,
    *,
    format: str | None = None,
    chunk_points: int = WINDOW_CHUNK_POINTS,
    skip: Callable[[int], bool] | None = None,
) -> Iterator[Chunk]:
    """The rows of a point cloud file, ``chunk_points`` at a time, in file order.

    Binary PLY and LAS/LAZ are decoded one chunk at a time; any other format is read
    whole (:func:`~ontodetect.io.read_cloud`) and handed out in slices. Chunk number k
    (rows ``k * chunk_points`` on) is stepped over without being decoded when
    ``skip(k)`` is true (binary PLY and LAS/LAZ; other formats hand out every chunk).

    Raises
    ------
    ReadError
        As the format's reader would.
    """
    path = Path(path)
    if isinstance(chunk_points, bool) or not isinstance(chunk_points, int) or chunk_points < 1:
        raise InvalidParameterError("chunk_points", "a whole number >= 1", chunk_points)
    fmt = _format(path, format)
    if fmt == "ply":
        chunks = _ply_chunks(path, chunk_points, skip)
        if chunks is not None:
            yield from chunks
            return
    elif fmt == "las":
        yield from _las_chunks(path, chunk_points, skip)
        return
    yield from _whole_chunks(path, fmt, chunk_points)


def _whole_chunks(path: Path, fmt: str, chunk_points: int) -> Iterator[Chunk]:
    from . import read_points  # lazy: the registry imports this module's readers by name

    cloud = read_points(path, format=fmt, on_nonfinite="drop")
    rows = cloud.index
    # Rows dropped by the reader (non-finite) leave gaps: hand out runs of kept rows.
    for a in range(0, len(cloud), chunk_points):
        b = min(a + chunk_points, len(cloud))
        sel = slice(a, b)
        if rows[b - 1] - rows[a] != b - a - 1:
            for i in range(a, b):  # rare: a slice with dropped rows, one row at a time
                yield Chunk(
                    int(rows[i]),
                    cloud.xyz[i : i + 1],
                    None if cloud.rgb is None else cloud.rgb[i : i + 1],
                    None if cloud.normals is None else cloud.normals[i : i + 1],
                )
            continue
        yield Chunk(
            int(rows[a]),
            cloud.xyz[sel],
            None if cloud.rgb is None else cloud.rgb[sel],
            None if cloud.normals is None else cloud.normals[sel],
        )


def _ply_chunks(path: Path, chunk_points: int, skip) -> Iterator[Chunk] | None:
    """Chunks of a binary PLY whose vertices are fixed-size rows; None for any other."""
    header = _read_header(path)
    vertex = next((e for e in header.elements if e.name == "vertex"), None)
    if vertex is None or header.encoding == "ascii" or vertex.has_lists:
        return None
    before = header.elements[: header.elements.index(vertex)]
    if any(e.has_lists for e in before):
        return None
    order = "<" if header.encoding == "binary_little_endian" else ">"
    offset = header.data_offset + sum(e.count * e.record(order).itemsize for e in before)
    plan = _plan_for(path, vertex)
    record = vertex.record(
        order, keep=[*(plan.xyz or ()), *(plan.rgb or ()), *(plan.normals or ())]
    )
    count = vertex.count
    if count == 0:
        raise CorruptFileError(path, "contains no points (element vertex 0)")
    size = file_size(path)
    if offset + count * record.itemsize > size:
        raise CorruptFileError(
            path,
            f"truncated: the header declares {count} vertices ({count * record.itemsize} "
            f"bytes from byte {offset}) but the file holds only {max(size - offset, 0)} bytes",
        )
    return _record_chunks(path, offset, record, count, plan, chunk_points, skip)


def _record_chunks(path, offset, record, count, plan, chunk_points, skip) -> Iterator[Chunk]:
    """Rows read into a buffer of one chunk (not mapped: a mapped file's pages would
    count in the process's resident memory as it is read through)."""
    try:
        fh = open(path, "rb")  # noqa: SIM115 - held across the generator's yields
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    with fh, np.errstate(invalid="ignore", over="ignore"):
        for k, start in enumerate(range(0, count, chunk_points)):
            if skip is not None and skip(k):
                continue
            m = min(chunk_points, count - start)
            fh.seek(offset + start * record.itemsize)
            try:
                part = np.fromfile(fh, dtype=record, count=m)
            except OSError as exc:
                raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
            if len(part) < m:
                raise CorruptFileError(
                    path, f"ends inside the vertex rows (row {start + len(part)})"
                )
            xyz = np.empty((m, 3), dtype=np.float64)
            for i, name in enumerate(plan.xyz):
                xyz[:, i] = part[name]
            rgb = normals = None
            if plan.rgb is not None:
                kind = np.result_type(*(record[n].newbyteorder("=") for n in plan.rgb))
                rgb = np.empty((m, 3), dtype=kind)
                for i, name in enumerate(plan.rgb):
                    rgb[:, i] = part[name]
            if plan.normals is not None:
                normals = np.empty((m, 3), dtype=np.float64)
                for i, name in enumerate(plan.normals):
                    normals[:, i] = part[name]
            yield Chunk(start, xyz, rgb, normals)


def _las_chunks(path: Path, chunk_points: int, skip) -> Iterator[Chunk]:
    laspy = _laspy()
    errors = _laspy_errors()
    _check_header(path, file_size(path))
    try:
        reader = laspy.open(
            _BoundedFile(path, "rb"), closefd=True, laz_backend=laspy.LazBackend.Lazrs
        )
    except BaseException as exc:
        if not isinstance(exc, errors):
            raise
        raise CorruptFileError(path, f"not a readable LAS/LAZ file ({exc})") from exc
    try:
        count = int(reader.header.point_count)
        if count <= 0:
            raise CorruptFileError(path, "contains no points (the header says 0)")
        has_rgb = {"red", "green", "blue"} <= set(reader.header.point_format.dimension_names)
        position = 0  # the reader's next row
        with np.errstate(over="ignore", invalid="ignore"):
            for k, start in enumerate(range(0, count, chunk_points)):
                if skip is not None and skip(k):
                    continue
                if position != start:
                    reader.seek(start)  # over skipped chunks (LAZ: through its chunk table)
                want = min(chunk_points, count - start)
                chunk = reader.read_points(want)
                n = len(chunk)
                position = start + n
                if n < want:
                    raise CorruptFileError(
                        path,
                        f"truncated: the header says {count} points but only "
                        f"{start + n} could be read",
                    )
                xyz = np.empty((n, 3), dtype=np.float64)
                xyz[:, 0] = np.asarray(chunk.x, dtype=np.float64)
                xyz[:, 1] = np.asarray(chunk.y, dtype=np.float64)
                xyz[:, 2] = np.asarray(chunk.z, dtype=np.float64)
                rgb = None
                if has_rgb:
                    rgb = np.empty((n, 3), dtype=np.uint16)
                    rgb[:, 0] = np.asarray(chunk.red)
                    rgb[:, 1] = np.asarray(chunk.green)
                    rgb[:, 2] = np.asarray(chunk.blue)
                yield Chunk(start, xyz, rgb, None)
    except (CorruptFileError, GeneratorExit):
        raise
    except BaseException as exc:
        if not isinstance(exc, errors):
            raise
        raise CorruptFileError(path, f"cannot decode the points ({exc})") from exc
    finally:
        with contextlib.suppress(*errors):
            reader.close()


@dataclass(frozen=True)
class CloudSurvey:
    """One pass over a whole file: its size, its bounds and an even subsample.

    Attributes
    ----------
    num_points : int
        Rows of the file.
    lo, hi : (3,) float
        Bounds of its finite coordinates.
    sample : PointCloud
        Every ``step``-th row (``index``: its rows in the file).
    step : int
    chunk_points : int
        Rows of a chunk.
    chunk_bounds : (k, 2, 3) float
        Low and high corner of every chunk's finite coordinates (NaN for a chunk without
        one): a window read steps over the chunks whose box misses it.
    """

    num_points: int
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    sample: PointCloud
    step: int
    chunk_points: int = WINDOW_CHUNK_POINTS
    chunk_bounds: NDArray[np.float64] | None = None


def survey_cloud(
    path: str | Path,
    *,
    format: str | None = None,
    sample_points: int = 2_000_000,
    chunk_points: int = WINDOW_CHUNK_POINTS,
    min_points: int = MIN_SCAN_POINTS,
) -> CloudSurvey:
    """Count, bound and subsample a file in one pass, a chunk at a time.

    The subsample is every ``step``-th row, ``step`` the smallest that gives at most
    ``sample_points`` rows (the row count comes from the header, without a first pass).
    A file with fewer than ``min_points`` points with finite coordinates is refused
    (:class:`~ontodetect.errors.ReadError`): the survey is the start of a detection.
    """
    path = Path(path)
    if isinstance(sample_points, bool) or not isinstance(sample_points, int) or sample_points < 1:
        raise InvalidParameterError("sample_points", "a whole number >= 1", sample_points)
    total = _declared_count(path, _format(path, format))
    step = max(1, -(-total // sample_points)) if total else 1
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    parts: list[Chunk] = []
    rows: list[NDArray[np.int64]] = []
    boxes: list[NDArray[np.float64]] = []
    n = usable = 0
    for chunk in iter_chunks(path, format=format, chunk_points=chunk_points):
        m = len(chunk.xyz)
        finite = np.isfinite(chunk.xyz).all(axis=1)
        usable += int(finite.sum())
        box = np.full((2, 3), np.nan)
        if finite.any():
            box = np.array([chunk.xyz[finite].min(axis=0), chunk.xyz[finite].max(axis=0)])
            lo = np.minimum(lo, box[0])
            hi = np.maximum(hi, box[1])
        k = chunk.start // chunk_points
        boxes.extend([np.full((2, 3), np.nan)] * (k - len(boxes)))  # (a reader's dropped rows)
        if k < len(boxes):
            boxes[k] = np.array([np.fmin(boxes[k][0], box[0]), np.fmax(boxes[k][1], box[1])])
        else:
            boxes.append(box)
        first = (-chunk.start) % step
        take = np.arange(first, m, step)
        take = take[finite[take]]
        if len(take):
            parts.append(_take(chunk, take))
            rows.append(chunk.start + take)
        n = max(n, chunk.start + m)
    if not parts:
        raise CorruptFileError(path, "contains no points with finite coordinates")
    check_enough_points(path, usable, min_points)
    sample = _cloud(path, parts, np.concatenate(rows))
    return CloudSurvey(n, lo, hi, sample, step, chunk_points, np.array(boxes).reshape(-1, 2, 3))


def _declared_count(path: Path, fmt: str) -> int:
    """Rows the file's header declares (0 when the format has no such header)."""
    try:
        if fmt == "ply":
            header = _read_header(path)
            vertex = next((e for e in header.elements if e.name == "vertex"), None)
            return 0 if vertex is None else vertex.count
        if fmt == "las":
            laspy = _laspy()
            with laspy.open(path) as reader:
                return int(reader.header.point_count)
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    return 0


def read_window(
    path: str | Path,
    window: Window,
    *,
    format: str | None = None,
    chunk_points: int = WINDOW_CHUNK_POINTS,
    chunk_bounds: ArrayLike | None = None,
) -> PointCloud | None:
    """The points of a file inside ``window``, with their rows in the file as ``index``.

    Only one chunk of the file is decoded at a time (binary PLY, LAS/LAZ): the memory
    a window takes is that of its own points, not the file's. With ``chunk_bounds``
    (:attr:`CloudSurvey.chunk_bounds`, for the same ``chunk_points``) the chunks whose
    box misses the window are not even decoded: a file written room by room, or sorted
    along a path, is read only where the window is. None when no point lies in the
    window.
    """
    path = Path(path)
    parts: list[Chunk] = []
    rows: list[NDArray[np.int64]] = []
    skip = None
    if chunk_bounds is not None:
        misses = window.misses(np.asarray(chunk_bounds, dtype=np.float64).reshape(-1, 2, 3))
        skip = lambda k: k < len(misses) and bool(misses[k])  # noqa: E731
    for chunk in iter_chunks(path, format=format, chunk_points=chunk_points, skip=skip):
        with np.errstate(invalid="ignore"):
            inside = np.flatnonzero(window.contains(chunk.xyz))
        if len(inside):
            parts.append(_take(chunk, inside))
            rows.append(chunk.start + inside)
    if not parts:
        return None
    return _cloud(path, parts, np.concatenate(rows))


def _take(chunk: Chunk, rows: NDArray[np.int64]) -> Chunk:
    return Chunk(
        chunk.start,
        chunk.xyz[rows],
        None if chunk.rgb is None else chunk.rgb[rows],
        None if chunk.normals is None else chunk.normals[rows],
    )


def _cloud(path: Path, parts: list[Chunk], index: NDArray[np.int64]) -> PointCloud:
    xyz = np.concatenate([p.xyz for p in parts])
    rgb = None
    if parts[0].rgb is not None:
        rgb = np.concatenate([p.rgb for p in parts])
        if rgb.dtype == np.uint16 and int(rgb.max(initial=0)) <= MAX_COLOR8:
            rgb = rgb.astype(np.uint8)  # LAS with 8-bit values in 16-bit fields
    normals = None
    if parts[0].normals is not None:
        normals = np.concatenate([p.normals for p in parts])
        if not np.isfinite(normals).all():
            normals = None
    try:
        return point_cloud(
            xyz,
            rgb=rgb,
            normals=normals,
            index=index,
            meta={"source": str(path)},
            on_nonfinite="drop",
            copy=False,
        )
    except InvalidParameterError as exc:
        raise CorruptFileError(path, f"invalid point data: {exc}") from exc
