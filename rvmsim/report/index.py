"""Reports of many runs: every run's report and an index page linking them
(``rvmsim report RUNS_DIR``), and the command's choice between that and one run's."""

from __future__ import annotations

import os
from pathlib import Path

from .._progress import progress_bar
from ..errors import RvmsimError
from ..storage import StagedFiles
from ..runs import find_runs, is_run_folder
from .page import escape, img_tag, page, url_path
from .run import _STEPS, EC_GROUP_NAMES, _build, _write, write_report

__all__ = ["write_batch_report", "write_any_report"]


def write_batch_report(runs_dir: str | Path, out: str | Path | None = None, *,
                       progress: bool = False) -> Path:
    """Write a report for every run folder in ``runs_dir`` and an index page linking them.

    Parameters
    ----------
    runs_dir : path
        A folder of run folders (as ``rvmsim batch`` writes them).
    out : path, optional
        The index file (default: ``runs_dir/index.html``); each run's report goes to its
        own folder as ``report.html`` and is linked relative to the index.
    progress : bool
        Show a progress bar over the runs' report steps on stderr.

    Returns
    -------
    Path
        The index file written.

    Raises
    ------
    RvmsimError
        No run folders in ``runs_dir``, or the index cannot be written.  A run whose
        report cannot be made gets an error row in the index instead.
    """
    runs_dir = Path(runs_dir)
    runs = find_runs(runs_dir)
    if not runs:
        raise RvmsimError(f"{runs_dir}: no run folders (with run.sqlite) here")
    index = Path(out) if out is not None else runs_dir / "index.html"
    head = ("<tr><th>vehicle</th><th>RVM image</th><th>EC score</th>"
            + "".join(f"<th>{escape(g)}-x {escape(n)}</th>" for g, n in EC_GROUP_NAMES.items())
            + "<th>report</th></tr>")
    rows = []
    # every run's report and the index renamed into place when all are written
    with StagedFiles() as staged, progress_bar(total=_STEPS * len(runs), desc="reports",
                                               unit="step", leave=False,
                                               disable=not progress) as bar:
        for k, run in enumerate(runs):
            try:
                text, s = _build(run, None, bar)
                rep = run / "report.html"
                _write(rep, text, staged, s.files)
            except RvmsimError as err:
                rows.append(f'<tr class="fail"><td>{escape(run.name)}</td>'
                            f'<td colspan="{len(EC_GROUP_NAMES) + 3}">{escape(err)}</td></tr>')
                continue
            finally:
                bar.n = _STEPS * (k + 1)  # a run that failed half-way counts as done
                bar.refresh()
            href = url_path(Path(os.path.relpath(rep, index.parent)).as_posix())
            cells = "".join(f'<td class="{st}">{escape(st)}</td>' for st in s.groups.values())
            rows.append(
                f'<tr><td>{escape(s.vehicle)}<br>'
                f'<span class="muted">{escape(run.name)}</span></td>'
                f'<td>{img_tag(s.thumb, s.vehicle)}</td>'
                f'<td class="num {"pass" if s.passed else "fail"}">{s.score:.4g}</td>'
                f'{cells}<td><a href="{escape(href)}">report</a></td></tr>')
        body = (f"<h1>RVM tuning review: {escape(runs_dir.name or str(runs_dir))}</h1>"
                f'<p class="muted">{len(runs)} runs in {escape(runs_dir)}; EC groups pass '
                'when every enabled EC of the group passes.</p>'
                f'<section id="index"><table>{head}{"".join(rows)}</table></section>')
        _write(index, page(f"RVM tuning review: {runs_dir.name}", body), staged)
    return index


def write_any_report(path: str | Path, out: str | Path | None = None, *,
                     progress: bool = False) -> Path:
    """``rvmsim report PATH``: :func:`write_report` if ``path`` is a run folder, else
    :func:`write_batch_report` if it holds run folders.

    Raises
    ------
    RvmsimError
        One line: neither.
    """
    path = Path(path)
    if is_run_folder(path):
        return write_report(path, out, progress=progress)
    if find_runs(path):
        return write_batch_report(path, out, progress=progress)
    raise RvmsimError(f"{path}: not a run folder (no run.sqlite) and no run folders in it")
