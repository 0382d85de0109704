"""The shipped ontology (``data/furniture.yaml``) and files added to it."""

from __future__ import annotations

import functools
from importlib import resources
from os import PathLike

from ._schema import Ontology, parse_shipped_ontology, read_ontology_file

__all__ = ["builtin_ontology", "load_ontology"]


@functools.cache
def builtin_ontology() -> Ontology:
    """The shipped furniture ontology: chair, sofa, table (+ stool and bench, not reported)."""
    text = resources.files("ontodetect").joinpath("data/furniture.yaml").read_text("utf-8")
    return parse_shipped_ontology(text, "builtin:furniture.yaml")


def load_ontology(*paths: str | PathLike[str], replace: bool = False) -> Ontology:
    """The built-in ontology with the classes of ``paths`` added or replacing same-named ones.

    With ``replace=True`` only the files' classes are used. A ``variant_of`` that names no
    class of the result is an error here (:meth:`Ontology.variant_groups`), before any scan
    is read.
    """
    result = None if replace else builtin_ontology()
    for p in paths:
        o = read_ontology_file(p, seeds=None if result is None else result.seeds)
        result = o if result is None else result.merged(o)
    if result is None:
        return builtin_ontology()
    result.variant_groups()
    return result
