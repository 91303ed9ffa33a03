"""The schema of a scene's ``eol`` section: the end-of-line (EOL) station's target.

At the end of the line each car stands at a station in front of a known target; the camera's
pose is measured from the target's checker corners (``rvmsim eol``, docs/eol.md).  The
section names the target and, optionally, where the station puts it::

    eol:
      target: calibration mat      # "board", or the name of a ground pattern: the
                                   #   station's own (below) or one of the test site's
      pose:                        # optional: where the station puts it (default: where
        origin: [-3.0, 0.5]        #   it is defined); a pattern: origin, yaw_deg
        yaw_deg: 0

    eol:
      target: station mat
      ground_patterns:             # optional: the station's own targets (a mat that is
        - name: station mat        #   not at the FMVSS test site); GroundPattern's keys
          origin: [-3.0, 0.5]
          square_size: 0.4
          checker: [[0, 0, 6, 2], [0, -3, 1.8, 0], [4.2, -3, 6, 0]]

    eol:
      target: board                # eol.board if given, else test_site.board
      board: {placement: upright, position: [0, -0.7, 1.2], squares: [7, 10],
              square_size: 0.1, pattern: charuco, marker_size: 0.075}
      pose:                        # a board: placement, position, yaw_deg, pitch_deg,
        placement: upright         #   roll_deg (each left out keeps the board's own)

A target's layout (squares, their size, a ChArUco board's markers, a mat's circles) is its
definition's; ``pose`` only moves it.  The station's own targets (``board``,
``ground_patterns``) are not part of the test site the ECs are judged on.  The station has
nothing but its target: no FMVSS test objects or guidelines, no other board or pattern
(:func:`rvmsim.scene.station_scene`).  The load state the car stands at is the compensation
model's ``station.measured_at``.

Conventions
-----------
Scene frame and units as in :mod:`rvmsim.scene.schema` (metres, degrees); a board's
``position`` is the centre of its face, a pattern's ``origin`` an (x, z) ground point.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, ValidationInfo, field_validator

from .board import PatternBoard
from .fields import Angle180, Metres, Vec3, _Model
from .pattern import GroundPattern

__all__ = ["EolSpec", "EolPose", "BOARD_TARGET", "BOARD_POSE_KEYS", "PATTERN_POSE_KEYS"]

#: ``target`` naming the scene's pattern board (``test_site.board``).
BOARD_TARGET = "board"
#: The keys of ``pose`` that place a board, and those that place a ground pattern.
BOARD_POSE_KEYS = ("placement", "position", "yaw_deg", "pitch_deg", "roll_deg")
PATTERN_POSE_KEYS = ("origin", "yaw_deg")


class EolPose(_Model):
    """Where the station puts its target; every key optional (a key left out keeps the test
    site's value).  A board takes :data:`BOARD_POSE_KEYS` (as
    :class:`~rvmsim.scene.PatternBoard`), a ground pattern :data:`PATTERN_POSE_KEYS` (as
    :class:`~rvmsim.scene.GroundPattern`)."""

    placement: Literal["ground", "upright", "free"] | None = None
    position: Vec3 | None = None
    origin: tuple[Metres, Metres] | None = None
    yaw_deg: Angle180 | None = None
    pitch_deg: Annotated[float, Field(ge=-90, le=90)] | None = None
    roll_deg: Angle180 | None = None

    def overrides(self) -> dict[str, object]:
        """The keys given, with their values."""
        return {k: getattr(self, k) for k in self.model_fields_set}


class EolSpec(_Model):
    """The EOL station's target (``target``: ``board`` or a ground pattern's ``name``), the
    station's own targets (``board``, ``ground_patterns``: not at the test site) and,
    optionally, the target's placement there (``pose``)."""

    target: Annotated[str, Field(min_length=1, max_length=80)]
    board: PatternBoard | None = None
    ground_patterns: Annotated[list[GroundPattern], Field(max_length=20)] = []
    pose: EolPose | None = None

    @property
    def is_board(self) -> bool:
        """Whether the target is the scene's pattern board."""
        return self.target == BOARD_TARGET

    @field_validator("board")
    @classmethod
    def _board_is_target(cls, board: PatternBoard | None,
                         info: ValidationInfo) -> PatternBoard | None:
        target = info.data.get("target")
        if board is not None and target is not None and target != BOARD_TARGET:
            raise ValueError(f"the station's board is given but the target is {target!r} "
                             f"(name {BOARD_TARGET!r} as the target, or leave the board out)")
        return board

    @field_validator("pose")
    @classmethod
    def _pose_keys(cls, pose: EolPose | None, info: ValidationInfo) -> EolPose | None:
        if pose is None:
            return pose
        board = info.data.get("target") == BOARD_TARGET
        allowed = BOARD_POSE_KEYS if board else PATTERN_POSE_KEYS
        wrong = sorted(set(pose.model_fields_set) - set(allowed))
        if wrong:
            kind = "a board" if board else "a ground pattern"
            raise ValueError(f"{', '.join(wrong)} cannot place {kind} (its keys: "
                             f"{', '.join(allowed)})")
        return pose
