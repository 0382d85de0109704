"""Library defaults the commands show in ``--help``, copied here so that building the CLI
imports none of the stages (start-up). tests/test_structure.py keeps every copy equal to
the library's value; change them there first."""

from __future__ import annotations

# ontodetect.demo
DEMO_ROOM = "office"
DEMO_SEED = 3
# ontodetect.synth.SENSORS
SENSORS: tuple[str, ...] = ("rgbd", "rgbd-frame", "tls", "monocular")
# ontodetect.cad
MIN_SCORE = 0.2
KERNELS = ("tukey", "huber", "cauchy", "l2")
# ontodetect.calibrate
PRIOR_SIGMA_SHARE = 0.5
ONE_SIDED_QUANTILE = 0.0
MIN_ROOMS = 2
PRIOR_STRENGTH = 8.0
MIN_GAIN_ROOMS = 4

#: (name here, module, name there) of every copy.
COPIES = (
    ("DEMO_ROOM", "ontodetect.demo", "DEMO_ROOM"),
    ("DEMO_SEED", "ontodetect.demo", "DEMO_SEED"),
    ("SENSORS", "ontodetect.synth", "SENSORS"),
    ("MIN_SCORE", "ontodetect.cad", "MIN_SCORE"),
    ("KERNELS", "ontodetect.cad", "KERNELS"),
    ("PRIOR_SIGMA_SHARE", "ontodetect.calibrate", "PRIOR_SIGMA_SHARE"),
    ("ONE_SIDED_QUANTILE", "ontodetect.calibrate", "ONE_SIDED_QUANTILE"),
    ("MIN_ROOMS", "ontodetect.calibrate", "MIN_ROOMS"),
    ("PRIOR_STRENGTH", "ontodetect.calibrate", "PRIOR_STRENGTH"),
    ("MIN_GAIN_ROOMS", "ontodetect.calibrate", "MIN_GAIN_ROOMS"),
)
