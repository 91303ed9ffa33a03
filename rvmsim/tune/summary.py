"""What ``rvmsim tune`` prints at the end of a run (:func:`summary_lines`): the search's
counts, the best candidate, what the run's kind judged (:class:`rvmsim.tune.Verdict`), and
where the results are and what comes next (:func:`next_steps`)."""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .run import TuneResult

__all__ = ["summary_lines", "next_steps", "signoff_command"]


def summary_lines(result: TuneResult) -> list[str]:
    """What ``rvmsim tune`` prints at the end: the search's counts and stop reason, the best
    candidate (a robust run's rank 1, whose robust score is not always the best EC score),
    then the verdict's lines (EC table, yield, per-market table, why it fails)."""
    o, best = result.outcome, result.outcome.best
    if best is None:
        return ["no trials"]
    idx, score = result.verdict.shown or (best.idx, best.score)
    head = (f"{result.run_dir}: {o.evaluated} evaluated, {o.replayed} replayed in "
            f"{o.seconds:.1f} s ({o.stopped}); best EC score {score:.4g} (trial {idx})")
    return [head, *result.verdict.lines, "", *next_steps(result.run_dir, result.scene)]


def next_steps(run_dir: Path, scene: str | Path | None = None) -> list[str]:
    """Where a finished run's results are, and the commands that come next, each complete
    enough to run as printed (its required options given: the robustness and sign-off
    folders go inside the run folder).

    Parameters
    ----------
    run_dir : Path
        The run folder.
    scene : str or Path, optional
        The run's scene file, for the robustness command (``SCENE`` when not given).
    """
    run = shlex.quote(str(run_dir))
    top = run_dir / "top"
    rob = shlex.quote(str(run_dir / "robustness"))
    scene_arg = shlex.quote(str(scene)) if scene is not None else "SCENE"
    lines = [f"run folder: {run_dir}"]
    if (top / "rank_1.yaml").is_file():
        lines.append(f"best setting: {top / 'rank_1.yaml'} (the diverse top-M: "
                     f"{top / 'rank_K.yaml'}, candidates.json)")
    steps = [(f"rvmsim report {run}", "the HTML report (report.html)"),
             (f"rvmsim console {run}", "adjust any top candidate live in the browser"),
             (f"rvmsim select {run} --rank K -o K.yaml", "export another candidate"),
             (f"rvmsim robustness {scene_arg} --params {shlex.quote(str(top / 'rank_1.yaml'))}"
              f" --out {rob}", "its yield over the mount tolerances"),
             (signoff_command(run_dir), "the sign-off record (HTML, PDF)")]
    width = max(len(c) for c, _ in steps)
    lines += ["next:", *(f"  {c:<{width}}   {what}" for c, what in steps)]
    return lines


def signoff_command(run_dir: Path) -> str:
    """The ``rvmsim signoff`` command of a run, as printed after tuning and in the report:
    the robustness folder :func:`next_steps`' robustness command writes, and the sign-off
    folder, both inside the run folder."""
    q = shlex.quote
    return (f"rvmsim signoff {q(str(run_dir))} --robustness {q(str(run_dir / 'robustness'))} "
            f"--out {q(str(run_dir / 'signoff'))}")
