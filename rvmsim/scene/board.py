"""The calibration pattern board of a scene (``test_site.board``): a checkerboard or a
ChArUco board, on the ground, upright, or in a free 6-DoF pose.  Its geometry is
:func:`rvmsim.scene.site.board_frame`; its inner corners :func:`rvmsim.scene.checker_corners`."""

from __future__ import annotations

from typing import Annotated, Literal

import cv2
from pydantic import Field, model_validator

from .fields import Angle180, NonNegFloat, PositiveFloat, Vec3, _Model

__all__ = ["PatternBoard"]


class PatternBoard(_Model):
    """Calibration pattern board: a checkerboard with a white margin.

    Pose (``placement``):

    * ``ground`` lays it flat on the ground (its rows running away from the car), turned
      by ``yaw_deg`` about the vertical;
    * ``upright`` stands it vertically facing the car, turned by ``yaw_deg``;
    * ``free`` is a full 6-DoF pose: ``yaw_deg``, ``pitch_deg``, ``roll_deg`` turn the
      upright board (all angles 0 = ``upright``) exactly as the camera's mount angles turn
      the camera (:func:`~rvmsim.camera.rotation_from_ypr`, yaw, then pitch, then roll
      about the board's own axes; pitch > 0 tips its face up (pitch 90 lays it face up with
      the ``ground`` board's axes); roll > 0 turns its u axis toward −v).

    ``position`` is the centre of the board's front surface in the scene frame (metres; a
    ``ground`` board's height is its plate's, so ``y`` is ignored there).

    Colour convention: the board's own axes are ``u`` along its width (``squares[0]``
    columns) and ``v`` along its height (``squares[1]`` rows), from the outer corner of the
    squares at (−width/2 + margin, −height/2 + margin); the square (i, j) (column i along u,
    row j along v) is black when i + j is even, so the corner square at the origin is black.
    With ``placement: ground`` and yaw 0, u is +X and v is +Z (the black corner square is on
    the −X side nearest the car); ``upright``/``free`` with zero angles have u along +X and
    v up (−Y), so the black corner square is bottom left on the −X side as the car sees it.

    ``pattern: charuco`` puts ``cv2.aruco`` markers (``aruco_dictionary``, ``marker_size``
    m wide) in the white squares, as ``cv2.aruco.CharucoBoard(squares, square_size,
    marker_size, dictionary)`` draws them (with ``setLegacyPattern(True)`` when
    ``squares[1]`` is even), its image's top row at the board's +v edge.

    The defaults, 4 × 6 squares of 0.14 m (0.64 m × 0.92 m with its margin) lying between
    cross guidelines 2 and 3, look about square from a rear-view camera, as EC 4-1 expects of
    a calibration board.  The bundled vehicles use 8 × 12 squares of 0.07 m (the same outer
    size), which conditions a fisheye calibration better.
    """

    enabled: bool = True
    squares: tuple[Annotated[int, Field(ge=2, le=200)], Annotated[int, Field(ge=2, le=200)]] = (4, 6)
    square_size: PositiveFloat = 0.14
    margin: NonNegFloat = 0.04
    placement: Literal["ground", "upright", "free"] = "ground"
    position: Vec3 = (0.0, 0.0, 1.5)
    yaw_deg: Angle180 = 0.0
    pitch_deg: Annotated[float, Field(ge=-90, le=90)] = 0.0
    roll_deg: Angle180 = 0.0
    pattern: Literal["checker", "charuco"] = "checker"
    aruco_dictionary: str = "DICT_4X4_50"
    marker_size: PositiveFloat | None = None

    @model_validator(mode="after")
    def _check(self) -> PatternBoard:
        if self.placement != "free" and (self.pitch_deg or self.roll_deg):
            raise ValueError(f"pitch_deg and roll_deg need placement: free "
                             f"(placement is {self.placement})")
        if self.pattern == "checker":
            if self.marker_size is not None:
                raise ValueError("marker_size is for pattern: charuco")
            return self
        if self.marker_size is None or self.marker_size >= self.square_size:
            raise ValueError("pattern charuco needs marker_size (m) below square_size")

        code = getattr(cv2.aruco, self.aruco_dictionary, None)
        if not self.aruco_dictionary.startswith("DICT_") or not isinstance(code, int):
            raise ValueError(f"aruco_dictionary {self.aruco_dictionary!r} is not a "
                             "cv2.aruco dictionary (e.g. DICT_4X4_50)")
        have = cv2.aruco.getPredefinedDictionary(code).bytesList.shape[0]
        need = self.squares[0] * self.squares[1] // 2
        if need > have:
            raise ValueError(f"{self.aruco_dictionary} has {have} markers, the board "
                             f"needs {need}")
        return self

    @property
    def size(self) -> tuple[float, float]:
        """(width, height) of the whole board, metres."""
        return (
            self.squares[0] * self.square_size + 2 * self.margin,
            self.squares[1] * self.square_size + 2 * self.margin,
        )
