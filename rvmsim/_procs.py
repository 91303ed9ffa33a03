"""Worker processes on this machine: the one process-pool recipe tuning and batches share.

Workers are spawned, not forked: a process that has run OpenCV's thread pool or an OpenGL
context cannot be forked safely.  :func:`spawn_pool` makes the pool
(:class:`concurrent.futures.ProcessPoolExecutor`, optionally with a per-worker initializer
that receives the state every task reads); :func:`stop_pool` ends it, at once when the
caller is interrupted.
"""

from __future__ import annotations

import multiprocessing as mp
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

__all__ = ["spawn_pool", "stop_pool"]


def spawn_pool(workers: int, *, initializer: Callable[..., None] | None = None,
               initargs: tuple[Any, ...] = ()) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned processes, each running ``initializer(*initargs)``
    once when it starts."""
    return ProcessPoolExecutor(max(1, workers), mp_context=mp.get_context("spawn"),
                               initializer=initializer, initargs=initargs)


def stop_pool(pool: ProcessPoolExecutor, *, now: bool) -> None:
    """Shut ``pool`` down: with ``now``, terminate its workers first (Ctrl-C, a stopped
    run, a broken pool) instead of waiting for the tasks in flight."""
    if now:
        # concurrent.futures has no public way to end running workers before Python 3.14
        # (ProcessPoolExecutor.terminate_workers); its process table is the only handle.
        for proc in list((getattr(pool, "_processes", None) or {}).values()):
            proc.terminate()
    pool.shutdown(wait=not now, cancel_futures=True)
