"""A cluster described from its points alone, for scoring tests on hand-made geometry."""

from __future__ import annotations

import numpy as np

from ontodetect.ontology import ClusterDescription
from ontodetect.segment.planes import plane_relations


def describe_points(pts: np.ndarray, planes: list) -> ClusterDescription:
    """The :class:`ClusterDescription` of the points ``pts`` (levelled, floor at 0) with
    these planes and patches, their relations measured on the points; the box is the
    points' horizontal extent, its height their top."""
    span = pts.max(axis=0) - pts.min(axis=0)
    return ClusterDescription(
        planes=planes,
        relations={(r.i, r.j): r for r in plane_relations(pts, planes)},
        length=float(max(span[:2])),
        breadth=float(min(span[:2])),
        height=float(pts[:, 2].max()),
        bottom=0.0,
    )
