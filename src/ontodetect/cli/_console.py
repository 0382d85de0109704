"""Consoles, verbosity and the Rich progress reporter the CLI installs."""

from __future__ import annotations

from rich.console import Console
from rich.progress import (
    BarColumn,
    Progress,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from .._progress import use_reporter

__all__ = [
    "RichReporter",
    "console",
    "err_console",
    "reporting",
    "setup_output",
    "showing_progress",
    "state",
]

#: Line width when the output is not a terminal: long enough never to wrap (file names
#: and JSON stay on one line for grep and pipes).
PIPE_WIDTH = 100_000


def _console(stderr: bool = False) -> Console:
    """A console that wraps and colours for a terminal, and neither for a pipe or a file.

    Markup is off: paths, file contents and keys such as ``[classes.chair.parts.seat]`` are
    printed verbatim; our own styling goes through ``rich.text.Text``.
    """
    c = Console(stderr=stderr, highlight=False, markup=False)
    if c.is_terminal:
        return c
    return Console(
        stderr=stderr,
        highlight=False,
        markup=False,
        width=PIPE_WIDTH,
        soft_wrap=True,
        color_system=None,
    )


console = _console()
err_console = _console(stderr=True)


class _State:
    quiet: bool = False
    verbose: bool = False


state = _State()


def setup_output(*, quiet: bool, verbose: bool) -> None:
    state.quiet = quiet
    state.verbose = verbose and not quiet


class RichReporter:
    """Shows library progress as Rich bars on stderr."""

    def __init__(self) -> None:
        self._progress = Progress(
            TextColumn("[progress.description]{task.description}"),
            BarColumn(),
            TaskProgressColumn(),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            console=err_console,
            transient=True,
        )
        self._open = 0

    def start(self, description: str, total: float | None) -> object:
        if self._open == 0:
            self._progress.start()
        self._open += 1
        return self._progress.add_task(description, total=total)

    def advance(self, task: object, amount: float) -> None:
        self._progress.advance(task, amount)  # type: ignore[arg-type]

    def finish(self, task: object) -> None:
        self._progress.remove_task(task)  # type: ignore[arg-type]
        self._open -= 1
        if self._open == 0:
            self._progress.stop()


def showing_progress() -> bool:
    """Whether progress bars are shown: not with ``--quiet``, nor when stderr is not a
    terminal (a pipe, a file, a CI log)."""
    return not state.quiet and err_console.is_terminal


def reporting():
    """Context manager: progress bars on unless ``--quiet`` (or stderr is not a terminal)."""
    if not showing_progress():
        return use_reporter(None)
    return use_reporter(RichReporter())
