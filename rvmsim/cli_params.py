"""The option types of ``rvmsim``'s commands, and the one line a usage error prints.

Click accepts values the pipeline cannot use (``--max-time nan``, an output folder that is a
file, a scheduler address without a port); the parameter types here refuse them while the
command line is parsed, so the error names the option before anything is read or written.

A usage error (unknown option, missing argument, bad value, extra argument, no command) is
one line on stderr, exit status 2::

    rvmsim tune: --budget: 'x' is not a valid integer
    rvmsim render: --out: blocker is a file, not a folder
    rvmsim render: SCENE: required argument not given
"""

from __future__ import annotations

import math
import os
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from .errors import RvmsimError

if TYPE_CHECKING:
    from .isp import IspParams, OutputSpec
    from .scene import Scene

__all__ = ["Command", "FiniteFloat", "Group", "Integer", "OutputFile", "OutputFolder",
           "SchedulerAddress", "SEED", "check_scale", "usage_error_line", "fail", "fail_os",
           "load_isp"]


class Integer(click.IntRange):
    """An integer, optionally within ``[min, max]`` (click's ``IntRange``, named "integer" in
    messages and help)."""

    name = "integer"


class FiniteFloat(click.FloatRange):
    """A finite real number, optionally within a range (click's ``FloatRange`` lets ``nan``
    through every bound, and ``inf`` through an open upper one)."""

    name = "number"

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


#: ``--seed``: numpy's seed sequences take any non-negative integer; 32 bits is what every
#: strategy can use.
SEED = Integer(0, 2**32 - 1)


def _existing_ancestor(path: Path) -> Path:
    """``path`` itself or its nearest parent that exists (``.`` or ``/`` at the latest)."""
    for candidate in (path, *path.parents):
        if os.path.lexists(candidate):
            return candidate
    return Path(path.anchor or ".")


class _Writable(click.Path):
    """A path to create or write: its nearest existing part must be a writable folder."""

    def __init__(self) -> None:
        super().__init__(path_type=Path)

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        path = Path(os.fsdecode(super().convert(value, param, ctx)))
        folder = _existing_ancestor(self.folder_of(path, param, ctx))
        if not folder.is_dir():
            self.fail(f"{path}: {folder} is a file, not a folder", param, ctx)
        if not os.access(folder, os.W_OK | os.X_OK):
            self.fail(f"{path}: folder {folder} is not writable", param, ctx)
        return path

    def folder_of(self, path: Path, param: click.Parameter | None,
                  ctx: click.Context | None) -> Path:
        """The folder the command writes into (after checking ``path`` itself)."""
        raise NotImplementedError


class OutputFolder(_Writable):
    """A folder to write into: an existing folder, or a path whose existing part is a
    writable folder (not a file)."""

    name = "folder"

    def folder_of(self, path: Path, param: click.Parameter | None,
                  ctx: click.Context | None) -> Path:
        if os.path.lexists(path) and not path.is_dir():
            self.fail(f"{path} is a file, not a folder", param, ctx)
        return path


class OutputFile(_Writable):
    """A file to write: not an existing folder, in a writable folder."""

    name = "file"

    def folder_of(self, path: Path, param: click.Parameter | None,
                  ctx: click.Context | None) -> Path:
        if path.is_dir():
            self.fail(f"{path} is a folder, not a file", param, ctx)
        return path.parent


class SchedulerAddress(click.ParamType):
    """A Dask scheduler address, ``[PROTOCOL://]HOST:PORT`` (``tcp://10.0.0.5:8786``,
    ``tls://[::1]:8786``)."""

    name = "address"
    _FORM = re.compile(r"(?:[a-z][a-z0-9+.-]*://)?(\[[0-9A-Fa-f:.]+\]|[^\s:/\[\]]+):(\d{1,5})")

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        match = self._FORM.fullmatch(str(value))
        if match is None or not 0 < int(match.group(2)) < 65536:
            self.fail(f"{value!r} is not a scheduler address (tcp://HOST:PORT)", param, ctx)
        return str(value)


def _parse_in(ctx: click.Context, parse: Any, args: list[str]) -> list[str]:
    """``parse(ctx, args)``, giving a usage error the context click's parser leaves out (a
    missing option value), so that its line names the command."""
    try:
        return list(parse(ctx, args))
    except click.UsageError as err:
        if err.ctx is None:
            err.ctx = ctx
        raise


class Command(click.Command):
    """A command whose every usage error knows the command (see :func:`usage_error_line`)."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        return _parse_in(ctx, super().parse_args, args)


class Group(click.Group):
    """The ``rvmsim`` group: its commands are :class:`Command`."""

    command_class = Command

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        return _parse_in(ctx, super().parse_args, args)


def check_scale(scene: Scene, params: IspParams, scale: float) -> None:
    """``--scale`` of process and evaluate must keep the ISP parameters in range (RAD and the
    shifts follow it, as in :func:`rvmsim.pipeline.render_rvm`), else a usage error of
    ``--scale``."""
    if scale != 1.0:
        try:
            params.for_input_scale(scene.fisheye_camera().scaled(scale).width
                                   / scene.camera.image_size[0])
        except ValueError as err:  # IspParams' own range check
            raise click.BadParameter(f"{scale:g} scales the ISP parameters out of range ({err})",
                                     click.get_current_context(), param_hint="--scale") from err


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


def fail(err: Exception) -> None:
    """Print ``err`` as the one line ``rvmsim: error: …`` on stderr and exit with status 2."""
    click.echo(f"rvmsim: error: {err}", err=True)
    sys.exit(2)


def fail_os(err: OSError, where: Path | None) -> None:
    """:func:`fail` for an OS error, naming its file (or ``where``)."""
    name = getattr(err, "filename", None) or where
    fail(RvmsimError(f"{name}: {err.strerror or err}" if name else str(err.strerror or err)))


def load_isp(params_file: Path | None) -> tuple[IspParams, OutputSpec]:
    """The params file's ISP parameters and output (the paper's defaults without one)."""
    from .isp import IspParams, OutputSpec, load_params

    return load_params(params_file) if params_file else (IspParams(), OutputSpec())
