"""``view.html``: one self-contained page to turn a detect run around in a browser.

The page carries its points (decimated), boxes, CAD object map and renderer inline: three.js,
vendored from its npm package (``ontodetect/data/vendor/three``, with its licence), is mapped
into the page as ``data:`` URLs, so the page opens from the file system with no network.
The page itself is ``ontodetect/data/viewer.html``.
"""

from __future__ import annotations

import base64
import html
import json
import os
import re
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, ReadError
from ..geometry import box_corners, rotation_between
from ..io import atomic_write_text, read_cloud, read_detections
from ._scene import class_color

__all__ = [
    "CHROMIUM_FLAGS",
    "THREE_VERSION",
    "VIEWER_MAX_POINTS",
    "thin_points",
    "viewer_html",
    "write_viewer",
]

#: Flags that let headless Chromium draw the page in a container without a display, GPU or
#: network (the viewer's browser test and the README's screenshots use them).
CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    # WebGL on the CPU (SwiftShader): without a GPU, Chromium asks for this opt-in
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    # the page draws at load; virtual time lets it finish before the dump or the screenshot
    "--virtual-time-budget=10000",
)
#: Points the page carries at most: a browser turns this many smoothly on a laptop.
VIEWER_MAX_POINTS = 250_000
#: Share of the budget that detected objects' points may take first, so that small
#: objects stay dense when a big room is thinned out.
OBJECT_SHARE = 0.5
#: Share of the budget the CAD object map's sample points may take (when it has no mesh).
CAD_SHARE = 0.25
#: Name of the layer of the points no detection covers.
OTHER = "other points"
#: Name of the layer of the CAD object map (from ``detect --cad``).
CAD_LAYER = "CAD object map"
#: The three.js release vendored in ``ontodetect/data/vendor/three`` (npm ``three``).
THREE_VERSION = "0.170.0"
#: Module name -> vendored file, as the page's import map gives them.
_MODULES = {
    "three": "three.module.min.js",
    "three/addons/controls/OrbitControls.js": "OrbitControls.js",
}
_LABELLED = ("labelled.ply", "labelled.laz", "labelled.las")
#: The object map as a triangle mesh (preferred) and as sample points.
_CAD_MESH = "object_map_mesh.ply"
_CAD_POINTS = "object_map.ply"


def _rgb255(name: str) -> list[int]:
    return [round(255 * v) for v in class_color(name)]


def _b64(values: NDArray[Any], dtype: Any) -> str:
    return base64.b64encode(np.ascontiguousarray(values, dtype=dtype).tobytes()).decode()


def thin_points(
    xyz: NDArray[np.float64],
    budget: int,
    *,
    groups: NDArray[np.int64] | None = None,
    rng: int | np.random.Generator | None = 0,
) -> NDArray[np.int64]:
    """Rows of at most ``budget`` points, spread evenly over space and over ``groups``.

    The points are binned in cubes sized so that about ``budget`` cubes are occupied (cubes
    of different groups are apart); one random point of every cube is taken first, then a
    second of every cube, and so on until the budget is spent. Sparse places and small
    groups (an object's few points) thus keep their points; dense ones give up theirs,
    unlike a plain random subset, which thins everything alike.

    Parameters
    ----------
    xyz : (n, 3) float
        Points.
    budget : int
        Rows returned at most.
    groups : (n,) int, optional
        Stratum of every point (an object's id); points of different groups never share
        a cube.
    rng : int or Generator or None
        Seed of the random picks.

    Returns
    -------
    (m,) int64
        Sorted rows, ``m = min(n, budget)``.

    Examples
    --------
    >>> import numpy as np
    >>> dense = np.random.default_rng(0).random((10_000, 3)) * 0.1  # a dense corner
    >>> sparse = np.random.default_rng(1).random((100, 3)) * 5 + 1  # a sparse room
    >>> rows = thin_points(np.vstack([dense, sparse]), 500)
    >>> len(rows), int((rows >= 10_000).sum()) > 50
    (500, True)
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    n = len(xyz)
    if n <= budget:
        return np.arange(n, dtype=np.int64)
    if budget <= 0:
        return np.zeros(0, dtype=np.int64)
    rng = np.random.default_rng(rng)
    group = np.zeros(n, np.int64) if groups is None else np.asarray(groups, np.int64)
    lo = xyz.min(axis=0)
    extent = float(np.max(xyz.max(axis=0) - lo)) or 1.0
    # A surface of extent^2 in cubes of size s occupies about (extent / s)^2 of them; one
    # correction from the count found is close enough (cubes only order the picks).
    size = extent / np.sqrt(budget)
    cell = _cells(xyz, lo, size, group)
    found = len(np.unique(cell))
    size *= np.sqrt(found / budget)
    cell = _cells(xyz, lo, size, group)
    order = rng.permutation(n)
    order = order[np.argsort(cell[order], kind="stable")]
    first = np.r_[True, cell[order][1:] != cell[order][:-1]]
    starts = np.flatnonzero(first)
    rank = np.arange(n) - np.repeat(starts, np.diff(np.r_[starts, n]))
    # Whole ranks while they fit, then a random share of the next one.
    per_rank = np.bincount(rank)
    full = int(np.searchsorted(np.cumsum(per_rank), budget, side="right"))
    taken = order[rank < full]
    rest = order[rank == full]
    need = budget - len(taken)
    if need > 0:
        taken = np.r_[taken, rng.choice(rest, size=need, replace=False)]
    return np.sort(taken).astype(np.int64)


def _cells(xyz: NDArray[Any], lo: NDArray[Any], size: float, group: NDArray[Any]) -> NDArray[Any]:
    """(n,) int64: one number per (group, cube); equal numbers, same cube."""
    keys = np.c_[group - group.min(), np.floor((xyz - lo) / max(size, 1e-12)).astype(np.int64)]
    dims = keys.max(axis=0) + 1
    if float(np.prod(dims.astype(np.float64))) < 2.0**62:
        return np.ravel_multi_index(keys.T, dims).astype(np.int64)
    _, code = np.unique(keys, axis=0, return_inverse=True)
    return code.reshape(-1).astype(np.int64)


def _layer(name: str, color: list[int], xyz: NDArray[Any], rgb: NDArray[Any]) -> dict[str, Any]:
    return {
        "name": name,
        "color": color,
        "count": len(xyz),
        "xyz": _b64(xyz, "<f4"),
        "rgb": _b64(rgb, np.uint8),
    }


@lru_cache(maxsize=1)
def _import_map() -> str:
    """The page's import map: every vendored module as a ``data:`` URL."""
    vendor = resources.files("ontodetect").joinpath("data/vendor/three")
    urls = {
        name: "data:text/javascript;base64,"
        + base64.b64encode(vendor.joinpath(file).read_bytes()).decode()
        for name, file in _MODULES.items()
    }
    return json.dumps({"imports": urls})


def _cad_mesh(path: Path, rot: NDArray[np.float64]) -> dict[str, Any] | None:
    """The object map's triangles, turned with ``rot``; None when the file has none."""
    import trimesh  # lazy: trimesh only when a folder has an object map mesh

    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds on a bad file
        raise ReadError(path, f"is not a readable triangle mesh ({exc})") from exc
    faces = np.asarray(getattr(mesh, "faces", np.zeros((0, 3))), dtype=np.int64)
    if len(faces) == 0:
        return None
    vertices = np.asarray(mesh.vertices, dtype=np.float64) @ rot.T
    colors = getattr(getattr(mesh, "visual", None), "vertex_colors", None)
    rgb = (
        np.asarray(colors, dtype=np.uint8)[:, :3]
        if colors is not None and len(colors) == len(vertices)
        else np.full((len(vertices), 3), 220, np.uint8)
    )
    return {
        "name": CAD_LAYER,
        "color": [220, 220, 220],
        "triangles": len(faces),
        "xyz": _b64(vertices, "<f4"),
        "rgb": _b64(rgb, np.uint8),
        "index": _b64(faces, "<u4"),
    }


def viewer_html(
    out_dir: str | os.PathLike[str], *, max_points: int = VIEWER_MAX_POINTS, seed: int = 0
) -> str:
    """The page of a detect run's folder (detections.json, labelled.ply or .laz, object map).

    Parameters
    ----------
    out_dir : path
        A folder ``ontodetect detect`` wrote.
    max_points : int
        Points carried at most. Above it, detected objects' points take up to half the
        budget and the rest of the room the remainder, each thinned with
        :func:`thin_points` (evenly over space, every object keeping its share).
    seed : int
        Seed of the thinning (the same folder gives the same page).

    Returns
    -------
    str
        The HTML document: three.js with its licence, the data, the page's script.
    """
    if isinstance(max_points, bool) or not isinstance(max_points, int) or max_points < 1:
        raise InvalidParameterError("max_points", "an integer >= 1", max_points)
    folder = Path(out_dir)
    doc = read_detections(folder / "detections.json")
    labelled = next((folder / n for n in _LABELLED if (folder / n).is_file()), None)
    if labelled is None:
        raise ReadError(folder, f"has no labelled cloud ({', '.join(_LABELLED)})")
    cloud = read_cloud(labelled)
    classes = list(doc.get("classes") or sorted({d["label"] for d in doc["detections"]}))
    field = next((f for f in ("scalar_label", "label") if f in cloud.fields), None)
    label = (
        np.asarray(cloud.fields[field], dtype=np.int64)
        if field is not None
        else np.full(len(cloud), -1, dtype=np.int64)
    )
    instance = (
        np.asarray(cloud.fields["scalar_instance"], dtype=np.int64)
        if "scalar_instance" in cloud.fields
        else label
    )
    rot = rotation_between(doc["frame"]["up"], [0.0, 0.0, 1.0])
    xyz = cloud.xyz @ rot.T
    rgb = cloud.rgb if cloud.rgb is not None else np.full((len(cloud), 3), 170, np.uint8)
    rng = np.random.default_rng(seed)
    objects = np.flatnonzero(label >= 0)
    keep_obj = objects[
        thin_points(xyz[objects], int(max_points * OBJECT_SHARE), groups=instance[objects], rng=rng)
    ]
    rest = np.flatnonzero(label < 0)
    keep_rest = rest[thin_points(xyz[rest], max_points - len(keep_obj), rng=rng)]
    layers = []
    for k, name in enumerate(classes):
        rows = keep_obj[label[keep_obj] == k]
        if len(rows):
            layers.append(_layer(name, _rgb255(name), xyz[rows], rgb[rows]))
    layers.append(_layer(OTHER, [170, 170, 170], xyz[keep_rest], rgb[keep_rest]))
    cad = _cad_mesh(folder / _CAD_MESH, rot) if (folder / _CAD_MESH).is_file() else None
    if cad is None and (folder / _CAD_POINTS).is_file():
        samples = read_cloud(folder / _CAD_POINTS)
        rows = thin_points(samples.xyz, int(max_points * CAD_SHARE), rng=rng)
        cad_rgb = (
            samples.rgb[rows] if samples.rgb is not None else np.full((len(rows), 3), 220, np.uint8)
        )
        layers.append(_layer(CAD_LAYER, [220, 220, 220], samples.xyz[rows] @ rot.T, cad_rgb))
    boxes = []
    for d in doc["detections"]:
        b = d["box"]
        corners = box_corners(rot @ np.asarray(b["center"], float), b["size"], float(b["yaw"]))
        boxes.append(
            {
                "id": d["id"],
                "label": d["label"],
                "score": float(d["score"]),
                "color": _rgb255(d["label"]),
                "corners": np.round(corners, 4).tolist(),
            }
        )
    shown = xyz[np.r_[keep_obj, keep_rest]] if len(cloud) else np.zeros((1, 3))
    lo, hi = shown.min(axis=0), shown.max(axis=0)
    source = Path(str(doc.get("source") or folder.name)).name
    title = f"{source}: {len(boxes)} objects"
    data = {
        "title": title,
        "center": ((lo + hi) / 2).tolist(),
        "radius": float(max(np.linalg.norm(hi - lo) / 2, 1e-3)),
        "point_size": 2,
        "points_total": len(cloud),
        "layers": layers,
        "cad_mesh": cad,
        "boxes": boxes,
        "three": THREE_VERSION,
    }
    # "</" cannot end the JSON script element early once escaped.
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    template = resources.files("ontodetect").joinpath("data/viewer.html").read_text("utf-8")
    fill = {"TITLE": html.escape(title), "IMPORTMAP": _import_map(), "DATA": payload}
    # One pass: a placeholder's text inside another's value is left alone.
    return re.sub(r"__(TITLE|IMPORTMAP|DATA)__", lambda m: fill[m.group(1)], template)


def write_viewer(
    out_dir: str | os.PathLike[str],
    path: str | os.PathLike[str] | None = None,
    *,
    max_points: int = VIEWER_MAX_POINTS,
    seed: int = 0,
) -> Path:
    """Write :func:`viewer_html` of ``out_dir`` to ``path`` (``out_dir/view.html``) atomically."""
    target = Path(out_dir) / "view.html" if path is None else Path(path)
    return atomic_write_text(target, viewer_html(out_dir, max_points=max_points, seed=seed))
