"""A progress row per scan in flight for ``detect`` on several inputs, and an overall row.

Each scan runs in a worker process (``--jobs``) or in this one. Inside it, a
:class:`StageSender` is the library's progress reporter: it sends the scan's current stage
(the innermost step announced with :func:`ontodetect._progress.progress`, its total and how
far it got) through a queue. Here, :class:`ScanRows` reads the queue on a thread and keeps one
Rich row per scan showing that stage; the batch's own progress (scans finished) is its
overall row. Nothing of this exists when bars are off (``-q``, or stderr is not a terminal).
"""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from collections.abc import Iterator
from typing import Any

from rich.progress import (
    BarColumn,
    Progress,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
)

from ._console import err_console

__all__ = ["ScanRows", "StageSender", "scan_rows"]

#: A scan's row is refreshed at most this often (s) while a step advances.
SEND_INTERVAL = 0.1
_DONE = "done"
_STATE = "state"


class StageSender:
    """The progress reporter of one scan's work: sends its current stage to ``channel``.

    Messages are ``("state", scan, description, total, completed)`` and ``("done", scan)``.
    """

    def __init__(self, channel: Any, scan: str) -> None:
        self._channel = channel
        self._scan = scan
        self._stack: list[list[Any]] = []
        self._sent = 0.0

    def _send(self, force: bool = True) -> None:
        now = time.monotonic()
        if not force and now - self._sent < SEND_INTERVAL:
            return
        self._sent = now
        desc, total, done = self._stack[-1] if self._stack else ("starting", None, 0.0)
        self._channel.put((_STATE, self._scan, desc, total, done))

    def begin(self) -> None:
        self._send()

    def end(self) -> None:
        self._channel.put((_DONE, self._scan))

    def start(self, description: str, total: float | None) -> object:
        self._stack.append([description, total, 0.0])
        self._send()
        return len(self._stack) - 1

    def advance(self, task: object, amount: float) -> None:
        depth = int(task)  # type: ignore[call-overload]
        if depth < len(self._stack):
            self._stack[depth][2] += amount
            self._send(force=False)

    def finish(self, task: object) -> None:
        del self._stack[int(task) :]  # type: ignore[call-overload]
        self._send()


class ScanRows:
    """Rich rows: the batch's overall progress and one row per scan in flight.

    It is the library reporter of this process (``map_scenes``' count of finished scans is
    the overall row) and reads the scans' :class:`StageSender` messages from ``channel``.
    """

    def __init__(self, channel: Any, *, console: Any = None) -> None:
        self.channel = channel
        self.progress = Progress(
            TextColumn("{task.fields[scan]}", style="bold"),
            TextColumn("{task.description}"),
            BarColumn(),
            TaskProgressColumn(),
            TimeElapsedColumn(),
            console=console or err_console,
            transient=True,
        )
        self.rows: dict[str, Any] = {}

    # -- the overall row: this process's reporter ---------------------------------------
    def start(self, description: str, total: float | None) -> object:
        return self.progress.add_task(description, total=total, scan="all scans")

    def advance(self, task: object, amount: float) -> None:
        self.progress.advance(task, amount)  # type: ignore[arg-type]

    def finish(self, task: object) -> None:
        self.progress.remove_task(task)  # type: ignore[arg-type]

    # -- the scans' rows ----------------------------------------------------------------
    def handle(self, message: tuple) -> None:
        """Apply one :class:`StageSender` message."""
        kind, scan = message[0], message[1]
        if kind == _DONE:
            row = self.rows.pop(scan, None)
            if row is not None:
                self.progress.remove_task(row)
            return
        desc, total, done = message[2:5]
        if scan not in self.rows:
            self.rows[scan] = self.progress.add_task(desc, total=total, scan=scan)
        self.progress.update(self.rows[scan], description=desc, total=total, completed=done)

    def drain(self) -> None:
        """Apply every message waiting in the channel."""
        while True:
            try:
                message = self.channel.get_nowait()
            except (queue.Empty, EOFError, OSError):
                return
            if message is None:
                return
            self.handle(message)

    def _listen(self, stop: threading.Event) -> None:
        while not stop.is_set():
            try:
                message = self.channel.get(timeout=0.1)
            except queue.Empty:
                continue
            except (EOFError, OSError):
                return
            if message is None:
                return
            self.handle(message)


@contextlib.contextmanager
def scan_rows(channel: Any) -> Iterator[ScanRows]:
    """Show :class:`ScanRows` of ``channel`` while the ``with`` block runs."""
    rows = ScanRows(channel)
    stop = threading.Event()
    listener = threading.Thread(target=rows._listen, args=(stop,), daemon=True)
    rows.progress.start()
    listener.start()
    try:
        yield rows
    finally:
        stop.set()
        listener.join()
        rows.drain()
        rows.progress.stop()
