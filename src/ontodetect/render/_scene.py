"""Drawing a scan and its objects: the top view and the perspective view."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

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
        Oriented boxes to outline, coloured by their label.
    title : str
        Figure title.
    legend_counts : mapping of class to count, optional
        Shown in the legend ("chair (4)").
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

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
        for name in {c for c in pc if c}:
            m = pc == name
            colors[m] = class_color(str(name))
            is_obj |= m
    # Fade the background towards white so objects stand out.
    colors[~is_obj] = 0.55 * colors[~is_obj] + 0.45
    sizes = np.where(is_obj, 1.6, 0.6)

    fig = plt.figure(figsize=(14, 6.5))
    ax_top = fig.add_subplot(1, 2, 1)
    order = np.argsort(pts[:, 2])  # higher points on top in the plan view
    ax_top.scatter(
        pts[order, 0], pts[order, 1], c=colors[order], s=sizes[order], linewidths=0, rasterized=True
    )
    ax_top.set_aspect("equal")
    ax_top.set_title("top view")
    ax_top.set_xlabel("x (m)")
    ax_top.set_ylabel("y (m)")
    ax3 = fig.add_subplot(1, 2, 2, projection="3d")
    # The ceiling hides the room from above: leave out the top of the scan in this view.
    if len(pts):
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        below = pts[:, 2] <= lo[2] + CEILING_CUT * (hi[2] - lo[2])
        ax3.scatter(
            pts[below, 0],
            pts[below, 1],
            pts[below, 2],
            c=colors[below],
            s=sizes[below] * 1.5,
            linewidths=0,
            depthshade=False,
            rasterized=True,
        )
        span = float(np.max(hi - lo)) / 2 or 1.0
        mid = (lo + hi) / 2
        ax3.set_xlim(mid[0] - span, mid[0] + span)
        ax3.set_ylim(mid[1] - span, mid[1] + span)
        ax3.set_zlim(lo[2], lo[2] + 2 * span)
    ax3.view_init(elev=38, azim=-58)
    ax3.set_box_aspect(None, zoom=1.35)
    ax3.set_title("perspective view")
    ax3.set_axis_off()

    edges = [
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
    ]
    for box in boxes:
        col = class_color(box.label)
        corners = box_corners(box.center, box.size, box.yaw)
        ring = corners[[0, 1, 2, 3, 0]]
        ax_top.plot(ring[:, 0], ring[:, 1], color=col, linewidth=1.4)
        if box.text:
            ax_top.text(
                corners[:4, 0].mean(),
                corners[:4, 1].mean(),
                box.text,
                fontsize=7,
                ha="center",
                va="center",
                color="black",
            )
        for a, b in edges:
            ax3.plot(*zip(corners[a], corners[b]), color=col, linewidth=1.0)

    labels = sorted({b.label for b in boxes} | set(legend_counts or {}))
    if labels:
        handles = [
            Line2D(
                [0],
                [0],
                color=class_color(n),
                lw=3,
                label=f"{n} ({legend_counts[n]})" if legend_counts and n in legend_counts else n,
            )
            for n in labels
        ]
        fig.legend(handles=handles, loc="lower center", ncol=min(len(handles), 6), frameon=False)
    if title:
        fig.suptitle(title)
    fig.tight_layout(rect=(0, 0.05, 1, 0.95))
    target = Path(path)
    with atomic_write(target, "wb") as fh:
        fig.savefig(fh, format="png", dpi=dpi)
    plt.close(fig)
    return target
