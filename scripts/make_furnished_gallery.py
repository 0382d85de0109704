"""Draw pictures of furnished simulated rooms (Sweet Home 3D models) into docs/images/.

Each picture shows one room scanned by the RGB-D camera: a top view and a
perspective view in the colours the sensor recorded (left) and coloured by the
ground-truth class with the furniture's boxes (right), and under them the
catalogues, models and creators used (their licences ask for it).

Needs the Sweet Home 3D catalogues (Debian's sweethome3d-furniture, or
ONTODETECT_SH3D_DIR). Usage::

    .venv/bin/python scripts/make_furnished_gallery.py [--out docs/images] [--points 150000]
"""

from __future__ import annotations

import argparse
import io
import sys
import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from PIL import Image

sys.path.insert(0, str(Path(__file__).parent))
from make_gallery import BOX_EDGES, CEILING_CUT, PALETTE_COLORS, _class_colors, class_color

from ontodetect.io import atomic_write_bytes
from ontodetect.render import box_corners
from ontodetect.synth.furnished import attribution_text, synthesize_furnished

#: (room type, seed) of each picture; the file is ``furnished-<room>.png``.
SCENES = [("living_room", 1), ("office", 6), ("open_plan", 0)]
SHOWN_POINTS = 60_000


def render(room: str, seed: int, points: int) -> bytes:
    result = synthesize_furnished(room, "rgbd", seed, points=points)
    cloud = result.output.world_cloud()
    xyz = cloud.xyz
    height = result.scene.size[2]
    inside = (xyz[:, 2] < CEILING_CUT * height) & (xyz[:, 2] > -0.5)
    inside &= np.all(
        (xyz[:, :2] > -0.5) & (xyz[:, :2] < np.asarray(result.scene.size[:2]) + 0.5), axis=1
    )
    idx = np.flatnonzero(inside)
    if len(idx) > SHOWN_POINTS:
        idx = np.sort(np.random.default_rng(0).choice(idx, SHOWN_POINTS, replace=False))
    pts = xyz[idx]
    rgb = cloud.rgb[idx] / 255.0
    by_class = _class_colors(cloud.fields["class_id"][idx])
    order = np.argsort(pts[:, 2])
    furniture = [o for o in result.scene.objects if not o.is_structure]
    credits = "Models: " + attribution_text(result.scene).replace("\n", "; ")
    wrapped = textwrap.fill(credits, 190)

    fig = plt.figure(figsize=(15, 12.5))
    fig.suptitle(f"furnished {result.summary()}", fontsize=11)
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
        persp.scatter(*pts.T, c=colors, s=0.5, linewidths=0, depthshade=False, rasterized=True)
        if col == 1:
            for obj in furniture:
                corners = box_corners(obj.box.center, obj.box.size, obj.box.yaw)
                color = class_color(obj.class_name)
                for a, b in BOX_EDGES[:4]:
                    top.plot(*corners[[a, b], :2].T, color=color, lw=0.8)
            names = sorted({o.class_name for o in furniture})
            handles = [
                plt.Line2D([], [], marker="o", ls="", color=class_color(n), label=n) for n in names
            ]
            top.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
        extent = np.ptp(pts, axis=0)
        persp.set_box_aspect(np.maximum(extent, 1e-3), zoom=1.35)
        persp.view_init(elev=38, azim=-58)
        persp.set_title(f"perspective, {label}")
        persp.set_axis_off()
    fig.text(0.01, 0.005, wrapped, fontsize=7, va="bottom", ha="left")
    fig.tight_layout(rect=(0, 0.02 + 0.012 * wrapped.count("\n"), 1, 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=72, metadata={"Software": None})
    plt.close(fig)
    image = Image.open(io.BytesIO(buf.getvalue())).convert("RGB").quantize(PALETTE_COLORS)
    small = io.BytesIO()
    image.save(small, format="PNG", optimize=True)
    return small.getvalue()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=Path(__file__).parent.parent / "docs" / "images"
    )
    parser.add_argument("--points", type=int, default=150_000)
    parser.add_argument("--only", default=None, help="Draw only this room type.")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for room, seed in SCENES:
        if args.only and room != args.only:
            continue
        path = args.out / f"furnished-{room}.png"
        atomic_write_bytes(path, render(room, seed, args.points))
        print(path)


if __name__ == "__main__":
    main()
