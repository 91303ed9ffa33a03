"""The calibration board's layout, as the validation sees it: its inner-corner grid and its
black and white squares.

:class:`BoardLayout` lists the board's inner corners in grid order and the centres of its
squares with their colours.  :class:`BoardShade` scores a camera pose by how well the
board's squares, seen from that pose, explain the capture's grey levels; a checker pose one
square off diagonally explains every inner corner, but not the board's outer ring of
squares, so this score tells the true pose from its one-square aliases.

Colour convention (as :mod:`rvmsim.scene` builds the board): square (i, j), counted from
the board's corner at −a, −b (``a`` along its width, ``b`` along its height, see
:func:`rvmsim.scene.board_frame`), is black when i + j is even; so the corner square at
−a, −b is black.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.  Scene frame as in :mod:`rvmsim.camera.mount`, metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera
from ..scene import CheckerCorner, Scene, board_frame, board_point
from .charuco import CharucoPattern

__all__ = ["BoardLayout", "BoardShade", "board_layout"]


@dataclass(frozen=True)
class BoardLayout:
    """The board's inner corners and squares.

    Attributes
    ----------
    grid : (nx, ny) int
        Inner corners along the board's width (``a``) and height (``b``).
    corner_index : (nx, ny) int
        Index of inner corner (i, j) (i along ``a``) in the scene's checker-corner list.
    corner_points : (nx, ny, 3) float
        The inner corners' scene points, m.
    square_points : (M, 3) float
        Sample points on the squares (the centre and four points ±0.3 square from it; on a
        ChArUco board's white squares, four points in the ring around the marker), m.
    square_shade : (M,) float
        Their colour: 0 black, 1 white.
    origin, a, b, normal : (3,) float
        Inner corner (0, 0) and the board's unit axes and front normal, scene frame.
    square_size : float
        m.
    charuco : CharucoPattern or None
        The board's markers, when it is a ChArUco board (its white squares are then sampled
        only in the white ring around the marker).
    """

    grid: tuple[int, int]
    corner_index: np.ndarray
    corner_points: np.ndarray
    square_points: np.ndarray
    square_shade: np.ndarray
    origin: np.ndarray
    a: np.ndarray
    b: np.ndarray
    normal: np.ndarray
    square_size: float
    charuco: CharucoPattern | None = None

    @property
    def symmetric(self) -> bool:
        """True when a half turn maps the colours onto themselves (squares along width +
        height even): then colour alone cannot tell the board from its half-turned self."""
        return (self.grid[0] + self.grid[1]) % 2 == 0

    def local_points(self) -> np.ndarray:
        """The inner corners in the board's own plane (nx, ny, 3): (along a, along b, 0) m
        from inner corner (0, 0)."""
        d = self.corner_points - self.origin
        return np.stack([d @ self.a, d @ self.b, np.zeros(self.grid)], axis=-1)


def board_layout(scene: Scene, corners: tuple[CheckerCorner, ...]) -> BoardLayout | None:
    """The enabled board's layout, with its corners' indices in ``corners``; None when the
    scene has no board (or its inner corners are not all in ``corners``)."""
    board = scene.test_site.board
    if not board.enabled:
        return None
    nx, ny = board.squares[0] - 1, board.squares[1] - 1
    by_name = {c.name: n for n, c in enumerate(corners) if c.label == L.BOARD}
    try:
        index = np.array([[by_name[f"board_inner_{i + 1}_{j + 1}"] for j in range(ny)]
                          for i in range(nx)])
    except KeyError:
        return None
    pts = np.array([c.point for c in corners])[index]
    _, a, b, nrm = board_frame(board)
    w, h = board.size
    s = board.square_size
    a0, b0 = -w / 2 + board.margin, -h / 2 + board.margin
    offsets: tuple[tuple[float, float], ...] = ((0.5, 0.5), (0.2, 0.2), (0.8, 0.2),
                                                (0.2, 0.8), (0.8, 0.8))
    charuco = None
    ring = offsets
    if board.pattern == "charuco" and board.marker_size is not None:
        charuco = CharucoPattern((board.squares[0], board.squares[1]), s, board.marker_size,
                                 board.aruco_dictionary)
        f = (1.0 - board.marker_size / s) / 4  # the middle of the white ring around a marker
        ring = ((0.5, f), (0.5, 1 - f), (f, 0.5), (1 - f, 0.5))
    samples, shade = [], []
    for i in range(board.squares[0]):
        for j in range(board.squares[1]):
            for oa, ob in (offsets if (i + j) % 2 == 0 else ring):
                samples.append(board_point(board, a0 + (i + oa) * s, b0 + (j + ob) * s))
                shade.append(float((i + j) % 2))
    return BoardLayout((nx, ny), index, pts, np.array(samples), np.array(shade),
                       pts[0, 0].copy(), np.asarray(a, float), np.asarray(b, float),
                       np.asarray(nrm, float), float(s), charuco)


@dataclass(frozen=True)
class BoardShade:
    """How well the board's squares, seen from a pose, explain the capture's grey levels.

    Attributes
    ----------
    layout : BoardLayout
    camera : FisheyeCamera
        Intrinsics and lens (its pose is not used).
    grey : (H, W) float32
        The capture's grey level.
    """

    layout: BoardLayout
    camera: FisheyeCamera
    grey: np.ndarray

    def shifts(self) -> list[np.ndarray]:
        """Camera moves (scene frame, m) that map the board's checker onto itself with the
        same colours: (du, dv) squares along the board's axes, du + dv even, up to two
        squares each way."""
        s, a, b = self.layout.square_size, self.layout.a, self.layout.b
        return [s * (du * a + dv * b) for du in range(-2, 3) for dv in range(-2, 3)
                if (du + dv) % 2 == 0 and (du, dv) != (0, 0)]

    def __call__(self, position: np.ndarray, rotation: np.ndarray) -> float:
        """The correlation (-1..1) of the squares' colours with the capture's grey level
        at their projections from the pose (position m, camera-to-scene rotation); -1 when
        fewer than 8 samples fall inside the image or their colour is constant."""
        import cv2

        rays = (self.layout.square_points - position) @ rotation
        uv, in_fov = self.camera.project_rays(rays)
        h, w = self.grey.shape
        ok = in_fov & (uv[:, 0] >= 0) & (uv[:, 1] >= 0) \
            & (uv[:, 0] <= w - 1) & (uv[:, 1] <= h - 1)
        if ok.sum() < 8 or np.ptp(self.layout.square_shade[ok]) == 0:
            return -1.0
        pts = uv[ok].astype(np.float32).reshape(-1, 1, 2)
        values = cv2.remap(self.grey, pts[..., 0], pts[..., 1], cv2.INTER_LINEAR).ravel()
        if np.ptp(values) == 0:
            return -1.0
        return float(np.corrcoef(self.layout.square_shade[ok], values)[0, 1])
