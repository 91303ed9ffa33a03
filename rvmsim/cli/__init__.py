"""Command-line interface: a thin shell over the library, one module per command group.

Every command parses its options (:mod:`.params`: option types that refuse what the
pipeline cannot use), calls the library and prints; user errors (bad scene files,
unreadable images, …) are one line on stderr and exit status 2, never a traceback
(:mod:`.errors`: one place maps them for every command).

Modules: :mod:`.entry` (the ``rvmsim`` script), :mod:`.group` (the ``rvmsim`` group and
:func:`main`; its names are this package's, imported when first used, so that importing
the package, as the script does, loads no command), :mod:`.render` (render,
process, evaluate), :mod:`.tune` (tune, status, select, batch), :mod:`.report`,
:mod:`.validate`, :mod:`.sweep`, :mod:`.robust` (robustness), :mod:`.calibrate`,
:mod:`.console`, :mod:`.eol`, :mod:`.signoff`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .group import COMMAND_MODULES, cli, main

__all__ = ["cli", "main", "COMMAND_MODULES"]


def __getattr__(name: str) -> Any:
    """:data:`__all__`'s names, from :mod:`.group` when first asked for."""
    if name in __all__:
        from . import group

        return getattr(group, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
