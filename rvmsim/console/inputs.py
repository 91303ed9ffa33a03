"""Checking what the browser sends: parameter values, labels and options.

Every problem is a :class:`ConsoleInputError`, one line naming the key, which the app
answers with a 4xx JSON error that the page shows; nothing from the browser reaches the
evaluation unchecked.
"""

from __future__ import annotations

import re

from ..errors import RvmsimError
from ..isp import PARAM_SPECS, IspParams

__all__ = ["ConsoleInputError", "parse_params", "parse_label", "parse_flag", "parse_steering",
           "MAX_LABEL"]

_SPEC = {s.name: s for s in PARAM_SPECS}
#: Longest label of a saved file (characters, after sanitising).
MAX_LABEL = 40


class ConsoleInputError(RvmsimError):
    """A bad value from the browser: ``key`` names it, ``status`` is the HTTP status."""

    def __init__(self, key: str, message: str, status: int = 422):
        super().__init__(f"{key}: {message}" if key else message)
        self.key = key
        self.status = status


def parse_params(doc: object, base: IspParams) -> IspParams:
    """The parameters of a request body's ``params`` mapping (name → number); names left
    out keep their value in ``base``.

    Raises
    ------
    ConsoleInputError
        Not a mapping, an unknown name, a non-number, a value outside its range.
    """
    if not isinstance(doc, dict):
        raise ConsoleInputError("params", "expected an object of parameter names and values")
    changes: dict[str, float] = {}
    for key, value in doc.items():
        spec = _SPEC.get(key) if isinstance(key, str) else None
        if spec is None:
            raise ConsoleInputError(str(key)[:40], "unknown ISP parameter")
        problem = spec.problem(value)
        if problem is not None:
            raise ConsoleInputError(key, problem)
        changes[key] = float(value)
    return base.replace(**changes)


def parse_label(value: object) -> str:
    """A label for a file name: letters, digits, ``-`` and ``_`` only (anything else
    becomes ``-``), at most :data:`MAX_LABEL` characters; "" for none."""
    if value is None:
        return ""
    if not isinstance(value, str):
        raise ConsoleInputError("label", "must be text")
    return re.sub(r"[^A-Za-z0-9_-]+", "-", value).strip("-_")[:MAX_LABEL]


def parse_flag(value: object, key: str) -> bool:
    """A true/false option (missing: false)."""
    if value is None:
        return False
    if not isinstance(value, bool):
        raise ConsoleInputError(key, "must be true or false")
    return value


def parse_steering(value: object, key: str = "steering_pct") -> float:
    """A steering angle as a percentage of the car's steering range: a number in
    [−100, 100] (missing: 0, straight ahead).

    Raises
    ------
    ConsoleInputError
        Not a number, or outside [−100, 100].
    """
    if value is None:
        return 0.0
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConsoleInputError(key, "must be a number (% of the steering range)")
    if not -100.0 <= float(value) <= 100.0:  # NaN fails too
        raise ConsoleInputError(key, f"{value} is outside [-100, 100] % of the steering range")
    return float(value) + 0.0
