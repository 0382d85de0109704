"""Regenerate the pictures of simulated scans in docs/gallery/.

Each picture shows one simulated scan four ways: a top view and a perspective
view, with the points in the colours the sensor recorded (left) and coloured by
their ground-truth class with the furniture's oriented boxes (right). The
ceiling is left out so that one can see in.

Usage::

    .venv/bin/python scripts/make_gallery.py [--out docs/gallery] [--points 200000]
"""

from __future__ import annotations

import argparse
import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from PIL import Image

from ontodetect.io import atomic_write_bytes
from ontodetect.render import CLASS_COLORS, box_corners
from ontodetect.render._scene import BOX_EDGES
from ontodetect.synth import CLASS_IDS, CLASS_NAMES, synthesize

#: (room type, sensor, seed) of each picture; the file is ``<room>-<sensor>.png``.
SCENES = [
    ("office", "rgbd", 3),
    ("living_room", "rgbd", 1),
    ("conference", "tls", 2),
    ("bedroom", "monocular", 4),
]
STRUCTURE = {"wall", "floor", "ceiling", "door", "window", "unlabelled"}
STRUCTURE_GREY = (0.82, 0.82, 0.82)
OUTLIER_BLACK = (0.0, 0.0, 0.0)
SHOWN_POINTS = 60_000  # per panel; more only blurs the picture
PALETTE_COLORS = 256
MUTED_COLORS = 12
CEILING_CUT = 0.85  # share of the room height shown


def class_color(name: str) -> tuple[float, float, float]:
    """The detection pictures' colour for the classes they draw; a muted one for the rest."""
    if name in CLASS_COLORS:
        return CLASS_COLORS[name]
    others = sorted(set(CLASS_IDS) - set(CLASS_COLORS) - STRUCTURE)
    # tab20b's blues, olives and browns: no reds or pinks that could pass for chairs.
    return plt.get_cmap("tab20b")(others.index(name) % MUTED_COLORS)[:3]


def _class_colors(class_id: np.ndarray) -> np.ndarray:
    colors = np.empty((len(class_id), 3))
    for cid in np.unique(class_id):
        name = CLASS_NAMES.get(int(cid), "unlabelled")
        if cid == 0:
            color = OUTLIER_BLACK
        elif name in STRUCTURE:
            color = STRUCTURE_GREY
        else:
            color = class_color(name)
        colors[class_id == cid] = color
    return colors


def render(room: str, sensor: str, seed: int, points: int) -> bytes:
    result = synthesize(room, sensor, seed, points=points)
    out = result.output
    cloud = out.world_cloud()
    xyz = cloud.xyz
    note = ""
    if out.frame == "map":
        # Show the map in metres, scaled by the odometry as the pipeline will do it.
        xyz = xyz * out.scale_factor
        note = f"  (map scale {out.scale:.3f}, recovered k_s = {out.scale_factor:.3f})"
    height = result.scene.size[2]
    inside = (xyz[:, 2] < CEILING_CUT * height) & (xyz[:, 2] > -0.5)
    inside &= np.all(
        (xyz[:, :2] > -0.5) & (xyz[:, :2] < np.asarray(result.scene.size[:2]) + 0.5), axis=1
    )
    rng = np.random.default_rng(0)
    idx = np.flatnonzero(inside)
    if len(idx) > SHOWN_POINTS:
        idx = np.sort(rng.choice(idx, SHOWN_POINTS, replace=False))
    pts = xyz[idx]
    rgb = cloud.rgb[idx] / 255.0
    by_class = _class_colors(cloud.fields["class_id"][idx])
    order = np.argsort(pts[:, 2])
    furniture = [o for o in result.scene.objects if not o.is_structure]

    fig = plt.figure(figsize=(15, 12))
    fig.suptitle(f"{result.summary()}{note}", fontsize=11)
    for col, (colors, label) in enumerate([(rgb, "sensor colours"), (by_class, "class")]):
        top = fig.add_subplot(2, 2, 1 + col)
        top.scatter(
            pts[order, 0], pts[order, 1], c=colors[order], s=0.8, linewidths=0, rasterized=True
        )
        top.set_aspect("equal")
        top.set_title(f"top view, {label}")
        top.set_xlabel("x (m)")
        top.set_ylabel("y (m)")
        persp = fig.add_subplot(2, 2, 3 + col, projection="3d")
        persp.scatter(
            pts[:, 0],
            pts[:, 1],
            pts[:, 2],
            c=colors,
            s=0.5,
            linewidths=0,
            depthshade=False,
            rasterized=True,
        )
        if col == 1:
            for obj in furniture:
                corners = box_corners(obj.box.center, obj.box.size, obj.box.yaw)
                color = class_color(obj.class_name)
                for a, b in BOX_EDGES[:4]:
                    top.plot(*corners[[a, b], :2].T, color=color, lw=0.8)
                for a, b in BOX_EDGES:
                    persp.plot(*corners[[a, b]].T, color=color, lw=0.6)
            names = sorted({o.class_name for o in furniture})
            handles = [
                plt.Line2D([], [], marker="o", ls="", color=class_color(n), label=n) for n in names
            ]
            top.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
        if col == 0:
            poses = out.poses[:, :3, 3]
            top.plot(
                poses[:, 0],
                poses[:, 1],
                "k^",
                ms=4,
                label="sensor",
            )
            top.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
        extent = np.ptp(pts, axis=0)
        persp.set_box_aspect(np.maximum(extent, 1e-3), zoom=1.35)
        persp.view_init(elev=32, azim=-58)
        persp.set_title(f"perspective, {label}")
        persp.set_axis_off()
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=72, metadata={"Software": None})
    plt.close(fig)
    # A 256-colour palette keeps the pictures small enough for the repository.
    image = Image.open(io.BytesIO(buf.getvalue())).convert("RGB").quantize(PALETTE_COLORS)
    small = io.BytesIO()
    image.save(small, format="PNG", optimize=True)
    return small.getvalue()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=Path(__file__).parent.parent / "docs" / "gallery"
    )
    parser.add_argument("--points", type=int, default=200_000)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for room, sensor, seed in SCENES:
        path = args.out / f"{room}-{sensor}.png"
        atomic_write_bytes(path, render(room, sensor, seed, args.points))
        print(path)


if __name__ == "__main__":
    main()
