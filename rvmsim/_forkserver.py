"""Run by the worker fork server as it starts (:func:`rvmsim._procs.start_worker_server`
preloads this module before any other): the server ignores SIGTERM.

A supervisor stops a command with SIGTERM to its whole process group (``timeout``, a
service manager), which reaches the fork server too.  Ended by it, the server would leave
the workers it forked (ended by the same signal) unreaped, to be reaped by init some time
after the command has returned.  Ignoring it, the server reaps them and ends when the
command stops it or is gone (it waits on a pipe only the command holds), as before.  Its
workers are forked with SIGTERM at its default again (:func:`rvmsim._procs._start_worker`).

Imported anywhere else, this module does nothing.
"""

from __future__ import annotations

import multiprocessing.forkserver
import signal
import sys

__all__: list[str] = []


def _in_fork_server() -> bool:
    """Whether this import runs inside the fork server's start (multiprocessing's
    ``forkserver.main`` preloading its modules)."""
    frame = sys._getframe()
    while frame is not None:
        if frame.f_code is multiprocessing.forkserver.main.__code__:
            return True
        frame = frame.f_back  # type: ignore[assignment]
    return False


if _in_fork_server():
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
