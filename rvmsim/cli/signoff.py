"""``rvmsim signoff``: the sign-off sheet (HTML and PDF) of a run's best ISP setting."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .errors import Command
from .params import FiniteFloat

__all__ = ["signoff"]


@click.command(cls=Command, error_path=("out",))
@click.argument("run", type=click.Path(path_type=Path))
@click.option("--out", "-o", type=click.Path(path_type=Path), required=True,
              help="Folder to write signoff.html, signoff.pdf, signoff.json and "
                   "guidelines.bin (the guidelines' ECU table) into (its parent must exist).")
@click.option("--robustness", "robustness_dir", type=click.Path(path_type=Path), default=None,
              help="Folder written by rvmsim robustness for this setting (the yield).")
@click.option("--validation", "validation_dir", type=click.Path(path_type=Path), default=None,
              help="Folder written by rvmsim validate (the real capture's validation).")
@click.option("--eol", "eol_dir", type=click.Path(path_type=Path), default=None,
              help="Folder written by rvmsim eol (the end-of-line record).")
@click.option("--markets", default=None, metavar="M1,M2,…",
              help="Judge the setting in these markets too (one row and picture per market; "
                   "docs/markets.md); a run tuned with --markets shows its own.")
@click.option("--reviewer", default="", help="The reviewer's name, for the signature block.")
@click.option("--allow-other-setting", is_flag=True,
              help="Sign with a robustness, validation or EOL folder of another setting or "
                   "vehicle (refused otherwise): the sheet opens with a red banner.")
@click.option("--min-yield", type=FiniteFloat(0, 1), default=None,
              help="The least production yield (0-1) that passes (default: the one the "
                   "--robustness folder recorded, its --min-yield or its variation's "
                   "min_yield; else the yield is shown, not judged).")
@click.option("--pdf/--no-pdf", default=True, show_default=True,
              help="Also print the page to signoff.pdf with headless Chromium.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def signoff(run: Path, out: Path, robustness_dir: Path | None, validation_dir: Path | None,
            eol_dir: Path | None, markets: str | None, reviewer: str,
            allow_other_setting: bool, min_yield: float | None, pdf: bool,
            progress: bool) -> None:
    """Write the sign-off sheet of RUN's best setting: its 14 values, params file and
    SHA-256, the input files with theirs, the tool's version and commit, every EC at the
    display output of record with its margin, the car's parking guidelines (their picture,
    and their ECU table written as guidelines.bin with its SHA-256), the yield
    (--robustness), validation and EOL records, the failing samples with the commands that
    reproduce them, and a signature block.  One self-contained HTML page and its PDF.  Exit
    status: 0 when nothing the sheet judged fails (the ECs at the display, the markets, the
    yield against the least yield, the validation, the EOL station; what was not given is
    not judged; the guidelines are shown, not judged), 1 when something fails, 2 on an
    error."""
    from ..report import signoff as write_signoff
    from ..tune.markets import judge_run_in_markets

    if markets is not None:  # the judge step (`rvmsim judge`), then the sheet reads the run
        judge_run_in_markets(run, markets)
        click.echo(f"judged in {markets}: wrote {run / 'best' / 'markets.json'}")
    result = write_signoff(run, out, robustness=robustness_dir, validation=validation_dir,
                           eol=eol_dir, reviewer=reviewer, pdf=pdf, progress=progress,
                           allow_other_setting=allow_other_setting, min_yield=min_yield)
    for why in result.other_setting:
        click.echo(f"warning: {why}: signed anyway (--allow-other-setting)", err=True)
    yield_text = ("robustness not run" if result.yield_ is None
                  else f"yield {100 * result.yield_:.1f} %")
    click.echo(f"ECs at the display: {'all pass' if result.nominal_passed else 'not all pass'}"
               f"; {yield_text}; params {result.params_file} sha256 {result.params_sha256}")
    if result.markets_text is not None:
        click.echo(f"markets: {result.markets_text}")
    click.echo(f"guidelines: {result.guidelines_text}")
    click.echo(f"wrote {result.html}" + ("" if result.pdf is None else f", {result.pdf}"))
    unjudged = [ch.name.lower() for ch in result.checks if ch.passed is None]
    click.echo(f"verdict: {'PASS' if result.passed else 'FAIL'}"
               + ("" if not unjudged else f" (not judged: {'; '.join(unjudged)})"))
    if not result.passed:
        failing = [f"{ch.name}: {ch.detail}" for ch in result.checks if ch.passed is False]
        click.echo(f"the sheet fails: {'; '.join(failing)}", err=True)
        sys.exit(1)
