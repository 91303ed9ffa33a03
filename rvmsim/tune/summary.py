"""What ``rvmsim tune`` prints at the end of a run (:func:`summary_lines`): the search's
counts, the best candidate, and what the run's kind judged (:class:`rvmsim.tune.Verdict`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .run import TuneResult

__all__ = ["summary_lines"]


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
    return [head, *result.verdict.lines]
