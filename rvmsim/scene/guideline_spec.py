"""The parking guidelines' spec (the scene's ``guidelines:`` section, or its own file) and the
lines painted on the site's ground to check them (:mod:`rvmsim.guidelines`).

Distances are metres behind the vehicle's rear-most point (the scene frame's +Z, origin on
the ground below that point); colours are RGB in 0–1; display widths in px of the RVM image
of record.  The bundled default (``rvmsim/guidelines/guidelines_default.yaml``) draws the
common production set: 0.5 m red, 1 m yellow, 2 m and 3 m green marks, width lines at the
car's width, and trajectory lines of the rear corners over 3 m of travel.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, model_validator

from .fields import Metres, NonNegFloat, PositiveFloat, Rgb, _Model

__all__ = ["DistanceMark", "WidthLines", "TrajectoryLines", "GuidelineSpec", "PaintedLine",
           "MAX_MARKS", "MAX_PAINTED_LINES", "LineKind"]

#: The kinds of guideline.
LineKind = Literal["mark", "width", "trajectory"]
#: Most distance marks a spec may give.
MAX_MARKS = 12
#: Most lines painted on the ground at once (labels 60–99, :func:`rvmsim.labels.guide_paint`).
MAX_PAINTED_LINES = 40

_Distance = Annotated[float, Field(gt=0, le=50)]
_WidthPx = Annotated[float, Field(gt=0, le=64)]


class DistanceMark(_Model):
    """A static mark across the path at ``distance`` m behind the rear-most point.

    ``length`` None: one line across, between the width lines; a length (m): two ticks of
    that length, each from a width line inward (the usual design for the far marks).
    """

    distance: _Distance
    color: Rgb = (0.1, 0.85, 0.2)
    length: PositiveFloat | None = None


class WidthLines(_Model):
    """The two lines at the car's width plus ``margin`` m each side, from ``start`` to ``end``
    m behind the rear-most point."""

    enabled: bool = True
    margin: Annotated[float, Field(ge=-0.5, le=2.0)] = 0.0
    start: NonNegFloat = 0.0
    end: _Distance = 3.0
    color: Rgb = (0.95, 0.85, 0.1)

    @model_validator(mode="after")
    def _order(self) -> WidthLines:
        if self.end <= self.start:
            raise ValueError(f"end ({self.end}) must be beyond start ({self.start})")
        return self


class TrajectoryLines(_Model):
    """The paths of the two rear corners (at the width lines' lateral place) while the car
    reverses ``travel`` m (arc length of the rear axle's centre) at a constant steering
    angle (:mod:`rvmsim.guidelines.kinematics`)."""

    enabled: bool = True
    travel: _Distance = 3.0
    color: Rgb = (0.95, 0.55, 0.05)


class GuidelineSpec(_Model):
    """What the guidelines draw (see the module docstring)."""

    marks: Annotated[list[DistanceMark], Field(max_length=MAX_MARKS)] = [
        DistanceMark(distance=0.5, color=(0.9, 0.1, 0.1)),
        DistanceMark(distance=1.0, color=(0.95, 0.85, 0.1)),
        DistanceMark(distance=2.0, color=(0.1, 0.85, 0.2), length=0.3),
        DistanceMark(distance=3.0, color=(0.1, 0.85, 0.2), length=0.3),
    ]
    width_lines: WidthLines = WidthLines()
    trajectory: TrajectoryLines = TrajectoryLines()
    #: Drawn line width on the RVM image of record, px.
    line_width_px: _WidthPx = 4.0
    #: Ground sampling of every line, m (finer: smoother curves, more table points).
    step: Annotated[float, Field(ge=0.005, le=0.5)] = 0.02

    @model_validator(mode="after")
    def _check(self) -> GuidelineSpec:
        distances = [m.distance for m in self.marks]
        if distances != sorted(set(distances)):
            raise ValueError("marks: distances must be increasing, each given once")
        return self


class PaintedLine(_Model):
    """A line painted on the ground (the guidelines' check, :mod:`rvmsim.guidelines.check`):
    a strip ``width`` m wide along the polyline ``points`` ((x, z) m, scene frame), with its
    own label (:func:`rvmsim.labels.guide_paint` of ``index``).  Set by the check, not a
    YAML key."""

    index: Annotated[int, Field(ge=0, lt=MAX_PAINTED_LINES)]
    points: tuple[tuple[Metres, Metres], ...]
    #: The guideline painted: its name and kind (``mark``, ``width``, ``trajectory``), and a
    #: trajectory's steering-wheel angle, degrees.
    name: str = ""
    kind: LineKind = "mark"
    steering_deg: Annotated[float, Field(ge=-1440, le=1440)] | None = None
    width: Annotated[float, Field(gt=0, le=1.0)] = 0.05
    color: Rgb = (0.95, 0.95, 0.95)

    @model_validator(mode="after")
    def _two_points(self) -> PaintedLine:
        if len(self.points) < 2:
            raise ValueError("a painted line needs two points at least")
        return self
