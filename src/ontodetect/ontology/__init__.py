"""Probabilistic ontology: classes as parts and relations, scored as products of Gaussians.

An ontology file (YAML, see ``docs/ontology.md``) describes each class by its planar
parts (seat, backrest, top), Gaussian constraints on their features and relations,
cluster-wide rules, discriminative label features for the energy, and environment
priors. :func:`score_cluster` finds, for every class, the best assignment of a
cluster's planes to the class's parts and returns P_obj|ont for every class and
"none" (thesis Eq. 3.1–3.5, 3.9–3.10).
"""

from __future__ import annotations

from ._builtin import builtin_ontology, load_ontology
from ._environment import (
    class_priors,
    object_prior,
    relative_priors,
    room_area_likelihood,
    room_categories,
    room_distribution,
    rooms_from_objects,
)
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
from ._near import score_near
from ._schema import (
    CAD_ROLES,
    Attach,
    ClusterRule,
    LabelModel,
    LowSeed,
    NearRule,
    ObjectClass,
    Ontology,
    Part,
    Relation,
    SeedStyle,
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
    with_priors,
)

__all__ = [
    "CAD_ROLES",
    "CLUSTER_FEATURES",
    "FEATURES",
    "NONE",
    "PART_FEATURES",
    "RELATION_FEATURES",
    "Attach",
    "ClassScore",
    "ClusterDescription",
    "ClusterRule",
    "ClusterScores",
    "ConstraintValue",
    "Feature",
    "Gaussian",
    "LabelModel",
    "LowSeed",
    "NearRule",
    "ObjectClass",
    "Ontology",
    "Part",
    "Relation",
    "SeedStyle",
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
    "relative_priors",
    "room_area_likelihood",
    "room_categories",
    "room_distribution",
    "rooms_from_objects",
    "score_class",
    "score_cluster",
    "score_near",
    "sigma_floor",
    "with_priors",
]
