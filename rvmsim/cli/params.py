"""The option types of ``rvmsim``'s commands, and the defaults and checks of their values.

Click accepts values the pipeline cannot use (``--max-time nan``, an output folder that is a
file, a scheduler address without a port); the parameter types here refuse them while the
command line is parsed, so the error names the option before anything is read or written
(one line, :func:`rvmsim.cli.errors.usage_error_line`).
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import click

if TYPE_CHECKING:
    from ..isp import IspParams, OutputSpec
    from ..scene import Scene

__all__ = ["FiniteFloat", "Integer", "OutputFile", "OutputFolder", "SchedulerAddress", "SEED",
           "DEFAULT_WORKERS", "ONLY_SUPPORTED", "default_folder", "scale_factors", "check_scale",
           "load_isp"]

#: ``--workers`` of tune, batch and robustness: one per core, at most their limit of 64.
DEFAULT_WORKERS = min(os.cpu_count() or 1, 64)


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


def default_folder(argument: str, folder: Callable[[Path], Path]
                   ) -> Callable[[click.Context, click.Parameter, Path | None], Path | None]:
    """An ``--out`` callback: the folder given, else ``folder(ARGUMENT)`` (``ARGUMENT``, the
    command's input file, is parsed first when ``--out`` is not given).

    The output folder is then known before the command runs, for its messages as well
    (:class:`rvmsim.cli.errors.Command`).
    """
    def callback(ctx: click.Context, param: click.Parameter, value: Path | None) -> Path | None:
        source = ctx.params.get(argument)  # None only while completing a command line
        return folder(source) if value is None and source is not None else value

    return callback


def scale_factors(ctx: click.Context, param: click.Parameter, value: str) -> tuple[float, ...]:
    """``--scales``: comma-separated finite factors in [0, 10], at least one."""
    out = []
    for part in str(value).split(","):
        try:
            f = float(part)
        except ValueError:
            raise click.BadParameter(f"{part.strip()!r} is not a number", ctx, param) from None
        if not 0 <= f <= 10:  # also refuses nan
            raise click.BadParameter(f"{part.strip()} is outside [0, 10]", ctx, param)
        out.append(f)
    return tuple(dict.fromkeys(out))


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


def load_isp(params_file: Path | None, *, complete: bool = False
             ) -> tuple[IspParams, OutputSpec]:
    """The params file's ISP parameters and output (the paper's defaults without one);
    ``complete``: every parameter must be in the file (:func:`rvmsim.isp.load_params`)."""
    from ..isp import IspParams, OutputSpec, load_params

    return (load_params(params_file, complete=complete) if params_file
            else (IspParams(), OutputSpec()))


#: ``--only-supported`` of the commands that score a scene (tune, evaluate, robustness):
#: score only the ECs the scene supports (:func:`rvmsim.criteria.check_supported`).
ONLY_SUPPORTED = click.option(
    "--only-supported", is_flag=True,
    help="Score only the ECs the scene supports, leaving out those whose objects it leaves "
         "out (test objects, guidelines or board disabled); without it such a scene is "
         "refused before any work.")
