"""Worker processes that start safely and soon."""

from __future__ import annotations

import multiprocessing
import multiprocessing.context
import os

__all__ = ["cpu_count", "fork_context", "pool_context"]


def pool_context() -> multiprocessing.context.BaseContext:
    """The start method for worker pools: a fork server that has imported the pipeline.

    Never a plain fork: the parent may hold threads (BLAS, Open3D) that a fork would copy
    mid-lock. Workers fork from a server process that imported ``ontodetect.pipeline``
    once, so they start in milliseconds; where there is no fork server, spawn.
    """
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(["ontodetect.pipeline"])
        return ctx
    return multiprocessing.get_context("spawn")


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
