"""How ``rvmsim`` reports errors: one line on stderr, exit status 2, never a traceback.

Two kinds, each mapped in one place:

- **Usage errors** (unknown option, missing argument, bad value, extra argument, no
  command): ``PROG [COMMAND]: [OPTION: ]what`` (:func:`usage_error_line`), printed by
  :func:`rvmsim.cli.main`::

      rvmsim tune: --budget: 'x' is not a valid integer
      rvmsim render: --out: blocker is a file, not a folder
      rvmsim render: SCENE: required argument not given

- **Errors of the inputs or the system** a command meets while it runs (a bad scene file, a
  run folder that is not one, a folder that cannot be written): ``rvmsim: error: …``.  Every
  command is a :class:`Command`, whose :meth:`Command.invoke` turns
  :class:`~rvmsim.errors.RvmsimError` into :func:`fail` and :class:`OSError` into
  :func:`fail_os` (naming the error's file, else the path in the command's
  :attr:`Command.error_path` parameters).  Commands therefore hold no ``except`` of their own
  for these.
"""

from __future__ import annotations

import signal
import sys
from pathlib import Path
from typing import Any, Callable, NoReturn

import click

from .._procs import Terminated
from ..errors import RvmsimError
from ..storage import os_error_text

__all__ = ["Command", "Group", "usage_error_line", "fail", "fail_os", "interrupted_status",
           "stopped_line", "CommandStopped"]


def fail(err: Exception) -> NoReturn:
    """Print ``err`` as the one line ``rvmsim: error: …`` on stderr and exit with status 2."""
    click.echo(f"rvmsim: error: {err}", err=True)
    sys.exit(2)


def interrupted_status(stop: BaseException | None) -> int:
    """The exit status of a command stopped by ``stop``: 128 + the signal's number, so 143
    for SIGTERM (:class:`~rvmsim._procs.Terminated`) and 130 for Ctrl-C (SIGINT, anything
    else)."""
    if isinstance(stop, Terminated):
        return 128 + stop.signal_number
    return 128 + int(signal.SIGINT)


def stopped_line(stop: BaseException | None) -> str:
    """What a stopped command says on stderr: ``rvmsim: terminated (SIGTERM)`` or
    ``rvmsim: interrupted``."""
    return ("rvmsim: terminated (SIGTERM)" if isinstance(stop, Terminated)
            else "rvmsim: interrupted")


def fail_os(err: OSError, where: Path | None) -> NoReturn:
    """:func:`fail` for an OS error, naming its file (or ``where``): ``FILE: the disk is
    full (…)`` for a full disk (:func:`~rvmsim.storage.os_error_text`)."""
    name = getattr(err, "filename", None) or where
    words = os_error_text(err)
    fail(RvmsimError(f"{name}: {words}" if name else words))


def _parse_in(ctx: click.Context, parse: Callable[[click.Context, list[str]], list[str]],
              args: list[str]) -> list[str]:
    """``parse(ctx, args)``, giving a usage error the context click's parser leaves out (a
    missing option value), so that its line names the command."""
    try:
        return list(parse(ctx, args))
    except click.UsageError as err:
        if err.ctx is None:
            err.ctx = ctx
        raise


class Command(click.Command):
    """A command of ``rvmsim``: its usage errors know the command (see
    :func:`usage_error_line`), and the errors it meets while running are one line, exit 2.

    Parameters
    ----------
    error_path : tuple of str
        The parameters (the first one set) naming the path an :class:`OSError` without a
        file name of its own is reported against (``("out",)``: the output folder); empty:
        none.
    """

    def __init__(self, *args: Any, error_path: tuple[str, ...] = (), **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.error_path = error_path

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        return _parse_in(ctx, super().parse_args, args)

    def invoke(self, ctx: click.Context) -> Any:
        """Run the command; :class:`~rvmsim.errors.RvmsimError` and :class:`OSError` become
        one line on stderr and exit status 2 (:func:`fail`, :func:`fail_os`)."""
        try:
            return super().invoke(ctx)
        except RvmsimError as err:
            fail(err)
        except OSError as err:
            where = next((ctx.params[n] for n in self.error_path if ctx.params.get(n)), None)
            fail_os(err, where)


class CommandStopped(Exception):
    """A command stopped by Ctrl-C or SIGTERM (``stop``: the KeyboardInterrupt or
    :class:`~rvmsim._procs.Terminated`), carried past click's ``main``, which would print an
    empty line on stderr for it before the command's one line."""

    def __init__(self, stop: KeyboardInterrupt):
        super().__init__(str(stop))
        self.stop = stop


class Group(click.Group):
    """The ``rvmsim`` group: its usage errors know it, and its commands are :class:`Command`."""

    command_class = Command

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        return _parse_in(ctx, super().parse_args, args)

    def invoke(self, ctx: click.Context) -> Any:
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt as stop:
            raise CommandStopped(stop) from None


def _param_name(param: click.Parameter) -> str:
    """``--long-option`` (the longest of its names) or ``ARGUMENT``."""
    if isinstance(param, click.Option):
        return max(param.opts, key=len)
    return param.human_readable_name


def _message(err: click.UsageError) -> str:
    """What went wrong, starting with the option or argument at fault when click knows it."""
    if isinstance(err, click.MissingParameter) and err.param is not None:
        return f"{_param_name(err.param)}: required {err.param.param_type_name} not given"
    if isinstance(err, click.BadParameter):
        name = _param_name(err.param) if err.param is not None else err.param_hint
        if isinstance(name, (list, tuple)):
            name = " / ".join(name)
        return f"{name}: {err.message}" if name else err.message
    if isinstance(err, click.NoSuchOption):
        hint = " or ".join(sorted(err.possibilities or ()))
        return f"{err.option_name}: no such option" + (f" (did you mean {hint}?)" if hint else "")
    return err.format_message()  # BadOptionUsage, extra arguments, no such command: named


def usage_error_line(err: click.UsageError, prog: str = "rvmsim") -> str:
    """The one line rvmsim prints for a usage error: ``PROG [COMMAND]: [OPTION: ]what``."""
    ctx = err.ctx
    where = prog if ctx is None or ctx.parent is None else f"{prog} {ctx.info_name}"
    text = " ".join(_message(err).split()).rstrip(".")
    if text[:2].istitle():  # click's own sentences ("Got unexpected extra argument (b)")
        text = text[0].lower() + text[1:]
    return f"{where}: {text}"
