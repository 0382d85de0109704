"""A seat that is level but not flat (``segment.planes.seat_layer``, ``planes.seat_layer``):
the upward-facing points at seat height of a cluster where MSAC fitted no level plane,
offered to the parts that say ``layer``."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _clusters import describe_points
from ontodetect.config import Config
from ontodetect.ontology import builtin_ontology
from ontodetect.ontology._score import score_class
from ontodetect.preprocess import graph_normals
from ontodetect.segment import radius_graph
from ontodetect.segment.planes import Patch, extract_planes, seat_layer


def _cushion(z=0.45, sag=0.03, size=0.45, per=1200, seed=0):
    """A square seat whose middle sags ``sag`` below its edges (a paraboloid)."""
    gen = np.random.default_rng(seed)
    u, v = gen.uniform(0.0, size, (2, per))
    r2 = ((u - size / 2) ** 2 + (v - size / 2) ** 2) / (size / 2) ** 2
    return np.c_[u, v, z - sag * (1.0 - np.minimum(r2, 2.0) / 2.0)]


def _back(z0=0.47, height=0.45, size=0.45, lean=15.0, per=900, seed=1):
    """A backrest along the seat's rear edge (y = size), leaning back ``lean`` degrees."""
    gen = np.random.default_rng(seed)
    u, h = gen.uniform(0.0, size, per), gen.uniform(0.0, height, per)
    return np.c_[u, size + h * math.tan(math.radians(lean)), z0 + h]


def _legs(z=0.45, size=0.45, per=60, seed=2):
    """Four legs from the floor up to under a seat of side ``size`` at height ``z``."""
    gen = np.random.default_rng(seed)
    corners = [(0.02, 0.02), (size - 0.02, 0.02), (0.02, size - 0.02), (size - 0.02, size - 0.02)]
    return np.vstack(
        [
            np.c_[np.full(per, x), np.full(per, y), gen.uniform(0.0, z - 0.05, per)]
            for x, y in corners
        ]
    )


def _normals(pts, radius=0.05):
    return graph_normals(pts, radius_graph(pts, radius))[0]


def _layer(pts, planes=(), radius=0.05):
    return seat_layer(
        pts, list(planes), _normals(pts, radius), threshold=0.01, min_points=20,
        connectivity=radius, rng=0,
    )  # fmt: skip


def test_a_sagging_cushion_is_one_layer_at_its_height():
    pts = np.vstack([_cushion(), _back(), _legs()])
    layer = _layer(pts)
    assert isinstance(layer, Patch) and layer.kind == "layer"
    assert layer.tilt < 3.0
    assert layer.height == pytest.approx(0.44, abs=0.02)
    # The band is 2 cm high, so it holds the flatter part of the cushion, most of its width.
    assert layer.length > 0.3 and layer.width > 0.2
    assert layer.members == ()  # no planes were given
    # The same points turned about the vertical give the same layer.
    c, s = math.cos(0.7), math.sin(0.7)
    turned = pts @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    again = _layer(turned)
    assert again.num_points == layer.num_points
    assert again.height == pytest.approx(layer.height, abs=1e-9)


def test_no_layer_where_a_level_plane_already_lies_at_seat_height():
    flat = np.vstack([_cushion(sag=0.0), _back(), _legs()])
    planes = extract_planes(flat, threshold=0.005, max_planes=4, min_points=40, rng=0)
    assert any(p.tilt < 2.0 for p in planes)
    assert _layer(flat, planes) is None


def test_bands_across_upright_surfaces_are_no_seat():
    gen = np.random.default_rng(3)
    # A wall and a curtain hanging in folds 8 cm deep: at seat height their points face
    # sideways, however many lie at one height.
    wall = np.c_[gen.uniform(0, 2.0, 6000), np.zeros(6000), gen.uniform(0, 2.4, 6000)]
    x = gen.uniform(0, 2.0, 6000)
    curtain = np.c_[x, 0.5 + 0.04 * np.sin(x * 2 * math.pi / 0.25), gen.uniform(0, 2.4, 6000)]
    for pts in (wall, curtain):
        assert _layer(pts) is None
    # Nothing at seat height at all (a table's top at 74 cm on its legs).
    top = np.c_[gen.uniform(0, 1.2, 3000), gen.uniform(0, 0.7, 3000), np.full(3000, 0.74)]
    assert _layer(top + [0, 0, 0.1]) is None


def test_a_layer_must_be_the_one_surface_there():
    # Two equal level shelves 20 cm apart at seat height (a low bookcase): neither holds
    # half of the upward-facing points there.
    gen = np.random.default_rng(4)
    shelves = [
        np.c_[gen.uniform(0, 0.8, 800), gen.uniform(0, 0.3, 800), z + 0.01 * gen.random(800)]
        for z in (0.35, 0.6)
    ]
    sides = np.c_[gen.uniform(0, 0.8, 400), np.full(400, -0.1), gen.uniform(0, 0.6, 400)]
    assert _layer(np.vstack([*shelves, sides])) is None
    assert _layer(np.vstack([shelves[0], sides])) is not None
    # A cushion with nothing under it down to the floor (on a bed, on a shelf): no seat.
    assert _layer(np.vstack([_cushion(), _back()])) is None


@settings(max_examples=20, deadline=None)
@given(sag=st.floats(0.0, 0.04), z=st.floats(0.36, 0.6), seed=st.integers(0, 10_000))
def test_any_cushion_gives_a_level_layer_at_its_rim_or_below(sag, z, seed):
    pts = np.vstack(
        [_cushion(z=z, sag=sag, seed=seed), _back(z0=z + 0.02, seed=seed + 1), _legs(z=z)]
    )
    layer = _layer(pts)
    assert layer is not None and layer.tilt <= 10.0
    assert z - sag - 0.011 <= layer.height <= z + 0.011


def _scored(layer_on):
    """The chair's score on a sagging seat and a flat backrest, with MSAC's planes only or
    with the seat's layer beside them."""
    back = _back(lean=12.0)
    # The back's points first: its inliers index both.
    pts = np.vstack([back, _cushion(sag=0.04), _legs()])
    # The backrest fitted and the seat not, as MSAC leaves a cushion when its best plane
    # runs slanted through seat and back.
    planes = extract_planes(back, threshold=0.004, max_planes=2, min_points=60, rng=0)
    assert len(planes) == 1 and planes[0].tilt > 60.0
    patches = [_layer(pts, planes)] if layer_on else []
    assert None not in patches
    return planes, patches, describe_points(pts, [*planes, *patches])


def test_the_chair_takes_the_layer_as_its_seat_and_the_table_cannot():
    onto = builtin_ontology()
    planes, _, without = _scored(layer_on=False)
    _, (_layer_patch,), with_layer = _scored(layer_on=True)
    k = len(planes)
    chair_without = score_class(onto["chair"], without)
    chair_with = score_class(onto["chair"], with_layer)
    assert chair_without.assignment["seat"] != k
    assert chair_with.assignment["seat"] == k
    assert chair_with.log_likelihood > chair_without.log_likelihood
    # The layer costs nothing as clutter where no part takes it.
    table = score_class(onto["table"], with_layer)
    assert k not in table.assignment.values()
    assert table.log_likelihood == pytest.approx(score_class(onto["table"], without).log_likelihood)
    assert with_layer.layer.tolist() == [False] * k + [True]


def test_the_option_adds_layers_and_moves_no_plane():
    from ontodetect.segment import segment
    from ontodetect.synth import synthesize

    cloud = synthesize("office", "rgbd", seed=2, points=50_000).cloud
    off = segment(cloud, Config(), seed=0, ontology=builtin_ontology())
    on = segment(cloud, Config().with_overrides(["planes.seat_layer=true"]), seed=0)
    assert [len(c.voxels) for c in on] == [len(c.voxels) for c in off]
    assert all(len(a.planes) == len(b.planes) for a, b in zip(on, off))
    added = [p for a, b in zip(on, off) for p in a.patches[len(b.patches) :] if p.kind == "layer"]
    assert added and all(p.kind != "layer" for c in off for p in c.patches)
    for p in added:
        assert 0.29 <= p.height <= 0.76 and p.tilt <= 10.0
