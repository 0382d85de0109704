"""The environment prior P_N from photographs of the scene (thesis §3.4, §3.6, Tables 4.11–4.13).

P_obj = Σ_N P_N · P_obj|N (Eq. 3.10) needs P_N, how likely the scene is of each room
category. This package estimates it from photographs as the thesis does: the GIST
descriptor of each image, a calibrated support vector classifier, and the mean over the
frames of one scene. It also combines that estimate with one from the scan itself.

- ``_gist``: :func:`gist`, the 512-value descriptor (Oliva & Torralba), and its settings.
- ``_model``: :class:`EnvironmentModel` (train, predict, save and load without pickle),
  :func:`train_environment` and :func:`predict_environment` on folders and files.
- ``_combine``: :func:`combine_room_priors`, P_N from the scan and from images as one.
"""

from __future__ import annotations

from ._combine import ROOM_PRIOR_FLOOR, combine_room_priors
from ._gist import GistParams, gist
from ._model import (
    MODEL_FORMAT,
    EnvironmentModel,
    cross_validated_accuracy,
    descriptors_of,
    predict_environment,
    train_environment,
)

__all__ = [
    "MODEL_FORMAT",
    "ROOM_PRIOR_FLOOR",
    "EnvironmentModel",
    "GistParams",
    "combine_room_priors",
    "cross_validated_accuracy",
    "descriptors_of",
    "gist",
    "predict_environment",
    "train_environment",
]
