"""``rvmsim report``: the HTML review report of a run, or of every run in a folder."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .errors import Command
from .params import OutputFile

__all__ = ["report", "judge"]


@click.command(cls=Command, error_path=("out", "path"))
@click.argument("path", type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFile(), default=None,
              help="HTML file to write (default: RUN/report.html, or RUNS_DIR/index.html).")
@click.option("--markets", default=None, metavar="M1,M2,…",
              help="First judge the run's best setting in these markets (as `rvmsim judge "
                   "RUN --markets` does: one row and picture per market, written into the "
                   "run; docs/markets.md); a run tuned with --markets shows its own.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def report(path: Path, out: Path | None, markets: str | None, progress: bool) -> None:
    """Write a self-contained HTML review report of a run (PATH = RUN), or of every run in a
    folder plus an index page (PATH = RUNS_DIR).  The report only reads the run; beside the
    page it writes the ECU table of rank 1's parking guidelines (guidelines.bin beside a
    report.html, NAME.guidelines.bin beside NAME.html), whose SHA-256 the page shows."""
    from ..report import write_any_report
    from ..tune.markets import judge_run_in_markets

    if markets is not None:
        judge_run_in_markets(path, markets)
        click.echo(f"judged in {markets}: wrote {path / 'best' / 'markets.json'}")
    click.echo(f"wrote {write_any_report(path, out, progress=progress)}")


@click.command(cls=Command, error_path=("run",))
@click.argument("run", type=click.Path(path_type=Path))
@click.option("--markets", required=True, metavar="M1,M2,…",
              help="The markets to judge the run's best setting in (docs/markets.md).")
def judge(run: Path, markets: str) -> None:
    """Judge RUN's best setting in other markets: each of its scenes at each market's site
    with the market's criteria, written into the run (best/markets.json and
    best/markets/<market>/), which `report`, `status` and `signoff` then show.  Exits 0 when
    it passes every market, 1 when it fails one."""
    from ..tune.markets import judge_run_in_markets, market_table_lines

    doc = judge_run_in_markets(run, markets)
    click.echo("\n".join(market_table_lines(doc)))
    click.echo(f"wrote {run / 'best' / 'markets.json'}")
    sys.exit(0 if doc.get("passed") else 1)
