"""The writer lock of a run folder or a sweep folder: one writer at a time, readers never wait.

A writer (``rvmsim tune``, ``tune --resume``, ``rvmsim sweep``) holds an OS-level lock on
``STEM.lock`` in the folder for as long as it writes (:class:`FolderLock`), and records who
it is beside it, in ``STEM.pid`` (its process id, host and process start time).  A second
writer fails at once with one line, ``FOLDER is in use by process N``.

Convention
----------
The lock is :mod:`filelock`'s (``fcntl.flock`` underneath on Linux and macOS): the kernel
drops it when the holding process ends in any way, SIGKILL included, so a lock left by a
killed writer is free again and the next writer simply takes it (and rewrites ``STEM.pid``).
SQLite's own locks are per transaction and, held for a whole run, would block the readers.

Readers (``rvmsim status``, ``select``, ``report``) never take the lock: :meth:`FolderLock.
writer` reads ``STEM.pid`` and checks that the process recorded there is still the same live
process (same start time, where the system tells it), which is how ``status`` tells a run
whose writer was killed ("interrupted (resumable)") from one still running.
"""

from __future__ import annotations

import os
import socket
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType

from filelock import FileLock, Timeout

from ..errors import RvmsimError

__all__ = ["FolderLock", "Writer"]


def _start_time(pid: int) -> str:
    """The start time of process ``pid`` as the system records it (Linux: clock ticks since
    boot, field 22 of ``/proc/PID/stat``), or "" where it cannot be read."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:  # no such process, or no /proc (macOS): the start time is not known
        return ""
    fields = stat[stat.rfind(")") + 2:].split()  # the command name may hold spaces
    return fields[19] if len(fields) > 19 else ""


@dataclass(frozen=True)
class Writer:
    """The process that writes a folder, as recorded beside its lock: process id, host
    name, and start time ("" where unknown; it tells a reused process id from the writer)."""

    pid: int
    host: str
    started: str

    @classmethod
    def this_process(cls) -> Writer:
        pid = os.getpid()
        return cls(pid, socket.gethostname(), _start_time(pid))

    @classmethod
    def parse(cls, text: str) -> Writer | None:
        """The writer of a ``STEM.pid`` text (``PID HOST [START]``), None if it is not one."""
        parts = text.split()
        if len(parts) not in (2, 3) or not parts[0].isdigit():
            return None
        return cls(int(parts[0]), parts[1], parts[2] if len(parts) == 3 else "")

    def text(self) -> str:
        return f"{self.pid} {self.host} {self.started}".rstrip() + "\n"

    def alive(self) -> bool:
        """Whether this writer is still running.  A writer on another host cannot be seen
        from here: it counts as running (its lock still decides)."""
        if self.host != socket.gethostname():
            return True
        try:
            os.kill(self.pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:  # alive, owned by another user
            pass
        return not self.started or _start_time(self.pid) in ("", self.started)

    def __str__(self) -> str:
        on = "" if self.host == socket.gethostname() else f" on {self.host}"
        return f"process {self.pid}{on}"


class FolderLock:
    """The writer lock of ``folder``: ``STEM.lock`` (the OS lock) and ``STEM.pid`` (its
    holder), see the module docstring.  Use as a context manager, or :meth:`acquire` and
    :meth:`release`; ``what`` names the folder's kind in messages ("run", "sweep")."""

    def __init__(self, folder: str | Path, stem: str, what: str):
        self.folder = Path(folder)
        self.lock_path = self.folder / f"{stem}.lock"
        self.pid_path = self.folder / f"{stem}.pid"
        self.what = what
        self._lock: FileLock | None = None

    def writer(self) -> Writer | None:
        """The live writer recorded beside the lock, or None (none recorded, or it has
        ended).  Takes no lock and waits for nothing."""
        try:
            text = self.pid_path.read_text(encoding="ascii", errors="replace")
        except OSError:  # no writer recorded (none ever, or it finished)
            return None
        writer = Writer.parse(text)
        return writer if writer is not None and writer.alive() else None

    def _in_use(self, writer: Writer | None) -> RvmsimError:
        who = str(writer) if writer is not None else "another process"
        return RvmsimError(f"{self.folder} is in use by {who} (another rvmsim writing this "
                           f"{self.what}); wait for it to finish, or stop it")

    def check_free(self) -> None:
        """Fail early, taking nothing, when a live writer is recorded (the lock itself,
        taken by :meth:`acquire`, is what decides)."""
        writer = self.writer()
        if writer is not None and writer.pid != os.getpid():
            raise self._in_use(writer)

    def acquire(self) -> None:
        """Take the lock (making the folder if needed) and record this process beside it.

        Raises
        ------
        RvmsimError
            One line: another live process holds it (``FOLDER is in use by process N``),
            or ``folder`` is not a folder.
        """
        if self.folder.exists() and not self.folder.is_dir():
            raise RvmsimError(f"{self.folder}: not a folder (a file is there)")
        self.folder.mkdir(parents=True, exist_ok=True)
        lock = FileLock(str(self.lock_path), timeout=0)
        try:
            lock.acquire()
        except Timeout:
            pid_text = self.pid_path.read_text(encoding="ascii", errors="replace") \
                if self.pid_path.is_file() else ""
            raise self._in_use(Writer.parse(pid_text)) from None
        self._lock = lock
        tmp = self.pid_path.with_name(self.pid_path.name + ".tmp")
        try:
            tmp.write_text(Writer.this_process().text(), encoding="ascii")
            os.replace(tmp, self.pid_path)
        except OSError as err:
            lock.release()
            self._lock = None
            if err.filename is None:  # a full disk fails the write, which names no file
                err.filename = str(self.pid_path)
            raise

    def release(self) -> None:
        """Forget this writer and drop the lock (the lock file stays: removing it could let
        two writers lock two different files)."""
        lock = self._lock
        if lock is None:
            return
        self._lock = None
        try:
            self.pid_path.unlink(missing_ok=True)
        finally:
            lock.release()

    def __enter__(self) -> FolderLock:
        self.acquire()
        return self

    def __exit__(self, kind: type[BaseException] | None, err: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.release()
