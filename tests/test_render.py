import numpy as np
import pytest
from PIL import Image

from ontodetect.render import BoxDrawing, box_corners, class_color, render_scene

CHAIR = tuple(round(255 * c) for c in class_color("chair"))


def test_box_corners_rotate_about_the_centre():
    c = box_corners([1.0, 2.0, 0.5], [2.0, 1.0, 1.0], np.pi / 2)
    assert c.shape == (8, 3)
    assert np.allclose(c.mean(axis=0), [1.0, 2.0, 0.5])
    # length 2 along x becomes length 2 along y after a quarter turn
    assert np.ptp(c[:, 1]) == pytest.approx(2.0)
    assert np.ptp(c[:, 0]) == pytest.approx(1.0)


def _scene(rng):
    """Points in a 3 m cube; those with x < 1 are a chair, boxed at its centre."""
    xyz = rng.uniform(0, 3, (2000, 3))
    classes = np.where(xyz[:, 0] < 1, "chair", None)
    box = BoxDrawing([0.5, 1.5, 0.4], [0.5, 0.5, 0.8], 0.2, "chair", "0.9")
    return xyz, classes, box


def _pixels(path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


def _chair_pixels(image: np.ndarray) -> np.ndarray:
    return np.all(image == CHAIR, axis=2)


def test_render_writes_a_png(tmp_path, rng):
    xyz, classes, box = _scene(rng)
    out = render_scene(
        tmp_path / "scene.png",
        xyz,
        point_class=classes,
        boxes=[box],
        title="test",
        legend_counts={"chair": 1},
    )
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.png"]
    image = _pixels(out)
    assert image.shape == (715, 1540, 3)  # 14 x 6.5 inches at 110 dpi


def test_the_picture_shows_the_objects_in_both_views_and_the_legend(tmp_path, rng):
    xyz, classes, box = _scene(rng)
    out = render_scene(tmp_path / "scene.png", xyz, point_class=classes, boxes=[box])
    image = _pixels(out)
    chair = _chair_pixels(image)
    width = image.shape[1]
    top, perspective, legend = chair[:650, : width // 2], chair[:650, width // 2 :], chair[650:]
    assert top.sum() > 500 and perspective.sum() > 500  # the chair's points, both views
    assert legend.sum() > 20  # the legend's swatch
    # In the top view the chair is the left third of the cube (x < 1 of 0..3).
    cols = np.flatnonzero(top.any(axis=0))
    background = np.flatnonzero((image[:650, : width // 2] < 250).any(axis=2).any(axis=0))
    assert cols.max() < background.min() + 0.5 * (background.max() - background.min())
    # Other points are drawn too, faded: grey, lighter than the chair's red.
    grey = np.all(image == round(255 * (0.55 * 0.55 + 0.45)), axis=2)
    assert grey.sum() > 500


def test_without_classes_nothing_is_drawn_in_a_class_colour(tmp_path, rng):
    xyz, _, _ = _scene(rng)
    image = _pixels(render_scene(tmp_path / "a.png", xyz))
    assert not _chair_pixels(image).any()
    assert (image < 250).any()  # the points are there


def test_the_same_scene_gives_the_same_picture(tmp_path, rng):
    xyz, classes, box = _scene(rng)
    a = render_scene(tmp_path / "a.png", xyz, point_class=classes, boxes=[box], title="t")
    b = render_scene(tmp_path / "b.png", xyz, point_class=classes, boxes=[box], title="t")
    assert a.read_bytes() == b.read_bytes()


def test_an_empty_scan_still_gives_a_picture(tmp_path):
    out = render_scene(tmp_path / "empty.png", np.zeros((0, 3)), title="nothing")
    assert _pixels(out).shape == (715, 1540, 3)
