"""Where independent tasks (one design point, one vehicle) run: local processes or a Dask
cluster.

Both executors take a mapping ``{key: argument}`` and a picklable top-level function, and
yield ``(key, result)`` as tasks finish, in completion order.  The caller stores each result
as it arrives, so an interrupted run keeps everything finished.

- :class:`LocalExecutor`: ``workers`` worker processes on this machine
  (``concurrent.futures.ProcessPoolExecutor``).  If a worker process dies (killed, out of
  memory), the pool is rebuilt and the tasks that had not finished run again.
- :class:`DaskExecutor`: an existing Dask ``distributed`` cluster (``tcp://HOST:PORT``).
  The scheduler does the scheduling: a worker lost mid-task has only its tasks re-run
  elsewhere (``distributed``'s own recovery).  rvmsim must be importable on the workers;
  scene mesh files must be readable there at the same paths.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import socket
import sys
import uuid
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import FIRST_COMPLETED, wait
from concurrent.futures.process import BrokenProcessPool
from typing import TYPE_CHECKING, TypeVar

from .._optional import import_distributed
from .._procs import start_pool, stop_pool, stop_requested
from ..errors import RvmsimError

if TYPE_CHECKING:
    import distributed

__all__ = ["Executor", "LocalExecutor", "DaskExecutor", "make_executor", "task_malloc"]

#: How often the local executor rebuilds its pool after losing a worker before giving up.
MAX_POOL_REBUILDS = 3

#: A task's argument and its result (a task function maps one to the other).
_Arg = TypeVar("_Arg")
_Result = TypeVar("_Result")


class Executor:
    """Runs ``fn(arg)`` for every item; see the module docstring."""

    name = "executor"

    def run(self, fn: Callable[[_Arg], _Result], items: Mapping[str, _Arg]
            ) -> Iterator[tuple[str, _Result]]:
        raise NotImplementedError

    def close(self) -> None:
        pass

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class LocalExecutor(Executor):
    """``workers`` worker processes on this machine (1: run in this process)."""

    name = "local"

    def __init__(self, workers: int = 1):
        self.workers = max(1, int(workers))

    def run(self, fn: Callable[[_Arg], _Result], items: Mapping[str, _Arg]
            ) -> Iterator[tuple[str, _Result]]:
        if self.workers == 1:
            for key, arg in items.items():
                yield key, fn(arg)
            return

        todo = dict(items)
        rebuilds = 0
        while todo:
            pool = start_pool(self.workers)
            futures = {pool.submit(fn, arg): key for key, arg in todo.items()}
            broken = False
            try:
                pending = set(futures)
                while pending:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for fut in done:
                        key = futures[fut]
                        try:
                            result = fut.result()
                        except BrokenProcessPool:
                            stop = stop_requested()  # a SIGTERM to the group ended it
                            if stop is not None:
                                raise stop from None
                            broken = True
                            continue
                        del todo[key]
                        yield key, result
                    if broken:
                        break
            except BaseException:  # Ctrl-C, or the caller stopped: stop the workers now
                broken = True
                raise
            finally:
                stop_pool(pool, now=broken)
            if broken:
                rebuilds += 1
                if rebuilds > MAX_POOL_REBUILDS:
                    raise RvmsimError(f"worker processes died {rebuilds} times; "
                                      f"{len(todo)} tasks not run")


def _refused(address: str | None, timeout_s: float) -> OSError | None:
    """Why a ``tcp://HOST:PORT`` scheduler address takes no connection now (refused, no
    such host; None: it takes one, or the address is another kind, which the Dask client's
    own connection attempts judge).  A refusal comes back at once, where the client would
    retry it for ``timeout_s``."""
    if not address or not address.startswith("tcp://"):
        return None
    host, _, port = address[len("tcp://"):].rpartition(":")
    if not host or not port.isdigit():
        return None  # the client says what is wrong with it
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s).close()
    except OSError as err:
        return err
    return None


class DaskExecutor(Executor):
    """Tasks on an existing Dask distributed cluster at ``address`` (``tcp://HOST:PORT``),
    or on a given ``client``."""

    name = "dask"

    def __init__(self, address: str | None = None, *,
                 client: distributed.Client | None = None, timeout_s: float = 10.0):
        distributed = import_distributed()
        self._own = client is None
        if client is None:
            refused = _refused(address, timeout_s)
            if refused is not None:  # said at once, not after the client's timeout_s
                raise RvmsimError(f"{address}: cannot reach the Dask scheduler ({refused})")
            try:
                client = distributed.Client(address, timeout=timeout_s)
            except (OSError, TimeoutError, ValueError) as err:
                raise RvmsimError(f"{address}: cannot reach the Dask scheduler ({err})") from None
        self.client = client
        if not address:  # a given client: its scheduler's address, for messages
            scheduler = client.scheduler  # None once the client is closed
            address = str(scheduler.address) if scheduler is not None else "?"
        self.address = address

    def run(self, fn: Callable[[_Arg], _Result], items: Mapping[str, _Arg]
            ) -> Iterator[tuple[str, _Result]]:
        distributed = import_distributed()
        # A fresh token per run: a key cancelled by an interrupted run may still be being
        # forgotten by the scheduler, and a new task under the same key would be cancelled
        # with it ("cancelled for reason: unknown") when the sweep is resumed at once.
        token = uuid.uuid4().hex[:8]
        futures = {self.client.submit(fn, arg, key=f"rvmsim-{key}-{token}", pure=False): key
                   for key, arg in items.items()}
        try:
            for fut in distributed.as_completed(list(futures)):
                key = futures[fut]
                try:
                    result = fut.result()
                except RvmsimError:
                    raise
                except Exception as err:  # noqa: BLE001 - anything the cluster reports
                    raise RvmsimError(
                        f"{self.address}: task {key} failed on the cluster: "
                        f"{type(err).__name__}: {_first_line(err)} (is rvmsim installed on the "
                        "scheduler and every worker, in the same version?)") from None
                fut.release()
                yield key, result
        finally:
            for fut in futures:
                if not fut.done():
                    fut.cancel()

    def close(self) -> None:
        if self._own:
            self.client.close()


#: glibc's ``mallopt`` parameter numbers, and its default mmap threshold.
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_DEFAULT_MMAP_THRESHOLD = 128 * 1024


@contextlib.contextmanager
def task_malloc(threshold_bytes: int = 256 * 1024 * 1024) -> Iterator[bool]:
    """Raise glibc's malloc trim threshold while a task runs, when the process was started
    with a low one, and restore it afterwards.

    Dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_=65536`` so that freed memory
    goes back to the OS at once; setting it also freezes glibc's mmap threshold at 128 KiB,
    so every image-sized array is mmapped and munmapped.  A design point allocates and frees
    the same few MB for every one of its thousands of candidates, and with that setting
    each reuse costs fresh page faults: a point ran ~25 % slower (5.2 s → 6.0–6.6 s in one
    process).  Both thresholds are raised while the task runs.  Yields True when they were
    changed (Linux/glibc only; elsewhere nothing happens).
    """
    env = os.environ.get("MALLOC_TRIM_THRESHOLD_", "")
    libc = None
    if env.isdigit() and int(env) < threshold_bytes and sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL("libc.so.6")
            if (libc.mallopt(_M_TRIM_THRESHOLD, threshold_bytes) != 1
                    or libc.mallopt(_M_MMAP_THRESHOLD, min(threshold_bytes, 32 << 20)) != 1):
                libc = None
        except (OSError, AttributeError):
            libc = None
    try:
        yield libc is not None
    finally:
        if libc is not None:
            libc.mallopt(_M_TRIM_THRESHOLD, int(env))
            libc.mallopt(_M_MMAP_THRESHOLD, _DEFAULT_MMAP_THRESHOLD)
            libc.malloc_trim(0)


def _first_line(err: BaseException) -> str:
    text = str(err).strip()
    return text.splitlines()[0] if text else ""


def make_executor(scheduler: str | None, workers: int) -> Executor:
    """The Dask executor for a scheduler address, else local processes."""
    if scheduler:
        return DaskExecutor(scheduler)
    return LocalExecutor(workers)
