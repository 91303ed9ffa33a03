"""What ``rvmsim tune`` prints at the end of a run (:func:`summary_lines`): the search's
counts, the best candidate, a robust run's yield and a markets or shared run's verdicts."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from .markets import market_summary_lines
from .shared import shared_problem_lines

if TYPE_CHECKING:
    from .run import TuneResult

__all__ = ["summary_lines"]


def summary_lines(result: TuneResult) -> list[str]:
    """What ``rvmsim tune`` prints at the end: the search's counts and stop reason, and the
    best candidate's EC table (as ``best/ec_table.txt`` holds it)."""
    o, best = result.outcome, result.outcome.best
    if best is None:
        return ["no trials"]
    robust = _robust_line(result.run_dir)
    idx, score = best.idx, best.score
    shown = result.run_dir / "best" / "ec.json"
    if robust and shown.is_file():  # a robust run's rank 1 is not always its best score
        idx = int(json.loads(shown.read_text()).get("trial", idx))
        score = json.loads((result.run_dir / "best" / "robust.json").read_text())[
            "top"][0]["robust_score"]
    head = (f"{result.run_dir}: {o.evaluated} evaluated, {o.replayed} replayed in "
            f"{o.seconds:.1f} s ({o.stopped}); best EC score {score:.4g} (trial {idx})")
    markets = market_summary_lines(result.run_dir)
    if markets:
        return [head, (result.run_dir / "best" / "ec_table.txt").read_text().rstrip(), "",
                *markets]
    problems = shared_problem_lines(result.run_dir)
    return [head, *robust, (result.run_dir / "best" / "ec_table.txt").read_text().rstrip(),
            *(["", "no setting found passes every scene:", *(f"  {p}" for p in problems)]
              if problems else [])]


def _robust_line(run_dir: Path) -> list[str]:
    """A robust run's best candidate as ``best/robust.json`` has it (none for other runs)."""
    path = run_dir / "best" / "robust.json"
    if not path.is_file():
        return []
    doc = json.loads(path.read_text())
    if not doc.get("top"):
        return []
    t = doc["top"][0]
    lo, hi = t["yield_ci"]
    lines = [f"robust: nominal EC score {t['nominal_score']:.4g}, robust ({doc['aggregate']} "
             f"of {t['samples']} samples and nominal) {t['robust_score']:.4g}, yield over the "
             f"samples {100 * t['yield']:.0f} % (95 %: {100 * lo:.0f}–{100 * hi:.0f} %)"]
    if doc.get("compensation") is None and t["yield"] < 1.0 and t.get("limiting_ec"):
        lines.append(f"robust: this yield is what one setting reaches without end-of-line "
                     f"compensation: EC {t['limiting_ec']} fails on "
                     f"{100 * t['limiting_rate']:.0f} % of the samples (per-car values: "
                     "tune --robust --compensation default)")
    return lines
