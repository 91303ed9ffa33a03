"""``rvmsim robustness``: the yield of one ISP setting over production variation."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .errors import Command
from .params import (DEFAULT_WORKERS, ONLY_SUPPORTED, SEED, FiniteFloat, Integer, OutputFolder,
                     SchedulerAddress, check_scale, load_isp, scale_factors)

__all__ = ["robustness"]


@click.command(cls=Command, error_path=("out",))
@click.argument("scene", metavar="SCENE|RUN", type=click.Path(path_type=Path))
@click.option("--params", "params_file", type=click.Path(path_type=Path), default=None,
              help="ISP params file (YAML/JSON) to sign off (default for a RUN: its "
                   "top/rank_1.yaml).")
@click.option("--samples", type=Integer(1, 100000), default=200, show_default=True,
              help="Variation samples (Sobol, scrambled).")
@click.option("--seed", type=SEED, default=0, show_default=True,
              help="Scrambling seed: the same seed, the same samples.")
@click.option("--out", "-o", type=OutputFolder(), required=True, help="Output folder.")
@click.option("--min-yield", type=FiniteFloat(0, 1), default=None,
              help="Exit 1 when the yield (0-1) is below this (default: the variation's "
                   "min_yield, else none).")
@click.option("--variation", "variation_file", type=click.Path(path_type=Path), default=None,
              help="Variation file (default: the scene's variation section).")
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None,
              help="Criteria file (YAML); default: the paper's thresholds.")
@click.option("--markets", default=None, metavar="M1,M2,…",
              help="The yield in each market and over all of them: each sample judged at "
                   "each market's site with its criteria (bundled names or SITE:CRITERIA, "
                   "docs/markets.md; default: a markets run's own).")
@click.option("--scale", type=FiniteFloat(0.05, 1.0), default=1.0, show_default=True,
              help="Render at this fraction of the sensor (RAD and shifts follow).")
@click.option("--scales", default="0.5,1,1.5,2", show_default=True, callback=scale_factors,
              help="Tolerance scale factors of the yield curve (comma-separated; each other "
                   "than 1 needs its own renders).")
@click.option("--scale-samples", type=Integer(1, 100000), default=None,
              help="Samples per tolerance scale factor of the yield curve (default: "
                   "min(--samples, 64)).")
@click.option("--workers", type=Integer(1, 64), default=DEFAULT_WORKERS,
              show_default=True, help="Local processes rendering the viewpoints not yet in "
                                      "the render cache.")
@click.option("--scheduler", type=SchedulerAddress(), default=None, metavar="tcp://HOST:PORT",
              help="Render those viewpoints on this Dask distributed cluster instead (the "
                   "scene's mesh files must be readable there at the same paths).")
@click.option("--compensation", default=None, metavar="FILE|default",
              help="Judge every sample after end-of-line compensation: a compensation file "
                   "(or a variation file with a compensation section), or 'default' "
                   "(docs/compensation.md).  The yield is then the yield after it; the "
                   "yield before is reported beside it.")
@click.option("--export-sample", "export_samples", type=Integer(0, 99999), multiple=True,
              metavar="N", help="Also write sample N's scene (its mount offsets and load "
                                "state; repeatable) as OUT/sample_N.yaml, with what was "
                                "measured on it in OUT/sample_N.json.")
@ONLY_SUPPORTED
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def robustness(scene: Path, params_file: Path, samples: int, seed: int, out: Path,
               min_yield: float | None, variation_file: Path | None,
               criteria_file: Path | None, markets: str | None, scale: float, scales: tuple[float, ...],
               scale_samples: int | None, workers: int, scheduler: str | None,
               compensation: str | None, export_samples: tuple[int, ...],
               only_supported: bool, progress: bool) -> None:
    """Yield of the ISP setting in --params over SCENE's production variation (SCENE may
    be a run folder: its scene, its best setting and, for a markets run, its markets).

    Draws mount-tolerance and load-state samples (the scene's variation section, or
    --variation), evaluates every EC on each, and writes robustness.json and
    robustness.html.  With --compensation each car is first corrected at the end of the
    line (its measured deviation turned into per-car ISP values) and the yield is the yield
    after that.  With --markets (or a markets run), the yield per market and over all
    markets, which the exit status and --min-yield then refer to.  With --export-sample N, also sample N as a scene file (``rvmsim evaluate``
    renders it in full: docs/robustness.md).  Exit status: 0 the yield is at least
    --min-yield (or the variation's min_yield; or none given), 1 below it, 2 an error.
    """
    from ..batch import make_executor
    from ..compensation import compensation_for
    from ..criteria import check_supported, load_criteria
    from ..markets import market_members, parse_markets
    from ..report import (RobustnessInputs, write_markets_robustness_outputs,
                          write_robustness_outputs)
    from ..robust import RobustnessSettings, markets_robustness, variation_for
    from ..robust import SampleExport, write_sample_scenes
    from ..robust import robustness as run_robustness
    from ..scene import read_scene_document

    for n in export_samples:
        if n >= samples:
            raise click.BadParameter(f"no sample {n}: --samples {samples} draws samples 0 to "
                                     f"{samples - 1}", click.get_current_context(),
                                     param_hint="--export-sample")
    scene, params_file, criteria_file, markets = _inputs(scene, params_file, criteria_file,
                                                         markets)
    _check_markets(markets, criteria_file, compensation, export_samples)
    market_list = () if markets is None else parse_markets(markets)
    params, output = load_isp(params_file)
    sc, document = read_scene_document(scene)
    check_scale(sc, params, scale)
    settings = RobustnessSettings(output, None if markets else check_supported(
                                      sc, load_criteria(criteria_file), scene,
                                      only_supported=only_supported),
                                  variation_for(sc, variation_file), samples, seed, scales,
                                  scale_samples, scale, min_yield,
                                  compensation_for(compensation))
    inputs = RobustnessInputs(params_file, criteria_file, variation_file, compensation, scale,
                              markets)
    if market_list:
        members = market_members([sc], market_list)
        with make_executor(scheduler, workers) as runner:
            mres = markets_robustness(sc, params, members, settings, runner=runner,
                                      progress=progress)
        written = write_markets_robustness_outputs(mres, out, inputs)
        click.echo(mres.summary())
        click.echo(f"wrote {', '.join(p.name for p in written)} in {out} "
                   f"({mres.timings['total']:.1f} s)")
        sys.exit(0 if mres.meets_min_yield else 1)
    with make_executor(scheduler, workers) as runner:
        result = run_robustness(sc, params, settings, runner=runner, progress=progress)
    written = write_robustness_outputs(result, out, inputs)
    written += write_sample_scenes(result, document, sc, export_samples, out,
                                   SampleExport(params_file, criteria_file, scale))
    click.echo(result.summary())
    click.echo(f"wrote {', '.join(p.name for p in written)} in {out} "
               f"({result.timings['total']:.1f} s)")
    sys.exit(0 if result.meets_min_yield else 1)


def _inputs(scene: Path, params_file: Path | None, criteria_file: Path | None,
            markets: str | None) -> tuple[Path, Path, Path | None, str | None]:
    """The scene, params, criteria and markets: as given, with what a run folder supplies
    (SCENE a run folder: its scene, its top/rank_1.yaml and criteria; --params a file in a
    run folder's top/ or best/: that run) for what is not given.  A markets run supplies
    its markets."""
    from ..runs import is_run_folder, open_run, run_inputs, run_settings

    run = scene if is_run_folder(scene) else (
        params_file.resolve().parent.parent if params_file is not None
        and is_run_folder(params_file.resolve().parent.parent) else None)
    if run is None:
        if params_file is None:
            raise click.BadParameter("give the ISP params file to judge (or a run folder as "
                                     "SCENE)", click.get_current_context(),
                                     param_hint="--params")
        return scene, params_file, criteria_file, markets
    store = open_run(run)
    try:
        settings = run_settings(run, store)
    finally:
        store.close()
    if markets is None and settings.kind.markets:
        markets = ",".join(settings.kind.markets)
    if scene == run:
        scene, crit = run_inputs(run, settings)
        criteria_file = criteria_file if criteria_file is not None or markets else crit
    if params_file is None:
        params_file = run / "top" / "rank_1.yaml"
        if not params_file.is_file():
            raise click.BadParameter(f"{run}: no top/rank_1.yaml (a run without a trial?); "
                                     "give --params", click.get_current_context(),
                                     param_hint="--params")
    return scene, params_file, criteria_file, markets


def _check_markets(markets: str | None, criteria_file: Path | None, compensation: str | None,
                   export_samples: tuple[int, ...]) -> None:
    """--markets against the options it does not combine with (one line each)."""
    if markets is None:
        return
    for given, flag, why in (
            (criteria_file is not None, "--criteria", "each market has its own (a market "
             "may be SITE:CRITERIA with your criteria file)"),
            (compensation is not None, "--compensation", "not supported with --markets yet"),
            (bool(export_samples), "--export-sample", "not supported with --markets yet")):
        if given:
            raise click.BadParameter(f"{why}", click.get_current_context(),
                                     param_hint=f"{flag} with --markets")
