"""Field types shared by the scene schema's models: bounded metres, degrees, pixels, colours,
and the strict base model (unknown keys and non-finite floats are errors)."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

__all__ = ["MAX_METRES", "Metres", "PositiveFloat", "NonNegFloat", "PositivePx", "Px",
           "Angle180", "Rgb", "Vec3", "Rect"]

#: Largest distance in a scene (metres): every length and coordinate lies within it.
MAX_METRES = 1000.0
Metres = Annotated[float, Field(ge=-MAX_METRES, le=MAX_METRES)]
PositiveFloat = Annotated[float, Field(gt=0, le=MAX_METRES)]
NonNegFloat = Annotated[float, Field(ge=0, le=MAX_METRES)]
#: Intrinsics in px (focal lengths px/rad), checked against the image size when loaded.
PositivePx = Annotated[float, Field(gt=0, le=1e7)]
Px = Annotated[float, Field(ge=-1e7, le=1e7)]
Angle180 = Annotated[float, Field(ge=-180, le=180)]
Rgb = tuple[
    Annotated[float, Field(ge=0, le=1)],
    Annotated[float, Field(ge=0, le=1)],
    Annotated[float, Field(ge=0, le=1)],
]
Vec3 = tuple[Metres, Metres, Metres]


class _Model(BaseModel):
    # Every float finite: a NaN or an infinity anywhere is an error naming its key.
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


Rect = tuple[Metres, Metres, Metres, Metres]
