"""Global start: the calibration board found in the capture without predicted corners.

The scene's pose only says roughly where the board is.  :func:`find_board_start` runs
OpenCV's chessboard detector (``cv2.findChessboardCornersSB``) on the whole capture and, where
that fails, on a perspective (pinhole) view of the fisheye capture centred on the board's
predicted direction and wide enough for the board to be anywhere within ±20° of it.  The
detected corners are back-projected through the lens (our own inverse of the projection;
for a Kannala-Brandt lens that is ``cv2.fisheye.undistortPoints``), and ``cv2.solvePnP``
(IPPE, planar) on them gives the camera pose, which our fisheye PnP (:func:`.pose.fit_pose`)
then polishes.

Correspondence: the detector gives a grid of the board's size, not which end is which,
nor even that it is the board's inner corners: on a small or blurred board it may take the
board's edge for a row and miss a row or column inside (seen on area-averaged renders of a
5 × 4 board: a 3 × 4 grid, one row of it on the board's lower edge).  So the detected grid
is read as a patch of the board's square lattice, in each of the eight ways it can lie
(turns and mirror images) and at each place it fits, its corners on the inner corners or on
the square corners of the board's edge; a reading that puts the camera behind the board is
dropped; of the rest, the colours of the board's squares decide (:class:`.board.BoardShade`),
and a reading turned more than :data:`MAX_START_TURN_DEG` from the scene's (CAD) rotation
is not believed.  A board whose half turn has the same colours (squares along width + height
even) cannot be told from it: the reading nearest the scene's rotation wins and the start
says it was ambiguous.  The one-square (diagonal) alias is one of these readings, and the
outer ring of squares' colours rejects it.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.  A pose correction ``x`` is as in :mod:`.projection`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import FisheyeCamera, ypr_from_rotation
from .board import BoardLayout, BoardShade
from .capture import grey
from .charuco import detect_charuco
from .pose import fit_pose
from .projection import project

__all__ = ["BoardStart", "find_board_start", "ypr_from_rotation", "VIEWS", "predicted_shift_px"]

#: Perspective view: the board may lie this far from its predicted direction, degrees.
VIEW_MARGIN_DEG = 20.0
#: Perspective view: pixels per board square at the view's centre.
VIEW_SQUARE_PX = 18.0
#: Perspective view: longest side, px.
VIEW_MAX_PX = 1200
#: A candidate whose squares' colours correlate less than this with the capture is wrong.
MIN_COLOUR_SCORE = 0.5
#: Corners fitting one board pose worse than this fraction of their spacing (RMS) are not
#: the board.
MAX_START_RMS = 0.03
#: Readings within this of the best colour score are told apart by the scene's rotation
#: (a half-turn-symmetric board's two readings sample the same squares, so they score
#: alike to rounding; a reading one square or a quarter turn off scores ~0.1 lower).
COLOUR_TIE = 0.02
#: A start turned further than this from the scene's rotation is not believed, degrees:
#: a CAD mount is within a few degrees of the real one.
MAX_START_TURN_DEG = 30.0


@dataclass(frozen=True)
class BoardStart:
    """The pose from the board found in the capture.

    Attributes
    ----------
    x : (6,) float
        Pose correction of the scene's mount (m, degrees), see :mod:`.projection`.
    found : (K, 2) float
        The detected corners that are the board's inner corners, px.
    corner_ij : (K, 2) int
        Which inner corner (i along the board's width, j along its height) each is.
    view : str
        Where the detector found them: ``"whole image"`` or ``"perspective view"``.
    rms_px : float
        Reprojection RMS of the corners at ``x``, px.
    colour_score : float
        Correlation of the board's square colours with the capture at ``x``.
    ambiguous : bool
        The board is half-turn symmetric and the scene's pose chose among the candidates.
    """

    x: np.ndarray
    found: np.ndarray
    corner_ij: np.ndarray
    view: str
    rms_px: float
    colour_score: float
    ambiguous: bool


def _view_basis(direction: np.ndarray) -> np.ndarray:
    """Columns: x, y, z axes (camera frame) of a pinhole view looking along ``direction``,
    its x axis as close to the camera's as possible."""
    z = direction / np.linalg.norm(direction)
    ref = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = ref - (ref @ z) * z
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)


def _detect(img: np.ndarray, grid: tuple[int, int]) -> np.ndarray | None:
    """The detector's corners (ny, nx, 2) in its own row order, or None."""
    import cv2

    flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
    ok, found = cv2.findChessboardCornersSB(img, grid, flags=flags)
    if not ok or found is None or len(found) != grid[0] * grid[1]:
        return None
    return np.asarray(found, np.float64).reshape(grid[1], grid[0], 2)


def _perspective_detect(grey_u8: np.ndarray, camera: FisheyeCamera,
                        layout: BoardLayout) -> np.ndarray | None:
    """Detect the board in a pinhole view of the capture centred on its predicted
    direction (``camera``'s pose); corners mapped back to capture px, (ny, nx, 2)."""
    import cv2

    rays = camera.scene_to_camera(layout.corner_points.reshape(-1, 3))
    centre = rays.mean(axis=0)
    basis = _view_basis(centre)
    unit = rays / np.linalg.norm(rays, axis=1, keepdims=True)
    spread = np.degrees(np.arccos(np.clip(unit @ basis[:, 2], -1, 1))).max()
    square_deg = np.degrees(layout.square_size / np.linalg.norm(centre))
    half = np.radians(min(spread + square_deg + VIEW_MARGIN_DEG, 65.0))
    f = VIEW_SQUARE_PX * np.linalg.norm(centre) / layout.square_size
    f = min(f, VIEW_MAX_PX / 2 / np.tan(half))
    n = int(2 * f * np.tan(half)) + 1
    c = (n - 1) / 2
    vv, uu = np.mgrid[0:n, 0:n].astype(np.float64)
    view_rays = np.stack([(uu - c) / f, (vv - c) / f, np.ones_like(uu)], axis=-1) @ basis.T
    uv, in_fov = camera.project_rays(view_rays.reshape(-1, 3))
    uv[~in_fov] = -10.0
    maps = uv.reshape(n, n, 2).astype(np.float32)
    view = cv2.remap(grey_u8, maps[..., 0], maps[..., 1], cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    found = _detect(view, layout.grid)
    if found is None:
        return None
    pts = found.reshape(-1, 2)
    back = np.stack([(pts[:, 0] - c) / f, (pts[:, 1] - c) / f, np.ones(len(pts))], -1) @ basis.T
    return np.asarray(camera.project_rays(back)[0]).reshape(found.shape)


def _readings(det: np.ndarray, grid: tuple[int, int]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every way of reading the detector's grid (rows, cols, 2) as a patch of the board's
    square lattice: (lattice indices (K, 2) int, the corners (K, 2) px).

    Lattice index (i, j) is inner corner (i, j) for 0 ≤ i < nx, 0 ≤ j < ny; −1 and nx (ny)
    are the square corners on the board's edge.  A reading lies in that range and holds at
    least half of the board's inner corners.
    """
    nx, ny = grid
    rows, cols = det.shape[:2]
    r, c = np.mgrid[0:rows, 0:cols]
    pts = det.reshape(-1, 2)
    out = []
    seen = set()
    for swap in (False, True):
        u, v = (c, r) if not swap else (r, c)
        for su in (1, -1):
            for sv in (1, -1):
                i0, j0 = (su * u).ravel(), (sv * v).ravel()
                for di in range(-1 - i0.min(), nx - i0.max()):
                    for dj in range(-1 - j0.min(), ny - j0.max()):
                        ij = np.stack([i0 + di, j0 + dj], axis=1)
                        key = ij.tobytes()
                        inner = (ij[:, 0] >= 0) & (ij[:, 0] < nx) & (ij[:, 1] >= 0) \
                            & (ij[:, 1] < ny)
                        if key in seen or 2 * inner.sum() < nx * ny:
                            continue
                        seen.add(key)
                        out.append((ij, pts))
    return out


def _pnp(camera: FisheyeCamera, layout: BoardLayout, ij: np.ndarray,
         found: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Camera (position m, camera-to-scene rotation) from the corners ``found`` (K, 2) px
    at the board's lattice indices ``ij`` (K, 2), by planar PnP in a pinhole view along their
    mean ray."""
    import cv2

    rays, _ = camera.pixel_rays(found)
    basis = _view_basis(rays.mean(axis=0))
    r_v = rays @ basis
    if np.any(r_v[:, 2] <= 1e-3):
        return None
    img = (r_v[:, :2] / r_v[:, 2:3]).astype(np.float64)
    obj = np.column_stack([ij * layout.square_size, np.zeros(len(ij))]).astype(np.float64)
    ok, rvec, tvec = cv2.solvePnP(obj, img, np.eye(3), None, flags=cv2.SOLVEPNP_IPPE)
    if not ok:
        return None
    r_bv = cv2.Rodrigues(rvec)[0]
    m = np.stack([layout.a, layout.b, layout.normal], axis=1)  # board-local -> scene
    r_sc = basis @ r_bv @ m.T                                # scene -> camera
    rot = r_sc.T
    pos = layout.origin - rot @ (basis @ tvec.ravel())
    return pos, rot


@dataclass(frozen=True)
class _Reading:
    """A reading of the detected grid with its PnP pose: colour score, degrees from the
    scene's rotation, position m, rotation, lattice indices (K, 2), corners (K, 2) px."""

    score: float
    turn_deg: float
    position: np.ndarray
    rotation: np.ndarray
    ij: np.ndarray
    found: np.ndarray


def _candidates(camera: FisheyeCamera, layout: BoardLayout, det: np.ndarray,
                shade: BoardShade) -> list[_Reading]:
    """Each reading of the detection (:func:`_readings`) that puts the camera in front of
    the board, with its pose and colour score."""
    out = []
    for ij, found in _readings(det, layout.grid):
        pose = _pnp(camera, layout, ij, found)
        if pose is None:
            continue
        pos, rot = pose
        if (pos - layout.origin) @ layout.normal <= 0:
            continue  # mirrored: the camera would see the board from behind
        d_rot = rot.T @ camera.rotation
        angle = np.degrees(np.arccos(np.clip((np.trace(d_rot) - 1) / 2, -1, 1)))
        out.append(_Reading(shade(pos, rot), float(angle), pos, rot, ij, found))
    return out


#: Where :func:`find_board_start` runs the detector, in order.
VIEWS = ("whole image", "perspective view")


def find_board_start(capture: np.ndarray, camera: FisheyeCamera, ypr0_deg: np.ndarray,
                     layout: BoardLayout, views: tuple[str, ...] = VIEWS,
                     charuco: tuple[np.ndarray, np.ndarray] | None = None) -> BoardStart | None:
    """The scene's mount correction from the board found in ``capture``, or None.

    Parameters
    ----------
    capture : (H, W, 3) uint8
    camera : FisheyeCamera
        The scene's camera at the scene's pose.
    ypr0_deg : (3,) float
        The scene's mount yaw, pitch, roll, degrees.
    layout : BoardLayout
    views : tuple of str
        Where to run the detector, in order (of :data:`VIEWS`): the first that gives a
        board pose wins.
    charuco : (ij, px), optional
        A ChArUco board's corners already found in ``capture``
        (:func:`.charuco.detect_charuco`); found here when not given.

    Returns
    -------
    BoardStart or None
        None when the board's direction is outside the field, the detector does not find
        it, or no assignment of its corners has the board's colours.
    """
    centre = camera.scene_to_camera(layout.corner_points.reshape(-1, 3).mean(axis=0)[None])[0]
    theta = np.degrees(np.arctan2(np.hypot(centre[0], centre[1]), centre[2]))
    if theta > camera.fov_deg / 2 + VIEW_MARGIN_DEG:
        return None
    g = grey(capture)
    g_u8 = np.clip(g, 0, 255).astype(np.uint8)
    shade = BoardShade(layout, camera, g.astype(np.float32))
    if layout.charuco is not None:
        named = charuco if charuco is not None else detect_charuco(g_u8, layout.charuco)
        start = None if named is None else _charuco_start(camera, ypr0_deg, layout, named, shade)
        if start is not None:
            return start
    for view in views:
        det = (_detect(g_u8, layout.grid) if view == "whole image"
               else _perspective_detect(g_u8, camera, layout))
        if det is None:
            continue
        if view == "perspective view":  # corners through the view's interpolation
            det = _refine(g.astype(np.float32), det)
        start = _best_start(camera, ypr0_deg, layout, det, shade, view)
        if start is not None:
            return start
    return None


def _refine(grey_f: np.ndarray, det: np.ndarray) -> np.ndarray:
    """The detector's corners (ny, nx, 2) refined by ``cv2.cornerSubPix`` in the capture,
    with a window of 0.3 grid spacing."""
    import cv2

    step = np.concatenate([np.linalg.norm(np.diff(det, axis=0), axis=-1).ravel(),
                           np.linalg.norm(np.diff(det, axis=1), axis=-1).ravel()])
    win = int(np.clip(round(0.3 * float(np.median(step))), 2, 12))
    pts = cv2.cornerSubPix(grey_f, det.reshape(-1, 1, 2).astype(np.float32), (win, win),
                           (-1, -1), (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-3))
    return np.asarray(pts, np.float64).reshape(det.shape)


def _best_start(camera: FisheyeCamera, ypr0_deg: np.ndarray, layout: BoardLayout,
                det: np.ndarray, shade: BoardShade, view: str) -> BoardStart | None:
    """The start from the detected corners ``det``: the reading with the board's colours
    (nearest the scene's rotation among those colours cannot tell apart), polished by our
    fisheye PnP on its inner corners; None when no reading within
    :data:`MAX_START_TURN_DEG` of the scene's rotation has the colours, or the inner corners
    do not fit one board pose (a spurious detection: RMS over :data:`MAX_START_RMS` of the
    grid spacing)."""
    readings = [c for c in _candidates(camera, layout, det, shade) if c.score >= MIN_COLOUR_SCORE]
    cands = [c for c in readings if c.turn_deg <= MAX_START_TURN_DEG]
    if not cands:
        return None
    best = max(c.score for c in cands)
    pick = min((c for c in cands if c.score >= best - COLOUR_TIE), key=lambda c: c.turn_deg)
    # Ambiguous: another reading (the half turn, however far from the scene's rotation)
    # has the same colours, so the scene's rotation chose.
    ties = [c for c in readings if c.score >= best - COLOUR_TIE]
    nx, ny = layout.grid
    inner = (pick.ij[:, 0] >= 0) & (pick.ij[:, 0] < nx) & (pick.ij[:, 1] >= 0) \
        & (pick.ij[:, 1] < ny)
    step = float(np.median(np.linalg.norm(np.diff(det, axis=0), axis=-1)))
    return _polished(camera, ypr0_deg, layout, pick.position, pick.rotation,
                     pick.ij[inner], pick.found[inner], step, view, pick.score, len(ties) > 1)


def _polished(camera: FisheyeCamera, ypr0_deg: np.ndarray, layout: BoardLayout,
              position: np.ndarray, rotation: np.ndarray, ij: np.ndarray, found: np.ndarray,
              step_px: float, view: str, score: float, ambiguous: bool) -> BoardStart | None:
    """The start from a PnP pose (``position`` m, ``rotation``) and the inner corners
    ``ij`` (K, 2) found at ``found`` (K, 2) px, polished by our fisheye PnP; None when they
    do not fit one board pose (RMS over :data:`MAX_START_RMS` of ``step_px``, or 0.5 px)."""
    x0 = np.concatenate([position - camera.position,
                         (ypr_from_rotation(rotation) - ypr0_deg + 180.0) % 360.0 - 180.0])
    pts = layout.corner_points[ij[:, 0], ij[:, 1]]
    x, resid, _ = fit_pose(camera, ypr0_deg, pts, found, x0=x0)
    rms = float(np.sqrt(np.mean(resid ** 2)))
    if rms > max(0.5, MAX_START_RMS * step_px):
        return None
    return BoardStart(x=x, found=found, corner_ij=ij, view=view, rms_px=rms,
                      colour_score=float(score), ambiguous=ambiguous)


def _charuco_start(camera: FisheyeCamera, ypr0_deg: np.ndarray, layout: BoardLayout,
                   det: tuple[np.ndarray, np.ndarray], shade: BoardShade) -> BoardStart | None:
    """The start from a ChArUco board's corners found by its markers (``det``, as
    :func:`.charuco.detect_charuco` gives them): they are named, so there is one reading
    and no ambiguity."""
    ij, found = det
    pose = _pnp(camera, layout, ij, found)
    if pose is None:
        return None
    pos, rot = pose
    d = np.linalg.norm(layout.corner_points[ij[:, 0], ij[:, 1]] - pos, axis=1)
    step = float(np.median(camera.fx * layout.square_size / d))  # ~px per square
    return _polished(camera, ypr0_deg, layout, pos, rot, ij, found, step, "ChArUco markers",
                     shade(pos, rot), False)


def predicted_shift_px(camera: FisheyeCamera, ypr0_deg: np.ndarray, x: np.ndarray,
                       points: np.ndarray) -> float:
    """Largest image move of ``points`` (m) between the scene's pose and the correction
    ``x``, px."""
    from .projection import corrected_pose

    before = project(camera, camera.position, camera.rotation, points)
    after = project(camera, *corrected_pose(camera, ypr0_deg, x), points)
    return float(np.max(np.linalg.norm(after - before, axis=1)))
