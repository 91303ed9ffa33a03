"""Global start: the calibration board found in the capture without predicted corners.

The scene's pose only says roughly where the board is.  :func:`find_board_start` runs
OpenCV's chessboard detector (``cv2.findChessboardCornersSB``) on the whole capture and, where
that fails, on a perspective (pinhole) view of the fisheye capture centred on the board's
predicted direction and wide enough for the board to be anywhere within ±20° of it.  The
detected corners are back-projected through the camera's own lens model
(:meth:`rvmsim.camera.FisheyeCamera.pixel_rays`, any registered model), and ``cv2.solvePnP``
(IPPE, planar) on them gives the camera pose, which our fisheye PnP (:func:`.fit.fit_pose`)
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

import cv2
import numpy as np

from ..camera import FisheyeCamera, ypr_from_rotation
from .board import BoardLayout, BoardShade, LatticeEvidence
from .board_detect import MIN_PATCH, GridDetection, detect_grids, view_basis
from .capture import grey
from .charuco import detect_charuco
from .fit import fit_pose
from .projection import corrected_pose, project

__all__ = ["BoardStart", "BoardSearch", "board_outline", "find_board_start", "search_board",
           "ypr_from_rotation", "VIEWS", "predicted_shift_px"]

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
#: A start moved further than this from the scene's camera position is not believed, m.
MAX_START_MOVE_M = 1.0
#: Readings whose colour score is within this of the best are rivals, decided by the samples
#: where their colours differ (:meth:`.board.BoardShade.lattice_evidence`).
RIVAL_SCORE = 0.25
#: Two readings are told apart by at least :data:`MIN_VOTES` samples where their colours
#: differ, of which this share must favour one (:meth:`.board.LatticeEvidence.winner`; a
#: reading that puts squares on the background fits about half).
MIN_FIT = 0.75
MIN_VOTES = 12
#: A start's corners are taken as good to this (px) when judging how well they pin the pose.
START_NOISE_PX = 0.5
#: A start pins the pose when one standard error is within these (m, degrees): a small or
#: distant part of a board fits a second, flipped pose about as well (the planar pose
#: ambiguity; 0.3-0.6 m and 6-10° for 9-12 corners 3 m away).
MAX_START_SIGMA_M = 0.06
MAX_START_SIGMA_DEG = 3.0
#: A reading must put at least this many of the detected corners on inner corners.
MIN_INNER = 6


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
    rivals : int
        Other readings of the same corners (within :data:`MAX_START_TURN_DEG` and
        :data:`MAX_START_MOVE_M` of the scene's pose, colours within :data:`RIVAL_SCORE`)
        that the capture refuted.
    whole : bool
        The detector found the board's whole grid (else a part of it).
    sigma : (6,) float or None
        The start's standard errors (m, degrees) for corners good to
        :data:`START_NOISE_PX` (see :attr:`pins_pose`).
    """

    x: np.ndarray
    found: np.ndarray
    corner_ij: np.ndarray
    view: str
    rms_px: float
    colour_score: float
    ambiguous: bool
    rivals: int = 0
    whole: bool = True
    sigma: np.ndarray | None = None

    @property
    def pins_pose(self) -> bool:
        """The corners pin the pose (one standard error within :data:`MAX_START_SIGMA_M` and
        :data:`MAX_START_SIGMA_DEG` for corners good to :data:`START_NOISE_PX`): a small or
        distant part of a board also fits a second, flipped pose (the planar ambiguity)."""
        return self.sigma is None or bool(np.max(self.sigma[:3]) <= MAX_START_SIGMA_M
                                          and np.max(self.sigma[3:]) <= MAX_START_SIGMA_DEG)


@dataclass(frozen=True)
class BoardSearch:
    """What looking for the board in the capture gave: a start, or why there is none.

    Attributes
    ----------
    start : BoardStart or None
    reason : str
        Why there is no start ("" when there is one): the board not found, found only
        where the scene's pose cannot be, its corners not fitting one board pose, or an
        ambiguous lattice (two readings whose colours fit alike).
    ambiguous : bool
        No start because two readings of the corners fit alike (the board's lattice).
    corners : (K, 2) float or None
        The corners of the largest grid the detector found, px (for pictures).
    outlines : tuple of (M, 2) float
        For an ambiguous lattice, the board's outline (px) at the pick and at its rival.
    """

    start: BoardStart | None
    reason: str = ""
    ambiguous: bool = False
    corners: np.ndarray | None = None
    outlines: tuple[np.ndarray, ...] = ()


def _readings(det: np.ndarray, grid: tuple[int, int]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Every way of reading the detector's grid (rows, cols, 2) as a patch of the board's
    square lattice: (lattice indices (K, 2) int, the corners (K, 2) px).

    Lattice index (i, j) is inner corner (i, j) for 0 ≤ i < nx, 0 ≤ j < ny; −1 and nx (ny)
    are the square corners on the board's edge.  A reading lies in that range and puts at
    least :data:`MIN_INNER` corners (or all the board's) on inner corners: a part of the
    board may be read at every place it fits.
    """
    nx, ny = grid
    rows, cols = det.shape[:2]
    r, c = np.mgrid[0:rows, 0:cols]
    pts = det.reshape(-1, 2)
    need = min(MIN_INNER, nx * ny)
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
                        if key in seen or inner.sum() < need:
                            continue
                        seen.add(key)
                        out.append((ij, pts))
    return out


def _pnp(camera: FisheyeCamera, layout: BoardLayout, ij: np.ndarray, found: np.ndarray,
         rays: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """Camera (position m, camera-to-scene rotation) from the corners ``found`` (K, 2) px
    at the board's lattice indices ``ij`` (K, 2), by planar PnP in a pinhole view along their
    mean ray (``rays``: their camera-frame rays, when already known)."""

    if rays is None:
        rays, _ = camera.pixel_rays(found)
    basis = view_basis(rays.mean(axis=0))
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
    move_m: float
    position: np.ndarray
    rotation: np.ndarray
    ij: np.ndarray
    found: np.ndarray


def _candidates(camera: FisheyeCamera, layout: BoardLayout, det: np.ndarray,
                shade: BoardShade) -> list[_Reading]:
    """Each reading of the detection (:func:`_readings`) that puts the camera in front of
    the board, with its pose and colour score."""
    out = []
    rays, _ = camera.pixel_rays(det.reshape(-1, 2))
    for ij, found in _readings(det, layout.grid):
        pose = _pnp(camera, layout, ij, found, rays)
        if pose is None:
            continue
        pos, rot = pose
        if (pos - layout.origin) @ layout.normal <= 0:
            continue  # mirrored: the camera would see the board from behind
        d_rot = rot.T @ camera.rotation
        angle = np.degrees(np.arccos(np.clip((np.trace(d_rot) - 1) / 2, -1, 1)))
        out.append(_Reading(shade(pos, rot), float(angle),
                            float(np.linalg.norm(pos - camera.position)), pos, rot, ij, found))
    return out


#: Where :func:`find_board_start` looks for the board, in order (see
#: :func:`.board_detect.detect_grids`).
VIEWS = ("whole image", "perspective view", "board plane view", "tiles")


def search_board(capture: np.ndarray, camera: FisheyeCamera, ypr0_deg: np.ndarray,
                 layout: BoardLayout, views: tuple[str, ...] = VIEWS,
                 charuco: tuple[np.ndarray, np.ndarray] | None = None) -> BoardSearch:
    """Look for the board in ``capture``: the scene's mount correction from it, or why not.

    Parameters
    ----------
    capture : (H, W, 3) uint8
    camera : FisheyeCamera
        The scene's camera at the scene's pose.
    ypr0_deg : (3,) float
        The scene's mount yaw, pitch, roll, degrees.
    layout : BoardLayout
    views : tuple of str
        Where to look, in order (of :data:`VIEWS`); the first grid that gives a start that
        pins the pose (:attr:`BoardStart.pins_pose`) wins, else the one with most corners.
    charuco : (ij, px), optional
        A ChArUco board's corners already found in ``capture``
        (:func:`.charuco.detect_charuco`); found here when not given.

    Returns
    -------
    BoardSearch
        The start, or the reason there is none (the board's direction outside the field,
        not found, found only where the scene's pose cannot be, not one board's corners,
        or an ambiguous lattice).
    """
    centre = camera.scene_to_camera(layout.corner_points.reshape(-1, 3).mean(axis=0)[None])[0]
    theta = np.degrees(np.arctan2(np.hypot(centre[0], centre[1]), centre[2]))
    if theta > camera.fov_deg / 2 + 45.0:
        return BoardSearch(None, f"at the scene's pose the board is {theta:.0f}° off the "
                           "optical axis, far outside the lens's field")
    g = grey(capture).astype(np.float32)
    shade = BoardShade(layout, camera, g)
    if layout.charuco is not None:
        named = (charuco if charuco is not None
                 else detect_charuco(np.clip(g, 0, 255).astype(np.uint8), layout.charuco))
        start = None if named is None else _charuco_start(camera, ypr0_deg, layout, named, shade)
        if start is not None:
            return BoardSearch(start)
    outcomes: list[BoardSearch] = []
    weak: list[BoardStart] = []  # starts that do not pin the pose: the largest, if no other
    for det in detect_grids(g, camera, layout, views):
        outcome = _judge(camera, ypr0_deg, layout, det, shade)
        if outcome.start is not None and (outcome.start.pins_pose or outcome.start.whole):
            return outcome  # pinned; or the whole board, which no other place betters
        if outcome.start is not None:
            weak.append(outcome.start)
        else:
            outcomes.append(outcome)
    if weak:
        return BoardSearch(max(weak, key=lambda st: len(st.found)))
    if not outcomes:
        return BoardSearch(None, "the chessboard detector did not find the board (whole or "
                           f"a part of at least {MIN_PATCH[0]} × {MIN_PATCH[1]} inner corners) "
                           "in the capture")
    # the most telling failure: an ambiguous lattice, else the largest grid's
    return max(outcomes, key=lambda o: (o.ambiguous, 0 if o.corners is None else len(o.corners)))


def find_board_start(capture: np.ndarray, camera: FisheyeCamera, ypr0_deg: np.ndarray,
                     layout: BoardLayout, views: tuple[str, ...] = VIEWS,
                     charuco: tuple[np.ndarray, np.ndarray] | None = None) -> BoardStart | None:
    """The scene's mount correction from the board found in ``capture``, or None (see
    :func:`search_board`, which also says why there is none)."""
    return search_board(capture, camera, ypr0_deg, layout, views, charuco).start


def _judge(camera: FisheyeCamera, ypr0_deg: np.ndarray, layout: BoardLayout,
           det: GridDetection, shade: BoardShade) -> BoardSearch:
    """The start from one detected grid, or why it gives none."""
    corners = det.corners.reshape(-1, 2)
    where = f"{det.n} corners in the {det.view}"
    readings = _candidates(camera, layout, det.corners, shade)
    near = [c for c in readings
            if c.turn_deg <= MAX_START_TURN_DEG and c.move_m <= MAX_START_MOVE_M]
    coloured = [c for c in readings if c.score >= MIN_COLOUR_SCORE]
    if not near or max(c.score for c in near) < MIN_COLOUR_SCORE:
        if coloured:
            far = max(coloured, key=lambda c: c.score)
            return BoardSearch(None, f"the board was found ({where}), but its colours fit only "
                               f"a pose {far.turn_deg:.0f}° and {far.move_m:.2f} m from the "
                               f"scene's (more than {MAX_START_TURN_DEG:.0f}° or "
                               f"{MAX_START_MOVE_M:.1f} m): is the scene's mount right?",
                               corners=corners)
        best = max((c.score for c in readings), default=-1.0)
        return BoardSearch(None, f"a grid of {where} is not the board: no reading of it has "
                           f"the board's square colours (best r = {best:.2f} < "
                           f"{MIN_COLOUR_SCORE})", corners=corners)
    near.sort(key=lambda c: -c.score)
    rivals = [c for c in near if c.score >= near[0].score - RIVAL_SCORE]
    pick, rival, ev = _decide(rivals, shade)
    if rival is not None and ev is not None:
        return BoardSearch(None, _ambiguity_text(where, pick, rival, ev, layout),
                           ambiguous=True, corners=corners,
                           outlines=tuple(board_outline(camera, layout, c.position, c.rotation)
                                          for c in (pick, rival)))
    # the half turn (however far from the scene's rotation) with the same colours: the
    # scene's rotation chose
    ties = [c for c in coloured if c.score >= pick.score - COLOUR_TIE]
    nx, ny = layout.grid
    inner = (pick.ij[:, 0] >= 0) & (pick.ij[:, 0] < nx) & (pick.ij[:, 1] >= 0) \
        & (pick.ij[:, 1] < ny)
    steps = np.concatenate([np.linalg.norm(np.diff(det.corners, axis=a), axis=-1).ravel()
                            for a in (0, 1) if det.corners.shape[a] > 1])
    start = _polished(camera, ypr0_deg, layout, pick.position, pick.rotation, pick.ij[inner],
                      pick.found[inner], float(np.median(steps)), det.view, pick.score,
                      len(ties) > 1, len(rivals) - 1, det.whole)
    if start is None:
        return BoardSearch(None, f"the grid of {where} does not fit one board pose (RMS over "
                           f"{MAX_START_RMS:.0%} of the corner spacing): not the board",
                           corners=corners)
    return BoardSearch(start)


def _decide(rivals: list[_Reading],
            shade: BoardShade) -> tuple[_Reading, _Reading | None, LatticeEvidence | None]:
    """Which of the readings whose colour scores are close the capture supports: each pair
    is decided by the samples where their colours differ
    (:meth:`~.board.BoardShade.lattice_evidence` and :meth:`~.board.LatticeEvidence.winner`
    with :data:`MIN_VOTES` and :data:`MIN_FIT`).  Returns (the pick, a rival nothing tells
    from it or None, their evidence)."""
    pick = rivals[0]

    def pose(c: _Reading) -> tuple[np.ndarray, np.ndarray]:
        return c.position, c.rotation

    for other in rivals[1:]:  # a rival the capture prefers takes over
        if shade.lattice_evidence(pose(pick), pose(other)).winner(MIN_VOTES, MIN_FIT) == 2:
            pick = other
    for other in rivals:
        if other is pick:
            continue
        ev = shade.lattice_evidence(pose(pick), pose(other))
        if ev.winner(MIN_VOTES, MIN_FIT) != 1:
            return pick, other, ev
    return pick, None, None


def _ambiguity_text(where: str, pick: _Reading, second: _Reading, ev: LatticeEvidence,
                    layout: BoardLayout) -> str:
    """Why two readings cannot be told apart, in the board's squares."""
    shift = (second.position - pick.position) / layout.square_size
    along = (f"{abs(float(shift @ layout.a)):.0f} squares along the board's width and "
             f"{abs(float(shift @ layout.b)):.0f} along its height")
    evidence = (f"of the {ev.n_differ} samples where their colours differ, "
                f"{ev.share_1:.0%} favour one, need {MIN_FIT:.0%} of at least {MIN_VOTES}"
                if ev.n_differ >= MIN_VOTES else
                f"where only one sees the board, {ev.fit_1:.0%} of {ev.n_1} and {ev.fit_2:.0%} "
                f"of {ev.n_2} samples fit it" if max(ev.n_1, ev.n_2) >= MIN_VOTES else
                "nothing in view tells them apart")
    return (f"the board's lattice is ambiguous: its {where} fit two places on the board "
            f"({along} apart; {evidence}): the board's edges are out of view or hidden; "
            "show more of the board, with its edge")


def _best_start(camera: FisheyeCamera, ypr0_deg: np.ndarray, layout: BoardLayout,
                det: np.ndarray, shade: BoardShade, view: str) -> BoardStart | None:
    """:func:`_judge` on the detected corners ``det`` (rows, cols, 2) px: its start or None."""
    return _judge(camera, ypr0_deg, layout, GridDetection(det, view, True), shade).start


def _polished(camera: FisheyeCamera, ypr0_deg: np.ndarray, layout: BoardLayout,
              position: np.ndarray, rotation: np.ndarray, ij: np.ndarray, found: np.ndarray,
              step_px: float, view: str, score: float, ambiguous: bool,
              rivals: int = 0, whole: bool = True) -> BoardStart | None:
    """The start from a PnP pose (``position`` m, ``rotation``) and the inner corners
    ``ij`` (K, 2) found at ``found`` (K, 2) px, polished by our fisheye PnP; None when they
    do not fit one board pose (RMS over :data:`MAX_START_RMS` of ``step_px``, or 0.5 px) or
    do not pin it (:data:`MAX_START_SIGMA_M`, :data:`MAX_START_SIGMA_DEG` for corners good
    to :data:`START_NOISE_PX`)."""
    x0 = np.concatenate([position - camera.position,
                         (ypr_from_rotation(rotation) - ypr0_deg + 180.0) % 360.0 - 180.0])
    pts = layout.corner_points[ij[:, 0], ij[:, 1]]
    x, resid, sigma = fit_pose(camera, ypr0_deg, pts, found, x0=x0)
    rms = float(np.sqrt(np.mean(resid ** 2)))
    if rms > max(0.5, MAX_START_RMS * step_px):
        return None
    # the pose's uncertainty for corners good to START_NOISE_PX (fit_pose scales it by
    # the residuals, which a few exact corners make tiny)
    per_component = float(np.sqrt(np.sum(resid ** 2) / max(1, 2 * len(resid) - 6)))
    spread = sigma * START_NOISE_PX / max(per_component, 1e-6)
    return BoardStart(x=x, found=found, corner_ij=ij, view=view, rms_px=rms,
                      colour_score=float(score), ambiguous=ambiguous, rivals=rivals,
                      whole=whole, sigma=spread)


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


def board_outline(camera: FisheyeCamera, layout: BoardLayout, position: np.ndarray,
                  rotation: np.ndarray, per_side: int = 24) -> np.ndarray:
    """The outline of the board's squares seen from the pose (``position`` m,
    camera-to-scene ``rotation``): (M, 2) px, ``per_side`` points along each side (the
    fisheye bends them), points outside the lens's field left out."""
    s = layout.square_size
    w, h = (layout.grid[0] + 1) * s, (layout.grid[1] + 1) * s
    t = np.linspace(0.0, 1.0, per_side, endpoint=False)
    a = np.concatenate([t * w, np.full_like(t, w), (1 - t) * w, np.zeros_like(t)]) - s
    b = np.concatenate([np.zeros_like(t), t * h, np.full_like(t, h), (1 - t) * h]) - s
    pts = layout.origin + a[:, None] * layout.a + b[:, None] * layout.b
    uv, ok = camera.project_rays((pts - position) @ rotation)
    return np.asarray(uv[ok], np.float64)


def predicted_shift_px(camera: FisheyeCamera, ypr0_deg: np.ndarray, x: np.ndarray,
                       points: np.ndarray) -> float:
    """Largest image move of ``points`` (m) between the scene's pose and the correction
    ``x``, px."""

    before = project(camera, camera.position, camera.rotation, points)
    after = project(camera, *corrected_pose(camera, ypr0_deg, x), points)
    return float(np.max(np.linalg.norm(after - before, axis=1)))
