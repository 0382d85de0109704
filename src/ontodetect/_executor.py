"""One way to run a map over units of work: in this process, or on a Dask cluster.

Batch work is a map over independent units (the tiles of one cloud, the scans of a
folder, the scenes of ``eval`` and ``calibrate``) whose small results are merged in
order. :class:`Executor` runs such a map: :class:`InProcess` one unit after the other
in this process (one room: the default), :class:`DaskExecutor` on a ``dask.distributed``
cluster, local (:func:`open_executor` with ``workers``) or existing (``scheduler``, or
the ``DASK_SCHEDULER_ADDRESS`` variable Dask itself reads). Units carry what their worker
needs to find its data (a path on storage every worker sees, a window), never the data:
only the units and their results travel through the scheduler.

A unit that raises is run again (``retries``) and, if it still fails, the map ends with
a :class:`UnitsFailedError` naming every unit that failed: no unit is dropped silently.
A worker lost mid-run (its process killed, its host gone) costs only the units it held,
which the scheduler gives to the others.

Dask is imported only when a cluster is asked for.
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import re
import time
import uuid
from collections.abc import Callable, Iterator, Sequence
from typing import Any, TypeVar

from ._parallel import cpu_count
from ._progress import progress
from ._rules import COUNT, Nullable, check_param
from .errors import InvalidParameterError, OntoDetectError

__all__ = [
    "CONNECT_TIMEOUT",
    "DEFAULT_RETRIES",
    "SCHEDULER_ENV",
    "DaskExecutor",
    "Executor",
    "InProcess",
    "UnitsFailedError",
    "executor_for",
    "open_executor",
    "scheduler_address",
]

#: Times a failed unit is run again on a cluster before it counts as failed.
DEFAULT_RETRIES = 2
#: Seconds to wait for a scheduler to answer before giving up on it.
CONNECT_TIMEOUT = 10.0
#: The environment variable Dask reads a scheduler's address from.
SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"
#: A scheduler address: ``protocol://host:port`` (``tcp``, ``tls``, ``ws``, ``wss``, ``ucx``).
_ADDRESS = re.compile(r"^(tcp|tls|ws|wss|ucx)://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.\-]+):(\d{1,5})$")
#: Longest error text kept per failed unit.
_MAX_MESSAGE = 300

T = TypeVar("T")
R = TypeVar("R")


class UnitsFailedError(OntoDetectError):
    """Units of a map failed (after their retries); the message names every one.

    Attributes
    ----------
    failures : list of (str, str)
        Name of each failed unit and why it failed.
    """

    def __init__(self, failures: Sequence[tuple[str, str]], what: str = "units") -> None:
        self.failures = [(str(n), str(m)) for n, m in failures]
        self.what = what
        listed = "; ".join(f"{n}: {m}" for n, m in self.failures)
        super().__init__(f"{len(self.failures)} {what} failed: {listed}")

    def __reduce__(self) -> tuple[Any, ...]:
        return (UnitsFailedError, (self.failures, self.what))


def _describe(exc: BaseException) -> str:
    text = str(exc).strip()
    text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return text if len(text) <= _MAX_MESSAGE else text[:_MAX_MESSAGE] + "..."


def _names(units: Sequence[Any], names: Sequence[str] | None) -> list[str]:
    if names is None:
        return [str(i) for i in range(len(units))]
    names = [str(n) for n in names]
    if len(names) != len(units):
        raise InvalidParameterError("names", f"one name per unit ({len(units)})", len(names))
    return names


class Executor:
    """Runs ``[fn(u) for u in units]`` somewhere and returns the results in order.

    Attributes
    ----------
    workers : int
        Units that can run at the same time.
    """

    workers: int = 1

    def map(
        self,
        fn: Callable[[T], R],
        units: Sequence[T],
        *,
        names: Sequence[str] | None = None,
        description: str = "Units",
        retries: int = DEFAULT_RETRIES,
    ) -> list[R]:
        """``[fn(u) for u in units]``, results in the order of ``units``.

        Parameters
        ----------
        fn : callable
            A module-level function (or a :func:`functools.partial` of one): it and the
            units are pickled for a cluster.
        units : sequence
            Small descriptions of the work (paths, windows), not the data.
        names : sequence of str, optional
            What to call each unit in progress and errors (default: its position).
        description : str
            Label of the progress bar, which counts finished units.
        retries : int
            Times a unit that raised is run again on a cluster (in this process a run is
            deterministic and is not repeated).

        Raises
        ------
        UnitsFailedError
            Some units still failed; every one is named.
        """
        raise NotImplementedError

    def channel(self) -> Any:
        """A queue the units can ``put`` small messages into wherever they run, and this
        process read (``get_nowait``, ``get(timeout=)``): a scan's stages for its progress
        row."""
        return queue.SimpleQueue()

    def close(self) -> None:
        """Release the workers this executor started (nothing for one it was given)."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"{type(self).__name__}(workers={self.workers})"


class InProcess(Executor):
    """Every unit in this process, one after the other: one room, or no cluster at hand.

    A unit that raises an :class:`~ontodetect.errors.OntoDetectError` ends the map with
    a :class:`UnitsFailedError` naming it; any other exception (a bug) is raised as it is.
    """

    workers = 1

    def map(self, fn, units, *, names=None, description="Units", retries=DEFAULT_RETRIES):
        labels = _names(units, names)
        results = []
        with progress(description, total=len(units)) as advance:
            for unit, name in zip(units, labels):
                try:
                    results.append(fn(unit))
                except OntoDetectError as exc:
                    raise UnitsFailedError([(name, str(exc))]) from exc
                advance(1)
        return results


class DaskExecutor(Executor):
    """Units as tasks of a ``dask.distributed`` cluster.

    Parameters
    ----------
    client : distributed.Client
        A connected client.
    own : bool
        Close the client (and its local cluster) on :meth:`close`.
    """

    def __init__(self, client: Any, *, own: bool = False) -> None:
        self.client = client
        self._own = own

    @property
    def workers(self) -> int:  # type: ignore[override]
        return max(1, len(self.client.scheduler_info().get("workers", {})))

    @property
    def address(self) -> str:
        """The scheduler's address."""
        return str(self.client.scheduler.address)

    def map(self, fn, units, *, names=None, description="Units", retries=DEFAULT_RETRIES):
        from distributed import as_completed

        check_param("retries", COUNT, retries)
        labels = _names(units, names)
        if not units:
            return []
        # Keys unique to this map (two maps over the same names must not share results);
        # the unit's name stays readable in the dashboard and in worker logs.
        run = uuid.uuid4().hex[:8]
        keys = [f"{_slug(description)}-{_slug(n)}-{run}-{i}" for i, n in enumerate(labels)]
        futures = self.client.map(fn, list(units), key=keys, retries=retries, pure=False)
        where = {f.key: i for i, f in enumerate(futures)}
        results: list[Any] = [None] * len(units)
        failures: list[tuple[int, str]] = []
        try:
            with progress(description, total=len(units)) as advance:
                for fut in as_completed(futures, loop=self.client.loop):
                    i = where[fut.key]
                    if fut.status == "finished":
                        results[i] = fut.result()
                    else:
                        exc = fut.exception()
                        failures.append((i, "cancelled" if exc is None else _describe(exc)))
                    fut.release()
                    advance(1)
        finally:
            for fut in futures:
                fut.release()
        if failures:
            failures.sort()
            raise UnitsFailedError([(labels[i], m) for i, m in failures])
        return results

    def channel(self) -> Any:
        from distributed import Queue

        return _DaskChannel(Queue(client=self.client))

    def close(self) -> None:
        if not self._own:
            return
        cluster = self.client.cluster
        with contextlib.suppress(Exception):
            self.client.close()
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close()

    def __repr__(self) -> str:
        return f"DaskExecutor({self.address!r}, workers={self.workers})"


class _DaskChannel:
    """A ``distributed.Queue`` with the reading side of :class:`queue.SimpleQueue`
    (picklable: a worker finds the queue by its name)."""

    def __init__(self, q: Any) -> None:
        self._q = q

    def put(self, message: Any) -> None:
        self._q.put(message)

    def get_nowait(self) -> Any:
        if not self._q.qsize():
            raise queue.Empty
        return self._q.get()

    def get(self, timeout: float | None = None) -> Any:
        # Polled: a waiting get that times out is logged as an error by the scheduler.
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            if self._q.qsize():
                return self._q.get()
            if deadline is not None and time.monotonic() >= deadline:
                raise queue.Empty
            time.sleep(0.02)


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.]+", "_", text).strip("_")[:60] or "unit"


def scheduler_address(scheduler: str | None = None) -> str | None:
    """The scheduler to use: ``scheduler``, else ``$DASK_SCHEDULER_ADDRESS``, else None.

    Raises
    ------
    InvalidParameterError
        The address is not ``protocol://host:port``.

    Examples
    --------
    >>> scheduler_address("tcp://10.0.0.5:8786")
    'tcp://10.0.0.5:8786'
    """
    address = scheduler if scheduler is not None else os.environ.get(SCHEDULER_ENV) or None
    if address is None:
        return None
    text = str(address).strip()
    match = _ADDRESS.match(text)
    if match is None or not 0 < int(match.group(3)) < 65536:
        raise InvalidParameterError(
            "scheduler",
            "a Dask scheduler address protocol://HOST:PORT, such as tcp://10.0.0.5:8786"
            + ("" if scheduler is not None else f" (read from ${SCHEDULER_ENV})"),
            address,
        )
    return text


def open_executor(
    scheduler: str | None = None,
    *,
    workers: int | None = None,
    jobs: int | None = None,
    memory_limit: str | int | None = None,
    timeout: float = CONNECT_TIMEOUT,
) -> Executor:
    """The executor a run asked for.

    In order: an existing cluster at ``scheduler`` (or ``$DASK_SCHEDULER_ADDRESS``); a
    local cluster of ``workers`` processes (one thread each); a local cluster of ``jobs``
    processes when ``jobs`` > 1 (0: one per usable CPU); else :class:`InProcess`. Close
    it (or use it in a ``with`` block) to stop a local cluster.

    Parameters
    ----------
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a running ``dask scheduler``.
    workers : int, optional
        Worker processes of a local cluster (>= 1).
    jobs : int, optional
        The ``--jobs`` of the commands: 1 (or None) in this process, N > 1 a local
        cluster of N workers, 0 one worker per usable CPU.
    memory_limit : str or int, optional
        Memory each local worker may use (``"4GB"``); Dask's default shares the
        machine's memory among the workers.
    timeout : float
        Seconds to wait for the scheduler.

    Raises
    ------
    InvalidParameterError
        A malformed address, or no scheduler answering there (named ``scheduler``).
    """
    address = scheduler_address(scheduler)
    workers = check_param("workers", Nullable(COUNT), workers)
    jobs = check_param("jobs", Nullable(COUNT), jobs)
    if address is not None:
        return _connect(address, timeout)
    if workers is None and jobs is not None and jobs != 1:
        workers = jobs or cpu_count()
        if workers == 1:
            return InProcess()
    if workers is None:
        return InProcess()
    if workers == 0:
        workers = cpu_count()
    return _local_cluster(workers, memory_limit)


def _connect(address: str, timeout: float) -> DaskExecutor:
    from distributed import Client

    try:
        client = Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise InvalidParameterError(
            "scheduler",
            f"the address of a Dask scheduler that answers within {timeout:g} s ({_describe(exc)})",
            address,
        ) from None
    return DaskExecutor(client, own=True)


def _local_cluster(workers: int, memory_limit: str | int | None) -> DaskExecutor:
    from distributed import Client, LocalCluster

    options: dict[str, Any] = {}
    if memory_limit is not None:
        options["memory_limit"] = memory_limit
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",  # any free port: several clusters may run on one host
        silence_logs=logging.ERROR,
        **options,
    )
    return DaskExecutor(Client(cluster, set_as_default=False), own=True)


@contextlib.contextmanager
def executor_for(executor: Executor | None, jobs: int | None = 1) -> Iterator[Executor]:
    """``executor`` as it is (left open), or one opened for ``jobs`` and closed after."""
    if executor is not None:
        if not isinstance(executor, Executor):
            raise InvalidParameterError(
                "executor", "an ontodetect Executor (see open_executor)", type(executor).__name__
            )
        yield executor
        return
    with open_executor(jobs=jobs) as opened:
        yield opened
