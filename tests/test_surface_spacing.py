"""The sampling spacing of a scan, from dense sensors to a fixed-size subsample of a large
room (ScanNet's 50,000 vertices of a 100-200 m² hall: 7-10 cm) and sparser."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect import _up
from ontodetect.preprocess import surface_spacing, voxelize

VOXEL = 0.02


def _room(spacing: float, rng: np.random.Generator) -> np.ndarray:
    """Floor (8 x 6 m) and two walls (2.5 m) sampled uniformly at random, one point per
    ``spacing``² of surface on average, as a random subsample of a mesh's vertices is."""
    out = []
    for a, b, axes in [(8.0, 6.0, (0, 1)), (8.0, 2.5, (0, 2)), (6.0, 2.5, (1, 2))]:
        n = rng.poisson(a * b / spacing**2)
        p = np.zeros((n, 3))
        p[:, axes[0]], p[:, axes[1]] = rng.random(n) * a, rng.random(n) * b
        out.append(p)
    return np.vstack(out)


def _spacing(points: np.ndarray) -> float:
    return surface_spacing(voxelize(points, VOXEL).centers, VOXEL)


@settings(max_examples=12, deadline=None)
@given(spacing=st.floats(0.05, 0.15), seed=st.integers(0, 2**16))
def test_a_sparse_scan_measures_its_own_spacing(spacing, seed):
    assert _spacing(_room(spacing, np.random.default_rng(seed))) / spacing == pytest.approx(
        0.95, abs=0.15
    )


def test_sparse_scans_are_measured_on_larger_cells(monkeypatch):
    # At 10 cm a 0.2 m cell holds 4 points on average, and a cell counts as planar from
    # MIN_CELL_POINTS: only the fuller cells are counted, and on them alone the spacing
    # came out 30 % short. Larger cells hold enough points to count every full one.
    points = _room(0.1, np.random.default_rng(0))
    assert _spacing(points) == pytest.approx(0.1, rel=0.15)
    monkeypatch.setattr(_up, "MIN_FULL_CELL", 0.0)  # 0.2 m cells whatever they hold
    assert _spacing(points) < 0.075


def test_a_dense_scan_keeps_the_small_cells(monkeypatch):
    points = _room(0.03, np.random.default_rng(1))
    dense = _spacing(points)
    assert dense == pytest.approx(0.03, rel=0.1)
    monkeypatch.setattr(_up, "MIN_FULL_CELL", 0.0)
    assert _spacing(points) == dense
