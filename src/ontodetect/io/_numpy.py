"""NumPy ``.npy`` arrays and ``.npz`` archives of points.

``.npy`` holds one array:

- (n, 3): x y z;
- (n, 6): x y z r g b, when columns 3-5 look like colours (every value finite
  and in 0..255; floats all <= 1 are taken as 0..1), as in ScanNet's
  ``*_vert.npy``; otherwise they are kept as fields ``col3 col4 col5``;
- (n, k > 6) or (n, 4..5): the extra columns become fields ``col6``, ``col7``...
  (``col3``... when there are no colours);
- a structured array with fields named ``x y z`` and optionally
  ``red green blue`` (or ``r g b``), ``nx ny nz``; every other field is kept.

``.npz`` holds named arrays: ``xyz`` (or ``points``; or separate ``x``, ``y``,
``z``; or ``pc``, an (n, 6) x y z r g b table with colours 0..1, as VoteNet stores SUN
RGB-D's frames, read by the .npy rules), ``rgb`` (or ``colors`` / ``colours``),
``normals``, ``index``, and every other numeric array with one row per point as a
field of the same name. Arrays of another length are ignored (their names are listed
in ``meta["ignored_arrays"]``).

Pickled objects are never loaded. Headers are checked against the file size
before anything is allocated, so a damaged header cannot request terabytes.
"""

from __future__ import annotations

import ast
import io
import math
import struct
import warnings
import zipfile
import zlib
from pathlib import Path
from typing import IO, Any

import numpy as np
from numpy.typing import NDArray

from ..cloud import DataWarning, PointCloud
from ..errors import CorruptFileError, ReadError, WriteError
from ._budget import check_bytes, check_points
from ._ply import (
    ColumnPlan,
    check_on_nonfinite,
    cloud_from_columns,
    plan_columns,
    write_atomically,
)

__all__ = ["read_npy", "read_npz", "write_npy", "write_npz"]

#: Largest ``.npy`` header accepted (NumPy's own limit for untrusted files).
NPY_HEADER_MAX_BYTES = 10_000
#: Deflate never expands data more than about 1032 times; a zip entry claiming
#: more is damaged (or a zip bomb) and is refused before it is inflated.
DEFLATE_MAX_RATIO = 1100
#: Largest colour value in 8-bit channels.
MAX_COLOR = 255

_MAGIC = b"\x93NUMPY"
_XYZ_KEYS = ("xyz", "points", "pc")
_RGB_KEYS = ("rgb", "colors", "colours")
_NORMAL_KEYS = ("normals",)
#: Names the npz reader gives a meaning; fields cannot be written under them.
_SPECIAL_KEYS = frozenset({*_XYZ_KEYS, *_RGB_KEYS, *_NORMAL_KEYS, "index"})
_NPZ_COLOR_NAMES = (("red", "green", "blue"),)
_NPZ_NORMAL_NAMES = (("nx", "ny", "nz"),)


# ---------------------------------------------------------------------------------
# .npy parsing with bounds checks
# ---------------------------------------------------------------------------------
def _about(what: str | None, problem: str) -> str:
    """``"array 'xyz': problem"`` for a member of an archive; the problem alone for the
    file itself, whose path the error already names."""
    return problem if what is None else f"{what}: {problem}"


def _npy_header(
    path: Path, fh: IO[bytes], what: str | None
) -> tuple[np.dtype, tuple[int, ...], bool]:
    """Read and validate an .npy header; returns (dtype, shape, fortran_order).

    ``what`` names the array in its errors (a member of an .npz archive); None for the
    file itself."""
    subject = what or "the file"
    magic = fh.read(8)
    if len(magic) < 8 or not magic.startswith(_MAGIC):
        raise CorruptFileError(path, f"{subject} is not a NumPy .npy array (bad magic bytes)")
    major = magic[6]
    if major == 1:
        length_bytes, size = 2, "<H"
    elif major in (2, 3):
        length_bytes, size = 4, "<I"
    else:
        raise CorruptFileError(path, f"{subject} has unknown .npy format version {major}")
    raw = fh.read(length_bytes)
    if len(raw) < length_bytes:
        raise CorruptFileError(path, _about(what, "truncated .npy header"))
    length = int(np.frombuffer(raw, size)[0])
    if length > NPY_HEADER_MAX_BYTES:
        raise CorruptFileError(path, _about(what, f".npy header of {length} bytes is too long"))
    text = fh.read(length)
    if len(text) < length:
        raise CorruptFileError(path, _about(what, "truncated .npy header"))
    try:
        header = ast.literal_eval(text.decode("utf-8" if major == 3 else "latin-1"))
        descr, fortran, shape = header["descr"], header["fortran_order"], header["shape"]
        dtype = np.lib.format.descr_to_dtype(descr)
    except Exception as exc:  # literal_eval and descr_to_dtype raise many types on garbage
        raise CorruptFileError(
            path, _about(what, f"unreadable .npy header ({type(exc).__name__})")
        ) from exc
    if not (
        isinstance(shape, tuple)
        and all(isinstance(d, int) and d >= 0 for d in shape)
        and isinstance(fortran, bool)
    ):
        raise CorruptFileError(path, _about(what, f"invalid .npy header (shape {shape!r})"))
    if dtype.hasobject:
        raise ReadError(path, f"{subject} holds Python objects, which are not loaded for safety")
    if dtype.itemsize == 0 or dtype.subdtype is not None:
        raise ReadError(path, f"{subject} has type {dtype}, which holds no point data")
    return dtype, shape, fortran


def _npy_array(
    path: Path, fh: IO[bytes], available: int, what: str | None, spent: int = 0
) -> NDArray[Any]:
    """Load one .npy array from ``fh`` after checking its size against ``available`` bytes
    and, with ``spent`` bytes already taken by earlier arrays, against the memory budget.
    ``what`` names the array in errors (None: the file itself)."""
    start = fh.tell()
    dtype, shape, fortran = _npy_header(path, fh, what)
    count = math.prod(shape)
    need = count * dtype.itemsize
    left = available - (fh.tell() - start)
    if need > left:
        raise CorruptFileError(
            path,
            _about(
                what,
                f"truncated, shape {shape} of {dtype} needs {need} bytes, {max(left, 0)} present",
            ),
        )
    if shape:
        check_points(path, shape[0], what or "the file")
    check_bytes(path, spent + need, what or "the file")
    data = fh.read(need)
    if len(data) < need:
        raise CorruptFileError(
            path, _about(what, f"truncated, {need} bytes needed, {len(data)} read")
        )
    try:
        arr = np.frombuffer(data, dtype=dtype, count=count)
        return arr.reshape(shape, order="F" if fortran else "C")
    except ValueError as exc:
        raise CorruptFileError(
            path, _about(what, f"cannot be read as shape {shape} of {dtype} ({exc})")
        ) from exc


# ---------------------------------------------------------------------------------
# Readers
# ---------------------------------------------------------------------------------
def _color_columns(block: NDArray[Any]) -> bool:
    """Whether three columns hold colours: finite values in 0..255."""
    if block.dtype.kind not in "biuf" or block.size == 0:
        return False
    if block.dtype.kind == "f" and not np.isfinite(block).all():
        return False
    return bool(block.min() >= 0 and block.max() <= MAX_COLOR)


def _columns_from_matrix(path: Path, arr: NDArray[Any], what: str) -> dict[str, NDArray[Any]]:
    """Named columns of an (n, k >= 3) matrix, following the .npy layout rules."""
    if arr.ndim != 2 or arr.shape[1] < 3:
        raise ReadError(
            path,
            f"{what} has shape {arr.shape}; expected (n, 3) points, (n, 6) "
            "points and colours, or a structured array with x, y, z",
        )
    if arr.dtype.kind not in "biuf":
        raise ReadError(path, f"{what} has type {arr.dtype}; expected real numbers")
    names = ["x", "y", "z"] + [f"col{i}" for i in range(3, arr.shape[1])]
    if arr.shape[1] >= 6 and _color_columns(arr[:, 3:6]):
        names[3:6] = ["red", "green", "blue"]
    return {name: arr[:, i] for i, name in enumerate(names)}


def _plan_or_fail(path: Path, names: list[str], what: str, **groups: Any) -> ColumnPlan:
    plan = plan_columns(names, **groups)
    if plan.xyz is None:
        raise ReadError(path, f"{what} has no x, y, z (found: {', '.join(names) or 'nothing'})")
    return plan


def read_npy(path: Path, *, on_nonfinite: str = "warn") -> PointCloud:
    """Read points from a ``.npy`` file.

    Parameters
    ----------
    path : Path
        An (n, 3), (n, 6) or wider array, or a structured array with x, y, z.
    on_nonfinite : {"warn", "drop", "raise"}
        Treatment of points with NaN or infinite coordinates.

    Returns
    -------
    PointCloud
        ``meta["columns"]`` names the columns of a plain array as read.

    Raises
    ------
    CorruptFileError
        Not an .npy file, a damaged header, fewer bytes than the shape needs, no points.
    ReadError
        The array is not a point table (wrong shape, Python objects, complex numbers).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "p.npy"
    >>> np.save(f, np.array([[0, 0, 0, 255, 0, 0, 7], [1, 1, 1, 0, 255, 0, 8.0]]))
    >>> c = read_npy(f)
    >>> c.rgb.tolist(), c.fields["col6"].tolist()
    ([[255, 0, 0], [0, 255, 0]], [7.0, 8.0])
    """
    path = Path(path)
    check_on_nonfinite(on_nonfinite)
    try:
        with open(path, "rb") as fh:
            size = fh.seek(0, io.SEEK_END)
            fh.seek(0)
            arr = _npy_array(path, fh, size, None)
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    meta: dict[str, Any] = {}
    if arr.dtype.names:
        if arr.ndim != 1:
            raise ReadError(path, f"structured array has shape {arr.shape}; expected (n,)")
        columns = {name: arr[name] for name in arr.dtype.names if arr.dtype[name].kind in "biuf"}
        plan = _plan_or_fail(path, list(columns), "the structured array")
    else:
        columns = _columns_from_matrix(path, arr, "the array")
        plan = plan_columns(list(columns))
        meta["columns"] = list(columns)
    if arr.shape[0] == 0:
        raise CorruptFileError(path, "contains no points (the array has 0 rows)")
    return cloud_from_columns(path, plan, columns, meta, on_nonfinite)


def _npz_arrays(path: Path) -> dict[str, NDArray[Any]]:
    arrays: dict[str, NDArray[Any]] = {}
    spent = 0
    try:
        with zipfile.ZipFile(path) as archive:
            for info in archive.infolist():
                if not info.filename.endswith(".npy"):
                    continue
                key = info.filename[: -len(".npy")]
                what = f"array {key!r}"
                if info.file_size > max(info.compress_size, 1) * DEFLATE_MAX_RATIO + (1 << 16):
                    raise CorruptFileError(
                        path,
                        f"{what}: implausible sizes in the archive "
                        f"({info.compress_size} bytes expand to "
                        f"{info.file_size})",
                    )
                with archive.open(info) as member:
                    # The member's .npy header is read first and its shape checked against
                    # the budget before anything is decompressed; reading at most the
                    # declared size bounds the rest.
                    arrays[key] = _npy_array(path, member, info.file_size, what, spent)
                spent += arrays[key].nbytes
    except (
        zipfile.BadZipFile,
        zlib.error,
        EOFError,
        NotImplementedError,
        ValueError,
        UnicodeDecodeError,
        OverflowError,
        KeyError,
        IndexError,
        RuntimeError,
        struct.error,
    ) as exc:
        raise CorruptFileError(path, f"not a readable .npz archive ({exc})") from exc
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    return arrays


def read_npz(path: Path, *, on_nonfinite: str = "warn") -> PointCloud:
    """Read points and their attributes from a ``.npz`` archive.

    Parameters
    ----------
    path : Path
        An archive with ``xyz`` (or ``points`` or ``pc``; or ``x``, ``y``, ``z``) and
        optionally ``rgb`` / ``colors``, ``normals``, ``index`` and per-point
        fields.
    on_nonfinite : {"warn", "drop", "raise"}
        Treatment of points with NaN or infinite coordinates.

    Returns
    -------
    PointCloud
        Fields keep their names and types; ``index`` is restored when stored.

    Raises
    ------
    CorruptFileError
        Not a zip archive, a damaged member, arrays of mismatched lengths, no points.
    ReadError
        No coordinates in the archive.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "p.npz"
    >>> np.savez(f, xyz=np.zeros((2, 3)), label=np.array([3, 4], np.int16))
    >>> read_npz(f).fields["label"].dtype
    dtype('int16')
    """
    path = Path(path)
    check_on_nonfinite(on_nonfinite)
    arrays = _npz_arrays(path)
    key = next((k for k in _XYZ_KEYS if k in arrays), None)
    columns: dict[str, NDArray[Any]] = {}
    if key is not None:
        columns.update(_columns_from_matrix(path, arrays.pop(key), f"array {key!r}"))
    n = next(iter(columns.values())).shape[0] if columns else None
    if n is None:
        sizes = {arrays[c].shape[0] for c in "xyz" if c in arrays and arrays[c].ndim == 1}
        n = sizes.pop() if len(sizes) == 1 else None
    if n is None:
        raise ReadError(
            path,
            "has no 'xyz' (or 'points', 'pc', or 'x', 'y', 'z') array (found: "
            f"{', '.join(sorted(arrays)) or 'nothing'})",
        )

    def take(keys: tuple[str, ...], name: str) -> None:
        k = next((k for k in keys if k in arrays), None)
        if k is None:
            return
        block = arrays.pop(k)
        if (
            block.ndim != 2
            or block.shape[0] != n
            or block.shape[1] not in (3, 4)
            or block.dtype.kind not in "biuf"
        ):
            raise CorruptFileError(
                path,
                f"array {k!r} has shape {block.shape} and type "
                f"{block.dtype}; expected ({n}, 3) numbers",
            )
        for i, part in enumerate(("red", "green", "blue") if name == "rgb" else ("nx", "ny", "nz")):
            columns[part] = block[:, i]

    take(_RGB_KEYS, "rgb")
    take(_NORMAL_KEYS, "normals")
    index = arrays.pop("index", None)
    if index is not None and (index.shape != (n,) or index.dtype.kind not in "iu"):
        raise CorruptFileError(
            path,
            f"array 'index' has shape {index.shape} and type "
            f"{index.dtype}; expected ({n},) integers",
        )
    ignored = []
    for k, values in arrays.items():
        if (
            values.ndim in (1, 2)
            and values.shape[0] == n
            and values.dtype.kind in "biuf"
            and k not in columns
        ):
            columns[k] = values
        else:
            ignored.append(k)
    if n == 0:
        raise CorruptFileError(path, "contains no points (the coordinates have 0 rows)")
    plan = _plan_or_fail(
        path,
        list(columns),
        "the archive",
        color_groups=_NPZ_COLOR_NAMES,
        normal_groups=_NPZ_NORMAL_NAMES,
    )
    meta: dict[str, Any] = {"ignored_arrays": ignored} if ignored else {}
    return cloud_from_columns(
        path,
        plan,
        columns,
        meta,
        on_nonfinite,
        index=None if index is None else index.astype(np.int64),
    )


# ---------------------------------------------------------------------------------
# Writers
# ---------------------------------------------------------------------------------
def write_npy(path: Path, cloud: PointCloud) -> Path:
    """Write xyz (and rgb) as one float64 array: (n, 3), or (n, 6) with colours 0..255.

    An ``.npy`` file holds one plain array, so normals, fields and ``index`` are
    not written (a :class:`~ontodetect.cloud.DataWarning` names them); write an
    ``.npz`` archive to keep everything. A cloud whose colours are all 0 or 1
    reads back as 0..1 colours, scaled to 255.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from ontodetect import point_cloud
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "p.npy"
    >>> np.load(write_npy(f, point_cloud([[1, 2, 3]], rgb=[[10, 20, 30]]))).tolist()
    [[1.0, 2.0, 3.0, 10.0, 20.0, 30.0]]
    """
    path = Path(path)
    if not isinstance(cloud, PointCloud):
        raise WriteError(path, f"expected a PointCloud, got {type(cloud).__name__}")
    dropped = (["normals"] if cloud.normals is not None else []) + list(cloud.fields)
    if dropped:
        warnings.warn(
            f"{path}: .npy stores only xyz and rgb; not written: {', '.join(dropped)} "
            "(write a .npz archive to keep them)",
            DataWarning,
            stacklevel=2,
        )
    table = cloud.xyz if cloud.rgb is None else np.hstack([cloud.xyz, cloud.rgb])
    table = np.ascontiguousarray(table, dtype=np.float64)
    return write_atomically(path, lambda fh: np.save(fh, table, allow_pickle=False))


def write_npz(path: Path, cloud: PointCloud, *, compressed: bool = False) -> Path:
    """Write everything a cloud holds as named arrays in a ``.npz`` archive.

    Arrays: ``xyz`` (float64), ``rgb`` (uint8), ``normals`` (float64),
    ``index`` (int64) and one array per field, with its own type.

    Parameters
    ----------
    path : Path
        Target file.
    cloud : PointCloud
        The cloud.
    compressed : bool
        Deflate the arrays (smaller, slower).

    Raises
    ------
    WriteError
        A field is named like one of the special arrays (``xyz``, ``points``,
        ``colors``, ``colours``, ``normals``) and would be misread.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from ontodetect import point_cloud
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "p.npz"
    >>> sorted(np.load(write_npz(f, point_cloud([[1, 2, 3]], fields={"label": [4]}))).files)
    ['index', 'label', 'xyz']
    """
    path = Path(path)
    if not isinstance(cloud, PointCloud):
        raise WriteError(path, f"expected a PointCloud, got {type(cloud).__name__}")
    arrays: dict[str, NDArray[Any]] = {"xyz": np.asarray(cloud.xyz)}
    if cloud.rgb is not None:
        arrays["rgb"] = np.asarray(cloud.rgb)
    if cloud.normals is not None:
        arrays["normals"] = np.asarray(cloud.normals)
    arrays["index"] = np.asarray(cloud.index)
    for name, values in cloud.fields.items():
        if name in _SPECIAL_KEYS or "/" in name or not name:
            raise WriteError(
                path,
                f"field {name!r} cannot be stored under that name in .npz "
                f"(reserved: {', '.join(sorted(_SPECIAL_KEYS))})",
            )
        arrays[name] = np.asarray(values)
    method = zipfile.ZIP_DEFLATED if compressed else zipfile.ZIP_STORED

    # Written member by member, as numpy.savez does, so that no field name can
    # collide with one of savez's own keyword arguments.
    def write(fh: IO[bytes]) -> None:
        with zipfile.ZipFile(fh, "w", compression=method, allowZip64=True) as archive:
            for name, values in arrays.items():
                with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
                    np.lib.format.write_array(member, values, allow_pickle=False)

    return write_atomically(path, write)
