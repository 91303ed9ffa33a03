"""The bad-input harness (issue #14): run one ``rvmsim`` command and check that it failed
cleanly.

A clean failure is: exit status 2, exactly one line on stderr, that line naming the file and
the key (or the option) at fault, no traceback, and every stored run or sweep folder the case
was given byte-identical afterwards.  Cases are data (:class:`Case`), so every input kind's
module lists its cases and hands them to :func:`check_case`.

A case runs in this process (:func:`tests.cli_runner.run_in_process`: the CLI's entry point,
the process state a child would have, the same exit status and streams) unless its
:attr:`Case.isolate` gives a reason to run it as a child process of its own under
:data:`MEMORY_CAP_BYTES` and :data:`TIMEOUT_S`: a regression of the guard it tests would
allocate past the cap or run for hours (a bomb), or the command starts something that
outlives it (a Dask client, a server).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ..cli_runner import MEMORY_CAP_BYTES, REPO, Outcome, run_in_child, run_in_process

__all__ = ["Case", "Outcome", "MEMORY_CAP_BYTES", "TIMEOUT_S", "REPO", "MEMORY", "ENDLESS",
           "DASK", "SERVER", "run_case", "folder_digest", "assert_clean_failure", "check_case"]

#: Wall-time limit of one isolated case (s): a hang fails the case.
TIMEOUT_S = 120.0

#: :attr:`Case.isolate` reasons.
MEMORY = "a regression of the guard would allocate past the memory cap"
ENDLESS = "a regression of the guard would run for hours or forever: needs the timeout"
DASK = "connects a Dask client, whose threads outlive the command"
SERVER = "a regression would serve until killed, under uvicorn's signal handlers"


@dataclass(frozen=True)
class Case:
    """One bad input.

    ``args`` are ``rvmsim``'s arguments (paths inside the case folder may be given relative
    to it: the command runs there).  ``setup(folder)`` writes the bad files into the case
    folder before the run.  ``names`` must all appear in the one stderr line (file name,
    key or option).  ``keep`` are the stored folders the command is given (relative to the
    case folder, named in ``args``: a folder the command does not read is not kept) whose
    bytes must not change; the case folder holds the finished run only when the case names
    it (:meth:`gives`).  ``env``: environment variables of the run.  ``isolate``: why the case needs a
    child process of its own (one of :data:`MEMORY`, :data:`ENDLESS`, :data:`DASK`,
    :data:`SERVER`); empty: it runs in this process.
    """

    id: str
    args: tuple[str, ...]
    names: tuple[str, ...]
    setup: Callable[[Path], None] | None = None
    keep: tuple[str, ...] = ()
    env: dict[str, str] = field(default_factory=dict)
    isolate: str = ""

    def gives(self, folder: str) -> bool:
        """Whether the command is given ``folder`` or a path inside it."""
        return any(a == folder or str(a).startswith(folder + "/") for a in self.args)


def run_case(case: Case, folder: Path) -> Outcome:
    """Run ``case``'s command in ``folder``: in a capped child when it is isolated, else in
    this process."""
    if case.isolate:
        return run_in_child(case.args, cwd=folder, env=case.env, timeout_s=TIMEOUT_S,
                            memory_cap=MEMORY_CAP_BYTES)
    return run_in_process(case.args, cwd=folder, env=case.env)


def folder_digest(folder: Path) -> dict[str, str]:
    """sha256 of every file below ``folder`` (relative path → hex digest)."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def assert_clean_failure(out: Outcome, names: Sequence[str]) -> None:
    """Exit 2, one stderr line naming every one of ``names``, no traceback."""
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert "Traceback" not in out.stderr, "a traceback: " + out.stderr[-3000:]
    assert out.code == 2, f"exit {out.code}, stderr: {out.stderr[-2000:]}"
    assert len(lines) == 1, f"{len(lines)} stderr lines: {out.stderr[-2000:]}"
    for name in names:
        assert name in lines[0], f"{name!r} not named in: {lines[0]}"


def check_case(case: Case, folder: Path) -> Outcome:
    """Set the case up in ``folder``, run it, and assert a clean failure that changed none of
    ``case.keep``."""
    unread = [k for k in case.keep if not case.gives(k)]
    assert not unread, f"keep= names folders the command is not given: {unread}"
    if case.setup is not None:
        case.setup(folder)
    before = {k: folder_digest(folder / k) for k in case.keep}
    out = run_case(case, folder)
    assert_clean_failure(out, case.names)
    for k in case.keep:
        assert folder_digest(folder / k) == before[k], f"{k} changed"
    return out
