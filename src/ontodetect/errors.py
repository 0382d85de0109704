"""Exceptions raised by ontodetect.

Every failure a user can cause is an :class:`OntoDetectError`; the command-line
interface turns one into a single line on stderr and exit status 2. The message
names the file, field or parameter, what was expected and what was found.
"""

from __future__ import annotations

from os import PathLike

__all__ = [
    "CorruptFileError",
    "InvalidOntologyError",
    "InvalidParameterError",
    "OntoDetectError",
    "ReadError",
    "UnsupportedFormatError",
    "WriteError",
]


class OntoDetectError(Exception):
    """Base class of every error ontodetect raises on purpose."""


class ReadError(OntoDetectError):
    """A file cannot be read: missing, unreadable, or not what it claims to be.

    Parameters
    ----------
    path : str or PathLike
        The file concerned; it is put at the front of the message.
    problem : str
        What is wrong, in plain words.
    """

    def __init__(self, path: str | PathLike[str], problem: str) -> None:
        self.path = str(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


class CorruptFileError(ReadError):
    """A file's content contradicts its format: truncated, damaged, counts that disagree."""


class UnsupportedFormatError(ReadError):
    """No reader (or writer) handles this file; the message lists the ones that exist."""

    def __init__(
        self, path: str | PathLike[str], problem: str, supported: list[str] | None = None
    ) -> None:
        self.supported = sorted(supported or [])
        if self.supported:
            problem = f"{problem} (supported: {', '.join(self.supported)})"
        super().__init__(path, problem)


class WriteError(OntoDetectError):
    """A file cannot be written; nothing already on disk was changed."""

    def __init__(self, path: str | PathLike[str], problem: str) -> None:
        self.path = str(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


class InvalidParameterError(OntoDetectError, ValueError):
    """A parameter is outside what it may be; the message names it, the rule and the value."""

    def __init__(self, name: str, rule: str, value: object) -> None:
        self.name = name
        self.rule = rule
        self.value = value
        super().__init__(f"The '{name}' parameter must be {rule}. Got {value!r} instead.")


class InvalidOntologyError(OntoDetectError):
    """An ontology file breaks its schema; the message names the file, line and key."""

    def __init__(
        self,
        path: str | PathLike[str] | None,
        problem: str,
        *,
        line: int | None = None,
        key: str | None = None,
    ) -> None:
        self.path = None if path is None else str(path)
        self.line = line
        self.key = key
        where = self.path or "<ontology>"
        if line is not None:
            where += f":{line}"
        if key:
            where += f" [{key}]"
        super().__init__(f"{where}: {problem}")
