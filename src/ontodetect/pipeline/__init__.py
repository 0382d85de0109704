"""The whole method in one call (:func:`detect`), its output types and the multi-pass vote.

- :func:`detect` (``_detect``): read → prepare → segment → score → label → vote.
- :class:`Detection`, :class:`Result`, :func:`with_cad` (``_result``): what it returns;
  :meth:`Result.to_dict` is the ``detections.json`` document (docs/detections-format.md).
- :func:`detect_tiled` (``_tiled``): a cloud of any size tile by tile on the floor plane,
  the tiles mapped over an executor (in this process or on Dask), detections merged.
- :func:`majority_labels`, :func:`pass_probabilities`, :func:`vote_turns`,
  :func:`class_for_label` (``_vote``): the vote over passes turned about the vertical;
  :func:`pass_ballots` and :class:`Ballot`: what each pass made of a cluster, for
  ``--explain``.

The scene measurements the scoring needs (:func:`describe_clusters`, :func:`open_below`,
:func:`hidden_heights`, :func:`shelter_heights`) live in ``ontodetect.segment._measure``
and are re-exported here for the names users import today.
"""

from __future__ import annotations

from ..segment._measure import (
    describe_cluster,
    describe_clusters,
    hidden_heights,
    open_below,
    shelter_heights,
)
from ._detect import detect
from ._result import DETECTIONS_FORMAT, Detection, Result, with_cad
from ._tiled import TiledResult, detect_tiled
from ._vote import (
    VOTE_IOU,
    Ballot,
    class_for_label,
    majority_labels,
    pass_ballots,
    pass_probabilities,
    vote_turns,
)

__all__ = [
    "DETECTIONS_FORMAT",
    "VOTE_IOU",
    "Ballot",
    "Detection",
    "Result",
    "TiledResult",
    "class_for_label",
    "describe_cluster",
    "describe_clusters",
    "detect",
    "detect_tiled",
    "hidden_heights",
    "majority_labels",
    "open_below",
    "pass_ballots",
    "pass_probabilities",
    "shelter_heights",
    "vote_turns",
    "with_cad",
]
