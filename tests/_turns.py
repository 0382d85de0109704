"""What a detection turned with its scan must keep: shared by the tests of the quarter turns
and of the walls along the axes."""

import math

import numpy as np


def found(result):
    """Each detection's label, points and score: what must not move when the scan turns."""
    return sorted(
        (d.label, tuple(np.asarray(d.point_indices).tolist()), round(d.score, 9))
        for d in result.detections
    )


def assert_turned_with_the_scan(base, turned, degrees: float) -> None:
    """``turned`` (the scan turned by ``degrees`` about z) finds ``base``'s detections, their
    boxes turned with it, in its own axes."""
    assert found(turned) == found(base), degrees
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    for a, b in zip(
        sorted(base.detections, key=lambda d: d.point_indices[0]),
        sorted(turned.detections, key=lambda d: d.point_indices[0]),
    ):
        assert np.allclose(rot @ a.center, b.center, atol=1e-6)
        turn = (b.yaw - a.yaw - math.radians(degrees)) % math.pi
        assert min(turn, math.pi - turn) < 1e-6  # a box's axis: up to half a turn
