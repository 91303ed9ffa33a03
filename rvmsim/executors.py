"""Where independent tasks (one design point, one vehicle) run: local processes or a Dask
cluster.

Both executors take a mapping ``{key: argument}`` and a picklable top-level function, and
yield ``(key, result)`` as tasks finish, in completion order.  The caller stores each result
as it arrives, so an interrupted run keeps everything finished.

- :class:`LocalExecutor`: ``workers`` spawned processes on this machine
  (``concurrent.futures.ProcessPoolExecutor``).  If a worker process dies (killed, out of
  memory), the pool is rebuilt and the tasks that had not finished run again.
- :class:`DaskExecutor`: an existing Dask ``distributed`` cluster (``tcp://HOST:PORT``).
  The scheduler does the scheduling: a worker lost mid-task has only its tasks re-run
  elsewhere (``distributed``'s own recovery).  rvmsim must be importable on the workers;
  scene mesh files must be readable there at the same paths.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import Any

from .errors import RvmsimError

__all__ = ["Executor", "LocalExecutor", "DaskExecutor", "make_executor"]

#: How often the local executor rebuilds its pool after losing a worker before giving up.
MAX_POOL_REBUILDS = 3


class Executor:
    """Runs ``fn(arg)`` for every item; see the module docstring."""

    name = "executor"

    def run(self, fn: Callable[[Any], Any], items: Mapping[str, Any]) -> Iterator[tuple[str, Any]]:
        raise NotImplementedError

    def close(self) -> None:
        pass

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class LocalExecutor(Executor):
    """``workers`` spawned processes on this machine (1: run in this process)."""

    name = "local"

    def __init__(self, workers: int = 1):
        self.workers = max(1, int(workers))

    def run(self, fn: Callable[[Any], Any], items: Mapping[str, Any]) -> Iterator[tuple[str, Any]]:
        if self.workers == 1:
            for key, arg in items.items():
                yield key, fn(arg)
            return
        import multiprocessing as mp
        from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
        from concurrent.futures.process import BrokenProcessPool

        todo = dict(items)
        rebuilds = 0
        while todo:
            pool = ProcessPoolExecutor(self.workers, mp_context=mp.get_context("spawn"))
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
                            broken = True
                            continue
                        del todo[key]
                        yield key, result
                    if broken:
                        break
            except BaseException:  # Ctrl-C, or the caller stopped: stop the workers now
                for proc in list((getattr(pool, "_processes", None) or {}).values()):
                    proc.terminate()
                broken = True
                raise
            finally:
                pool.shutdown(wait=not broken, cancel_futures=True)
            if broken:
                rebuilds += 1
                if rebuilds > MAX_POOL_REBUILDS:
                    raise RvmsimError(f"worker processes died {rebuilds} times; "
                                      f"{len(todo)} tasks not run")


class DaskExecutor(Executor):
    """Tasks on an existing Dask distributed cluster at ``address`` (``tcp://HOST:PORT``),
    or on a given ``client``."""

    name = "dask"

    def __init__(self, address: str | None = None, *, client: Any = None,
                 timeout_s: float = 10.0):
        try:
            import distributed
        except ImportError:
            raise RvmsimError("--scheduler needs the 'distributed' package "
                              "(pip install distributed)") from None
        self._own = client is None
        if client is None:
            try:
                client = distributed.Client(address, timeout=timeout_s)
            except (OSError, TimeoutError, ValueError) as err:
                raise RvmsimError(f"{address}: cannot reach the Dask scheduler ({err})") from None
        self.client = client
        self.address = address or client.scheduler.address

    def run(self, fn: Callable[[Any], Any], items: Mapping[str, Any]) -> Iterator[tuple[str, Any]]:
        import distributed

        futures = {self.client.submit(fn, arg, key=f"rvmsim-{key}", pure=False): key
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


def _first_line(err: BaseException) -> str:
    text = str(err).strip()
    return text.splitlines()[0] if text else ""


def make_executor(scheduler: str | None, workers: int) -> Executor:
    """The Dask executor for a scheduler address, else local processes."""
    if scheduler:
        return DaskExecutor(scheduler)
    return LocalExecutor(workers)
