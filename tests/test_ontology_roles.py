"""Part roles in the ontology file: seeds, CAD roles, context; and their errors."""

import pytest

from ontodetect.errors import InvalidOntologyError
from ontodetect.ontology import builtin_ontology, load_ontology, parse_ontology, read_ontology_file

HEAD = "format: ontodetect.ontology/1\n"
SEEDS = "seeds:\n  flat: {margin: 0.1, rise: 0.2, outside_cost: 1.0}\n"


def test_the_builtin_roles_are_those_the_code_had():
    o = builtin_ontology()
    # segment/_parts.py: seats up to 75 cm (Table 4.1), tops above.
    assert [(s.name, top) for s, top in o.seed_styles()] == [("seat", 0.75), ("top", 1.0)]
    seat, top = o.seeds["seat"], o.seeds["top"]
    assert (seat.margin, seat.rise, seat.outside_cost, seat.inside_above) == (0.3, 0.8, 0.5, False)
    assert (top.margin, top.rise, top.outside_cost, top.inside_above) == (0.05, 0.15, 20.0, True)
    assert top.attach is None and seat.attach.rise == (0.1, 0.45)
    assert (seat.attach.width, seat.attach.margin, seat.attach.share) == (0.6, 0.25, 0.7)
    a = seat.attach
    assert (a.back_reach, a.back_overhang, a.back_span, a.back_seat_length, a.back_top) == (
        0.5,
        0.5,
        0.3,
        0.8,
        0.95,
    )
    assert a.outer_margin == 0.1 and top.low is None
    assert (seat.low.up_to, seat.low.level, seat.low.margin) == (0.6, 0.05, 0.2)
    # labeling: chair (and the easy chair), sofa, stool and bench profit from a table nearby.
    seating = {"chair", "easy_chair", "sofa", "stool", "bench"}
    assert o.context_pairs() == {(s, "table") for s in seating} | {("table", s) for s in seating}
    # cad/_fit.py: the seat and the backrest by name, SEAT_RANGE, TOP_RANGE and the scales.
    assert o.cad_parts("chair") == o.cad_parts("sofa") == {"seat": "seat", "backrest": "back"}
    assert o.cad_parts("table") == {"top": "top"}
    for label in ("chair", "sofa", "table"):
        assert o.cad_search("seat", label) == (0.3, 0.75)
        assert o.cad_search("top", label) == (0.3, 1.15)
    assert o.cad_scale("sofa") == (0.6, 1.8) and o.cad_scale("table") == (0.4, 3.0)
    assert o.cad_scale("chair") is None
    assert o.cad_above_seat("chair") == o.cad_above_seat("table") == 0.27  # BACK_ABOVE_SEAT


def test_seed_sizes_are_the_seed_parts_height_length_and_width():
    sizes = builtin_ontology().seed_sizes()
    assert sorted(sizes) == ["seat", "top"]
    assert len(sizes["seat"]) == 2 and len(sizes["top"]) == 1  # chair and sofa; table
    assert all(set(p) == {"height", "length", "width"} for ps in sizes.values() for p in ps)
    chair_seat = builtin_ontology()["chair"].part("seat").constraints
    assert sizes["seat"][0]["length"] == chair_seat["length"]


def test_a_patch_takes_its_seed_style_by_height_and_size(tmp_path):
    from ontodetect.segment import seed_style

    o = builtin_ontology()
    styles, sizes = o.seed_styles(), o.seed_sizes()

    def style(h, length, width):
        return seed_style(h, styles, extent=(length, width), sizes=sizes).name

    assert style(0.74, 2.4, 1.0) == "top"  # a conference top, too large for a chair's seat
    assert style(0.74, 1.2, 0.6) == "top"  # an EN 527-1 desk
    assert style(0.74, 0.45, 0.4) == "seat"  # a high chair's seat
    assert style(0.45, 1.8, 0.6) == "seat"  # a sofa's joined cushions
    assert style(0.45, 0.7, 0.6) == "seat"  # a club armchair's seat (within one sigma)
    assert style(0.45, 4.5, 1.2) == "seat"  # nothing allows it: by height, as without sizes
    assert style(0.9, 0.4, 0.3) == "top"  # above every seat, whatever its size
    # A seed part that says nothing of its size allows any size.
    f = tmp_path / "crate.yaml"
    f.write_text(
        HEAD + "classes:\n  crate:\n    parts:\n      lid: {seed: seat, height: {max: 0.8}}\n"
    )
    mine = load_ontology(f)
    got = seed_style(0.78, mine.seed_styles(), extent=(3.0, 2.0), sizes=mine.seed_sizes())
    assert got.name == "seat"


def test_a_file_may_use_the_builtin_seed_styles_and_define_its_own(tmp_path):
    f = tmp_path / "mine.yaml"
    f.write_text(
        HEAD + SEEDS + "classes:\n  shelf:\n    parts:\n"
        "      board: {seed: flat, height: {max: 1.8}}\n"
        "  crate:\n    parts:\n      lid: {seed: seat, height: [0.3, 0.5]}\n"
    )
    o = load_ontology(f)
    assert o.seeds["flat"].margin == 0.1 and "seat" in o.seeds
    assert [s.name for s, _ in o.seed_styles()] == ["seat", "top", "flat"]
    with pytest.raises(InvalidOntologyError, match="no seed style named 'seat'"):
        read_ontology_file(f)  # alone, it knows only its own styles


@pytest.mark.parametrize(
    ("body", "key", "message"),
    [
        ("      p: {seed: nope, height: [0.3, 0.5]}\n", "classes.c.parts.p.seed", "no seed style"),
        ("      p: {seed: flat}\n", "classes.c.parts.p.seed", "needs a height"),
        ("      p: {seed: flat, height: {min: 0.3}}\n", "classes.c.parts.p.seed", "upper end"),
        ("      p: {cad: leg}\n", "classes.c.parts.p.cad", "expected one of seat, back, top"),
        (
            "      p: {cad: {role: seat, search: [0.8, 0.3]}}\n",
            "classes.c.parts.p.cad.search",
            "low < high",
        ),
        ("      p: {cad: {role: seat, size: 2}}\n", "classes.c.parts.p.cad.size", "unknown key"),
        (
            "      p: {cad: {role: seat, above_seat: 0.2}}\n",
            "classes.c.parts.p.cad.above_seat",
            "only a back part",
        ),
        ("      p: {}\n    context: table\n", "classes.c.context", "list of class names"),
        ("      p: {}\n    cad: {scale: [2, 1]}\n", "classes.c.cad.scale", "low < high"),
        ("      p: {}\n    cad: {stretch: 1}\n", "classes.c.cad.stretch", "unknown key"),
    ],
)
def test_role_errors_name_the_dotted_key_and_the_file(body, key, message):
    with pytest.raises(InvalidOntologyError, match=message) as exc:
        parse_ontology(HEAD + SEEDS + "classes:\n  c:\n    parts:\n" + body, "mine.yaml")
    assert f"[{key}]" in str(exc.value) and "mine.yaml" in str(exc.value)


@pytest.mark.parametrize(
    ("seeds", "key"),
    [
        ("  s: {margin: 0.1, rise: 0.2}\n", "seeds.s"),
        ("  s: {margin: -1, rise: 0.2, outside_cost: 1}\n", "seeds.s.margin"),
        (
            "  s: {margin: 0.1, rise: 0.2, outside_cost: 1, inside_above: 1}\n",
            "seeds.s.inside_above",
        ),
        ("  s: {margin: 0.1, rise: 0.2, outside_cost: 1, attach: {width: 1}}\n", "seeds.s.attach"),
        ("  s: {margin: 0.1, rise: 0.2, outside_cost: 1, low: {up_to: 0.6}}\n", "seeds.s.low"),
    ],
)
def test_seed_style_errors(seeds, key):
    text = HEAD + "seeds:\n" + seeds + "classes:\n  c:\n    parts:\n      p: {}\n"
    with pytest.raises(InvalidOntologyError) as exc:
        parse_ontology(text, "mine.yaml")
    assert f"[{key}]" in str(exc.value)
