"""Progress reporting that costs nothing unless someone is watching.

Library code announces long work with :func:`progress`; by default nothing is
shown. The command-line interface installs a Rich reporter with
:func:`use_reporter`, and any other caller can install its own.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from typing import Protocol

__all__ = ["Reporter", "progress", "use_reporter"]


class Reporter(Protocol):
    def start(self, description: str, total: float | None) -> object: ...
    def advance(self, task: object, amount: float) -> None: ...
    def finish(self, task: object) -> None: ...


_current: ContextVar[Reporter | None] = ContextVar("ontodetect_reporter", default=None)


@contextlib.contextmanager
def use_reporter(reporter: Reporter | None) -> Iterator[None]:
    """Install ``reporter`` for the work done inside the ``with`` block."""
    token = _current.set(reporter)
    try:
        yield
    finally:
        _current.reset(token)


@contextlib.contextmanager
def progress(description: str, total: float | None = None) -> Iterator[Callable[[float], None]]:
    """Announce a long step; yields ``advance(amount)``.

    Examples
    --------
    >>> with progress("counting", total=3) as advance:
    ...     for _ in range(3):
    ...         advance(1)
    """
    reporter = _current.get()
    if reporter is None:
        yield lambda amount=1: None
        return
    task = reporter.start(description, total)
    try:
        yield lambda amount=1: reporter.advance(task, amount)
    finally:
        reporter.finish(task)
