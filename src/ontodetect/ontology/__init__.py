"""Probabilistic ontology: classes as parts and relations, scored as products of Gaussians.

An ontology file (YAML, see ``docs/ontology.md``) describes each class by its planar
parts (seat, backrest, top), Gaussian constraints on their features and relations,
cluster-wide rules, discriminative label features for the energy, and environment
priors. :func:`score_cluster` finds, for every class, the best assignment of a
cluster's planes to the class's parts and returns P_obj|ont for every class and
"none" (thesis Eq. 3.1–3.5, 3.9–3.10).
"""

from __future__ import annotations

import functools
from importlib import resources
from os import PathLike

from ._environment import class_priors, object_prior, room_categories, room_distribution
from ._features import (
    CLUSTER_FEATURES,
    FEATURES,
    PART_FEATURES,
    RELATION_FEATURES,
    Feature,
    feature_registry,
    register_feature,
    sigma_floor,
)
from ._gaussian import Gaussian
from ._schema import (
    ClusterRule,
    LabelModel,
    ObjectClass,
    Ontology,
    Part,
    Relation,
    parse_ontology,
    read_ontology_file,
)
from ._score import (
    NONE,
    ClassScore,
    ClusterDescription,
    ClusterScores,
    ConstraintValue,
    cluster_log_factor,
    continuations,
    missing_factor,
    part_values,
    plane_feature,
    score_class,
    score_cluster,
)

__all__ = [
    "CLUSTER_FEATURES",
    "FEATURES",
    "NONE",
    "PART_FEATURES",
    "RELATION_FEATURES",
    "ClassScore",
    "ClusterDescription",
    "ClusterRule",
    "ClusterScores",
    "ConstraintValue",
    "Feature",
    "Gaussian",
    "LabelModel",
    "ObjectClass",
    "Ontology",
    "Part",
    "Relation",
    "builtin_ontology",
    "class_priors",
    "cluster_log_factor",
    "continuations",
    "feature_registry",
    "load_ontology",
    "missing_factor",
    "object_prior",
    "parse_ontology",
    "part_values",
    "plane_feature",
    "read_ontology_file",
    "register_feature",
    "room_categories",
    "room_distribution",
    "score_class",
    "score_cluster",
    "sigma_floor",
]


@functools.cache
def builtin_ontology() -> Ontology:
    """The shipped furniture ontology: chair, sofa, table (+ stool and bench, not reported)."""
    text = resources.files("ontodetect").joinpath("data/furniture.yaml").read_text("utf-8")
    return parse_ontology(text, "builtin:furniture.yaml")


def load_ontology(*paths: str | PathLike[str], replace: bool = False) -> Ontology:
    """The built-in ontology with the classes of ``paths`` added or replacing same-named ones.

    With ``replace=True`` only the files' classes are used.
    """
    result = None if replace else builtin_ontology()
    for p in paths:
        o = read_ontology_file(p)
        result = o if result is None else result.merged(o)
    if result is None:
        return builtin_ontology()
    return result
