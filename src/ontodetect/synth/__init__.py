"""Simulated indoor scenes with ground truth: rooms, furniture and virtual sensors.

- :mod:`~ontodetect.synth.scene`: the :class:`Scene` / :class:`SceneObject` data model.
- :mod:`~ontodetect.synth.rooms`: :func:`build_room` and :data:`ROOM_TYPES`.
- :mod:`~ontodetect.synth.sensors`: RGB-D camera, laser scanner, monocular SLAM.
- :mod:`~ontodetect.synth.artefacts`: artefacts of real scans (ScanNet-like sampling, a
  drifted second floor layer, holes, a tilt) applied to a scanned cloud.
- :mod:`~ontodetect.synth.dataset`: :func:`synthesize`, :func:`write_synth`,
  :func:`load_synth`, :func:`synthesize_many`.
- :mod:`~ontodetect.synth.sh3d`: Sweet Home 3D furniture catalogues (:func:`read_catalog`,
  :func:`load_model`).
- :mod:`~ontodetect.synth.furnished`: rooms furnished with catalogue models
  (:func:`furnished_scene`, :data:`FURNISHED_ROOM_TYPES`, :func:`attribution`).
"""

from __future__ import annotations

from typing import Any

from .dataset import (
    SYNTH_FORMAT,
    SynthResult,
    load_synth,
    room_types,
    sensor_options,
    synthesize,
    synthesize_many,
    write_synth,
)
from .scene import CLASS_IDS, CLASS_NAMES, OrientedBox, Scene, SceneObject
from .sensors import (
    SENSORS,
    RGBDSensor,
    SensorOutput,
    camera_trajectory,
    scan_monocular_slam,
    scan_rgbd_frame,
    scan_rgbd_trajectory,
    scan_tls,
    tls_stations,
)

__all__ = [
    "CLASS_IDS",
    "CLASS_NAMES",
    "FURNISHED_ROOM_TYPES",
    "ROOM_TYPES",
    "SENSORS",
    "SYNTH_FORMAT",
    "OrientedBox",
    "RGBDSensor",
    "Scene",
    "SceneObject",
    "SensorOutput",
    "SynthResult",
    "attribution",
    "build_room",
    "camera_trajectory",
    "furnished_scene",
    "load_synth",
    "room_types",
    "scan_monocular_slam",
    "scan_rgbd_frame",
    "scan_rgbd_trajectory",
    "scan_tls",
    "sensor_options",
    "synthesize",
    "synthesize_furnished",
    "synthesize_many",
    "tls_stations",
    "write_synth",
]


_FURNISHED = ("FURNISHED_ROOM_TYPES", "attribution", "furnished_scene", "synthesize_furnished")


def __getattr__(name: str) -> Any:
    # The room builders are imported on first use: they are big, and the sensors and
    # the dataset reader do not need them.
    if name in ("build_room", "ROOM_TYPES"):
        from . import rooms  # lazy: big, and the sensors and the reader do not need it

        return getattr(rooms, name)
    if name in _FURNISHED:
        from . import furnished  # lazy: reads catalogues; only furnished rooms need it

        return getattr(furnished, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
