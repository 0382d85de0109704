"""The one YAML loader every configuration, ontology and manifest goes through.

PyYAML's ``SafeLoader`` refuses tags that build objects, but it still expands aliases (a
few hundred bytes of nested ``*a`` grow to gigabytes), recurses once per nesting level
(deep nesting ends in ``RecursionError``), accepts lists as mapping keys, and reads
``1e-12`` as a string (YAML 1.1 wants a dot in a float). :class:`SafeYamlLoader` fixes
the four: aliases are refused, nesting deeper than :data:`MAX_YAML_DEPTH` is refused,
keys must be scalars, and any decimal number written with an exponent is a float.
"""

from __future__ import annotations

import re
from typing import Any, ClassVar

import yaml
from yaml.events import AliasEvent

try:
    from yaml.cyaml import CParser
except ImportError:  # PyYAML built without libyaml
    CParser = None

__all__ = [
    "MAX_YAML_DEPTH",
    "CSafeYamlLoader",
    "SafeYamlLoader",
    "YamlError",
    "describe_yaml_error",
    "load_yaml",
]

#: Deepest nesting of mappings and lists accepted; our files need fewer than ten levels.
MAX_YAML_DEPTH = 64

# YAML 1.2's float: "1e-12" and "3E5" are numbers, as in JSON.
_FLOAT = re.compile(
    r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
    |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
    |[-+]?\.(?:inf|Inf|INF)
    |\.(?:nan|NaN|NAN))$""",
    re.X,
)


class YamlError(yaml.YAMLError):
    """A document this loader refuses; ``line`` is 1-based when known."""

    def __init__(self, problem: str, line: int | None = None) -> None:
        super().__init__(problem)
        self.problem = problem
        self.line = line


class SafeYamlLoader(yaml.SafeLoader):
    """``SafeLoader`` without aliases, with bounded nesting, scalar keys and YAML 1.2 floats."""

    yaml_implicit_resolvers: ClassVar[dict[Any, list[Any]]] = {
        k: [r for r in v if r[0] != "tag:yaml.org,2002:float"]
        for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()
    }

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(AliasEvent):
            event = self.peek_event()
            raise YamlError(
                f"aliases (*{event.anchor}) are not allowed: write the value out",
                event.start_mark.line + 1,
            )
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                event = self.peek_event()
                raise YamlError(
                    f"nested more than {MAX_YAML_DEPTH} levels deep", event.start_mark.line + 1
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def compose_mapping_node(self, anchor: Any) -> Any:
        node = super().compose_mapping_node(anchor)
        for key, _ in node.value:
            if not isinstance(key, yaml.ScalarNode):
                raise YamlError(
                    "a key must be a plain name or number, not a list or mapping",
                    key.start_mark.line + 1,
                )
        return node


SafeYamlLoader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT, list("-+0123456789."))


class _CSafeYamlLoader(SafeYamlLoader):
    """:class:`SafeYamlLoader` reading its events from libyaml's parser.

    Scanning and parsing in Python are most of the time of a load; libyaml makes the same
    events (with the same lines), and the nodes are still composed here, with the checks
    of :class:`SafeYamlLoader` (aliases, nesting, keys). libyaml and PyYAML may still
    differ on unusual documents: use it on files known to read the same both ways.
    """

    def __init__(self, stream: Any) -> None:
        self._events = CParser(stream)
        yaml.composer.Composer.__init__(self)
        yaml.constructor.SafeConstructor.__init__(self)
        yaml.resolver.Resolver.__init__(self)
        self._depth = 0

    def check_event(self, *choices: Any) -> bool:
        return self._events.check_event(*choices)

    def peek_event(self) -> Any:
        return self._events.peek_event()

    def get_event(self) -> Any:
        return self._events.get_event()

    def dispose(self) -> None:
        self._events.dispose()


#: :class:`SafeYamlLoader` on libyaml's parser, or None when PyYAML was built without it.
CSafeYamlLoader: type[SafeYamlLoader] | None = None if CParser is None else _CSafeYamlLoader


def load_yaml(text: str) -> Any:
    """Parse one YAML document with :class:`SafeYamlLoader`.

    Raises
    ------
    yaml.YAMLError
        Invalid YAML, or a :class:`YamlError` for what the loader refuses.

    Examples
    --------
    >>> load_yaml("min: 1e-12")
    {'min': 1e-12}
    >>> try:
    ...     load_yaml("a: &x [1]\\nb: *x")
    ... except YamlError as exc:
    ...     print(exc.problem)
    aliases (*x) are not allowed: write the value out
    """
    loader = SafeYamlLoader(text)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def describe_yaml_error(exc: yaml.YAMLError) -> str:
    """``(line N): problem`` (or ``: problem``) for any PyYAML error."""
    if isinstance(exc, YamlError):
        line = exc.line
    else:
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        line = None if mark is None else mark.line + 1
    problem = getattr(exc, "problem", None)
    if problem is None and isinstance(exc, yaml.reader.ReaderError):
        # "unacceptable character #x0000: special characters are not allowed", one line.
        problem = (
            f"{exc.reason}: character #x{exc.character:04x} at byte {exc.position}"
            if (isinstance(exc.character, int))
            else f"{exc.reason} at byte {exc.position}"
        )
    problem = " ".join(str(problem or exc).split())
    return (f" (line {line})" if line else "") + f": {problem}"
