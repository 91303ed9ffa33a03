"""The bad-input harness (issue #14): run one ``rvmsim`` command in a child process under a
memory cap, and check that it failed cleanly.

A clean failure is: exit status 2, exactly one line on stderr, that line naming the file and
the key (or the option) at fault, no traceback, and every stored run or sweep folder the case
was given byte-identical afterwards.  Cases are data (:class:`Case`), so every input kind's
module lists its cases and hands them to :func:`check_case`.
"""

from __future__ import annotations

import hashlib
import os
import resource
import subprocess
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

#: Address-space cap of each case's child process: a blow-up (a 74 GiB allocation, a
#: billion-laughs expansion) fails the case with MemoryError, not the machine.  Rendering
#: a small scene needs well under 1 GiB.
MEMORY_CAP_BYTES = 2 * 1024**3
#: Wall-time limit of one case (s): a hang fails the case.
TIMEOUT_S = 120.0

REPO = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Case:
    """One bad input.

    ``args`` are ``rvmsim``'s arguments (paths inside the case folder may be given relative
    to it: the child runs there).  ``setup(folder)`` writes the bad files into the case
    folder before the run.  ``names`` must all appear in the one stderr line (file name,
    key or option).  ``keep`` are folders (relative to the case folder) whose bytes must not
    change.
    """

    id: str
    args: tuple[str, ...]
    names: tuple[str, ...]
    setup: Callable[[Path], None] | None = None
    keep: tuple[str, ...] = ()
    env: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Outcome:
    code: int
    stdout: str
    stderr: str


def _cap_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP_BYTES, MEMORY_CAP_BYTES))


def run_rvmsim(args: Sequence[str], *, cwd: Path, env: dict[str, str] | None = None,
               timeout_s: float = TIMEOUT_S) -> Outcome:
    """``python -m rvmsim ARGS`` in ``cwd`` under :data:`MEMORY_CAP_BYTES`."""
    child_env = {**os.environ, "PYOPENGL_PLATFORM": "egl", "PYTHONPATH": str(REPO),
                 "COLUMNS": "200", **(env or {})}
    res = subprocess.run([sys.executable, "-m", "rvmsim", *args], cwd=cwd, env=child_env,
                         capture_output=True, text=True, timeout=timeout_s, stdin=subprocess.DEVNULL,
                         preexec_fn=_cap_memory)
    return Outcome(res.returncode, res.stdout, res.stderr)


def folder_digest(folder: Path) -> dict[str, str]:
    """sha256 of every file below ``folder`` (relative path → hex digest)."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def assert_clean_failure(out: Outcome, names: Sequence[str]) -> None:
    """Exit 2, one stderr line naming every one of ``names``, no traceback."""
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert "Traceback" not in out.stderr, out.stderr[-3000:]
    assert out.code == 2, f"exit {out.code}, stderr: {out.stderr[-2000:]}"
    assert len(lines) == 1, f"{len(lines)} stderr lines: {out.stderr[-2000:]}"
    for name in names:
        assert name in lines[0], f"{name!r} not named in: {lines[0]}"


def check_case(case: Case, folder: Path) -> Outcome:
    """Set the case up in ``folder``, run it, and assert a clean failure that changed none of
    ``case.keep``."""
    if case.setup is not None:
        case.setup(folder)
    before = {k: folder_digest(folder / k) for k in case.keep}
    out = run_rvmsim(case.args, cwd=folder, env=case.env)
    assert_clean_failure(out, case.names)
    for k in case.keep:
        assert folder_digest(folder / k) == before[k], f"{k} changed"
    return out
