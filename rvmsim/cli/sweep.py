"""``rvmsim sweep``: a design-stage feasibility sweep."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from .errors import Command, interrupted_status, stopped_line
from .params import Integer, OutputFolder, SchedulerAddress, default_folder

__all__ = ["sweep"]


@click.command(cls=Command, error_path=("out",))
@click.argument("sweep_file", type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFolder(), default=None,
              callback=default_folder("sweep_file", lambda f: Path("runs") / f"sweep_{f.stem}"),
              help="Output folder (default: runs/sweep_<sweep file name>).")
@click.option("--workers", type=Integer(1, 256), default=os.cpu_count() or 1,
              show_default=True, help="Local processes (one design point each).")
@click.option("--scheduler", type=SchedulerAddress(), default=None, metavar="tcp://HOST:PORT",
              help="Run the design points on this Dask distributed cluster instead.")
@click.option("--force", is_flag=True, help="Start over, dropping the finished points.")
@click.option("--allow-large", is_flag=True,
              help="Run sweeps of more than the documented number of design points (the "
                   "limit on the sweep's points, see docs/sweep.md).")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def sweep(sweep_file: Path, out: Path, workers: int, scheduler: str | None,
          force: bool, allow_large: bool, progress: bool) -> None:
    """Render and tune every design point of SWEEP_FILE (a base scene and axes to vary).

    Writes sweep.csv/sweep.json (one row per point: its verdict (pass, not found,
    infeasible), best EC score, pass/fail per EC, the limiting EC, the tuned parameters),
    feasibility.png, sensitivity.png and sweep.html.  Points not passing are re-checked from
    their neighbours' optima (tune.recheck in the sweep file).  Finished points and
    re-checks are stored as they arrive: run the same command again to resume.
    """
    from ..batch import load_sweep, make_executor, run_sweep, stored_sweep
    from ..report import write_sweep_outputs

    spec = load_sweep(sweep_file, allow_large=allow_large)
    try:
        with make_executor(scheduler, workers) as ex:
            res = run_sweep(spec, out, executor=ex, force=force, progress=progress)
    except KeyboardInterrupt as stop:  # Ctrl-C, or SIGTERM (rvmsim._procs.Terminated)
        # Every finished point is in sweep.sqlite; write what there is, then stop.
        part = stored_sweep(spec, out)
        write_sweep_outputs(part)
        click.echo(f"{stopped_line(stop)}: {len(part.results)} of {len(part.points)} design "
                   "points done; run the same command again to resume", err=True)
        sys.exit(interrupted_status(stop))
    written = write_sweep_outputs(res)
    click.echo(res.summary())
    click.echo(f"wrote {', '.join(p.name for p in written)} in {out}")
