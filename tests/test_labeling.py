"""Energy labelling (Eq. 3.6–3.8) against hand computation."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ontodetect.errors import InvalidParameterError
from ontodetect.labeling import energy, label_clusters, label_costs, label_fit
from ontodetect.ontology import (
    ClassScore,
    ClusterScores,
    Gaussian,
    LabelModel,
    builtin_ontology,
)


def scores(**probs):
    probs = {"chair": 0, "sofa": 0, "table": 0, "stool": 0, "bench": 0, **probs}
    probs["none"] = max(0.0, 1 - sum(probs.values()))
    best = max(probs, key=probs.get)
    return ClusterScores(classes={}, probabilities=probs, best=best)


def plane(length, width, color=None):
    return SimpleNamespace(length=length, width=width, color_mean=color)


def test_energy_matches_hand_computation():
    p, f, beta = 0.604, 0.3, 0.7
    by_hand = 1 - 0.7 / (1 + math.exp(-0.604)) - 0.3 / (1 + math.exp(-0.3))
    assert energy(p, f, beta=beta, gamma=0.3) == pytest.approx(by_hand)
    assert energy(0, 0) == pytest.approx(0.5)
    with pytest.raises(InvalidParameterError, match="beta \\+ gamma"):
        energy(0.5, 0.5, beta=0.6, gamma=0.6)


def test_label_fit_is_the_product_over_planes():
    model = LabelModel(color=((100.0, 50.0, 0.0), 40.0), plane_size=Gaussian(0.45, 0.2))
    planes = [plane(0.45, 0.4, (100, 50, 0)), plane(0.65, 0.3, (140, 50, 0))]
    by_hand = 1.0 * 1.0 * math.exp(-0.5) * math.exp(-0.5)
    assert label_fit(planes, model) == pytest.approx(by_hand)
    assert label_fit(planes, LabelModel()) == 1.0


def test_costs_prefer_table_for_a_large_top():
    o = builtin_ontology()
    s = scores(chair=0.30, table=0.35)
    costs = label_costs(s, [plane(1.2, 0.8)], o)
    assert costs["table"] < costs["chair"]
    p, f = 0.35, float(o["table"].labeling.plane_size(1.2))
    assert costs["table"] == pytest.approx(1 - 0.5 / (1 + math.exp(-p)) - 0.5 / (1 + math.exp(-f)))


def test_threshold_and_not_reported_classes():
    o = builtin_ontology()
    out = label_clusters(
        [scores(chair=0.1), scores(chair=0.7), scores(stool=0.8)], [[plane(0.4, 0.4)]] * 3, o
    )
    assert out[0].label is None and out[0].reason == "none of the classes"
    assert out[1].label == "chair"
    assert out[2].label is None and "stool" in out[2].reason


def test_classes_sharing_a_label_are_weighed_together():
    """A small top whose table-ness is split between "table" and "side_table" (0.25 + 0.2)
    is a table, not the chair (0.3) that beats each of them alone; the costs of both classes
    use the label's probability, 0.45."""
    o = builtin_ontology()
    s = scores(chair=0.3, table=0.25, side_table=0.2)
    top = [plane(0.55, 0.5)]
    costs = label_costs(s, top, o)
    f = float(o["side_table"].labeling.plane_size(0.55))
    assert costs["side_table"] == pytest.approx(energy(0.45, f))
    (choice,) = label_clusters([s], [top], o)
    assert choice.label == "table" and choice.extra["class"] == "side_table"
    # Neither class alone passes the threshold, nor beats "none"; the label does both.
    probs = {
        "table": 0.12,
        "side_table": 0.1,
        "chair": 0.14,
        "sofa": 0.14,
        "stool": 0.14,
        "bench": 0.14,
        "cabinet": 0.08,
        "none": 0.14,
    }
    split = ClusterScores(classes={}, probabilities=probs, best="chair")
    (choice,) = label_clusters([split], [top], o, threshold=0.15)
    assert choice.label == "table"


CLASSES = (
    "chair",
    "sofa",
    "table",
    "side_table",
    "stool",
    "ottoman",
    "bench",
    "cabinet",
    "bed",
    "none",
)


@settings(max_examples=200, deadline=None)
@given(
    weights=st.lists(st.floats(0.0, 1.0), min_size=len(CLASSES), max_size=len(CLASSES)),
    threshold=st.floats(0.05, 0.5),
)
def test_a_label_is_chosen_only_when_its_probability_earns_it(weights, threshold):
    """Whatever the probabilities: the chosen class's label reaches the threshold and beats
    "none"; nothing is chosen when "none" beats every label or no label reaches the
    threshold; and the labels' probabilities and "none" add up to 1."""
    from ontodetect.labeling import label_probability

    o = builtin_ontology()
    total = sum(weights)
    if total <= 0:
        return
    probs = {name: w / total for name, w in zip(CLASSES, weights)}
    s = ClusterScores(classes={}, probabilities=probs, best=max(probs, key=probs.get))
    (choice,) = label_clusters([s], [[plane(0.6, 0.5)]], o, threshold=threshold)
    labels = {c.label for c in o.classes}
    by_label = {lab: label_probability(probs, o, lab) for lab in labels}
    assert sum(by_label.values()) + probs["none"] == pytest.approx(1.0)
    best = max(by_label.values())
    cls = choice.extra.get("class")
    if cls is None:
        assert probs["none"] > best or best < threshold
    else:
        assert by_label[o[cls].label] >= threshold
        assert probs["none"] <= best


def test_exclusion_keeps_the_cheaper_of_two_overlapping_hypotheses():
    o = builtin_ontology()
    s = [scores(chair=0.5), scores(chair=0.9)]
    out = label_clusters(s, [[plane(0.45, 0.4)]] * 2, o, overlaps={(0, 1): 0.4})
    assert [c.label for c in out] == [None, "chair"]
    assert out[0].reason == "excluded by an overlap"


def test_context_tips_an_ambiguous_seat_towards_chair_near_a_table():
    o = builtin_ontology()
    amb = scores(chair=0.40, table=0.40)
    planes = [[plane(0.9, 0.6)], [plane(1.4, 0.8)]]
    centers = np.array([[0.0, 0.0, 0.4], [0.5, 0.0, 0.7]])
    alone = label_clusters([amb, scores(table=0.9)], planes, o)
    helped = label_clusters([amb, scores(table=0.9)], planes, o, centers=centers, context=0.2)
    assert alone[0].label == "table"
    assert helped[0].label == "chair"
    assert helped[1].label == "table"


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [({"beta": 1.5}, "beta"), ({"threshold": -0.1}, "threshold"), ({"context": -1}, "context")],
)
def test_bad_parameters(kwargs, name):
    with pytest.raises(InvalidParameterError, match=f"'{name}'"):
        label_clusters([scores(chair=0.5)], [[plane(0.4, 0.4)]], builtin_ontology(), **kwargs)


def _with_priors(s, **priors):
    """``s`` with a class score per class named, holding only its room prior P_obj."""
    classes = {k: ClassScore(k, 0.0, math.log(p), {}, {}, ()) for k, p in priors.items()}
    return ClusterScores(classes=classes, probabilities=s.probabilities, best=s.best)


@pytest.mark.parametrize(
    ("other", "length", "room_favours", "explains"),
    [
        ("sink", 0.3, True, True),
        ("toilet", 0.6, True, True),
        ("sink", 0.3, False, False),
        ("toilet", 0.6, False, False),
        ("stool", 0.6, True, False),
    ],
)
def test_a_likelier_competitor_explains_a_chair_away_where_the_room_favours_it(
    other, length, room_favours, explains
):
    """Eq. 3.7's plane-size term gives each of these clusters to the chair, though the
    ontology finds the competitor likelier (0.4 against 0.3). With ``explain_away`` a sink
    or a WC takes the cluster (no reported label) in a room whose prior makes it likelier
    than a chair (a bathroom: 1 against 0.3), not where both are as likely (1 and 1); a
    stool never does, since a chair whose backrest the scan lost reads as one."""
    o = builtin_ontology()
    priors = {"chair": 0.3 if room_favours else 1.0, other: 1.0}
    s = _with_priors(scores(chair=0.3, **{other: 0.4}), **priors)
    seat = [plane(length, 0.4)]
    (default,) = label_clusters([s], [seat], o)
    assert default.label == "chair"
    (choice,) = label_clusters([s], [seat], o, explain_away=True)
    if explains:
        assert choice.label is None and choice.reason.endswith("(not reported)")
        assert o[choice.extra["class"]].label == o[other].label
        # --explain says what was barred and by what.
        assert choice.extra["explained_away"] == ["chair"]
        assert choice.extra["explained_by"] == o[other].label
    else:
        assert choice == default
    # Reporting every class (--classes all) changes what a win yields, not who wins: the
    # competitor that explained the chair away is reported, and a chair stays a chair.
    (every,) = label_clusters([s], [seat], o.reporting("all"), explain_away=True)
    assert every.extra["class"] == choice.extra["class"]
    assert every.label == o[choice.extra["class"]].label
