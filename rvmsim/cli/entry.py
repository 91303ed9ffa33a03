"""The command line's entry point (``rvmsim``, ``python -m rvmsim``).

For a command that renders or starts worker pools (:data:`WORKER_COMMANDS`), the worker
fork server (:func:`rvmsim._procs.start_worker_server`) is started before anything else,
so that it imports the package for its workers (about 2 s) while this process imports the
command line, instead of after it.  So the command group (:mod:`.group`) is imported inside
:func:`main`, as every command imports what it runs, and importing this module (or
:mod:`rvmsim.cli`, whose names load when first used) imports nothing of the commands.
Importing it starts nothing either: the fork server starts in :func:`main` alone.  Measured
on the README's run: 8011 evaluations in 13.9 s, 15.1–15.6 s with the command line
imported before the fork server starts; a quarter-size ``rvmsim render`` 3.1 s against
4.7 s (docs/performance.md).
"""

from __future__ import annotations

import atexit
import sys
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Final

from .._procs import WORKER_PRELOAD, start_worker_server, stop_helpers

__all__ = ["main", "WORKER_COMMANDS", "COMMAND_PRELOAD"]

#: The commands that render (:func:`rvmsim.render.render_faces` runs in a worker) or start
#: worker pools.  Those that read a run's render from the cache (report, signoff, console)
#: are not among them: they render only when the cache lost it.
WORKER_COMMANDS = frozenset({"render", "process", "evaluate", "tune", "batch", "sweep",
                             "robustness", "eol", "validate", "calibrate", "judge"})


#: What the fork server imports for a command's workers where it is not
#: :data:`~rvmsim._procs.WORKER_PRELOAD` (everything any pool runs, and pyrender for
#: renders).  ``tune``'s workers evaluate candidates: from a warm render cache it renders
#: nothing, so it does not wait for pyrender and the station's modules before its first
#: candidate (0.5 s of 2.1 s: tools/bench_first_candidate.py); on a cache miss its render
#: worker imports pyrender itself.
COMMAND_PRELOAD: Final[Mapping[str, tuple[str, ...]]] = MappingProxyType({
    "tune": ("rvmsim.tune",)})


def command_of(args: Sequence[str]) -> str | None:
    """The command named in ``args`` (the command line without the program): the first
    argument that is not an option."""
    return next((a for a in args if not a.startswith("-")), None)


def main() -> None:
    """Run the command line."""
    # the fork server and the resource tracker are waited for as the interpreter exits,
    # so nothing of the command runs once its exit status can be read (one registration
    # however often main runs in a process)
    atexit.unregister(stop_helpers)
    atexit.register(stop_helpers)
    command = command_of(sys.argv[1:])
    if command in WORKER_COMMANDS:
        start_worker_server(preload=COMMAND_PRELOAD.get(command, WORKER_PRELOAD))
    from .group import main as cli_main

    cli_main()
