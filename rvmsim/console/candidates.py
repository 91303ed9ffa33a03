"""The candidates the console offers to load: a run's top-M.

Issue #17 item 1 adds :func:`rvmsim.tune.diverse_candidates` (genuinely different top-M);
until it is on main, :func:`_candidates` builds objects with the same fields from the run's
store.  It is the one place to switch over.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from ..isp import IspParams, params_to_dict
from ..tune import open_run, run_settings

__all__ = ["Candidate", "candidate_json"]


@dataclass(frozen=True)
class Candidate:
    """One candidate of a run, as :func:`rvmsim.tune.diverse_candidates` gives it.

    ``rank`` counts from 1; ``trial`` is its index in the run's store; ``score`` its EC
    score; ``passed`` whether every enabled EC passes; ``distance`` its distance from rank 1
    in normalised parameter space; ``differs`` one line saying how it differs from rank 1;
    ``margins`` each EC's margin inside its acceptable range.
    """

    rank: int
    trial: int
    score: float
    passed: bool
    params: IspParams
    distance: float = 0.0
    differs: str = ""
    margins: Mapping[str, float] = field(default_factory=dict)


def _candidates(run_dir: str | Path) -> list[Candidate]:
    """The run's top-M (M = its tuning config's ``top_m``), best first.

    The adapter until ``rvmsim.tune.diverse_candidates(run_dir)`` lands: replace its body
    with that call.
    """
    store = open_run(run_dir)
    try:
        top = store.top(run_settings(run_dir, store).config.top_m)
    finally:
        store.close()
    return [Candidate(rank=k, trial=rec.idx, score=rec.score, passed=rec.passed,
                      params=rec.params) for k, rec in enumerate(top, start=1)]


def candidate_json(c: Any) -> dict[str, Any]:
    """A candidate (any object with :class:`Candidate`'s fields) as the page reads it."""
    return {"rank": int(c.rank), "trial": int(c.trial), "score": float(c.score),
            "passed": bool(c.passed), "params": params_to_dict(c.params),
            "distance": float(c.distance), "differs": str(c.differs),
            "margins": {str(k): float(v) for k, v in dict(c.margins).items()}}
