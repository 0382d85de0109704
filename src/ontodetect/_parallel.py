"""Worker processes that start safely and soon, for the passes over one scan.

Maps over many units of work (tiles, scans, scenes) go through
:mod:`ontodetect._executor` instead.
"""

from __future__ import annotations

import functools
import multiprocessing
import multiprocessing.context
import os
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["cpu_count", "fork_context", "one_blas_thread"]

_F = TypeVar("_F", bound=Callable[..., Any])


def fork_context() -> multiprocessing.context.BaseContext | None:
    """Plain fork, for short-lived workers that compute on numpy arrays only, or None.

    A forked worker needs neither a guarded ``__main__`` nor a fresh import, which a
    library function called from any script cannot ask for; it must not touch what
    other threads of the parent may have held at the fork (progress displays, Open3D),
    and the pipeline's passes do not. None where the platform cannot fork.
    """
    if "fork" in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("fork")
    return None


def cpu_count() -> int:
    """CPUs this process may run on (fewer than the machine's under an affinity mask)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return os.cpu_count() or 1


def one_blas_thread(fn: _F) -> _F:
    """``fn`` with every BLAS/LAPACK library of the process held to one thread meanwhile
    (``threadpoolctl``), and the caller's setting back afterwards.

    The detection's linear algebra is on small matrices (a plane's 3 x 3 scatter, a
    triangle's barycentric transform), thousands of times, while its passes already run in
    processes of their own, one per CPU. Threads a BLAS library starts for each small call
    only contend with those processes: on a 2-CPU machine the command line took 0.80 times
    the CPU time and 0.87 times the wall time with them held to one (docs/benchmarks.md,
    "BLAS threads"). Forked passes inherit the limit. The results do not depend on it.
    """

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        from threadpoolctl import threadpool_limits  # lazy: start-up

        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
