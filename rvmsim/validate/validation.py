"""Validate a scene against a real capture from the vehicle's rear-view camera.

A tuning is only worth as much as the synthetic frame it is tuned on.  :func:`validate`
compares the scene's rendered fisheye frame with a capture of the physical camera at the
test site and says what to fix in the scene, in these steps:

1. **Landmarks** (:mod:`.landmarks`, :mod:`.matching`): the scene's checker corners that
   the synthetic frame shows, found in the capture.
2. **Pose** (:mod:`.pose`): the mount pose that best explains the found corners, by fisheye
   PnP in the scene's mount parameters, alternating with the matching.
3. **Edges** (:mod:`.edges`): symmetric chamfer distance of the Canny edges over the part of
   the view the scene models, with the scene's pose and after a re-render at the corrected
   pose.
4. **RVM** (:mod:`.rvm`, with ISP parameters): both frames through our ISP, and the ECs.
5. **Verdict** (:mod:`.verdict`) against :class:`~.verdict.Tolerances`.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Union

import numpy as np

from ..camera import ypr_from_rotation
from ..criteria import Criteria, default_criteria
from ..isp import IspParams, OutputSpec
from ..render import FisheyeImages, cached_render, render_fisheye
from ..scene import Scene
from .board import BoardShade, board_layout
from .board_start import VIEWS, BoardStart, predicted_shift_px, search_board
from .capture import check_capture_size, grey
from .charuco import detect_charuco
from .failure import ValidationFailure
from .landmarks import VisibleLandmarks, visible_landmarks
from .outputs import board_picture, compare_with_pictures, landmark_picture
from .pose import PoseFit, PoseSearch, find_pose, pose_correction
from .projection import corrected_pose, project
from .rvm import compare_rvm
from .scene_edit import mount_correction, scene_with_mount
from .shade_search import MIN_SCORE as SHADE_MIN_SCORE
from .shade_search import ShadeStart, search_pose_by_shade
from .verdict import LandmarkMatch, PoseCorrection, Tolerances, Validation, judge
from ..pipeline import record_output

__all__ = ["validate", "ValidationSettings", "RERENDER_SHIFT_PX"]

#: A board start that moves the landmarks' predictions further than this re-renders the
#: synthetic frame there before matching, px.
RERENDER_SHIFT_PX = 3.0


@dataclass(frozen=True)
class ValidationSettings:
    """How a capture is judged (``rvmsim validate``'s options).

    Parameters
    ----------
    params, output, criteria : IspParams, OutputSpec, Criteria, optional
        With ISP parameters, the capture and the synthetic frame are also compared as RVM
        images (of ``output``'s size), and the ECs (``criteria``, default the paper's)
        evaluated on both.
    tolerances : Tolerances
        The verdict's limits.
    search_px : float
        How far from its prediction a landmark is searched for at first, px.
    rerender : bool
        Render the scene again at the corrected pose (for the corrected overlay, the
        edge comparison after correction and the capture's ECs).
    global_start : bool
        Look for the scene's board in the capture with the chessboard detector and start
        the pose search from the pose it gives (:func:`~.board_start.search_board`);
        else start from the scene's pose.
    dense_align : bool
        With ground patterns, start the corner matching from the dense pre-alignment on
        their shade: where no board start was found, the global search
        (:func:`~.shade_search.search_pose_by_shade`: from ±10° / ±0.3 m, ~2 s at
        960 × 640), then the local one (:func:`~.pose.dense_align`: for a pose tens of px
        off; ~1 s at 1280 × 960); without it, from the scene's pose (or the board start),
        which must then be within the search radius (a station's car within ±1° and a few
        mm of its nominal pose is), and the board is not looked for in tiles of the whole
        field (:data:`~.board_start.VIEWS`).  The checker-shift disambiguation runs either
        way.
    """

    params: IspParams | None = None
    output: OutputSpec | None = None
    criteria: Criteria | None = None
    tolerances: Tolerances = Tolerances()
    search_px: float = 30.0
    rerender: bool = True
    global_start: bool = True
    dense_align: bool = True


def validate(scene: Scene, capture: np.ndarray,
             settings: ValidationSettings = ValidationSettings(), *,
             synthetic: FisheyeImages | None = None, use_cache: bool = False,
             capture_name: str = "<array>", progress: bool = False) -> Validation:
    """Compare a real capture with the scene's synthetic frame.

    Parameters
    ----------
    scene : Scene
    capture : (H, W, 3) uint8
        RGB capture of the physical camera (see :func:`~.capture.load_capture`).
    synthetic : FisheyeImages, optional
        The scene's rendered frame; rendered when missing, through the render cache
        (:func:`rvmsim.render.cached_render`, keyed on the scene's content) with
        ``use_cache``.
    settings : ValidationSettings
        The ISP comparison, the verdict's tolerances, the search radius, the re-render and
        the board start.
    capture_name : str
        For messages and the JSON summary.
    progress : bool
        Progress bars while rendering.

    Raises
    ------
    RvmsimError
        Capture of the wrong size, or a scene without enough visible checker corners.
    ValidationFailure
        A step failed (``detection``: fewer than ``tolerances.min_landmarks`` landmarks
        found; ``correspondence``: a one-square alias; ``pose fit``), with the pictures.
    """
    if synthetic is None:
        synthetic = (cached_render(scene, progress=progress)[0] if use_cache
                     else render_fisheye(scene, progress=progress))
    cam = synthetic.camera
    check_capture_size(capture, cam, capture_name)
    tolerances, global_start = settings.tolerances, settings.global_start
    ypr0 = _mount_ypr_deg(scene)
    by_shade = settings.dense_align and bool(scene.test_site.ground_patterns)
    # Few corners in view at the scene's pose is an error only when no start helps.
    landmarks = visible_landmarks(scene, synthetic, 0 if global_start or by_shade
                                  else tolerances.min_landmarks)
    layout = board_layout(scene, landmarks.corners)
    charuco = (None if layout is None or layout.charuco is None else
               detect_charuco(np.clip(grey(capture), 0, 255).astype(np.uint8), layout.charuco))
    found = (search_board(capture, cam, ypr0, layout, _board_places(settings), charuco=charuco)
             if global_start and layout is not None else None)
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
            raise ValidationFailure("correspondence", f"{capture_name}: {found.reason}")
        start, x_start, search_lm, fit = search.fit_from_first(starts)
    except ValidationFailure as fail:
        images = _failure_pictures(capture, synthetic, landmarks, fail.found)
        if found is not None and found.corners is not None:
            images["board"] = board_picture(capture, found.corners, found.outlines)
        if found is not None and found.reason and found.reason not in fail.detail:
            fail = ValidationFailure(fail.step, f"{fail.detail}; the board search: "
                                     f"{found.reason}", found=fail.found)
        raise fail.with_images(images) from None
    fit = replace(fit, x=fit.x + x_start)
    landmarks = replace(search_lm, predicted_px=landmarks.predicted_px)
    correction = mount_correction(scene, pose_correction(cam, ypr0, fit.x, fit.sigma))
    pos1, rot1 = corrected_pose(cam, ypr0, fit.x)
    matches = _landmark_matches(landmarks, fit, project(cam, pos1, rot1, landmarks.points))
    err_before, err_after = _inlier_errors(matches)

    edges_before, images = compare_with_pictures(capture, synthetic.color, synthetic.labels,
                                                 "overlay", "edges")
    images["landmarks"] = landmark_picture(capture, matches)
    corrected, edges_after = None, None
    if settings.rerender:
        corrected = _render_corrected(scene, synthetic, correction, pos1, rot1, progress)
        edges_after, corrected_images = compare_with_pictures(
            capture, corrected.color, corrected.labels, "overlay_corrected", "edges_corrected")
        images.update(corrected_images)
    rvm = None
    if settings.params is not None:
        # the ECs judged at the RVM image of record, whatever size the params were searched at

        mirror = settings.output.mirror if settings.output is not None else True
        record = record_output(settings.criteria or default_criteria(), scene, mirror)
        rvm, rvm_images = compare_rvm(capture, synthetic, corrected, settings.params,
                                      record, settings.criteria)
        images.update(rvm_images)

    rms_after = _rms(err_after)
    return Validation(
        scene_name=scene.name, capture=capture_name, image_size=(cam.width, cam.height),
        landmarks=matches, n_predicted=landmarks.n_usable,
        rms_before_px=_rms(err_before), max_before_px=float(err_before.max()),
        rms_after_px=rms_after, max_after_px=float(err_after.max()),
        correction=correction, edges_before=edges_before, edges_after=edges_after, rvm=rvm,
        checks=judge(rms_after, correction, edges_before, tolerances), images=images,
        start=_start_text(start),
    )


@dataclass(frozen=True)
class _PoseStart:
    """What the pose search from a start needs (one validation)."""

    scene: Scene
    capture: np.ndarray
    synthetic: FisheyeImages
    landmarks: VisibleLandmarks
    ypr0: np.ndarray
    settings: ValidationSettings
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
        first: ValidationFailure | None = None
        near: ValidationFailure | None = None
        for plan in starts:
            start: BoardStart | ShadeStart | None = None
            if isinstance(plan, BoardStart):
                start = plan
            elif callable(plan):
                start = plan()
            try:
                if isinstance(start, ShadeStart) and start.score < SHADE_MIN_SCORE:
                    raise ValidationFailure(
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
            except ValidationFailure as fail:
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
        frame) from ``start`` (:func:`_search_frame`, :func:`~.pose.find_pose`); the dense
        pre-alignment runs when ``dense`` (default: the settings say so and the start is
        not the shade search's, which ends with the same alignment)."""
        tol = self.settings.tolerances
        x_start, syn, lm = _search_frame(self.scene, self.synthetic, self.landmarks, start,
                                         self.ypr0, tol.min_landmarks, self.progress,
                                         self.capture_name, self.board_search)
        if dense is None:
            dense = self.settings.dense_align and not isinstance(start, ShadeStart)
        fit = find_pose(PoseSearch(self.capture, syn, self.scene, lm, self.ypr0 + x_start[3:],
                                   float(self.settings.search_px), tol.min_landmarks,
                                   self.capture_name, self.named),
                        self.board, self.board_index, dense=dense)
        return x_start, lm, fit


#: A start: a board start or None (the scene's pose), the shade search (called when its turn
#: comes) or ``"near"`` (the scene's pose, kept only for a small correction).
_Start = Union[BoardStart, None, Callable[[], Union[ShadeStart, None]], str]
#: The scene's own pose is kept as the start (no global search) when the fit from it moves
#: the mount at most this far (m, degrees) and explains :data:`NEAR_SHARE` of the corners.
NEAR_M, NEAR_DEG, NEAR_SHARE = 0.05, 2.0, 0.8


def _board_places(settings: ValidationSettings) -> tuple[str, ...]:
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
            raise ValidationFailure(
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
    frame = _render_corrected(scene, synthetic,
                              mount_correction(scene, pose_correction(
                                  synthetic.camera, ypr0, start.x, np.zeros(6))),
                              pos, rot, progress)
    seen = visible_landmarks(scene, frame, 0)
    if seen.n_usable < min_landmarks:
        raise ValidationFailure(
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


def _failure_pictures(capture: np.ndarray, synthetic: FisheyeImages,
                      landmarks: VisibleLandmarks,
                      found: np.ndarray | None) -> dict[str, np.ndarray]:
    """The pictures of a validation that stopped: the blend and edges with the scene's pose,
    and the landmarks (predicted; found ones drawn as not fitted)."""
    _, images = compare_with_pictures(capture, synthetic.color, synthetic.labels,
                                      "overlay", "edges")
    uv = landmarks.predicted_px
    matches = tuple(
        LandmarkMatch(name=c.name, point=c.point,
                      predicted_px=(float(uv[n, 0]), float(uv[n, 1])),
                      found_px=None if found is None or not np.isfinite(found[n, 0])
                      else (float(found[n, 0]), float(found[n, 1])),
                      corrected_px=(float(uv[n, 0]), float(uv[n, 1])),
                      method="", ncc=0.0, inlier=False)
        for n, c in enumerate(landmarks.corners) if landmarks.usable[n])
    images["landmarks"] = landmark_picture(capture, matches)
    return images


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


def _render_corrected(scene: Scene, synthetic: FisheyeImages, correction: PoseCorrection,
                      position: np.ndarray, rotation: np.ndarray,
                      progress: bool) -> FisheyeImages:
    """The scene rendered again at the corrected pose (position m, rotation)."""
    return render_fisheye(scene_with_mount(scene, correction),
                          camera=replace(synthetic.camera, position=position, rotation=rotation),
                          progress=progress)


def _mount_ypr_deg(scene: Scene) -> np.ndarray:
    """The yaw, pitch, roll (degrees) of the scene's camera: its mount angles, or under a
    ``load_state`` those of the camera moved with the body (where the pose search starts)."""
    if scene.load_state is not None:
        return ypr_from_rotation(scene.fisheye_camera().rotation)
    m = scene.camera.mount
    return np.array([m.yaw_deg, m.pitch_deg, m.roll_deg], dtype=np.float64)
