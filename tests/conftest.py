"""Shared fixtures: a seeded generator and deterministic Hypothesis settings."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

# Deterministic property tests: the same examples on every run and machine.
settings.register_profile(
    "ci",
    derandomize=True,
    deadline=None,
    max_examples=40,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    database=None,
)
settings.register_profile("dev", max_examples=200, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture
def rng() -> np.random.Generator:
    """A generator with a fixed seed, fresh for every test."""
    return np.random.default_rng(20161221)


# -- every detections.json a test writes follows the shipped JSON Schema -----------------
def _check_detections_files(root) -> None:
    import json
    from pathlib import Path

    import jsonschema

    from ontodetect.io import detections_schema

    validator = jsonschema.Draft202012Validator(detections_schema())
    for path in sorted(Path(root).rglob("detections.json")):
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue  # a test that writes a damaged file on purpose
        if not isinstance(doc, dict) or doc.get("format") != "ontodetect.detections/1":
            continue  # a test of the reader's refusal
        errors = sorted(validator.iter_errors(doc), key=lambda e: list(e.absolute_path))
        if errors:
            where = "/".join(str(p) for p in errors[0].absolute_path)
            pytest.fail(
                f"{path} breaks detections.schema.json at {where!r}: {errors[0].message}",
                pytrace=False,
            )


@pytest.fixture(autouse=True)
def _detections_follow_the_schema(request):
    """After each test that used ``tmp_path``: its detections.json files validate."""
    yield
    tmp = request.node.funcargs.get("tmp_path") if hasattr(request.node, "funcargs") else None
    if tmp is not None:
        _check_detections_files(tmp)


@pytest.fixture(autouse=True, scope="session")
def _session_detections_follow_the_schema(tmp_path_factory):
    """At the end of the run: every detections.json under pytest's temporary folders
    (module and session fixtures included) validates."""
    yield
    _check_detections_files(tmp_path_factory.getbasetemp())
