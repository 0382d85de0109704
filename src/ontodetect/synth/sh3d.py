"""Furniture made by designers: Sweet Home 3D furniture catalogues (``.sh3f``) read as meshes.

A ``.sh3f`` file is a zip archive holding ``PluginFurnitureCatalog.properties``
(a Java properties file: catalogue-level keys ``id``, ``name``, ``license``,
``provider`` and, per piece ``N``, keys ``id#N``, ``name#N``, ``category#N``,
``tags#N``, ``model#N``, ``width#N``, ``depth#N``, ``height#N`` in centimetres,
``elevation#N``, ``modelRotation#N``, ``creator#N``, ``license#N``,
``doorOrWindow#N`` ...) and the pieces' OBJ models with their MTL materials
and textures. Debian's ``sweethome3d-furniture`` package installs five of them
in ``/usr/share/sweethome3d/furniture``.

- :func:`read_catalog` reads one catalogue's entries (:class:`CatalogEntry`);
  :func:`read_catalogs` reads every catalogue of a folder, by default
  :func:`default_catalog_dir`.
- :func:`load_model` turns an entry into a :class:`ModelMesh` in the simulator's
  object frame: metres, z up, front towards +y, origin at the centre of the
  footprint on the floor, scaled to the entry's declared size exactly as
  Sweet Home 3D does (the rotated model's bounding box is stretched to width x
  height x depth), with a colour per triangle from the material.

Sweet Home 3D's models are y-up with their front towards +z (Java 3D); the
turn that takes them to our frame is ``(x, y, z) -> (-x, z, y)``, a proper
rotation, so the sitter's right stays +x.
"""

from __future__ import annotations

import functools
import io
import os
import re
import warnings
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import CorruptFileError, InvalidParameterError, ReadError

__all__ = [
    "CATALOG_DIR_ENV",
    "DEFAULT_CATALOG_DIR",
    "Catalog",
    "CatalogEntry",
    "ModelMesh",
    "default_catalog_dir",
    "load_model",
    "parse_properties",
    "read_catalog",
    "read_catalogs",
]

#: Where Debian's ``sweethome3d-furniture`` package puts the catalogues.
DEFAULT_CATALOG_DIR = Path("/usr/share/sweethome3d/furniture")
#: Environment variable naming another folder of ``.sh3f`` catalogues.
CATALOG_DIR_ENV = "ONTODETECT_SH3D_DIR"
#: The properties file every catalogue holds.
PROPERTIES_NAME = "PluginFurnitureCatalog.properties"
#: Keys every piece must have (``<key>#N``).
REQUIRED_KEYS = ("id", "name", "model", "width", "depth", "height")
#: Colour of triangles whose material gives none (0..255).
DEFAULT_COLOR = (160, 160, 160)
#: Materials this opaque or less (MTL ``d``) are clear glass: named ``glass``, which
#: the virtual sensors see through (see :data:`ontodetect.synth.sensors.TRANSPARENT_PARTS`).
GLASS_OPACITY = 0.35
#: Centimetres per metre: catalogues give sizes and elevations in centimetres.
_CM = 100.0
#: Models kept loaded (they are reused across rooms).
_MODEL_CACHE_SIZE = 256
# Java 3D (x, y up, z front) -> ours (x right, y front, z up), a proper rotation.
_Y_UP_TO_Z_UP = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])


@dataclass(frozen=True)
class CatalogEntry:
    """One piece of furniture of a catalogue.

    Attributes
    ----------
    id : str
        The catalogue's id of the piece, e.g. ``"Blend Swap CC-0#armchair"``.
    name, category : str
        As the catalogue names them (``"Armchair"``, ``"Living room"``).
    tags : tuple of str
    size : (3,) float
        Width (x), depth (y) and height (z) in metres, as Sweet Home 3D defines them:
        the size of the model's bounding box once ``model_rotation`` is applied.
    elevation : float
        Height of the model's bottom above the floor in metres (wall lamps, upper cabinets).
    model_rotation : tuple of 9 float
        Row-major 3 x 3 matrix Sweet Home 3D applies to the OBJ's vertices first.
    model : str
        Path of the OBJ inside the archive.
    creator : str
        Author of the model ("" when the catalogue does not say).
    license : str
        The entry's licence, or the catalogue's when the entry has none.
    door_or_window : bool
        Doors and windows are building parts, not furniture.
    catalog : str
        Name of the catalogue (``"Blend Swap CC-BY"``).
    path : str
        The ``.sh3f`` file.
    index : int
        N of the entry's ``key#N`` keys.
    """

    id: str
    name: str
    category: str
    tags: tuple[str, ...]
    size: tuple[float, float, float]
    elevation: float
    model_rotation: tuple[float, ...]
    model: str
    creator: str
    license: str
    door_or_window: bool
    catalog: str
    path: str
    index: int

    @property
    def width(self) -> float:
        return self.size[0]

    @property
    def depth(self) -> float:
        return self.size[1]

    @property
    def height(self) -> float:
        return self.size[2]


@dataclass(frozen=True)
class Catalog:
    """The entries of one ``.sh3f`` file and what the catalogue says about itself.

    Attributes
    ----------
    path : Path
    id, name, license, provider : str
    entries : tuple of CatalogEntry
        In the order of their numbers.
    """

    path: Path
    id: str
    name: str
    license: str
    provider: str
    entries: tuple[CatalogEntry, ...]

    def __iter__(self) -> Iterator[CatalogEntry]:
        return iter(self.entries)

    def __len__(self) -> int:
        return len(self.entries)

    def entry(self, entry_id: str) -> CatalogEntry:
        """The entry with this id; KeyError when there is none."""
        for e in self.entries:
            if e.id == entry_id:
                return e
        raise KeyError(entry_id)


@dataclass(frozen=True, eq=False)
class ModelMesh:
    """A catalogue model in the object frame (metres, z up, front +y, footprint centred at 0).

    Attributes
    ----------
    vertices : (v, 3) float64
        The bottom is at ``elevation`` (0 for pieces standing on the floor).
    triangles : (t, 3) int32
    triangle_part : (t,) int32
        Index into ``part_names``: one part per material of the model.
    part_names : tuple of str
        The materials' names; clear ones are called ``"glass"``.
    triangle_color : (t, 3) uint8
        The material's diffuse colour (MTL ``Kd``), the mean colour of its texture
        when it has one, grey otherwise.
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int32]
    triangle_part: NDArray[np.int32]
    part_names: tuple[str, ...]
    triangle_color: NDArray[np.uint8]


# --------------------------------------------------------------------------------------
# Reading catalogues.

_ESCAPES = {"t": "\t", "n": "\n", "r": "\r", "f": "\f"}
_UNICODE = re.compile(r"\\u([0-9a-fA-F]{4})")


def _unescape(text: str) -> str:
    out = []
    i = 0
    while i < len(text):
        ch = text[i]
        if ch != "\\" or i + 1 == len(text):
            out.append(ch)
            i += 1
            continue
        nxt = text[i + 1]
        m = _UNICODE.match(text, i)
        if m:
            out.append(chr(int(m.group(1), 16)))
            i = m.end()
        else:
            out.append(_ESCAPES.get(nxt, nxt))
            i += 2
    return "".join(out)


def _split_key(line: str) -> tuple[str, str]:
    """Key and raw value of one logical line (``=``, ``:`` or white space separate them)."""
    i = 0
    while i < len(line):
        ch = line[i]
        if ch == "\\":
            i += 2
            continue
        if ch in "=: \t\f":
            break
        i += 1
    key, rest = line[:i], line[i:].lstrip(" \t\f")
    if rest[:1] in ("=", ":"):
        rest = rest[1:].lstrip(" \t\f")
    return key, rest


def parse_properties(text: str) -> dict[str, str]:
    """Parse Java properties text: comments, continuation lines and backslash escapes.

    Parameters
    ----------
    text : str
        The file's content decoded as latin-1 (``\\uXXXX`` escapes give the rest of Unicode).

    Returns
    -------
    dict of str to str

    Examples
    --------
    >>> parse_properties("# a comment\\nname#1=Fauteuil \\\\u00e0 bascule\\nwidth#1 : 59.4\\n")
    {'name#1': 'Fauteuil à bascule', 'width#1': '59.4'}
    """
    props: dict[str, str] = {}
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i].lstrip(" \t\f")
        i += 1
        if not line or line[0] in "#!":
            continue
        # A line ending in an odd number of backslashes continues on the next one.
        while (len(line) - len(line.rstrip("\\"))) % 2 == 1 and i <= len(lines):
            line = line[:-1] + (lines[i].lstrip(" \t\f") if i < len(lines) else "")
            i += 1
        key, value = _split_key(line)
        props[_unescape(key)] = _unescape(value)
    return props


def _number(path: Path, props: dict[str, str], key: str, default: float | None = None) -> float:
    text = props.get(key, "").strip()
    if not text:
        if default is None:
            raise CorruptFileError(path, f"{PROPERTIES_NAME} has no value for '{key}'")
        return default
    try:
        value = float(text)
    except ValueError:
        raise CorruptFileError(
            path, f"{PROPERTIES_NAME}: '{key}' should be a number, found {text!r}"
        ) from None
    if not np.isfinite(value):
        raise CorruptFileError(path, f"{PROPERTIES_NAME}: '{key}' is not finite ({text!r})")
    return value


def _rotation(path: Path, props: dict[str, str], key: str) -> tuple[float, ...]:
    text = props.get(key, "").strip()
    if not text:
        return (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        values = ()
    if len(values) != 9 or not all(np.isfinite(values)):
        raise CorruptFileError(
            path, f"{PROPERTIES_NAME}: '{key}' should be 9 numbers (a 3 x 3 matrix), found {text!r}"
        )
    return values


def _open_zip(path: Path) -> zipfile.ZipFile:
    if not path.is_file():
        raise ReadError(path, "no such furniture catalogue (.sh3f file)")
    try:
        return zipfile.ZipFile(path)
    except zipfile.BadZipFile as exc:
        raise CorruptFileError(
            path, f"is not a furniture catalogue: not a zip archive ({exc})"
        ) from exc
    except OSError as exc:
        raise ReadError(path, f"cannot be read ({exc.strerror or exc})") from exc


def read_catalog(path: str | os.PathLike[str]) -> Catalog:
    """Read a Sweet Home 3D furniture catalogue (``.sh3f``).

    Parameters
    ----------
    path : str or PathLike
        The ``.sh3f`` file.

    Returns
    -------
    Catalog
        Sizes and elevations converted from centimetres to metres.

    Raises
    ------
    ReadError
        The file is missing or unreadable.
    CorruptFileError
        Not a zip archive, no ``PluginFurnitureCatalog.properties``, or an entry
        lacks one of :data:`REQUIRED_KEYS` or has a malformed number; the message
        names the file and the key.

    Examples
    --------
    >>> catalog = read_catalog(DEFAULT_CATALOG_DIR / "BlendSwap-CC-0.sh3f")  # doctest: +SKIP
    >>> catalog.entry("Blend Swap CC-0#oakTable").size  # doctest: +SKIP
    (1.24, 1.24, 0.741)
    """
    path = Path(path)
    with _open_zip(path) as archive:
        try:
            raw = archive.read(PROPERTIES_NAME)
        except KeyError:
            raise CorruptFileError(
                path, f"is not a furniture catalogue: no {PROPERTIES_NAME} in the archive"
            ) from None
        except (zipfile.BadZipFile, OSError, EOFError) as exc:
            raise CorruptFileError(path, f"{PROPERTIES_NAME} cannot be unpacked ({exc})") from exc
    props = parse_properties(raw.decode("latin-1"))
    numbers = sorted(
        {int(m.group(1)) for k in props if (m := re.fullmatch(r"id#(\d+)", k)) is not None}
    )
    if not numbers:
        raise CorruptFileError(path, f"{PROPERTIES_NAME} lists no furniture (no 'id#N' key)")
    name = props.get("name", "").strip() or path.stem
    licence = props.get("license", "").strip()
    entries = []
    for n in numbers:
        for key in REQUIRED_KEYS:
            if not props.get(f"{key}#{n}", "").strip():
                raise CorruptFileError(
                    path,
                    f"{PROPERTIES_NAME}: entry {n} ({props.get(f'id#{n}', '?')}) "
                    f"has no '{key}#{n}'",
                )
        size = tuple(_number(path, props, f"{k}#{n}") / _CM for k in ("width", "depth", "height"))
        if min(size) < 0:
            raise CorruptFileError(
                path, f"{PROPERTIES_NAME}: entry {n} has a negative size {size} (m)"
            )
        tags = tuple(t.strip() for t in props.get(f"tags#{n}", "").split(",") if t.strip())
        entries.append(
            CatalogEntry(
                id=props[f"id#{n}"].strip(),
                name=props[f"name#{n}"].strip(),
                category=props.get(f"category#{n}", "").strip(),
                tags=tags,
                size=(size[0], size[1], size[2]),
                elevation=_number(path, props, f"elevation#{n}", 0.0) / _CM,
                model_rotation=_rotation(path, props, f"modelRotation#{n}"),
                model=props[f"model#{n}"].strip(),
                creator=props.get(f"creator#{n}", "").strip(),
                license=props.get(f"license#{n}", "").strip() or licence,
                door_or_window=props.get(f"doorOrWindow#{n}", "").strip().lower() == "true",
                catalog=name,
                path=str(path),
                index=n,
            )
        )
    return Catalog(
        path=path,
        id=props.get("id", "").strip(),
        name=name,
        license=licence,
        provider=props.get("provider", "").strip(),
        entries=tuple(entries),
    )


def default_catalog_dir() -> Path:
    """The folder of ``.sh3f`` catalogues: ``$ONTODETECT_SH3D_DIR``, else Debian's.

    Raises
    ------
    ReadError
        The folder does not exist (the message says how to get the catalogues).

    Examples
    --------
    >>> default_catalog_dir()  # doctest: +SKIP
    PosixPath('/usr/share/sweethome3d/furniture')
    """
    env = os.environ.get(CATALOG_DIR_ENV, "").strip()
    folder = Path(env) if env else DEFAULT_CATALOG_DIR
    if not folder.is_dir():
        hint = (
            f"set by {CATALOG_DIR_ENV}"
            if env
            else f"install Debian's sweethome3d-furniture or set {CATALOG_DIR_ENV}"
        )
        raise ReadError(folder, f"no folder of furniture catalogues ({hint})")
    return folder


def read_catalogs(folder: str | os.PathLike[str] | None = None) -> list[Catalog]:
    """Read every ``*.sh3f`` catalogue of ``folder`` (default :func:`default_catalog_dir`).

    Returns
    -------
    list of Catalog
        Sorted by file name.

    Raises
    ------
    ReadError
        The folder is missing or holds no ``.sh3f`` file; or a catalogue is unreadable.
    """
    where = default_catalog_dir() if folder is None else Path(folder)
    if not where.is_dir():
        raise ReadError(where, "no such folder of furniture catalogues")
    files = sorted(where.glob("*.sh3f"))
    if not files:
        raise ReadError(where, "holds no furniture catalogue (*.sh3f)")
    return [_read_catalog_cached(str(f), f.stat().st_mtime_ns) for f in files]


@functools.lru_cache(maxsize=32)
def _read_catalog_cached(path: str, mtime_ns: int) -> Catalog:
    return read_catalog(path)


# --------------------------------------------------------------------------------------
# Loading models.


def _material_color(material: object) -> tuple[int, int, int]:
    image = getattr(material, "image", None)
    if image is not None:
        try:
            rgb = np.asarray(image.convert("RGB").reduce(8), dtype=np.float64)
            return tuple(int(v) for v in np.clip(rgb.reshape(-1, 3).mean(axis=0), 0, 255))
        except (OSError, ValueError):
            pass
    kd = getattr(material, "kwargs", {}).get("kd")
    if kd is not None:
        values = np.atleast_1d(np.asarray(kd, dtype=np.float64))
        rgb = np.resize(values, 3)
        return tuple(int(v) for v in np.clip(np.rint(rgb * 255), 0, 255))
    return DEFAULT_COLOR


def _is_clear(material: object) -> bool:
    kwargs = getattr(material, "kwargs", {})
    for key, opaque_when_high in (("d", True), ("tr", False)):
        if key in kwargs:
            try:
                value = float(np.atleast_1d(kwargs[key])[0])
            except (TypeError, ValueError):
                continue
            opacity = value if opaque_when_high else 1.0 - value
            return opacity <= GLASS_OPACITY
    return False


def _part_name(material: object, fallback: str) -> str:
    if _is_clear(material):
        return "glass"
    name = str(getattr(material, "name", "") or fallback).strip()
    return name or fallback


def _read_obj(entry: CatalogEntry) -> list[tuple[NDArray, NDArray, str, tuple[int, int, int]]]:
    """The OBJ's pieces, one per material: (vertices, triangles, part name, colour)."""
    import trimesh
    from trimesh.resolvers import ZipResolver

    path = Path(entry.path)
    name = entry.model.lstrip("/")
    folder = name.rsplit("/", 1)[0] + "/" if "/" in name else ""
    with _open_zip(path) as archive:
        try:
            files = {
                n[len(folder) :]: archive.read(n)
                for n in archive.namelist()
                if n.startswith(folder) and not n.endswith("/")
            }
        except (zipfile.BadZipFile, OSError, EOFError) as exc:
            raise CorruptFileError(path, f"model {entry.model} cannot be unpacked ({exc})") from exc
    key = name[len(folder) :]
    if key not in files:
        raise CorruptFileError(
            path, f"entry {entry.index} ({entry.id}): model {entry.model} is not in the archive"
        )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            loaded = trimesh.load(
                io.BytesIO(files[key]),
                file_type="obj",
                resolver=ZipResolver(files),
                group_material=True,
                split_object=False,
                process=False,
            )
    except Exception as exc:  # trimesh raises many kinds on a damaged OBJ
        raise CorruptFileError(
            path, f"entry {entry.index} ({entry.id}): model {entry.model} cannot be read ({exc})"
        ) from exc
    geometries = (
        [loaded] if isinstance(loaded, trimesh.Trimesh) else list(loaded.dump(concatenate=False))
    )
    pieces = []
    for k, g in enumerate(geometries):
        if not isinstance(g, trimesh.Trimesh) or len(g.faces) == 0:
            continue
        material = getattr(g.visual, "material", None)
        pieces.append(
            (
                np.asarray(g.vertices, dtype=np.float64),
                np.asarray(g.faces, dtype=np.int64),
                _part_name(material, f"material_{k}"),
                _material_color(material),
            )
        )
    if not pieces:
        raise CorruptFileError(
            path, f"entry {entry.index} ({entry.id}): model {entry.model} has no triangles"
        )
    return pieces


def load_model(entry: CatalogEntry) -> ModelMesh:
    """The entry's model as a mesh in the object frame, at its declared size.

    As Sweet Home 3D does, ``model_rotation`` turns the OBJ first, then the
    turned model's bounding box is stretched to (width, height, depth) along
    Java 3D's (x, y, z); the result is turned to z up with the front towards +y
    and moved so that the footprint's centre is at the origin and the bottom at
    ``entry.elevation``. Meshes are cached (read-only arrays): a model used in
    many rooms is read once.

    Parameters
    ----------
    entry : CatalogEntry

    Returns
    -------
    ModelMesh

    Raises
    ------
    CorruptFileError
        The model or its materials are missing from the archive or cannot be read.

    Examples
    --------
    >>> catalog = read_catalog(DEFAULT_CATALOG_DIR / "Scopia.sh3f")  # doctest: +SKIP
    >>> mesh = load_model(catalog.entry("Scopia#office_chair"))  # doctest: +SKIP
    >>> np.ptp(mesh.vertices, axis=0).round(3).tolist()  # doctest: +SKIP
    [0.635, 0.637, 1.0]
    """
    if not isinstance(entry, CatalogEntry):
        raise InvalidParameterError("entry", "a CatalogEntry", type(entry).__name__)
    mtime = Path(entry.path).stat().st_mtime_ns if Path(entry.path).is_file() else 0
    return _load_model_cached(entry, mtime)


@functools.lru_cache(maxsize=_MODEL_CACHE_SIZE)
def _load_model_cached(entry: CatalogEntry, mtime_ns: int) -> ModelMesh:
    pieces = _read_obj(entry)
    names = list(dict.fromkeys(p[2] for p in pieces))
    offsets = np.cumsum([0] + [len(p[0]) for p in pieces])
    vertices = np.concatenate([p[0] for p in pieces])
    triangles = np.concatenate([p[1] + off for p, off in zip(pieces, offsets[:-1], strict=True)])
    counts = [len(p[1]) for p in pieces]
    part = np.repeat([names.index(p[2]) for p in pieces], counts).astype(np.int32)
    color = np.repeat(np.array([p[3] for p in pieces], dtype=np.uint8), counts, axis=0)
    # Drop vertices no triangle uses (they would stretch the bounding box).
    used, inverse = np.unique(triangles, return_inverse=True)
    vertices, triangles = vertices[used], inverse.reshape(-1, 3)

    rotation = np.asarray(entry.model_rotation, dtype=np.float64).reshape(3, 3)
    v = vertices @ rotation.T
    lo, hi = v.min(axis=0), v.max(axis=0)
    extent = hi - lo
    target = np.array([entry.width, entry.height, entry.depth])  # Java 3D x, y, z
    scale = np.divide(target, extent, out=np.ones(3), where=extent > 0)
    v = (v - (lo + hi) / 2) * scale
    if np.linalg.det(rotation) < 0:  # a mirroring rotation: keep the winding outwards
        triangles = triangles[:, ::-1]
    v = v @ _Y_UP_TO_Z_UP.T
    v[:, 2] += entry.height / 2 + entry.elevation
    mesh = ModelMesh(
        vertices=v,
        triangles=np.ascontiguousarray(triangles, dtype=np.int32),
        triangle_part=part,
        part_names=tuple(names),
        triangle_color=color,
    )
    for array in (mesh.vertices, mesh.triangles, mesh.triangle_part, mesh.triangle_color):
        array.flags.writeable = False
    return mesh
