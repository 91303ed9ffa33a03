"""Running ``rvmsim`` commands from tests: in a child process, or in this process.

* :func:`run_in_child`: ``rvmsim ARGS`` in a child process, optionally under an
  address-space cap, killed at a timeout.  The child is forked from a process that has
  imported the CLI once (multiprocessing's fork server), so it costs milliseconds rather
  than the 1–3 s of a new interpreter; ``fresh=True`` runs ``python -m rvmsim`` itself.
  :func:`start_in_child`: ``python -m rvmsim ARGS`` started and not waited for.  A child is
  for what needs a process of its own: a memory cap, a timeout of a possible hang, a signal
  or a kill, a lock held by another process, a server, anything that would leave state
  behind in this process.
* :func:`run_in_process`: the console-script entry point (``rvmsim.cli.main``) called here,
  with the process state a child would have had set up and put back afterwards, and the
  same :class:`Outcome`.  No interpreter start and no re-import.

What differs in this process, and how :func:`run_in_process` makes it the same:

* ``sys.argv`` and ``__main__`` (as ``python -m rvmsim`` has them: click names the program
  from them), the working folder, the environment (``COLUMNS=200`` as the children get it,
  so click and tqdm format for a wide terminal), stdin (empty, as ``stdin=DEVNULL``): set
  for the call, restored after it.
* stdout and stderr: Python's streams are replaced by buffers, and file descriptors 1 and 2
  point at temporary files during the call, so what C code and spawned workers write is
  captured as a child's pipes would capture it.
* Warnings: pytest turns every warning into an error (``filterwarnings = error``); a child
  has Python's default filters and prints a warning on stderr.  The call runs under the
  default filters, so a warning is a stderr line (which fails a one-line check), not an
  exception the command never sees in production.
* ``sys.exit`` (the CLI's, or a plugin's) is the exit status; any other exception is a
  traceback on stderr and status 1, as in a child.
* Logging handlers that a command attaches to the captured streams are removed afterwards.
* State a child would throw away but this process would keep is refused, not hidden: a
  thread still running after the command (a Dask client), a changed signal handler, a
  criteria plugin *file* imported (plugin modules are cached per process, so a second
  run would not see an edited file), a changed multiprocessing start method or recursion
  limit.  Each is an :class:`AssertionError` telling to use :func:`run_in_child`.
"""

from __future__ import annotations

import atexit
import contextlib
import importlib.util
import json
import io
import logging
import multiprocessing
import os
import resource
import signal
import subprocess
import sys
import tempfile
import threading
import traceback
import types
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Final

REPO: Final = Path(__file__).resolve().parents[1]
#: Address-space cap of a capped child (bytes): a blow-up (a 74 GiB allocation, a
#: billion-laughs expansion) fails with MemoryError, not the machine.
MEMORY_CAP_BYTES: Final = 2 * 1024**3
#: Default wall-time limit of a child (s).
TIMEOUT_S: Final = 600.0
#: Environment every command gets (besides this process's and the caller's).
BASE_ENV: Final = {"PYOPENGL_PLATFORM": "egl", "COLUMNS": "200"}
#: Prefix of the modules :func:`rvmsim.criteria.registry` makes of plugin files.
PLUGIN_FILE_MODULE: Final = "rvmsim_criteria_plugin_"
#: Signals whose handlers a command must leave as it found them.
WATCHED_SIGNALS: Final = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGCHLD)
#: Threads that outlive a command by design and do no harm: tqdm's monitor (one per
#: process, a daemon that only wakes bars up).
HARMLESS_THREADS: Final = ("TMonitor",)
#: What the fork server of :func:`run_in_child` imports once: the CLI and what its commands
#: import when they run (about 400 MB of address space, inside a capped child's cap; no
#: OpenGL context, no thread of ours).  A module missing here is imported by each child.
FORK_SERVER_PRELOAD: Final = ("rvmsim.cli.group", "rvmsim.pipeline", "rvmsim.render", "rvmsim.batch",
                              "rvmsim.report", "rvmsim.validate", "rvmsim.calibrate",
                              "rvmsim.robust", "rvmsim.console")
#: How long a thread a command started may take to end after it returned (s).
THREAD_GRACE_S: Final = 5.0


@dataclass(frozen=True)
class Outcome:
    """What one ``rvmsim`` command did: exit status, stdout and stderr text."""

    code: int
    stdout: str
    stderr: str


Env = Mapping[str, str | None]


def child_command(*args: object) -> list[str]:
    """The argv of ``python -m rvmsim ARGS`` (each argument through ``str``)."""
    return [sys.executable, "-m", "rvmsim", *map(str, args)]


def child_env(env: Env | None = None) -> dict[str, str]:
    """This process's environment with :data:`BASE_ENV`, this worktree first on
    ``PYTHONPATH``, and ``env`` (a value of None removes the variable)."""
    out = {**os.environ, **BASE_ENV}
    out["PYTHONPATH"] = os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH"))
                                        if p)
    for key, value in (env or {}).items():
        if value is None:
            out.pop(key, None)
        else:
            out[key] = value
    return out


def _child_setup(memory_cap: int | None, *,
                 default_sigint: bool = False) -> Callable[[], None] | None:
    """What a child does before it runs Python: cap its address space; take Ctrl-C as a
    program started in a terminal does (a shell's background job ignores SIGINT, and
    children inherit that)."""
    if memory_cap is None and not default_sigint:
        return None

    def setup() -> None:
        if memory_cap is not None:
            resource.setrlimit(resource.RLIMIT_AS, (memory_cap, memory_cap))
        if default_sigint:
            signal.signal(signal.SIGINT, signal.SIG_DFL)
    return setup


def run_in_child(args: Sequence[object], *, cwd: Path | str | None = None,
                 env: Env | None = None, timeout_s: float = TIMEOUT_S,
                 memory_cap: int | None = None, fresh: bool = False) -> Outcome:
    """``rvmsim ARGS`` in a child process, waited for.

    Parameters
    ----------
    args : sequence
        rvmsim's arguments (``str`` of each is passed).
    cwd : path, optional
        Working folder of the child (default: this process's).
    env : mapping, optional
        Variables set (None: removed) on top of :func:`child_env`.
    timeout_s : float
        Wall-time limit (s); over it the child is killed and ``subprocess.TimeoutExpired``
        raised.
    memory_cap : int, optional
        Address-space limit of the child (bytes), e.g. :data:`MEMORY_CAP_BYTES`.
    fresh : bool
        ``python -m rvmsim ARGS`` in a new interpreter (1–3 s of imports) instead of a fork of
        a process that has imported the CLI once (:func:`_forked_child`).
    """
    if not fresh:
        return _forked_child([str(a) for a in args], cwd=cwd, env=child_env(env),
                             timeout_s=timeout_s, memory_cap=memory_cap)
    res = subprocess.run(child_command(*args), cwd=cwd, env=child_env(env),
                         capture_output=True, text=True, timeout=timeout_s,
                         stdin=subprocess.DEVNULL, preexec_fn=_child_setup(memory_cap))
    return Outcome(res.returncode, res.stdout, res.stderr)


def _forked_child(args: list[str], *, cwd: Path | str | None, env: dict[str, str],
                  timeout_s: float, memory_cap: int | None) -> Outcome:
    """``rvmsim ARGS`` in a child forked from multiprocessing's fork server, which imports
    :data:`FORK_SERVER_PRELOAD` once (per test process): a separate process (its own memory,
    cap, signal handlers, threads; killed at the timeout) without an interpreter start.  The
    child takes the working folder, the whole environment and argv given, stdin from
    /dev/null, stdout and stderr into files, and exits as ``python -m rvmsim`` would."""
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(FORK_SERVER_PRELOAD))
    with tempfile.TemporaryDirectory(prefix="rvmsim-child-") as tmp:
        out, err = Path(tmp) / "stdout", Path(tmp) / "stderr"
        proc = ctx.Process(target=_child_main, name="rvmsim",
                           args=(args, str(cwd or os.getcwd()), env, str(out), str(err),
                                 memory_cap))
        proc.start()
        proc.join(timeout_s)
        if proc.is_alive():
            proc.kill()
            proc.join()
            raise subprocess.TimeoutExpired(["rvmsim", *args], timeout_s)
        code = proc.exitcode
        assert code is not None
        return Outcome(code, out.read_text(errors="backslashreplace"),
                       err.read_text(errors="backslashreplace"))


def _child_main(args: list[str], cwd: str, env: dict[str, str], out: str, err: str,
                memory_cap: int | None) -> None:
    """The forked child: set the process up as ``python -m rvmsim`` finds it, run the entry
    point, exit with its status (an uncaught exception: its traceback, status 1)."""
    if memory_cap is not None:
        resource.setrlimit(resource.RLIMIT_AS, (memory_cap, memory_cap))
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(env)
    new_paths = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p not in sys.path]
    sys.path[:0] = [p for p in new_paths if p]  # as a new interpreter would put them first
    for fd, path in ((1, out), (2, err)):
        target = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        os.dup2(target, fd)
        os.close(target)
    sys.stdout = io.TextIOWrapper(open(1, "wb", closefd=False), line_buffering=True)
    sys.stderr = io.TextIOWrapper(open(2, "wb", closefd=False), line_buffering=True,
                                  errors="backslashreplace")
    _python_m_rvmsim(args)
    code = _call_main()
    atexit._run_exitfuncs()  # what an interpreter does on its way out (a child skips it)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def start_in_child(args: Sequence[object], *, cwd: Path | str | None = None,
                   env: Env | None = None, memory_cap: int | None = None,
                   stdout: int | IO[Any] | None = subprocess.DEVNULL,
                   stderr: int | IO[Any] | None = subprocess.DEVNULL,
                   start_new_session: bool = False) -> subprocess.Popen[str]:
    """``python -m rvmsim ARGS`` started in a child process and not waited for (to be
    signalled, killed, or to hold a lock while another command runs); text mode, stdin
    from ``/dev/null``, SIGINT at its default (Ctrl-C interrupts it even when this process
    runs as a background job); ``stdout``/``stderr`` as for :class:`subprocess.Popen`."""
    return subprocess.Popen(child_command(*args), cwd=cwd, env=child_env(env), text=True,
                            stdin=subprocess.DEVNULL, stdout=stdout, stderr=stderr,
                            preexec_fn=_child_setup(memory_cap, default_sigint=True),
                            start_new_session=start_new_session)


# ---------------------------------------------------------------------------- in process
@contextlib.contextmanager
def _environment(env: Env | None) -> Iterator[None]:
    """``os.environ`` with :data:`BASE_ENV` and ``env`` for the block, then as it was."""
    saved = dict(os.environ)
    try:
        os.environ.update(BASE_ENV)
        for key, value in (env or {}).items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        yield
    finally:
        for key in set(os.environ) - set(saved):
            del os.environ[key]
        for key, value in saved.items():
            if os.environ.get(key) != value:
                os.environ[key] = value


@contextlib.contextmanager
def _fd_captured(fd: int, sink: IO[bytes]) -> Iterator[None]:
    """File descriptor ``fd`` pointing at ``sink`` for the block."""
    saved = os.dup(fd)
    try:
        os.dup2(sink.fileno(), fd)
        yield
    finally:
        os.dup2(saved, fd)
        os.close(saved)


@dataclass
class _Captured:
    """What a command wrote: Python's stream first, then what reached the descriptor."""

    stdout: str = ""
    stderr: str = ""


def _read(sink: IO[bytes]) -> str:
    sink.seek(0)
    return sink.read().decode("utf-8", "backslashreplace")


@contextlib.contextmanager
def _captured() -> Iterator[_Captured]:
    """stdin empty; stdout and stderr captured at the Python and the descriptor level
    (filled in when the block ends)."""
    for stream in (sys.stdout, sys.stderr):
        stream.flush()  # what this process wrote before is not the command's
    result = _Captured()
    py_out, py_err = io.StringIO(), io.StringIO()
    saved = (sys.stdin, sys.stdout, sys.stderr)
    with tempfile.TemporaryFile() as fd_out, tempfile.TemporaryFile() as fd_err:
        try:
            with _fd_captured(1, fd_out), _fd_captured(2, fd_err):
                sys.stdin, sys.stdout, sys.stderr = io.StringIO(""), py_out, py_err
                try:
                    yield result
                finally:
                    sys.stdin, sys.stdout, sys.stderr = saved
                    _drop_handlers_of(py_out, py_err)
        finally:
            result.stdout = py_out.getvalue() + _read(fd_out)
            result.stderr = py_err.getvalue() + _read(fd_err)


def _drop_handlers_of(*streams: object) -> None:
    """Remove every logging handler writing to one of ``streams`` (made during the call)."""
    loggers = [logging.getLogger(), *(lg for lg in logging.Logger.manager.loggerDict.values()
                                      if isinstance(lg, logging.Logger))]
    for lg in loggers:
        for handler in list(lg.handlers):
            if getattr(handler, "stream", None) in streams:
                lg.removeHandler(handler)


def _print_warning(message: Warning | str, category: type[Warning], filename: str,
                   lineno: int, file: IO[str] | None = None, line: str | None = None) -> None:
    """Print a warning on stderr, as an interpreter without pytest does."""
    (file or sys.stderr).write(warnings.formatwarning(message, category, filename, lineno,
                                                      line))


@contextlib.contextmanager
def _child_warnings() -> Iterator[None]:
    """Python's default warning filters (a fresh interpreter's) for the block."""
    with warnings.catch_warnings():
        warnings.resetwarnings()
        warnings.filterwarnings("default", category=DeprecationWarning, module="__main__")
        for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning,
                         ResourceWarning):
            warnings.filterwarnings("ignore", category=category, append=True)
        warnings.showwarning = _print_warning  # not into pytest's record of warnings
        yield


def _start_method() -> str:
    """The multiprocessing start method in force (the platform's default, the first of
    ``get_all_start_methods()``, until someone sets or first asks for it)."""
    return (multiprocessing.get_start_method(allow_none=True)
            or multiprocessing.get_all_start_methods()[0])


@dataclass(frozen=True)
class _Globals:
    """Process state a command must not change (see the module docstring)."""

    threads: frozenset[threading.Thread]
    handlers: tuple[Any, ...]
    plugin_modules: frozenset[str]
    start_method: str
    recursion_limit: int
    sys_path: tuple[str, ...]

    @classmethod
    def now(cls) -> _Globals:
        return cls(frozenset(threading.enumerate()),
                   tuple(signal.getsignal(s) for s in WATCHED_SIGNALS),
                   frozenset(m for m in sys.modules if m.startswith(PLUGIN_FILE_MODULE)),
                   _start_method(),
                   sys.getrecursionlimit(), tuple(sys.path))

    def changes(self, before: _Globals) -> list[str]:
        """What changed since ``before`` (putting back what can be put back)."""
        out = []
        if self.sys_path != before.sys_path:
            sys.path[:] = before.sys_path
        for sig, old, new in zip(WATCHED_SIGNALS, before.handlers, self.handlers):
            if old != new:
                signal.signal(sig, old)
                out.append(f"changed the handler of {sig.name}")
        plugins = sorted(self.plugin_modules - before.plugin_modules)
        if plugins:
            out.append(f"imported plugin files {plugins}")
        if self.start_method != before.start_method:
            out.append(f"set the multiprocessing start method to {self.start_method}")
        if self.recursion_limit != before.recursion_limit:
            sys.setrecursionlimit(before.recursion_limit)
            out.append(f"set the recursion limit to {self.recursion_limit}")
        return out


def _threads_left(before: frozenset[threading.Thread]) -> list[str]:
    """Threads started during the call that are still running after a grace period."""
    new = [t for t in threading.enumerate() if t not in before
           and type(t).__name__ not in HARMLESS_THREADS]
    for t in new:
        t.join(THREAD_GRACE_S / max(1, len(new)))
    return [t.name for t in new if t.is_alive()]


def _exit_status(stop: SystemExit, stderr: IO[str]) -> int:
    """The status a child would exit with after ``SystemExit(stop.code)``."""
    if stop.code is None:
        return 0
    if isinstance(stop.code, int):
        return stop.code
    print(stop.code, file=stderr)
    return 1


def _python_m_rvmsim(args: list[str]) -> None:
    """``sys.argv`` and ``__main__`` as ``python -m rvmsim ARGS`` has them (click names the
    program from both: "python -m rvmsim")."""
    spec = importlib.util.find_spec("rvmsim.__main__")
    sys.argv = [spec.origin if spec is not None and spec.origin else "rvmsim", *args]
    main = types.ModuleType("__main__")
    main.__package__ = "rvmsim"
    sys.modules["__main__"] = main


def _call_main() -> int:
    """``rvmsim.cli.main()`` (reading ``sys.argv``) → the exit status; any other exception
    that leaves it (even one not derived from ``Exception``) is printed as the interpreter
    prints it, status 1."""
    from rvmsim.cli import main

    try:
        main()
    except SystemExit as stop:
        return _exit_status(stop, sys.stderr)
    except KeyboardInterrupt:
        raise  # the person running the tests pressed Ctrl-C
    except BaseException:  # noqa: BLE001 - what a child would die of: a traceback, status 1
        traceback.print_exc(file=sys.stderr)
        return 1
    return 0


def tune_status(run: Path | str) -> int:
    """The exit status ``rvmsim tune`` owes for the finished run folder ``run``, read from
    what the run wrote: 0 when its best setting passes what the run judges
    (``best/markets.json``, else ``best/members.json``, else ``best/ec.json``), else 1."""
    best = Path(run) / "best"
    for name in ("markets.json", "members.json", "ec.json"):
        if (best / name).is_file():
            return 0 if json.loads((best / name).read_text(encoding="utf-8"))["passed"] else 1
    return 1


def run_in_process(args: Sequence[object], *, cwd: Path | str | None = None,
                   env: Env | None = None) -> Outcome:
    """``rvmsim ARGS`` through the console-script entry point, in this process.

    Parameters
    ----------
    args : sequence
        rvmsim's arguments (``str`` of each is passed).
    cwd : path, optional
        Working folder during the call (default: this process's).
    env : mapping, optional
        Variables set (None: removed) on top of this process's environment and
        :data:`BASE_ENV`, for the call only.

    Raises
    ------
    AssertionError
        The command left process state behind that a child would not have (see the module
        docstring): run it with :func:`run_in_child`.
    """
    before = _Globals.now()
    saved_argv, saved_main, saved_cwd = sys.argv, sys.modules["__main__"], os.getcwd()
    try:
        with _environment(env), _child_warnings(), _captured() as streams:
            _python_m_rvmsim([str(a) for a in args])
            if cwd is not None:
                os.chdir(cwd)
            code = _call_main()
    finally:
        sys.argv, sys.modules["__main__"] = saved_argv, saved_main
        os.chdir(saved_cwd)
    problems = _Globals.now().changes(before)
    left = _threads_left(before.threads)
    if left:
        problems.append(f"left threads running {left}")
    if problems:
        raise AssertionError(f"rvmsim {' '.join(map(str, args))} " + "; ".join(problems)
                             + ": run it with run_in_child")
    return Outcome(code, streams.stdout, streams.stderr)
