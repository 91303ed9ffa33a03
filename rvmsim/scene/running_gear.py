"""The car's running gear in the scene's ``vehicle`` section: wheelbase, rear overhang, track,
the lock angle and the steering gear, for the parking guidelines (:mod:`rvmsim.guidelines`).
None of them is part of the render key.  Metres and degrees."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from .fields import _Model

__all__ = ["RunningGearKeys"]


class RunningGearKeys(_Model):
    """The running-gear keys of :class:`~rvmsim.scene.Vehicle` (all optional; the guidelines
    need them all: :meth:`running_gear_problem`)."""

    #: Front axle to rear axle, m.
    wheelbase: Annotated[float, Field(ge=1.0, le=10.0)] | None = Field(default=None, exclude=True)
    #: Rear axle to the rear-most point (the scene frame's origin plane), m.
    rear_overhang: Annotated[float, Field(ge=0.1, le=5.0)] | None = Field(default=None,
                                                                            exclude=True)
    #: Rear track (wheel centre to wheel centre), m.
    track: Annotated[float, Field(ge=0.5, le=4.0)] | None = Field(default=None, exclude=True)
    #: The inner front wheel's angle at full lock, degrees.
    max_road_wheel_deg: Annotated[float, Field(gt=0, le=70)] | None = Field(default=None,
                                                                             exclude=True)
    #: Steering-wheel degrees per degree of road-wheel angle (single-track equivalent).
    steering_ratio: Annotated[float, Field(ge=1.0, le=60.0)] | None = Field(default=None,
                                                                            exclude=True)
    #: [steering-wheel deg, road-wheel deg] rows from [0, 0], both increasing (mirrored for
    #: the other side): a non-linear steering gear instead of ``steering_ratio``.
    steering_table: Annotated[
        list[tuple[Annotated[float, Field(ge=0, le=1440)], Annotated[float, Field(ge=0, le=70)]]],
        Field(min_length=2, max_length=64)] | None = Field(default=None, exclude=True)

    @model_validator(mode="after")
    def _running_gear(self) -> RunningGearKeys:
        if self.steering_ratio is not None and self.steering_table is not None:
            raise ValueError("give steering_ratio or steering_table, not both")
        table = self.steering_table
        if table is not None:
            if tuple(table[0]) != (0.0, 0.0):
                raise ValueError("steering_table must start at [0, 0]")
            for (w0, r0), (w1, r1) in zip(table, table[1:]):
                if not (w1 > w0 and r1 > r0):
                    raise ValueError("steering_table: both angles must increase row by row")
        return self

    def running_gear_problem(self) -> tuple[str, str] | None:
        """(key, message) of the first running-gear key the guidelines need that is missing,
        or None when wheelbase, rear overhang, track, lock angle and steering are all given."""
        for key in ("wheelbase", "rear_overhang", "track", "max_road_wheel_deg"):
            if getattr(self, key) is None:
                return f"vehicle.{key}", "missing: the guidelines need the car's running gear"
        if self.steering_ratio is None and self.steering_table is None:
            return ("vehicle.steering_ratio", "missing (or steering_table): the trajectory "
                    "lines need the steering gear")
        return None
