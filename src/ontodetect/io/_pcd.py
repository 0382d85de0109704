"""PCL point cloud data (PCD): reader and writer.

Reads ``VERSION 0.7`` files (and the older headers without ``WIDTH``) in the
three encodings PCL writes:

- ``ascii``: one point per line;
- ``binary``: packed little-endian records, one per point;
- ``binary_compressed``: two uint32 (compressed and uncompressed size) then LZF
  data that expands to one array per field (all x, then all y, ...).

``x y z`` become the coordinates; a packed ``rgb`` / ``rgba`` field (float32 or
uint32 holding ``0xAARRGGBB``) becomes colours; ``normal_x normal_y normal_z``
become normals; every other field becomes a named field of its own type, and a
field with ``COUNT k > 1`` (a feature histogram, say) becomes an (n, k) field.
Padding fields named ``_`` are skipped.

An organized cloud (``HEIGHT > 1``, a depth camera frame) marks missing depth
with NaN coordinates: those points are dropped silently and ``index`` keeps the
row-major grid position (``row * WIDTH + column``) of every point kept. ``meta``
records ``width``, ``height``, ``organized``, ``viewpoint`` and ``pcd_data``.

The writer puts such a frame back on its grid (NaN where a pixel has no point), and
stores coordinates as float32, as PCL does, unless that would move them by more than
:data:`~ontodetect.io._ply.FLOAT32_TOLERANCE` (a cloud in map coordinates): then as
float64.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import IO, Any

import lzf
import numpy as np
from numpy.typing import NDArray

from .._progress import progress
from ..cloud import PointCloud, pixel_grid
from ..errors import CorruptFileError, InvalidParameterError, ReadError, WriteError
from ._budget import check_bytes, check_points
from ._ply import (
    HEADER_MAX_BYTES,
    Column,
    ColumnPlan,
    ascii_table,
    check_float32_range,
    check_on_nonfinite,
    cloud_from_columns,
    cloud_from_records,
    coordinate_dtype,
    field_columns,
    file_size,
    parse_column,
    plan_columns,
    storage_dtype,
    write_ascii_rows,
    write_atomically,
    write_rows,
)

__all__ = ["read_pcd", "write_pcd"]

#: LZF never expands data more than this many times (a 3-byte back reference
#: copies at most 264 bytes); a larger claimed ratio means a damaged size field.
LZF_MAX_RATIO = 100
#: Largest buffer binary_compressed can describe (sizes are uint32).
LZF_MAX_BYTES = 2**32 - 1
#: Default VIEWPOINT: origin, identity rotation (tx ty tz qw qx qy qz).
DEFAULT_VIEWPOINT = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
#: Encodings of the points named on the ``DATA`` line.
ENCODINGS = ("ascii", "binary", "binary_compressed")

_TYPES = {
    ("F", 4): "f4",
    ("F", 8): "f8",
    ("I", 1): "i1",
    ("I", 2): "i2",
    ("I", 4): "i4",
    ("I", 8): "i8",
    ("U", 1): "u1",
    ("U", 2): "u2",
    ("U", 4): "u4",
    ("U", 8): "u8",
}
_CODES = {code: key for key, code in _TYPES.items()}
_PACKED = ("rgb", "rgba")
_DATA_LINE = re.compile(rb"(?:^|\n)[ \t]*DATA[ \t]+([A-Za-z_]+)[ \t]*\r?\n", re.IGNORECASE)
_PADDING = "_"
# Internal names of a packed colour field and of the channels unpacked from it.
_PACKED_KEY = "__packed_rgb__"
_UNPACKED = ("__red__", "__green__", "__blue__")


@dataclass(frozen=True)
class _Field:
    name: str
    code: str  # NumPy type code without byte order ("f4")
    count: int

    @property
    def nbytes(self) -> int:
        return np.dtype(self.code).itemsize * self.count


@dataclass
class _Header:
    fields: list[_Field]
    width: int
    height: int
    points: int
    viewpoint: tuple[float, ...]
    data: str
    version: str
    data_offset: int
    lines: int  # lines in the header, DATA included

    @property
    def record(self) -> np.dtype:
        """Structured type of one binary record (padding left unnamed)."""
        names, formats, offsets, pos = [], [], [], 0
        for f in self.fields:
            if f.name != _PADDING:
                names.append(f.name)
                formats.append(("<" + f.code, (f.count,)) if f.count > 1 else "<" + f.code)
                offsets.append(pos)
            pos += f.nbytes
        return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": pos})


def _ints(path: Path, key: str, words: list[str], number: int) -> list[int]:
    try:
        values = [int(w) for w in words]
    except ValueError:
        values = [-1]
    if any(v < 0 for v in values):
        raise CorruptFileError(
            path,
            f"header line {number}: {key} should hold whole numbers "
            f">= 0, found {' '.join(words)!r}",
        )
    return values


def _read_header(path: Path) -> _Header:
    try:
        with open(path, "rb") as fh:
            head = fh.read(HEADER_MAX_BYTES)
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    if not head:
        raise CorruptFileError(path, "is empty")
    match = _DATA_LINE.search(head)
    if match is None:
        raise CorruptFileError(path, "not a PCD file: no 'DATA' line ends the header")
    text = head[: match.start()].decode("latin-1")
    data = match.group(1).decode("latin-1").lower()
    if data not in ENCODINGS:
        raise CorruptFileError(
            path, f"unknown DATA {data!r} (expected ascii, binary or binary_compressed)"
        )
    entries: dict[str, tuple[list[str], int]] = {}
    lines = text.split("\n")
    for number, raw in enumerate(lines, start=1):
        words = raw.split()
        if not words or words[0].startswith("#"):
            continue
        key = words[0].upper()
        if key == "COLUMNS":  # spelling of FIELDS in files before version 0.6
            key = "FIELDS"
        if key not in (
            "VERSION",
            "FIELDS",
            "SIZE",
            "TYPE",
            "COUNT",
            "WIDTH",
            "HEIGHT",
            "VIEWPOINT",
            "POINTS",
        ):
            raise CorruptFileError(path, f"header line {number}: unknown keyword {words[0][:24]!r}")
        if key in entries:
            raise CorruptFileError(path, f"header line {number}: a second {key} line")
        entries[key] = (words[1:], number)
    if "FIELDS" not in entries:
        raise CorruptFileError(path, "the header has no FIELDS line")
    names, _ = entries["FIELDS"]
    if not names:
        raise CorruptFileError(path, "the FIELDS line names no field")
    nfields = len(names)

    def per_field(key: str, default: str | None) -> tuple[list[str], int]:
        if key not in entries:
            if default is None:
                raise CorruptFileError(path, f"the header has no {key} line")
            return [default] * nfields, 0
        words, number = entries[key]
        if len(words) != nfields:
            raise CorruptFileError(
                path,
                f"header line {number}: {key} has {len(words)} entries but FIELDS names "
                f"{nfields} fields",
            )
        return words, number

    sizes_w, sizes_line = per_field("SIZE", None)
    types, _ = per_field("TYPE", None)
    counts_w, counts_line = per_field("COUNT", "1")
    sizes = _ints(path, "SIZE", sizes_w, sizes_line)
    counts = _ints(path, "COUNT", counts_w, counts_line)
    fields = []
    seen: set[str] = set()
    for name, size, kind, count in zip(names, sizes, types, counts):
        code = _TYPES.get((kind.upper(), size))
        if code is None:
            raise CorruptFileError(
                path,
                f"field {name!r} has TYPE {kind!r} with SIZE {size}, which is not a PCD "
                "type (F 4/8, I or U 1/2/4/8)",
            )
        if count < 1:
            raise CorruptFileError(path, f"field {name!r} has COUNT {count}; expected >= 1")
        if name != _PADDING:
            if name in seen:
                raise CorruptFileError(path, f"field {name!r} appears twice in FIELDS")
            seen.add(name)
        fields.append(_Field(name, code, count))

    points_w = entries.get("POINTS", ([], 0))
    width_w = entries.get("WIDTH", ([], 0))
    height_w = entries.get("HEIGHT", (["1"], 0))
    for key, (words, number) in (("WIDTH", width_w), ("HEIGHT", height_w), ("POINTS", points_w)):
        if (words or key in entries) and len(words) != 1:
            raise CorruptFileError(path, f"header line {number}: {key} should be one number")
    if not points_w[0] and not width_w[0]:
        raise CorruptFileError(path, "the header has neither WIDTH nor POINTS")
    height = _ints(path, "HEIGHT", height_w[0], height_w[1])[0]
    points = _ints(path, "POINTS", points_w[0], points_w[1])[0] if points_w[0] else None
    width = _ints(path, "WIDTH", width_w[0], width_w[1])[0] if width_w[0] else None
    if width is None:
        width, height = points, 1
    if points is None:
        points = width * height
    if points != width * height:
        raise CorruptFileError(
            path,
            f"POINTS {points} disagrees with WIDTH x HEIGHT = {width} x {height} = "
            f"{width * height}",
        )
    viewpoint = DEFAULT_VIEWPOINT
    if "VIEWPOINT" in entries:
        words, number = entries["VIEWPOINT"]
        try:
            viewpoint = tuple(float(w) for w in words)
        except ValueError:
            viewpoint = ()
        if len(viewpoint) != 7:
            raise CorruptFileError(
                path, f"header line {number}: VIEWPOINT should be 7 numbers (tx ty tz qw qx qy qz)"
            )
    version = " ".join(entries.get("VERSION", (["0.7"], 0))[0])
    return _Header(
        fields, width, height, points, viewpoint, data, version, match.end(), text.count("\n") + 2
    )


def _plan(path: Path, header: _Header) -> ColumnPlan:
    names = [f.name for f in header.fields if f.name != _PADDING and f.name.lower() not in _PACKED]
    plan = plan_columns(names)
    if plan.xyz is None:
        missing = [c for c in "xyz" if c not in {n.lower() for n in names}]
        raise CorruptFileError(
            path,
            f"has no {'/'.join(missing)} field (FIELDS {' '.join(f.name for f in header.fields)})",
        )
    counts = {f.name: f.count for f in header.fields}
    for name in (*plan.xyz, *(plan.rgb or ()), *(plan.normals or ())):
        if counts[name] != 1:
            raise CorruptFileError(path, f"field {name!r} has COUNT {counts[name]}; expected 1")
    return plan


def _packed_field(path: Path, header: _Header, plan: ColumnPlan) -> _Field | None:
    """The packed colour field, unless the file has separate colour channels."""
    if plan.rgb is not None:
        return None
    packed = next((f for f in header.fields if f.name.lower() in _PACKED), None)
    if packed is not None and (packed.count != 1 or np.dtype(packed.code).itemsize != 4):
        raise CorruptFileError(
            path,
            f"field {packed.name!r} should be one 4-byte packed colour "
            f"(TYPE F or U, SIZE 4, COUNT 1)",
        )
    return packed


def _unpack_rgb(packed: NDArray[Any]) -> NDArray[np.uint8]:
    """(n,) uint32 ``0xAARRGGBB`` (or the same bits as float32) -> (n, 3) uint8 r, g, b."""
    little = np.ascontiguousarray(packed).view("<u4")
    return little.view(np.uint8).reshape(-1, 4)[:, 2::-1].copy()


def _meta(header: _Header) -> dict[str, Any]:
    return {
        "width": header.width,
        "height": header.height,
        "organized": header.height > 1,
        "viewpoint": list(header.viewpoint),
        "pcd_data": header.data,
        "pcd_version": header.version,
    }


def _freeze(a: NDArray[Any]) -> NDArray[Any]:
    a.flags.writeable = False
    return a


def _read_binary(
    path: Path, header: _Header, plan: ColumnPlan, packed: _Field | None, on_nonfinite: str
) -> PointCloud:
    record = header.record
    need = header.points * record.itemsize
    size = file_size(path)
    if header.data_offset + need > size:
        raise CorruptFileError(
            path,
            f"truncated: {header.points} points of {record.itemsize} bytes need {need} "
            f"bytes of data, the file holds {max(size - header.data_offset, 0)}",
        )
    check_points(path, header.points, "the header")
    if packed is None:
        return cloud_from_records(
            path, plan, header.data_offset, record, header.points, _meta(header), on_nonfinite
        )
    # The packed colour rides along as a uint32 field and is unpacked afterwards.
    packed_name = _PACKED_KEY
    names = list(record.names)
    formats = [record.fields[n][0] for n in names]
    offsets = [record.fields[n][1] for n in names]
    names[names.index(packed.name)] = packed_name
    formats[names.index(packed_name)] = np.dtype("<u4")
    record = np.dtype(
        {"names": names, "formats": formats, "offsets": offsets, "itemsize": record.itemsize}
    )
    fields = dict(plan.fields)
    fields[packed_name] = packed_name
    with_packed = ColumnPlan(plan.xyz, None, plan.normals, fields, plan.ignored)
    cloud = cloud_from_records(
        path, with_packed, header.data_offset, record, header.points, _meta(header), on_nonfinite
    )
    colors = _unpack_rgb(cloud.fields[packed_name])
    rest = {k: v for k, v in cloud.fields.items() if k != packed_name}
    return PointCloud(
        cloud.xyz, _freeze(colors), cloud.normals, MappingProxyType(rest), cloud._index, cloud.meta
    )


def _read_compressed(
    path: Path, header: _Header, plan: ColumnPlan, packed: _Field | None, on_nonfinite: str
) -> PointCloud:
    try:
        with open(path, "rb") as fh:
            fh.seek(header.data_offset)
            sizes = fh.read(8)
            present = fh.seek(0, 2) - header.data_offset - 8
            fh.seek(header.data_offset + 8)
            if len(sizes) < 8:
                raise CorruptFileError(path, "truncated: the compressed data sizes are missing")
            compressed, expanded = struct.unpack("<II", sizes)
            expected = header.points * sum(f.nbytes for f in header.fields)
            if expanded != expected:
                raise CorruptFileError(
                    path,
                    f"binary_compressed data expands to {expanded} bytes, but "
                    f"{header.points} points of the declared fields need {expected}",
                )
            if expanded > max(compressed, 1) * LZF_MAX_RATIO:
                raise CorruptFileError(
                    path,
                    f"binary_compressed sizes are implausible "
                    f"({compressed} bytes claimed to expand to {expanded})",
                )
            if compressed > present:
                # Checked before reading: a read of the declared size allocates it first.
                raise CorruptFileError(
                    path,
                    f"truncated: {compressed} bytes of compressed data declared, "
                    f"{max(present, 0)} present",
                )
            check_points(path, header.points, "the header")
            check_bytes(path, expanded, "the binary_compressed data")
            data = fh.read(compressed)
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    if len(data) < compressed:
        raise CorruptFileError(
            path, f"truncated: {compressed} bytes of compressed data declared, {len(data)} present"
        )
    with progress(f"Decompressing {path.name}", total=None):
        try:
            raw = lzf.decompress(data, expanded) if expanded else b""
        except ValueError as exc:
            raise CorruptFileError(path, f"the LZF-compressed data is damaged ({exc})") from exc
    if raw is None or len(raw) != expanded:
        raise CorruptFileError(
            path,
            f"the LZF-compressed data is damaged (it expands to "
            f"{0 if raw is None else len(raw)} bytes instead of {expanded})",
        )
    n = header.points
    arrays: dict[str, NDArray[Any]] = {}
    pos = 0
    for f in header.fields:
        if f.name != _PADDING:
            kind = np.dtype("<" + f.code)
            arr = np.frombuffer(raw, kind, n * f.count, pos)
            arrays[f.name] = arr.reshape(n, f.count) if f.count > 1 else arr
        pos += n * f.nbytes
    return _from_arrays(path, header, plan, packed, arrays, on_nonfinite)


def _from_arrays(
    path: Path,
    header: _Header,
    plan: ColumnPlan,
    packed: _Field | None,
    arrays: dict[str, NDArray[Any]],
    on_nonfinite: str,
) -> PointCloud:
    """Cloud from whole per-field arrays (ascii and binary_compressed data)."""
    if packed is not None:
        rgb = _unpack_rgb(arrays.pop(packed.name))
        arrays.update({key: rgb[:, i] for i, key in enumerate(_UNPACKED)})
        plan = ColumnPlan(plan.xyz, _UNPACKED, plan.normals, plan.fields, plan.ignored)
    return cloud_from_columns(path, plan, arrays, _meta(header), on_nonfinite)


def _ascii_packed(values: NDArray[np.float64]) -> NDArray[np.uint32]:
    """Packed colours read from text, written either as integers or as float bits.

    PCL writes a float ``rgb`` field in ASCII files as the integer ``0xAARRGGBB``
    (an opaque colour's float bits are NaN); other writers print the float. A
    genuine packed float is tiny (below 1e-30 unless alpha is set), so values
    that are whole numbers of at least 1 are taken as integers.
    """
    finite = np.isfinite(values)
    clean = np.where(finite, values, 0.0)
    whole = np.all(clean == np.round(clean)) and clean.min(initial=0) >= 0
    if whole and clean.max(initial=0) >= 1 and clean.max(initial=0) <= 2**32 - 1:
        return clean.astype(np.uint32)
    with np.errstate(over="ignore", under="ignore"):
        return clean.astype(np.float32).view(np.uint32)


def _read_ascii(
    path: Path, header: _Header, plan: ColumnPlan, packed: _Field | None, on_nonfinite: str
) -> PointCloud:
    try:
        with open(path, "rb") as fh:
            fh.seek(header.data_offset)
            body = fh.read()
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    n = header.points
    if n * 2 > len(body) + 2:
        raise CorruptFileError(
            path,
            f"truncated: {n} points declared but only {len(body)} bytes of text follow the header",
        )
    lines = [line for line in body.splitlines() if line.strip()][:n]
    if len(lines) < n:
        raise CorruptFileError(
            path, f"truncated: {n} points declared, {len(lines)} lines of data present"
        )
    ncols = sum(f.count for f in header.fields)
    first = header.lines + 1
    table = ascii_table(path, lines, ncols, first, "a point line")
    arrays: dict[str, NDArray[Any]] = {}
    col = 0
    for f in header.fields:
        tokens = table[:, col : col + f.count]
        col += f.count
        if f.name == _PADDING:
            continue
        what = f"field {f.name!r}"
        if packed is not None and f.name == packed.name:
            arrays[f.name] = _ascii_packed(
                parse_column(path, tokens[:, 0], np.float64, what, first)
            )
            continue
        parts = [
            parse_column(path, tokens[:, j], np.dtype(f.code), what, first) for j in range(f.count)
        ]
        arrays[f.name] = parts[0] if f.count == 1 else np.stack(parts, axis=1)
    return _from_arrays(path, header, plan, packed, arrays, on_nonfinite)


def read_pcd(path: Path, *, on_nonfinite: str | None = None) -> PointCloud:
    """Read a PCL ``.pcd`` file (ascii, binary or binary_compressed).

    Parameters
    ----------
    path : Path
        The file.
    on_nonfinite : {"warn", "drop", "raise"}, optional
        What to do with points whose coordinates are NaN or infinite. By default
        they are dropped silently in organized clouds (``HEIGHT > 1``, where NaN
        marks missing depth) and dropped with a
        :class:`~ontodetect.cloud.DataWarning` otherwise. ``index`` keeps the
        row-major grid position of every point kept.

    Returns
    -------
    PointCloud
        ``meta`` holds ``width``, ``height``, ``organized``, ``viewpoint``
        (tx ty tz qw qx qy qz), ``pcd_data`` and ``pcd_version``.

    Raises
    ------
    CorruptFileError
        A header that breaks the format, POINTS that disagree with WIDTH x
        HEIGHT, less data than declared, damaged compressed data, no points.
    ReadError
        The file cannot be opened.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "grid.pcd"
    >>> _ = f.write_text("VERSION .7\\nFIELDS x y z\\nSIZE 4 4 4\\nTYPE F F F\\nCOUNT 1 1 1\\n"
    ...     "WIDTH 2\\nHEIGHT 2\\nPOINTS 4\\nDATA ascii\\n"
    ...     "0 0 1\\nnan nan nan\\n1 1 1\\n0 1 1\\n")
    >>> c = read_pcd(f)
    >>> c.index.tolist(), c.meta["organized"]
    ([0, 2, 3], True)
    """
    path = Path(path)
    header = _read_header(path)
    if on_nonfinite is None:
        on_nonfinite = "drop" if header.height > 1 else "warn"
    check_on_nonfinite(on_nonfinite)
    if header.points == 0:
        raise CorruptFileError(path, "contains no points (POINTS 0)")
    plan = _plan(path, header)
    packed = _packed_field(path, header, plan)
    if header.data == "ascii":
        return _read_ascii(path, header, plan, packed, on_nonfinite)
    if header.data == "binary":
        return _read_binary(path, header, plan, packed, on_nonfinite)
    return _read_compressed(path, header, plan, packed, on_nonfinite)


# ---------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------
def _pack_rgb(rgb: NDArray[np.uint8]) -> NDArray[np.float32]:
    """(n, 3) uint8 -> (n,) float32 carrying ``0x00RRGGBB`` (PCL's packed ``rgb``).

    Alpha is left 0, so every packed value is a small finite float that no tool
    mistakes for a missing value.
    """
    rgb = rgb.astype(np.uint32)
    packed = (rgb[:, 0] << 16) | (rgb[:, 1] << 8) | rgb[:, 2]
    return packed.astype("<u4").view("<f4")


def _coordinate_type(path: Path, cloud: PointCloud, dtype: Any) -> np.dtype:
    """Little-endian type of coordinates and normals: ``dtype``, or when it is None,
    float32 unless that loses more than :data:`~ontodetect.io._ply.FLOAT32_TOLERANCE`."""
    if dtype is None:
        arrays = [cloud.xyz] if cloud.normals is None else [cloud.xyz, cloud.normals]
        return storage_dtype(np.float32, *arrays)
    kind = coordinate_dtype(dtype).newbyteorder("<")
    if kind.itemsize == 4:
        check_float32_range(path, "xyz", cloud.xyz)
        if cloud.normals is not None:
            check_float32_range(path, "normals", cloud.normals)
    return kind


def _grid(cloud: PointCloud) -> tuple[int, int, NDArray[np.int64] | None]:
    """WIDTH, HEIGHT and, when points must move to their pixels, the pixel of each.

    A frame whose points each have a pixel of their own (:func:`pixel_grid`; a frame
    read from an organized PCD lost its NaN pixels) goes back on its grid. Else a
    ``meta`` grid that the points fill exactly is kept as it is; anything else (a
    grid that no longer fits the points, or a frame whose pixels are unknown:
    :func:`_pixels_lost`) is written unorganized.
    """
    grid = None if _pixels_lost(cloud) else pixel_grid(cloud)
    if grid is not None:
        pixels, width, height = grid
        if np.bincount(pixels, minlength=width * height).max() == 1:
            full = len(pixels) == width * height and bool(np.all(np.diff(pixels) == 1))
            return width, height, None if full else pixels
    width, height = cloud.meta.get("width"), cloud.meta.get("height")
    if (
        isinstance(width, int)
        and isinstance(height, int)
        and height > 1
        and width * height == len(cloud)
    ):
        return width, height, None
    return len(cloud), 1, None


def _pixels_lost(cloud: PointCloud) -> bool:
    """True when a frame's pixels would be read from an index that does not hold them.

    An organized frame without a ``pixel`` field keeps each point's pixel in its index.
    A cloud built again from part of a frame without its index
    (``point_cloud(frame.xyz[keep], meta=frame.meta)``) numbers its points 0, 1, 2...:
    those are not its pixels, and writing them as pixels would move its points. An index
    0..n-1 over fewer points than the grid has pixels is taken as such a numbering; a
    frame read from a file has it only when every pixel without depth is at the end of
    the grid, and then it is written unorganized, with every point, all the same.
    """
    if "pixel" in cloud.fields or not cloud.is_complete:
        return False
    width, height = cloud.meta.get("width"), cloud.meta.get("height")
    return not (
        isinstance(width, (int, np.integer))
        and isinstance(height, (int, np.integer))
        and int(width) * int(height) == len(cloud)
    )


def _on_grid(values: NDArray[Any], pixels: NDArray[np.int64], size: int, fill: Any) -> NDArray[Any]:
    """(size, ...) array with ``values`` at rows ``pixels`` and ``fill`` elsewhere."""
    out = np.full((size, *values.shape[1:]), fill, dtype=values.dtype)
    out[pixels] = values
    return out


def _viewpoint(cloud: PointCloud) -> tuple[float, ...]:
    view = cloud.meta.get("viewpoint")
    try:
        values = tuple(float(v) for v in view)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        return DEFAULT_VIEWPOINT
    return values if len(values) == 7 and all(np.isfinite(values)) else DEFAULT_VIEWPOINT


def _write_compressed(path: Path, fh: IO[bytes], columns: list[Column]) -> None:
    # Column-major: every field's (n, count) values in turn.
    raw = b"".join(
        np.ascontiguousarray(values, dtype=kind).tobytes() for _, kind, values in columns
    )
    if len(raw) > LZF_MAX_BYTES:
        raise WriteError(
            path,
            f"{len(raw)} bytes of data exceed the 4 GiB binary_compressed "
            "limit; write with data='binary'",
        )
    with progress(f"Compressing {path.name}", total=None):
        # LZF adds at most one byte per 32 literals; this margin always suffices.
        packed = lzf.compress(raw, len(raw) + len(raw) // 32 + 16) if raw else b""
    if packed is None:
        raise WriteError(path, "LZF compression failed")
    fh.write(struct.pack("<II", len(packed), len(raw)))
    fh.write(packed)


def write_pcd(path: Path, cloud: PointCloud, *, data: str = "binary", dtype: Any = None) -> Path:
    """Write a cloud as a PCL ``.pcd`` file, atomically.

    Parameters
    ----------
    path : Path
        Target file.
    cloud : PointCloud
        Points; colours are written as PCL's packed float ``rgb`` (alpha 0);
        normals as ``normal_x normal_y normal_z``; every field with its own type,
        an (n, k) field as one field with ``COUNT k`` (so an (n, 1) field reads
        back as (n,)). An organized frame (:func:`~ontodetect.cloud.pixel_grid`,
        each point on a pixel of its own) is written on its ``width`` x
        ``height`` grid in pixel order, with NaN coordinates and normals, zero
        colours and fields where a pixel has no point, and its ``viewpoint``;
        so is a cloud whose ``meta`` grid (height > 1) matches its size. A frame
        whose points no longer know their pixels (rebuilt without its ``index``
        from part of a frame) is written unorganized, never on wrong pixels.
    data : {"binary", "ascii", "binary_compressed"}
        Encoding of the points.
    dtype : {"float32", "float64"}, optional
        Type of coordinates and normals. By default float32, as in PCL's point
        types, unless that would move a value by more than
        :data:`~ontodetect.io._ply.FLOAT32_TOLERANCE` (coordinates far from the
        origin), in which case float64, which keeps them exactly.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    WriteError
        The folder is missing or not writable, or a field cannot be stored.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from ontodetect import point_cloud
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.pcd"
    >>> c = point_cloud([[0, 0, 0], [1, 2, 3]], rgb=[[255, 0, 0], [0, 0, 255]])
    >>> read_pcd(write_pcd(f, c, data="binary_compressed")).rgb.tolist()
    [[255, 0, 0], [0, 0, 255]]
    """
    path = Path(path)
    if not isinstance(cloud, PointCloud):
        raise WriteError(path, f"expected a PointCloud, got {type(cloud).__name__}")
    if data not in ENCODINGS:
        raise InvalidParameterError("data", "one of 'ascii', 'binary', 'binary_compressed'", data)
    kind = _coordinate_type(path, cloud, dtype)
    width, height, pixels = _grid(cloud)
    xyz, rgb, normals, fields = cloud.xyz, cloud.rgb, cloud.normals, dict(cloud.fields)
    if pixels is not None:
        # Missing pixels as PCL stores them: NaN points (readers drop them).
        size = width * height
        xyz = _on_grid(xyz, pixels, size, np.nan)
        rgb = None if rgb is None else _on_grid(rgb, pixels, size, 0)
        normals = None if normals is None else _on_grid(normals, pixels, size, np.nan)
        fields = {name: _on_grid(np.asarray(v), pixels, size, 0) for name, v in fields.items()}
    columns: list[Column] = [(c, kind, xyz[:, i]) for i, c in enumerate("xyz")]
    if rgb is not None:
        columns.append(("rgb", np.dtype("<f4"), _pack_rgb(rgb)))
    if normals is not None:
        columns += [
            (c, kind, normals[:, i]) for i, c in enumerate(("normal_x", "normal_y", "normal_z"))
        ]
    columns += field_columns(
        path, fields, allow_64bit=True, split=False, taken=[name for name, _, _ in columns]
    )
    n = width * height
    types = [_CODES[k.str[1:]] for _, k, _ in columns]
    header = "\n".join(
        [
            "# .PCD v0.7 - Point Cloud Data file format",
            "VERSION 0.7",
            "FIELDS " + " ".join(name for name, _, _ in columns),
            "SIZE " + " ".join(str(size) for _, size in types),
            "TYPE " + " ".join(t for t, _ in types),
            "COUNT " + " ".join(str(v.shape[1] if v.ndim == 2 else 1) for _, _, v in columns),
            f"WIDTH {width}",
            f"HEIGHT {height}",
            "VIEWPOINT " + " ".join(f"{v:.17g}" for v in _viewpoint(cloud)),
            f"POINTS {n}",
            f"DATA {data}\n",
        ]
    ).encode("ascii")
    label = f"Writing {path.name}"

    def write(fh: IO[bytes]) -> None:
        fh.write(header)
        if data == "binary":
            write_rows(fh, columns, n, label)
        elif data == "ascii":
            # Like PCL, print the packed colour as the integer it holds: opaque
            # colours read as float are NaN.
            text = [
                (name, np.dtype("<u4"), values.view("<u4"))
                if name == "rgb"
                else (name, kind, values)
                for name, kind, values in columns
            ]
            write_ascii_rows(fh, text, n, label)
        else:
            _write_compressed(path, fh, columns)

    return write_atomically(path, write)
