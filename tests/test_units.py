"""Nearest-neighbour spacing without SciPy: the same distances as a k-d tree."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from ontodetect._units import estimate_spacing, nearest_other_sq
from ontodetect.errors import InvalidParameterError


def _tree_sq(points, rows):
    dist, _ = cKDTree(points).query(points[rows], k=2)
    return dist[:, 1] ** 2


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 400),
    shape=st.sampled_from(["cube", "plane", "cluster+far", "duplicates", "line"]),
)
def test_grid_search_equals_the_kdtree(seed, n, shape):
    rng = np.random.default_rng(seed)
    if shape == "cube":
        p = rng.random((n, 3))
    elif shape == "plane":
        p = np.c_[rng.random((n, 2)) * 7, np.full(n, 1.3)]
    elif shape == "cluster+far":
        p = np.r_[rng.random((n, 3)) * 0.05, [[400.0, -30.0, 2.0]]]
    elif shape == "duplicates":
        p = np.repeat(rng.random((n // 2 + 1, 3)), 2, axis=0)
    else:
        p = np.c_[np.sort(rng.random(n)) * 3, np.zeros((n, 2))]
    rows = rng.choice(len(p), min(len(p), 50), replace=False)
    np.testing.assert_allclose(nearest_other_sq(p, rows), _tree_sq(p, rows), rtol=1e-12, atol=0)


def test_lone_and_coincident_points():
    assert nearest_other_sq(np.zeros((1, 3)), np.array([0])).tolist() == [np.inf]
    assert nearest_other_sq(np.ones((4, 3)), np.arange(4)).tolist() == [0.0] * 4


def test_spacing_is_the_same_either_way():
    rng = np.random.default_rng(3)
    g = np.stack(np.meshgrid(np.arange(60), np.arange(50), [0]), -1).reshape(-1, 3) * 0.02
    scan = g + rng.normal(0, 0.002, g.shape)
    grid = estimate_spacing(scan, sample=500, index="grid")
    tree = estimate_spacing(scan, sample=500, index="kdtree")
    assert grid == tree
    assert grid == pytest.approx(0.02, rel=0.25)


def test_unknown_index_is_refused():
    with pytest.raises(InvalidParameterError, match="'index' parameter"):
        estimate_spacing(np.random.default_rng(0).random((10, 3)), index="octree")
