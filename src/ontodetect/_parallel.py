"""Worker processes that start safely and soon, for the passes over one scan.

Maps over many units of work (tiles, scans, scenes) go through
:mod:`ontodetect._executor` instead.
"""

from __future__ import annotations

import multiprocessing
import multiprocessing.context
import os

__all__ = ["cpu_count", "fork_context"]


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
