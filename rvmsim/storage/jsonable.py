"""JSON of the values rvmsim stores and writes (run and sweep databases, result files)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["json_default"]


def json_default(o: Any) -> Any:
    """``json.dumps(..., default=json_default)``: numpy scalars (float32, integers) as Python
    numbers.  (Python and float64 NaN never reach ``default``: json writes them itself.)"""

    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    raise TypeError(f"{type(o).__name__} is not JSON serializable")
