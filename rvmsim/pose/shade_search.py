"""A global, coarse-to-fine search for the mount pose on the shade of the scene's patterns.

The local pre-alignment (:func:`.fit.dense_align`, Nelder-Mead from the scene's pose)
holds for a pose a few degrees or a few cm off; 0.15 m of height on the real BAIC frame
already puts it in a local optimum.  :func:`search_pose_by_shade` finds the pose from
±10° / ±0.3 m:

* The score of a pose is how well the patterns' analytic black and white, seen from it,
  explain the capture's grey level: the ground patterns' shade (:class:`.pose.GroundShade`)
  and, when the scene has a board, its squares' colours (:class:`.board.BoardShade`),
  averaged.
* Coarse to fine (:data:`LEVELS`): the capture is blurred (σ in degrees of view, the
  largest first) and sampled on a grid of that spacing.  A blurred capture turns the
  score's narrow peaks at the checker's period into broad hills, so the coarse level's
  search sees the mat's outline, its white squares and discs; the finer level sharpens.
* Each level runs CMA-ES (the ``cmaes`` package) on the pose correction scaled by
  :data:`POSE_SCALE` (one unit is 0.1 m or 3.3°, so the first level's σ = 1 covers
  ±10° / ±0.3 m in three steps), from the best pose so far, a few restarts with fixed seeds
  (deterministic).  Then the checker's same-colour shifts (the pattern's periodic aliases,
  up to two squares) are tried, and the best pose goes on to the next level.
* The ground is sampled over the whole lens field, not where the scene's frame shows it:
  the start frame rendered 0.3 m off can show the car's body where the capture shows the
  mat.  Off the patterns a sample does not count.

A *pose correction* ``x`` is (Δx, Δy, Δz m, Δyaw, Δpitch, Δroll degrees), see
:mod:`.projection`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Protocol

import cv2
import numpy as np
from cmaes import CMA

from ..camera import FisheyeCamera
from ..scene import Scene
from .board import BoardLayout, BoardShade
from .capture import grey
from .fit import GroundShade, dense_align
from .projection import corrected_pose

__all__ = ["POSE_SCALE", "SearchLevel", "LEVELS", "ShadeStart", "search_pose_by_shade"]

#: One unit of the search's scaled pose: 0.1 m on each position axis, 10/3° on each angle.
POSE_SCALE = np.array([0.1, 0.1, 0.1, 10 / 3, 10 / 3, 10 / 3])
#: The search stays within ±5 units: ±0.5 m, ±16.7°.
BOUND = 5.0
#: CMA-ES population per generation.
POPULATION = 16
#: Runs of one level whose poses are this close (scaled units, each axis: 25 mm, 0.8°)
#: found the same optimum.
AGREE = 0.5
#: Two runs that both score below this (correlation) mean the patterns are not in the capture:
#: stop restarting.
MIN_SCORE = 0.2


@dataclass(frozen=True)
class SearchLevel:
    """One level of the coarse-to-fine search.

    Attributes
    ----------
    step_deg : float
        Sample spacing, degrees of view at the image centre (``fx`` px per radian).
    blur_deg : float
        σ of the Gaussian blur of the capture's grey level, degrees of view.
    sigma : float
        CMA-ES's initial step, in units of :data:`POSE_SCALE`.
    generations : int
        At most this many generations per run.
    restarts : int
        Runs (seeds 0, 1, …) from the best pose so far; the best result wins.
    board : bool
        Whether the board's squares are scored at this level.  Not at the coarsest: the
        board's patch in the scene's view is a few squares whose score has a peak at every
        square's shift even on a blurred capture, which puts CMA-ES's first, wide steps in
        false optima that the mat's broad hills don't have.
    """

    step_deg: float
    blur_deg: float
    sigma: float
    generations: int
    restarts: int
    board: bool = True


#: Coarse (the mat's outline and white squares; ±10° / ±0.3 m) to fine (~15 mm, 0.3°).
LEVELS = (SearchLevel(1.5, 1.5, 1.0, 40, 6, board=False),
          SearchLevel(1.0, 0.6, 0.3, 20, 1))
#: The polish after the levels: the ground patterns' shade sampled every this many degrees
#: of view, not blurred; Nelder-Mead from steps of 10 mm and 0.3°, at most
#: :data:`POLISH_EVALUATIONS` poses.
POLISH_STEP_DEG = 0.75
POLISH_EVALUATIONS = 150


@dataclass(frozen=True)
class ShadeStart:
    """The pose the shade search found.

    Attributes
    ----------
    x : (6,) float
        Pose correction of the scene's mount (m, degrees).
    score : float
        The mean shade correlation there at the finest level (-1..1).
    evaluations : int
        Poses scored.
    """

    x: np.ndarray
    score: float
    evaluations: int


class Shade(Protocol):
    """A score of a pose by a pattern's colours (:class:`GroundShade`, :class:`BoardShade`)."""

    def __call__(self, position: np.ndarray, rotation: np.ndarray) -> float: ...

    def shifts(self) -> list[np.ndarray]: ...


def level_shades(scene: Scene, cam: FisheyeCamera, capture: np.ndarray,
                 layout: BoardLayout | None, level: SearchLevel) -> list[Shade]:
    """The scores at one level: the ground patterns' (sampled over the lens field) and the
    board's squares' (``layout``), on the capture blurred as ``level`` says."""

    px_per_deg = _px_per_deg(cam)
    blur = level.blur_deg * px_per_deg
    shades: list[Shade] = []
    if scene.test_site.ground_patterns:
        shades.append(GroundShade.sample(scene, cam, None, capture,
                                         step=max(1, round(level.step_deg * px_per_deg)),
                                         blur_px=blur))
    if layout is not None and (level.board or not shades):
        level_grey = cv2.GaussianBlur(grey(capture), (0, 0), blur) if blur > 0 else grey(capture)
        shades.append(BoardShade(layout, cam, level_grey))
    return shades


def search_pose_by_shade(scene: Scene, cam: FisheyeCamera, ypr0_deg: np.ndarray,
                         capture: np.ndarray, layout: BoardLayout | None = None, *,
                         x0: np.ndarray | None = None,
                         levels: tuple[SearchLevel, ...] = LEVELS) -> ShadeStart | None:
    """The pose correction whose patterns' shade best explains the capture, from ±10° / ±0.3 m.

    Parameters
    ----------
    scene : Scene
        Its ground patterns (and board) are scored.
    cam : FisheyeCamera
        The scene's camera; its position is the uncorrected optical centre.
    ypr0_deg : (3,) float
        The scene's mount yaw, pitch, roll, degrees.
    capture : (H, W, 3) uint8
    layout : BoardLayout, optional
        The scene's board: its squares' colours are scored too.
    x0 : (6,) float, optional
        Where the search starts (default zero: the scene's pose).
    levels : tuple of SearchLevel
        Coarse to fine.

    Returns
    -------
    ShadeStart or None
        None when the scene has neither ground patterns nor a board.  A level whose best
        score is below :data:`MIN_SCORE` ends the search there (the patterns are not in the
        capture): its score says so.
    """
    if not scene.test_site.ground_patterns and layout is None:
        return None
    z = np.zeros(6) if x0 is None else np.asarray(x0, np.float64) / POSE_SCALE
    ypr0 = np.asarray(ypr0_deg, np.float64)
    evaluations, score = 0, -1.0
    for level in levels:
        shades = level_shades(scene, cam, capture, layout, level)

        def cost(zz: np.ndarray, shades: list[Shade] = shades) -> float:
            pos, rot = corrected_pose(cam, ypr0, zz * POSE_SCALE)
            return -float(np.mean([sh(pos, rot) for sh in shades]))

        shifts = [d / POSE_SCALE[:3] for sh in shades for d in sh.shifts()]
        runs: list[tuple[float, np.ndarray]] = []
        for seed in range(level.restarts):
            f, z_run, n = _cma(cost, z, level.sigma, seed, level.generations)
            f, z_run = _best_shift(cost, f, z_run, shifts)
            evaluations += n + len(shifts)
            runs.append((f, z_run))
            if _agree(runs) or (len(runs) >= 2 and -min(r[0] for r in runs) < MIN_SCORE):
                break  # found; or the patterns are nowhere in the capture
        best, z = min(runs, key=lambda r: r[0])
        score = -best
        if score < MIN_SCORE:
            return ShadeStart(z * POSE_SCALE, score, evaluations)  # the patterns are nowhere
    x = z * POSE_SCALE
    if scene.test_site.ground_patterns:
        fine = GroundShade.sample(scene, cam, None, capture,
                                  step=max(1, round(POLISH_STEP_DEG * _px_per_deg(cam))))
        x = dense_align(fine, cam, ypr0, x0=x, steps=np.array([0.01] * 3 + [0.3] * 3),
                        max_evaluations=POLISH_EVALUATIONS)
        evaluations += POLISH_EVALUATIONS
    return ShadeStart(x, score, evaluations)


def _px_per_deg(cam: FisheyeCamera) -> float:
    """Pixels per degree of view at the image centre (the mean focal length)."""
    return float(np.mean(np.diag(cam.K)[:2])) * math.pi / 180


def _best_shift(cost: Callable[[np.ndarray], float], f: float, z: np.ndarray,
                shifts: list[np.ndarray]) -> tuple[float, np.ndarray]:
    """``z`` or the best of its position shifts by ``shifts`` (scaled units), by cost."""
    for shift in shifts:
        z_try = z.copy()
        z_try[:3] += shift
        f_try = cost(z_try)
        if f_try < f:
            f, z = f_try, z_try
    return f, z


def _agree(runs: list[tuple[float, np.ndarray]]) -> bool:
    """Two runs ended within :data:`AGREE` of the best run's pose (scaled units, each axis):
    the best is then taken as the global optimum."""
    if len(runs) < 2:
        return False
    best = min(runs, key=lambda r: r[0])[1]
    return sum(bool(np.all(np.abs(z - best) <= AGREE)) for _, z in runs) >= 2


def _cma(cost: Callable[[np.ndarray], float], mean: np.ndarray, sigma: float, seed: int,
         generations: int) -> tuple[float, np.ndarray, int]:
    """One CMA-ES run: (best cost, its point, evaluations)."""

    opt = CMA(mean=np.clip(mean, -BOUND + 1e-6, BOUND - 1e-6), sigma=sigma,
              bounds=np.tile([-BOUND, BOUND], (6, 1)), seed=seed, population_size=POPULATION)
    best_f, best_z, n = math.inf, mean, 0
    for _ in range(generations):
        told = []
        for _ in range(opt.population_size):
            zz = opt.ask()
            f = cost(zz)
            told.append((zz, f))
            if f < best_f:
                best_f, best_z = f, zz
        n += len(told)
        opt.tell(told)
        if opt.should_stop():
            break
    return best_f, np.asarray(best_z, np.float64), n
