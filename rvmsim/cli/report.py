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
def report(path: Path, out: Path | None) -> None:
    """Write a self-contained HTML review report of a run (PATH = RUN), or of every run in a
    folder plus an index page (PATH = RUNS_DIR)."""
    from ..report import write_any_report

    click.echo(f"wrote {write_any_report(path, out)}")
