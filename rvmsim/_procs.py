"""Worker processes on this machine: the one process-pool recipe tuning and batches share,
and the rule that no process outlives its parent.

Workers are not forked from the caller: a process that has run OpenCV's thread pool or an
OpenGL context cannot be forked safely.  They are forked from multiprocessing's *fork
server*, a process of its own started once per process (at its first pool) that imports
:data:`WORKER_PRELOAD` and nothing else, so every worker of every pool starts with the
package imported (milliseconds, where a spawned worker took seconds to import it again).
Where there is no fork server (Windows), workers are spawned.  :func:`start_pool` makes the
pool (:class:`concurrent.futures.ProcessPoolExecutor`, optionally with a per-worker
initializer that receives the state every task reads); :func:`stop_pool` ends it, at once
when the caller is interrupted.  A worker takes the caller's environment as it is when the
pool is made (the fork server's is that of its start).

**No process outlives its parent.**  However the parent ends (Ctrl-C, SIGTERM, SIGKILL, a
crash), every worker of :func:`start_pool` exits within about a second
(:func:`die_with_parent`, run in each worker before anything else):

- on Linux the kernel sends it SIGKILL when the process that forked it dies
  (``PR_SET_PDEATHSIG``).  That is the fork server, which ends as soon as the parent is
  gone (it waits on a pipe only the parent holds: each worker closes its inherited copy).
  A spawned worker's is the parent itself (set only when the pool is made in the main
  thread, since the kernel ties it to the *thread* that started the worker).  The worker
  checks its parent right after setting it, in case the parent died while it started;
- on every platform a daemon thread waits on the pipe multiprocessing keeps from the parent
  to each child (:func:`multiprocessing.parent_process`'s sentinel, at end of file once the
  parent is gone: no polling) and ends the worker with :func:`os._exit`;
- Ctrl-C is the parent's business: workers ignore SIGINT (a terminal sends it to the whole
  process group; the fork server ignores it too), and the parent stops them with
  :func:`stop_pool` as it unwinds.

The multiprocessing resource tracker, the other child, exits by itself once the parent and
every worker have closed its pipe (so within the same second).  A pool must be fed
(``submit``, ``map``) from the thread that made it: that thread starts the workers.

:func:`stop_on_signals` makes SIGTERM the same orderly stop as Ctrl-C in the command line
(:class:`Terminated`, a :class:`KeyboardInterrupt`: every finished batch stays stored and
the run can be resumed; a SIGTERM more than :data:`SIGTERM_REPEAT_S` after the first ends
the process at once, one sooner is the same stop sent again to the process group, as
``timeout`` and service managers do).  Under it, either signal
waits while a pool starts a worker (``submit`` writes the worker's state into a pipe the
worker reads as it starts, up to a second): cut there, the worker would be left out of the
pool's table, unstopped, and die of its half-read state with a traceback on the command's
stderr.

Workers never import the caller's ``__main__`` (multiprocessing would run a script again in
each worker, and in the fork server, unless it guards itself with
``if __name__ == "__main__"``): their tasks are rvmsim's own, so a user's plain script that
renders or tunes works as it reads (:func:`_main_hidden`).
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing as mp
import multiprocessing.forkserver
import multiprocessing.resource_tracker
import multiprocessing.util
import os
import pickle
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from types import FrameType
from typing import Any, Final, ParamSpec, TypeVar

from .errors import RvmsimError

__all__ = ["start_pool", "start_worker_server", "WORKER_PRELOAD", "stop_pool", "stop_helpers",
           "die_with_parent", "stop_on_signals", "stop_requested", "Terminated",
           "ORPHAN_EXIT_STATUS", "SIGTERM_REPEAT_S"]

_P = ParamSpec("_P")
_T = TypeVar("_T")

#: What the fork server imports as it starts, so that every worker starts with it: the
#: modules of the pools' tasks (tuning, batches, the end-of-line station) and pyrender for
#: the render workers (:func:`rvmsim.render.render_faces`).
WORKER_PRELOAD: Final = ("rvmsim.tune", "rvmsim.batch", "rvmsim.eol",
                         "rvmsim.render._gl_preload")
#: Exit status of a worker that ends because its parent is gone (nobody reads it).
ORPHAN_EXIT_STATUS = 75
#: Linux's ``prctl`` option that sets the signal a process gets when its parent dies.
_PR_SET_PDEATHSIG = 1
#: Longest wait (s) of :func:`stop_pool` for terminated workers to be gone and their pool to
#: know it.
_BROKEN_WAIT_S = 2.0
#: How often the fallback watch polls the parent's pid when there is no parent pipe (s).
_POLL_S = 0.25


def start_pool(workers: int, *, initializer: Callable[..., None] | None = None,
               initargs: tuple[Any, ...] = ()) -> ProcessPoolExecutor:
    """A pool of ``workers`` processes, each running ``initializer(*initargs)`` once when it
    starts, after :func:`die_with_parent` (every worker ends with this process; see the
    module docstring).  Submit to it from the thread that calls this."""
    # The initializer and its state travel pickled and are unpickled only once the worker
    # watches its parent: unpickling a scorer may import half the package.
    payload = pickle.dumps((initializer, initargs), protocol=pickle.HIGHEST_PROTOCOL)
    context: mp.context.BaseContext
    if start_worker_server():
        context = mp.get_context("forkserver")
        kernel = True  # the fork server's main thread forks every worker
    else:
        context = mp.get_context("spawn")
        kernel = threading.current_thread() is threading.main_thread()
    return _Pool(max(1, workers), mp_context=context, initializer=_start_worker,
                 initargs=(os.getpid(), kernel, dict(os.environ), payload))


def start_worker_server(also: Sequence[str] = (), *,
                        preload: Sequence[str] = WORKER_PRELOAD) -> bool:
    """Start the fork server every pool's workers are forked from, if it is not running
    (it imports ``preload`` and the modules ``also`` in the background: this returns at
    once; a server already running keeps what it imported, and a worker imports what its
    task needs beyond it).  False where there is no fork server (workers are spawned)."""
    if "forkserver" not in mp.get_all_start_methods():
        return False
    # The preload takes effect when the server starts (a running server keeps its own).
    # The server ignores SIGINT (multiprocessing's) and SIGTERM (rvmsim._forkserver, which it
    # imports first), so a signal to the whole process group leaves it to reap its workers.
    multiprocessing.forkserver.set_forkserver_preload(
        list(dict.fromkeys(["rvmsim._forkserver", *preload, *also])))
    with _sigint_blocked(), _main_hidden():
        multiprocessing.forkserver.ensure_running()
    return True


class _Pool(ProcessPoolExecutor):
    """A process pool whose ``submit`` (``map`` calls it), which starts a worker when one
    is missing, is not cut by Ctrl-C or SIGTERM half-way (:func:`stop_on_signals`)."""

    def submit(self, fn: Callable[_P, _T], /, *args: _P.args,
               **kwargs: _P.kwargs) -> Future[_T]:
        task: Callable[..., _T] = _task
        with _signals_held(), _sigint_blocked(), _main_hidden():
            return super().submit(task, fn, *args, **kwargs)


#: This worker's start-up failure: its state or initializer raised an
#: :class:`~rvmsim.errors.RvmsimError` (e.g. a criteria plugin that fails when the worker
#: loads it again).  Every task the worker runs raises it (:func:`_task`), so the parent gets
#: it as the task's error, one line, instead of a traceback and a broken pool.
_START_FAILURE: RvmsimError | None = None


def _task(fn: Callable[..., _T], *args: Any, **kwargs: Any) -> _T:
    """A pool task: ``fn(*args, **kwargs)``, or the worker's start-up failure."""
    if _START_FAILURE is not None:
        raise _START_FAILURE
    return fn(*args, **kwargs)


@contextlib.contextmanager
def _main_hidden() -> Iterator[None]:
    """While a process starts: the caller's ``__main__`` shows neither a file nor a module
    name, so multiprocessing does not have the new process import it (as ``__mp_main__``,
    running a script's unguarded code again)."""
    main = sys.modules.get("__main__")
    if main is None:
        yield
        return
    saved: dict[str, Any] = {k: main.__dict__[k] for k in ("__file__", "__spec__")
                             if k in main.__dict__}
    main.__dict__.pop("__file__", None)
    main.__dict__["__spec__"] = None
    try:
        yield
    finally:
        main.__dict__.pop("__spec__", None)
        main.__dict__.update(saved)


@contextlib.contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in this thread for the block (delivered when it ends): a worker started
    meanwhile inherits the mask, so a Ctrl-C that reaches the whole process group while it
    starts stays pending until it ignores SIGINT (:func:`_start_worker`), instead of
    raising in its start-up.  (multiprocessing starts its resource tracker the same way.)"""
    if not hasattr(signal, "pthread_sigmask"):  # Windows: no process groups to signal
        yield
        return
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def stop_pool(pool: ProcessPoolExecutor, *, now: bool) -> None:
    """Shut ``pool`` down: with ``now``, terminate its workers first (Ctrl-C, a stopped
    run, a broken pool) instead of waiting for the tasks in flight."""
    if now:
        # concurrent.futures has no public way to end running workers before Python 3.14
        # (ProcessPoolExecutor.terminate_workers); its process table is the only handle.
        procs = list((getattr(pool, "_processes", None) or {}).values())
        for proc in procs:
            proc.terminate()
        # Let the pool's manager thread see its workers gone and fail the tasks still
        # pending before they are cancelled: cancelled first, it fails them afterwards and
        # prints an InvalidStateError traceback (Python 3.11's concurrent.futures).
        deadline = time.monotonic() + _BROKEN_WAIT_S
        for proc in procs:
            proc.join(max(0.0, deadline - time.monotonic()))
        while procs and not getattr(pool, "_broken", True) and time.monotonic() < deadline:
            time.sleep(0.01)
    pool.shutdown(wait=not now, cancel_futures=True)


def stop_helpers() -> None:
    """End the helper processes multiprocessing started for this process, the worker fork
    server and the resource tracker, and wait until they are gone.

    Left alone, each ends when it sees this process's end (its pipe closes), a moment after
    it: a supervisor that reads a command's exit status and then looks at its process group
    would still find them.  The command line runs this as the interpreter exits (registered
    by :func:`rvmsim.cli.entry.main`), after its pools and its render worker have ended; a
    process that did not start them (a worker, which inherited them) leaves them alone.
    multiprocessing has no public call for either (both ``_stop`` methods are what its own
    tests use), so this reads their private handles, as :func:`_leave_fork_server` does.
    """
    if mp.parent_process() is not None:
        return
    for child in mp.active_children():  # the pools' workers, reaped by the server first
        child.join(_BROKEN_WAIT_S)  # (ended by a signal to the group: its status unread)
    server = multiprocessing.forkserver._forkserver
    if getattr(server, "_forkserver_pid", None) is not None:
        server._stop()  # type: ignore[attr-defined]  # private, see above
    # Then what the interpreter's exit would run after this: the finalizers that unlink the
    # pools' semaphores (and tell the tracker so) and remove multiprocessing's temporary
    # folder.  A pool that broke (its workers ended by a signal to the process group) still
    # holds its semaphores here; with the tracker stopped first, it unlinks them itself
    # with a "leaked semaphore objects" warning, and each finalizer then fails with a
    # traceback.  It runs once (multiprocessing marks it done).
    multiprocessing.util._exit_function()  # type: ignore[attr-defined]  # private, see above
    tracker = multiprocessing.resource_tracker._resource_tracker
    if getattr(tracker, "_pid", None) is not None:
        tracker._stop()  # type: ignore[attr-defined]  # private, see above


def _start_worker(parent_pid: int, kernel: bool, environ: dict[str, str],
                  payload: bytes) -> None:
    """A pool worker's first step: die with the parent, leave Ctrl-C to it, take the
    parent's environment, then run the pool's own initializer."""
    die_with_parent(parent_pid, kernel=kernel)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # drops a Ctrl-C pending since the start
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # the fork server's is "ignore"
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    os.environ.clear()
    os.environ.update(environ)
    global _START_FAILURE
    try:
        initializer, initargs = pickle.loads(payload)
        if initializer is not None:
            initializer(*initargs)
    except RvmsimError as err:  # kept for the tasks to raise (see _START_FAILURE)
        _START_FAILURE = err


def die_with_parent(parent_pid: int, *, kernel: bool = True) -> None:
    """End this process as soon as process ``parent_pid`` (its parent) is gone.

    Parameters
    ----------
    parent_pid : int
        The parent's pid, as the parent saw it (:func:`os.getpid` there).
    kernel : bool
        Also ask Linux for SIGKILL at the death of the process that forked this one
        (``PR_SET_PDEATHSIG``): the parent, or the fork server, which ends with it.  Only
        when it was forked from a thread that lives as long as its process (the kernel
        watches the thread that forked, so a worker started from a thread that then ends
        would die).

    A daemon thread watches too (every platform; see the module docstring), and if the
    parent is already gone the process exits here with :data:`ORPHAN_EXIT_STATUS`.
    """
    if kernel and sys.platform.startswith("linux"):
        _kill_at_parent_death()
    _leave_fork_server()
    parent = mp.parent_process()
    if parent is not None and parent.pid == parent_pid:
        gone = not parent.is_alive()  # its sentinel: the parent's end of a pipe
    else:  # not a multiprocessing child
        gone = os.getppid() != parent_pid
    if gone:  # it died before the kernel was told: nobody will say so
        os._exit(ORPHAN_EXIT_STATUS)
    threading.Thread(target=_watch_parent, args=(parent_pid,), name="rvmsim-parent-watch",
                     daemon=True).start()


def _leave_fork_server() -> None:
    """Close this process's copy of the write end of the fork server's "alive" pipe.

    multiprocessing gives every process its fork server forks a copy (so that such a process
    could start more of them), and the server runs until every copy is closed.  A worker
    starts none, and without its copy the server ends as soon as the parent is gone, and
    the kernel then ends the worker (see :func:`die_with_parent`)."""
    server = multiprocessing.forkserver._forkserver  # the module's one server; no public handle
    fd = getattr(server, "_forkserver_alive_fd", None)
    if fd is not None and getattr(server, "_forkserver_pid", None) is None:  # inherited
        os.close(fd)
        setattr(server, "_forkserver_alive_fd", None)


def _kill_at_parent_death() -> None:
    """``prctl(PR_SET_PDEATHSIG, SIGKILL)`` through the C library."""

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        failed = libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) != 0
    except (OSError, AttributeError):  # no prctl in this C library: the thread watches alone
        failed = True
    if failed:
        print(f"rvmsim: worker {os.getpid()}: PR_SET_PDEATHSIG not available; a thread "
              "watches the parent instead", file=sys.stderr)


def _watch_parent(parent_pid: int) -> None:
    """Block until the parent is gone, then end this process at once."""
    parent = mp.parent_process()
    if parent is not None and parent.pid == parent_pid:
        parent.join()  # its sentinel: the parent's end of the start-up pipe closed
    else:  # not a multiprocessing child: watch the parent's pid (re-parented when it dies)
        while os.getppid() == parent_pid:
            time.sleep(_POLL_S)
    os._exit(ORPHAN_EXIT_STATUS)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the main thread is, to stop as Ctrl-C stops
    (:func:`stop_on_signals`); ``signal_number`` is the signal's."""

    signal_number = int(signal.SIGTERM)


#: Sections of the main thread that a stop must not cut (nested), and the stop that came
#: during one, raised as the outermost ends.
_held = 0
_pending: KeyboardInterrupt | None = None
#: When the first SIGTERM of :func:`stop_on_signals` came (monotonic s; None: none yet).
_sigterm_at: float | None = None
#: A SIGTERM within this many seconds of the first is the same stop (s): ``timeout`` and
#: a service manager send SIGTERM to the command and then to its whole process group, so
#: the command gets it twice at once.  A later one ends the process at once.
SIGTERM_REPEAT_S: Final = 2.0


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """For the block: a Ctrl-C or SIGTERM (under :func:`stop_on_signals`) in the main
    thread waits, and is raised when the block ends."""
    global _held, _pending
    if threading.current_thread() is not threading.main_thread():
        yield  # signal handlers run in the main thread only
        return
    _held += 1
    try:
        yield
    finally:
        _held -= 1
        if _held == 0 and _pending is not None:
            stop, _pending = _pending, None
            raise stop


def _stop(stop: KeyboardInterrupt) -> None:
    """Raise ``stop`` now, or when the held section ends."""
    global _pending
    if _held:
        _pending = _pending or stop
        return
    raise stop


def _on_sigint(signum: int, frame: FrameType | None) -> None:
    _stop(KeyboardInterrupt())


def _on_sigterm(signum: int, frame: FrameType | None) -> None:
    # one orderly stop; a later SIGTERM (say, from an impatient supervisor) ends at once
    global _sigterm_at
    if _sigterm_at is not None:
        if time.monotonic() - _sigterm_at < SIGTERM_REPEAT_S:
            return  # the same stop, sent again to the whole process group
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        return
    _sigterm_at = time.monotonic()
    _stop(Terminated())


def stop_requested() -> KeyboardInterrupt | None:
    """The stop (:class:`Terminated`) that a SIGTERM under :func:`stop_on_signals` has
    asked for, or None.  A caller whose pool broke raises it instead of reporting a failed
    worker: a SIGTERM sent to the whole process group ends the workers too, and their pool
    may report that before the caller has seen its own signal."""
    return Terminated() if _sigterm_at is not None else None


@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """For the block: SIGTERM raises :class:`Terminated` (a KeyboardInterrupt) in the main
    thread, so a command stops as after Ctrl-C (workers stopped, results kept, run
    resumable), and neither signal cuts a pool's start of a worker (see the module
    docstring).  The previous handlers are put back afterwards (unless the block set other
    ones).  A signal ignored when the block starts stays ignored; outside the main thread
    (where Python cannot set handlers) nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    global _sigterm_at
    ours = {signal.SIGINT: _on_sigint, signal.SIGTERM: _on_sigterm}
    before = {sig: signal.getsignal(sig) for sig in ours}
    _sigterm_at = None
    ours = {sig: handler for sig, handler in ours.items()
            if before[sig] is not signal.SIG_IGN}  # started as "ignore" (nohup, background)
    for sig, handler in ours.items():
        signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, handler in ours.items():
            # ours (or SIGTERM's default after one stop) goes; a handler someone else set
            # meanwhile stays, theirs to answer for
            if signal.getsignal(sig) in (handler, signal.SIG_DFL):
                old = before[sig]
                signal.signal(sig, old if old is not None else signal.SIG_DFL)
