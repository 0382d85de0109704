"""Text point clouds: XYZ, TXT, CSV and Leica PTS.

A text cloud is one point per line, columns separated by whitespace or commas:
``x y z [r g b] [extra ...]``. The reader understands

- an optional header line naming the columns (``x y z r g b intensity``,
  CloudCompare's ``//X,Y,Z,R,G,B``, or a ``# x y z`` comment right above the
  data); named columns are used by name;
- a Leica PTS point count on the first line (``x y z intensity r g b`` follows);
- ``#`` comments, blank lines, ``\\r\\n`` line ends;
- colours as integers 0..255 (or 16-bit 0..65535) or floats 0..1.

Numbers are parsed in blocks of a few megabytes by NumPy's C parser (about
0.3 s per million ``x y z r g b`` lines); only when a block fails is it scanned
line by line to report the exact line number of the problem.

The helpers :func:`load_numeric_table` and :func:`split_columns` are shared with
the other text-based readers (3DTK, S3DIS).
"""

from __future__ import annotations

import io
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._progress import progress
from ..cloud import RESERVED_FIELDS, DataWarning, PointCloud, point_cloud
from ..errors import CorruptFileError, InvalidParameterError, ReadError, WriteError
from ._atomic import atomic_write

__all__ = ["load_numeric_table", "read_text", "write_text"]

#: Bytes parsed per block: large enough for NumPy's parser to run at full speed,
#: small enough for a steady progress bar and bounded temporary memory.
CHUNK_BYTES = 8 << 20
#: Lines examined at the top of a file to find comments, a header or a point count.
HEADER_PROBE_LINES = 1000
#: Longest line considered while probing the header; longer ones are not text.
MAX_HEADER_LINE = 1 << 16
#: Characters of an offending line quoted in error messages.
QUOTE_CHARS = 60
#: Rows formatted per write call.
WRITE_ROWS = 50_000
#: Largest integer colour of a 16-bit channel.
MAX_COLOR16 = 65535

_NAME_RE = re.compile(r"^[A-Za-z_][^\x00-\x1f]*$")
_CONTROL_RE = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")

# Header spellings -> the cloud's attribute columns.
_ALIASES = {
    "x": "x",
    "y": "y",
    "z": "z",
    "r": "r",
    "red": "r",
    "rf": "r",
    "g": "g",
    "green": "g",
    "gf": "g",
    "b": "b",
    "blue": "b",
    "bf": "b",
    "nx": "nx",
    "normal_x": "nx",
    "normalx": "nx",
    "ny": "ny",
    "normal_y": "ny",
    "normaly": "ny",
    "nz": "nz",
    "normal_z": "nz",
    "normalz": "nz",
    "i": "intensity",
    "intensity": "intensity",
}
# Fields whose values are labels or counts: stored as int32 when every value is integral.
_INTEGER_FIELDS = frozenset(
    {
        "class_id",
        "instance",
        "classification",
        "label",
        "class",
        "scan",
        "segment",
        "return_number",
        "number_of_returns",
        "point_source_id",
        "object_id",
        "ring",
    }
)
# Leica PTS column layouts by number of columns.
_PTS_LAYOUTS = {
    3: ["x", "y", "z"],
    4: ["x", "y", "z", "intensity"],
    6: ["x", "y", "z", "r", "g", "b"],
    7: ["x", "y", "z", "intensity", "r", "g", "b"],
}


# ---------------------------------------------------------------------------------
# Shared numeric table parsing
# ---------------------------------------------------------------------------------
@dataclass
class TableStats:
    """What :func:`load_numeric_table` had to repair or skip, and PTS section counts."""

    repaired: list[int] = field(default_factory=list)
    skipped: list[int] = field(default_factory=list)
    section_counts: list[int] = field(default_factory=list)


def split_columns(line: str, delimiter: str | None) -> list[str]:
    """Tokens of one line (after removing a ``#`` comment).

    Examples
    --------
    >>> split_columns(" 1, 2 ,3 # note", ",")
    ['1', '2', '3']
    >>> split_columns("1  2\\t3", None)
    ['1', '2', '3']
    """
    s = line.split("#", 1)[0].strip()
    if not s:
        return []
    if delimiter is None:
        return s.split()
    return [t.strip() for t in s.split(delimiter)]


def _quote(line: str) -> str:
    line = line.rstrip("\r\n")
    return repr(line if len(line) <= QUOTE_CHARS else line[:QUOTE_CHARS] + "...")


def _floats(tokens: Sequence[str]) -> list[float] | None:
    try:
        return [float(t) for t in tokens]
    except ValueError:
        return None


def _slow_parse(
    path: Path,
    text: str,
    first_line: int,
    delimiter: str | None,
    ncols: int | None,
    repair: bool,
    pts_sections: bool,
    stats: TableStats,
) -> tuple[NDArray[np.float64], int | None]:
    """Parse line by line; the authority when the fast parser rejects a block."""
    rows: list[list[float]] = []
    for offset, line in enumerate(text.split("\n")):
        line_no = first_line + offset
        tokens = split_columns(line, delimiter)
        if not tokens:
            continue
        if pts_sections and len(tokens) == 1 and tokens[0].isdigit():
            stats.section_counts.append(int(tokens[0]))
            continue
        values = _floats(tokens)
        if values is not None and (ncols is None or len(values) == ncols):
            ncols = len(values)
            rows.append(values)
            continue
        if repair:
            # Stray control characters (S3DIS has one in Area_5/hallway_6) sit where a
            # separator should be: turn them into spaces and try again.
            cleaned = split_columns(_CONTROL_RE.sub(" ", line), delimiter)
            values = _floats(cleaned)
            if values is not None and (ncols is None or len(values) == ncols):
                ncols = len(values)
                rows.append(values)
                stats.repaired.append(line_no)
            else:
                stats.skipped.append(line_no)
            continue
        if values is None:
            raise CorruptFileError(path, f"line {line_no}: expected numbers, found {_quote(line)}")
        raise CorruptFileError(
            path,
            f"line {line_no}: expected {ncols} columns, found {len(values)} in {_quote(line)}",
        )
    width = ncols or 0
    return np.asarray(rows, dtype=np.float64).reshape(-1, width), ncols


def _fast_parse(data: bytes, delimiter: str | None) -> NDArray[np.float64] | None:
    try:
        with warnings.catch_warnings():
            # An all-comment block is not an error here; the caller counts points.
            warnings.simplefilter("ignore", UserWarning)
            arr = np.loadtxt(
                io.BytesIO(data),
                dtype=np.float64,
                delimiter=delimiter,
                comments="#",
                ndmin=2,
                encoding="latin-1",
            )
    except Exception:
        # Whatever the fast parser dislikes, the line-by-line parser decides (and names
        # the line); no exception from here reaches the caller.
        return None
    return arr


def load_numeric_table(
    path: Path,
    *,
    offset: int = 0,
    first_line: int = 1,
    delimiter: str | None = None,
    ncols: int | None = None,
    repair: bool = False,
    pts_sections: bool = False,
    description: str | None = None,
) -> tuple[NDArray[np.float64], TableStats]:
    """Parse the numeric lines of a text file from byte ``offset`` on.

    Parameters
    ----------
    path : Path
        The file.
    offset : int
        Byte where the numbers start (after any header).
    first_line : int
        1-based line number at ``offset``, for error messages.
    delimiter : str or None
        Column separator; None means any whitespace.
    ncols : int, optional
        Expected number of columns; taken from the first line otherwise.
    repair : bool
        Replace stray control characters by separators, and skip lines that stay
        unreadable, instead of raising (the caller reports ``stats``).
    pts_sections : bool
        Accept lines holding a single integer as Leica PTS section counts.
    description : str, optional
        Progress message; ``"Reading <name>"`` by default.

    Returns
    -------
    table : (n, k) float
        One row per point line.
    stats : TableStats
        Lines repaired or skipped, PTS section counts.

    Raises
    ------
    CorruptFileError
        Non-numeric text or a wrong number of columns (message names the line),
        unless ``repair`` is set.
    ReadError
        The file cannot be read.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
    >>> _ = f.write_text("# two points\\n1 2 3\\n4 5 6\\n")
    >>> load_numeric_table(f)[0].tolist()
    [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
    """
    stats = TableStats()
    blocks: list[NDArray[np.float64]] = []
    line_no = first_line
    try:
        size = path.stat().st_size
        fh = open(path, "rb")  # noqa: SIM115 - closed in the finally below
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    try:
        fh.seek(offset)
        carry = b""
        with progress(description or f"Reading {path.name}", total=max(size - offset, 0)) as adv:
            while True:
                block = fh.read(CHUNK_BYTES)
                adv(len(block))
                if block:
                    data = carry + block
                    cut = data.rfind(b"\n")
                    if cut < 0:
                        carry = data
                        continue
                    data, carry = data[: cut + 1], data[cut + 1 :]
                else:
                    data, carry = carry, b""
                    if not data:
                        break
                arr = _fast_parse(data, delimiter)
                if arr is not None and arr.size and ncols is not None and arr.shape[1] != ncols:
                    arr = None
                if arr is None:
                    text = data.decode("latin-1")
                    arr, ncols = _slow_parse(
                        path, text, line_no, delimiter, ncols, repair, pts_sections, stats
                    )
                elif arr.size:
                    ncols = arr.shape[1]
                if arr.size:
                    blocks.append(arr)
                line_no += data.count(b"\n")
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    finally:
        fh.close()
    if not blocks:
        return np.zeros((0, ncols or 0)), stats
    return np.concatenate(blocks, axis=0), stats


# ---------------------------------------------------------------------------------
# Header probing
# ---------------------------------------------------------------------------------
@dataclass
class _Layout:
    offset: int
    first_line: int
    delimiter: str | None
    ncols: int
    names: list[str] | None
    count: int | None


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _header_tokens(text: str) -> list[str]:
    text = text.strip()
    parts = text.split(",") if "," in text else text.split()
    return [p.strip().strip("\"'") for p in parts if p.strip()]


def _looks_like_names(tokens: list[str]) -> bool:
    return (
        bool(tokens)
        and all(_NAME_RE.match(t) for t in tokens)
        and not all(_is_number(t) for t in tokens)
    )


def _probe(path: Path, delimiter: str | None) -> _Layout:
    """Find where the numbers start, the separator, the column names and a PTS count."""
    header: list[str] | None = None
    header_line = 0
    comment: tuple[int, str] | None = None
    count: int | None = None
    offset = 0
    try:
        with open(path, "rb") as fh:
            for line_no in range(1, HEADER_PROBE_LINES + 1):
                raw = fh.readline(MAX_HEADER_LINE)
                if not raw:
                    break
                text = raw.decode("latin-1")
                s = text.strip()
                here, offset = offset, offset + len(raw)
                if not s:
                    continue
                if s.startswith("//") and header is None and count is None:
                    header, header_line = _header_tokens(s[2:]), line_no
                    continue
                if s.startswith("#"):
                    comment = (line_no, s[1:])
                    continue
                delim = delimiter if delimiter is not None else ("," if "," in s else None)
                tokens = split_columns(text, delim)
                if all(_is_number(t) for t in tokens):
                    first_content = header is None and count is None and comment is None
                    if len(tokens) == 1 and first_content and tokens[0].isdigit():
                        count = int(tokens[0])
                        continue
                    if header is None and comment is not None and comment[0] == line_no - 1:
                        names = _header_tokens(comment[1])
                        if len(names) == len(tokens) and _looks_like_names(names):
                            header, header_line = names, comment[0]
                    if header is not None and len(header) != len(tokens):
                        raise CorruptFileError(
                            path,
                            f"line {header_line} names {len(header)} columns but line "
                            f"{line_no} has {len(tokens)} values",
                        )
                    return _Layout(here, line_no, delim, len(tokens), header, count)
                names = _header_tokens(s)
                if header is None and count is None and _looks_like_names(names):
                    header, header_line = names, line_no
                    continue
                raise CorruptFileError(
                    path, f"line {line_no}: expected numbers, found {_quote(text)}"
                )
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    raise CorruptFileError(
        path,
        "contains no points"
        if line_no < HEADER_PROBE_LINES
        else f"no numeric line within the first {HEADER_PROBE_LINES} lines",
    )


# ---------------------------------------------------------------------------------
# Reader
# ---------------------------------------------------------------------------------
def _field_name(name: str) -> str:
    key = re.sub(r"[^0-9a-z_]+", "_", name.strip().lower()).strip("_") or "column"
    if key.startswith("scalar_") and len(key) > len("scalar_"):
        key = key[len("scalar_") :]
    key = _ALIASES.get(key, key)
    if key in RESERVED_FIELDS and key not in _ALIASES.values():
        key = f"{key}_field"
    return key


def _looks_like_colors(cols: NDArray[np.float64]) -> bool:
    if cols.size == 0 or not np.isfinite(cols).all() or cols.min() < 0:
        return False
    integral = bool(np.all(cols == np.round(cols)))
    return float(cols.max()) <= 1.0 or (integral and float(cols.max()) <= 255)


def _to_colors(path: Path, cols: NDArray[np.float64], names: Sequence[str]) -> NDArray[np.uint8]:
    finite = np.isfinite(cols)
    if not finite.all():
        raise CorruptFileError(path, f"colour columns {'/'.join(names)} hold NaN or infinity")
    lo, hi = float(cols.min()), float(cols.max())
    integral = bool(np.all(cols == np.round(cols)))
    if lo < 0 or hi > MAX_COLOR16 or (not integral and hi > 1.0):
        raise CorruptFileError(
            path,
            f"colour columns {'/'.join(names)} should hold integers 0..255 or floats "
            f"0..1, found values from {lo:g} to {hi:g}",
        )
    if not integral:
        return np.rint(cols * 255.0).astype(np.uint8)
    if hi > 255:  # 16-bit colours: keep the high byte
        return (cols.astype(np.uint32) >> 8).astype(np.uint8)
    return cols.astype(np.uint8)


def _default_names(ncols: int, pts: bool, table: NDArray[np.float64]) -> list[str]:
    if pts and ncols in _PTS_LAYOUTS:
        return list(_PTS_LAYOUTS[ncols])
    names = ["x", "y", "z"] + [f"col{i}" for i in range(3, ncols)]
    if ncols >= 6 and _looks_like_colors(table[:, 3:6]):
        names[3:6] = ["r", "g", "b"]
    return names


def read_text(
    path: Path,
    *,
    columns: Sequence[str] | str | None = None,
    delimiter: str | None = None,
    on_nonfinite: str = "warn",
) -> PointCloud:
    """Read an XYZ / TXT / CSV / PTS point cloud.

    Parameters
    ----------
    path : Path
        The file.
    columns : sequence of str or str, optional
        Names of the columns, overriding any header (``"x y z nx ny nz"``). Names
        ``x y z``, ``r g b`` (or ``red green blue``) and ``nx ny nz`` fill the
        coordinates, colours and normals; every other column becomes a field.
    delimiter : str, optional
        Column separator; guessed from the first data line (comma or whitespace).
    on_nonfinite : {"warn", "drop", "raise"}
        What to do with NaN/infinite coordinates (see :func:`~ontodetect.point_cloud`).

    Returns
    -------
    PointCloud
        ``fields`` hold the extra columns, named from the header or ``col3``,
        ``col4``...; label-like fields (``class_id``, ``instance``,
        ``classification``, ...) with integral values are int32, others float64.
        ``meta["columns"]`` lists the column names as understood.

    Raises
    ------
    CorruptFileError
        Non-numeric text (the message names the line), ragged rows, a PTS count
        that disagrees with the number of lines, colours out of range, no points.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.csv"
    >>> _ = f.write_text("//X,Y,Z,R,G,B,Intensity\\n1,2,3,255,0,0,7\\n")
    >>> c = read_text(f)
    >>> c.xyz.tolist(), c.rgb.tolist(), c.fields["intensity"].tolist()
    ([[1.0, 2.0, 3.0]], [[255, 0, 0]], [7.0])
    """
    path = Path(path)
    layout = _probe(path, delimiter)
    if layout.ncols < 3:
        raise CorruptFileError(
            path,
            f"line {layout.first_line}: expected at least 3 columns (x y z), found {layout.ncols}",
        )
    pts = path.suffix.lower() == ".pts" or layout.count is not None
    table, stats = load_numeric_table(
        path,
        offset=layout.offset,
        first_line=layout.first_line,
        delimiter=layout.delimiter,
        ncols=layout.ncols,
        pts_sections=pts,
    )
    n = table.shape[0]
    if n == 0:
        raise CorruptFileError(path, "contains no points")
    declared = None
    if layout.count is not None:
        declared = layout.count + sum(stats.section_counts)
        if declared != n:
            raise CorruptFileError(
                path, f"the point count says {declared} points but {n} point lines follow"
            )

    if columns is not None:
        given = columns.split() if isinstance(columns, str) else list(columns)
        if len(given) != layout.ncols:
            raise InvalidParameterError(
                "columns",
                f"a list of {layout.ncols} names (one per column of {path.name})",
                given,
            )
        raw_names = given
    elif layout.names is not None:
        raw_names = layout.names
    else:
        raw_names = _default_names(layout.ncols, pts, table)

    names: list[str] = []
    for raw in raw_names:
        key = _field_name(raw)
        base, k = key, 1
        while key in names:
            key, k = f"{base}_{k}", k + 1
        names.append(key)
    where = {name: i for i, name in enumerate(names)}
    xyz_cols = [where[a] for a in ("x", "y", "z")] if {"x", "y", "z"} <= set(where) else [0, 1, 2]
    used = set(xyz_cols)
    rgb = normals = None
    if {"r", "g", "b"} <= set(where):
        rgb_cols = [where[a] for a in ("r", "g", "b")]
        rgb = _to_colors(path, table[:, rgb_cols], [raw_names[i] for i in rgb_cols])
        used.update(rgb_cols)
    if {"nx", "ny", "nz"} <= set(where):
        nrm_cols = [where[a] for a in ("nx", "ny", "nz")]
        normals = table[:, nrm_cols]
        used.update(nrm_cols)
    fields: dict[str, NDArray[Any]] = {}
    for i, name in enumerate(names):
        if i in used:
            continue
        values = np.ascontiguousarray(table[:, i])
        if (
            name in _INTEGER_FIELDS
            and np.isfinite(values).all()
            and np.all(values == np.round(values))
            and (values.size == 0 or np.abs(values).max() < 2**31)
        ):
            values = values.astype(np.int32)
        fields[name] = values
    meta: dict[str, Any] = {"columns": names, "delimiter": layout.delimiter or "whitespace"}
    if declared is not None:
        meta["declared_count"] = declared
    return point_cloud(
        table[:, xyz_cols],
        rgb=rgb,
        normals=normals,
        fields=fields,
        meta={"source": str(path)} | meta,
        on_nonfinite=on_nonfinite,
        copy=False,
    )


# ---------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------
def _column_name(name: str) -> str:
    # The reader recognises a header by names that start with a letter or "_".
    text = re.sub(r"[\s,#]+", "_", name) or "field"
    return text if _NAME_RE.match(text) else f"f_{text}"


def write_text(
    path: Path,
    cloud: PointCloud,
    *,
    precision: int | None = None,
    delimiter: str | None = None,
    header: bool = True,
) -> Path:
    """Write a cloud as text: ``x y z [r g b] [nx ny nz] [fields]``, one point per line.

    Parameters
    ----------
    path : Path
        Target; ``.csv`` is comma separated, ``.pts`` is written in Leica's layout
        (point count, then ``x y z [intensity] [r g b]``), others use spaces.
    cloud : PointCloud
        What to write. Fields of shape (n, k) become ``name_0 .. name_k-1`` columns.
    precision : int, optional
        Digits after the decimal point for coordinates, normals and float fields.
        By default every float is written with the shortest text that reads back
        to exactly the same float64.
    delimiter : str, optional
        Column separator; by default ``","`` for ``.csv`` and ``" "`` otherwise.
    header : bool
        Write a first line naming the columns (ignored for ``.pts``).

    Returns
    -------
    Path
        The written file (replaced atomically).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from ontodetect import point_cloud
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.xyz"
    >>> _ = write_text(f, point_cloud([[0.1, 2, 3]], rgb=[[1, 2, 3]]))
    >>> f.read_text()
    'x y z r g b\\n0.1 2.0 3.0 1 2 3\\n'
    """
    path = Path(path)
    if precision is not None and (not isinstance(precision, int) or not 0 <= precision <= 17):
        raise InvalidParameterError("precision", "an integer in 0..17 or None", precision)
    suffix = path.suffix.lower()
    sep = delimiter if delimiter is not None else ("," if suffix == ".csv" else " ")
    pts = suffix == ".pts"
    float_fmt = "%r" if precision is None else f"%.{precision}f"

    names: list[str] = []
    columns: list[NDArray[Any]] = []
    formats: list[str] = []

    def add(name: str, values: NDArray[Any]) -> None:
        kind = values.dtype.kind
        if kind == "b":
            values = values.astype(np.int64)
            kind = "i"
        names.append(name)
        if kind in "iu":
            columns.append(values.astype(np.int64))
            formats.append("%d")
        else:
            columns.append(values.astype(np.float64))
            formats.append(float_fmt)

    for i, axis in enumerate("xyz"):
        add(axis, cloud.xyz[:, i])
    if pts:
        extra = sorted(set(cloud.fields) - {"intensity"})
        if extra:
            warnings.warn(
                f"{path}: the PTS layout has no room for fields {extra}; they are not written",
                DataWarning,
                stacklevel=2,
            )
        if "intensity" in cloud.fields:
            add("intensity", np.asarray(cloud.fields["intensity"]).reshape(len(cloud), -1)[:, 0])
        if cloud.rgb is not None:
            for i, c in enumerate("rgb"):
                add(c, cloud.rgb[:, i])
    else:
        if cloud.rgb is not None:
            for i, c in enumerate("rgb"):
                add(c, cloud.rgb[:, i])
        if cloud.normals is not None:
            for i, c in enumerate(("nx", "ny", "nz")):
                add(c, cloud.normals[:, i])
        for name, values in cloud.fields.items():
            arr = np.asarray(values)
            col = _column_name(name)
            if arr.ndim == 1:
                add(col, arr)
            else:
                flat = arr.reshape(len(cloud), -1)
                for k in range(flat.shape[1]):
                    add(f"{col}_{k}", flat[:, k])

    row_fmt = sep.join(formats) + "\n"
    n = len(cloud)
    with atomic_write(path, "w") as fh, progress(f"Writing {path.name}", total=n) as advance:
        if pts:
            fh.write(f"{n}\n")
        elif header:
            fh.write(sep.join(names) + "\n")
        for start in range(0, n, WRITE_ROWS):
            stop = min(start + WRITE_ROWS, n)
            # tolist() gives Python floats, whose %r is the shortest exact text.
            rows = zip(*(c[start:stop].tolist() for c in columns), strict=True)
            try:
                fh.write("".join(row_fmt % row for row in rows))
            except (TypeError, ValueError) as exc:  # pragma: no cover - defensive
                raise WriteError(path, f"cannot format values ({exc})") from exc
            advance(stop - start)
    return path
