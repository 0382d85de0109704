"""The one sign rule for normals and axes: largest component positive, ties by z, y, x."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ontodetect.geometry import SIGN_TIE_TOLERANCE, canonical_sign
from ontodetect.segment.planes import PlaneModel

TOL = SIGN_TIE_TOLERANCE


@pytest.mark.parametrize(
    ("vector", "expected"),
    [
        ([1.0, -2.0, 2.0], 1.0),  # |y| == |z|: z decides
        ([1.0, 2.0, -2.0], -1.0),
        ([-3.0, 3.0, 0.0], 1.0),  # |x| == |y|: y decides
        ([3.0, -3.0, 0.0], -1.0),
        ([-1.0, 1.0, 1.0], 1.0),  # all three tied: z
        ([-1.0, 1.0, -1.0], -1.0),
        ([-2.0, 0.0, 2.0], 1.0),  # |x| == |z|: z, not x
    ],
)
def test_exact_tie_goes_to_z_then_y_then_x(vector, expected):
    assert canonical_sign(np.array(vector)) == expected


def test_no_tie_follows_the_largest_component():
    assert canonical_sign(np.array([-0.9, 0.3, 0.3])) == -1.0
    assert canonical_sign(np.array([0.1, -0.2, 0.97])) == 1.0
    assert canonical_sign(np.array([0.5, -0.8, 0.33])) == -1.0


@pytest.mark.parametrize("delta", [0.0, 0.25 * TOL, 0.99 * TOL])
def test_near_tie_within_tolerance_is_a_tie(delta):
    # |y| exceeds |z| by less than the tolerance: still z decides.
    v = np.array([0.1, -(2 / 3 + delta), 2 / 3])
    assert canonical_sign(v) == 1.0
    assert canonical_sign(-v) == -1.0


@pytest.mark.parametrize("delta", [3 * TOL, 1e-6, 1e-3])
def test_near_tie_beyond_tolerance_is_not_a_tie(delta):
    # |y| exceeds |z| by more than the tolerance: y decides.
    v = np.array([0.1, -(2 / 3 + delta), 2 / 3])
    assert canonical_sign(v) == -1.0
    assert canonical_sign(-v) == 1.0


def test_zero_vector_keeps_its_sign():
    assert canonical_sign(np.zeros(3)) == 1.0


@given(
    st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=3, max_size=3).filter(
        lambda v: max(abs(x) for x in v) > 1e-6
    )
)
def test_rule_is_odd_and_scale_free(values):
    v = np.array(values)
    s = canonical_sign(v)
    assert s in (1.0, -1.0)
    # Exactly one of v and -v is kept, whatever its length.
    assert canonical_sign(-v) == -s
    assert canonical_sign(s * v) == 1.0


def test_plane_fit_orients_by_the_rule_at_a_last_bit_tie():
    # The normal (1, -2, 2) / 3 comes back with |n_y| and |n_z| differing in the last bit
    # depending on the library build; the fitted normal is the same either way.
    rng = np.random.default_rng(7)
    normal = np.array([1.0, -2.0, 2.0]) / 3.0
    u = np.cross(normal, [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(normal, u)
    pts = rng.uniform(-1, 1, (40, 1)) * u + rng.uniform(-1, 1, (40, 1)) * w
    for flip in (1.0, -1.0):
        model = PlaneModel.from_estimate(pts * flip)
        assert model is not None
        np.testing.assert_allclose(model.normal, normal, atol=1e-12)
