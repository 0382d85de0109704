"""Reading and writing point clouds and labelled scans.

Every format has one reader (and some a writer) registered in :data:`READERS`
and :data:`WRITERS`; :func:`read_cloud` and :func:`write_cloud` dispatch by the
file's extension, its name pattern (``*_vert.npy``, ``scanNNN.3d``), the layout
of a folder (ScanNet, S3DIS), or an explicit ``format=``. Modules are imported
only when their format is used, so optional heavy libraries (laspy) cost nothing
otherwise.

Readers return a :class:`~ontodetect.cloud.PointCloud`; on any problem with the
file they raise a :class:`~ontodetect.errors.ReadError` subclass whose message
names the file and the problem.

Beside point clouds: photographs of a scene as grey levels (:func:`read_image`,
:func:`image_files`) and fitted models as numeric arrays with a JSON header, never
pickled (:func:`write_array_archive`, :func:`read_array_archive`).
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..cloud import PointCloud
from ..errors import (
    CorruptFileError,
    OntoDetectError,
    ReadError,
    UnsupportedFormatError,
    WriteError,
)
from ._arrays import read_array_archive, write_array_archive
from ._atomic import (
    RUN_MARKER,
    atomic_write,
    atomic_write_bytes,
    atomic_write_text,
    check_output_folder,
    make_folder,
    staged_folder,
)
from ._budget import MIN_SCAN_POINTS, check_enough_points
from ._detections import (
    DETECTIONS_FORMAT,
    detections_schema,
    read_detections,
    validate_detections,
    write_detections,
    write_timings,
)
from ._exports import (
    EXPORTERS,
    export_detections,
    read_box_table,
    read_scannet_instances,
    write_box_table,
    write_scannet_instances,
)
from ._image import image_files, read_image
from ._inputs import expand_inputs as _expand_inputs
from ._layouts import DATASET_FORMATS
from ._textfile import regular_file

__all__ = [
    "DATASET_FORMATS",
    "DETECTIONS_FORMAT",
    "EXPORTERS",
    "FORMATS",
    "MIN_SCAN_POINTS",
    "READERS",
    "RUN_MARKER",
    "WRITERS",
    "FormatInfo",
    "atomic_write",
    "atomic_write_bytes",
    "atomic_write_text",
    "check_output_folder",
    "detect_format",
    "detections_schema",
    "expand_inputs",
    "export_detections",
    "image_files",
    "make_folder",
    "read_array_archive",
    "read_box_table",
    "read_cloud",
    "read_detections",
    "read_image",
    "read_points",
    "read_scannet_instances",
    "staged_folder",
    "supported_formats",
    "validate_detections",
    "write_array_archive",
    "write_box_table",
    "write_cloud",
    "write_detections",
    "write_mesh",
    "write_scannet_instances",
    "write_timings",
]


@dataclass(frozen=True)
class FormatInfo:
    """One registered format: where its reader and writer live and what it is."""

    name: str
    module: str
    reader: str | None
    writer: str | None
    extensions: tuple[str, ...]
    description: str


#: Every format ontodetect knows, by name.
FORMATS: dict[str, FormatInfo] = {
    f.name: f
    for f in [
        FormatInfo(
            "ply",
            "_ply",
            "read_ply",
            "write_ply",
            (".ply",),
            "Stanford PLY, ascii or binary; mesh vertices are points",
        ),
        FormatInfo(
            "pcd",
            "_pcd",
            "read_pcd",
            "write_pcd",
            (".pcd",),
            "PCL point cloud data: ascii, binary, binary_compressed",
        ),
        FormatInfo(
            "text",
            "_text",
            "read_text",
            "write_text",
            (".xyz", ".txt", ".csv", ".pts"),
            "columns x y z [r g b] [extra], whitespace or comma separated",
        ),
        FormatInfo(
            "npy",
            "_numpy",
            "read_npy",
            "write_npy",
            (".npy",),
            "NumPy array (n, 3) xyz or (n, 6) xyz rgb",
        ),
        FormatInfo(
            "npz",
            "_numpy",
            "read_npz",
            "write_npz",
            (".npz",),
            "NumPy archive with xyz (or points) and optional rgb, normals, fields",
        ),
        FormatInfo(
            "las", "_las", "read_las", "write_las", (".las", ".laz"), "ASPRS LAS / LAZ lidar files"
        ),
        FormatInfo(
            "3dtk",
            "_threedtk",
            "read_3dtk",
            None,
            (".3d",),
            "3DTK scan (scanNNN.3d + scanNNN.pose), cm, left-handed y-up",
        ),
        FormatInfo(
            "scannet",
            "_scannet",
            "read_scannet",
            None,
            (),
            "ScanNet release scan: *_vh_clean_2.ply + aggregation + segs + label tsv",
        ),
        FormatInfo(
            "scannet-votenet",
            "_scannet",
            "read_scannet_votenet",
            None,
            ("_vert.npy",),
            "ScanNet as preprocessed for VoteNet: *_vert.npy, *_sem_label.npy, *_ins_label.npy",
        ),
        FormatInfo(
            "sunrgbd-votenet",
            "_sunrgbd",
            "read_sunrgbd_votenet",
            None,
            ("_pc.npz",),
            "SUN RGB-D frames as preprocessed for VoteNet: *_pc.npz, *_bbox.npy (oriented boxes)",
        ),
        FormatInfo(
            "s3dis",
            "_s3dis",
            "read_s3dis",
            None,
            (),
            "S3DIS room folder with Annotations/<class>_<k>.txt",
        ),
    ]
}


def _load(info: FormatInfo, attr: str | None, path: Path, what: str) -> Callable[..., Any]:
    if attr is None:
        raise UnsupportedFormatError(
            path,
            f"format {info.name!r} cannot be {what}",
            [f.name for f in FORMATS.values() if (f.writer if what == "written" else f.reader)],
        )
    module = importlib.import_module(f"{__name__}.{info.module}")
    return getattr(module, attr)


class _Registry(dict):
    """Name -> callable, importing the implementing module on first use."""

    def __init__(self, attr: str) -> None:
        super().__init__()
        self._attr = attr

    def __missing__(self, name: str) -> Callable[..., Any]:
        info = FORMATS.get(name)
        if info is None or getattr(info, self._attr) is None:
            raise KeyError(name)
        fn = _load(info, getattr(info, self._attr), Path(name), "read")
        self[name] = fn
        return fn

    def __contains__(self, name: object) -> bool:
        info = FORMATS.get(name)  # type: ignore[arg-type]
        return info is not None and getattr(info, self._attr) is not None

    def keys(self):  # type: ignore[override]
        return [n for n in FORMATS if n in self]


#: Format name -> reader ``fn(path, **options) -> PointCloud``.
READERS: dict[str, Callable[..., PointCloud]] = _Registry("reader")
#: Format name -> writer ``fn(path, cloud, **options) -> Path``.
WRITERS: dict[str, Callable[..., Path]] = _Registry("writer")


def expand_inputs(paths: Iterable[str | os.PathLike[str]]) -> list[Path]:
    """The scans that paths, folders of scans and glob patterns name, in order, each once.

    A file or a folder that is one scan (ScanNet, S3DIS, 3DTK) is itself; any other folder
    stands for the readable files in it, sorted; a path that does not exist but holds
    ``*``, ``?`` or ``[`` is a glob pattern.
    """
    return _expand_inputs(paths, detect_format)


def supported_formats(kind: str = "read") -> list[str]:
    """Names of the formats that can be read (``kind="read"``) or written (``"write"``)."""
    attr = "reader" if kind == "read" else "writer"
    return [n for n, f in FORMATS.items() if getattr(f, attr) is not None]


def detect_format(path: str | os.PathLike[str]) -> str:
    """Guess a file's or folder's format from its name and, for folders, its layout.

    Examples
    --------
    >>> detect_format("room/scene0000_00_vert.npy")
    'scannet-votenet'
    >>> detect_format("scan.laz")
    'las'
    """
    p = Path(path)
    name = p.name.lower()
    if p.is_dir():
        if (p / "Annotations").is_dir():
            return "s3dis"
        if any(p.glob("*_vh_clean_2.ply")):
            return "scannet"
        if any(p.glob("*.3d")):
            return "3dtk"
        raise UnsupportedFormatError(
            p,
            "is a folder that is neither a ScanNet scan, an S3DIS room nor a 3DTK scan folder",
            supported_formats(),
        )
    if name.endswith(("_vert.npy", "_sem_label.npy", "_ins_label.npy")):
        return "scannet-votenet"
    if name.endswith("_bbox.npy") and p.with_name(name[: -len("_bbox.npy")] + "_pc.npz").exists():
        return "sunrgbd-votenet"
    if name.endswith("_vh_clean_2.ply") and any(p.parent.glob("*.aggregation.json")):
        return "scannet"
    suffix = p.suffix.lower()
    for info in FORMATS.values():
        if suffix and suffix in info.extensions:
            return info.name
    raise UnsupportedFormatError(
        p, f"unknown file extension {p.suffix or '(none)'!r}", supported_formats()
    )


def read_cloud(
    path: str | os.PathLike[str], format: str | None = None, **options: Any
) -> PointCloud:
    """Read a point cloud or labelled scan.

    Parameters
    ----------
    path : str or PathLike
        A file, or a folder for the ScanNet, S3DIS and 3DTK layouts.
    format : str, optional
        One of :func:`supported_formats`; guessed from ``path`` when omitted.
    **options
        Passed to the format's reader.

    Returns
    -------
    PointCloud
        With ``meta["source"]`` and ``meta["format"]`` set.

    Raises
    ------
    ReadError
        The file is missing, unreadable, corrupt, or of an unsupported format.
    """
    p = Path(path)
    try:
        p.stat()
    except FileNotFoundError:
        raise ReadError(p, "no such file or folder") from None
    except PermissionError:
        raise ReadError(p, "permission denied (a folder on the way cannot be entered)") from None
    except OSError as exc:
        raise ReadError(p, f"cannot be looked at ({exc.strerror or exc})") from None
    fmt = format.lower() if format else detect_format(p)
    if fmt not in FORMATS or FORMATS[fmt].reader is None:
        raise UnsupportedFormatError(p, f"unknown format {format!r}", supported_formats())
    if p.is_dir():
        if fmt not in ("scannet", "s3dis", "3dtk"):
            raise ReadError(p, f"is a folder, but format {fmt!r} reads a single file")
        if not os.access(p, os.R_OK | os.X_OK):
            raise ReadError(p, "permission denied (the folder cannot be listed)")
    else:
        # Before opening: a FIFO would block and /dev/zero never ends.
        regular_file(p, f"{fmt} file")
    try:
        cloud = READERS[fmt](p, **options)
    except PermissionError as exc:
        raise ReadError(exc.filename or p, "permission denied") from None
    if len(cloud) == 0:  # every point had NaN or infinite coordinates
        raise CorruptFileError(p, "contains no points with finite coordinates")
    meta = {"source": str(p), "format": fmt}
    meta.update({k: v for k, v in cloud.meta.items() if k not in meta})
    return cloud.with_meta(**meta)


#: Layouts whose reader, given ``labels=None``, reads its labels only when their files are
#: there (:func:`read_points`).
LABELS_WHEN_PRESENT = ("scannet-votenet", "sunrgbd-votenet")


def read_points(
    path: str | os.PathLike[str],
    format: str | None = None,
    *,
    min_points: int = 1,
    **options: Any,
) -> PointCloud:
    """:func:`read_cloud`, but a scan of a VoteNet layout whose label files are missing (a
    ScanNet test scan, a SUN RGB-D frame without boxes) is read without its labels: what
    detection needs is the points (``detect``, ``segment``, ``info``, a batch, tiles).

    ``format`` is a reader's name or None (guessed from the path); ``options`` go to the
    reader, as :func:`read_cloud`'s do. A cloud with fewer than ``min_points`` points with
    finite coordinates is refused with a :class:`~ontodetect.errors.ReadError` naming the
    file (:data:`MIN_SCAN_POINTS` for detection and segmentation; an empty cloud always is).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from ontodetect import point_cloud
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "a.ply"
    >>> _ = write_cloud(f, point_cloud([[0, 0, 0], [1, 0, 0], [0, 1, 0]]))
    >>> len(read_points(f))
    3
    >>> read_points(f, min_points=MIN_SCAN_POINTS)
    Traceback (most recent call last):
    ...
    ontodetect.errors.ReadError: ...a.ply: holds only 3 points with finite coordinates; ...
    """
    layout = format
    if layout is None:
        try:
            layout = detect_format(path)
        except (OntoDetectError, OSError):  # read_cloud says it, after its checks of the path
            layout = None
    if layout in LABELS_WHEN_PRESENT:
        options = {"labels": None, **options}
    cloud = read_cloud(path, format=format, **options)
    check_enough_points(path, len(cloud), min_points)
    return cloud


def write_cloud(
    path: str | os.PathLike[str], cloud: PointCloud, format: str | None = None, **options: Any
) -> Path:
    """Write a point cloud atomically (temporary file, then rename).

    Parameters
    ----------
    path : str or PathLike
        Target file; its extension chooses the format unless ``format`` is given.
    cloud : PointCloud
        What to write: points, colours, normals and every extra field the format
        can carry.
    format : str, optional
        One of ``supported_formats("write")``.

    Returns
    -------
    Path
        The written file.
    """
    p = Path(path)
    if not isinstance(cloud, PointCloud):
        raise WriteError(p, f"expected a PointCloud, got {type(cloud).__name__}")
    try:
        fmt = format.lower() if format else detect_format(p)
    except UnsupportedFormatError as exc:
        raise UnsupportedFormatError(
            p,
            f"cannot choose a writer for extension {p.suffix or '(none)'!r}",
            supported_formats("write"),
        ) from exc
    if fmt not in WRITERS:
        raise UnsupportedFormatError(
            p, f"format {fmt!r} cannot be written", supported_formats("write")
        )
    return WRITERS[fmt](p, cloud, **options)


def write_mesh(
    path: str | os.PathLike[str],
    vertices: Any,
    triangles: Any,
    colors: Any = None,
    **options: Any,
) -> Path:
    """Write a triangle mesh ((v, 3) vertices, (t, 3) triangles, optional (v, 3) uint8
    colours) as a binary PLY file, atomically; ``options`` are those of
    :func:`ontodetect.io._ply.write_mesh_ply` (``dtype``, ``comments``)."""
    from ._ply import write_mesh_ply  # lazy: start-up

    return write_mesh_ply(Path(path), vertices, triangles, colors, **options)
