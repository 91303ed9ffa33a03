"""The candidates the console offers to load: the run's diverse top-M
(:func:`rvmsim.tune.diverse_candidates`, as its ``top/`` files, ``status`` and ``select``
offer them), and their JSON for the page.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ..isp import params_to_dict
from ..tune import Candidate, diverse_candidates

__all__ = ["Candidate", "candidate_json"]


def _candidates(run_dir: str | Path) -> list[Candidate]:
    """The run's diverse top-M (its tuning config's M and minimum distance), rank 1 first."""
    return diverse_candidates(run_dir)


def candidate_json(c: Any) -> dict[str, Any]:
    """A candidate (any object with :class:`Candidate`'s fields) as the page reads it."""
    return {"rank": int(c.rank), "trial": int(c.trial), "score": float(c.score),
            "passed": bool(c.passed), "params": params_to_dict(c.params),
            "distance": float(c.distance), "differs": str(c.differs),
            "margins": {str(k): (float(v) if math.isfinite(float(v)) else None)
                        for k, v in dict(c.margins).items()}}  # NaN: not measured
