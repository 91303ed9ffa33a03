"""The ``rvmsim`` command group and the console-script entry point :func:`main`."""

from __future__ import annotations

import importlib
import sys
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Final, NoReturn

import click

from .._procs import stop_on_signals
from ..errors import RvmsimError
from ..render import RenderProcess
from .errors import (CommandStopped, Group, fail, fail_os, interrupted_status, stopped_line,
                     usage_error_line)

__all__ = ["cli", "main", "COMMAND_MODULES"]

#: Every command of ``rvmsim`` and the module that defines it (as an attribute of its
#: name).  A command's module is imported when the command is asked for, so ``rvmsim tune``
#: imports neither the console's web server nor the report's and the sign-off's pages
#: before its first candidate (docs/performance.md, "A command's first candidate").
COMMAND_MODULES: Final[Mapping[str, str]] = MappingProxyType({
    "render": "rvmsim.cli.render", "process": "rvmsim.cli.render",
    "evaluate": "rvmsim.cli.render", "tune": "rvmsim.cli.tune", "batch": "rvmsim.cli.tune",
    "status": "rvmsim.cli.tune", "select": "rvmsim.cli.tune", "report": "rvmsim.cli.report",
    "judge": "rvmsim.cli.report", "validate": "rvmsim.cli.validate",
    "sweep": "rvmsim.cli.sweep", "robustness": "rvmsim.cli.robust",
    "calibrate": "rvmsim.cli.calibrate", "console": "rvmsim.cli.console",
    "eol": "rvmsim.cli.eol", "signoff": "rvmsim.cli.signoff",
    "guidelines": "rvmsim.cli.guidelines"})


class _Commands(Group):
    """The group of :data:`COMMAND_MODULES`: a command's module is imported when it is
    first asked for (to run it, or for the help page)."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMAND_MODULES)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        if cmd_name not in self.commands and cmd_name in COMMAND_MODULES:
            self.add_command(getattr(importlib.import_module(COMMAND_MODULES[cmd_name]),
                                     cmd_name))
        return self.commands.get(cmd_name)


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]},
             invoke_without_command=True, no_args_is_help=False)
@click.version_option(package_name="rvmsim")
@click.pass_context
def cli(ctx: click.Context) -> None:
    """rvmsim: automatic ISP tuning for rear-view-monitoring fisheye cameras."""
    if ctx.invoked_subcommand is None:  # a usage error of one line, not the help page
        names = ", ".join(cli.list_commands(ctx))
        raise click.UsageError(f"missing command (one of {names}; see rvmsim --help)", ctx)


def main(args: Sequence[str] | None = None) -> NoReturn:
    """Run ``rvmsim ARGS`` (``sys.argv[1:]`` when ``args`` is None: the console script and
    ``python -m rvmsim``) and exit with its status.

    A usage error is one line naming the option, exit 2
    (:func:`~rvmsim.cli.errors.usage_error_line`); so is any error a command did not report
    itself (:class:`~rvmsim.cli.errors.Command` reports theirs); Ctrl-C exits 130 and SIGTERM
    the same orderly way with 143 (128 + the signal; a tuning run keeps every finished batch
    and can be resumed, and no worker process outlives the command: :mod:`rvmsim._procs`).
    Every render of the command runs in one render worker
    (:class:`~rvmsim.render.RenderProcess`), ended when the command ends.  Always raises
    :class:`SystemExit`.
    """
    try:
        with stop_on_signals(), RenderProcess():
            code = cli.main(args=None if args is None else list(args),
                            prog_name=None if args is None else "rvmsim", standalone_mode=False)
    except (KeyboardInterrupt, click.exceptions.Abort, CommandStopped) as err:
        # a command's stop comes as CommandStopped; outside one click re-raises a
        # KeyboardInterrupt (and so a SIGTERM's Terminated) as Abort from it
        stop = (err.stop if isinstance(err, CommandStopped)
                else err.__cause__ if isinstance(err, click.exceptions.Abort) else err)
        click.echo(stopped_line(stop), err=True)
        sys.exit(interrupted_status(stop))
    except click.UsageError as err:
        click.echo(usage_error_line(err), err=True)
        sys.exit(err.exit_code)
    except click.ClickException as err:
        click.echo(f"rvmsim: error: {err.format_message()}", err=True)
        sys.exit(err.exit_code)
    except RvmsimError as err:
        fail(err)
    except OSError as err:
        fail_os(err, None)
    sys.exit(code if isinstance(code, int) else 0)
