"""Your own CAD models: mesh files (STL, OBJ, PLY, GLB) described by a small YAML manifest.

A manifest lists models; each names its class, its full model and optionally a
thin profile (the surfaces a sensor sees; derived from the full model by
:func:`~ontodetect.cad.visible_surface` when left out), and says how the file is
oriented and in which units it was drawn::

    format: ontodetect.cad-models/1     # optional
    models:
      - name: my-chair                  # unique; replaces a built-in model of that name
        label: chair                    # class name of the ontology
        full: chair.stl                 # display model (relative to the manifest)
        thin: chair-thin.stl            # matching profile (optional)
        up: z                           # file axis that points up: x, y, z, -x, -y, -z
        front: -y                       # file axis the object faces (default y)
        units: mm                       # m, cm, mm, in, ft, or metres per file unit
        symmetry: 1                     # 1 none, 2 half turn, 4 quarter turn, 0 round
        seat_height: 0.45               # metres; seat_width, seat_depth for seating,
                                        # top_height, top_width, top_depth for tables
        color: [120, 90, 60]            # optional display colour

A file with vertices but no faces (a point cloud in PLY) is accepted as a
point set: it is grid-averaged instead of sampled. Everything is moved to the
canonical frame of :class:`~ontodetect.cad.CadModel`: up along z, front along y,
metres, footprint centred on the origin, lowest point on the floor.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from ..errors import CorruptFileError, InvalidParameterError, ReadError
from ..geometry._mesh import Mesh
from ..io._textfile import read_text
from ..io._yaml import describe_yaml_error, load_yaml
from ..preprocess import AXES
from ._models import (
    DEFAULT_COLOR,
    LABEL_COLORS,
    SYMMETRIES,
    CadModel,
    ModelLibrary,
    _dims_of,
    canonical_mesh,
    visible_surface,
)

__all__ = ["MANIFEST_FORMAT", "UNITS", "load_manifest", "load_mesh", "orientation"]

MANIFEST_FORMAT = "ontodetect.cad-models/1"
#: Metres per unit of the unit names a manifest may use.
UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048}
#: Mesh file types read through trimesh.
MESH_SUFFIXES = (".stl", ".obj", ".ply", ".glb", ".gltf", ".off")
#: Optional sizes a manifest may give (metres, after the units).
SIZE_KEYS = ("seat_height", "seat_width", "seat_depth", "top_height", "top_width", "top_depth")
_KEYS = {
    "name",
    "label",
    "full",
    "thin",
    "up",
    "front",
    "units",
    "symmetry",
    "color",
    "description",
    "anchor",
    *SIZE_KEYS,
}


def orientation(up: str = "z", front: str = "y") -> NDArray[np.float64]:
    """(3, 3) rotation taking a file's ``up`` axis to +z and its ``front`` axis to +y.

    Examples
    --------
    >>> orientation("-z", "-y").astype(int).tolist()   # a model drawn upside down
    [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
    >>> orientation("y", "-z").astype(int).tolist()    # y-up (glTF, many modellers)
    [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    """
    for name, v in (("up", up), ("front", front)):
        if v not in AXES:
            raise InvalidParameterError(name, "one of " + ", ".join(map(repr, AXES)), v)
    u = np.asarray(AXES[up], dtype=np.float64)
    f = np.asarray(AXES[front], dtype=np.float64)
    if abs(float(u @ f)) > 0.5:
        raise InvalidParameterError("front", f"an axis perpendicular to up ({up!r})", front)
    # Rows are the file's coordinates of the canonical x (right), y (front) and z (up).
    return np.stack([np.cross(f, u), f, u])


def load_mesh(path: str | os.PathLike[str]) -> Mesh:
    """Read an STL, OBJ, PLY, GLB/glTF or OFF file as one mesh (scenes are flattened).

    A file with vertices but no faces gives a :class:`Mesh` without triangles
    (a point set).
    """
    import trimesh  # lazy: trimesh only to read mesh files

    p = Path(path)
    if not p.is_file():
        raise ReadError(p, "no such file")
    if p.suffix.lower() not in MESH_SUFFIXES:
        raise ReadError(p, f"not a mesh file (expected one of {', '.join(MESH_SUFFIXES)})")
    try:
        loaded = trimesh.load(str(p), process=False)
        # A scene (GLB, OBJ with groups) is flattened into one mesh with its node transforms.
        parts = loaded.dump() if isinstance(loaded, trimesh.Scene) else [loaded]
    except Exception as exc:  # trimesh raises many kinds of errors on bad files
        raise CorruptFileError(p, f"cannot read the mesh ({type(exc).__name__}: {exc})") from exc
    meshes = [g for g in parts if len(getattr(g, "faces", ())) > 0]
    if meshes:
        whole = meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(meshes)
        vertices = np.asarray(whole.vertices, dtype=np.float64)
        faces = np.asarray(whole.faces, dtype=np.int64)
    else:
        clouds = [
            np.asarray(getattr(g, "vertices", np.zeros((0, 3))), dtype=np.float64) for g in parts
        ]
        vertices = np.concatenate(clouds) if clouds else np.zeros((0, 3))
        faces = np.zeros((0, 3), dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) == 0:
        raise CorruptFileError(p, "the file holds no vertices")
    if not np.all(np.isfinite(vertices)):
        raise CorruptFileError(p, "the file holds non-finite vertices")
    return Mesh(vertices, faces.reshape(-1, 3).astype(np.int32))


def _fail(path: Path, where: str, problem: str) -> CorruptFileError:
    return CorruptFileError(path, f"{where}: {problem}")


def _number(path: Path, where: str, value: Any, *, positive: bool = True) -> float:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or (positive and value <= 0)
    ):
        raise _fail(
            path, where, f"expected a {'positive ' if positive else ''}number, got {value!r}"
        )
    return float(value)


def _model_entry(path: Path, k: int, entry: Any, names: set[str]) -> CadModel:
    where = f"models[{k}]"
    if not isinstance(entry, Mapping):
        raise _fail(path, where, f"expected a mapping, got {type(entry).__name__}")
    unknown = sorted(set(entry) - _KEYS)
    if unknown:
        raise _fail(
            path, f"{where}.{unknown[0]}", f"unknown key (known: {', '.join(sorted(_KEYS))})"
        )
    for key in ("name", "label", "full"):
        if not isinstance(entry.get(key), str) or not entry[key]:
            raise _fail(
                path, f"{where}.{key}", f"expected a non-empty string, got {entry.get(key)!r}"
            )
    name = entry["name"]
    if name in names:
        raise _fail(path, f"{where}.name", f"{name!r} is used twice")
    names.add(name)
    up, front = str(entry.get("up", "z")), str(entry.get("front", "y"))
    try:
        R = orientation(up, front)
    except InvalidParameterError as exc:
        raise _fail(path, f"{where}.{exc.name}", str(exc)) from None
    units = entry.get("units", "m")
    if isinstance(units, str):
        if units not in UNITS:
            raise _fail(
                path,
                f"{where}.units",
                f"expected one of {', '.join(UNITS)} or a number, got {units!r}",
            )
        factor = UNITS[units]
    else:
        factor = _number(path, f"{where}.units", units)
    symmetry = entry.get("symmetry", 1)
    if symmetry not in SYMMETRIES or isinstance(symmetry, bool):
        raise _fail(path, f"{where}.symmetry", f"expected one of 0, 1, 2, 4, got {symmetry!r}")
    sizes = {key: _number(path, f"{where}.{key}", entry[key]) for key in SIZE_KEYS if key in entry}
    color = entry.get("color", LABEL_COLORS.get(entry["label"], DEFAULT_COLOR))
    if (
        not isinstance(color, (list, tuple))
        or len(color) != 3
        or not all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c <= 255 for c in color)
    ):
        raise _fail(path, f"{where}.color", f"expected [r, g, b] in 0..255, got {color!r}")
    anchor = entry.get("anchor")
    if anchor is not None and (not isinstance(anchor, (list, tuple)) or len(anchor) != 3):
        raise _fail(path, f"{where}.anchor", f"expected [x, y, z] in metres, got {anchor!r}")

    T = np.eye(4)
    T[:3, :3] = R * factor

    def read(key: str) -> Mesh:
        file = path.parent / entry[key]
        return load_mesh(file).transformed(T)

    full, shift = canonical_mesh(read("full"))
    # The visibility test's viewpoints stand on the floor of the canonical frame.
    thin = read("thin").translated(shift) if entry.get("thin") else visible_surface(full)
    dims = _dims_of(full, sizes)
    if anchor is None:
        # The seat or top centre above the footprint centre is the natural first guess.
        height = sizes.get("seat_height", sizes.get("top_height"))
        anchor_t = None if height is None else (0.0, 0.0, float(height))
    else:
        anchor_t = tuple(float(_number(path, f"{where}.anchor", v, positive=False)) for v in anchor)
    return CadModel(
        name=name,
        label=entry["label"],
        full=full,
        thin=thin,
        dims=dims,
        symmetry=int(symmetry),
        anchor=anchor_t,
        color=tuple(int(c) for c in color),
        description=str(entry.get("description", "")),
        source=str(path.parent / entry["full"]),
    )


def load_manifest(path: str | os.PathLike[str]) -> ModelLibrary:
    """Read a model manifest (YAML) and the mesh files it names.

    Parameters
    ----------
    path : str or PathLike
        The manifest; mesh paths in it are relative to its folder.

    Returns
    -------
    ModelLibrary
        The manifest's models (merge them into the built-in ones with
        ``builtin_library().merged(load_manifest(path).values())``).

    Raises
    ------
    ReadError, CorruptFileError
        Naming the manifest, the entry and the key at fault.
    """
    p = Path(path)
    text = read_text(p)
    try:
        doc = load_yaml(text)
    except yaml.YAMLError as exc:
        raise CorruptFileError(p, f"not valid YAML{describe_yaml_error(exc)}") from None
    if not isinstance(doc, Mapping):
        raise _fail(p, "top level", "expected a mapping with a 'models' list")
    fmt = doc.get("format", MANIFEST_FORMAT)
    if fmt != MANIFEST_FORMAT:
        raise _fail(p, "format", f"expected {MANIFEST_FORMAT!r}, got {fmt!r}")
    models = doc.get("models")
    if not isinstance(models, list) or not models:
        raise _fail(p, "models", "expected a non-empty list of models")
    names: set[str] = set()
    return ModelLibrary(_model_entry(p, k, e, names) for k, e in enumerate(models))
