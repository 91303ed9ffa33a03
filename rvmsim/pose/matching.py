"""Finding the landmarks in a capture.

The calibration board is found with OpenCV's chessboard detector where it may be visible
(at least half its inner corners predicted usable), a ChArUco board by its markers (the
corners :func:`.charuco.detect_charuco` names, found once per capture);
every other checker corner by normalised cross-correlation (NCC) of its rendered
neighbourhood within a search radius, followed by ``cv2.cornerSubPix``.  The colours of a
checker corner's four squares make the match polarity-safe against its neighbours (which
have the opposite colour order).

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`; an image is indexed ``[v, u]``.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from .. import labels as L
from ..render import FisheyeImages
from ..scene import CheckerCorner, Scene
from .capture import grey
from .landmarks import spacing_px
from .projection import project

__all__ = ["MIN_NCC", "find_landmarks"]

#: Minimum normalised cross-correlation for a local match to count as found.
MIN_NCC = 0.6


def _peak_offset(res: np.ndarray, x: int, y: int) -> tuple[float, float] | None:
    """Sub-pixel offset of the correlation peak at (x, y) of ``res``: a parabola through it
    and its neighbours along each axis; None at the border of ``res``."""
    if not (0 < x < res.shape[1] - 1 and 0 < y < res.shape[0] - 1):
        return None

    def vertex(a: float, b: float, c: float) -> float:
        d = a - 2.0 * b + c
        return 0.0 if d >= 0 else float(np.clip(0.5 * (a - c) / d, -0.5, 0.5))

    return (vertex(res[y, x - 1], res[y, x], res[y, x + 1]),
            vertex(res[y - 1, x], res[y, x], res[y + 1, x]))


def _match_local(cap: np.ndarray, syn: np.ndarray, p_syn: np.ndarray, p_pred: np.ndarray,
                 spacing: float, radius: float,
                 refine: str = "corner") -> tuple[np.ndarray | None, float]:
    """Find the rendered neighbourhood of ``p_syn`` in the capture near ``p_pred``.

    ``cap`` and ``syn`` are grey (float32) capture and synthetic frame; ``p_syn`` the
    corner's pixel in ``syn``, ``p_pred`` its predicted pixel in ``cap``; ``spacing`` and
    ``radius`` px.  ``refine``: ``"corner"`` refines the match by ``cv2.cornerSubPix`` (an
    X corner with nothing else in its window), ``"ncc"`` by the correlation peak's sub-pixel
    vertex (a ChArUco corner, whose window holds marker edges that would pull cornerSubPix
    off it).  Returns the capture pixel (None: not found) and the NCC.
    """

    h, w = cap.shape
    half = int(np.clip(round(0.45 * spacing), 4, 24))
    r = int(math.ceil(radius)) + (1 if refine == "ncc" else 0)
    x0, y0 = int(round(p_syn[0])) - half, int(round(p_syn[1])) - half
    tmpl = syn[y0:y0 + 2 * half + 1, x0:x0 + 2 * half + 1]
    sx0 = int(round(p_pred[0])) - half - r
    sy0 = int(round(p_pred[1])) - half - r
    sx1, sy1 = sx0 + 2 * (half + r) + 1, sy0 + 2 * (half + r) + 1
    if sx0 < 0 or sy0 < 0 or sx1 > w or sy1 > h or tmpl.shape != (2 * half + 1,) * 2:
        return None, 0.0
    if float(tmpl.std()) < 1.0:
        return None, 0.0
    res = cv2.matchTemplate(cap[sy0:sy1, sx0:sx1], tmpl, cv2.TM_CCOEFF_NORMED)
    _, best, _, loc = cv2.minMaxLoc(res)
    if not np.isfinite(best) or best < MIN_NCC:
        return None, float(best) if np.isfinite(best) else 0.0
    est = np.array([p_syn[0] + sx0 + loc[0] - x0, p_syn[1] + sy0 + loc[1] - y0])
    if refine == "ncc":
        off = _peak_offset(res, loc[0], loc[1])
        return (None if off is None else est + np.array(off)), float(best)
    win = int(np.clip(round(0.3 * spacing), 2, 12))
    pt = cv2.cornerSubPix(cap, est.reshape(1, 1, 2).astype(np.float32), (win, win), (-1, -1),
                          (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-3))
    pt = pt.reshape(2).astype(np.float64)
    if np.linalg.norm(pt - est) > max(2.0, 0.25 * spacing):
        return None, float(best)
    return pt, float(best)


def _match_board(cap_u8: np.ndarray, scene: Scene, idx: list[int], pred: np.ndarray,
                 spacing: np.ndarray, radius: float) -> dict[int, np.ndarray]:
    """The board's inner corners by cv2.findChessboardCornersSB on a crop around them.

    ``idx`` are the board's inner corners among ``pred`` (predicted pixels, px); the
    detector's corners are assigned to them and accepted when they agree up to one common
    shift ≤ ``radius`` + 2 px.  Returns {corner index: capture pixel}; {} when not found.
    """

    board = scene.test_site.board
    nx, ny = board.squares[0] - 1, board.squares[1] - 1
    if len(idx) != nx * ny:
        return {}
    p = pred[idx]
    s = float(np.median(spacing[idx]))
    pad = 1.5 * s + radius
    h, w = cap_u8.shape
    x0, y0 = max(0, int(p[:, 0].min() - pad)), max(0, int(p[:, 1].min() - pad))
    x1, y1 = min(w, int(p[:, 0].max() + pad) + 1), min(h, int(p[:, 1].max() + pad) + 1)
    crop = cap_u8[y0:y1, x0:x1]
    f = float(np.clip(30.0 / max(s, 1.0), 1.0, 4.0))
    if f > 1.0:
        crop = cv2.resize(crop, None, fx=f, fy=f, interpolation=cv2.INTER_CUBIC)
    flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
    ok, found = cv2.findChessboardCornersSB(crop, (nx, ny), flags=flags)
    if not ok or found is None or len(found) != nx * ny:
        return {}
    # Back to image pixels: crop pixel centres sit at (i + 0.5) / f - 0.5 in the original.
    found = (found.reshape(-1, 2) + 0.5) / f - 0.5 + np.array([x0, y0])
    cost = np.linalg.norm(found[:, None, :] - p[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    d = found[rows] - p[cols]
    shift = np.median(d, axis=0)
    if np.any(np.linalg.norm(d - shift, axis=1) > 0.35 * s) or np.linalg.norm(shift) > radius + 2:
        return {}
    return {idx[c]: found[r] for r, c in zip(rows, cols)}


def find_landmarks(capture: np.ndarray, synthetic: FisheyeImages, scene: Scene,
                   corners: list[CheckerCorner] | tuple[CheckerCorner, ...], *,
                   position: np.ndarray, rotation: np.ndarray, radius_px: float,
                   usable: np.ndarray, named: dict[int, np.ndarray] | None = None,
                   ) -> tuple[np.ndarray, np.ndarray, list[str], np.ndarray]:
    """Find ``corners`` in the capture, predicted from the pose (position, rotation).

    Parameters
    ----------
    capture : (H, W, 3) uint8
        RGB capture.
    synthetic : FisheyeImages
        The scene's rendered frame (its camera's pose is the one the scene gives).
    scene : Scene
    corners : sequence of CheckerCorner
    position : (3,) float
        Optical centre to predict from, m.
    rotation : (3, 3) float
        Camera-to-scene rotation to predict from.
    radius_px : float
        Search radius around each prediction, px.
    usable : (N,) bool
        Which corners to look for.
    named : dict, optional
        Corners already found by name, {index in ``corners``: capture px} (a ChArUco
        board's, :func:`.charuco.detect_charuco`): used where usable and within
        ``radius_px`` + 2 px of the prediction, refined by the correlation of their rendered
        neighbourhood within 1.5 px (method ``"charuco"``).  The board's other corners are
        matched locally with that refinement too, not ``cv2.cornerSubPix`` (the markers in
        their windows would bias it).

    Returns
    -------
    found : (N, 2) float
        Capture pixels, px (NaN where not found).
    ncc : (N,) float
        Normalised cross-correlation of each match (1.0 for the chessboard detector).
    method : list of str
        ``"chessboard"``, ``"charuco"``, ``"local"`` or ``""`` (not found).
    predicted : (N, 2) float
        The predictions searched around, px.
    """
    cam = synthetic.camera
    pts = np.array([c.point for c in corners])
    pred = project(cam, position, rotation, pts)
    syn_uv = project(cam, cam.position, cam.rotation, pts)
    spacing = spacing_px(cam, position, rotation, corners)
    cap_g = grey(capture)
    syn_g = grey(synthetic.color)
    found = np.full((len(corners), 2), np.nan)
    ncc = np.zeros(len(corners))
    method = [""] * len(corners)
    board_idx = [n for n, c in enumerate(corners)
                 if c.label == L.BOARD and c.name.startswith("board_inner")]
    charuco = np.zeros(len(corners), bool)
    if named:
        # A ChArUco board: its markers say where each corner is; the rendered neighbourhood
        # (markers and all) places it to a fraction of a pixel.
        charuco[board_idx] = True
        for n, xy in named.items():
            if not usable[n] or np.linalg.norm(np.asarray(xy) - pred[n]) > radius_px + 2.0:
                continue
            local, score = _match_local(cap_g, syn_g, syn_uv[n], np.asarray(xy), spacing[n],
                                        1.5, refine="ncc")
            found[n], ncc[n], method[n] = (np.asarray(xy) if local is None else local), \
                max(score, 0.0), "charuco"
    # The detector sees the whole board or nothing; it runs whenever the board may be seen
    # (half its inner corners usable), and its finds count for the usable corners.
    elif board_idx and 2 * sum(bool(usable[n]) for n in board_idx) >= len(board_idx):
        for n, xy in _match_board(cap_g.astype(np.uint8), scene, board_idx, pred,
                                  spacing, radius_px).items():
            if usable[n]:
                found[n], ncc[n], method[n] = xy, 1.0, "chessboard"
    for n in range(len(corners)):
        if not usable[n] or method[n]:
            continue
        r = min(radius_px, 0.6 * spacing[n])
        local, score = _match_local(cap_g, syn_g, syn_uv[n], pred[n], spacing[n], r,
                                    refine="ncc" if charuco[n] else "corner")
        ncc[n] = score
        if local is not None:
            found[n], method[n] = local, "local"
    return found, ncc, method, pred
