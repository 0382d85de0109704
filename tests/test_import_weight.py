"""Importing the detection stages does not import the heavy libraries they use lazily."""

import subprocess
import sys

import pytest

HEAVY = ("open3d", "matplotlib", "trimesh", "sklearn", "skimage")


@pytest.mark.parametrize(
    "module",
    [
        "ontodetect.ontology",
        "ontodetect.segment",
        "ontodetect.labeling",
        "ontodetect.cad",
        "ontodetect.geometry._mesh",
        "ontodetect.preprocess",
    ],
)
def test_importing_a_stage_leaves_heavy_libraries_unloaded(module):
    code = f"import sys, {module}\nprint(' '.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.split() == [], f"{module} imports {out.strip()}"


def test_cad_does_not_import_the_simulator():
    code = (
        "import sys, ontodetect.cad\n"
        "print([m for m in sys.modules if m.startswith('ontodetect.synth')])"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]"
