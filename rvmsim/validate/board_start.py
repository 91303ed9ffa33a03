"""Global start: the calibration board found in the capture without predicted corners.

The scene's pose only says roughly where the board is.  :func:`find_board_start` runs
OpenCV's chessboard detector (``cv2.findChessboardCornersSB``) on the whole capture and, where
that fails, on a perspective (pinhole) view of the fisheye capture centred on the board's
predicted direction and wide enough for the board to be anywhere within ±20° of it.  The
detected corners are back-projected through the lens (our own inverse of the projection;
for a Kannala-Brandt lens that is ``cv2.fisheye.undistortPoints``), and ``cv2.solvePnP``
(IPPE, planar) on them gives the camera pose, which our fisheye PnP (:func:`.pose.fit_pose`)
then polishes.

Correspondence: the detector gives the grid, not which end is which.  Every assignment of
its grid to the board's inner corners (the four flips, and the transposes of a square grid)
is tried; a mirrored assignment puts the camera behind the board and is dropped; of the
rest, the colours of the board's squares decide (:class:`.board.BoardShade`).  A board whose
half turn has the same colours (squares along width + height even) cannot be told from it:
the candidate nearest the scene's (CAD) rotation wins and the start says it was ambiguous.
A one-square (diagonal) alias cannot occur here: the detector finds exactly the board's
``nx × ny`` inner corners, and the colours of the outer ring of squares are checked.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.  A pose correction ``x`` is as in :mod:`.projection`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import FisheyeCamera
from .board import BoardLayout, BoardShade
from .capture import grey
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


@dataclass(frozen=True)
class BoardStart:
    """The pose from the board found in the capture.

    Attributes
    ----------
    x : (6,) float
        Pose correction of the scene's mount (m, degrees), see :mod:`.projection`.
    found : (nx, ny, 2) float
        The detected inner corners in the capture, in the board's grid order, px.
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
    view: str
    rms_px: float
    colour_score: float
    ambiguous: bool


def ypr_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """Mount yaw, pitch, roll (degrees) of a camera-to-scene rotation: the inverse of
    :func:`rvmsim.camera.rotation_from_ypr` (``Ry(yaw) @ Rx(-pitch) @ Rz(roll)``)."""
    r = np.asarray(rotation, dtype=np.float64)
    pitch = np.arcsin(np.clip(r[1, 2], -1.0, 1.0))
    yaw = np.arctan2(r[0, 2], r[2, 2])
    roll = np.arctan2(r[1, 0], r[1, 1])
    return np.degrees([yaw, pitch, roll])


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


def _assignments(det: np.ndarray, grid: tuple[int, int]) -> list[np.ndarray]:
    """Every way of reading the detector's grid (ny, nx, 2) as the board's (nx, ny, 2)."""
    base = det.transpose(1, 0, 2)  # [i, j] with i along the detector's rows
    cands = [base[::fi, ::fj] for fi in (1, -1) for fj in (1, -1)]
    if grid[0] == grid[1]:
        cands += [c.transpose(1, 0, 2) for c in cands]
    return [np.ascontiguousarray(c) for c in cands]


def _pnp(camera: FisheyeCamera, layout: BoardLayout,
         found: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Camera (position m, camera-to-scene rotation) from the corners ``found`` (nx, ny, 2)
    assigned to the board's grid, by planar PnP in a pinhole view along their mean ray."""
    import cv2

    rays, _ = camera.pixel_rays(found.reshape(-1, 2))
    basis = _view_basis(rays.mean(axis=0))
    r_v = rays @ basis
    if np.any(r_v[:, 2] <= 1e-3):
        return None
    img = (r_v[:, :2] / r_v[:, 2:3]).astype(np.float64)
    obj = layout.local_points().reshape(-1, 3)
    ok, rvec, tvec = cv2.solvePnP(obj, img, np.eye(3), None, flags=cv2.SOLVEPNP_IPPE)
    if not ok:
        return None
    r_bv = cv2.Rodrigues(rvec)[0]
    m = np.stack([layout.a, layout.b, layout.normal], axis=1)  # board-local -> scene
    r_sc = basis @ r_bv @ m.T                                # scene -> camera
    rot = r_sc.T
    pos = layout.origin - rot @ (basis @ tvec.ravel())
    return pos, rot


def _candidates(camera: FisheyeCamera, layout: BoardLayout, det: np.ndarray,
                shade: BoardShade) -> list[tuple[float, float, np.ndarray, np.ndarray, np.ndarray]]:
    """(colour score, angle to the scene's rotation in degrees, position, rotation, the
    corners in the board's grid order) of each assignment that puts the camera in front of
    the board."""
    out = []
    for found in _assignments(det, layout.grid):
        pose = _pnp(camera, layout, found)
        if pose is None:
            continue
        pos, rot = pose
        if (pos - layout.origin) @ layout.normal <= 0:
            continue  # mirrored: the camera would see the board from behind
        d_rot = rot.T @ camera.rotation
        angle = np.degrees(np.arccos(np.clip((np.trace(d_rot) - 1) / 2, -1, 1)))
        out.append((shade(pos, rot), float(angle), pos, rot, found))
    return out


#: Where :func:`find_board_start` runs the detector, in order.
VIEWS = ("whole image", "perspective view")


def find_board_start(capture: np.ndarray, camera: FisheyeCamera, ypr0_deg: np.ndarray,
                     layout: BoardLayout, views: tuple[str, ...] = VIEWS) -> BoardStart | None:
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
    """The start from the detected corners ``det``: the assignment with the board's colours
    (nearest the scene's rotation among those colours cannot tell apart), polished by our
    fisheye PnP; None when none has the colours or the corners do not fit one board pose
    (a spurious detection: RMS over :data:`MAX_START_RMS` of the grid spacing)."""
    cands = [c for c in _candidates(camera, layout, det, shade) if c[0] >= MIN_COLOUR_SCORE]
    if not cands:
        return None
    best = max(c[0] for c in cands)
    close = [c for c in cands if c[0] >= best - 0.2]
    score, _, pos, rot, found = min(close, key=lambda c: c[1])
    x0 = np.concatenate([pos - camera.position,
                         (ypr_from_rotation(rot) - ypr0_deg + 180.0) % 360.0 - 180.0])
    pts = layout.corner_points.reshape(-1, 3)
    x, resid, _ = fit_pose(camera, ypr0_deg, pts, found.reshape(-1, 2), x0=x0)
    rms = float(np.sqrt(np.mean(resid ** 2)))
    step = float(np.median(np.linalg.norm(np.diff(found, axis=0), axis=-1)))
    if rms > max(0.5, MAX_START_RMS * step):
        return None
    return BoardStart(x=x, found=found, view=view, rms_px=rms, colour_score=float(score),
                      ambiguous=len(close) > 1)


def predicted_shift_px(camera: FisheyeCamera, ypr0_deg: np.ndarray, x: np.ndarray,
                       points: np.ndarray) -> float:
    """Largest image move of ``points`` (m) between the scene's pose and the correction
    ``x``, px."""
    from .projection import corrected_pose

    before = project(camera, camera.position, camera.rotation, points)
    after = project(camera, *corrected_pose(camera, ypr0_deg, x), points)
    return float(np.max(np.linalg.norm(after - before, axis=1)))
