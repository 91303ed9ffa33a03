"""``rvmsim report``: the HTML review report of a run, or of every run in a folder."""

from __future__ import annotations

from pathlib import Path

import click

from .errors import Command
from .params import OutputFile

__all__ = ["report"]


@click.command(cls=Command, error_path=("out", "path"))
@click.argument("path", type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFile(), default=None,
              help="HTML file to write (default: RUN/report.html, or RUNS_DIR/index.html).")
@click.option("--markets", default=None, metavar="M1,M2,…",
              help="Judge the run's best setting in these markets too (one row and picture "
                   "per market; docs/markets.md); a run tuned with --markets shows its own.")
def report(path: Path, out: Path | None, markets: str | None) -> None:
    """Write a self-contained HTML review report of a run (PATH = RUN), or of every run in a
    folder plus an index page (PATH = RUNS_DIR)."""
    from ..report import write_any_report
    from ..tune.markets import judge_run_in_markets

    if markets is not None:
        judge_run_in_markets(path, markets)
    click.echo(f"wrote {write_any_report(path, out)}")
