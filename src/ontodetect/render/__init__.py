"""Pictures of scans and results: a top view and a perspective view, rasterised with NumPy
and finished with Pillow, and ``view.html``, a self-contained page to turn a result around
in a browser (three.js, vendored and inlined: no network).

Objects are coloured by class and outlined by their oriented boxes; the rest of
the scan is drawn in its own colours, faded, so that the objects stand out.
Rendering never needs a screen.
"""

from __future__ import annotations

from ..geometry import box_corners
from ._scene import CLASS_COLORS, MAX_POINTS, BoxDrawing, class_color, render_scene
from ._viewer import (
    CHROMIUM_FLAGS,
    THREE_VERSION,
    VIEWER_MAX_POINTS,
    thin_points,
    viewer_html,
    write_viewer,
)

__all__ = [
    "CHROMIUM_FLAGS",
    "CLASS_COLORS",
    "MAX_POINTS",
    "THREE_VERSION",
    "VIEWER_MAX_POINTS",
    "BoxDrawing",
    "box_corners",
    "class_color",
    "render_scene",
    "thin_points",
    "viewer_html",
    "write_viewer",
]
