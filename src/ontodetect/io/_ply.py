"""Stanford PLY (polygon file format): reader and writer.

The reader understands the three encodings of the format (``ascii``,
``binary_little_endian``, ``binary_big_endian``) and every numeric property
type. The ``vertex`` element gives the points: ``x y z`` (any numeric type, any
order), colours (``red green blue``, ``r g b`` or ``diffuse_red ...``; uchar
0..255, 16-bit, or floats 0..1), normals (``nx ny nz``) and every other scalar
property as a named field (``label``, ``instance``, ``intensity``,
``scalar_*``...), each keeping its own type. Alpha is ignored. Faces and any
other element, list properties included, are skipped: a mesh's vertices are its
points.

Binary vertex data is decoded chunk by chunk through a small cache-resident
buffer straight into the final arrays (float64 coordinates, uint8 colours), on
two threads for large files (:mod:`._chunks`): the file's bytes are never held in
memory a second time.

The helpers here (named-column planning, chunked record decoding, ASCII token
tables, cloud assembly) are shared with the PCD and NumPy readers.
"""

from __future__ import annotations

import mmap
import os
import re
import struct
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import IO, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._progress import progress
from .._rules import ON_NONFINITE, check_param
from ..cloud import RESERVED_FIELDS, PointCloud, point_cloud
from ..errors import CorruptFileError, InvalidParameterError, ReadError, WriteError
from ._atomic import atomic_write
from ._chunks import Copy, Span, read_records

__all__ = ["read_ply", "write_mesh_ply", "write_ply"]

#: Longest header accepted; a file without ``end_header`` this far in is not PLY.
HEADER_MAX_BYTES = 1 << 20
#: Bytes read at a time while looking for the end of a header.
HEADER_CHUNK_BYTES = 1 << 16
#: Rows encoded per write call.
WRITE_CHUNK_ROWS = 1 << 20
#: Characters of an offending value quoted in error messages.
QUOTE_CHARS = 24

#: Largest finite float32, as a Python float (comparisons stay in float64).
FLOAT32_MAX = float(np.finfo(np.float32).max)
#: Largest change (in the cloud's units, metres as a rule) that storing coordinates and
#: normals as float32 may make; beyond it the writers choose float64. Far below any
#: scan's noise, and above float32's rounding in a frame a few hundred metres across,
#: so room-scale clouds keep float32 while map coordinates (UTM: float32 steps of
#: 3 to 50 cm) keep every digit.
FLOAT32_TOLERANCE = 1e-5
#: Suffix given to a property whose name the cloud reserves for itself.
RENAMED_SUFFIX = "_field"


# PLY type names (both spellings) -> NumPy type codes without byte order.
_PLY_TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}
# NumPy type codes -> the PLY name written for them.
_PLY_NAMES = {
    "i1": "char",
    "u1": "uchar",
    "i2": "short",
    "u2": "ushort",
    "i4": "int",
    "u4": "uint",
    "f4": "float",
    "f8": "double",
}
# NumPy type codes -> struct format characters (for the row-by-row path).
_STRUCT = {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I", "f4": "f", "f8": "d"}
_ENCODINGS = {"ascii": "", "binary_little_endian": "<", "binary_big_endian": ">"}

_COLOR_NAMES = (
    ("red", "green", "blue"),
    ("r", "g", "b"),
    ("diffuse_red", "diffuse_green", "diffuse_blue"),
)
_NORMAL_NAMES = (("nx", "ny", "nz"), ("normal_x", "normal_y", "normal_z"))
_ALPHA_NAMES = frozenset({"alpha", "a", "diffuse_alpha"})

_END_HEADER = re.compile(rb"\nend_header[ \t]*\r?\n")


# ---------------------------------------------------------------------------------
# Helpers shared with the PCD and NumPy readers
# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class ColumnPlan:
    """Which named columns of a file become coordinates, colours, normals and fields."""

    xyz: tuple[str, str, str] | None
    rgb: tuple[str, str, str] | None
    normals: tuple[str, str, str] | None
    #: source column name -> field name in the cloud
    fields: Mapping[str, str]
    ignored: tuple[str, ...] = ()


def plan_columns(
    names: Sequence[str],
    color_groups: Sequence[tuple[str, str, str]] = _COLOR_NAMES,
    normal_groups: Sequence[tuple[str, str, str]] = _NORMAL_NAMES,
) -> ColumnPlan:
    """Sort named per-point columns into coordinates, colours, normals and fields.

    Names match case-insensitively. A column whose name the cloud reserves
    (``index``, or ``red`` without ``green`` and ``blue``) is kept as a field with
    the suffix ``_field``. Alpha is dropped when colours were found.

    Examples
    --------
    >>> p = plan_columns(["x", "y", "z", "red", "green", "blue", "alpha", "label"])
    >>> p.rgb, dict(p.fields), p.ignored
    (('red', 'green', 'blue'), {'label': 'label'}, ('alpha',))
    """
    lower: dict[str, str] = {}
    for name in names:
        lower.setdefault(name.lower(), name)

    def pick(groups: Sequence[tuple[str, str, str]]) -> tuple[str, str, str] | None:
        for group in groups:
            if all(key in lower for key in group):
                return (lower[group[0]], lower[group[1]], lower[group[2]])
        return None

    xyz = pick([("x", "y", "z")])
    rgb = pick(color_groups)
    normals = pick(normal_groups)
    used = set(xyz or ()) | set(rgb or ()) | set(normals or ())
    ignored = tuple(n for n in names if rgb is not None and n.lower() in _ALPHA_NAMES)
    taken = set(names)
    fields: dict[str, str] = {}
    for name in names:
        if name in used or name in ignored:
            continue
        dest = name
        if dest in RESERVED_FIELDS:
            dest = name + RENAMED_SUFFIX
            while dest in taken:
                dest += "_"
            taken.add(dest)
        fields[name] = dest
    return ColumnPlan(xyz, rgb, normals, MappingProxyType(fields), ignored)


def check_on_nonfinite(value: str) -> str:
    """Validate the ``on_nonfinite`` reader option."""
    return check_param("on_nonfinite", ON_NONFINITE, value)


def _frozen(a: NDArray[Any]) -> NDArray[Any]:
    a.flags.writeable = False
    return a


def assemble_cloud(
    path: Path,
    xyz: NDArray[np.float64],
    *,
    rgb: NDArray[Any] | None = None,
    normals: NDArray[np.float64] | None = None,
    fields: Mapping[str, NDArray[Any]] | None = None,
    index: NDArray[np.int64] | None = None,
    meta: Mapping[str, Any] | None = None,
    on_nonfinite: str = "warn",
    all_finite: bool | None = None,
) -> PointCloud:
    """Build a cloud from arrays a reader owns, without copying them.

    When every coordinate is finite and colours are already uint8, the arrays
    are frozen and wrapped as they are: the reader has already produced exactly
    what :func:`~ontodetect.cloud.point_cloud` would (float64 C-ordered
    coordinates, numeric fields of the right length, names the cloud does not
    reserve), and skipping its per-row finiteness test saves more time than the
    whole binary decode. uint8 colours are kept as they are, strided or not
    (the binary decoder gives the first three columns of an (n, 4) block). The
    row index is left for the cloud to build when first asked for (one more
    8-byte value a point). Anything else goes through ``point_cloud(copy=False)``,
    which drops non-finite points (keeping their file rows in ``index``) and
    converts colours. Problems with the content become :class:`CorruptFileError`.
    """
    n = xyz.shape[0]
    meta = {"source": str(path), **(meta or {})}
    fields = dict(fields or {})
    if n == 0:
        raise CorruptFileError(path, "contains no points")
    if all_finite is None:
        all_finite = bool(np.isfinite(xyz).all())
    if not all_finite:
        bad = int(n - np.isfinite(xyz).all(axis=1).sum())
        if on_nonfinite == "raise":
            raise CorruptFileError(
                path,
                f"{bad} of {n} points have NaN or infinite coordinates (on_nonfinite='raise')",
            )
        if bad == n:  # refused here, before point_cloud warns that it dropped every point
            raise CorruptFileError(path, f"contains no points with finite coordinates (of {n})")
    fast = (
        all_finite
        and index is None
        and xyz.dtype == np.float64
        and xyz.flags.c_contiguous
        and (rgb is None or (rgb.dtype == np.uint8 and rgb.shape == (n, 3)))
        and (normals is None or normals.dtype == np.float64)
    )
    if fast:
        return PointCloud(
            xyz=_frozen(xyz),
            rgb=None if rgb is None else _frozen(rgb),
            normals=None if normals is None else _frozen(normals),
            fields=MappingProxyType({k: _frozen(v) for k, v in fields.items()}),
            index=None,  # every row kept: the cloud builds arange(n) only if asked
            meta=MappingProxyType(meta),
        )
    try:
        cloud = point_cloud(
            xyz,
            rgb=rgb,
            normals=normals,
            fields=fields,
            index=index,
            meta=meta,
            on_nonfinite=on_nonfinite,
            copy=False,
        )
    except InvalidParameterError as exc:
        raise CorruptFileError(path, f"invalid point data: {exc}") from exc
    if len(cloud) == 0:
        raise CorruptFileError(path, f"contains no points with finite coordinates (of {n})")
    return cloud


def _quote(token: bytes) -> str:
    text = token.decode("latin-1")
    if len(text) > QUOTE_CHARS:
        text = text[:QUOTE_CHARS] + "..."
    return repr(text)


def ascii_table(
    path: Path, lines: Sequence[bytes], ncols: int, first_line: int, what: str
) -> NDArray[np.bytes_]:
    """Split text lines of ``ncols`` numbers into an (n, ncols) table of tokens.

    ``first_line`` is the 1-based line number of ``lines[0]`` in the file, used
    in error messages.
    """
    tokens = b" ".join(lines).split()
    if len(tokens) != len(lines) * ncols:
        for i, line in enumerate(lines):
            found = len(line.split())
            if found != ncols:
                raise CorruptFileError(
                    path, f"line {first_line + i}: {what} needs {ncols} values, found {found}"
                )
    return np.array(tokens, dtype=np.bytes_).reshape(len(lines), ncols)


def parse_column(
    path: Path, tokens: NDArray[np.bytes_], dtype: np.dtype, what: str, first_line: int
) -> NDArray[Any]:
    """Parse a column of text tokens as ``dtype``, naming the line of a bad value."""
    dtype = np.dtype(dtype).newbyteorder("=")
    try:
        with np.errstate(over="ignore"):  # float32 overflow gives inf, caught as non-finite
            if dtype.kind == "f":
                return tokens.astype(np.float64).astype(dtype)
        info = np.iinfo(dtype)
        wide = np.uint64 if dtype.kind == "u" else np.int64
        try:
            values = tokens.astype(wide)
        except (ValueError, OverflowError):
            # Some writers print integers as "3.0"; accept them when they are whole.
            floats = tokens.astype(np.float64)
            if not (
                np.isfinite(floats).all()
                and np.all(floats == np.round(floats))
                and floats.min() >= info.min
                and floats.max() <= info.max
            ):
                raise ValueError("not an integer of the type") from None
            values = floats.astype(wide)
        if values.size and (values.min() < info.min or values.max() > info.max):
            raise ValueError("out of range")
        return values.astype(dtype)
    except (ValueError, OverflowError):
        pass
    for i, token in enumerate(tokens):
        try:
            value = float(token)
            ok = dtype.kind == "f" or (
                value == round(value) and np.iinfo(dtype).min <= value <= np.iinfo(dtype).max
            )
        except (ValueError, OverflowError):
            ok = False
        if not ok:
            kind = "a number" if dtype.kind == "f" else f"an integer fitting {dtype.name}"
            raise CorruptFileError(
                path, f"line {first_line + i}: {what} should be {kind}, found {_quote(token)}"
            )
    raise CorruptFileError(path, f"{what} holds values that cannot be read as {dtype.name}")


def _xyz_names(path: Path, plan: ColumnPlan) -> tuple[str, str, str]:
    if plan.xyz is None:
        raise CorruptFileError(path, "has no x, y and z columns")
    return plan.xyz


def _packed_colours(record: np.dtype, names: Sequence[str]) -> int | None:
    """Offset of the red byte when red, green and blue are consecutive uint8 fields."""
    fields = [record.fields[n] for n in names]
    start = fields[0][1]
    if all(f[0] == np.uint8 and f[1] == start + i for i, f in enumerate(fields)):
        return int(start)
    return None


def cloud_from_records(
    path: Path,
    plan: ColumnPlan,
    offset: int,
    record: np.dtype,
    count: int,
    meta: Mapping[str, Any],
    on_nonfinite: str,
    *,
    chunk_rows: int | None = None,
    threads: int | None = None,
) -> PointCloud:
    """Decode a block of binary records laid out by ``record`` into a cloud.

    ``chunk_rows`` and ``threads`` go to :func:`~ontodetect.io._chunks.read_records`
    (their defaults suit large files; tests pass tiny chunks).
    """
    xyz = np.empty((count, 3), dtype=np.float64)
    copies: list[Copy] = [(xyz, i, name) for i, name in enumerate(_xyz_names(path, plan))]
    rgb = normals = None
    if plan.rgb is not None:
        start = _packed_colours(record, plan.rgb)
        if start is not None:
            # One 4-byte copy a point instead of three 1-byte ones, which cost
            # nearly as much as casting the coordinates: the colours are the
            # first three columns of an (n, 4) block whose last one holds the
            # byte after blue (alpha, often).
            block = np.empty((count, 4), dtype=np.uint8)
            rgb = block[:, :3]
            copies.append((block.view("V4").reshape(count), None, Span(start, np.dtype("V4"))))
        else:
            kind = np.result_type(*(record[n].newbyteorder("=") for n in plan.rgb))
            rgb = np.empty((count, 3), dtype=kind)
            copies += [(rgb, i, name) for i, name in enumerate(plan.rgb)]
    if plan.normals is not None:
        normals = np.empty((count, 3), dtype=np.float64)
        copies += [(normals, i, name) for i, name in enumerate(plan.normals)]
    fields: dict[str, NDArray[Any]] = {}
    for src, dest in plan.fields.items():
        sub = record[src]
        base, shape = (sub.base, sub.shape) if sub.shape else (sub, ())
        fields[dest] = np.empty((count, *shape), dtype=base.newbyteorder("="))
        copies.append((fields[dest], None, src))
    finite = read_records(
        path, offset, record, count, copies, xyz, chunk_rows=chunk_rows, threads=threads
    )
    return assemble_cloud(
        path,
        xyz,
        rgb=rgb,
        normals=normals,
        fields=fields,
        meta=meta,
        on_nonfinite=on_nonfinite,
        all_finite=finite,
    )


def cloud_from_columns(
    path: Path,
    plan: ColumnPlan,
    columns: Mapping[str, NDArray[Any]],
    meta: Mapping[str, Any],
    on_nonfinite: str,
    index: NDArray[np.int64] | None = None,
) -> PointCloud:
    """Build a cloud from named 1-D (or (n, k)) columns."""

    def stack(names: tuple[str, str, str], dtype: Any = None) -> NDArray[Any]:
        cols = [columns[n] for n in names]
        kind = dtype or np.result_type(*(c.dtype.newbyteorder("=") for c in cols))
        out = np.empty((cols[0].shape[0], 3), dtype=kind)
        with np.errstate(invalid="ignore", over="ignore"):
            for i, c in enumerate(cols):
                out[:, i] = c
        return out

    xyz = stack(_xyz_names(path, plan), np.float64)
    rgb = None if plan.rgb is None else stack(plan.rgb)
    normals = None if plan.normals is None else stack(plan.normals, np.float64)
    fields = {}
    for src, dest in plan.fields.items():
        values = np.ascontiguousarray(columns[src], dtype=columns[src].dtype.newbyteorder("="))
        # A view would keep the whole file buffer it came from alive.
        fields[dest] = values if values.base is None else values.copy()
    return assemble_cloud(
        path,
        xyz,
        rgb=rgb,
        normals=normals,
        fields=fields,
        index=index,
        meta=meta,
        on_nonfinite=on_nonfinite,
    )


def file_size(path: Path) -> int:
    try:
        return os.stat(path).st_size
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc


# ---------------------------------------------------------------------------------
# PLY header
# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Property:
    name: str
    code: str  # NumPy type code without byte order ("f4")
    count_code: str | None = None  # list properties: type of the length prefix


@dataclass
class _Element:
    name: str
    count: int
    properties: list[_Property] = field(default_factory=list)

    @property
    def has_lists(self) -> bool:
        return any(p.count_code is not None for p in self.properties)

    def record(self, order: str, keep: Iterable[str] | None = None) -> np.dtype:
        """Structured type of one row (scalar properties only), optionally only ``keep``."""
        wanted = None if keep is None else set(keep)
        names, formats, offsets, pos = [], [], [], 0
        for p in self.properties:
            if wanted is None or p.name in wanted:
                names.append(p.name)
                formats.append(order + p.code)
                offsets.append(pos)
            pos += np.dtype(p.code).itemsize
        return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": pos})

    def min_row_bytes(self, ascii: bool) -> int:
        if ascii:  # one character and a separator per value
            return 2 * len(self.properties)
        return sum(np.dtype(p.count_code or p.code).itemsize for p in self.properties)


@dataclass
class _Header:
    encoding: str
    elements: list[_Element]
    comments: list[str]
    data_offset: int
    lines: int  # lines in the header, end_header included


def _read_header(path: Path) -> _Header:
    try:
        with open(path, "rb") as fh:
            head = b""
            match = None
            while len(head) < HEADER_MAX_BYTES:
                chunk = fh.read(HEADER_CHUNK_BYTES)
                if not chunk:
                    break
                # Look again only in the new bytes (plus an overlap for a split marker).
                start = max(0, len(head) - len("\nend_header\r\n"))
                head += chunk
                match = _END_HEADER.search(head, start)
                if match:
                    break
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    if not head:
        raise CorruptFileError(path, "is empty")
    if not (head.startswith(b"ply") and head[3:4] in (b"\n", b"\r")):
        raise CorruptFileError(path, "not a PLY file: it does not start with the line 'ply'")
    if match is None:
        stripped = head.rstrip(b" \t\r\n")
        if stripped.endswith(b"\nend_header"):
            start, end = len(stripped) - len(b"\nend_header"), len(head)
        elif len(head) >= HEADER_MAX_BYTES:
            raise CorruptFileError(
                path, f"no 'end_header' line within the first {HEADER_MAX_BYTES} bytes"
            )
        else:
            raise CorruptFileError(path, "the header has no 'end_header' line (truncated?)")
    else:
        start, end = match.start(), match.end()
    text = head[:start].decode("latin-1")

    encoding: str | None = None
    elements: list[_Element] = []
    comments: list[str] = []
    lines = text.split("\n")
    for number, raw in enumerate(lines[1:], start=2):
        words = raw.split()
        if not words:
            continue
        key = words[0]
        where = f"header line {number}"
        if key in ("comment", "obj_info"):
            comments.append(raw.strip()[len(key) :].strip())
        elif key == "format":
            if encoding is not None:
                raise CorruptFileError(path, f"{where}: a second 'format' line")
            if len(words) != 3 or words[1] not in _ENCODINGS:
                raise CorruptFileError(
                    path,
                    f"{where}: unknown format {' '.join(words[1:])!r} (expected 'ascii', "
                    "'binary_little_endian' or 'binary_big_endian' followed by a version)",
                )
            encoding = words[1]
        elif key == "element":
            if len(words) != 3:
                raise CorruptFileError(
                    path, f"{where}: expected 'element <name> <count>', found {raw.strip()!r}"
                )
            try:
                count = int(words[2])
            except ValueError:
                count = -1
            if count < 0:
                raise CorruptFileError(
                    path,
                    f"{where}: element {words[1]!r} count should be a whole number >= 0, "
                    f"found {words[2]!r}",
                )
            if any(e.name == words[1] for e in elements):
                raise CorruptFileError(path, f"{where}: element {words[1]!r} is declared twice")
            elements.append(_Element(words[1], count))
        elif key == "property":
            if not elements:
                raise CorruptFileError(path, f"{where}: 'property' before any 'element'")
            element = elements[-1]
            if len(words) == 5 and words[1] == "list":
                count_code, code = _PLY_TYPES.get(words[2]), _PLY_TYPES.get(words[3])
                name = words[4]
                if count_code is None or count_code[0] not in "iu" or code is None:
                    raise CorruptFileError(
                        path,
                        f"{where}: list property {name!r} has unknown or non-integer "
                        f"length type {words[2]!r} or unknown item type {words[3]!r}",
                    )
                prop = _Property(name, code, count_code)
            elif len(words) == 3 and words[1] in _PLY_TYPES:
                prop = _Property(words[2], _PLY_TYPES[words[1]])
            else:
                raise CorruptFileError(
                    path,
                    f"{where}: expected 'property <type> <name>' with a type among "
                    f"{', '.join(sorted(set(_PLY_TYPES)))}, found {raw.strip()!r}",
                )
            if any(p.name == prop.name for p in element.properties):
                raise CorruptFileError(
                    path,
                    f"{where}: property {prop.name!r} is declared twice "
                    f"in element {element.name!r}",
                )
            element.properties.append(prop)
        else:
            raise CorruptFileError(
                path, f"{where}: unknown header keyword {_quote(key.encode('latin-1'))}"
            )
    if encoding is None:
        raise CorruptFileError(path, "the header has no 'format' line")
    return _Header(encoding, elements, comments, end, len(lines) + 1)


# ---------------------------------------------------------------------------------
# PLY body
# ---------------------------------------------------------------------------------
def _walk_binary(
    path: Path, buf: Any, pos: int, element: _Element, order: str, collect: bool
) -> tuple[int, dict[str, list[Any]]]:
    """Step over the rows of an element with list properties, one row at a time.

    Returns the offset after the element and, with ``collect``, the values of its
    scalar properties. Used only when the fast uniform-length skip does not apply.
    """
    size = len(buf)
    fmts = [
        (
            p,
            struct.Struct(order + _STRUCT[p.code]),
            struct.Struct(order + _STRUCT[p.count_code or "u1"]),
        )
        for p in element.properties
    ]
    values: dict[str, list[Any]] = {p.name: [] for p in element.properties if p.count_code is None}
    item_sizes = {p.name: np.dtype(p.code).itemsize for p in element.properties}
    for row in range(element.count):
        for prop, scalar, length in fmts:
            if prop.count_code is None:
                if pos + scalar.size > size:
                    break
                if collect:
                    values[prop.name].append(scalar.unpack_from(buf, pos)[0])
                pos += scalar.size
            else:
                if pos + length.size > size:
                    break
                k = length.unpack_from(buf, pos)[0]
                if k < 0:
                    raise CorruptFileError(
                        path,
                        f"element {element.name!r} row {row}: list "
                        f"{prop.name!r} has negative length {k}",
                    )
                pos += length.size + k * item_sizes[prop.name]
        else:
            if pos <= size:
                continue
        raise CorruptFileError(
            path, f"ends inside element {element.name!r} (row {row} of {element.count})"
        )
    return pos, values


def _skip_binary(path: Path, buf: Any, pos: int, element: _Element, order: str) -> int:
    """Offset just after ``element``; vectorized when every list has the same length."""
    remaining = len(buf) - pos
    if element.count * element.min_row_bytes(ascii=False) > remaining:
        raise CorruptFileError(
            path,
            f"element {element.name!r} declares {element.count} rows, more than the "
            f"{remaining} bytes left can hold",
        )
    if not element.has_lists:
        return pos + element.count * element.record(order).itemsize
    lists = [p for p in element.properties if p.count_code is not None]
    if len(lists) == 1 and element.count:
        # Meshes store triangles (or quads) only: test that guess in one strided read.
        prop = lists[0]
        before = after = 0
        seen = False
        for p in element.properties:
            if p is prop:
                seen = True
            elif seen:
                after += np.dtype(p.code).itemsize
            else:
                before += np.dtype(p.code).itemsize
        length = np.dtype(order + prop.count_code)  # type: ignore[operator]
        first = int(np.frombuffer(buf, length, 1, pos + before)[0])
        row = before + length.itemsize + max(first, 0) * np.dtype(prop.code).itemsize + after
        if first >= 0 and element.count * row <= remaining:
            counts = np.ndarray((element.count,), length, buf, pos + before, (row,))
            uniform = bool((counts == first).all())
            del counts
            if uniform:
                return pos + element.count * row
    return _walk_binary(path, buf, pos, element, order, collect=False)[0]


def _plan_for(path: Path, vertex: _Element) -> ColumnPlan:
    scalars = [p.name for p in vertex.properties if p.count_code is None]
    plan = plan_columns(scalars)
    if plan.xyz is None:
        missing = [c for c in "xyz" if c not in {n.lower() for n in scalars}]
        lists = [p.name for p in vertex.properties if p.count_code is not None]
        listed = [name for name in lists if name.lower() in missing]
        if listed:
            what = "properties" if len(listed) > 1 else "property"
            raise CorruptFileError(
                path,
                f"element 'vertex': {what} {', '.join(map(repr, listed))} "
                f"{'are lists' if len(listed) > 1 else 'is a list'}, which is not supported "
                "for coordinates (x, y and z must be scalar properties)",
            )
        raise CorruptFileError(
            path,
            f"element 'vertex' has no {'/'.join(missing)} property (properties: "
            f"{', '.join(p.name for p in vertex.properties) or 'none'})",
        )
    return plan


def _read_binary(
    path: Path,
    header: _Header,
    vertex: _Element,
    plan: ColumnPlan,
    meta: dict[str, Any],
    on_nonfinite: str,
) -> PointCloud:
    order = _ENCODINGS[header.encoding]
    size = file_size(path)
    before = header.elements[: header.elements.index(vertex)]
    pos = header.data_offset
    if before or vertex.has_lists:
        # Elements ahead of the vertices (rare) are stepped over in a mapped view.
        try:
            with open(path, "rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as mm:
                for element in before:
                    pos = _skip_binary(path, mm, pos, element, order)
                if vertex.has_lists:
                    if vertex.count * vertex.min_row_bytes(ascii=False) > size - pos:
                        raise CorruptFileError(
                            path,
                            f"element 'vertex' declares {vertex.count} points, more than "
                            f"the {size - pos} bytes left can hold",
                        )
                    _, values = _walk_binary(path, mm, pos, vertex, order, collect=True)
                    columns = {
                        p.name: np.array(values[p.name], dtype=np.dtype(p.code))
                        for p in vertex.properties
                        if p.count_code is None
                    }
                    return cloud_from_columns(path, plan, columns, meta, on_nonfinite)
        except OSError as exc:
            raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    record = vertex.record(
        order, keep=[*(plan.xyz or ()), *(plan.rgb or ()), *(plan.normals or ()), *plan.fields]
    )
    need = vertex.count * record.itemsize
    if pos + need > size:
        raise CorruptFileError(
            path,
            f"truncated: the header declares {vertex.count} vertices ({need} bytes from "
            f"byte {pos}) but the file holds only {max(size - pos, 0)} bytes there",
        )
    return cloud_from_records(path, plan, pos, record, vertex.count, meta, on_nonfinite)


def _read_ascii(
    path: Path,
    header: _Header,
    vertex: _Element,
    plan: ColumnPlan,
    meta: dict[str, Any],
    on_nonfinite: str,
) -> PointCloud:
    try:
        with open(path, "rb") as fh:
            fh.seek(header.data_offset)
            body = fh.read()
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    skip = sum(e.count for e in header.elements[: header.elements.index(vertex)])
    if (skip + vertex.count) * 2 > len(body) + 2:
        raise CorruptFileError(
            path,
            f"truncated: the header declares {skip + vertex.count} lines of data "
            f"before the end of the vertices but only {len(body)} bytes follow it",
        )
    # Split only as far as the vertices: faces after them can be most of the file.
    parts = body.split(b"\n", skip + vertex.count)
    if len(parts) <= skip + vertex.count:  # the data ends within the needed lines
        while parts and not parts[-1].strip():
            parts.pop()
    lines = parts[skip : skip + vertex.count]
    first = header.lines + skip + 1
    if len(lines) < vertex.count:
        raise CorruptFileError(
            path,
            f"truncated: the header declares {vertex.count} vertices but the file holds "
            f"only {len(lines)} vertex lines",
        )
    scalars = [p for p in vertex.properties if p.count_code is None]
    if vertex.has_lists:
        lines = [_ascii_scalars(path, line, vertex, first + i) for i, line in enumerate(lines)]
    table = ascii_table(path, lines, len(scalars), first, "a vertex line")
    columns = {
        p.name: parse_column(
            path, table[:, i], np.dtype(p.code), f"vertex property {p.name!r}", first
        )
        for i, p in enumerate(scalars)
        if p.name in {*(plan.xyz or ()), *(plan.rgb or ()), *(plan.normals or ()), *plan.fields}
    }
    return cloud_from_columns(path, plan, columns, meta, on_nonfinite)


def _ascii_scalars(path: Path, line: bytes, element: _Element, number: int) -> bytes:
    """The scalar values of one ASCII row whose element has list properties."""
    words = line.split()
    out, pos = [], 0
    for prop in element.properties:
        if pos >= len(words):
            raise CorruptFileError(
                path, f"line {number}: too few values for element {element.name!r}"
            )
        if prop.count_code is None:
            out.append(words[pos])
            pos += 1
        else:
            try:
                k = int(words[pos])
            except ValueError:
                k = -1
            if k < 0:
                raise CorruptFileError(
                    path,
                    f"line {number}: list {prop.name!r} length should be "
                    f"a whole number, found {_quote(words[pos])}",
                )
            pos += 1 + k
    if pos != len(words):
        raise CorruptFileError(
            path, f"line {number}: {len(words)} values where element {element.name!r} needs {pos}"
        )
    return b" ".join(out)


def read_ply(path: Path, *, on_nonfinite: str = "warn") -> PointCloud:
    """Read the vertices of a PLY file (ascii or binary) as a point cloud.

    Parameters
    ----------
    path : Path
        The ``.ply`` file.
    on_nonfinite : {"warn", "drop", "raise"}
        Points with NaN or infinite coordinates are dropped with a
        :class:`~ontodetect.cloud.DataWarning` ("warn"), dropped silently
        ("drop") or refused ("raise"); dropped points keep their file rows in
        ``index``.

    Returns
    -------
    PointCloud
        ``xyz`` (n, 3) float64; ``rgb`` (n, 3) uint8 when the vertices have
        colours; ``normals`` when they have ``nx ny nz``; every other scalar
        vertex property as a field of its own type (``index`` becomes
        ``index_field``). ``meta`` holds ``ply_format``, ``comments`` (comment and
        obj_info lines) and ``faces`` (rows of the ``face`` element, when there is
        one).

    Raises
    ------
    CorruptFileError
        Not a PLY file, a header that breaks the format, no x/y/z, no points,
        fewer bytes or lines than the header declares, values that are not numbers.
    ReadError
        The file cannot be opened.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "tri.ply"
    >>> _ = f.write_text("ply\\nformat ascii 1.0\\nelement vertex 3\\nproperty float x\\n"
    ...     "property float y\\nproperty float z\\nproperty int label\\nelement face 1\\n"
    ...     "property list uchar int vertex_indices\\nend_header\\n"
    ...     "0 0 0 7\\n1 0 0 7\\n0 1 0 8\\n3 0 1 2\\n")
    >>> c = read_ply(f)
    >>> len(c), c.fields["label"].tolist(), c.meta["faces"]
    (3, [7, 7, 8], 1)
    """
    path = Path(path)
    check_on_nonfinite(on_nonfinite)
    header = _read_header(path)
    vertex = next((e for e in header.elements if e.name == "vertex"), None)
    if vertex is None:
        raise CorruptFileError(
            path,
            "has no 'vertex' element (elements: "
            f"{', '.join(e.name for e in header.elements) or 'none'})",
        )
    if vertex.count == 0:
        raise CorruptFileError(path, "contains no points (element vertex 0)")
    plan = _plan_for(path, vertex)
    meta: dict[str, Any] = {"ply_format": header.encoding, "comments": list(header.comments)}
    faces = next((e for e in header.elements if e.name == "face"), None)
    if faces is not None:
        meta["faces"] = faces.count
    if header.encoding == "ascii":
        return _read_ascii(path, header, vertex, plan, meta, on_nonfinite)
    return _read_binary(path, header, vertex, plan, meta, on_nonfinite)


# ---------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------
#: A column to write: name, stored type (little-endian), values.
Column = tuple[str, np.dtype, NDArray[Any]]

_TOKEN = re.compile(r"^[^\s\x00-\x1f\x7f]+$")


def coordinate_dtype(dtype: Any) -> np.dtype:
    """Validate the ``dtype`` writer option: float32 or float64."""
    try:
        kind = np.dtype(dtype)
    except TypeError:
        kind = None
    if kind not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise InvalidParameterError("dtype", "'float32' or 'float64'", dtype)
    return kind


def float32_keeps(values: NDArray[np.float64]) -> bool:
    """True when float32 stores every value within :data:`FLOAT32_TOLERANCE`.

    NaN and infinities count as kept (float32 holds them); a value beyond the
    float32 range becomes infinite, which does not.
    """
    for start in range(0, len(values), WRITE_CHUNK_ROWS):
        block = values[start : start + WRITE_CHUNK_ROWS]
        with np.errstate(over="ignore", invalid="ignore"):
            moved = np.abs(block.astype(np.float32).astype(np.float64) - block)
            if np.any(moved > FLOAT32_TOLERANCE):
                return False
    return True


def storage_dtype(dtype: Any, *arrays: NDArray[np.float64]) -> np.dtype:
    """Little-endian type that stores coordinate ``arrays`` as the ``dtype`` option asks:
    float64 as float64; float32 as float32 when that moves no value by more than
    :data:`FLOAT32_TOLERANCE`, else as float64 (map coordinates, which float32 would move
    by centimetres, and values beyond its range).

    Examples
    --------
    >>> storage_dtype("float32", np.array([1.5, 2.25])).str
    '<f4'
    >>> storage_dtype("float32", np.array([500000.123, 2.25])).str
    '<f8'
    """
    kind = coordinate_dtype(dtype)
    if kind.itemsize == 4 and not all(float32_keeps(a) for a in arrays):
        kind = np.dtype(np.float64)
    return kind.newbyteorder("<")


def check_float32_range(path: Path, name: str, values: NDArray[Any]) -> None:
    """Refuse to write values that float32 cannot hold instead of writing infinities."""
    top = float(np.abs(values).max()) if values.size else 0.0
    if top > FLOAT32_MAX:
        raise WriteError(
            path, f"{name} holds values up to {top:g}, beyond float32; write with dtype='float64'"
        )


def field_columns(
    path: Path,
    fields: Mapping[str, NDArray[Any]],
    allow_64bit: bool,
    taken: Iterable[str],
    split: bool = True,
) -> list[Column]:
    """The columns that store a cloud's extra fields, each with its own numeric type.

    With ``split``, a field of shape (n, k) becomes ``k`` columns ``name_0 ...
    name_{k-1}``; otherwise it stays one (n, k) column. Booleans are stored as
    uint8 and float16 as float32; without ``allow_64bit`` (PLY), 64-bit integers
    are stored as 32-bit when their values fit and refused otherwise.
    """
    used = set(taken)
    out: list[Column] = []
    for name, values in fields.items():
        if not _TOKEN.match(name):
            raise WriteError(path, f"field {name!r}: names must be non-empty and without spaces")
        arr = np.asarray(values)
        if arr.dtype == np.bool_:
            arr = arr.astype(np.uint8)
        elif arr.dtype == np.float16:
            arr = arr.astype(np.float32)
        elif arr.dtype.itemsize == 8 and arr.dtype.kind in "iu" and not allow_64bit:
            small = np.int32 if arr.dtype.kind == "i" else np.uint32
            info = np.iinfo(small)
            if arr.size and (arr.min() < info.min or arr.max() > info.max):
                raise WriteError(
                    path,
                    f"field {name!r} holds 64-bit integers outside the {info.dtype} range "
                    "that PLY can store",
                )
            arr = arr.astype(small)
        if arr.dtype.kind not in "iuf":
            raise WriteError(path, f"field {name!r} has type {arr.dtype}, which cannot be stored")
        if arr.ndim > 2 or (arr.ndim == 2 and arr.shape[1] == 0):
            raise WriteError(
                path,
                f"field {name!r} has shape {arr.shape}; only (n,) and (n, k) "
                "fields with k >= 1 can be stored",
            )
        if arr.ndim == 2 and split:
            parts = [(f"{name}_{j}", arr[:, j]) for j in range(arr.shape[1])]
        else:
            parts = [(name, arr)]
        for part, col in parts:
            if part in used:
                raise WriteError(
                    path, f"field {name!r} would be stored as {part!r}, a name already in use"
                )
            used.add(part)
            out.append((part, arr.dtype.newbyteorder("<"), col))
    return out


def _record(columns: Sequence[Column], order: str = "<") -> np.dtype:
    return np.dtype(
        [(name, kind.newbyteorder(order), values.shape[1:]) for name, kind, values in columns]
    )


def write_rows(fh: IO[bytes], columns: Sequence[Column], n: int, label: str) -> None:
    """Write ``n`` packed little-endian rows made of ``columns``, a block at a time."""
    record = _record(columns)
    with progress(label, total=n) as advance:
        for start in range(0, n, WRITE_CHUNK_ROWS):
            stop = min(start + WRITE_CHUNK_ROWS, n)
            rows = np.empty(stop - start, dtype=record)
            for name, _, values in columns:
                rows[name] = values[start:stop]
            fh.write(rows.view(np.uint8).data)
            advance(stop - start)


def ascii_format(kind: np.dtype) -> str:
    """printf format that reads back to the same value of type ``kind``."""
    if kind.kind == "f":
        # 9 and 17 significant digits are enough to recover any float32 / float64.
        return "%.9g" if kind.itemsize <= 4 else "%.17g"
    return "%d"


def write_ascii_rows(fh: IO[bytes], columns: Sequence[Column], n: int, label: str) -> None:
    """Write ``n`` rows of ``columns`` as text, one row per line."""
    columns = [
        (f"{name}\x00{j}", kind, values[:, j]) if values.ndim == 2 else (name, kind, values)
        for name, kind, values in columns
        for j in range(values.shape[1] if values.ndim == 2 else 1)
    ]
    record = _record(columns, "=")
    fmt = [ascii_format(kind) for _, kind, _ in columns]
    with progress(label, total=n) as advance:
        for start in range(0, n, WRITE_CHUNK_ROWS):
            stop = min(start + WRITE_CHUNK_ROWS, n)
            rows = np.empty(stop - start, dtype=record)
            for name, _, values in columns:
                rows[name] = values[start:stop]
            np.savetxt(fh, rows, fmt=fmt)
            advance(stop - start)


def write_atomically(path: Path, write: Callable[[IO[bytes]], None]) -> Path:
    """Run ``write(fh)`` on a temporary file that replaces ``path`` only on success."""
    try:
        with atomic_write(path, "wb") as fh:
            write(fh)
    except OSError as exc:
        raise WriteError(path, f"cannot write ({exc.strerror or exc})") from exc
    return path


def _header_start(path: Path, fmt: str, comments: Sequence[str]) -> list[str]:
    """The first lines of a PLY header written by ontodetect: magic, format, comments
    (each checked to be one line of ASCII text)."""
    for text in comments:
        if not isinstance(text, str) or any(c in text for c in "\r\n") or not text.isascii():
            raise WriteError(path, f"header comment {text!r}: expected one line of ASCII text")
    return [
        "ply",
        f"format {fmt} 1.0",
        "comment written by ontodetect",
        *(f"comment {text}" for text in comments),
    ]


def write_ply(
    path: Path,
    cloud: PointCloud,
    *,
    ascii: bool = False,
    dtype: Any = "float64",
    comments: Sequence[str] = (),
) -> Path:
    """Write a cloud as a PLY file (binary little-endian unless ``ascii``), atomically.

    Parameters
    ----------
    path : Path
        Target file.
    cloud : PointCloud
        Points, colours (as ``uchar red green blue``), normals (``nx ny nz``) and
        every field, each with its own type (``int label``, ``float score``...).
        64-bit integer fields are stored as 32-bit when their values fit (PLY has
        no 64-bit integers); (n, k) fields become ``name_0 ... name_{k-1}``.
    ascii : bool
        Write text instead of binary (for small files one wants to read).
    dtype : {"float64", "float32"}
        Type of the coordinates and normals. float32 is used only when it moves no
        value by more than :data:`FLOAT32_TOLERANCE`; coordinates far from the origin
        (map coordinates) are written as float64 all the same, which keeps them exactly.
    comments : sequence of str
        Header comment lines (one ``comment`` line each, after ``written by ontodetect``);
        a line may not hold a line break.

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
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.ply"
    >>> c = point_cloud([[0, 0, 0], [1, 2, 3]], fields={"label": np.array([5, 6], np.int32)})
    >>> read_ply(write_ply(f, c)).fields["label"].tolist()
    [5, 6]
    """
    path = Path(path)
    if not isinstance(cloud, PointCloud):
        raise WriteError(path, f"expected a PointCloud, got {type(cloud).__name__}")
    arrays = [cloud.xyz] if cloud.normals is None else [cloud.xyz, cloud.normals]
    kind = storage_dtype(dtype, *arrays)
    columns: list[Column] = [(c, kind, cloud.xyz[:, i]) for i, c in enumerate("xyz")]
    if cloud.rgb is not None:
        columns += [
            (c, np.dtype("u1"), cloud.rgb[:, i]) for i, c in enumerate(("red", "green", "blue"))
        ]
    if cloud.normals is not None:
        columns += [(c, kind, cloud.normals[:, i]) for i, c in enumerate(("nx", "ny", "nz"))]
    columns += field_columns(
        path, cloud.fields, allow_64bit=False, taken=[name for name, _, _ in columns]
    )
    n = len(cloud)
    lines = [
        *_header_start(path, "ascii" if ascii else "binary_little_endian", comments),
        f"element vertex {n}",
    ]
    lines += [f"property {_PLY_NAMES[kind.str[1:]]} {name}" for name, kind, _ in columns]
    lines.append("end_header\n")
    header = "\n".join(lines).encode("ascii")
    label = f"Writing {path.name}"

    def write(fh: IO[bytes]) -> None:
        fh.write(header)
        if ascii:
            write_ascii_rows(fh, columns, n, label)
        else:
            write_rows(fh, columns, n, label)

    return write_atomically(path, write)


def write_mesh_ply(
    path: Path,
    vertices: ArrayLike,
    triangles: ArrayLike,
    colors: ArrayLike | None = None,
    *,
    dtype: Any = "float64",
    comments: Sequence[str] = (),
) -> Path:
    """Write a triangle mesh as a binary little-endian PLY file, atomically.

    Parameters
    ----------
    path : Path
        Target file.
    vertices : (v, 3) float
        Stored as ``x y z`` of type ``dtype``.
    triangles : (t, 3) int
        Vertex indices, stored as ``property list uchar int vertex_indices``.
    colors : (v, 3) uint8, optional
        Vertex colours (``uchar red green blue``).
    dtype : {"float64", "float32"}
        Type of the coordinates: float64 keeps millimetres in a frame far from its origin;
        float32 is used only when it moves no vertex by more than
        :data:`FLOAT32_TOLERANCE` (else float64).
    comments : sequence of str
        Header comment lines after ``written by ontodetect``.

    Returns
    -------
    Path
        The written file; Open3D, trimesh, MeshLab and CloudCompare read it.

    Raises
    ------
    WriteError
        The folder is missing or not writable, or the arrays do not make a mesh.

    Examples
    --------
    >>> import pathlib, tempfile, trimesh
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "m.ply"
    >>> _ = write_mesh_ply(f, [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    >>> m = trimesh.load(f, process=False)
    >>> len(m.vertices), m.faces.tolist()
    (3, [[0, 1, 2]])
    """
    path = Path(path)
    coordinate_dtype(dtype)  # a bad option is named before the arrays are looked at
    xyz = np.asarray(vertices, dtype=np.float64)
    tri = np.asarray(triangles)
    if xyz.ndim != 2 or xyz.shape[1] != 3:
        raise WriteError(path, f"vertices of shape {xyz.shape}, expected (v, 3)")
    if tri.ndim != 2 or tri.shape[1] != 3 or (tri.size and tri.dtype.kind not in "iu"):
        raise WriteError(path, f"triangles of shape {tri.shape}, expected (t, 3) integers")
    if tri.size and (tri.min() < 0 or tri.max() >= len(xyz)):
        raise WriteError(path, f"triangles name vertices outside 0..{len(xyz) - 1}")
    kind = storage_dtype(dtype, xyz)
    columns: list[Column] = [(c, kind, xyz[:, i]) for i, c in enumerate("xyz")]
    if colors is not None:
        rgb = np.asarray(colors)
        if rgb.shape != xyz.shape:
            raise WriteError(path, f"colours of shape {rgb.shape}, expected {xyz.shape}")
        rgb = rgb.astype(np.uint8)
        columns += [(c, np.dtype("u1"), rgb[:, i]) for i, c in enumerate(("red", "green", "blue"))]
    lines = [
        *_header_start(path, "binary_little_endian", comments),
        f"element vertex {len(xyz)}",
        *(f"property {_PLY_NAMES[k.str[1:]]} {name}" for name, k, _ in columns),
        f"element face {len(tri)}",
        "property list uchar int vertex_indices",
        "end_header\n",
    ]
    header = "\n".join(lines).encode("ascii")
    faces = np.empty(len(tri), dtype=np.dtype([("n", "u1"), ("v", "<i4", (3,))]))
    faces["n"] = 3
    faces["v"] = tri

    def write(fh: IO[bytes]) -> None:
        fh.write(header)
        write_rows(fh, columns, len(xyz), f"Writing {path.name}")
        fh.write(faces.view(np.uint8).data)

    return write_atomically(path, write)
