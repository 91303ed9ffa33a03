"""A validation that could not finish, and which of its steps failed.

Steps, in order: ``detection`` (too few landmarks found in the capture), ``correspondence``
(found corners that cannot be told from a one-square alias), ``pose fit`` (the corners do
not determine the pose).  A failed ``check`` is not an error: it is a verdict
(:class:`.verdict.Validation`, exit status 1).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..errors import RvmsimError

__all__ = ["ValidationFailure", "Step"]

Step = Literal["detection", "correspondence", "pose fit"]


class ValidationFailure(RvmsimError):
    """One-line error naming the failed step, with the pictures made so far.

    Parameters
    ----------
    step : {"detection", "correspondence", "pose fit"}
    message : str
        What went wrong (starts with the capture's name).
    images : dict of str to (H, W, 3) uint8, optional
        Pictures (``overlay``, ``edges``, ``landmarks``) to write for the user.
    found : (N, 2) float, optional
        The landmarks found before the failure (NaN: not found), px.
    """

    def __init__(self, step: Step, message: str, images: dict[str, np.ndarray] | None = None,
                 found: np.ndarray | None = None) -> None:
        super().__init__(f"{message} (step failed: {step})")
        self.step: Step = step
        self.detail = message
        self.images = dict(images or {})
        self.found = found

    def with_images(self, images: dict[str, np.ndarray]) -> ValidationFailure:
        """The same failure carrying ``images``."""
        return ValidationFailure(self.step, self.detail, images, self.found)
