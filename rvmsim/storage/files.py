"""Writing output files whole or not at all, text that any file name fits in, and what a
full disk is called.

- :func:`staged_folder`: a command that writes an output folder (``signoff``,
  ``robustness``, ``validate``, ``calibrate``) writes everything into a hidden folder beside
  it, ``.NAME.rvmsim-PID-….tmp``; only when all of it is written are the files moved into
  the output folder (each by one rename, replacing the file of its name; other files in the
  folder are left).  An error (a full disk, a PDF printer that fails) removes the hidden
  folder and leaves the output folder as it was.  A hidden folder left by a killed command
  is removed by the next command writing that output folder.
- :class:`StagedFiles`: the same for single files written into a folder that must stay
  where it is (``report`` into a run folder): each is written under a temporary name beside
  its place and renamed into it when all are written.
- :func:`write_text`: text as UTF-8 where a name that is not valid UTF-8 (Python's surrogate
  escapes, ``'car\\udcff.png'`` from the bytes ``b'car\\xff.png'``) is written readably, as
  ``car\\xff.png``; JSON keeps such a name exactly (``json.dumps`` writes ``"\\udcff"``,
  which reads back to the same name).
- :func:`os_error_text`: an :class:`OSError`'s words; "the disk is full (…)" for ``ENOSPC``
  and ``EFBIG`` (a file over the size limit of the process or file system).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import uuid
from collections.abc import Iterator
from pathlib import Path

from ..errors import RvmsimError
from .lock import Writer

__all__ = ["staged_folder", "StagedFiles", "write_text", "readable_text", "os_error_text",
           "write_problem", "disk_is_full", "DISK_FULL_ERRNOS", "LOW_DISK_BYTES"]

#: The errors of a write that mean there is no room: no space left on the device, a file
#: over the size limit (of the process, ``ulimit -f``, or of the file system).
DISK_FULL_ERRNOS = frozenset({errno.ENOSPC, errno.EFBIG, errno.EDQUOT})
#: Free bytes under which a disk counts as full when SQLite reports a "disk I/O error".
LOW_DISK_BYTES = 16 * 1024**2

_STAGE_TAG = ".rvmsim-"


def readable_text(text: str) -> str:
    """``text`` with each surrogate escape of a name that is not valid UTF-8 shown as its
    byte, ``\\xff`` (``'Jos\\udce9'`` → ``'Jos\\\\xe9'``); any other text is returned as it
    is.  The result encodes as UTF-8."""
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        raw = text.encode("utf-8", "surrogateescape" if _only_escapes(text) else "surrogatepass")
        return raw.decode("utf-8", "backslashreplace")


def _only_escapes(text: str) -> bool:
    """Whether every surrogate in ``text`` is a surrogate escape (U+DC80..U+DCFF)."""
    return all(not 0xD800 <= ord(c) <= 0xDFFF or 0xDC80 <= ord(c) <= 0xDCFF for c in text)


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` as UTF-8 (:func:`readable_text`: a name that is not valid
    UTF-8 is written as ``\\xff``)."""
    path = Path(path)
    try:
        path.write_bytes(readable_text(text).encode("utf-8"))
    except OSError as err:
        if err.filename is None:  # a failed write (a full disk) names no file: this one
            err.filename = str(path)
        raise
    return path


def disk_is_full(path: str | Path) -> bool:
    """Whether the file system holding ``path`` (or its nearest existing parent) has less
    than :data:`LOW_DISK_BYTES` free (False where that cannot be told)."""
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    try:
        return shutil.disk_usage(p).free < LOW_DISK_BYTES
    except OSError:
        return False


def os_error_text(err: OSError) -> str:
    """What went wrong, in words: "the disk is full (No space left on device)" for
    :data:`DISK_FULL_ERRNOS`, else the error's own words."""
    words = err.strerror or str(err)
    if err.errno in DISK_FULL_ERRNOS:
        return f"the disk is full ({words})"
    return words


def write_problem(err: OSError, doing: str = "cannot write") -> str:
    """What a failed write says after the file's name: "the disk is full (…)" for
    :data:`DISK_FULL_ERRNOS`, else "``doing`` (the error's words)"."""
    if err.errno in DISK_FULL_ERRNOS:
        return os_error_text(err)
    return f"{doing} ({err.strerror or err})"


def _stage_owner(name: str) -> Writer | None:
    """The process that made the staging folder ``name`` (``.OUT.rvmsim-PID-START-HEX.tmp``),
    None if the name is not one."""
    tail = name.rsplit(_STAGE_TAG, 1)[-1].removesuffix(".tmp").split("-")
    if len(tail) != 3 or not tail[0].isdigit():
        return None
    return Writer(int(tail[0]), Writer.this_process().host, tail[1])


def _remove_stale_stages(out: Path) -> None:
    """Remove the staging folders of ``out`` that a command which has ended left."""
    prefix = f".{out.name}{_STAGE_TAG}"
    try:
        entries = list(out.parent.iterdir())
    except OSError:
        return
    for entry in entries:
        if entry.name.startswith(prefix) and entry.name.endswith(".tmp"):
            owner = _stage_owner(entry.name)
            if owner is not None and not owner.alive():
                shutil.rmtree(entry, ignore_errors=True)


def _move_in(stage: Path, out: Path) -> None:
    """Move every entry of ``stage`` into ``out`` (created when missing), each replacing
    the entry of its name; then remove ``stage``."""
    if not out.exists():
        os.rename(stage, out)  # a new folder: in whole, at once
        return
    for entry in sorted(stage.iterdir()):
        target = out / entry.name
        if target.is_dir() and not target.is_symlink():
            # a folder of the earlier output: swapped out, then removed
            old = stage / f".{entry.name}.old-{uuid.uuid4().hex[:8]}"
            os.rename(target, old)
            os.rename(entry, target)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(entry, target)
    shutil.rmtree(stage, ignore_errors=True)


@contextlib.contextmanager
def staged_folder(out: str | Path) -> Iterator[Path]:
    """Write the output folder ``out`` whole or not at all (see the module docstring).

    The ``with`` block writes into the folder yielded (hidden, beside ``out``); when it ends
    without an error its entries are moved into ``out`` (created when missing, with its
    parents), each replacing the entry of its name.  On any error the staging folder is
    removed, ``out`` is left as it was, and the error is raised again, an :class:`OSError`
    as a one-line :class:`~rvmsim.errors.RvmsimError` naming its file ("the disk is full"
    for a full disk).  Paths written into the files must name ``out``, not the staging
    folder.

    Raises
    ------
    RvmsimError
        ``out`` is a file, it or the staging folder cannot be made, a write in the block
        failed, or the results cannot be moved in.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise RvmsimError(f"{out}: is a file, not a folder")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RvmsimError(f"{out.parent}: "
                          f"{write_problem(err, 'cannot create output folder')}") from None
    _remove_stale_stages(out)
    me = Writer.this_process()
    stage = out.parent / f".{out.name}{_STAGE_TAG}{me.pid}-{me.started or 0}-" \
                         f"{uuid.uuid4().hex[:8]}.tmp"
    try:
        stage.mkdir()
    except OSError as err:
        raise RvmsimError(f"{out.parent}: {write_problem(err, 'cannot write here')}") from None
    try:
        try:
            yield stage
        except OSError as err:
            name = getattr(err, "filename", None)
            shown = out / Path(name).relative_to(stage) if name and _inside(name, stage) \
                else name or out
            raise RvmsimError(f"{shown}: {write_problem(err)}") from None
        except RvmsimError as err:
            if type(err) is RvmsimError and str(stage) in str(err):  # name `out`'s file
                raise RvmsimError(str(err).replace(str(stage), str(out))) from None
            raise
        try:
            _move_in(stage, out)
        except OSError as err:
            raise RvmsimError(f"{out}: "
                              f"{write_problem(err, 'cannot move the results in')}") from None
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _inside(name: str | bytes | os.PathLike[str], folder: Path) -> bool:
    try:
        Path(os.fsdecode(name)).relative_to(folder)
        return True
    except ValueError:
        return False


class StagedFiles:
    """Files written into ``folder`` whole or not at all: :meth:`path` gives the temporary
    name to write a file under (hidden, beside its place), :meth:`commit` renames every one
    into place, :meth:`discard` removes them.  As a context manager: committed when the
    block ends without an error, discarded otherwise (an :class:`OSError` of the block
    raised again as a one-line :class:`~rvmsim.errors.RvmsimError` naming its file)."""

    def __init__(self) -> None:
        self._files: dict[Path, Path] = {}

    def path(self, target: str | Path) -> Path:
        """The temporary file to write ``target``'s content into (its folder is created)."""
        target = Path(target)
        tmp = target.with_name(f".{target.name}{_STAGE_TAG}{os.getpid()}-"
                               f"{uuid.uuid4().hex[:8]}.tmp")
        target.parent.mkdir(parents=True, exist_ok=True)
        self._files[target] = tmp
        return tmp

    def drop(self, target: str | Path) -> None:
        """Remove ``target``'s temporary file (a write that failed): it is not committed."""
        tmp = self._files.pop(Path(target), None)
        if tmp is not None:
            with contextlib.suppress(OSError):
                tmp.unlink()

    def commit(self) -> list[Path]:
        """Rename every written file into its place; returns the places."""
        for target, tmp in self._files.items():
            os.replace(tmp, target)
        done = list(self._files)
        self._files.clear()
        return done

    def discard(self) -> None:
        """Remove every temporary file."""
        for tmp in self._files.values():
            with contextlib.suppress(OSError):
                tmp.unlink()
        self._files.clear()

    def __enter__(self) -> StagedFiles:
        return self

    def __exit__(self, kind: type[BaseException] | None, err: BaseException | None,
                 tb: object) -> None:
        if err is None:
            try:
                self.commit()
                return
            except OSError as failed:
                err = failed
        targets = {tmp: target for target, tmp in self._files.items()}
        self.discard()
        if isinstance(err, OSError):
            name = getattr(err, "filename", None)
            shown = targets.get(Path(os.fsdecode(name)), name) if name else None
            raise RvmsimError(f"{shown}: {write_problem(err)}" if shown
                              else write_problem(err)) from None
