"""Command-line interface: a thin shell over the library.

Every command reports user errors (bad scene files, unreadable images, …) as one line on
stderr and exits with status 2; it never prints a traceback for them.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from .cli_params import (SEED, FiniteFloat, Group, Integer, OutputFile, OutputFolder,
                         SchedulerAddress, check_scale, usage_error_line)
from .cli_params import fail as _fail
from .cli_params import fail_os as _fail_os
from .cli_params import load_isp as _load_isp
from .errors import RvmsimError
from .tune import DEFAULT_STRATEGY, STRATEGIES

__all__ = ["cli", "main"]

#: ``--strategy`` choices and help: the strategy registry.
_STRATEGY_HELP = "; ".join(f"{name}: {cls.summary}" for name, cls in STRATEGIES.items()) + "."
#: ``--workers`` of tune and batch: one per core, at most their limit of 64.
_DEFAULT_WORKERS = min(os.cpu_count() or 1, 64)


@click.group(cls=Group, context_settings={"help_option_names": ["-h", "--help"]},
             invoke_without_command=True, no_args_is_help=False)
@click.version_option(package_name="rvmsim")
@click.pass_context
def cli(ctx: click.Context) -> None:
    """rvmsim: automatic ISP tuning for rear-view-monitoring fisheye cameras."""
    if ctx.invoked_subcommand is None:  # a usage error of one line, not the help page
        names = ", ".join(cli.list_commands(ctx))
        raise click.UsageError(f"missing command (one of {names}; see rvmsim --help)", ctx)


@cli.command()
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFolder(), required=True, help="Output folder.")
@click.option("--scale", type=FiniteFloat(0.05, 4.0), default=1.0, show_default=True,
              help="Resample the sensor by this factor (0.25 for a quick preview).")
@click.option("--face-size", type=Integer(16, 4096), default=None,
              help="Cube face size in px (default: automatic, as dense as the fisheye image).")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def render(scene: Path, out: Path, scale: float, face_size: int | None, progress: bool) -> None:
    """Render the fisheye (P camera) colour and label images of SCENE.

    Writes fisheye_color.png, fisheye_labels.png (one uint8 label ID per pixel),
    fisheye_labels_preview.png (labels in colour) and render.json into the output folder.
    """
    from .pipeline import write_fisheye
    from .render import render_fisheye
    from .scene import load_scene

    try:
        sc = load_scene(scene)
        cam = sc.fisheye_camera()
        if scale != 1.0:
            cam = cam.scaled(scale)
        images = render_fisheye(sc, camera=cam, face_size=face_size, progress=progress)
        write_fisheye(images, out, scene_file=scene, vehicle=sc.name)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out)
    total = sum(images.timings.values())
    click.echo(
        f"rendered {sc.name}: {cam.width}x{cam.height} px, {len(images.faces)} cube faces of "
        f"{images.face_size} px in {total:.2f} s -> {out}"
    )


@cli.command()
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--params", "params_file", type=click.Path(path_type=Path), default=None,
              help="ISP params file (YAML/JSON); default: the paper's Table 2 defaults.")
@click.option("--out", "-o", type=OutputFolder(), required=True, help="Output folder.")
@click.option("--scale", type=FiniteFloat(0.05, 4.0), default=1.0, show_default=True,
              help="Render the fisheye at this fraction of the sensor (RAD and shifts follow).")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def process(scene: Path, params_file: Path | None, out: Path, scale: float,
            progress: bool) -> None:
    """Render SCENE and run the ISP: fisheye image -> RVM image.

    Writes rvm_color.png, rvm_labels.png (uint8 IDs), rvm_labels_preview.png,
    fisheye_roi.png (the fisheye image with the region the RVM image uses outlined in green)
    and isp.json (the parameters used).
    """
    from .pipeline import render_rvm, write_processed
    from .scene import load_scene

    try:
        params, output = _load_isp(params_file)
        sc = load_scene(scene)
        check_scale(sc, params, scale)
        frame = render_rvm(sc, params, output, scale=scale, progress=progress)
        write_processed(frame, out, params)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out)
    click.echo(f"processed {sc.name}: RVM image {output.width}x{output.height} px -> {out}")


@cli.command()
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--params", "params_file", type=click.Path(path_type=Path), default=None,
              help="ISP params file (YAML/JSON); default: the paper's Table 2 defaults.")
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None,
              help="Criteria file (YAML); default: the paper's thresholds.")
@click.option("--out", "-o", type=OutputFolder(), default=None,
              help="Output folder (default: out/<scene name>/evaluate).")
@click.option("--scale", type=FiniteFloat(0.05, 4.0), default=1.0, show_default=True,
              help="Render the fisheye at this fraction of the sensor (RAD and shifts follow).")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def evaluate(scene: Path, params_file: Path | None, criteria_file: Path | None,
             out: Path | None, scale: float, progress: bool) -> None:
    """Evaluate the RVM image of SCENE under ISP parameters: the eleven ECs and the EC score.

    Prints the EC table and writes ec.json, ec_annotated.png (the measurements drawn on the RVM
    image), rvm_color.png and rvm_labels.png.
    """
    from .criteria import load_criteria
    from .pipeline import render_rvm, write_evaluation
    from .scene import load_scene

    out = out or Path("out") / scene.stem / "evaluate"
    try:
        params, output = _load_isp(params_file)
        criteria = load_criteria(criteria_file)
        sc = load_scene(scene)
        check_scale(sc, params, scale)
        frame = render_rvm(sc, params, output, criteria=criteria, scale=scale, annotate=True,
                           progress=progress)
        write_evaluation(frame, out, params, scene_file=scene, vehicle=sc.name,
                         criteria_file=criteria_file)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out)
    click.echo(f"{sc.name} — criteria: {criteria.name}")
    click.echo(frame.ec.table())
    click.echo(f"wrote {out / 'ec.json'} and {out / 'ec_annotated.png'}")


@cli.command()
@click.argument("scenes", nargs=-1, type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFolder(), default=None,
              help="Run folder (default: runs/<scene name>, runs/<name>+<name>… with --shared).")
@click.option("--shared", is_flag=True, help="One parameter set for all SCENES (the worst "
              "scene's EC score is maximised, every scene must pass).")
@click.option("--aggregate", default=None, metavar="min|quantile Q", help="--shared, --robust: "
              "the EC score is the members' minimum or this quantile [default: min, "
              "quantile 0.1 with --robust].")
@click.option("--robust", is_flag=True, help="Judge every candidate on production variation "
              "samples too (the scene's variation section, or --variation): its EC score is "
              "the worst sample's.")
@click.option("--samples", type=Integer(1, 256), default=None,
              help="With --robust: variation samples per scene [default: 16].")
@click.option("--variation", "variation_file", type=click.Path(path_type=Path), default=None,
              help="With --robust: a variation file instead of the scene's section.")
@click.option("--strategy", type=click.Choice(list(STRATEGIES)),
              default=DEFAULT_STRATEGY, show_default=True, help=_STRATEGY_HELP)
@click.option("--config", "config_file", type=click.Path(path_type=Path), default=None,
              help="Tuning config (YAML): tuned parameters, ranges, steps, N, T, budgets.")
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None,
              help="Criteria file (YAML); default: the paper's thresholds.")
@click.option("--seed", type=SEED, default=0, show_default=True, help="Random seed.")
@click.option("--workers", type=Integer(1, 64), default=_DEFAULT_WORKERS,
              show_default=True, help="Worker processes.")
@click.option("--budget", type=Integer(1), default=None,
              help="Evaluations (cmaes-solved, cmaes, random) or fine trials T per seed (grid-random).")
@click.option("--max-time", type=FiniteFloat(0), default=None,
              help="Stop after this many seconds (the run can be resumed).")
@click.option("--target-score", type=FiniteFloat(0, 1), default=None,
              help="Stop once the EC score reaches this.")
@click.option("--resume", "resume_dir", type=click.Path(path_type=Path), default=None,
              help="Continue the run in this folder (same settings, same final result).")
@click.option("--force", is_flag=True, help="Replace an existing run in the output folder.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def tune(scenes: tuple[Path, ...], out: Path | None, shared: bool, aggregate: str | None,
         robust: bool, samples: int | None, variation_file: Path | None, strategy: str, config_file: Path | None, criteria_file: Path | None, seed: int,
         workers: int, budget: int | None, max_time: float | None, target_score: float | None,
         resume_dir: Path | None, force: bool, progress: bool) -> None:
    """Tune the ISP of SCENE, one setting for SCENE1 SCENE2 … (--shared), or --resume RUN."""
    from .tune import (RunOptions, TuneRequest, check_tune_arguments, load_tuning_config,
                       summary_lines)
    from .tune import resume as resume_run
    from .tune import tune as run_tune
    from .tune.robust import DEFAULT_SAMPLES

    try:
        check_tune_arguments(len(scenes), shared, aggregate, resume_dir is not None, robust,
                             samples, variation_file)
        options = RunOptions(workers, max_time, target_score, progress)
        if resume_dir is not None:
            result = resume_run(resume_dir, options=options)
        else:
            request = TuneRequest(
                tuple(scenes), strategy, load_tuning_config(config_file),
                criteria_file=criteria_file, seed=seed, budget=budget, aggregate=aggregate,
                robust_samples=(samples or DEFAULT_SAMPLES) if robust else None,
                variation_file=variation_file)
            result = run_tune(request, out or Path("runs") / "+".join(s.stem for s in scenes),
                              options=options, force=force)
        lines = summary_lines(result)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out)
    click.echo("\n".join(lines))


@cli.command()
@click.argument("scenes", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFolder(), default=Path("runs"),
              show_default=True, help="Folder for the runs (one sub-folder per scene).")
@click.option("--strategy", type=click.Choice(list(STRATEGIES)),
              default=DEFAULT_STRATEGY, show_default=True, help=_STRATEGY_HELP)
@click.option("--config", "config_file", type=click.Path(path_type=Path), default=None)
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None)
@click.option("--seed", type=SEED, default=0, show_default=True, help="Random seed.")
@click.option("--workers", type=Integer(1, 64), default=_DEFAULT_WORKERS,
              show_default=True)
@click.option("--budget", type=Integer(1), default=None)
@click.option("--scheduler", type=SchedulerAddress(), default=None, metavar="tcp://HOST:PORT",
              help="Tune the scenes as tasks on this Dask distributed cluster (one task per "
                   "scene) instead of one after another here.")
@click.option("--progress/--no-progress", default=True)
def batch(scenes, out, strategy, config_file, criteria_file, seed, workers, budget,
          scheduler, progress) -> None:
    """Tune every scene in SCENES; print and write a summary table (summary.json, .txt).

    A scene that cannot be loaded or tuned is reported and skipped; the others still run.
    Locally the scenes run one after another, each on --workers processes; with --scheduler
    each scene is one task on the cluster, and its run folder is written here as it finishes.
    """
    from .batch import (BatchSettings, SceneRun, run_batch, summary_ec_ids, summary_table,
                        write_summary)
    from .tune import load_tuning_config

    try:
        settings = BatchSettings(strategy, load_tuning_config(config_file), criteria_file,
                                 seed, budget, workers)
    except RvmsimError as err:
        _fail(err)
    bars: list = []  # the overall bar on top, each vehicle's tuning bar below it

    def overall():  # made once a scene starts: no bar above an error before that (one line)
        if progress and not bars:
            from tqdm import tqdm

            bars.append(tqdm(total=len(scenes), unit="vehicle", desc="batch", position=0))
        return bars[0] if bars else None

    def say(msg: str, err: bool = False) -> None:
        if (bar := overall()) is not None:
            bar.write(msg, file=sys.stderr if err else sys.stdout)
        else:
            click.echo(msg, err=err)

    runs: list[SceneRun] = []
    try:
        for r in run_batch(scenes, out, settings, scheduler=scheduler, progress=progress,
                           on_start=lambda k, scene: say(f"[{k}/{len(scenes)}] {scene}")):
            runs.append(r)
            if r.error is not None:
                say(f"rvmsim: error: {r.error} (skipped)", err=True)
            if (bar := overall()) is not None:
                bar.update(1)
                if r.ok:
                    bar.set_postfix_str(f"{r.vehicle[:20]}: EC {r.ec_score:.3g}")
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out)
    if bars:
        bars[0].close()
    table = summary_table(runs, summary_ec_ids(runs, criteria_file))
    click.echo(table)
    try:
        write_summary(out, runs, table)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out)
    if any(not r.ok for r in runs):
        sys.exit(1)


_MIN_DISTANCE = click.option(
    "--min-distance", type=FiniteFloat(0, 1, min_open=True), default=None,
    help="Least distance between candidates, in fractions of each tuned parameter's span "
         "(default: the run's diverse.min_distance).")
_BY_SCORE = click.option("--by-score", is_flag=True,
                         help="The plain order by EC score instead of the diverse top-M.")


@cli.command()
@click.argument("run", type=click.Path(path_type=Path))
@click.option("--top", "top_m", type=Integer(1, 100), default=None,
              help="Candidates to show (M; default: the run's).")
@_MIN_DISTANCE
@_BY_SCORE
def status(run: Path, top_m: int | None, min_distance: float | None, by_score: bool) -> None:
    """Show a run's progress and its diverse top-M candidates (works while it runs)."""
    from .tune import status_lines

    try:
        lines = status_lines(run, top_m, by_score=by_score, min_distance=min_distance)
    except RvmsimError as err:
        _fail(err)
    click.echo("\n".join(lines))


@cli.command()
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
    from .tune import rank_params_text

    try:
        text = rank_params_text(run, rank, by_score=by_score, min_distance=min_distance)
    except RvmsimError as err:
        _fail(err)
    if out is None:
        click.echo(text, nl=False)
    else:
        try:
            out.write_text(text)
        except OSError as err:
            _fail(RvmsimError(f"{out}: {err.strerror or err}"))
        click.echo(f"wrote {out}")


@cli.command()
@click.argument("path", type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFile(), default=None,
              help="HTML file to write (default: RUN/report.html, or RUNS_DIR/index.html).")
def report(path: Path, out: Path | None) -> None:
    """Write a self-contained HTML review report of a run (PATH = RUN), or of every run in a
    folder plus an index page (PATH = RUNS_DIR)."""
    from .report import write_any_report

    try:
        written = write_any_report(path, out)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out or path)
    click.echo(f"wrote {written}")


# commands in modules of their own (cli.py is at its size limit)
from .cli_calibrate import calibrate  # noqa: E402
from .cli_console import console  # noqa: E402
from .cli_robust import robustness  # noqa: E402
from .cli_sweep import sweep  # noqa: E402
from .cli_validate import validate  # noqa: E402

cli.add_command(calibrate)
cli.add_command(console)
cli.add_command(robustness)
cli.add_command(sweep)
cli.add_command(validate)


def main() -> None:
    """Console-script entry point: a usage error is one line naming the option, exit 2
    (:func:`~rvmsim.cli_params.usage_error_line`); so is any error a command did not report
    itself; Ctrl-C exits 130 (a tuning run keeps every finished batch and can be resumed)."""
    try:
        code = cli.main(standalone_mode=False)
    except (KeyboardInterrupt, click.exceptions.Abort):
        click.echo("rvmsim: interrupted", err=True)
        sys.exit(130)
    except click.UsageError as err:
        click.echo(usage_error_line(err), err=True)
        sys.exit(err.exit_code)
    except click.ClickException as err:
        click.echo(f"rvmsim: error: {err.format_message()}", err=True)
        sys.exit(err.exit_code)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, None)
    sys.exit(code if isinstance(code, int) else 0)


if __name__ == "__main__":
    main()
