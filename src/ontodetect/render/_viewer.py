"""``view.html``: one self-contained page to turn a detect run around in a browser.

The page carries its points (decimated), boxes and renderer inline: it opens from the file
system with no network and no library (a small canvas renderer with a depth buffer,
``ontodetect/data/viewer.html``).
"""

from __future__ import annotations

import base64
import html
import json
import os
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, ReadError
from ..geometry import box_corners, rotation_between
from ..io import atomic_write_text, read_cloud, read_detections
from ._scene import class_color

__all__ = ["VIEWER_MAX_POINTS", "viewer_html", "write_viewer"]

#: Points the page carries at most: a browser turns this many smoothly on a laptop.
VIEWER_MAX_POINTS = 250_000
#: Share of the budget that detected objects' points may take first, so that small
#: objects stay dense when a big room is thinned out.
OBJECT_SHARE = 0.5
#: Name of the layer of the points no detection covers.
OTHER = "other points"
#: Name of the layer of the CAD object map (``object_map.ply``, from ``detect --cad``).
CAD_LAYER = "CAD object map"
_LABELLED = ("labelled.ply", "labelled.laz", "labelled.las")


def _rgb255(name: str) -> list[int]:
    return [round(255 * v) for v in class_color(name)]


def _pick(members: NDArray[np.int64], budget: int, rng: np.random.Generator) -> NDArray[np.int64]:
    if len(members) <= budget:
        return members
    return np.sort(rng.choice(members, size=budget, replace=False))


def _layer(name: str, color: list[int], xyz: NDArray[Any], rgb: NDArray[Any]) -> dict[str, Any]:
    return {
        "name": name,
        "color": color,
        "xyz": base64.b64encode(np.ascontiguousarray(xyz, dtype="<f4").tobytes()).decode(),
        "rgb": base64.b64encode(np.ascontiguousarray(rgb, dtype=np.uint8).tobytes()).decode(),
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
        Points carried at most; above it, a seeded random subset where detected objects'
        points are kept first (up to half the budget) and the rest of the room fills the
        remainder.
    seed : int
        Seed of the subset (the same folder gives the same page).

    Returns
    -------
    str
        The HTML document.
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
    rot = rotation_between(doc["frame"]["up"], [0.0, 0.0, 1.0])
    xyz = cloud.xyz @ rot.T
    rgb = cloud.rgb if cloud.rgb is not None else np.full((len(cloud), 3), 170, np.uint8)
    rng = np.random.default_rng(seed)
    objects = np.flatnonzero(label >= 0)
    keep_obj = _pick(objects, int(max_points * OBJECT_SHARE), rng)
    keep_rest = _pick(np.flatnonzero(label < 0), max_points - len(keep_obj), rng)
    layers = []
    for k, name in enumerate(classes):
        rows = keep_obj[label[keep_obj] == k]
        if len(rows):
            layers.append(_layer(name, _rgb255(name), xyz[rows], rgb[rows]))
    layers.append(_layer(OTHER, [170, 170, 170], xyz[keep_rest], rgb[keep_rest]))
    cad_file = folder / "object_map.ply"
    if cad_file.is_file():
        cad = read_cloud(cad_file)
        rows = _pick(np.arange(len(cad)), max_points // 4, rng)
        cad_rgb = cad.rgb[rows] if cad.rgb is not None else np.full((len(rows), 3), 220, np.uint8)
        layers.append(_layer(CAD_LAYER, [220, 220, 220], cad.xyz[rows] @ rot.T, cad_rgb))
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
        "layers": layers,
        "boxes": boxes,
    }
    # "</" cannot end the JSON script element early once escaped.
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    template = resources.files("ontodetect").joinpath("data/viewer.html").read_text("utf-8")
    return template.replace("__TITLE__", html.escape(title)).replace("__DATA__", payload)


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
