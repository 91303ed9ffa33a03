"""``rvmsim tune``, ``status``, ``select`` and ``batch``: tuning runs, started, resumed,
watched, exported from, and several scenes tuned one after another (or on a cluster)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click
from click.core import ParameterSource

from .._progress import ProgressBar, progress_bar
from ..search import DEFAULT_STRATEGY, STRATEGIES
from ..tune.robust import DEFAULT_SAMPLES, ROBUST_AGGREGATE
from ..errors import RvmsimError
from .errors import Command
from .params import (DEFAULT_WORKERS, ONLY_SUPPORTED, SEED, FiniteFloat, Integer, OutputFile,
                     OutputFolder, SchedulerAddress)

if TYPE_CHECKING:
    from ..batch import SceneRun

__all__ = ["tune", "status", "select", "batch"]

#: ``--strategy`` choices and help: the strategy registry.
_STRATEGY_HELP = "; ".join(f"{name}: {cls.summary}" for name, cls in STRATEGIES.items()) + "."


@click.command(cls=Command, error_path=("out",))
@click.argument("scenes", nargs=-1, type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFolder(), default=None,
              help="Run folder (default: runs/<scene name>, runs/<name>+<name>… with --shared).")
@click.option("--shared", is_flag=True, help="One parameter set for all SCENES (the worst "
              "scene's EC score is maximised, every scene must pass); exits 1 when none "
              "passes all, naming the ECs that fail on which scenes.")
@click.option("--aggregate", default=None, metavar="min|quantile Q", help="--shared, --robust: "
              "the EC score is the members' minimum or this quantile [default: min, "
              f"{ROBUST_AGGREGATE} with --robust].")
@click.option("--robust", is_flag=True, help="Judge every candidate on production variation "
              "samples too (the scene's variation section, or --variation): its EC score is "
              "a low quantile of the nominal's and the samples' scores [default: "
              f"{ROBUST_AGGREGATE}; --aggregate min: the worst one's]; it passes where every "
              "one passes.")
@click.option("--samples", type=Integer(1, 256), default=None,
              help=f"With --robust: variation samples per scene [default: {DEFAULT_SAMPLES}].")
@click.option("--variation", "variation_file", type=click.Path(path_type=Path), default=None,
              help="With --robust: a variation file instead of the scene's section.")
@click.option("--compensation", default=None, metavar="FILE|default",
              help="With --robust: tune for the yield after end-of-line compensation (each "
                   "sample judged with its per-car values): a compensation file, or "
                   "'default' (docs/compensation.md).")
@click.option("--strategy", type=click.Choice(list(STRATEGIES)),
              default=DEFAULT_STRATEGY, show_default=True, help=_STRATEGY_HELP)
@click.option("--config", "config_file", type=click.Path(path_type=Path), default=None,
              help="Tuning config (YAML): tuned parameters, ranges, steps, N, T, budgets.")
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None,
              help="Criteria file (YAML); default: the paper's thresholds.")
@click.option("--markets", default=None, metavar="M1,M2,…",
              help="One setting for every market: fmvss111-full, fmvss111, unr158, jp, or "
                   "SITE:CRITERIA (docs/markets.md); exits 1 when none passes all.")
@click.option("--seed", type=SEED, default=0, show_default=True, help="Random seed.")
@click.option("--workers", type=Integer(1, 64), default=DEFAULT_WORKERS,
              show_default=True, help="Worker processes.")
@click.option("--budget", type=Integer(1), default=None,
              help="Evaluations (cmaes-solved, cmaes, random) or fine trials T per seed (grid-random).")
@click.option("--max-time", type=FiniteFloat(0), default=None,
              help="Stop after this many seconds (the run can be resumed).")
@click.option("--target-score", type=FiniteFloat(0, 1), default=None,
              help="Stop once the EC score reaches this.")
@click.option("--resume", "resume_dir", type=click.Path(path_type=Path), default=None,
              help="Continue the run in this folder with its own settings (same final "
                   "result); a SCENE or run option given too must be the run's own.")
@click.option("--force", is_flag=True, help="Replace an existing run in the output folder.")
@ONLY_SUPPORTED
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def tune(scenes: tuple[Path, ...], out: Path | None, shared: bool, aggregate: str | None,
         robust: bool, samples: int | None, variation_file: Path | None,
         compensation: str | None, strategy: str,
         config_file: Path | None, criteria_file: Path | None, markets: str | None, seed: int,
         workers: int, budget: int | None, max_time: float | None, target_score: float | None,
         resume_dir: Path | None, force: bool, only_supported: bool, progress: bool) -> None:
    """Tune the ISP of SCENE, one setting for SCENE1 SCENE2 … (--shared) or for several
    markets (--markets), or --resume RUN. Exits 1 when the best setting found fails an EC
    (the run is stored all the same)."""
    from ..compensation import compensation_for
    from ..tune import Markets, Robust, RunOptions, Shared, TuneRequest
    from ..search import load_tuning_config
    from ..tune import resume as resume_run
    from ..tune import summary_lines
    from ..tune import tune as run_tune
    from ..tune.resumed import ResumeArgs

    _check_flags(len(scenes), shared or markets is not None, aggregate, resume_dir is not None,
                 robust, samples, variation_file, compensation, markets=markets is not None)
    options = RunOptions(workers, max_time, target_score, progress)
    if resume_dir is not None:
        given = _given(click.get_current_context())
        result = resume_run(resume_dir, options=options, given=ResumeArgs(
            scenes=tuple(scenes), shared=shared, markets=markets, robust=robust,
            samples=samples, variation_file=variation_file, compensation=compensation,
            aggregate=aggregate, strategy=strategy if "strategy" in given else None,
            seed=seed if "seed" in given else None, budget=budget, config_file=config_file,
            criteria_file=criteria_file, out=out, force=force, only_supported=only_supported))
    else:
        kind: Shared | Robust | Markets | None = None  # the run's kind, as its flags name it
        if markets is not None:
            kind = Markets(markets, aggregate or "min")
        elif robust:
            kind = Robust(samples or DEFAULT_SAMPLES, variation_file,
                          compensation_for(compensation), aggregate or ROBUST_AGGREGATE)
        elif shared:
            kind = Shared(aggregate or "min")
        request = TuneRequest(
            tuple(scenes), strategy, load_tuning_config(config_file), criteria_file=criteria_file,
            seed=seed, budget=budget, kind=kind, only_supported=only_supported)
        name = "+".join(s.stem for s in scenes) + ("" if markets is None else "@markets")
        result = run_tune(request, out or Path("runs") / name, options=options, force=force)
    click.echo("\n".join(summary_lines(result)))
    # 1 when the best setting fails what the run judges (the summary says which ECs)
    sys.exit(result.verdict.exit_status)


def _check_flags(n_scenes: int, shared: bool, aggregate: str | None, resume: bool,
                 robust: bool, samples: int | None, variation: object, compensation: object,
                 *, markets: bool) -> None:
    """``rvmsim tune``'s scene arguments against its flags (what each run kind checks of
    its own values is the kind's: :func:`rvmsim.tune.new_run_settings`)."""
    if not robust and (samples is not None or variation is not None
                       or compensation is not None):
        flag = ("samples" if samples is not None else "variation" if variation is not None
                else "compensation")
        raise RvmsimError(f"--{flag}: only with --robust (tune on production variation "
                          "samples)")
    if markets and robust:
        raise RvmsimError("--markets with --robust: not supported; tune for the markets, "
                          "then measure the yield per market with rvmsim robustness "
                          "RUN --markets …")
    if resume:  # each given option is checked against the run's own settings
        return  # (rvmsim.tune.resumed, once the run's store is read)
    if not n_scenes:
        raise RvmsimError("tune: give a SCENE file, or --resume RUN")
    if shared and n_scenes < 2 and not markets:
        raise RvmsimError(f"--shared: give at least two scenes (got {n_scenes}); tune one "
                          "scene without --shared")
    if not shared and n_scenes > 1:
        raise RvmsimError(f"tune: {n_scenes} scenes given: add --shared to tune one "
                          "parameter set for all, or use rvmsim batch to tune each")
    if aggregate is not None and not (shared or robust):
        raise RvmsimError("--aggregate: only with --shared (several scenes) or --robust")


def _given(ctx: click.Context) -> set[str]:
    """The options given on the command line (or in the environment), not defaulted."""

    return {name for name in ctx.params
            if ctx.get_parameter_source(name) not in (None, ParameterSource.DEFAULT)}


_MIN_DISTANCE = click.option(
    "--min-distance", type=FiniteFloat(0, 1, min_open=True), default=None,
    help="Least distance between candidates, in fractions of each tuned parameter's span "
         "(default: the run's diverse.min_distance).")
_BY_SCORE = click.option("--by-score", is_flag=True,
                         help="The plain order by EC score instead of the diverse top-M.")


@click.command(cls=Command)
@click.argument("run", type=click.Path(path_type=Path))
@click.option("--top", "top_m", type=Integer(1, 100), default=None,
              help="Candidates to show (M; default: the run's).")
@_MIN_DISTANCE
@_BY_SCORE
def status(run: Path, top_m: int | None, min_distance: float | None, by_score: bool) -> None:
    """Show a run's progress and its diverse top-M candidates (works while it runs)."""
    from ..runs import status_lines

    click.echo("\n".join(status_lines(run, top_m, by_score=by_score,
                                      min_distance=min_distance)))


@click.command(cls=Command, error_path=("out",))
@click.argument("run", type=click.Path(path_type=Path))
@click.option("--rank", type=Integer(1), default=1, show_default=True,
              help="Rank K in the run's diverse top-M (as status, top/ and the report list it).")
@click.option("--out", "-o", type=OutputFile(), default=None,
              help="Params file to write (default: print it).")
@_MIN_DISTANCE
@_BY_SCORE
def select(run: Path, rank: int, out: Path | None, min_distance: float | None,
           by_score: bool) -> None:
    """Export the rank-K parameter set of a run as a params file."""
    from ..runs import rank_params_text

    text = rank_params_text(run, rank, by_score=by_score, min_distance=min_distance)
    if out is None:
        click.echo(text, nl=False)
    else:
        out.write_text(text)
        click.echo(f"wrote {out}")


class _BatchProgress:
    """``rvmsim batch``'s terminal: the overall bar on top (each vehicle's tuning bar below
    it), made once a scene starts, so that an error before that is one line."""

    def __init__(self, n_scenes: int, show: bool) -> None:
        self.n_scenes = n_scenes
        self.show = show
        self.bar: ProgressBar | None = None

    def overall(self) -> ProgressBar | None:
        if self.show and self.bar is None:
            self.bar = progress_bar(total=self.n_scenes, unit="vehicle", desc="batch", position=0)
        return self.bar

    def say(self, msg: str, err: bool = False) -> None:
        if (bar := self.overall()) is not None:
            bar.write(msg, file=sys.stderr if err else sys.stdout)
        else:
            click.echo(msg, err=err)

    def done(self, run: SceneRun) -> None:
        if run.error is not None:
            self.say(f"rvmsim: error: {run.error} (skipped)", err=True)
        if (bar := self.overall()) is not None:
            bar.update(1)
            if run.ok:
                bar.set_postfix_str(f"{run.vehicle[:20]}: EC {run.ec_score:.3g}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


@click.command(cls=Command, error_path=("out",))
@click.argument("scenes", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFolder(), default=Path("runs"),
              show_default=True, help="Folder for the runs (one sub-folder per scene).")
@click.option("--strategy", type=click.Choice(list(STRATEGIES)),
              default=DEFAULT_STRATEGY, show_default=True, help=_STRATEGY_HELP)
@click.option("--config", "config_file", type=click.Path(path_type=Path), default=None)
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None)
@click.option("--seed", type=SEED, default=0, show_default=True, help="Random seed.")
@click.option("--workers", type=Integer(1, 64), default=DEFAULT_WORKERS,
              show_default=True)
@click.option("--budget", type=Integer(1), default=None)
@click.option("--scheduler", type=SchedulerAddress(), default=None, metavar="tcp://HOST:PORT",
              help="Tune the scenes as tasks on this Dask distributed cluster (one task per "
                   "scene) instead of one after another here.")
@click.option("--progress/--no-progress", default=True)
def batch(scenes: tuple[Path, ...], out: Path, strategy: str, config_file: Path | None,
          criteria_file: Path | None, seed: int, workers: int, budget: int | None,
          scheduler: str | None, progress: bool) -> None:
    """Tune every scene in SCENES; print and write a summary table (summary.json, .txt).

    A scene that cannot be loaded or tuned is reported and skipped; the others still run.
    Locally the scenes run one after another, each on --workers processes; with --scheduler
    each scene is one task on the cluster, and its run folder is written here as it finishes.
    """
    from ..batch import BatchSettings, run_batch, summary_ec_ids, summary_table, write_summary
    from ..search import load_tuning_config

    settings = BatchSettings(strategy, load_tuning_config(config_file), criteria_file,
                             seed, budget, workers)
    terminal = _BatchProgress(len(scenes), progress)
    runs: list[SceneRun] = []
    for r in run_batch(scenes, out, settings, scheduler=scheduler, progress=progress,
                       on_start=lambda k, scene: terminal.say(f"[{k}/{len(scenes)}] {scene}")):
        runs.append(r)
        terminal.done(r)
    terminal.close()
    table = summary_table(runs, summary_ec_ids(runs, criteria_file))
    click.echo(table)
    write_summary(out, runs, table)
    if any(not r.ok for r in runs):
        sys.exit(1)
