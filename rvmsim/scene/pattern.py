"""A flat pattern on the ground (``test_site.ground_patterns``, a station's own targets in
``eol.ground_patterns``): a calibration mat, painted squares.  Its geometry is
:func:`rvmsim.scene.pattern_point`; its inner corners :func:`rvmsim.scene.checker_corners`."""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import Field, model_validator

from .fields import Metres, PositiveFloat, Rect, Rgb, _Model, Angle180

__all__ = ["GroundPattern"]


class GroundPattern(_Model):
    """A flat black-and-white pattern lying on the ground: a calibration mat, painted squares.

    The pattern has its own frame on the ground: ``u`` along the scene's +X and ``v`` along
    +Z when ``yaw_deg`` is 0, in metres from ``origin`` (an (x, z) point of the scene).  A
    checker of ``square_size`` squares covers the ``checker`` rectangles ``[u0, v0, u1, v1]``;
    its squares start at the origin and the square ``[0, s] × [0, s]`` is black.  Squares cut
    by a rectangle's border are cut there.  ``white`` rectangles are plain white and lie over
    the checker (a mat's circle squares); ``circles`` ``[u, v, diameter]`` are black discs
    over everything.  Every corner where four whole checker squares meet (and no white
    rectangle or circle touches them) is a landmark for ``rvmsim validate``.
    """

    name: str = "ground pattern"
    origin: tuple[Metres, Metres] = (0.0, 0.0)
    yaw_deg: Angle180 = 0.0
    square_size: PositiveFloat
    checker: Annotated[list[Rect], Field(min_length=1)]
    white: list[Rect] = []
    circles: list[tuple[Metres, Metres, PositiveFloat]] = []
    black_color: Rgb = (0.03, 0.03, 0.03)
    white_color: Rgb = (0.92, 0.92, 0.92)

    @model_validator(mode="after")
    def _check(self) -> GroundPattern:
        for key in ("checker", "white"):
            for i, (u0, v0, u1, v1) in enumerate(getattr(self, key)):
                if not (u1 > u0 and v1 > v0):
                    raise ValueError(f"{key}[{i}]: a rectangle is [u0, v0, u1, v1] with "
                                     f"u1 > u0 and v1 > v0, got {[u0, v0, u1, v1]}")
        cells = sum(
            math.ceil((u1 - u0) / self.square_size + 1) * math.ceil((v1 - v0) / self.square_size + 1)
            for u0, v0, u1, v1 in self.checker
        )
        if cells > 20000:
            raise ValueError(f"the checker has about {cells} squares (at most 20000): "
                             "is square_size in metres?")
        return self
