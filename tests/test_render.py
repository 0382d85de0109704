import numpy as np
import pytest

from ontodetect.render import BoxDrawing, box_corners, render_scene


def test_box_corners_rotate_about_the_centre():
    c = box_corners([1.0, 2.0, 0.5], [2.0, 1.0, 1.0], np.pi / 2)
    assert c.shape == (8, 3)
    assert np.allclose(c.mean(axis=0), [1.0, 2.0, 0.5])
    # length 2 along x becomes length 2 along y after a quarter turn
    assert np.ptp(c[:, 1]) == pytest.approx(2.0)
    assert np.ptp(c[:, 0]) == pytest.approx(1.0)


def test_render_writes_a_png(tmp_path, rng):
    xyz = rng.uniform(0, 3, (2000, 3))
    classes = np.where(xyz[:, 0] < 1, "chair", None)
    out = render_scene(
        tmp_path / "scene.png",
        xyz,
        point_class=classes,
        boxes=[BoxDrawing([0.5, 1.5, 0.4], [0.5, 0.5, 0.8], 0.2, "chair", "0.9")],
        title="test",
        legend_counts={"chair": 1},
    )
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(data) > 10_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.png"]
