"""Named settings of the calibration: sample counts, prior strength, sigma floors, digits."""

from __future__ import annotations

from typing import Any

#: A ground-truth object calibrates only through a cluster with at least this point IoU
#: (the overlap a detection needs to count, docs/evaluation.md).
MIN_CLUSTER_IOU = 0.25
#: Constraints measured fewer times than this keep their prior...
MIN_SAMPLES = 3
#: ...and so do constraints measured in fewer rooms than this.
MIN_ROOMS = 2
#: σ is never below this share of the prior's σ... On held-out ScanNet rooms a quarter let
#: σ shrink so far that objects of other rooms failed several constraints at once (every
#: factor multiplies); half kept recall.
PRIOR_SIGMA_SHARE = 0.5
#: Weight of the ontology's own value, in objects (κ0 = ν0 of the conjugate normal prior):
#: the rules were written for every chair, a few dozen measured chairs of a handful of
#: rooms should move them only part of the way.
PRIOR_STRENGTH = 8.0
#: The objects of one room count as at most this many independent samples: a room's
#: chairs are often copies of one model, seen under the same sensor noise.
ROOM_SAMPLES = 3
#: A validation F1 "does not fall" when it is lower by at most this (float noise).
F1_TOLERANCE = 1e-9
#: The nested check keeps a group only when its gain shows in at least this many
#: calibration rooms left out in turn, with no loss in any: a one-sided sign test over
#: the left-out rooms. A change that does nothing, helping or hurting each room by
#: chance, gains in k rooms and loses in none with probability 2^-k: 4 rooms is the
#: least for 90 % confidence (p = 0.0625; 3 rooms give only 0.125). On ScanNet rooms a
#: gain in 2 of 3 rooms (p = 0.25) came from one or two detections per room and cost
#: recall on held-out rooms. With fewer calibration rooms to leave out, nothing can be
#: validated and the original is kept.
MIN_GAIN_ROOMS = 4
# ...nor below the feature's absolute floor, which the ontology's feature registry keeps
# (ontodetect.ontology.sigma_floor).
#: A one-sided bound or plateau end moves to this quantile of the values (``min``; 1 - it
#: for ``max``). 0 takes the extreme value, the maximum-likelihood end of a flat range; a
#: larger share ignores outliers but, with a few dozen objects, cuts off real ones.
ONE_SIDED_QUANTILE = 0.0
#: Significant digits of the numbers written to the calibrated file (more when needed).
DIGITS = 4
MAX_DIGITS = 15
#: Strings longer than this are written as folded blocks.
LONG_TEXT = 60
#: Width of the lines of the written file.
LINE_WIDTH = 96

#: A constraint's place in the YAML: (class, "parts", part, feature),
#: (class, "relations", index, feature) or (class, "cluster", feature).
ConstraintPath = tuple[Any, ...]
