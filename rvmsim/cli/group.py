"""The ``rvmsim`` command group and the console-script entry point :func:`main`."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import NoReturn

import click

from .._procs import stop_on_signals
from ..errors import RvmsimError
from ..render import RenderProcess
from .calibrate import calibrate
from .console import console
from .eol import eol
from .errors import Group, fail, fail_os, interrupted_status, stopped_line, usage_error_line
from .render import evaluate, process, render
from .report import judge, report
from .robust import robustness
from .signoff import signoff
from .sweep import sweep
from .tune import batch, select, status, tune
from .validate import validate

__all__ = ["cli", "main", "COMMANDS"]

#: Every command of ``rvmsim``, in the order the modules list them.
COMMANDS: tuple[click.Command, ...] = (render, process, evaluate, tune, batch, status, select,
                                       report, judge, validate, sweep, robustness, calibrate,
                                       console, eol, signoff)


@click.group(cls=Group, context_settings={"help_option_names": ["-h", "--help"]},
             invoke_without_command=True, no_args_is_help=False)
@click.version_option(package_name="rvmsim")
@click.pass_context
def cli(ctx: click.Context) -> None:
    """rvmsim: automatic ISP tuning for rear-view-monitoring fisheye cameras."""
    if ctx.invoked_subcommand is None:  # a usage error of one line, not the help page
        names = ", ".join(cli.list_commands(ctx))
        raise click.UsageError(f"missing command (one of {names}; see rvmsim --help)", ctx)


for _command in COMMANDS:
    cli.add_command(_command)


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
    except (KeyboardInterrupt, click.exceptions.Abort) as err:
        # click re-raises a KeyboardInterrupt (and so a SIGTERM's Terminated) as Abort from it
        stop = err.__cause__ if isinstance(err, click.exceptions.Abort) else err
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
