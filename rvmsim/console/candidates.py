"""The candidates the console offers to load are the run's diverse top-M
(:func:`rvmsim.runs.store_candidates`, as its ``top/`` files, ``status`` and ``select``
offer them); here, their JSON for the page.
"""

from __future__ import annotations

import math
from typing import Any

from ..isp import params_to_dict
from ..runs import Candidate

__all__ = ["Candidate", "candidate_json"]


def candidate_json(c: Candidate) -> dict[str, Any]:
    """A candidate as the page reads it (JSON, to be sent)."""
    return {"rank": int(c.rank), "trial": int(c.trial), "score": float(c.score),
            "passed": bool(c.passed), "params": params_to_dict(c.params),
            "distance": float(c.distance), "differs": str(c.differs),
            "margins": {str(k): (float(v) if math.isfinite(float(v)) else None)
                        for k, v in dict(c.margins).items()}}  # NaN: not measured
