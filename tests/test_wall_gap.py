"""``wall_gap``: how far a cluster stands from the nearest voxel taken as wall. A panel
radiator hangs on its wall (EN 442 brackets: 25-50 mm off it); a chair seen from behind,
whose backrest is a panel as wide as a radiator's, stands in the room."""

import dataclasses
import math

import numpy as np
import pytest

from ontodetect.ontology import builtin_ontology, score_class
from ontodetect.segment import segment, wall_gaps
from test_ontology import P, cluster
from test_preprocess import box, rect


def _room(rng, walls=True):
    """A 5 x 4 m room scanned to 2.4 m: a radiator on the wall at y = 0 (4 cm off it, from
    0.15 to 0.75 m) and a box standing 1.5 m from every wall."""
    w, d, top = 5.0, 4.0, 2.4
    parts = [rect(rng, (0, 0, 0), (w, 0, 0), (0, d, 0), 0.03)]
    if walls:
        parts += [
            rect(rng, (0, 0, 0), (w, 0, 0), (0, 0, top), 0.03),
            rect(rng, (0, d, 0), (w, 0, 0), (0, 0, top), 0.03),
            rect(rng, (0, 0, 0), (0, d, 0), (0, 0, top), 0.03),
            rect(rng, (w, 0, 0), (0, d, 0), (0, 0, top), 0.03),
        ]
    radiator = box(rng, (1.5, 0.04, 0.15), (2.5, 0.14, 0.75), 0.02)
    middle = box(rng, (1.5, 1.5, 0.0), (2.1, 2.5, 0.9), 0.02)
    return np.vstack([*parts, radiator, middle])


def _gap_at(seg, gaps, where):
    """The gap of the cluster whose box centre is nearest ``where`` (x, y)."""
    k = int(np.argmin([np.linalg.norm(np.asarray(c.box.center)[:2] - where) for c in seg]))
    return gaps[k]


def test_a_radiator_hangs_on_its_wall_and_a_box_stands_in_the_room():
    seg = segment(_room(np.random.default_rng(0)))
    gaps = wall_gaps(seg)
    assert len(gaps) == len(seg)
    assert _gap_at(seg, gaps, (2.0, 0.09)) < 0.1
    assert _gap_at(seg, gaps, (1.8, 2.0)) == pytest.approx(1.5, abs=0.05)


def test_no_wall_no_measure():
    seg = segment(_room(np.random.default_rng(0), walls=False))
    assert len(seg) >= 2
    assert np.isnan(wall_gaps(seg)).all()


def _panel(wall_gap):
    """An upright panel 1.0 x 0.5 m from 0.15 m up, 10 cm deep: a radiator's or a
    backrest's seen alone."""
    desc = cluster(
        [P(tilt=90, height=0.45, length=1.0, width=0.6)], length=1.0, breadth=0.1, height=0.75
    )
    return dataclasses.replace(desc, bottom=0.15, wall_gap=wall_gap)


def test_a_radiator_away_from_every_wall_costs_and_an_unmeasured_gap_does_not():
    radiator = next(c for c in builtin_ontology().classes if c.name == "radiator")

    def factor(gap):
        s = score_class(radiator, _panel(gap))
        return next(c.factor for c in s.constraints if c.feature == "wall_gap")

    assert factor(0.05) == pytest.approx(1.0)
    assert factor(1.0) < 1e-3
    assert factor(math.nan) == 1.0
    on_wall = score_class(radiator, _panel(0.05)).log_likelihood
    unknown = score_class(radiator, _panel(math.nan)).log_likelihood
    assert on_wall == pytest.approx(unknown)


def test_a_radiators_panel_reaches_down_near_the_floor_and_a_backrest_does_not():
    """EN 442 radiators are fitted 100-150 mm above the floor; a backrest seen from behind
    is a panel as wide whose lowest points are its seat's: the same panel top (0.75 m),
    from 0.15 m and from 0.45 m."""
    radiator = next(c for c in builtin_ontology().classes if c.name == "radiator")

    def score(bottom):
        panel = P(tilt=90, height=(bottom + 0.75) / 2, length=1.0, width=0.75 - bottom)
        desc = cluster([panel], length=1.0, breadth=0.1, height=0.75)
        return score_class(radiator, dataclasses.replace(desc, bottom=0.15, wall_gap=0.05))

    low, high = score(0.15), score(0.45)
    assert next(
        c.factor for c in low.constraints if c.feature == "bottom" and c.part == "panel"
    ) == (pytest.approx(1.0))
    assert low.log_likelihood - high.log_likelihood > math.log(20)
