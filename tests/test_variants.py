"""A class that describes another one a second way (``variant_of``): the two share a label
and a cluster takes the better of the two descriptions, never their sum."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ontodetect.errors import InvalidOntologyError
from ontodetect.labeling import label_probability
from ontodetect.ontology import (
    ClusterDescription,
    builtin_ontology,
    load_ontology,
    parse_ontology,
    score_cluster,
)
from ontodetect.ontology._score import ClassScore, _posterior

HEADER = "format: ontodetect.ontology/1\nclasses:\n"
SEAT = "    parts:\n      seat: {tilt: {max: 6}, height: [0.4, 0.8]}\n"
#: A cluster of no planes: every class scores it, each by its parts' missing factors.
EMPTY = ClusterDescription(planes=[], relations={}, length=0.6, breadth=0.5, height=0.9, bottom=0.0)


def _score(name, likelihood, group=None):
    return ClassScore(name, math.log(likelihood), 0.0, {}, {}, (), group=group)


def test_the_better_description_takes_the_label_and_the_other_counts_nothing():
    scores = {
        "chair": _score("chair", 0.3),
        "easy_chair": _score("easy_chair", 0.5, group="chair"),
        "toilet": _score("toilet", 0.4),
    }
    p = _posterior(scores, math.log(0.05)).probabilities
    assert p["chair"] == 0.0
    assert p["easy_chair"] == pytest.approx(0.5 / (0.5 + 0.4 + 0.05))
    assert p["toilet"] == pytest.approx(0.4 / (0.5 + 0.4 + 0.05))
    # Summed, the two descriptions would have taken the cluster from the WC by 0.8 to 0.4
    # even though neither alone describes it much better than the WC does.


def test_a_tie_goes_to_the_class_the_variant_describes():
    scores = {"easy_chair": _score("easy_chair", 0.4, "chair"), "chair": _score("chair", 0.4)}
    p = _posterior(scores, math.log(0.05)).probabilities
    assert p["chair"] > 0 and p["easy_chair"] == 0.0


@given(
    st.floats(1e-6, 1.0),
    st.floats(1e-6, 1.0),
    st.floats(1e-6, 1.0),
    st.floats(1e-3, 0.5),
)
def test_a_label_described_twice_is_as_likely_as_its_better_description_alone(a, b, c, none):
    onto = builtin_ontology()
    both = {
        "chair": _score("chair", a),
        "easy_chair": _score("easy_chair", b, group="chair"),
        "toilet": _score("toilet", c),
    }
    better = "chair" if a >= b else "easy_chair"
    alone = {better: both[better], "toilet": both["toilet"]}
    p_both = _posterior(both, math.log(none)).probabilities
    p_alone = _posterior(alone, math.log(none)).probabilities
    assert label_probability(p_both, onto, "chair") == pytest.approx(
        label_probability(p_alone, onto, "chair"), rel=1e-12
    )
    assert p_both["toilet"] == pytest.approx(p_alone["toilet"], rel=1e-12)
    assert sum(p_both.values()) == pytest.approx(1.0)


def test_the_built_in_easy_chair_is_a_variant_of_the_chair():
    onto = builtin_ontology()
    assert onto["easy_chair"].variant_of == "chair"
    assert onto["easy_chair"].label == "chair"
    assert onto.variant_groups()["easy_chair"] == "chair"
    assert onto["chair"].variant_of is None


def test_scoring_gives_one_of_the_two_descriptions_no_probability():
    onto = builtin_ontology()
    scores = score_cluster(EMPTY, onto)
    p = scores.probabilities
    assert min(p["chair"], p["easy_chair"]) == 0.0
    assert scores.classes["easy_chair"].group == "chair"
    assert scores.classes["chair"].group is None


def test_a_variant_takes_the_label_of_the_class_it_describes_unless_it_names_one():
    text = "  chair:\n" + SEAT + "  armchair:\n    variant_of: chair\n" + SEAT
    onto = parse_ontology(HEADER + text)
    assert onto["armchair"].label == "chair" and onto["armchair"].variant_of == "chair"
    assert onto.variant_groups() == {"chair": "chair", "armchair": "chair"}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("  armchair:\n    variant_of: chiar\n" + SEAT, "no class of the ontology"),
        (
            "  chair:\n" + SEAT + "  armchair:\n    variant_of: chair\n" + SEAT
            + "  wingback:\n    variant_of: armchair\n    label: chair\n" + SEAT,
            "itself a variant of 'chair'",
        ),
        (
            "  chair:\n" + SEAT + "  armchair:\n    variant_of: chair\n    label: seat\n" + SEAT,
            "its label 'seat' is not 'chair''s",
        ),
    ],
)  # fmt: skip
def test_a_variant_that_cannot_be_one_is_an_error_naming_its_key(text, message):
    onto = parse_ontology(HEADER + text)
    with pytest.raises(InvalidOntologyError, match=message) as err:
        score_cluster(EMPTY, onto)
    assert err.value.key.endswith(".variant_of")


@pytest.mark.parametrize("value", ["armchair", "''", "[chair]"])
def test_a_variant_of_itself_or_of_no_name_is_refused_when_read(value):
    with pytest.raises(InvalidOntologyError, match="variant_of"):
        parse_ontology(HEADER + f"  armchair:\n    variant_of: {value}\n" + SEAT)


def test_a_file_with_a_variant_of_no_class_is_refused_when_loaded(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(HEADER + "  armchair:\n    variant_of: chiar\n" + SEAT)
    with pytest.raises(InvalidOntologyError, match="'chiar', which is no class") as err:
        load_ontology(bad)
    assert err.value.key == "classes.armchair.variant_of"
