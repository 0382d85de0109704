"""ASPRS LAS and LAZ lidar files, through laspy (LAZ with the lazrs backend).

Coordinates are stored in LAS as 32-bit integers with a per-file scale and
offset (survey files often use UTM offsets like 500000, 4000000); the reader
applies them in float64, so millimetre steps stay exact far from the origin.
Colours are 16-bit in LAS: the reader keeps the high byte (``v >> 8``), unless
every colour is at most 255 (files written by tools that store 8-bit values in
the 16-bit fields), in which case the values are kept as they are. The writer
stores ``v * 257`` so that 255 becomes 65535 and reading back gives ``v``
exactly.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import struct
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._progress import progress
from ..cloud import PointCloud, point_cloud
from ..errors import CorruptFileError, InvalidParameterError, ReadError, WriteError
from ._atomic import atomic_write
from ._budget import check_points

__all__ = ["read_las", "write_las"]

#: Points decoded per step: bounds memory when a damaged header claims billions.
CHUNK_POINTS = 1 << 20
#: Default coordinate resolution of the writer (1 mm for coordinates in metres).
DEFAULT_SCALE = 0.001
#: Largest integer coordinate a LAS file can hold.
INT32_MAX = 2**31 - 1
#: Longest extra-bytes dimension name allowed by the LAS specification.
MAX_EXTRA_NAME = 32
#: Largest value of an 8-bit colour kept unscaled on reading.
MAX_COLOR8 = 255
#: 16-bit colour = 8-bit colour times this (255 -> 65535).
COLOR8_TO_16 = 257
#: Largest classification of the LAS 1.2 point formats (5 bits).
MAX_LEGACY_CLASS = 31
#: GeoTIFF keys naming the EPSG code of the coordinate system (projected, geographic).
_EPSG_KEYS = (3072, 2048)
#: Values of those keys that are EPSG codes (GeoTIFF 1.1, requirement classes 7 and 8).
_EPSG_RANGE = (1024, 32766)

# Standard dimensions copied into fields when the file has them.
_STANDARD_FIELDS = ("classification", "intensity", "return_number", "point_source_id", "gps_time")
_NORMAL_NAMES = {
    "nx": 0,
    "normal_x": 0,
    "normalx": 0,
    "ny": 1,
    "normal_y": 1,
    "normaly": 1,
    "nz": 2,
    "normal_z": 2,
    "normalz": 2,
}


def _laspy() -> Any:
    import laspy

    return laspy


class _BoundedFile(io.FileIO):
    """A file whose ``read(n)`` never asks for more than what is left.

    A damaged length field (of a variable-length record, say) would otherwise
    make the reader allocate gigabytes before finding out the data is not there.
    """

    def read(self, size: int | None = -1) -> bytes:
        if size is not None and size > 0:
            left = max(os.fstat(self.fileno()).st_size - self.tell(), 0)
            size = min(size, left)
        return super().read(size)


# Public header layout (LAS 1.0-1.4): offsets of the fields checked before laspy
# sees the file, so that damaged counts fail fast instead of looping or allocating.
_SIGNATURE = b"LASF"
_MIN_HEADER = 227
_VLR_HEADER = 54
_EVLR_HEADER = 60
_HEADER_14 = 255
# LAZ marks compressed point formats with these bits of the format id.
_COMPRESSED_BITS = 0xC0
# The LASzip record: its VLR ids, its shortest valid length, the chunk-size value
# meaning "variable", and the largest chunk buffer (points x record bytes) accepted.
_LASZIP_USER = b"laszip encoded"
_LASZIP_RECORD = 22204
_LASZIP_MIN_RECORD = 34
_VARIABLE_CHUNKS = 0xFFFFFFFF
_MAX_CHUNK_BYTES = 1 << 30
#: More variable-length records than any real file has (they are a few each).
_MAX_VLRS = 10_000
# A LAZ chunk table starts with a version and a chunk count (uint32 each).
_CHUNK_TABLE_HEAD = 8


def _check_laszip_record(path: Path, header_size: int, n_vlrs: int, record_size: int) -> None:
    """Refuse a LASzip record whose chunk size would need an impossible buffer."""
    if n_vlrs > _MAX_VLRS:
        raise CorruptFileError(path, f"damaged header: {n_vlrs} variable-length records")
    try:
        with open(path, "rb") as fh:
            at = header_size
            for _ in range(n_vlrs):
                fh.seek(at)
                head = fh.read(_VLR_HEADER)
                if len(head) < _VLR_HEADER:
                    raise CorruptFileError(path, "truncated: a variable-length record is cut short")
                user_id = head[2:18].rstrip(b"\0")
                (record_id, length) = struct.unpack_from("<HH", head, 18)
                if user_id == _LASZIP_USER and record_id == _LASZIP_RECORD:
                    data = fh.read(length)
                    if len(data) < _LASZIP_MIN_RECORD:
                        raise CorruptFileError(path, "damaged LAZ: the LASzip record is too short")
                    (chunk_size,) = struct.unpack_from("<I", data, 12)
                    if chunk_size != _VARIABLE_CHUNKS and chunk_size * max(record_size, 1) > (
                        _MAX_CHUNK_BYTES
                    ):
                        raise CorruptFileError(
                            path,
                            f"damaged LAZ: chunks of {chunk_size} points of {record_size} "
                            "bytes are beyond any real file",
                        )
                    return
                at += _VLR_HEADER + length
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc


def _check_chunk_table(path: Path, size: int, point_offset: int) -> None:
    """Refuse LAZ chunk tables that cannot fit the file.

    The decompressor allocates the whole table up front from its count, and a
    failed allocation there ends the process instead of raising an exception.
    """
    try:
        with open(path, "rb") as fh:
            fh.seek(point_offset)
            raw = fh.read(8)
            if len(raw) < 8:
                raise CorruptFileError(path, "truncated: no LAZ chunk table offset")
            (table_offset,) = struct.unpack("<q", raw)
            if table_offset == -1:  # written at the very end by streaming writers
                fh.seek(max(size - 8, 0))
                (table_offset,) = struct.unpack("<q", fh.read(8).rjust(8, b"\0"))
            if not point_offset + 8 <= table_offset <= size - _CHUNK_TABLE_HEAD:
                raise CorruptFileError(
                    path,
                    f"damaged LAZ: chunk table offset {table_offset} lies outside the "
                    f"{size}-byte file",
                )
            fh.seek(table_offset)
            _version, n_chunks = struct.unpack("<II", fh.read(_CHUNK_TABLE_HEAD))
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    # Every chunk takes at least one byte of the file.
    if n_chunks > size:
        raise CorruptFileError(
            path, f"damaged LAZ: the chunk table claims {n_chunks} chunks in a {size}-byte file"
        )


def _check_header(path: Path, size: int) -> None:
    try:
        with open(path, "rb") as fh:
            head = fh.read(_HEADER_14)
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    if len(head) < _MIN_HEADER or head[:4] != _SIGNATURE:
        raise CorruptFileError(path, "is not a LAS/LAZ file (no 'LASF' header of 227 bytes)")
    minor = head[25]
    header_size, point_offset, n_vlrs = struct.unpack_from("<HII", head, 94)
    if not _MIN_HEADER <= header_size <= point_offset <= size:
        raise CorruptFileError(
            path,
            f"damaged header: header size {header_size} and point data offset "
            f"{point_offset} do not fit a file of {size} bytes",
        )
    if n_vlrs * _VLR_HEADER > point_offset - header_size:
        raise CorruptFileError(
            path,
            f"damaged header: {n_vlrs} variable-length records cannot fit in the "
            f"{point_offset - header_size} bytes before the points",
        )
    if head[104] & _COMPRESSED_BITS:
        _check_laszip_record(path, header_size, n_vlrs, head[105] | head[106] << 8)
        _check_chunk_table(path, size, point_offset)
    if minor >= 4 and len(head) >= _HEADER_14 and header_size >= _HEADER_14:
        first_evlr, n_evlrs = struct.unpack_from("<QI", head, 235)
        if n_evlrs and (first_evlr < point_offset or first_evlr + n_evlrs * _EVLR_HEADER > size):
            raise CorruptFileError(
                path,
                f"damaged header: {n_evlrs} extended records starting at byte "
                f"{first_evlr} do not fit a file of {size} bytes",
            )


def _laspy_errors() -> tuple[type[BaseException], ...]:
    laspy = _laspy()
    errors: list[type[BaseException]] = [
        laspy.errors.LaspyException,
        ValueError,
        TypeError,
        OSError,
        EOFError,
        struct.error,
        IndexError,
        KeyError,
        # OverflowError, and ZeroDivisionError from an extra-bytes descriptor of type 0.
        ArithmeticError,
        AttributeError,
        RuntimeError,
        # A damaged count can still ask for an impossible allocation.
        MemoryError,
    ]
    try:
        import lazrs

        errors.append(lazrs.LazrsError)
    except ImportError:  # pragma: no cover - lazrs is a dependency
        pass
    return tuple(errors)


def _is_decode_error(exc: BaseException, errors: tuple[type[BaseException], ...]) -> bool:
    # The Rust LAZ decoder reports a panic (a slice out of range on damaged data) as
    # pyo3's PanicException, which derives from BaseException and cannot be imported.
    return isinstance(exc, errors) or type(exc).__name__ == "PanicException"


def _field_name(name: str) -> str:
    return re.sub(r"[^0-9a-z_]+", "_", name.strip().lower()).strip("_") or "extra"


def _crs_meta(header: Any) -> dict[str, Any]:
    laspy = _laspy()
    known = laspy.vlrs.known
    meta: dict[str, Any] = {}
    vlrs = list(header.vlrs) + list(getattr(header, "evlrs", None) or [])
    for vlr in vlrs:
        if isinstance(vlr, known.WktCoordinateSystemVlr) and "crs_wkt" not in meta:
            wkt = vlr.string
            if isinstance(wkt, bytes):
                wkt = wkt.decode("latin-1")
            wkt = str(wkt).rstrip("\x00").strip()
            if wkt:
                meta["crs_wkt"] = wkt
        elif isinstance(vlr, known.GeoKeyDirectoryVlr) and "crs_epsg" not in meta:
            codes = {
                key.id: int(key.value_offset)
                for key in getattr(vlr, "geo_keys", [])
                if key.id in _EPSG_KEYS and _EPSG_RANGE[0] <= key.value_offset <= _EPSG_RANGE[1]
            }
            # A projected system, when given, is the one the coordinates are in.
            for key_id in _EPSG_KEYS:
                if key_id in codes:
                    meta["crs_epsg"] = codes[key_id]
                    break
    return meta


def read_las(path: Path, *, on_nonfinite: str = "warn") -> PointCloud:
    """Read a LAS or LAZ file.

    Parameters
    ----------
    path : Path
        ``.las`` or ``.laz`` (any LAS version and point format laspy reads).
    on_nonfinite : {"warn", "drop", "raise"}
        Passed to :func:`~ontodetect.point_cloud` (LAS integers are always finite,
        so this matters only for odd scales).

    Returns
    -------
    PointCloud
        ``xyz`` in float64 (scale and offset applied), ``rgb`` when the point
        format has colours, fields ``classification`` (uint8), ``intensity``
        (uint16), ``return_number`` (uint8), ``point_source_id`` (uint16),
        ``gps_time`` (float64, when present) and every extra-bytes dimension
        (extra dimensions ``nx ny nz`` become normals). ``meta`` holds
        ``point_format``, ``version``, ``scale``, ``offset``, ``point_count`` and,
        when the file has them, ``crs_wkt`` and ``crs_epsg``.

    Raises
    ------
    CorruptFileError
        The file is truncated, its header contradicts its size, laspy cannot
        decode it, or it holds no points.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from ontodetect import point_cloud
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.laz"
    >>> _ = write_las(f, point_cloud([[500000.001, 4000000.002, 12.5]]))
    >>> read_las(f).xyz.tolist()
    [[500000.001, 4000000.002, 12.5]]
    """
    path = Path(path)
    laspy = _laspy()
    errors = _laspy_errors()
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    _check_header(path, size)
    try:
        # The sequential decoder: the parallel one allocates whole chunks up front, and a
        # failed allocation there ends the process instead of raising.
        reader = laspy.open(
            _BoundedFile(path, "rb"), closefd=True, laz_backend=laspy.LazBackend.Lazrs
        )
    except BaseException as exc:
        if not _is_decode_error(exc, errors):
            raise
        raise CorruptFileError(path, f"not a readable LAS/LAZ file ({_describe(exc)})") from exc
    try:
        header = reader.header
        fmt = header.point_format
        count = int(header.point_count)
        if count <= 0:
            raise CorruptFileError(path, "contains no points (the header says 0)")
        check_points(path, count, "the header")
        record = int(fmt.size)
        scales, offsets = np.asarray(header.scales), np.asarray(header.offsets)
        if not (
            np.all(np.isfinite(scales)) and np.all(scales != 0) and np.all(np.isfinite(offsets))
        ):
            raise CorruptFileError(
                path,
                f"damaged header: scale {scales.tolist()} and offset {offsets.tolist()} "
                "must be finite, with non-zero scales",
            )
        if not header.are_points_compressed:
            needed = int(header.offset_to_point_data) + count * record
            if needed > size:
                raise CorruptFileError(
                    path,
                    f"truncated: the header says {count} points of {record} bytes "
                    f"({needed} bytes in all) but the file has {size} bytes",
                )
        dims = set(fmt.dimension_names)
        extra_names = list(fmt.extra_dimension_names)
        has_rgb = {"red", "green", "blue"} <= dims
        xyz_parts: list[NDArray[np.float64]] = []
        rgb_parts: list[NDArray[np.uint16]] = []
        field_parts: dict[str, list[NDArray[Any]]] = {
            name: [] for name in _STANDARD_FIELDS if name in dims
        }
        extra_parts: dict[str, list[NDArray[Any]]] = {name: [] for name in extra_names}
        got = 0
        # Extreme scales can overflow to infinity: such points are dropped (with a
        # warning) by point_cloud rather than stopping the read here.
        with (
            progress(f"Reading {path.name}", total=count) as advance,
            np.errstate(over="ignore", invalid="ignore"),
        ):
            for chunk in reader.chunk_iterator(CHUNK_POINTS):
                n = len(chunk)
                if n == 0:
                    break
                xyz_parts.append(
                    np.column_stack(
                        [
                            np.asarray(chunk.x, dtype=np.float64),
                            np.asarray(chunk.y, dtype=np.float64),
                            np.asarray(chunk.z, dtype=np.float64),
                        ]
                    )
                )
                if has_rgb:
                    rgb_parts.append(
                        np.column_stack(
                            [np.asarray(chunk.red), np.asarray(chunk.green), np.asarray(chunk.blue)]
                        ).astype(np.uint16)
                    )
                for name, parts in field_parts.items():
                    parts.append(np.array(chunk[name]))
                for name, parts in extra_parts.items():
                    parts.append(np.array(chunk[name]))
                got += n
                advance(n)
                if got >= count:
                    break
        meta: dict[str, Any] = {
            "point_format": int(fmt.id),
            "version": str(header.version),
            "scale": [float(s) for s in header.scales],
            "offset": [float(o) for o in header.offsets],
            "point_count": count,
            "compressed": bool(header.are_points_compressed),
        }
        meta.update(_crs_meta(header))
    except CorruptFileError:
        raise
    except BaseException as exc:
        if not _is_decode_error(exc, errors):
            raise
        raise CorruptFileError(path, f"cannot decode the points ({_describe(exc)})") from exc
    finally:
        with contextlib.suppress(*errors):
            reader.close()
    if got != count:
        raise CorruptFileError(
            path, f"truncated: the header says {count} points but only {got} could be read"
        )

    xyz = np.concatenate(xyz_parts)[:count]
    rgb = None
    if has_rgb:
        rgb16 = np.concatenate(rgb_parts)[:count]
        rgb = (rgb16 if int(rgb16.max()) <= MAX_COLOR8 else rgb16 >> 8).astype(np.uint8)
    fields: dict[str, NDArray[Any]] = {}
    for name, parts in field_parts.items():
        fields[name] = np.concatenate(parts)[:count]
    normals_cols: dict[int, NDArray[np.float64]] = {}
    for name, parts in extra_parts.items():
        values = np.concatenate(parts)[:count]
        key = _field_name(name)
        if key in _NORMAL_NAMES and values.ndim == 1:
            with np.errstate(invalid="ignore"):  # signalling NaNs in damaged floats
                normals_cols[_NORMAL_NAMES[key]] = values.astype(np.float64)
            continue
        base, k = key, 1
        while key in fields:
            key, k = f"{base}_{k}", k + 1
        fields[key] = values
    normals = None
    if len(normals_cols) == 3:
        normals = np.column_stack([normals_cols[i] for i in range(3)])
    else:
        for axis, values in normals_cols.items():
            fields["n" + "xyz"[axis] + "_extra"] = values
    return point_cloud(
        xyz,
        rgb=rgb,
        normals=normals,
        fields=fields,
        meta={"source": str(path), **meta},
        on_nonfinite=on_nonfinite,
        copy=False,
    )


def _describe(exc: BaseException) -> str:
    text = str(exc).strip() or type(exc).__name__
    return text if len(text) <= 200 else text[:200] + "..."


# ---------------------------------------------------------------------------------
# Writer
# ---------------------------------------------------------------------------------
def _check_scale(scale: Any) -> NDArray[np.float64]:
    arr = (
        np.broadcast_to(np.asarray(scale, dtype=np.float64), (3,)) if np.ndim(scale) <= 1 else None
    )
    if arr is None or not np.all(np.isfinite(arr)) or not np.all(arr > 0):
        raise InvalidParameterError("scale", "a positive number or three positive numbers", scale)
    return np.array(arr, dtype=np.float64)


def _integral_in(values: NDArray[Any], lo: float, hi: float) -> bool:
    if values.size == 0:
        return True
    v = np.asarray(values)
    if v.dtype.kind == "b":
        v = v.astype(np.int64)
    if v.dtype.kind == "f" and not (np.isfinite(v).all() and np.all(v == np.round(v))):
        return False
    if v.dtype.kind not in "iuf":
        return False
    return float(v.min()) >= lo and float(v.max()) <= hi


def _dim_range(info: Any) -> tuple[float, float] | None:
    kind = info.kind.name
    if kind == "BitField":
        return 0.0, float(2**info.num_bits - 1)
    if kind == "UnsignedInteger":
        return 0.0, float(2**info.num_bits - 1)
    if kind == "SignedInteger":
        return float(-(2 ** (info.num_bits - 1))), float(2 ** (info.num_bits - 1) - 1)
    return None  # floating point


def _choose_format(cloud: PointCloud) -> int:
    has_rgb = cloud.rgb is not None
    has_gps = "gps_time" in cloud.fields
    cls = cloud.fields.get("classification")
    legacy_ok = cls is None or _integral_in(np.asarray(cls), 0, MAX_LEGACY_CLASS)
    rn = cloud.fields.get("return_number")
    legacy_ok = legacy_ok and (rn is None or _integral_in(np.asarray(rn), 0, 7))
    if not legacy_ok:
        return 7 if has_rgb else 6
    return {(False, False): 0, (False, True): 1, (True, False): 2, (True, True): 3}[
        (has_rgb, has_gps)
    ]


def _extra_dtype(values: NDArray[Any]) -> np.dtype[Any]:
    kind = values.dtype.kind
    if kind == "b":
        return np.dtype(np.uint8)
    if kind == "f" and values.dtype.itemsize < 4:
        return np.dtype(np.float32)
    return values.dtype


def write_las(
    path: Path,
    cloud: PointCloud,
    *,
    scale: float | tuple[float, float, float] = DEFAULT_SCALE,
    offset: tuple[float, float, float] | None = None,
    compress: bool | None = None,
) -> Path:
    """Write a cloud as LAS, or LAZ (compressed) when the name ends in ``.laz``.

    Parameters
    ----------
    path : Path
        Target file.
    cloud : PointCloud
        Points, colours (written as 16-bit ``v * 257``), normals (extra bytes
        ``nx ny nz``, float32) and fields.
    scale : float or (3,) float
        Coordinate resolution; coordinates are rounded to a multiple of it.
    offset : (3,) float, optional
        Coordinate offset; ``floor(min)`` of the points by default.
    compress : bool, optional
        Force LAZ (True) or LAS (False); by default from the extension.

    Returns
    -------
    Path
        The written file (replaced atomically).

    Notes
    -----
    The point format is the smallest that holds the data: 0-3 (LAS 1.2) with
    colours (2, 3) and GPS time (1, 3); 6 or 7 (LAS 1.4) when classifications
    exceed 31 or return numbers exceed 7. Fields named like a standard
    dimension of that format (``classification``, ``intensity``,
    ``return_number``, ``point_source_id``, ``gps_time``, ``user_data``...)
    go into it; every other field is stored as an extra-bytes dimension of its
    own dtype, (n, k) fields as ``name_0 .. name_k-1``. ``meta["crs_wkt"]`` is
    written as a WKT coordinate system record.

    Raises
    ------
    WriteError
        A value does not fit its LAS dimension (the message names the field, the
        range and the values found), the coordinates do not fit 32-bit integers
        at this scale, or the file cannot be written.
    """
    path = Path(path)
    laspy = _laspy()
    scales = _check_scale(scale)
    xyz = np.asarray(cloud.xyz, dtype=np.float64)
    n = len(cloud)
    if offset is None:
        offsets = np.floor(xyz.min(axis=0)) if n else np.zeros(3)
    else:
        offsets = np.asarray(offset, dtype=np.float64)
        if offsets.shape != (3,) or not np.all(np.isfinite(offsets)):
            raise InvalidParameterError("offset", "three finite numbers", offset)
    ints = np.round((xyz - offsets) / scales)
    if n and (np.abs(ints).max() > INT32_MAX):
        raise WriteError(
            path,
            f"coordinates span {np.ptp(xyz, axis=0).max():g} units, too much for 32-bit "
            f"integers at scale {scales.tolist()}; use a larger scale",
        )
    compress = path.suffix.lower() == ".laz" if compress is None else bool(compress)
    point_format = _choose_format(cloud)
    version = "1.4" if point_format >= 6 else "1.2"
    header = laspy.LasHeader(point_format=point_format, version=version)
    header.scales = scales
    header.offsets = offsets
    fmt = laspy.PointFormat(point_format)
    standard = {d.name: d for d in fmt.dimensions if d.name not in ("X", "Y", "Z")}

    standard_values: dict[str, NDArray[Any]] = {}
    extra_values: dict[str, NDArray[Any]] = {}
    for name, values in cloud.fields.items():
        arr = np.asarray(values)
        if name in standard and arr.ndim == 1:
            rng = _dim_range(standard[name])
            if rng is not None and not _integral_in(arr, *rng):
                lo, hi = (float(arr.min()), float(arr.max())) if arr.size else (0.0, 0.0)
                raise WriteError(
                    path,
                    f"field {name!r} must hold integers {rng[0]:g}..{rng[1]:g} to be the "
                    f"LAS {name} dimension, found values {lo:g}..{hi:g}; rename the field to "
                    "store it as an extra dimension",
                )
            standard_values[name] = arr
            continue
        flat = arr.reshape(n, -1) if arr.ndim > 1 else arr[:, None]
        for k in range(flat.shape[1]):
            key = name if arr.ndim == 1 else f"{name}_{k}"
            extra_values[key] = np.ascontiguousarray(flat[:, k])
    if cloud.normals is not None:
        for i, key in enumerate(("nx", "ny", "nz")):
            extra_values[key] = cloud.normals[:, i].astype(np.float32)
    for key in extra_values:
        if len(key.encode("utf-8")) > MAX_EXTRA_NAME or key.lower() in ("x", "y", "z"):
            raise WriteError(
                path,
                f"field name {key!r} cannot be a LAS extra dimension "
                f"(at most {MAX_EXTRA_NAME} bytes, not x/y/z)",
            )
    try:
        for key, values in extra_values.items():
            header.add_extra_dim(laspy.ExtraBytesParams(name=key, type=_extra_dtype(values)))
        wkt = cloud.meta.get("crs_wkt")
        if isinstance(wkt, str) and wkt:
            header.vlrs.append(laspy.vlrs.known.WktCoordinateSystemVlr(wkt))
            if point_format >= 6:
                header.global_encoding.wkt = True
        las = laspy.LasData(header)
        las.X = ints[:, 0].astype(np.int32)
        las.Y = ints[:, 1].astype(np.int32)
        las.Z = ints[:, 2].astype(np.int32)
        if cloud.rgb is not None:
            rgb16 = cloud.rgb.astype(np.uint16) * COLOR8_TO_16
            las.red, las.green, las.blue = rgb16[:, 0], rgb16[:, 1], rgb16[:, 2]
        for name, values in standard_values.items():
            info = standard[name]
            target = np.float64 if info.kind.name == "FloatingPoint" else np.int64
            las[name] = np.asarray(values).astype(target)
        for key, values in extra_values.items():
            las[key] = values.astype(_extra_dtype(values))
        with atomic_write(path, "wb") as fh:
            las.write(fh, do_compress=compress)
    except WriteError:
        raise
    except BaseException as exc:
        if not _is_decode_error(exc, _laspy_errors()):
            raise
        raise WriteError(path, f"laspy could not write the file ({_describe(exc)})") from exc
    return path
