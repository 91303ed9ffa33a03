"""Fisheye (Kannala-Brandt) intrinsics from board views: ``cv2.fisheye.calibrate`` with
per-corner and per-view outlier rejection."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..errors import RvmsimError
from .board import BoardSpec

__all__ = ["BoardView", "ViewFit", "Calibration", "calibrate_fisheye",
           "corner_threshold_px"]

#: A view is an outlier when its RMS exceeds this many times the median (and
#: :data:`OUTLIER_MIN_EXCESS_PX` more than it).
OUTLIER_FACTOR = 3.0
OUTLIER_MIN_EXCESS_PX = 0.3
#: Fewest views a calibration is made from.
MIN_VIEWS = 3
#: A corner is an outlier when its reprojection error exceeds
#: max(:data:`CORNER_MIN_PX`, :data:`CORNER_SIGMAS` × σ), σ the robust per-axis sigma
#: (1.4826 × the median of |dx|, |dy| over every corner of the used views).
CORNER_MIN_PX = 3.0
CORNER_SIGMAS = 5.0
#: A view is dropped when more than this share of its corners are outliers.
VIEW_BAD_SHARE = 0.5
#: Fewest corners a view keeps (a board pose needs a homography's four).
MIN_KEPT_CORNERS = 4
#: Fits of the corner-rejection loop, at most.
MAX_REFITS = 6


#: Fewest corners a view of a ChArUco board (which may show part of it) is used with.
MIN_VIEW_CORNERS = 8


@dataclass(frozen=True)
class BoardView:
    """One capture's found corners: ``name`` (the file), ``corners`` (N, 2) px, and
    ``object_points`` (N, 3) m, the board points they are (None: the whole board, in the
    order of :meth:`~.board.BoardSpec.object_points`; a ChArUco view names its own)."""

    name: str
    corners: np.ndarray
    object_points: np.ndarray | None = None

    def points(self, board: BoardSpec) -> np.ndarray:
        """The view's board points (N, 3), metres."""
        return board.object_points() if self.object_points is None else self.object_points


@dataclass(frozen=True)
class ViewFit:
    """How one view fits the calibration: RMS and largest reprojection error (px) over its
    kept corners, whether it was used (False: rejected as an outlier), the board pose
    (rvec, tvec; board to camera, metres), and the corners dropped as outliers (indices
    into the view's corners, and their reprojection errors, px; a rejected view reports
    the corners that were bad when it was rejected)."""

    name: str
    rms_px: float
    max_px: float
    used: bool
    rvec: tuple[float, float, float]
    tvec: tuple[float, float, float]
    dropped: tuple[int, ...] = ()
    dropped_px: tuple[float, ...] = ()


@dataclass(frozen=True)
class Calibration:
    """The result of :func:`calibrate_fisheye`.

    Attributes
    ----------
    K : (3, 3) float64
        Camera matrix (fx, fy, cx, cy px; skew fixed at 0).
    D : (4,) float64
        cv2.fisheye's k1..k4 (Kannala-Brandt).
    image_size : (int, int)
        (width, height) px.
    rms_px : float
        RMS reprojection error over the used views' corners, px.
    views : tuple of ViewFit
        Every view, used or rejected, in input order.
    """

    K: np.ndarray
    D: np.ndarray
    image_size: tuple[int, int]
    rms_px: float
    views: tuple[ViewFit, ...]


def _flag(name: str) -> int:
    """A cv2.fisheye calibration flag (OpenCV 4 keeps them in cv2.fisheye, 5 in cv2)."""

    return int(getattr(cv2.fisheye, name, None) or getattr(cv2, name))


def _fit(objs: list[np.ndarray], pts: list[np.ndarray],
         size: tuple[int, int]
         ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """cv2.fisheye.calibrate of the image points ``pts`` (board points ``objs``; views may
    differ in count) from its own start and from focal lengths of W/8 … W (cv2's start
    fails on wide views); the lowest RMS wins."""

    flags = _flag("CALIB_RECOMPUTE_EXTRINSIC") | _flag("CALIB_FIX_SKEW")
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 300, 1e-12)
    # (1, N, 3) / (1, N, 2): the shapes every OpenCV version accepts.
    obj_in = [o.reshape(1, -1, 3).astype(np.float64) for o in objs]
    imgs = [c.reshape(1, -1, 2).astype(np.float64) for c in pts]
    w, h = size
    best: tuple[float, np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray]] | None = None
    last = ""
    for f0 in [None, *(w * np.geomspace(1 / 8, 1, 10))]:
        K0 = np.array([[f0 or 1.0, 0, (w - 1) / 2], [0, f0 or 1.0, (h - 1) / 2], [0, 0, 1]])
        fl = flags if f0 is None else flags | _flag("CALIB_USE_INTRINSIC_GUESS")
        try:
            rms, K, D, rvecs, tvecs = cv2.fisheye.calibrate(obj_in, imgs, size, K0,
                                                            np.zeros((4, 1)), flags=fl,
                                                            criteria=crit)
        except cv2.error as err:
            last = str(err).strip().splitlines()[-1]
            continue
        if np.all(np.isfinite(K)) and K[0, 0] > 0 and (best is None or rms < best[0]):
            best = (rms, K, D.ravel(), list(rvecs), list(tvecs))
    if best is None:
        raise RvmsimError(f"cv2.fisheye.calibrate failed on {len(pts)} views: {last}")
    return best[1], best[2], best[3], best[4]


def _residuals(obj: np.ndarray, corners: np.ndarray, K: np.ndarray, D: np.ndarray,
               rvec: np.ndarray, tvec: np.ndarray) -> np.ndarray:
    """(N, 2) reprojection residuals (projected − found), px."""

    proj, _ = cv2.fisheye.projectPoints(obj.reshape(-1, 1, 3), rvec, tvec, K, D)
    return np.asarray(proj.reshape(-1, 2) - corners, np.float64)


def corner_threshold_px(residuals: np.ndarray) -> float:
    """The reprojection error above which a corner is an outlier, px:
    max(:data:`CORNER_MIN_PX`, :data:`CORNER_SIGMAS` × σ), σ = 1.4826 × the median of
    the residuals' |dx| and |dy| (a robust per-axis sigma that a few wrong corners do not
    move), ``residuals`` (N, 2) px over every corner of the used views."""
    sigma = 1.4826 * float(np.median(np.abs(residuals))) if len(residuals) else 0.0
    return max(CORNER_MIN_PX, CORNER_SIGMAS * sigma)


def calibrate_fisheye(views: list[BoardView], board: BoardSpec,
                      image_size: tuple[int, int]) -> Calibration:
    """Kannala-Brandt intrinsics from board views, dropping outlier corners, then views.

    Calibrates on every corner of every view.  Then, up to :data:`MAX_REFITS` times: every
    corner of the used views whose reprojection error (with the fit's view pose) exceeds
    :func:`corner_threshold_px` is dropped (a corner dropped before comes back when it
    fits again); a view with more than :data:`VIEW_BAD_SHARE` of its corners dropped, or
    fewer than :data:`MIN_KEPT_CORNERS` kept, is dropped whole; once no corner changes, a
    view whose RMS over its kept corners is more than :data:`OUTLIER_FACTOR` × the median
    (and :data:`OUTLIER_MIN_EXCESS_PX` above it) is dropped too; and it calibrates again on
    what is kept, until nothing changes.  At least :data:`MIN_VIEWS` views stay.

    Raises
    ------
    RvmsimError
        Fewer than :data:`MIN_VIEWS` views, or cv2 fails.

    Convention
    ----------
    cv2.fisheye's model; pixel centres at integer coordinates.
    """
    if len(views) < MIN_VIEWS:
        raise RvmsimError(f"calibration needs the board found in at least {MIN_VIEWS} "
                          f"captures (found in {len(views)})")
    objs = [v.points(board) for v in views]
    for v, o in zip(views, objs):
        if len(o) != len(v.corners):
            raise RvmsimError(f"{v.name}: {len(v.corners)} corners for {len(o)} board points")
    keep = [np.ones(len(v.corners), bool) for v in views]
    used = list(range(len(views)))
    for _ in range(MAX_REFITS + 1):
        K, D, rvecs, tvecs = _fit([objs[i][keep[i]] for i in used],
                                  [views[i].corners[keep[i]] for i in used], image_size)
        res = {i: _residuals(objs[i], views[i].corners, K, D, r, t)
               for i, r, t in zip(used, rvecs, tvecs)}
        new_keep, new_used = _reject(res, keep, used)
        if new_used == used and all(np.array_equal(new_keep[i], keep[i]) for i in used):
            break
        keep, used = new_keep, new_used
    return _result(objs, views, used, keep, K, D, image_size)


def _reject(res: dict[int, np.ndarray], keep: list[np.ndarray], used: list[int]
            ) -> tuple[list[np.ndarray], list[int]]:
    """The corners and views kept after a fit whose residuals are ``res`` (view index →
    (N, 2) px): :func:`calibrate_fisheye`'s rules; ``keep`` of views already dropped stays
    as it was."""
    thr = corner_threshold_px(np.concatenate([r[keep[i]] for i, r in res.items()]))
    new_keep = list(keep)
    survivors = []
    for i in used:
        ok = np.linalg.norm(res[i], axis=1) <= thr
        new_keep[i] = ok
        if np.mean(~ok) <= VIEW_BAD_SHARE and int(ok.sum()) >= MIN_KEPT_CORNERS:
            survivors.append(i)
    # The view RMS rule only once the corners are settled (a view's pose is pulled by its
    # wrong corners until they are dropped, and its good corners then fit badly too).
    settled = all(np.array_equal(new_keep[i], keep[i]) for i in used)
    rms = np.array([np.sqrt(np.mean(np.sum(res[i][new_keep[i]] ** 2, axis=1)))
                    for i in survivors])
    if settled and len(rms):
        med = float(np.median(rms))
        good = rms <= max(OUTLIER_FACTOR * med, med + OUTLIER_MIN_EXCESS_PX)
        if int(good.sum()) >= MIN_VIEWS:
            survivors = [i for i, g in zip(survivors, good) if g]
    if len(survivors) < MIN_VIEWS:  # too few left: keep the views, drop only corners
        survivors = [i for i in used if int(new_keep[i].sum()) >= MIN_KEPT_CORNERS]
    if len(survivors) < MIN_VIEWS:
        return keep, used
    return new_keep, survivors


def _result(objs: list[np.ndarray], views: list[BoardView], used: list[int],
            keep: list[np.ndarray], K: np.ndarray, D: np.ndarray,
            size: tuple[int, int]) -> Calibration:
    """Every view's fit, posed by solvePnP on its kept corners with the final K, D (a view
    with too few kept corners on all of them)."""

    fits, sq = [], []
    for i, (v, obj) in enumerate(zip(views, objs)):
        k = keep[i] if int(keep[i].sum()) >= MIN_KEPT_CORNERS else np.ones(len(obj), bool)
        ok, rvec, tvec = cv2.fisheye.solvePnP(obj[k].reshape(-1, 1, 3),
                                              v.corners[k].reshape(-1, 1, 2), K, D)
        if not ok:
            rvec, tvec = np.zeros(3), np.zeros(3)
        e = np.linalg.norm(_residuals(obj, v.corners, K, D, rvec, tvec), axis=1)
        if i in used:
            sq.append(e[keep[i]] ** 2)
        drop = np.flatnonzero(~keep[i])
        fits.append(ViewFit(v.name, float(np.sqrt(np.mean(e[k] ** 2))), float(e[k].max()),
                            i in used,
                            tuple(float(x) for x in np.ravel(rvec)),  # type: ignore[arg-type]
                            tuple(float(x) for x in np.ravel(tvec)),  # type: ignore[arg-type]
                            tuple(int(j) for j in drop), tuple(float(e[j]) for j in drop)))
    rms = float(np.sqrt(np.mean(np.concatenate(sq))))
    return Calibration(np.asarray(K, np.float64), np.asarray(D, np.float64), size, rms,
                       tuple(fits))
