"""The mount pose that explains a capture.

* :func:`fit_pose` is fisheye PnP in the scene's own mount parameters: Levenberg-Marquardt
  (trust-region) over Δposition (m) and Δyaw/pitch/roll (degrees) with our Kannala-Brandt
  projection; standard errors come from the Jacobian.
* :meth:`PoseSearch.match_and_fit` alternates landmark matching and fitting three times with
  a shrinking search radius: robust (soft-L1) first, then least squares on the inliers
  (residual ≤ max(1 px, 3 robust σ)).
* :func:`find_pose` gets there from a rough pose: with ground patterns, a dense
  pre-alignment (:class:`GroundShade`, :func:`dense_align`) first, then the checker-shift
  disambiguation (a checker is periodic; its non-periodic parts decide).

A *pose correction* ``x`` is (Δx, Δy, Δz m, Δyaw, Δpitch, Δroll degrees), see
:mod:`.projection`.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.  Positions are in the scene frame (x driver side, y down, z rearward);
the ground plane is y = 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares, minimize

from .. import labels as L
from ..camera import FisheyeCamera
from ..errors import RvmsimError
from ..render import FisheyeImages
from ..scene import PATTERN_LIFT_M, GroundPattern, Scene, pattern_axes, pattern_shade
from .board import BoardShade
from .capture import grey
from .failure import PoseFailure
from .landmarks import VisibleLandmarks
from .matching import find_landmarks
from .projection import corrected_pose, project
from .records import PoseCorrection

#: At the fitted pose, the board's squares must correlate this well with the capture.
MIN_BOARD_SCORE = 0.5

__all__ = [
    "fit_pose",
    "PoseFit",
    "PoseSearch",
    "GroundShade",
    "dense_align",
    "find_pose",
    "pose_correction",
]


def fit_pose(camera: FisheyeCamera, ypr_deg: ArrayLike, points: np.ndarray,
             found_px: np.ndarray, *, robust: bool = True,
             x0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fisheye PnP in the scene's mount parameters.

    Parameters
    ----------
    camera : FisheyeCamera
        The scene's camera (intrinsics and lens; its pose is the starting point).
    ypr_deg : (3,) float
        The scene's mount yaw, pitch, roll, degrees (``camera.rotation`` is made from them).
    points : (N, 3) float
        Scene points, metres.
    found_px : (N, 2) float
        Where they were found in the capture, px.
    robust : bool
        Soft-L1 loss with a 1 px scale (outliers weigh less); else plain least squares.
    x0 : (6,) float, optional
        Starting correction.

    Returns
    -------
    x : (6,) float
        Δx, Δy, Δz (m) and Δyaw, Δpitch, Δroll (degrees).
    residuals_px : (N,) float
        Reprojection error of each point after the correction.
    sigma : (6,) float
        One standard error of each component of ``x`` (same units).
    """

    points = np.asarray(points, dtype=np.float64)
    found_px = np.asarray(found_px, dtype=np.float64)
    ypr0 = np.asarray(ypr_deg, dtype=np.float64)

    def fun(x: np.ndarray) -> np.ndarray:
        pos, rot = corrected_pose(camera, ypr0, x)
        return (project(camera, pos, rot, points) - found_px).ravel()

    res = least_squares(fun, np.zeros(6) if x0 is None else np.asarray(x0, dtype=np.float64),
                        x_scale=np.array([0.01, 0.01, 0.01, 0.5, 0.5, 0.5]),
                        loss="soft_l1" if robust else "linear", f_scale=1.0, method="trf",
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200)
    r = fun(res.x)
    resid = np.hypot(r[0::2], r[1::2])
    jac = res.jac
    dof = max(1, len(r) - 6)
    try:
        cov = np.linalg.inv(jac.T @ jac) * float(r @ r) / dof
        sigma = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        # A singular normal matrix: the corners do not constrain every component.
        sigma = np.full(6, np.inf)
    return res.x, resid, sigma


@dataclass(frozen=True)
class PoseFit:
    """One round of matching and fitting.

    Attributes
    ----------
    x : (6,) float
        The pose correction (m, degrees).
    found : (N, 2) float
        Capture pixels of the landmarks, px (NaN: not found).
    ncc : (N,) float
        Match correlations.
    method : tuple of str
        How each landmark was found (``"chessboard"``, ``"charuco"``, ``"local"``, ``""``).
    inliers : (N,) bool
        Landmarks used by the final least-squares fit.
    sigma : (6,) float
        Standard errors of ``x``.
    """

    x: np.ndarray
    found: np.ndarray
    ncc: np.ndarray
    method: tuple[str, ...]
    inliers: np.ndarray
    sigma: np.ndarray


@dataclass(frozen=True)
class PoseSearch:
    """What matching and fitting need, fixed for one validation.

    Attributes
    ----------
    capture : (H, W, 3) uint8
    synthetic : FisheyeImages
        The scene's rendered frame.
    scene : Scene
    landmarks : VisibleLandmarks
    ypr0_deg : (3,) float
        The scene's mount yaw, pitch, roll, degrees.
    search_px : float
        First search radius, px.
    min_landmarks : int
        Fewer found landmarks is an error.
    capture_name : str
        For messages.
    named : dict, optional
        Landmarks found by name in the capture, {index: px} (a ChArUco board's corners).
    """

    capture: np.ndarray
    synthetic: FisheyeImages
    scene: Scene
    landmarks: VisibleLandmarks
    ypr0_deg: np.ndarray
    search_px: float
    min_landmarks: int
    capture_name: str
    named: dict[int, np.ndarray] | None = None

    def pose(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(position m, rotation) after the correction ``x``."""
        return corrected_pose(self.synthetic.camera, self.ypr0_deg, x)

    def match_and_fit(self, x: np.ndarray) -> PoseFit:
        """Alternate landmark matching and pose fitting three times from ``x``, the search
        radius shrinking to 3× the last RMS (clipped to 2 px .. ``search_px``).

        Raises
        ------
        RvmsimError
            Fewer than ``min_landmarks`` landmarks found.
        """
        cam = self.synthetic.camera
        lm, need = self.landmarks, self.min_landmarks
        pts = lm.points
        radius = float(self.search_px)
        for _ in range(3):
            pos, rot = self.pose(x)
            found, ncc, method, _pred = find_landmarks(
                self.capture, self.synthetic, self.scene, lm.corners, position=pos,
                rotation=rot, radius_px=radius, usable=lm.usable, named=self.named)
            ok = np.isfinite(found[:, 0])
            if ok.sum() < need:
                raise PoseFailure(
                    "detection",
                    f"{self.capture_name}: too few landmarks found: {int(ok.sum())} of "
                    f"{lm.n_usable} predicted checker corners (need {need}) within "
                    f"{radius:.0f} px (0.6 square at most) of where the start pose puts "
                    "them: the start is further off than that, or the capture is not of "
                    "this scene", found=found)
            idx = np.flatnonzero(ok)
            x_r, res_r, _ = fit_pose(cam, self.ypr0_deg, pts[idx], found[idx], robust=True, x0=x)
            mad = float(np.median(res_r)) * 1.4826
            keep = res_r <= max(1.0, 3.0 * mad)
            if keep.sum() < need:
                keep = res_r <= np.sort(res_r)[need - 1]
            x, res_i, sigma = fit_pose(cam, self.ypr0_deg, pts[idx[keep]], found[idx[keep]],
                                       robust=False, x0=x_r)
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(sigma))):
                raise PoseFailure(
                    "pose fit", f"{self.capture_name}: the {int(keep.sum())} matched "
                    "landmarks do not determine the mount pose (they lie on a line or too "
                    "close together)", found=found)
            inl = np.zeros(len(lm.corners), bool)
            inl[idx[keep]] = True
            rms = float(np.sqrt(np.mean(res_i ** 2)))
            radius = float(np.clip(3.0 * rms, 2.0, self.search_px))
        return PoseFit(x, found, ncc, tuple(method), inl, sigma)


@dataclass(frozen=True)
class GroundShade:
    """How well the ground patterns' black and white, seen from a pose, explain the capture.

    The score is the correlation of the pattern's shade (0 black, 1 white) with the
    capture's grey level over every 2nd pixel (both ways) where the synthetic frame sees the
    ground.  Build it with :meth:`sample`.

    Attributes
    ----------
    rays : (M, 3) float
        Camera-frame rays of the sampled pixels (inside the lens's field).
    grey : (M,) float
        The capture's grey level there (0..255).
    patterns : tuple of GroundPattern
        The scene's ground patterns (the first one wins where they overlap).
    """

    rays: np.ndarray
    grey: np.ndarray
    patterns: tuple[GroundPattern, ...]

    @classmethod
    def sample(cls, scene: Scene, cam: FisheyeCamera, labels: np.ndarray | None,
               capture: np.ndarray, *, step: int = 2, blur_px: float = 0.0) -> GroundShade:
        """Sample the ground pixels of ``labels`` (the scene's label image; None: every
        pixel in the lens's field) in ``capture``, every ``step`` px both ways, the
        capture's grey level blurred by a Gaussian of ``blur_px`` (σ, px; 0: not)."""

        vv, uu = np.mgrid[0:cam.height:step, 0:cam.width:step]
        keep = (np.ones(vv.shape, bool) if labels is None
                else np.isin(labels[vv, uu], (L.GROUND, L.GROUND_PATTERN)))
        uv = np.stack([uu[keep], vv[keep]], axis=1).astype(np.float64)
        rays, in_fov = cam.pixel_rays(uv)
        level = grey(capture)
        if blur_px > 0:
            level = cv2.GaussianBlur(level, (0, 0), blur_px)
        values = level[vv[keep], uu[keep]][in_fov].astype(np.float64)
        return cls(rays[in_fov], values, tuple(scene.test_site.ground_patterns))

    def shifts(self) -> list[np.ndarray]:
        """Camera moves (scene frame, m) that map the first pattern's checker onto itself
        with the same polarity: (du, dv) squares, du + dv even, up to two squares each way."""
        p = self.patterns[0]
        ax, bx = pattern_axes(p)
        return [p.square_size * (du * ax + dv * bx)
                for du in range(-2, 3) for dv in range(-2, 3)
                if (du + dv) % 2 == 0 and (du, dv) != (0, 0)]

    def __call__(self, position: np.ndarray, rotation: np.ndarray) -> float:
        """The correlation (-1..1) from the pose (position m, camera-to-scene rotation);
        -1 where fewer than 100 samples hit a pattern or the shade is constant."""
        shade = self.shade(position, rotation)
        ok = np.isfinite(shade)
        if ok.sum() < 100 or np.ptp(shade[ok]) == 0:
            return -1.0
        return float(np.corrcoef(shade[ok], self.grey[ok])[0, 1])

    def shade(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """The patterns' shade (0 black, 1 white) where each sample's ray meets the ground
        from the pose (position m, camera-to-scene rotation); NaN off the patterns."""
        d = self.rays @ rotation.T
        height = -PATTERN_LIFT_M - position[1]
        # rays down to the ground (none when the camera is below it)
        hit = np.flatnonzero(d[:, 1] > 1e-6) if height > 0 else np.zeros(0, np.int64)
        t = height / d[hit, 1]
        x = position[0] + t * d[hit, 0]
        z = position[2] + t * d[hit, 2]
        on = np.full(len(hit), np.nan)
        for p in self.patterns:
            on = np.where(np.isnan(on), pattern_shade(p, x, z), on)
        shade = np.full(len(d), np.nan)
        shade[hit] = on
        return shade


def dense_align(shade: GroundShade, cam: FisheyeCamera, ypr0_deg: np.ndarray, *,
                x0: np.ndarray | None = None, steps: np.ndarray | None = None,
                max_evaluations: int = 800) -> np.ndarray:
    """The pose correction maximising the ground-shade correlation.

    Nelder-Mead from ``x0`` (default zero) with initial steps ``steps`` (default 30 mm and
    1°), at most ``max_evaluations`` poses scored; ``x0`` if that does not improve the
    correlation.
    """

    def cost(x: np.ndarray) -> float:
        return -shade(*corrected_pose(cam, ypr0_deg, x))

    x0 = np.zeros(6) if x0 is None else np.asarray(x0, np.float64)
    steps = np.array([0.03, 0.03, 0.03, 1.0, 1.0, 1.0]) if steps is None else steps
    simplex = np.vstack([x0, x0 + np.diag(steps)])
    res = minimize(cost, x0, method="Nelder-Mead",
                   options={"initial_simplex": simplex, "xatol": 1e-4, "fatol": 1e-5,
                            "maxfev": max_evaluations})
    return np.asarray(res.x) if res.fun < cost(x0) else x0


def find_pose(search: PoseSearch, board: BoardShade | None = None,
              board_index: np.ndarray | None = None, *, dense: bool = True) -> PoseFit:
    """The matched landmarks and fitted pose, from the search's pose or near it.

    With ground patterns, the pose whose ground-pattern shade best fits the capture
    (:func:`dense_align`) brings the corners within a few px even when the search's pose is
    tens of px off; then :meth:`PoseSearch.match_and_fit`.  A checker is periodic: a pose
    one square off diagonally matches every corner with the right polarity.  The
    non-periodic parts decide: the ground patterns' borders, white squares and discs
    (:class:`GroundShade`), and the board's outer ring of squares (``board``,
    :class:`~.board.BoardShade`).  The same-polarity shifts are tried best-scoring first
    (the shade at the shifted pose), and a fit whose mean shade correlation is better by
    > 0.02 wins (with at least 80 % as many inliers); then again from it (three rounds at
    most).  A board's fit must then beat
    every shift on the samples where their colours differ, or the ground's shade must
    (:func:`_check_board_lattice`).

    Parameters
    ----------
    search : PoseSearch
    board : BoardShade, optional
        The scene's board, when it has one.
    board_index : (K,) int, optional
        The board's inner corners among the landmarks.
    dense : bool
        Run the dense pre-alignment on the ground patterns (else the matching starts at
        the search's pose; the shade still decides among the checker shifts).

    Raises
    ------
    PoseFailure
        Too few landmarks found from the starting pose (step ``detection``); the board's
        corners were matched but its squares' colours do not fit the pose, i.e. a
        one-square alias that no shift resolves, or a shift of the board fits as well (an
        ambiguous lattice; step ``correspondence``).
    """
    cam = search.synthetic.camera
    shades: list[GroundShade | BoardShade] = []
    x0 = np.zeros(6)
    if search.scene.test_site.ground_patterns:
        ground = GroundShade.sample(search.scene, cam, search.synthetic.labels, search.capture)
        shades.append(ground)
        if dense:
            x0 = dense_align(ground, cam, search.ypr0_deg)
    if board is not None:
        shades.append(board)
    fit = search.match_and_fit(x0)
    if not shades:
        return fit

    def score(x: np.ndarray) -> float:
        return float(np.mean([sh(*search.pose(x)) for sh in shades]))

    best = score(fit.x)
    shifts = [d for sh in shades for d in sh.shifts()]
    for _ in range(3):  # the best-scoring shifts first; again from a new fit
        tries = sorted(((score(fit.x + np.r_[dx, 0.0, 0.0, 0.0]), k)
                        for k, dx in enumerate(shifts)), reverse=True)
        moved = False
        for try_score, k in tries:
            if try_score <= best + 0.02:
                break
            try:
                alt = search.match_and_fit(fit.x + np.r_[shifts[k], 0.0, 0.0, 0.0])
            except RvmsimError:
                continue  # too few landmarks from that shift: it is not the pose
            alt_score = score(alt.x)
            # a true correction matches about as many corners as the alias did
            if alt_score > best + 0.02 and alt.inliers.sum() >= 0.8 * fit.inliers.sum():
                fit, best, moved = alt, alt_score, True
                break
        if not moved:
            break
    if board is not None and board_index is not None and fit.inliers[board_index].sum() >= 4:
        board_score = board(*search.pose(fit.x))
        if board_score < MIN_BOARD_SCORE:
            raise PoseFailure(
                "correspondence",
                f"{search.capture_name}: the board's corners were matched, but its squares' "
                f"colours do not fit the pose (correlation {board_score:.2f} < "
                f"{MIN_BOARD_SCORE}): the match is probably one square off", found=fit.found)
        _check_board_lattice(search, fit, board, [sh for sh in shades if sh is not board])
    usable = int(search.landmarks.n_usable)
    if fit.inliers.sum() < MIN_FIT_SHARE * usable:
        raise PoseFailure(
            "correspondence",
            f"{search.capture_name}: the fitted pose explains only {int(fit.inliers.sum())} of "
            f"the {usable} checker corners it predicts in view (need {MIN_FIT_SHARE:.0%}): "
            "it fits a part of the scene (e.g. a small part of the board, which a flipped "
            "pose also fits), not the capture", found=fit.found)
    return fit


#: A fit must explain at least this share of the checker corners predicted in view from the
#: frame it was matched in; a wrong pose that fits a few corners (a small part of a board
#: also fits its flipped pose) leaves most of the others unfound.
MIN_FIT_SHARE = 0.5


#: Two poses of the board are told apart by at least this many samples where their colours
#: differ, a share of at least :data:`LATTICE_SHARE` favouring one
#: (:meth:`~.board.LatticeEvidence.winner`).
LATTICE_VOTES = 12
LATTICE_SHARE = 0.75


def _check_board_lattice(search: PoseSearch, fit: PoseFit, board: BoardShade,
                         others: list[GroundShade | BoardShade]) -> None:
    """Refuse a fit that a same-colour shift of the board explains as well: the capture's
    board must prefer the fit to every shift (:meth:`~.board.BoardShade.lattice_evidence`),
    or the other evidence (the ground patterns' shade, better by > 0.02) must."""
    pose = search.pose(fit.x)

    def other_score(position: np.ndarray, rotation: np.ndarray) -> float:
        return float(np.mean([sh(position, rotation) for sh in others])) if others else -1.0

    base = other_score(*pose)
    for dx in board.shifts():
        shifted = (pose[0] + dx, pose[1])
        ev = board.lattice_evidence(pose, shifted)
        verdict = ev.winner(LATTICE_VOTES, LATTICE_SHARE)
        if verdict == 1 or (others and base > other_score(*shifted) + 0.02):
            continue
        s = board.layout.square_size
        du, dv = round(float(dx @ board.layout.a) / s), round(float(dx @ board.layout.b) / s)
        why = ("the capture prefers the shifted pose, but the corners could not be matched "
               "there" if verdict == 2 else
               f"{ev.n_differ} samples tell them apart ({ev.share_1:.0%} favour the fit, need "
               f"{LATTICE_SHARE:.0%} of at least {LATTICE_VOTES})" if ev.n_differ else
               "nothing in view tells them apart")
        raise PoseFailure(
            "correspondence",
            f"{search.capture_name}: the board's lattice is ambiguous: its corners fit as well "
            f"{du:+d}, {dv:+d} squares along its width and height ({why}); the board's edges "
            "are out of view or hidden: show more of the board, with its edge",
            found=fit.found)


def pose_correction(cam: FisheyeCamera, ypr0_deg: np.ndarray, x: np.ndarray,
                    sigma: np.ndarray) -> PoseCorrection:
    """The record of the correction ``x`` (m, degrees) with standard errors ``sigma``."""
    pos1, _ = corrected_pose(cam, ypr0_deg, x)
    ypr1 = ypr0_deg + x[3:]
    return PoseCorrection(
        d_position_mm=_vec3(x[:3] * 1000),
        d_yaw_deg=float(x[3]), d_pitch_deg=float(x[4]), d_roll_deg=float(x[5]),
        sigma_position_mm=_vec3(sigma[:3] * 1000),
        sigma_angles_deg=_vec3(sigma[3:]),
        position_m=_vec3(pos1),
        yaw_deg=float(ypr1[0]), pitch_deg=float(ypr1[1]), roll_deg=float(ypr1[2]),
    )


def _vec3(v: np.ndarray) -> tuple[float, float, float]:
    return float(v[0]), float(v[1]), float(v[2])
