"""Every range of the built-in ontology cites where it comes from (a standard, a catalogue
range or a physical argument), in a comment beside it or in the file's list of rules that
hold throughout (tilts, fills, touching parts, missing and size factors)."""

import re
from importlib import resources

#: Features whose values follow one rule cited once at the head of the file.
CITED_ONCE = ("tilt", "fill", "distance", "missing", "extra_plane", "extra_surface", "plane_size")


def _classes_section() -> list[str]:
    text = resources.files("ontodetect").joinpath("data/furniture.yaml").read_text("utf-8")
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("classes:"))
    return lines[start:]


def test_every_range_cites_its_source():
    lines = _classes_section()
    uncited = []
    for i, line in enumerate(lines):
        m = re.match(r"^\s+([a-z_]+): .*\d", line)
        if not m or "#" in line or m.group(1) in CITED_ONCE:
            continue
        following = lines[i + 1].strip() if i + 1 < len(lines) else ""
        if not following.startswith("#"):
            uncited.append(line.strip())
    assert not uncited, f"ranges without a source: {uncited}"


def test_the_rules_cited_once_are_written_at_the_head():
    text = resources.files("ontodetect").joinpath("data/furniture.yaml").read_text("utf-8")
    head = text[text.index("# Values that follow one rule") : text.index("\nclasses:")]
    for name in CITED_ONCE:
        assert re.search(rf"\b{name}\b", head), name


def test_no_range_is_read_off_one_scene():
    # A prior comes from a standard, a catalogue or a physical argument, never one scan.
    text = "\n".join(_classes_section()).lower()
    for phrase in ("scene0", "development scan", "read off", "scannet-dev"):
        assert phrase not in text, phrase
