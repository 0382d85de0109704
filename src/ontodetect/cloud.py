"""The point cloud every stage passes along.

A :class:`PointCloud` holds float64 coordinates, optional uint8 colours and
normals, named per-point fields (labels, intensity, instance ids) and, for every
point, its row in the file it was read from, so that any result can be reported
against the input file even after points were dropped. Arrays are copied on the
way in and made read-only: nothing in ontodetect changes a user's array, and a
cloud cannot be changed behind the back of a stage that holds it.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._rules import ON_NONFINITE, check_param
from .errors import InvalidParameterError
from .geometry import as_points

__all__ = ["DataWarning", "PointCloud", "pixel_grid", "point_cloud", "sensor_position"]

#: Names that are not allowed as extra fields because the cloud stores them itself.
RESERVED_FIELDS = frozenset(
    {
        "x",
        "y",
        "z",
        "red",
        "green",
        "blue",
        "rgb",
        "rgba",
        "nx",
        "ny",
        "nz",
        "normal_x",
        "normal_y",
        "normal_z",
        "index",
    }
)


class DataWarning(UserWarning):
    """Something in the input was repaired (for example non-finite points dropped)."""


def _frozen(a: NDArray[Any]) -> NDArray[Any]:
    a.flags.writeable = False
    return a


class PointCloud:
    """An immutable point cloud.

    Build one with :func:`point_cloud`, which validates and copies its inputs;
    the constructor itself trusts its arguments.

    Attributes
    ----------
    xyz : (n, 3) float64
        Coordinates.
    rgb : (n, 3) uint8 or None
        Colours, 0..255.
    normals : (n, 3) float64 or None
        Unit normals.
    fields : mapping of str to (n, ...) array
        Extra per-point values (``label``, ``instance``, ``intensity``...).
    index : (n,) int64
        Row of every point in the file it came from (``arange(n)`` when nothing
        was dropped; then it is only built when first asked for, which saves a
        large read the time and memory of one more array).
    meta : mapping of str to object
        Where the cloud came from (``source``, ``format``, organized ``width``
        and ``height``, ...).
    """

    __slots__ = ("_index", "fields", "meta", "normals", "rgb", "xyz")

    xyz: NDArray[np.float64]
    rgb: NDArray[np.uint8] | None
    normals: NDArray[np.float64] | None
    fields: Mapping[str, NDArray[Any]]
    meta: Mapping[str, Any]

    def __init__(
        self,
        xyz: NDArray[np.float64],
        rgb: NDArray[np.uint8] | None = None,
        normals: NDArray[np.float64] | None = None,
        fields: Mapping[str, NDArray[Any]] | None = None,
        index: NDArray[np.int64] | None = None,
        meta: Mapping[str, Any] | None = None,
    ) -> None:
        setter = object.__setattr__
        setter(self, "xyz", xyz)
        setter(self, "rgb", rgb)
        setter(self, "normals", normals)
        setter(self, "fields", fields if fields is not None else MappingProxyType({}))
        setter(self, "_index", index)
        setter(self, "meta", meta if meta is not None else MappingProxyType({}))

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"PointCloud is immutable: cannot set {name!r}")

    def __reduce__(self) -> tuple[Any, ...]:
        # For worker processes: the read-only mappings travel as plain dicts.
        return (
            _rebuild,
            (self.xyz, self.rgb, self.normals, dict(self.fields), self._index, dict(self.meta)),
        )

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"PointCloud is immutable: cannot delete {name!r}")

    @property
    def index(self) -> NDArray[np.int64]:
        """(n,) int64: row of every point in its source file."""
        if self._index is None:
            object.__setattr__(self, "_index", _frozen(np.arange(len(self), dtype=np.int64)))
        return self._index

    @property
    def is_complete(self) -> bool:
        """True when the cloud holds every row of its file in order (no point dropped)."""
        return self._index is None or (
            len(self._index) == 0
            or (
                self._index[0] == 0
                and self._index[-1] == len(self) - 1
                and bool(np.all(np.diff(self._index) == 1))
            )
        )

    # -- basic facts -----------------------------------------------------------------
    def __len__(self) -> int:
        return int(self.xyz.shape[0])

    @property
    def num_points(self) -> int:
        """Number of points."""
        return len(self)

    @property
    def has_colors(self) -> bool:
        return self.rgb is not None

    @property
    def has_normals(self) -> bool:
        return self.normals is not None

    @property
    def bounds(self) -> NDArray[np.float64]:
        """(2, 3) float: minimum and maximum corner of the axis-aligned box."""
        if len(self) == 0:
            return np.zeros((2, 3))
        return np.stack([self.xyz.min(axis=0), self.xyz.max(axis=0)])

    def __repr__(self) -> str:
        extras = []
        if self.rgb is not None:
            extras.append("rgb")
        if self.normals is not None:
            extras.append("normals")
        extras += list(self.fields)
        src = self.meta.get("source")
        tail = f", source={src!r}" if src else ""
        return f"PointCloud(n={len(self)}, with={extras}{tail})"

    # -- derived clouds --------------------------------------------------------------
    def select(self, which: ArrayLike) -> PointCloud:
        """A new cloud with the chosen points, keeping their rows in the original file.

        Parameters
        ----------
        which : (n,) bool or (k,) int
            A mask over the points or the indices to keep.

        Examples
        --------
        >>> c = point_cloud([[0, 0, 0], [1, 0, 0], [2, 0, 0]])
        >>> c.select([2, 0]).index.tolist()
        [2, 0]
        """
        sel = np.asarray(which)
        if sel.dtype == bool:
            if sel.shape != (len(self),):
                raise InvalidParameterError(
                    "which", f"a boolean mask of shape ({len(self)},)", f"shape {sel.shape}"
                )
        elif sel.size and not np.issubdtype(sel.dtype, np.integer):
            raise InvalidParameterError("which", "a boolean mask or integer indices", sel.dtype)
        else:
            sel = sel.astype(np.intp, copy=False)
            if sel.size and (sel.min() < -len(self) or sel.max() >= len(self)):
                raise InvalidParameterError(
                    "which", f"indices in [0, {len(self)})", f"{sel.min()}..{sel.max()}"
                )
        return PointCloud(
            xyz=_frozen(self.xyz[sel]),
            rgb=None if self.rgb is None else _frozen(self.rgb[sel]),
            normals=None if self.normals is None else _frozen(self.normals[sel]),
            fields=MappingProxyType({k: _frozen(v[sel]) for k, v in self.fields.items()}),
            index=_frozen(self.index[sel]),
            meta=self.meta,
        )

    def replace(self, **changes: Any) -> PointCloud:
        """A new cloud with some attributes replaced, validated like :func:`point_cloud`.

        Examples
        --------
        >>> c = point_cloud([[0, 0, 0], [1, 0, 0]])
        >>> c.replace(xyz=c.xyz * 2).xyz[1].tolist()
        [2.0, 0.0, 0.0]
        """
        current = {
            "xyz": self.xyz,
            "rgb": self.rgb,
            "normals": self.normals,
            "fields": dict(self.fields),
            "index": self._index,
            "meta": dict(self.meta),
        }
        unknown = set(changes) - set(current)
        if unknown:
            raise InvalidParameterError("changes", f"among {sorted(current)}", sorted(unknown))
        current.update(changes)
        return point_cloud(**current, on_nonfinite="raise")

    def with_fields(self, **new_fields: ArrayLike) -> PointCloud:
        """A new cloud with extra per-point fields added or replaced."""
        merged = dict(self.fields)
        merged.update(new_fields)
        return self.replace(fields=merged)

    def with_meta(self, **meta: Any) -> PointCloud:
        """A new cloud sharing the arrays, with entries added to :attr:`meta`."""
        merged = dict(self.meta)
        merged.update(meta)
        return PointCloud(
            self.xyz, self.rgb, self.normals, self.fields, self._index, MappingProxyType(merged)
        )

    # -- Open3D ----------------------------------------------------------------------
    def to_open3d(self) -> Any:
        """The cloud as an ``open3d.geometry.PointCloud`` (colours scaled to 0..1)."""
        import open3d as o3d

        pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.array(self.xyz)))
        if self.rgb is not None:
            pc.colors = o3d.utility.Vector3dVector(self.rgb.astype(np.float64) / 255.0)
        if self.normals is not None:
            pc.normals = o3d.utility.Vector3dVector(np.array(self.normals))
        return pc


def _as_colors(a: ArrayLike, n: int, copy: bool) -> NDArray[np.uint8]:
    arr = np.asarray(a)
    if arr.ndim != 2 or arr.shape[0] != n or arr.shape[1] not in (3, 4):
        raise InvalidParameterError("rgb", f"an array of shape ({n}, 3)", f"shape {arr.shape}")
    arr = arr[:, :3]
    if arr.dtype == np.uint8:
        return np.array(arr, copy=True) if copy else np.ascontiguousarray(arr)
    if arr.dtype.kind == "f":
        finite = np.isfinite(arr)
        if not finite.all():
            raise InvalidParameterError("rgb", "finite colour values", "NaN or Inf")
        # Floats in 0..1 are the usual convention; anything larger is taken as 0..255.
        scale = 255.0 if arr.size == 0 or float(arr.max()) <= 1.0 else 1.0
        return np.clip(np.rint(arr * scale), 0, 255).astype(np.uint8)
    if arr.dtype.kind in "iu":
        top = int(arr.max()) if arr.size else 0
        if top > 255:  # 16-bit colours (LAS, some PLY files)
            return (arr.astype(np.uint32) >> 8).astype(np.uint8)
        if arr.size and int(arr.min()) < 0:
            raise InvalidParameterError("rgb", "values in 0..255", f"minimum {int(arr.min())}")
        return arr.astype(np.uint8)
    raise InvalidParameterError("rgb", "a numeric array", f"dtype {arr.dtype}")


def _rebuild(
    xyz: NDArray[np.float64],
    rgb: NDArray[np.uint8] | None,
    normals: NDArray[np.float64] | None,
    fields: dict[str, NDArray[Any]],
    index: NDArray[np.int64] | None,
    meta: dict[str, Any],
) -> PointCloud:
    return PointCloud(xyz, rgb, normals, MappingProxyType(fields), index, MappingProxyType(meta))


def point_cloud(
    xyz: ArrayLike,
    rgb: ArrayLike | None = None,
    normals: ArrayLike | None = None,
    fields: Mapping[str, ArrayLike] | None = None,
    index: ArrayLike | None = None,
    meta: Mapping[str, Any] | None = None,
    *,
    on_nonfinite: str = "warn",
    copy: bool = True,
) -> PointCloud:
    """Validate arrays and build a :class:`PointCloud`.

    Parameters
    ----------
    xyz : (n, 3) float
        Coordinates (any real dtype; stored as float64).
    rgb : (n, 3) uint8 or float, optional
        Colours: uint8 0..255, floats 0..1 (or 0..255), or 16-bit integers.
    normals : (n, 3) float, optional
        Normals.
    fields : mapping of str to (n, ...) array, optional
        Extra per-point values.
    index : (n,) int, optional
        Row of each point in its source file; ``arange(n)`` by default.
    meta : mapping, optional
        Free-form description of the source.
    on_nonfinite : {"warn", "drop", "raise"}
        What to do with points whose coordinates are NaN or infinite: drop them
        with a :class:`DataWarning` that counts them ("warn"; no warning when none
        is left: the empty cloud says it), drop them
        silently ("drop", for formats where missing points are normal), or
        raise :class:`~ontodetect.errors.InvalidParameterError` ("raise").
        Dropped points keep their place in :attr:`PointCloud.index`.
    copy : bool
        Copy the inputs (default). Readers that own their arrays pass False.

    Returns
    -------
    PointCloud

    Examples
    --------
    >>> c = point_cloud([[0, 0, 0], [float("nan"), 0, 0], [1, 2, 3]], on_nonfinite="drop")
    >>> len(c), c.index.tolist()
    (2, [0, 2])
    """
    check_param("on_nonfinite", ON_NONFINITE, on_nonfinite)
    pts = as_points(xyz, "xyz", copy=copy)
    n = pts.shape[0]
    cols = None if rgb is None else _as_colors(rgb, n, copy)
    nrm = None if normals is None else as_points(normals, "normals", n=n, copy=copy)
    extra: dict[str, NDArray[Any]] = {}
    for name, values in (fields or {}).items():
        if not isinstance(name, str) or not name:
            raise InvalidParameterError("fields", "keyed by non-empty strings", name)
        if name in RESERVED_FIELDS:
            raise InvalidParameterError(f"fields[{name!r}]", "not a reserved name", name)
        arr = np.array(values, copy=True) if copy else np.asarray(values)
        if arr.ndim == 0 or arr.shape[0] != n:
            raise InvalidParameterError(
                f"fields[{name!r}]", f"an array with {n} rows", f"shape {arr.shape}"
            )
        if arr.dtype.kind not in "biuf":
            raise InvalidParameterError(f"fields[{name!r}]", "numeric", f"dtype {arr.dtype}")
        extra[name] = arr
    idx: NDArray[np.int64] | None = None
    if index is not None:
        idx = np.array(index, dtype=np.int64, copy=True) if copy else np.asarray(index, np.int64)
        if idx.shape != (n,):
            raise InvalidParameterError("index", f"an array of shape ({n},)", f"shape {idx.shape}")

    # One sum is far cheaper than a per-row test; it overflows only for absurd values,
    # and then the per-row test decides.
    with np.errstate(over="ignore", invalid="ignore"):
        total_finite = bool(np.isfinite(pts.sum()))
    finite = np.ones(n, dtype=bool) if total_finite else np.isfinite(pts).all(axis=1)
    if not finite.all():
        if idx is None:
            idx = np.arange(n, dtype=np.int64)
        bad = int(n - finite.sum())
        if on_nonfinite == "raise":
            raise InvalidParameterError("xyz", "finite coordinates", f"{bad} NaN/Inf points")
        if on_nonfinite == "warn" and bad < n:  # none left: whoever needs points says so
            src = (meta or {}).get("source", "input")
            warnings.warn(
                f"{src}: dropped {bad} of {n} points with NaN or infinite coordinates",
                DataWarning,
                stacklevel=2,
            )
        pts = pts[finite]
        cols = None if cols is None else cols[finite]
        nrm = None if nrm is None else nrm[finite]
        extra = {k: v[finite] for k, v in extra.items()}
        idx = idx[finite]

    return PointCloud(
        xyz=_frozen(pts),
        rgb=None if cols is None else _frozen(cols),
        normals=None if nrm is None else _frozen(nrm),
        fields=MappingProxyType({k: _frozen(v) for k, v in extra.items()}),
        index=None if idx is None else _frozen(idx),
        meta=MappingProxyType(dict(meta or {})),
    )


# -- single views --------------------------------------------------------------------------
def sensor_position(cloud: PointCloud) -> NDArray[np.float64] | None:
    """(3,) position of the sensor in the cloud's frame when the cloud is one view.

    ``cloud.meta["sensor_position"]`` when set (``ontodetect detect --viewpoint``, a
    simulated frame read by :func:`ontodetect.synth.load_synth`), else the translation
    of an organized cloud's ``viewpoint`` (a PCD camera frame: its ``VIEWPOINT``, the
    origin by default); None for anything else, such as a scan fused from many views,
    where no one position saw every point.

    Examples
    --------
    >>> frame = point_cloud([[0.0, 0.0, 1.0]]).with_meta(
    ...     organized=True, viewpoint=[0.1, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
    >>> sensor_position(frame).tolist(), sensor_position(point_cloud([[0.0, 0.0, 1.0]]))
    ([0.1, 0.0, 0.0], None)
    """
    meta = cloud.meta
    position = meta.get("sensor_position")
    if position is None and meta.get("organized") and meta.get("viewpoint") is not None:
        position = list(meta["viewpoint"])[:3]
    return None if position is None else as_position(position)


def as_position(value: Any, name: str = "viewpoint") -> NDArray[np.float64]:
    """``value`` as a (3,) float position, or :class:`InvalidParameterError` naming ``name``."""
    try:
        out = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        out = np.zeros(0)
    if out.shape != (3,) or not np.all(np.isfinite(out)):
        raise InvalidParameterError(name, "three finite numbers (x, y, z)", value)
    return out


def pixel_grid(cloud: PointCloud) -> tuple[NDArray[np.int64], int, int] | None:
    """Pixel of every point and the image size, when the cloud is an organized frame.

    The pixel is row-major in a ``meta["width"]`` × ``meta["height"]`` grid: the
    ``pixel`` field when there is one (a simulated frame in the world frame), else the
    point's row when ``meta["organized"]`` (a PCD frame, whose missing pixels were
    dropped). None when the cloud is not a frame.

    Examples
    --------
    >>> frame = point_cloud([[0.0, 0.0, 1.0], [0.0, 0.1, 1.0]], index=[1, 5]).with_meta(
    ...     organized=True, width=4, height=2)
    >>> pixels, width, height = pixel_grid(frame)
    >>> pixels.tolist(), width, height
    ([1, 5], 4, 2)
    """
    meta = cloud.meta
    width, height = meta.get("width"), meta.get("height")
    if not isinstance(width, (int, np.integer)) or not isinstance(height, (int, np.integer)):
        return None
    if "pixel" in cloud.fields:
        pixels = np.asarray(cloud.fields["pixel"], dtype=np.int64)
    elif meta.get("organized"):
        pixels = np.asarray(cloud.index, dtype=np.int64)
    else:
        return None
    if int(height) < 2 or not len(pixels) or pixels.min() < 0 or pixels.max() >= width * height:
        return None
    return pixels, int(width), int(height)
