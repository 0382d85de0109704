"""The shipped Places205 tables (data/places205.yaml): categories, aliases, presets and
the tables P(object | category) an ontology's ``prior: {rooms: NAME}`` may name."""

from __future__ import annotations

import functools
from importlib import resources
from typing import Any

from ..io._yaml import load_yaml

__all__ = ["places_data", "room_table_names"]


@functools.cache
def places_data() -> dict[str, Any]:
    """The parsed places205.yaml (cached), with every table of ``tables`` spread into the
    categories: ``categories[N][table]`` is P(object | N) for ``seating`` and the others."""
    text = resources.files("ontodetect").joinpath("data/places205.yaml").read_text("utf-8")
    data = load_yaml(text)
    for name, table in data.get("tables", {}).items():
        values = table.get("values", {})
        unknown = set(values) - set(data["categories"])
        if unknown:  # pragma: no cover - the shipped file is checked by the tests
            raise ValueError(f"places205.yaml: table {name!r} names unknown {sorted(unknown)}")
        for category, row in data["categories"].items():
            row[name] = float(values.get(category, table["default"]))
    areas = data.get("areas", {})
    if set(areas) != set(data["categories"]):  # pragma: no cover - checked by the tests
        raise ValueError("places205.yaml: areas must give every category, and only those")
    for category, area in areas.items():
        if not 0 < float(area["median"]) < float(area["p95"]):  # pragma: no cover
            raise ValueError(f"places205.yaml: areas of {category!r}: 0 < median < p95")
    return data


def room_table_names() -> list[str]:
    """Names of the tables P(object | category), e.g. ``"seating"`` (Table 4.10)."""
    return sorted(next(iter(places_data()["categories"].values())))
