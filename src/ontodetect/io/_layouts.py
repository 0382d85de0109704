"""Labelled dataset layouts: their names and the discovery of the scenes a folder holds
(docs/evaluation.md, "Dataset layouts"). Reading a scene is ``evaluation.load_scene``'s."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .._rules import OneOf, check_param
from ..errors import ReadError, UnsupportedFormatError

__all__ = [
    "DATASET_FORMATS",
    "FORMAT_ALIASES",
    "SceneSource",
    "discover_scenes",
    "natural_key",
    "scene_group",
]

#: Dataset layouts: "auto" finds out which of the others a folder is.
DATASET_FORMATS = ("auto", "ontodetect", "scannet", "scannet-votenet", "sunrgbd-votenet", "s3dis")
#: Other names of layouts.
FORMAT_ALIASES = {"synth": "ontodetect", "votenet": "scannet-votenet", "sunrgbd": "sunrgbd-votenet"}
#: Folder levels below the dataset folder searched for scenes (dataset / area / room).
MAX_DEPTH = 2

_VOTENET_SUFFIX = "_vert.npy"
_SUNRGBD_SUFFIX = "_pc.npz"
_SUNRGBD_BOXES = "_bbox.npy"
_SCANNET_MESH = "_vh_clean_2.ply"
_SCAN_ID = re.compile(r"(scene\d{4})_\d{2}")


@dataclass(frozen=True)
class SceneSource:
    """Where one scene of a dataset is and how to read it.

    Attributes
    ----------
    name : str
        Unique within the dataset: the scan id (``scene0000_00``) or the folder's path
        relative to the dataset folder (``scene_0003``, ``Area_1/office_2``). Stored
        detections are looked up as ``<detections dir>/<name>/detections.json``.
    path : str
        The scene folder, the ``*_vert.npy`` file of a VoteNet ScanNet scan or the
        ``*_pc.npz`` file of a VoteNet SUN RGB-D frame.
    format : str
        ``ontodetect``, ``scannet``, ``scannet-votenet``, ``sunrgbd-votenet`` or ``s3dis``.
    group : str
        Scans of the same space share a group (rescans ``scene0000_00``/``_01`` are
        group ``scene0000``); calibration keeps a group on one side of a split.
    """

    name: str
    path: str
    format: str
    group: str


def scene_group(name: str) -> str:
    """The room a scan belongs to: ScanNet rescans of one space share it.

    Examples
    --------
    >>> scene_group("scene0000_02"), scene_group("val/scene0011_01"), scene_group("office_1")
    ('scene0000', 'val/scene0011', 'office_1')
    """
    m = _SCAN_ID.search(name)
    if m is None:
        return name
    return name[: m.start()] + m.group(1)


def natural_key(text: str) -> list[Any]:
    """Sort key of scene names with numbers in them: ``office_2`` before ``office_10``."""
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", text)]


def _folder_layout(folder: Path) -> str | None:
    """The layout of a folder that holds exactly one scene, or None."""
    if (folder / "scene.json").is_file() and (folder / "cloud.ply").is_file():
        return "ontodetect"
    if (folder / "Annotations").is_dir():
        return "s3dis"
    if any(folder.glob(f"*{_SCANNET_MESH}")):
        return "scannet"
    return None


def _normalise_format(fmt: str) -> str:
    name = FORMAT_ALIASES.get(str(fmt).lower(), str(fmt).lower())
    return check_param("format", OneOf(DATASET_FORMATS), name)


def _scenes_in(folder: Path, root: Path, fmt: str, depth: int) -> list[SceneSource]:
    rel = folder.relative_to(root).as_posix()
    layout = _folder_layout(folder)
    if layout is not None and fmt in ("auto", layout):
        name = folder.name if rel == "." else rel
        return [SceneSource(name, str(folder), layout, scene_group(name))]
    out = []
    if fmt in ("auto", "scannet-votenet"):
        prefix = "" if rel == "." else f"{rel}/"
        for vert in folder.glob(f"*{_VOTENET_SUFFIX}"):
            name = prefix + vert.name[: -len(_VOTENET_SUFFIX)]
            out.append(SceneSource(name, str(vert), "scannet-votenet", scene_group(name)))
    if fmt in ("auto", "sunrgbd-votenet"):
        prefix = "" if rel == "." else f"{rel}/"
        for pc in folder.glob(f"*{_SUNRGBD_SUFFIX}"):
            frame = pc.name[: -len(_SUNRGBD_SUFFIX)]
            if (folder / f"{frame}{_SUNRGBD_BOXES}").is_file():  # labelled frames only
                name = prefix + frame
                out.append(SceneSource(name, str(pc), "sunrgbd-votenet", name))
    if depth < MAX_DEPTH:
        for sub in folder.iterdir():
            if sub.is_dir() and not sub.name.startswith((".", "__")):
                out += _scenes_in(sub, root, fmt, depth + 1)
    return out


def discover_scenes(path: str | os.PathLike[str], format: str = "auto") -> list[SceneSource]:
    """Find the scenes of a dataset folder (or the one scene a path is).

    Parameters
    ----------
    path : str or PathLike
        A dataset folder, a scene folder, or a scene's file (``*_vert.npy``,
        ``*_pc.npz``, ``*_vh_clean_2.ply``, a synthetic scene's ``cloud.ply``).
    format : {"auto", "ontodetect", "scannet", "scannet-votenet", "sunrgbd-votenet", "s3dis"}
        Layout to look for; "auto" recognises each folder by its files. Folders are
        searched up to two levels deep (dataset / area / room).

    Returns
    -------
    list of SceneSource
        In natural order of their names (``office_2`` before ``office_10``).

    Raises
    ------
    ReadError
        The path does not exist or holds no scene of the layout asked for.

    Examples
    --------
    >>> import tempfile, pathlib, numpy as np
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> for s in ("scene0001_00", "scene0001_01"):
    ...     np.save(d / f"{s}_vert.npy", np.zeros((1, 6), np.float32))
    >>> [(s.name, s.format, s.group) for s in discover_scenes(d)]
    [('scene0001_00', 'scannet-votenet', 'scene0001'), ('scene0001_01', 'scannet-votenet', 'scene0001')]
    """  # noqa: E501
    fmt = _normalise_format(format)
    p = Path(path)
    if not p.exists():
        raise ReadError(p, "no such file or folder")
    if p.is_file():
        name = p.name
        for suffix in (_VOTENET_SUFFIX, "_sem_label.npy", "_ins_label.npy"):
            if name.endswith(suffix) and fmt in ("auto", "scannet-votenet"):
                scene = name[: -len(suffix)]
                vert = p.with_name(scene + _VOTENET_SUFFIX)
                return [SceneSource(scene, str(vert), "scannet-votenet", scene_group(scene))]
        for suffix in (_SUNRGBD_SUFFIX, _SUNRGBD_BOXES):
            if name.endswith(suffix) and fmt in ("auto", "sunrgbd-votenet"):
                frame = name[: -len(suffix)]
                points = p.with_name(frame + _SUNRGBD_SUFFIX)
                if points.is_file():
                    return [SceneSource(frame, str(points), "sunrgbd-votenet", frame)]
        layout = _folder_layout(p.parent)
        if layout is not None and fmt in ("auto", layout):
            return [SceneSource(p.parent.name, str(p.parent), layout, scene_group(p.parent.name))]
        raise UnsupportedFormatError(
            p, "is not a scene of a known dataset layout", list(DATASET_FORMATS[1:])
        )
    try:
        found = _scenes_in(p, p, fmt, 0)
    except PermissionError as exc:
        raise ReadError(
            exc.filename or p, "permission denied (a folder of the dataset cannot be listed)"
        ) from None
    if not found:
        what = "any known layout" if fmt == "auto" else f"the {fmt!r} layout"
        raise ReadError(
            p,
            f"holds no scene of {what} (looked for synthetic scenes with scene.json + "
            f"cloud.ply, *{_VOTENET_SUFFIX}, *{_SUNRGBD_SUFFIX} with *{_SUNRGBD_BOXES}, "
            f"*{_SCANNET_MESH} and S3DIS Annotations/ "
            f"up to {MAX_DEPTH} folders deep)",
        )
    return sorted(found, key=lambda s: natural_key(s.name))
