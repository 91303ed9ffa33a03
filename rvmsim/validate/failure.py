"""A validation that could not finish, and which of its steps failed.

The steps are the pose search's (:class:`rvmsim.pose.PoseFailure`); a validation's failure
carries the pictures made so far.  A failed ``check`` is not an error: it is a verdict
(:class:`.verdict.Validation`, exit status 1).
"""

from __future__ import annotations

from ..pose import PoseFailure

__all__ = ["ValidationFailure"]


class ValidationFailure(PoseFailure):
    """One-line error naming the failed step of a validation, with its pictures
    (``overlay``, ``edges``, ``landmarks``): a :class:`rvmsim.pose.PoseFailure` that
    ``rvmsim validate`` writes the pictures of."""
