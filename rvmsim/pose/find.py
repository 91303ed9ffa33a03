"""Find the camera's mount pose in a capture of the test site (or a station's target).

:func:`find_mount` is the whole search, the part of ``rvmsim validate`` that ``rvmsim eol``
(a car's pose at the station) needs too:

1. **Landmarks** (:mod:`.landmarks`): the scene's checker corners its frame shows usably.
2. **Starts** (:mod:`.board_start`, :mod:`.shade_search`): the board found by the
   chessboard detector (or its ChArUco markers), and with ground patterns the pose whose
   patterns' shade fits the capture; else the scene's pose.
3. **Matching and fit** (:mod:`.matching`, :mod:`.fit`): the corners found near their
   predictions, and the mount pose by fisheye PnP in the scene's mount parameters,
   alternating with the matching.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.  Positions are in the scene frame, m; angles degrees.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Union

import numpy as np

from ..camera import ypr_from_rotation
from ..render import FisheyeImages, render_fisheye
from ..scene import Scene
from .board import BoardShade, board_layout
from .board_start import VIEWS, BoardStart, predicted_shift_px, search_board
from .capture import check_capture_size, grey
from .charuco import detect_charuco
from .failure import PoseFailure
from .fit import PoseFit, PoseSearch, find_pose, pose_correction
from .landmarks import VisibleLandmarks, visible_landmarks
from .mount import mount_correction, scene_with_mount
from .projection import corrected_pose, project
from .records import LandmarkMatch, PoseCorrection
from .shade_search import MIN_SCORE as SHADE_MIN_SCORE
from .shade_search import ShadeStart, search_pose_by_shade

__all__ = ["PoseSettings", "MountFit", "find_mount", "render_corrected", "RERENDER_SHIFT_PX"]

#: A board start that moves the landmarks' predictions further than this re-renders the
#: synthetic frame there before matching, px.
RERENDER_SHIFT_PX = 3.0


@dataclass(frozen=True)
class PoseSettings:
    """How the mount pose is searched for.

    Parameters
    ----------
    min_landmarks : int
        Fewer matched landmarks than this is a failure (:class:`~.failure.PoseFailure`).
    search_px : float
        How far from its prediction a landmark is searched for at first, px.
    global_start : bool
        Look for the scene's board in the capture with the chessboard detector and start
        the pose search from the pose it gives (:func:`~.board_start.search_board`);
        else start from the scene's pose.
    dense_align : bool
        With ground patterns, start the corner matching from the dense pre-alignment on
        their shade: where no board start was found, the global search
        (:func:`~.shade_search.search_pose_by_shade`: from ±10° / ±0.3 m, ~2 s at
        960 × 640), then the local one (:func:`~.fit.dense_align`: for a pose tens of px
        off; ~1 s at 1280 × 960); without it, from the scene's pose (or the board start),
        which must then be within the search radius (a station's car within ±1° and a few
        mm of its nominal pose is), and the board is not looked for in tiles of the whole
        field (:data:`~.board_start.VIEWS`).  The checker-shift disambiguation runs either
        way.
    """

    min_landmarks: int = 8
    search_px: float = 30.0
    global_start: bool = True
    dense_align: bool = True


@dataclass(frozen=True)
class MountFit:
    """The mount pose found in a capture.

    Attributes
    ----------
    correction : PoseCorrection
        The change of the mount and the corrected mount values (those of ``camera.mount``:
        under a ``load_state``, on the unloaded body).
    position_m : (3,) float
        The corrected camera position as the scene shows it (under a load state, moved
        with the body), scene frame, m.
    rotation : (3, 3) float
        The corrected camera rotation as the scene shows it.
    landmarks : tuple of LandmarkMatch
        Every usable landmark: predicted, found, reprojected at the corrected pose.
    n_predicted : int
        The landmarks predicted usable at the scene's pose.
    start : str
        How the search started, for the summary.
    """

    correction: PoseCorrection
    position_m: np.ndarray
    rotation: np.ndarray
    landmarks: tuple[LandmarkMatch, ...]
    n_predicted: int
    start: str

    @property
    def n_inliers(self) -> int:
        """The landmarks the final fit used."""
        return sum(m.inlier for m in self.landmarks)

    def errors_px(self) -> tuple[np.ndarray, np.ndarray]:
        """Distances of the inliers' finds from their predictions and from their corrected
        reprojections, px."""
        inl = [m for m in self.landmarks if m.inlier]
        found = np.array([m.found_px for m in inl], dtype=np.float64).reshape(-1, 2)
        before = np.array([m.predicted_px for m in inl], dtype=np.float64).reshape(-1, 2)
        after = np.array([m.corrected_px for m in inl], dtype=np.float64).reshape(-1, 2)
        return np.linalg.norm(found - before, axis=1), np.linalg.norm(found - after, axis=1)

    @property
    def rms_after_px(self) -> float:
        """RMS distance of the inliers' finds from their corrected reprojections, px."""
        return float(np.sqrt(np.mean(self.errors_px()[1] ** 2)))


def find_mount(scene: Scene, capture: np.ndarray, synthetic: FisheyeImages,
               settings: PoseSettings = PoseSettings(), *, capture_name: str = "<array>",
               progress: bool = False) -> MountFit:
    """The mount pose that best explains the scene's checker corners found in ``capture``.

    Parameters
    ----------
    scene : Scene
    capture : (H, W, 3) uint8
        RGB capture of the physical camera (:func:`~.capture.load_capture`), the camera's
        size.
    synthetic : FisheyeImages
        The scene's rendered frame at its pose (the corners' templates and predictions).
    settings : PoseSettings
    capture_name : str
        For messages.
    progress : bool
        Progress bars while rendering a start's frame.

    Raises
    ------
    RvmsimError
        Capture of the wrong size, or a scene without enough visible checker corners.
    PoseFailure
        A step failed (``detection``: fewer than ``min_landmarks`` landmarks found;
        ``correspondence``: a one-square alias; ``pose fit``), with the landmarks predicted
        and what the board search gave (for pictures).
    """
    cam = synthetic.camera
    check_capture_size(capture, cam, capture_name)
    ypr0 = _mount_ypr_deg(scene)
    by_shade = settings.dense_align and bool(scene.test_site.ground_patterns)
    # Few corners in view at the scene's pose is an error only when no start helps.
    landmarks = visible_landmarks(scene, synthetic, 0 if settings.global_start or by_shade
                                  else settings.min_landmarks)
    layout = board_layout(scene, landmarks.corners)
    charuco = (None if layout is None or layout.charuco is None else
               detect_charuco(np.clip(grey(capture), 0, 255).astype(np.uint8), layout.charuco))
    found = (search_board(capture, cam, ypr0, layout, _board_places(settings), charuco=charuco)
             if settings.global_start and layout is not None else None)
    starts = _start_plan(None if found is None else found.start, by_shade,
                         lambda: search_pose_by_shade(scene, cam, ypr0, capture, layout))
    board = (None if layout is None
             else BoardShade(layout, cam, grey(capture).astype(np.float32)))
    # A ChArUco board's corners, by landmark index (its markers name them).
    named = (None if charuco is None or layout is None else
             {int(layout.corner_index[i, j]): xy for (i, j), xy in zip(*charuco)})
    search = _PoseStart(scene, capture, synthetic, landmarks, ypr0, settings, capture_name,
                        named, board, None if layout is None else layout.corner_index.ravel(),
                        progress, "" if found is None else found.reason)
    try:
        if found is not None and found.ambiguous and not by_shade:
            raise PoseFailure("correspondence", f"{capture_name}: {found.reason}")
        start, x_start, search_lm, fit = search.fit_from_first(starts)
    except PoseFailure as fail:
        detail = fail.detail
        if found is not None and found.reason and found.reason not in detail:
            detail = f"{detail}; the board search: {found.reason}"
        raise PoseFailure(fail.step, detail, found=fail.found,
                          landmarks=_unfitted_matches(landmarks, fail.found),
                          board_corners=None if found is None else found.corners,
                          board_outlines=() if found is None else found.outlines) from None
    fit = replace(fit, x=fit.x + x_start)
    landmarks_at_start = replace(search_lm, predicted_px=landmarks.predicted_px)
    correction = mount_correction(scene, pose_correction(cam, ypr0, fit.x, fit.sigma))
    pos1, rot1 = corrected_pose(cam, ypr0, fit.x)
    matches = _landmark_matches(landmarks_at_start, fit,
                                project(cam, pos1, rot1, landmarks_at_start.points))
    return MountFit(correction=correction, position_m=pos1, rotation=rot1, landmarks=matches,
                    n_predicted=landmarks_at_start.n_usable, start=_start_text(start))


def render_corrected(scene: Scene, synthetic: FisheyeImages, correction: PoseCorrection,
                     position: np.ndarray, rotation: np.ndarray,
                     progress: bool = False) -> FisheyeImages:
    """The scene rendered again at the corrected pose (``position`` m, ``rotation``; the
    scene's mount set from ``correction``, which moves its body under a load state)."""
    return render_fisheye(scene_with_mount(scene, correction),
                          camera=replace(synthetic.camera, position=position, rotation=rotation),
                          progress=progress)


@dataclass(frozen=True)
class _PoseStart:
    """What the pose search from a start needs (one search)."""

    scene: Scene
    capture: np.ndarray
    synthetic: FisheyeImages
    landmarks: VisibleLandmarks
    ypr0: np.ndarray
    settings: PoseSettings
    capture_name: str
    named: dict[int, np.ndarray] | None
    board: BoardShade | None
    board_index: np.ndarray | None
    progress: bool
    board_search: str = ""

    def fit_from_first(self, starts: list[_Start]) -> tuple[
            BoardStart | ShadeStart | None, np.ndarray, VisibleLandmarks, PoseFit]:
        """The fit from the first of ``starts`` that gives one (:meth:`fit_from`; a shade
        search's start is matched twice; the scene's own pose only when it needs a small
        correction, :data:`NEAR_M` and :data:`NEAR_DEG`, and explains most corners), with
        that start; when none does, the first failure of a start that was not a shortcut (the
        scene's own pose tried as "near" says only that it is not near)."""
        first: PoseFailure | None = None
        near: PoseFailure | None = None
        for plan in starts:
            start: BoardStart | ShadeStart | None = None
            if isinstance(plan, BoardStart):
                start = plan
            elif callable(plan):
                start = plan()
            try:
                if isinstance(start, ShadeStart) and start.score < SHADE_MIN_SCORE:
                    raise PoseFailure(
                        "detection", f"{self.capture_name}: the scene's patterns fit the "
                        f"capture's shade nowhere within ±10° / ±0.3 m of its pose (best "
                        f"correlation {start.score:.2f}, < {SHADE_MIN_SCORE}): is the capture "
                        "of this scene?")
                x_start, lm, fit = self.fit_from(start)
                if plan == "near" and not _near_fit(fit, lm):
                    continue
                if isinstance(start, ShadeStart) and x_start.any():
                    # The frame at the shade's pose can be ~1 cm / 0.2° off the corners'
                    # pose, and its templates then bias the corners by a few mm: match once
                    # more in a frame rendered at the fitted pose.
                    x_start, lm, fit = self.fit_from(replace(start, x=fit.x + x_start),
                                                     dense=False)
                return start, x_start, lm, fit
            except PoseFailure as fail:
                if plan == "near":
                    near = fail
                else:
                    first = first or fail
        failure = first or near
        assert failure is not None
        raise failure

    def fit_from(self, start: BoardStart | ShadeStart | None, *,
                 dense: bool | None = None) -> tuple[np.ndarray, VisibleLandmarks, PoseFit]:
        """(the start's correction, the landmarks of the frame matched in, the fit in that
        frame) from ``start`` (:func:`_search_frame`, :func:`~.fit.find_pose`); the dense
        pre-alignment runs when ``dense`` (default: the settings say so and the start is
        not the shade search's, which ends with the same alignment)."""
        x_start, syn, lm = _search_frame(self.scene, self.synthetic, self.landmarks, start,
                                         self.ypr0, self.settings.min_landmarks, self.progress,
                                         self.capture_name, self.board_search)
        if dense is None:
            dense = self.settings.dense_align and not isinstance(start, ShadeStart)
        fit = find_pose(PoseSearch(self.capture, syn, self.scene, lm, self.ypr0 + x_start[3:],
                                   float(self.settings.search_px), self.settings.min_landmarks,
                                   self.capture_name, self.named),
                        self.board, self.board_index, dense=dense)
        return x_start, lm, fit


#: A start: a board start or None (the scene's pose), the shade search (called when its turn
#: comes) or ``"near"`` (the scene's pose, kept only for a small correction).
_Start = Union[BoardStart, None, Callable[[], Union[ShadeStart, None]], str]
#: The scene's own pose is kept as the start (no global search) when the fit from it moves
#: the mount at most this far (m, degrees) and explains :data:`NEAR_SHARE` of the corners.
NEAR_M, NEAR_DEG, NEAR_SHARE = 0.05, 2.0, 0.8


def _board_places(settings: PoseSettings) -> tuple[str, ...]:
    """Where the board is looked for: a station's car near its nominal pose (no dense
    search) needs no tiles of the whole field."""
    return VIEWS if settings.dense_align else tuple(v for v in VIEWS if v != "tiles")


def _start_plan(board_start: BoardStart | None, by_shade: bool,
                shade: Callable[[], ShadeStart | None]) -> list[_Start]:
    """The starts to try in order: a board start that pins the pose alone; else, with
    ground patterns, the scene's pose when it is near, the global shade search, then the
    board's weak start."""
    if not by_shade or (board_start is not None and board_start.pins_pose):
        return [board_start]
    plan: list[_Start] = ["near", shade]
    return plan + ([board_start] if board_start is not None else [])


def _near_fit(fit: PoseFit, landmarks: VisibleLandmarks) -> bool:
    """The fit from the scene's pose needs only a small correction and explains most of the
    corners in view."""
    return bool(np.all(np.abs(fit.x[:3]) <= NEAR_M) and np.all(np.abs(fit.x[3:]) <= NEAR_DEG)
                and fit.inliers.sum() >= NEAR_SHARE * landmarks.n_usable)


def _search_frame(scene: Scene, synthetic: FisheyeImages, landmarks: VisibleLandmarks,
                  start: BoardStart | ShadeStart | None, ypr0: np.ndarray, min_landmarks: int,
                  progress: bool, capture_name: str,
                  board_search: str = "") -> tuple[np.ndarray, FisheyeImages, VisibleLandmarks]:
    """Where the pose search starts: (the start's correction, the frame rendered there, its
    landmarks).  The scene's own frame when there is no start (the board's or the shade
    search's) or it moves no usable
    landmark by more than :data:`RERENDER_SHIFT_PX` (the local matching's templates come
    from that frame, so it must show the capture's view closely).  ``board_search``: why
    the board gave no start, for the message when nothing else helps."""
    if start is None:
        if landmarks.n_usable < min_landmarks:
            board = (board_search if board_search else
                     "the scene has no board to look for" if not scene.test_site.board.enabled
                     else "the board was not looked for")
            raise PoseFailure(
                "detection", f"{capture_name}: {board}; and at the scene's pose only "
                f"{landmarks.n_usable} checker corners are visible in the synthetic frame "
                f"(need {min_landmarks}); compare the pictures: is the mount far off, or "
                "the board out of view or too small?")
        return np.zeros(6), synthetic, landmarks
    if landmarks.n_usable >= max(min_landmarks, 1) and predicted_shift_px(
            synthetic.camera, ypr0, start.x,
            landmarks.points[landmarks.usable]) <= RERENDER_SHIFT_PX:
        return np.zeros(6), synthetic, landmarks
    pos, rot = corrected_pose(synthetic.camera, ypr0, start.x)
    frame = render_corrected(scene, synthetic,
                              mount_correction(scene, pose_correction(
                                  synthetic.camera, ypr0, start.x, np.zeros(6))),
                              pos, rot, progress)
    seen = visible_landmarks(scene, frame, 0)
    if seen.n_usable < min_landmarks:
        raise PoseFailure(
            "detection", f"{capture_name}: at the pose {_start_text(start)} only "
            f"{seen.n_usable} checker corners are visible in the frame rendered there (need "
            f"{min_landmarks}){'; the board search: ' + board_search if board_search else ''}")
    return start.x, frame, seen


def _start_text(start: BoardStart | ShadeStart | None) -> str:
    """How the pose search started, for the summary."""
    if start is None:
        return "the scene's pose"
    if isinstance(start, ShadeStart):
        return (f"the pose whose patterns' shade best fits the capture (global search: "
                f"r = {start.score:.2f}, {start.evaluations} poses scored)")
    if start.view == "ChArUco markers":
        return (f"the board found by its ChArUco markers ({len(start.found)} corners; corner "
                f"RMS {start.rms_px:.2f} px, square colours r = {start.colour_score:.2f})")
    part = "" if start.whole else f"a part of it, {len(start.found)} inner corners; "
    text = (f"the board found by the chessboard detector ({start.view}; {part}corner RMS "
            f"{start.rms_px:.2f} px, square colours r = {start.colour_score:.2f})")
    if start.rivals:
        text += (f"; {start.rivals} other placement(s) of its corners on the board were "
                 "refuted by the squares' colours where they differ")
    if start.ambiguous:
        text += ("; the board is half-turn symmetric, so its orientation was taken from the "
                 "scene's pose")
    return text


def _unfitted_matches(landmarks: VisibleLandmarks,
                      found: np.ndarray | None) -> tuple[LandmarkMatch, ...]:
    """One record per usable landmark of a search that stopped: predicted, and found where
    it was (none fitted: the reprojection is the prediction)."""
    uv = landmarks.predicted_px
    return tuple(
        LandmarkMatch(name=c.name, point=c.point,
                      predicted_px=(float(uv[n, 0]), float(uv[n, 1])),
                      found_px=None if found is None or not np.isfinite(found[n, 0])
                      else (float(found[n, 0]), float(found[n, 1])),
                      corrected_px=(float(uv[n, 0]), float(uv[n, 1])),
                      method="", ncc=0.0, inlier=False)
        for n, c in enumerate(landmarks.corners) if landmarks.usable[n])


def _landmark_matches(landmarks: VisibleLandmarks, fit: PoseFit,
                      corrected_px: np.ndarray) -> tuple[LandmarkMatch, ...]:
    """One record per usable landmark (predicted, found, corrected px)."""
    syn_uv, found = landmarks.predicted_px, fit.found
    return tuple(
        LandmarkMatch(
            name=c.name, point=c.point,
            predicted_px=(float(syn_uv[n, 0]), float(syn_uv[n, 1])),
            found_px=None if not np.isfinite(found[n, 0]) else (float(found[n, 0]),
                                                                float(found[n, 1])),
            corrected_px=(float(corrected_px[n, 0]), float(corrected_px[n, 1])),
            method=fit.method[n], ncc=float(fit.ncc[n]), inlier=bool(fit.inliers[n]),
        )
        for n, c in enumerate(landmarks.corners) if landmarks.usable[n]
    )


def _inlier_errors(matches: tuple[LandmarkMatch, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Distances of the inliers' finds from their predictions and from their corrected
    reprojections, px."""
    inl = [m for m in matches if m.inlier]
    found = np.array([m.found_px for m in inl], dtype=np.float64).reshape(-1, 2)
    before = np.array([m.predicted_px for m in inl], dtype=np.float64).reshape(-1, 2)
    after = np.array([m.corrected_px for m in inl], dtype=np.float64).reshape(-1, 2)
    return np.linalg.norm(found - before, axis=1), np.linalg.norm(found - after, axis=1)


def _rms(err: np.ndarray) -> float:
    return float(np.sqrt(np.mean(err ** 2)))


def _mount_ypr_deg(scene: Scene) -> np.ndarray:
    """The yaw, pitch, roll (degrees) of the scene's camera: its mount angles, or under a
    ``load_state`` those of the camera moved with the body (where the pose search starts)."""
    if scene.load_state is not None:
        return ypr_from_rotation(scene.fisheye_camera().rotation)
    m = scene.camera.mount
    return np.array([m.yaw_deg, m.pitch_deg, m.roll_deg], dtype=np.float64)
