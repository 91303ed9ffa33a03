"""Fisheye (Kannala-Brandt) intrinsics from board views: ``cv2.fisheye.calibrate`` with
per-view outlier rejection."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import RvmsimError
from .board import BoardSpec

__all__ = ["BoardView", "ViewFit", "Calibration", "calibrate_fisheye"]

#: A view is an outlier when its RMS exceeds this many times the median (and
#: :data:`OUTLIER_MIN_EXCESS_PX` more than it).
OUTLIER_FACTOR = 3.0
OUTLIER_MIN_EXCESS_PX = 0.3
#: Fewest views a calibration is made from.
MIN_VIEWS = 3


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
    """How one view fits the calibration: RMS and largest reprojection error (px), whether
    it was used (False: rejected as an outlier), and the board pose (rvec, tvec; board to
    camera, metres)."""

    name: str
    rms_px: float
    max_px: float
    used: bool
    rvec: tuple[float, float, float]
    tvec: tuple[float, float, float]


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

    def lens_radius_px(self, theta_rad: np.ndarray) -> np.ndarray:
        """Distance from the principal point along x (fx · θd(θ)), px, at incidence
        angles ``theta_rad``."""
        t = np.asarray(theta_rad, dtype=np.float64)
        k1, k2, k3, k4 = self.D
        return self.K[0, 0] * t * (1 + k1 * t**2 + k2 * t**4 + k3 * t**6 + k4 * t**8)


def _flag(name: str) -> int:
    """A cv2.fisheye calibration flag (OpenCV 4 keeps them in cv2.fisheye, 5 in cv2)."""
    import cv2

    return int(getattr(cv2.fisheye, name, None) or getattr(cv2, name))


def _fit(objs: list[np.ndarray], views: list[BoardView],
         size: tuple[int, int]
         ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray], list[np.ndarray]]:
    """cv2.fisheye.calibrate of the views (board points ``objs``) from its own start and
    from focal lengths of W/8 … W (cv2's start fails on wide views); the lowest RMS wins."""
    import cv2

    flags = _flag("CALIB_RECOMPUTE_EXTRINSIC") | _flag("CALIB_FIX_SKEW")
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 300, 1e-12)
    # (1, N, 3) / (1, N, 2): the shapes every OpenCV version accepts.
    obj_in = [o.reshape(1, -1, 3).astype(np.float64) for o in objs]
    imgs = [v.corners.reshape(1, -1, 2).astype(np.float64) for v in views]
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
        raise RvmsimError(f"cv2.fisheye.calibrate failed on {len(views)} views: {last}")
    return best[1], best[2], best[3], best[4]


def _errors(obj: np.ndarray, view: BoardView, K: np.ndarray, D: np.ndarray, rvec: np.ndarray,
            tvec: np.ndarray) -> np.ndarray:
    import cv2

    proj, _ = cv2.fisheye.projectPoints(obj.reshape(-1, 1, 3), rvec, tvec, K, D)
    return np.linalg.norm(proj.reshape(-1, 2) - view.corners, axis=1)


def calibrate_fisheye(views: list[BoardView], board: BoardSpec,
                      image_size: tuple[int, int]) -> Calibration:
    """Kannala-Brandt intrinsics from board views, rejecting outlier views.

    Calibrates on every view, then drops the views whose RMS is more than
    :data:`OUTLIER_FACTOR` × the median (and :data:`OUTLIER_MIN_EXCESS_PX` above it) and
    calibrates again, until no view is dropped (at least :data:`MIN_VIEWS` stay).

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
    used = list(range(len(views)))
    while True:
        K, D, rvecs, tvecs = _fit([objs[i] for i in used], [views[i] for i in used],
                                  image_size)
        rms = np.array([np.sqrt(np.mean(_errors(objs[i], views[i], K, D, r, t) ** 2))
                        for i, r, t in zip(used, rvecs, tvecs)])
        med = float(np.median(rms))
        bad = rms > max(OUTLIER_FACTOR * med, med + OUTLIER_MIN_EXCESS_PX)
        if not bad.any() or len(used) - int(bad.sum()) < MIN_VIEWS:
            break
        used = [i for i, b in zip(used, bad) if not b]
    return _result(objs, views, used, K, D, image_size)


def _result(objs: list[np.ndarray], views: list[BoardView], used: list[int], K: np.ndarray,
            D: np.ndarray, size: tuple[int, int]) -> Calibration:
    """Every view's fit (rejected ones posed by solvePnP with the final K, D)."""
    import cv2

    fits, sq = [], []
    for i, (v, obj) in enumerate(zip(views, objs)):
        ok, rvec, tvec = cv2.fisheye.solvePnP(obj.reshape(-1, 1, 3), v.corners.reshape(-1, 1, 2),
                                              K, D)
        if not ok:
            rvec, tvec = np.zeros(3), np.zeros(3)
        e = _errors(obj, v, K, D, rvec, tvec)
        if i in used:
            sq.append(e**2)
        fits.append(ViewFit(v.name, float(np.sqrt(np.mean(e**2))), float(e.max()), i in used,
                            tuple(float(x) for x in np.ravel(rvec)),  # type: ignore[arg-type]
                            tuple(float(x) for x in np.ravel(tvec))))  # type: ignore[arg-type]
    rms = float(np.sqrt(np.mean(np.concatenate(sq))))
    return Calibration(np.asarray(K, np.float64), np.asarray(D, np.float64), size, rms,
                       tuple(fits))
