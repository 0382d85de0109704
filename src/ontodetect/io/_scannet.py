"""ScanNet scans, in the release layout and as preprocessed for VoteNet.

Release layout (one folder per scan)::

    scene0000_00_vh_clean_2.ply                   mesh; its vertices are the points
    scene0000_00_vh_clean_2.0.010000.segs.json    {"segIndices": [segment of each vertex]}
    scene0000_00.aggregation.json                 {"segGroups": [{"objectId", "label",
        (or scene0000_00_vh_clean.aggregation.json)   "segments": [...]}, ...]}
    scannetv2-labels.combined.tsv                 raw_category -> nyu40id (here or one up)

VoteNet layout (``batch_load_scannet_data.py``)::

    scene0000_00_vert.npy       (n, 6) float32 x y z r g b, colours 0..255
    scene0000_00_sem_label.npy  (n,) NYU40 id per point
    scene0000_00_ins_label.npy  (n,) instance id per point, 0 = none
    scene0000_00_bbox.npy       (K, 7) boxes [cx cy cz dx dy dz nyu40id], optional

Both give the same fields: ``class_id`` (NYU40 id, 0 = unannotated) and
``instance`` (``objectId + 1`` of the aggregation, 0 = none), both int32, the
numbering VoteNet's preprocessing uses.
"""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._rules import ON_NONFINITE, check_param
from ..cloud import PointCloud, point_cloud
from ..errors import CorruptFileError, ReadError
from . import read_cloud  # the PLY reader goes through the registry
from ._labels import UNANNOTATED, nyu40_name, read_scannet_label_map
from ._text import _to_colors

__all__ = ["read_scannet", "read_scannet_votenet"]

MESH_SUFFIX = "_vh_clean_2.ply"
SEGS_SUFFIX = "_vh_clean_2.0.010000.segs.json"
AGGREGATION_SUFFIXES = (".aggregation.json", "_vh_clean.aggregation.json")
LABEL_TABLE = "scannetv2-labels.combined.tsv"
VOTENET_SUFFIXES = ("_vert.npy", "_sem_label.npy", "_ins_label.npy", "_bbox.npy")
#: A VoteNet scan's label files and the fields they become.
VOTENET_LABELS = (("_sem_label.npy", "class_id"), ("_ins_label.npy", "instance"))
#: Columns of a VoteNet box: centre (3), size (3), NYU40 id.
BOX_COLUMNS = 7
#: Bytes of an .npy header read before trusting its shape.
MAX_NPY_HEADER = 1 << 16


# ---------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------
def _load_json(path: Path) -> Any:
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    try:
        return json.loads(raw)
    except (ValueError, RecursionError) as exc:  # JSONDecodeError and UnicodeDecodeError
        raise CorruptFileError(path, f"is not valid JSON ({exc})") from exc


def _int_array(path: Path, values: Any, what: str) -> NDArray[np.int64]:
    if not isinstance(values, list):
        raise CorruptFileError(
            path, f"{what} should be a list of integers, found {type(values).__name__}"
        )
    try:
        arr = np.asarray(values)
    except (ValueError, TypeError, OverflowError) as exc:
        raise CorruptFileError(path, f"{what} should be a list of integers ({exc})") from exc
    if arr.size == 0:
        return np.zeros(0, dtype=np.int64)
    if arr.ndim != 1 or arr.dtype.kind not in "iu":
        raise CorruptFileError(
            path,
            f"{what} should be a list of integers, found "
            f"{arr.dtype if arr.ndim == 1 else f'{arr.ndim}-d data'}",
        )
    return arr.astype(np.int64)


def _scene_files(path: Path) -> tuple[Path, str]:
    if path.is_dir():
        meshes = sorted(path.glob(f"*{MESH_SUFFIX}"))
        if not meshes:
            raise ReadError(path, f"holds no ScanNet mesh (<scene>{MESH_SUFFIX})")
        if len(meshes) > 1:
            raise ReadError(
                path,
                f"holds {len(meshes)} ScanNet meshes "
                f"({', '.join(m.name for m in meshes[:3])}); pass one of them",
            )
        mesh = meshes[0]
    else:
        mesh = path
    if not mesh.name.endswith(MESH_SUFFIX):
        raise ReadError(mesh, f"is not a ScanNet mesh (expected a name ending in {MESH_SUFFIX})")
    return mesh, mesh.name[: -len(MESH_SUFFIX)]


def _first_existing(candidates: list[Path], what: str) -> Path:
    for c in candidates:
        if c.is_file():
            return c
    others = ""
    if len(candidates) > 1:
        others = f" (also looked for {', '.join(c.name for c in candidates[1:])})"
    raise ReadError(candidates[0], f"missing: the scan's {what} is needed{others}")


def _axis_alignment(path: Path) -> NDArray[np.float64]:
    try:
        text = path.read_bytes().decode("latin-1")
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc
    m = re.search(r"^\s*axisAlignment\s*=\s*(.*)$", text, re.MULTILINE)
    if m is None:
        raise CorruptFileError(path, "has no 'axisAlignment = ...' line")
    try:
        vals = [float(v) for v in m.group(1).split()]
    except ValueError:
        raise CorruptFileError(path, "axisAlignment should be 16 numbers") from None
    if len(vals) != 16 or not np.all(np.isfinite(vals)):
        raise CorruptFileError(
            path, f"axisAlignment should be 16 finite numbers, found {len(vals)}"
        )
    return np.array(vals).reshape(4, 4)


def _instance_meta(instance: NDArray[np.int32], class_id: NDArray[np.int32]) -> dict[str, Any]:
    """Per instance: its class (majority over its points) and that class's NYU40 name."""
    has = instance > 0
    if not has.any():
        return {"instance_class_ids": {}, "instance_labels": {}}
    pairs, counts = np.unique(np.stack([instance[has], class_id[has]]), axis=1, return_counts=True)
    # Majority class per instance: sort by (instance, count) and keep the last of each.
    order = np.lexsort((counts, pairs[0]))
    inst_sorted = pairs[0][order]
    last = np.r_[inst_sorted[1:] != inst_sorted[:-1], True]
    chosen = order[last]
    class_ids = {int(i): int(c) for i, c in zip(pairs[0][chosen], pairs[1][chosen], strict=True)}
    labels = {i: nyu40_name(c) for i, c in class_ids.items()}
    return {"instance_class_ids": class_ids, "instance_labels": labels}


# ---------------------------------------------------------------------------------
# release layout
# ---------------------------------------------------------------------------------
def read_scannet(
    path: Path,
    *,
    label_map: str | Path | None = None,
    align: bool = False,
    on_nonfinite: str = "warn",
) -> PointCloud:
    """Read a ScanNet scan in the release layout, with its instance and class labels.

    Parameters
    ----------
    path : Path
        The scan folder, or its ``<scene>_vh_clean_2.ply``.
    label_map : str or Path, optional
        ``scannetv2-labels.combined.tsv``; looked for in the scan folder and its
        parent by default.
    align : bool
        Apply the ``axisAlignment`` matrix of ``<scene>.txt`` (ScanNet's
        metadata file), as VoteNet's preprocessing does. The file must exist.
    on_nonfinite : {"warn", "drop", "raise"}
        Passed to the PLY reader.

    Returns
    -------
    PointCloud
        The mesh vertices with their colours; fields ``instance`` and
        ``class_id`` (int32). ``meta`` holds ``scene_id``, ``instance_labels``
        (instance -> raw ScanNet label), ``instance_class_ids`` (instance ->
        NYU40 id) and ``unmapped_labels`` (labels the table does not know, given
        class 0).

    Raises
    ------
    ReadError
        A sibling file is missing (the message names it).
    CorruptFileError
        A JSON file is damaged or its lengths disagree with the mesh.
    """
    path = Path(path)
    mesh, scene = _scene_files(path)
    folder = mesh.parent
    aggregation = _first_existing(
        [folder / f"{scene}{s}" for s in AGGREGATION_SUFFIXES], "aggregation (segments -> objects)"
    )
    agg = _load_json(aggregation)
    if not isinstance(agg, dict) or not isinstance(agg.get("segGroups"), list):
        raise CorruptFileError(aggregation, "should be a JSON object with a 'segGroups' list")
    seg_candidates = [folder / f"{scene}{SEGS_SUFFIX}"]
    named = agg.get("segmentsFile")
    if isinstance(named, str) and named:
        alt = folder / named.split("/")[-1].removeprefix("scannet.")
        if alt != seg_candidates[0]:
            seg_candidates.append(alt)
    segs_file = _first_existing(seg_candidates, "over-segmentation (vertex -> segment)")
    if label_map is not None:
        table = Path(label_map)
        if not table.is_file():
            raise ReadError(table, "missing: the label table given as label_map does not exist")
    else:
        table = _first_existing(
            [folder / LABEL_TABLE, folder.parent / LABEL_TABLE],
            "label table (pass label_map= to give its path)",
        )
    mapping = read_scannet_label_map(table)

    segs = _load_json(segs_file)
    if not isinstance(segs, dict) or "segIndices" not in segs:
        raise CorruptFileError(segs_file, "should be a JSON object with a 'segIndices' list")
    seg_of_vertex = _int_array(segs_file, segs["segIndices"], "segIndices")

    cloud = read_cloud(mesh, format="ply", on_nonfinite=on_nonfinite)
    n_vertices = int(cloud.index.max()) + 1 if len(cloud) else 0
    nothing_dropped = len(cloud) == n_vertices
    if len(seg_of_vertex) < n_vertices or (nothing_dropped and len(seg_of_vertex) != n_vertices):
        raise CorruptFileError(
            segs_file,
            f"has {len(seg_of_vertex)} segment indices but {mesh.name} has {n_vertices} vertices",
        )

    uniq, inverse = np.unique(seg_of_vertex, return_inverse=True)
    inst_of_seg = np.zeros(len(uniq), dtype=np.int32)
    class_of_seg = np.zeros(len(uniq), dtype=np.int32)
    labels: dict[int, str] = {}
    unmapped: set[str] = set()
    for k, group in enumerate(agg["segGroups"]):
        if not isinstance(group, dict):
            raise CorruptFileError(aggregation, f"segGroups[{k}] should be an object")
        object_id, label = group.get("objectId", group.get("id")), group.get("label")
        if (
            not isinstance(object_id, int)
            or isinstance(object_id, bool)
            or object_id < 0
            or not isinstance(label, str)
        ):
            raise CorruptFileError(
                aggregation,
                f"segGroups[{k}] should have an integer objectId >= 0 and a "
                f"string label, found objectId={object_id!r}, label={label!r}",
            )
        if object_id + 1 > np.iinfo(np.int32).max:
            raise CorruptFileError(aggregation, f"segGroups[{k}]: objectId {object_id} too large")
        members = _int_array(aggregation, group.get("segments"), f"segGroups[{k}].segments")
        # Segments no vertex uses are ignored, as in ScanNet's own scripts.
        pos = np.searchsorted(uniq, members[np.isin(members, uniq)])
        instance_id = object_id + 1
        class_id = mapping.get(label, UNANNOTATED)
        if label not in mapping:
            unmapped.add(label)
        inst_of_seg[pos] = instance_id
        class_of_seg[pos] = class_id
        labels[instance_id] = label
    instance = inst_of_seg[inverse][cloud.index]
    class_id_arr = class_of_seg[inverse][cloud.index]

    xyz, normals = cloud.xyz, cloud.normals
    meta: dict[str, Any] = {"scene_id": scene}
    if align:
        meta_file = folder / f"{scene}.txt"
        if not meta_file.is_file():
            raise ReadError(meta_file, "missing: align=True needs the scan's metadata file")
        m = _axis_alignment(meta_file)
        xyz = xyz @ m[:3, :3].T + m[:3, 3]
        normals = None if normals is None else normals @ m[:3, :3].T
        meta["axis_alignment"] = m.tolist()
    # Every annotated object, including any whose segments cover no vertex.
    meta["instance_labels"] = dict(sorted(labels.items()))
    meta["instance_class_ids"] = {
        i: mapping.get(lbl, UNANNOTATED) for i, lbl in sorted(labels.items())
    }
    meta["unmapped_labels"] = sorted(unmapped)
    meta["files"] = {
        "mesh": mesh.name,
        "aggregation": aggregation.name,
        "segments": segs_file.name,
        "label_map": str(table),
    }
    fields = {k: v for k, v in cloud.fields.items() if k != "alpha"}
    fields["instance"] = instance
    fields["class_id"] = class_id_arr
    return point_cloud(
        xyz,
        rgb=cloud.rgb,
        normals=normals,
        fields=fields,
        index=cloud.index,
        meta={**dict(cloud.meta), "source": str(path), **meta},
        on_nonfinite="raise",
        copy=False,
    )


# ---------------------------------------------------------------------------------
# VoteNet layout
# ---------------------------------------------------------------------------------
def _plain_number(dtype: np.dtype[Any]) -> bool:
    # Integers, or floats up to float64: extended precision is no format VoteNet writes,
    # and damaged 80-bit values do not even convert cleanly.
    return dtype.kind in "iu" or (dtype.kind == "f" and dtype.itemsize <= 8)


def _load_npy(path: Path) -> NDArray[Any]:
    """``np.load`` that checks the header against the file size before allocating."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh, warnings.catch_warnings():
            # A damaged header can look like one written by Python 2; NumPy warns and
            # parses it anyway, and any failure is reported below as damage.
            warnings.filterwarnings("ignore", message="Reading `.npy`", category=UserWarning)
            try:
                version = np.lib.format.read_magic(fh)
                if version == (1, 0):
                    shape, _fortran, dtype = np.lib.format.read_array_header_1_0(
                        fh, max_header_size=MAX_NPY_HEADER
                    )
                elif version in ((2, 0), (3, 0)):
                    # Version 3 differs from 2 only by allowing UTF-8 field names.
                    shape, _fortran, dtype = np.lib.format.read_array_header_2_0(
                        fh, max_header_size=MAX_NPY_HEADER
                    )
                else:
                    raise CorruptFileError(path, f"is not a valid .npy file (version {version})")
            except CorruptFileError:
                raise
            except Exception as exc:
                # NumPy's header parser tokenizes a Python literal and can fail in many
                # ways (ValueError, SyntaxError, tokenize.TokenError...): all mean damage.
                raise CorruptFileError(path, f"is not a valid .npy file ({exc})") from exc
            if dtype.hasobject:
                raise CorruptFileError(path, "holds Python objects; only numeric arrays are read")
            count = int(np.prod(shape, dtype=object))
            need = count * dtype.itemsize
            have = size - fh.tell()
            if need > have:
                raise CorruptFileError(
                    path,
                    f"truncated: the header announces shape {tuple(shape)} of {dtype} "
                    f"({need} bytes) but only {have} bytes follow",
                )
            fh.seek(0)
            try:
                return np.lib.format.read_array(
                    fh, allow_pickle=False, max_header_size=MAX_NPY_HEADER
                )
            except (ValueError, EOFError, TypeError, MemoryError) as exc:
                raise CorruptFileError(path, f"cannot be read ({exc})") from exc
    except OSError as exc:
        raise ReadError(path, f"cannot read ({exc.strerror or exc})") from exc


def _box_table(
    path: Path, boxes: NDArray[Any], columns: int, names: str = ""
) -> NDArray[np.float64]:
    """A VoteNet box file's array (``_load_npy`` of ``path``), checked to be ``(K, columns)``
    plain numbers, as float64 (``names``: what the columns are, for the message)."""
    if (
        boxes.ndim != 2
        or (boxes.size and boxes.shape[1] != columns)
        or not _plain_number(boxes.dtype)
    ):
        raise CorruptFileError(
            path,
            f"should be a (K, {columns}) array{names}, found shape {boxes.shape} of {boxes.dtype}",
        )
    with np.errstate(invalid="ignore"):
        return boxes.astype(np.float64)


def _label_array(path: Path, n: int, vert: Path) -> NDArray[np.int32]:
    arr = _load_npy(path)
    if arr.ndim != 1 or not _plain_number(arr.dtype):
        raise CorruptFileError(
            path, f"should be a (n,) integer array, found shape {arr.shape} of {arr.dtype}"
        )
    if len(arr) != n:
        raise CorruptFileError(
            path,
            f"has {len(arr)} labels but {vert.name} has {n} points; the two files "
            f"{path.name} and {vert.name} do not belong together",
        )
    if arr.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            if not (np.isfinite(arr).all() and np.all(arr == np.round(arr))):
                raise CorruptFileError(path, "labels should be integers")
    if arr.size and (arr.min() < 0 or arr.max() > np.iinfo(np.int32).max):
        raise CorruptFileError(path, f"labels should be in 0..2^31, found {arr.min()}..{arr.max()}")
    return arr.astype(np.int32)


def read_scannet_votenet(
    path: Path, *, labels: bool | None = True, on_nonfinite: str = "warn"
) -> PointCloud:
    """Read a ScanNet scan as preprocessed for VoteNet (``*_vert.npy`` and siblings).

    Parameters
    ----------
    path : Path
        ``<scene>_vert.npy``, or its ``_sem_label.npy`` / ``_ins_label.npy`` sibling.
    labels : bool or None
        Read ``_sem_label.npy`` and ``_ins_label.npy`` (they must exist); False
        reads the points only; None reads them when both are there (a test scan has
        none).
    on_nonfinite : {"warn", "drop", "raise"}
        Passed to :func:`~ontodetect.point_cloud`.

    Returns
    -------
    PointCloud
        ``xyz``, ``rgb``; fields ``class_id`` and ``instance`` (int32); columns
        after the sixth become fields ``col6``, ``col7``... ``meta`` holds
        ``scene_id``, ``instance_class_ids`` and ``instance_labels`` (NYU40 name of
        each instance's majority class) and, when ``_bbox.npy`` exists, ``boxes``
        ((K, 7) list: centre, size, NYU40 id).

    Raises
    ------
    ReadError
        A needed sibling file is missing (the message names it).
    CorruptFileError
        A damaged .npy file, or arrays whose lengths disagree (the message names
        both files).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> np.save(d / "s_vert.npy", np.array([[0, 0, 0, 255, 0, 0]], dtype=np.float32))
    >>> np.save(d / "s_sem_label.npy", np.array([5], dtype=np.uint32))
    >>> np.save(d / "s_ins_label.npy", np.array([1], dtype=np.uint32))
    >>> c = read_scannet_votenet(d / "s_vert.npy")
    >>> c.fields["class_id"].tolist(), c.meta["instance_labels"]
    ([5], {1: 'chair'})
    """
    path = Path(path)
    name = path.name
    scene = next((name[: -len(s)] for s in VOTENET_SUFFIXES if name.endswith(s)), None)
    if scene is None:
        raise ReadError(
            path,
            f"is not a VoteNet ScanNet file (expected a name ending in "
            f"{', '.join(VOTENET_SUFFIXES[:3])})",
        )
    folder = path.parent
    vert_file = folder / f"{scene}_vert.npy"
    if not vert_file.is_file():
        raise ReadError(vert_file, "missing: the points of the scan are needed")
    vert = _load_npy(vert_file)
    if vert.ndim != 2 or vert.shape[1] < 3 or not _plain_number(vert.dtype):
        raise CorruptFileError(
            vert_file,
            f"should be an (n, 6) array x y z r g b, found shape {vert.shape} of {vert.dtype}",
        )
    n = vert.shape[0]
    if n == 0:
        raise CorruptFileError(vert_file, "contains no points")
    # Damaged float32 data can hold signalling NaNs, which warn when widened; they are
    # dropped (coordinates) or refused (colours) below like any NaN.
    with np.errstate(invalid="ignore"):
        vert = vert.astype(np.float64)
    rgb = None
    if vert.shape[1] >= 6:
        rgb = _to_colors(vert_file, vert[:, 3:6], ["r", "g", "b"])
    fields: dict[str, NDArray[Any]] = {f"col{i}": vert[:, i] for i in range(6, vert.shape[1])}
    meta: dict[str, Any] = {"source": str(path), "scene_id": scene}
    if labels is None:
        labels = all((folder / f"{scene}{suffix}").is_file() for suffix, _ in VOTENET_LABELS)
    if labels:
        for suffix, key in VOTENET_LABELS:
            f = folder / f"{scene}{suffix}"
            if not f.is_file():
                raise ReadError(
                    f, "missing: it holds the scan's labels (labels=False reads the points only)"
                )
            fields[key] = _label_array(f, n, vert_file)
        meta.update(_instance_meta(fields["instance"], fields["class_id"]))
    box_file = folder / f"{scene}_bbox.npy"
    if box_file.is_file():
        meta["boxes"] = _box_table(box_file, _load_npy(box_file), BOX_COLUMNS).tolist()
    check_param("on_nonfinite", ON_NONFINITE, on_nonfinite)
    return point_cloud(
        vert[:, :3],
        rgb=rgb,
        fields=fields,
        meta=meta,
        on_nonfinite=on_nonfinite,
        copy=False,
    )
