"""Where a page's numbers come from: the tool's version and commit, the date, the machine,
and the files read, each with its SHA-256.

Shared by the run report, the robustness page and the sign-off page
(:mod:`rvmsim.report.signoff`).  The commit is that of the checkout rvmsim's own source
files are in (``git rev-parse HEAD`` there, "+ uncommitted changes" when ``git status`` lists
any); an installed copy that is no git checkout says so.
"""

from __future__ import annotations

import hashlib
import os
import platform
import subprocess
from dataclasses import dataclass
from datetime import datetime, timezone
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from .._version import __version__
from ..errors import RvmsimError
from ..scene import load_scene, mesh_parts
from .page import escape, path_html, sha_html

__all__ = ["Provenance", "provenance", "sha256_file", "FileRecord", "file_record",
           "provenance_html", "files_table", "scene_records", "NOT_A_CHECKOUT"]

#: What the commit field says when rvmsim's source is not in a git checkout.
NOT_A_CHECKOUT = "not a git checkout"

#: Seconds a ``git`` call may take (a slow network file system, a lock).
_GIT_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class Provenance:
    """The tool and the machine a page was made with.

    ``commit`` is the 40-hex commit of rvmsim's source checkout, or :data:`NOT_A_CHECKOUT`;
    ``dirty`` whether that checkout has uncommitted changes (None: no checkout);
    ``date`` ISO 8601 in UTC, to the second."""

    version: str
    commit: str
    dirty: bool | None
    source: str
    date: str
    machine: str
    cpu_count: int
    python: str

    @property
    def commit_text(self) -> str:
        """The commit as a page shows it."""
        if self.dirty is None:
            return self.commit
        return self.commit + (" + uncommitted changes" if self.dirty else "")

    def as_dict(self) -> dict[str, object]:
        """JSON-ready."""
        return {"version": self.version, "commit": self.commit, "dirty": self.dirty,
                "source": self.source, "date": self.date, "machine": self.machine,
                "cpu_count": self.cpu_count, "python": self.python}


def _version() -> str:
    """rvmsim's version: the installed package's metadata, else ``rvmsim.__version__``."""
    try:
        installed = version("rvmsim")
    except PackageNotFoundError:
        return __version__
    return __version__ if installed == __version__ else f"{__version__} (installed {installed})"


def _git(folder: Path, *args: str) -> str | None:
    """``git -C folder ARGS``'s output, None when git fails or is missing."""
    try:
        done = subprocess.run(["git", "-C", str(folder), *args], capture_output=True, text=True,
                              timeout=_GIT_TIMEOUT_S, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return done.stdout if done.returncode == 0 else None


def _commit(source: Path) -> tuple[str, bool | None]:
    """The checkout's HEAD commit and whether it has uncommitted changes."""
    head = _git(source, "rev-parse", "HEAD")
    if head is None or not head.strip():
        return NOT_A_CHECKOUT, None
    status = _git(source, "status", "--porcelain", "--untracked-files=no")
    return head.strip(), None if status is None else bool(status.strip())


def provenance() -> Provenance:
    """The tool (version, commit of its source), now (UTC) and this machine."""
    source = Path(__file__).resolve().parents[1]
    commit, dirty = _commit(source.parent)
    now = datetime.now(timezone.utc).replace(microsecond=0).isoformat()
    machine = f"{platform.node() or 'unknown host'}: {platform.platform()}, " \
              f"{platform.machine() or 'unknown CPU'}"
    return Provenance(_version(), commit, dirty, str(source), now, machine,
                      os.cpu_count() or 1, platform.python_version())


def sha256_file(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, 64 hex digits (read in 1 MiB blocks)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        while block := f.read(1 << 20):
            h.update(block)
    return h.hexdigest()


@dataclass(frozen=True)
class FileRecord:
    """One input file: what it is (``role``), where, and its SHA-256 (None: not readable
    now, ``note`` says why; a bundled criteria set has no file)."""

    role: str
    path: str
    sha256: str | None
    note: str = ""

    def as_dict(self) -> dict[str, object]:
        return {"role": self.role, "path": self.path, "sha256": self.sha256, "note": self.note}


def file_record(role: str, path: str | Path) -> FileRecord:
    """:class:`FileRecord` of ``path`` (its absolute path and hash, or why there is none)."""
    p = Path(path).expanduser()
    try:
        return FileRecord(role, str(p.resolve()), sha256_file(p))
    except OSError as err:
        return FileRecord(role, str(p), None, f"not readable now: {err.strerror or err}")


def provenance_html(p: Provenance) -> str:
    """A small table: version, commit, date, machine."""
    rows = (("rvmsim version", p.version), ("commit", p.commit_text),
            ("source", p.source), ("date (UTC)", p.date),
            ("machine", f"{p.machine}; {p.cpu_count} CPUs; Python {p.python}"))
    return ('<table class="provenance">' + "".join(
        f"<tr><th>{escape(a)}</th><td><code>{escape(b)}</code></td></tr>" for a, b in rows)
        + "</table>")


def files_table(records: list[FileRecord]) -> str:
    """The files with their SHA-256 as an HTML table."""
    def note(r: FileRecord) -> str:
        return "" if not r.note else f' <span class="muted">{escape(r.note)}</span>'

    rows = "".join(
        f'<tr class="{"fail" if r.note.startswith("not readable") else ""}">'
        f"<td>{escape(r.role)}</td>"
        f"<td>{path_html(r.path)}<br>{sha_html(r.sha256)}{note(r)}</td></tr>"
        for r in records)
    return f"<table><tr><th>file</th><th>path, then its SHA-256</th></tr>{rows}</table>"


def scene_records(scene_file: str | Path, role: str = "scene") -> list[FileRecord]:
    """The scene file and every mesh file it names (resolved as the scene resolves them),
    each with its SHA-256.  A scene that no longer loads gives its own record only."""

    records = [file_record(role, scene_file)]
    try:
        scene = load_scene(scene_file)
    except (RvmsimError, OSError):  # the record says the file is gone or changed
        return records
    records += [file_record(f"mesh ({key})", scene.resolve_path(part.mesh))
                for key, part in mesh_parts(scene)]
    return records
