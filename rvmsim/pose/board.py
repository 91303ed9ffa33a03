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

import cv2
import numpy as np
from scipy.spatial import cKDTree

from .. import labels as L
from ..camera import FisheyeCamera
from ..scene import CheckerCorner, Scene, board_frame, board_point
from .charuco import CharucoPattern

__all__ = ["BoardLayout", "BoardShade", "LatticeEvidence", "board_layout", "UNFIT"]

#: Samples a pose alone puts on the board fit its colours at least this well when the pose is
#: right (the board is there); squares put on the background fit about half.
UNFIT = 0.6
#: Where the board's local contrast is below this share of its overall contrast, it is
#: hidden (or washed out) and its samples are not evidence.
MIN_LOCAL_CONTRAST = 0.35


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
    margin: float = 0.0

    def local_shade(self, pa: np.ndarray, pb: np.ndarray) -> np.ndarray:
        """The board's colour at board-plane coordinates (``pa``, ``pb``) m from inner corner
        (0, 0) along ``a`` and ``b``: 0 black, 1 white (a square or the margin), −1 off the
        board; NaN (unknown) within 0.15 square of a square's edge (blur mixes the colours
        there), on a ChArUco marker, or near the margin's edges."""
        s = self.square_size
        na, nb = self.grid[0] + 1, self.grid[1] + 1
        ua, ub = pa / s + 1.0, pb / s + 1.0  # in squares from the board's squares' corner
        ia, ib = np.floor(ua), np.floor(ub)
        fa, fb = ua - ia, ub - ib
        inside = (ia >= 0) & (ia < na) & (ib >= 0) & (ib < nb)
        clean = (np.abs(fa - 0.5) <= 0.35) & (np.abs(fb - 0.5) <= 0.35)
        out = np.where(inside, np.where(clean, np.mod(ia + ib, 2), np.nan), -1.0)
        if self.charuco is not None:
            half = 0.5 * self.charuco.marker_size / s + 0.1
            marker = (np.abs(fa - 0.5) < half) & (np.abs(fb - 0.5) < half) & (out == 1)
            out = np.where(marker, np.nan, out)
        m = self.margin / s
        d = np.maximum(np.maximum(-ua, ua - na), np.maximum(-ub, ub - nb))  # squares outside
        buf = min(0.15, m / 4)
        in_margin = (d > 0) & (d < m)
        white = in_margin & (d >= buf) & (d <= m - buf) if m >= 0.1 else np.zeros_like(in_margin)
        out = np.where(in_margin, np.where(white, 1.0, np.nan), out)
        return out

    @property
    def symmetric(self) -> bool:
        """True when a half turn maps the colours onto themselves (squares along width +
        height even): then colour alone cannot tell the board from its half-turned self."""
        return (self.grid[0] + self.grid[1]) % 2 == 0


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
                       np.asarray(nrm, float), float(s), charuco, float(board.margin))


def _local_levels(pix: np.ndarray, grey: np.ndarray, black: np.ndarray,
                  white: np.ndarray, where: np.ndarray,
                  k: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Per sample (of those ``where`` is True; NaN and False elsewhere), the midpoint between
    the capture's black and white levels near it (the medians of its ``k`` nearest ``black``
    and ``white`` samples; pixels ``pix`` (N, 2), grey levels ``grey``), so vignetting and
    uneven light do not shift the threshold; and whether
    the board shows contrast there (at least :data:`MIN_LOCAL_CONTRAST` of the board's
    overall): where it is hidden, both colours look alike and the sample says nothing."""

    at = np.flatnonzero(where)
    levels = []
    for mask in (black, white):
        kk = min(k, int(mask.sum()))
        _, idx = cKDTree(pix[mask]).query(pix[at], k=kk)
        near = grey[mask][np.asarray(idx).reshape(len(at), kk)]
        levels.append(np.partition(near, kk // 2, axis=1)[:, kk // 2])
    overall = float(np.median(grey[white]) - np.median(grey[black]))
    mid, seen = np.full(len(pix), np.nan), np.zeros(len(pix), bool)
    mid[at] = 0.5 * (levels[0] + levels[1])
    seen[at] = levels[1] - levels[0] >= max(MIN_LOCAL_CONTRAST * overall, 4.0)
    return mid, seen


@dataclass(frozen=True)
class LatticeEvidence:
    """What the capture says about two poses of the board (see
    :meth:`BoardShade.lattice_evidence`).

    Attributes
    ----------
    n_differ : int
        Samples where both poses see the board and predict different colours.
    share_1 : float
        The share of them whose grey level is nearer pose 1's colour's level.
    n_1, fit_1, n_2, fit_2 : int, float
        Samples where only pose 1 (2) sees the board, and the share of them whose grey
        level has the colour it predicts (0.5 is chance: squares put on the background).
    """

    n_differ: int
    share_1: float
    n_1: int
    fit_1: float
    n_2: int
    fit_2: float

    def winner(self, min_samples: int, min_share: float) -> int:
        """1 or 2: the pose the capture prefers; 0: it cannot tell.

        The samples where both see the board decide when there are ``min_samples`` of them
        and a share of at least ``min_share`` favours one pose.  Else a pose whose samples
        off the other's board do not fit (``min_samples`` of them, fewer than
        :data:`UNFIT` fitting: it put squares on the background) loses to one whose samples
        fit (or that has none), unless the shared samples lean the other way."""
        if self.n_differ >= min_samples:
            if self.share_1 >= min_share:
                return 1
            if self.share_1 <= 1.0 - min_share:
                return 2
        lean = 0.5 if self.n_differ < min_samples else self.share_1
        bad_1 = self.n_1 >= min_samples and self.fit_1 < UNFIT
        bad_2 = self.n_2 >= min_samples and self.fit_2 < UNFIT
        if bad_2 and not bad_1 and lean >= 0.5:
            return 1
        if bad_1 and not bad_2 and lean <= 0.5:
            return 2
        return 0


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

    def lattice_evidence(self, pose_1: tuple[np.ndarray, np.ndarray],
                         pose_2: tuple[np.ndarray, np.ndarray]) -> LatticeEvidence:
        """How the capture decides between two poses of the board that agree on most of it
        (readings of its lattice a few squares apart, or the fit and a shifted fit).

        Points on the board's plane, a sixth of a square apart over the board and two
        squares around it, are projected from either pose; at each of those pixels each
        pose predicts the board's colour, or no board (:meth:`BoardLayout.local_shade`).  Where both
        predict the same colour, the capture gives the black and white levels, and their
        midpoint classifies every other sample black or white.  Where both predict
        different colours (one's margin where the other sees squares; squares of the other
        colour), each sample votes; where only one sees the board, the sample tests that
        one's colour alone.

        Returns
        -------
        LatticeEvidence
        """

        lay = self.layout
        h, w = self.grey.shape
        step = lay.square_size / 6
        ext = lay.margin + 2 * lay.square_size
        ga = np.arange(-lay.square_size - ext, lay.grid[0] * lay.square_size + ext, step)
        gb = np.arange(-lay.square_size - ext, lay.grid[1] * lay.square_size + ext, step)
        aa, bb = np.meshgrid(ga + step / 2, gb + step / 2, indexing="ij")
        pts = lay.origin + aa.reshape(-1, 1) * lay.a + bb.reshape(-1, 1) * lay.b
        uv = []
        for pos, rot in (pose_1, pose_2):
            p, ok = self.camera.project_rays((pts - pos) @ rot)
            ok &= (p[:, 0] >= 0) & (p[:, 1] >= 0) & (p[:, 0] <= w - 1) & (p[:, 1] <= h - 1)
            uv.append(p[ok])
        pix = np.concatenate(uv)
        s1, s2 = (self._shade_at_pixels(pos, rot, pix) for pos, rot in (pose_1, pose_2))
        c = cv2.remap(self.grey, pix[:, 0].astype(np.float32).reshape(-1, 1),
                      pix[:, 1].astype(np.float32).reshape(-1, 1), cv2.INTER_LINEAR).ravel()
        agree = (s1 == s2) & (s1 >= 0)
        black, white = c[agree & (s1 == 0)], c[agree & (s1 == 1)]
        if len(black) < 4 or len(white) < 4:
            return LatticeEvidence(0, 0.5, 0, 0.0, 0, 0.0)
        decisive = ((s1 >= 0) & (s2 >= 0) & (s1 != s2)) | ((s1 >= 0) & (s2 == -1)) \
            | ((s2 >= 0) & (s1 == -1))
        mid, seen = _local_levels(pix, c, agree & (s1 == 0), agree & (s1 == 1), decisive)
        is_white = c > mid
        differ = (s1 >= 0) & (s2 >= 0) & (s1 != s2) & seen
        n_d = int(differ.sum())
        share = float(np.mean(is_white[differ] == (s1[differ] == 1))) if n_d else 0.5

        def alone(a: np.ndarray, b: np.ndarray) -> tuple[int, float]:
            mine = (a >= 0) & (b == -1) & seen
            n = int(mine.sum())
            return n, (float(np.mean(is_white[mine] == (a[mine] == 1))) if n else 0.0)

        return LatticeEvidence(n_d, share, *alone(s1, s2), *alone(s2, s1))

    def _shade_at_pixels(self, position: np.ndarray, rotation: np.ndarray,
                         uv: np.ndarray) -> np.ndarray:
        """The board's colour seen at pixels ``uv`` (N, 2) from the pose, as
        :meth:`BoardLayout.local_shade` gives it (−1 where the ray misses the board)."""
        lay = self.layout
        rays, ok = self.camera.pixel_rays(uv)
        d = rays @ rotation.T  # scene frame
        denom = d @ lay.normal
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((lay.origin - position) @ lay.normal) / denom
        hit = ok & (t > 0) & np.isfinite(t)
        p = position + t[:, None] * d - lay.origin
        out = lay.local_shade(p @ lay.a, p @ lay.b)
        return np.where(hit, out, -1.0)
