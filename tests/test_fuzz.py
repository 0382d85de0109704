"""Seeded fuzzing in the suite: every reader and the configuration, ontology and
detections loaders, fed damaged files, either return or refuse in one line (issue 23).

A few hundred cases here; ``ONTODETECT_FUZZ_CASES=10000`` (or
``python -m benchmarks fuzz --cases 10000``) runs a longer one.
"""

from __future__ import annotations

import os

from benchmarks.bench_fuzz import run_cases


def test_damaged_files_are_read_or_refused_in_one_line():
    cases = int(os.environ.get("ONTODETECT_FUZZ_CASES", "420"))
    outcome = run_cases(cases, seed=int(os.environ.get("ONTODETECT_FUZZ_SEED", "0")), timeout=5.0)
    assert outcome.cases == cases
    assert outcome.kinds["failure"] == 0, "\n\n".join(outcome.failures)
    # Damage is noticed: most cases are refused, and some survive (a flipped colour bit).
    assert outcome.kinds["refused"] > cases // 3
    assert outcome.kinds["success"] > 0
