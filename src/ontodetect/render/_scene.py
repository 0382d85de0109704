"""Drawing a scan and its objects: the top view and the perspective view.

The points are rasterised with NumPy, each pixel taking the colour of the point drawn on
it last (the highest in the top view, the nearest in the perspective view), and Pillow
adds the box outlines, the text and the PNG encoding: a few hundredths of a second, where
a plotting library took most of a second to import and draw the same picture.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..geometry import box_corners
from ..io._atomic import atomic_write

__all__ = ["CLASS_COLORS", "MAX_POINTS", "BoxDrawing", "class_color", "render_scene"]

#: Colour of each class in pictures (RGB 0..1); other classes get a stable colour from a palette.
CLASS_COLORS: dict[str, tuple[float, float, float]] = {
    "chair": (0.89, 0.10, 0.11),
    "sofa": (0.22, 0.49, 0.72),
    "table": (0.30, 0.69, 0.29),
    "desk": (0.30, 0.69, 0.29),
    "stool": (1.00, 0.50, 0.00),
    "bench": (0.60, 0.31, 0.64),
}
_PALETTE = [
    (0.65, 0.34, 0.16),
    (0.97, 0.51, 0.75),
    (0.6, 0.6, 0.6),
    (0.74, 0.74, 0.13),
    (0.09, 0.75, 0.81),
    (0.55, 0.34, 0.29),
]
#: Points drawn at most; a denser picture shows nothing more.
MAX_POINTS = 120_000
#: The perspective view shows the scan up to this share of its height (no ceiling).
CEILING_CUT = 0.8
#: Size of the picture in inches; ``render_scene(dpi=...)`` gives the pixels an inch.
FIGURE_INCHES = (14.0, 6.5)
#: Where the perspective view looks from: elevation and azimuth in degrees, and the
#: distance of the eye from the scene's centre in half-widths of the scene.
VIEW_ELEVATION, VIEW_AZIMUTH, VIEW_DISTANCE = 38.0, -58.0, 7.0
#: Share of its own colour a background point keeps, the rest white: objects stand out.
BACKGROUND_FADE = 0.55
#: zlib level of the PNG: 1 writes it several times faster than the default 6, for a
#: file about a third larger.
PNG_COMPRESSION = 1
#: Side in pixels (at 110 dpi) of the square an object's point covers; others cover one.
OBJECT_POINT = 2
#: Share of the axes left empty around the data on each side.
MARGIN = 0.05

_BLACK = (0, 0, 0)
#: Corner pairs of a box's twelve edges (corners 0-3 at the bottom, 4-7 above them).
BOX_EDGES = (
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
)


def class_color(name: str) -> tuple[float, float, float]:
    """The picture colour of a class."""
    if name in CLASS_COLORS:
        return CLASS_COLORS[name]
    return _PALETTE[sum(map(ord, name)) % len(_PALETTE)]


@dataclass(frozen=True)
class BoxDrawing:
    """An upright oriented box to draw: centre, size (length, width, height), yaw, label."""

    center: Sequence[float]
    size: Sequence[float]
    yaw: float
    label: str
    text: str = ""


def _subsample(n: int, limit: int, seed: int = 0) -> NDArray[np.intp]:
    if n <= limit:
        return np.arange(n)
    return np.sort(np.random.default_rng(seed).choice(n, limit, replace=False))


def _rgb8(color: Sequence[float]) -> tuple[int, int, int]:
    r, g, b = (round(255 * float(c)) for c in color)
    return r, g, b


@dataclass(frozen=True)
class _Panel:
    """A view fitted into a rectangle of the picture: ``project`` takes (k, 3) points to
    (k, 2) view coordinates (y up) and (k,) depths (drawn from low to high); pixels are
    ``origin + scale * (x, -y)``."""

    project: Any
    origin: tuple[float, float]
    scale: float
    box: tuple[int, int, int, int]  # left, top, right, bottom of the drawn area

    def pixels(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        view, _ = self.project(points)
        return np.column_stack(
            [self.origin[0] + self.scale * view[:, 0], self.origin[1] - self.scale * view[:, 1]]
        )


def _fit(project: Any, extent: NDArray[np.float64], area: Sequence[float]) -> _Panel:
    """The panel that shows the view of ``extent`` (points whose view must fit) centred in
    ``area`` (left, top, right, bottom) with equal scales on both axes and a margin."""
    left, top, right, bottom = area
    view, _ = project(extent)
    lo, hi = view.min(axis=0), view.max(axis=0)
    span = np.maximum(hi - lo, 1e-9)
    lo, hi = lo - MARGIN * span, hi + MARGIN * span
    scale = float(min((right - left) / (hi[0] - lo[0]), (bottom - top) / (hi[1] - lo[1])))
    # Centred: what the view leaves unused goes half to each side.
    x0 = (left + right - scale * (hi[0] - lo[0])) / 2 - scale * lo[0]
    y0 = (top + bottom + scale * (hi[1] - lo[1])) / 2 + scale * lo[1]
    used = (
        math.floor(x0 + scale * lo[0]),
        math.floor(y0 - scale * hi[1]),
        math.ceil(x0 + scale * hi[0]),
        math.ceil(y0 - scale * lo[1]),
    )
    return _Panel(project, (x0, y0), scale, used)


def _top(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The plan: x and y as they are, higher points drawn later (on top)."""
    return points[:, :2], points[:, 2]


def _camera(center: NDArray[np.float64], radius: float) -> Any:
    """Perspective projection from ``VIEW_DISTANCE * radius`` away from ``center``, in the
    direction of :data:`VIEW_ELEVATION` and :data:`VIEW_AZIMUTH`; nearer points later."""
    elev, azim = math.radians(VIEW_ELEVATION), math.radians(VIEW_AZIMUTH)
    back = np.array(
        [math.cos(elev) * math.cos(azim), math.cos(elev) * math.sin(azim), math.sin(elev)]
    )
    eye = center + VIEW_DISTANCE * radius * back
    right = np.cross(-back, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -back)

    def project(points: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        rel = points - eye
        depth = rel @ -back
        view = np.column_stack([rel @ right, rel @ up]) / depth[:, None]
        return view, -depth

    return project


def _rasterise(
    canvas: NDArray[np.uint8],
    panel: _Panel,
    points: NDArray[np.float64],
    colors: NDArray[np.uint8],
    big: NDArray[np.bool_],
    size: int,
) -> None:
    """Paint the points into ``canvas``: one pixel each, ``size`` x ``size`` for ``big``
    ones; on a pixel several points fall on, the last in depth order wins."""
    if not len(points):
        return
    px = np.floor(panel.pixels(points)).astype(np.int64)
    _, depth = panel.project(points)
    if size > 1:
        offsets = np.array([(i, j) for i in range(size) for j in range(size)])
        extra = np.flatnonzero(big)
        px = np.concatenate([px, *(px[extra] + o for o in offsets[1:])])
        depth = np.concatenate([depth, np.tile(depth[extra], len(offsets) - 1)])
        colors = np.concatenate([colors, np.tile(colors[extra], (len(offsets) - 1, 1))])
    left, top, right, bottom = panel.box
    h, w = canvas.shape[:2]
    inside = (
        (px[:, 0] >= max(left, 0))
        & (px[:, 0] < min(right, w))
        & (px[:, 1] >= max(top, 0))
        & (px[:, 1] < min(bottom, h))
    )
    px, depth, colors = px[inside], depth[inside], colors[inside]
    flat = px[:, 1] * w + px[:, 0]
    order = np.lexsort((depth, flat))  # by pixel, then by depth: the last of a pixel wins
    last = np.ones(len(order), dtype=bool)
    last[:-1] = flat[order[1:]] != flat[order[:-1]]
    chosen = order[last]
    canvas.reshape(-1, 3)[flat[chosen]] = colors[chosen]


def _ticks(lo: float, hi: float, most: int = 8) -> NDArray[np.float64]:
    """Round tick values in [lo, hi]: steps of 1, 2, 2.5 or 5 times a power of ten."""
    span = max(hi - lo, 1e-9)
    base = 10.0 ** math.floor(math.log10(span / most))
    step = next(base * m for m in (1, 2, 2.5, 5, 10) if span / (base * m) <= most)
    first = math.ceil(lo / step - 1e-9)
    return np.arange(first, math.floor(hi / step + 1e-9) + 1) * step


def _label(value: float) -> str:
    text = f"{value:.2f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def _fonts(scale: float) -> dict[str, Any]:
    """The picture's fonts (Pillow's own), by use, sized in points at 110 dpi."""
    from PIL import ImageFont  # lazy: only to draw

    def font(points: float) -> Any:
        # The basic layout: the same pixels with or without the optional text shaping library.
        base = ImageFont.load_default(size=max(1, round(points * scale * 110 / 72)))
        return base.font_variant(layout_engine=ImageFont.Layout.BASIC)

    return {"title": font(12), "axes": font(12), "ticks": font(10), "small": font(7)}


def _axes(
    draw: Any, panel: _Panel, area: Sequence[float], fonts: dict[str, Any], scale: float
) -> None:
    """Frame, ticks and labels (metres) of the top view, drawn around ``area``."""
    left, top, right, bottom = (round(v) for v in area)
    draw.rectangle((left, top, right, bottom), outline=_BLACK, width=1)
    tick = round(3.5 * scale)
    x_lo = (left - panel.origin[0]) / panel.scale
    x_hi = (right - panel.origin[0]) / panel.scale
    y_lo = (panel.origin[1] - bottom) / panel.scale
    y_hi = (panel.origin[1] - top) / panel.scale
    for value in _ticks(x_lo, x_hi):
        x = round(panel.origin[0] + panel.scale * value)
        draw.line(((x, bottom), (x, bottom + tick)), fill=_BLACK)
        draw.text(
            (x, bottom + tick + 2), _label(value), fill=_BLACK, font=fonts["ticks"], anchor="mt"
        )
    widest = 0.0
    for value in _ticks(y_lo, y_hi):
        y = round(panel.origin[1] - panel.scale * value)
        widest = max(widest, fonts["ticks"].getlength(_label(value)))
        draw.line(((left - tick, y), (left, y)), fill=_BLACK)
        draw.text(
            (left - tick - 3, y), _label(value), fill=_BLACK, font=fonts["ticks"], anchor="rm"
        )
    draw.text(
        ((left + right) / 2, bottom + 24 * scale),
        "x (m)",
        fill=_BLACK,
        font=fonts["ticks"],
        anchor="mt",
    )
    # The y label, written sideways beside the tick labels.
    from PIL import Image, ImageDraw  # lazy: only to draw

    text = fonts["ticks"]
    x0, y0, x1, y1 = text.getbbox("y (m)")
    label = Image.new("L", (x1 - x0 + 2, y1 - y0 + 2), 0)
    ImageDraw.Draw(label).text((1 - x0, 1 - y0), "y (m)", fill=255, font=text)
    label = label.rotate(90, expand=True)
    x = round(left - tick - 3 - widest - 8 * scale - label.width)
    y = round((top + bottom - label.height) / 2)
    draw.bitmap((x, y), label, fill=_BLACK)


def _legend(
    draw: Any,
    labels: Sequence[str],
    counts: Mapping[str, int],
    middle: tuple[float, float],
    fonts: dict[str, Any],
    scale: float,
) -> None:
    """One line of coloured swatches and class names (with their counts), centred."""
    if not labels:
        return
    font = fonts["axes"]
    texts = [f"{n} ({counts[n]})" if n in counts else n for n in labels]
    swatch, gap, after = 36 * scale, 10 * scale, 30 * scale
    widths = [swatch + gap + font.getlength(t) for t in texts]
    x = middle[0] - (sum(widths) + after * (len(texts) - 1)) / 2
    y = middle[1]
    for name, text, w in zip(labels, texts, widths):
        draw.line(
            ((x, y), (x + swatch, y)), fill=_rgb8(class_color(name)), width=max(1, round(4 * scale))
        )
        draw.text((x + swatch + gap, y), text, fill=_BLACK, font=font, anchor="lm")
        x += w + after


def render_scene(
    path: str | os.PathLike[str],
    xyz: NDArray[np.float64],
    *,
    rgb: NDArray[np.uint8] | None = None,
    point_class: Sequence[str | None] | NDArray | None = None,
    boxes: Sequence[BoxDrawing] = (),
    title: str = "",
    legend_counts: Mapping[str, int] | None = None,
    dpi: int = 110,
) -> Path:
    """Draw a top view and a perspective view of a scan with its objects and write a PNG.

    Parameters
    ----------
    path : str or PathLike
        Target PNG (written atomically).
    xyz : (n, 3) float
        Points, z up.
    rgb : (n, 3) uint8, optional
        Point colours; grey when absent.
    point_class : (n,) sequence of str or None, optional
        Class of each point (None for background); such points are drawn in
        their class colour.
    boxes : sequence of BoxDrawing
        Oriented boxes to outline, coloured by their label; their text is written at
        their centre in the top view.
    title : str
        Picture title.
    legend_counts : mapping of class to count, optional
        Shown in the legend ("chair (4)").
    dpi : int
        Pixels an inch of the 14 x 6.5 inch picture (:data:`FIGURE_INCHES`).

    Returns
    -------
    Path
        ``path``.

    Examples
    --------
    >>> import tempfile
    >>> from PIL import Image
    >>> xyz = np.random.default_rng(0).uniform(0, 3, (500, 3))
    >>> box = BoxDrawing([1, 1, 0.5], [1, 0.6, 1], 0.3, "chair", "0.9")
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     with Image.open(render_scene(f"{tmp}/scene.png", xyz, boxes=[box])) as picture:
    ...         picture.size
    (1540, 715)
    """
    from PIL import Image, ImageDraw  # lazy: only to draw

    xyz = np.asarray(xyz, dtype=np.float64)
    keep = _subsample(len(xyz), MAX_POINTS)
    pts = xyz[keep]
    if rgb is not None:
        colors = np.asarray(rgb, dtype=np.float64)[keep] / 255.0
    else:
        colors = np.full((len(pts), 3), 0.55)
    is_obj = np.zeros(len(pts), dtype=bool)
    if point_class is not None:
        pc = np.asarray(point_class, dtype=object)[keep]
        for name in sorted({str(c) for c in pc if c}):
            m = pc == name
            colors[m] = class_color(name)
            is_obj |= m
    # Fade the background towards white so objects stand out.
    colors[~is_obj] = BACKGROUND_FADE * colors[~is_obj] + (1 - BACKGROUND_FADE)
    colors8 = np.round(255 * colors).astype(np.uint8)

    scale = dpi / 110.0
    width, height = round(FIGURE_INCHES[0] * dpi), round(FIGURE_INCHES[1] * dpi)
    canvas = np.full((height, width, 3), 255, dtype=np.uint8)
    corners = [box_corners(b.center, b.size, b.yaw) for b in boxes]
    size = max(1, round(OBJECT_POINT * scale))

    # The top view on the left, in axes of equal scales around the points and boxes.
    top_area = (84 * scale, 106 * scale, 758 * scale, 662 * scale)
    extent = np.vstack([pts.reshape(-1, 3), *corners]) if corners else pts
    top = None
    if len(extent):
        top = _fit(_top, extent, top_area)
        top_area = top.box  # the frame: the data's extent, at equal scales
        _rasterise(canvas, top, pts, colors8, is_obj, size)

    # The perspective view on the right, without the ceiling, which hides the room.
    persp = None
    persp_area = (820 * scale, 110 * scale, 1500 * scale, 665 * scale)
    if len(pts):
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        below = pts[:, 2] <= lo[2] + CEILING_CUT * (hi[2] - lo[2])
        radius = float(np.max(hi - lo)) / 2 or 1.0
        camera = _camera((lo + hi) / 2, radius)
        persp = _fit(camera, np.vstack([pts[below], *corners]), persp_area)
        _rasterise(canvas, persp, pts[below], colors8[below], is_obj[below], size)

    image = Image.fromarray(canvas)
    draw = ImageDraw.Draw(image)
    fonts = _fonts(scale)
    line = max(1, round(2 * scale))
    for box, ring in zip(boxes, corners):
        color = _rgb8(class_color(box.label))
        if persp is not None:
            xy = persp.pixels(ring)
            for a, b in BOX_EDGES:
                draw.line((tuple(xy[a]), tuple(xy[b])), fill=color, width=1)
        if top is not None:
            xy = top.pixels(ring[[0, 1, 2, 3, 0]])
            draw.line([tuple(p) for p in xy], fill=color, width=line, joint="curve")
            if box.text:
                ((cx, cy),) = top.pixels(ring[:4].mean(axis=0, keepdims=True))
                draw.text(
                    (cx, cy),
                    box.text,
                    fill=_BLACK,
                    font=fonts["small"],
                    anchor="mm",
                    # A white rim: legible over the object's own colour.
                    stroke_width=max(1, round(scale)),
                    stroke_fill=(255, 255, 255),
                )
    if top is not None:
        _axes(draw, top, top_area, fonts, scale)
    for area, name in ((top_area, "top view"), (persp_area, "perspective view")):
        draw.text(
            ((area[0] + area[2]) / 2, top_area[1] - 8 * scale),
            name,
            fill=_BLACK,
            font=fonts["axes"],
            anchor="mb",
        )
    if title:
        draw.text((width / 2, 22 * scale), title, fill=_BLACK, font=fonts["title"], anchor="mm")
    labels = sorted({b.label for b in boxes} | set(legend_counts or {}))
    _legend(draw, labels, legend_counts or {}, (width / 2, height - 22 * scale), fonts, scale)

    target = Path(path)
    with atomic_write(target, "wb") as fh:
        image.save(fh, format="PNG", compress_level=PNG_COMPRESSION)
    return target
