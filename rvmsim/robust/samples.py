"""Quasi-random samples of production variation: scrambled Sobol points, deterministic per
seed, mapped through each axis's inverse distribution function.

Each sample holds the drawn mount offsets (continuous), the offsets it is *rendered* at
(positions snapped to the centre of their equal-probability bin of
``variation.position_levels`` bins per axis: translations need renders, so only a few
positions are rendered; rotations are exact, a re-fold of the rendered cube) and its load
state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .variation import MOUNT_AXES, LoadState, Variation

__all__ = ["MountSample", "draw_samples", "nominal_sample", "position_levels_at"]

#: Sobol dimensions: the six mount axes, then the load state.
_DIMS = len(MOUNT_AXES) + 1


@dataclass(frozen=True)
class MountSample:
    """One car off the line.

    Attributes
    ----------
    index : int
        Position in the drawn sequence.
    offsets : (6,) tuple of float
        Drawn mount offsets in :data:`~rvmsim.scene.MOUNT_AXES` order: x, y, z (mm, scene
        frame) and yaw, pitch, roll (degrees).
    render_position_mm : (3,) tuple of float
        The position offset the sample is rendered at (see the module docstring).
    load : LoadState
    scale : float
        The tolerance scale factor the sample was drawn with.
    """

    index: int
    offsets: tuple[float, float, float, float, float, float]
    render_position_mm: tuple[float, float, float]
    load: LoadState
    scale: float = 1.0

    @property
    def position_mm(self) -> tuple[float, float, float]:
        return self.offsets[0], self.offsets[1], self.offsets[2]

    @property
    def angles_deg(self) -> tuple[float, float, float]:
        """(yaw, pitch, roll) offsets, degrees."""
        return self.offsets[3], self.offsets[4], self.offsets[5]

    def as_dict(self) -> dict[str, object]:
        return {"index": self.index, "load": self.load.name,
                **{n: round(v, 6) for n, v in zip(MOUNT_AXES, self.offsets)},
                "render_position_mm": [round(v, 6) for v in self.render_position_mm]}


def nominal_sample(variation: Variation | None = None) -> MountSample:
    """The car as designed: no mount offset, the first load state (nominal if none)."""
    load = variation.load_states[0] if variation is not None else LoadState("nominal")
    return MountSample(-1, (0.0,) * 6, (0.0, 0.0, 0.0), load, 0.0)


def _unit_points(n: int, seed: int) -> np.ndarray:
    """The first ``n`` points of a scrambled Sobol sequence in (0, 1)^_DIMS (a power of two
    is drawn, so the balance properties hold for the whole block)."""
    # scipy.stats is imported where it is used, not at module top: it takes 0.25 s,
    # and every command that tunes imports this module before its first candidate.
    from scipy.stats import qmc

    sobol = qmc.Sobol(d=_DIMS, scramble=True, seed=np.random.default_rng(seed))
    u = sobol.random_base2(max(0, math.ceil(math.log2(max(n, 1)))))[:n]
    return np.clip(u, 1e-12, 1.0 - 1e-12)


def position_levels_at(levels: int, scale: float) -> int:
    """Rendered levels per position axis at tolerance ``scale`` for ``levels`` at 1×:
    ``min(levels, max(1, ceil(levels · scale)))``.  At 0.5× of 2 levels that is 1 (the
    position at 0: the snapping error of ±h/2 uniform at one level equals that of ±h at two,
    RMS h/(2√3)); above 1× the levels stay (the bins widen with the tolerances)."""
    return min(levels, max(1, math.ceil(levels * scale - 1e-9)))


def draw_samples(variation: Variation, n: int, seed: int, scale: float = 1.0) -> list[MountSample]:
    """``n`` quasi-random samples of ``variation`` with its tolerances times ``scale``.

    Parameters
    ----------
    variation : Variation
    n : int
        Number of samples (≥ 1).
    seed : int
        Scrambling seed: the same seed gives the same samples.
    scale : float
        Tolerance scale factor (0.5, 1, 2, …): every mount offset is multiplied by it; load
        states are discrete and do not scale.  Below 1 the positions are rendered at fewer
        levels (:func:`position_levels_at`): bins no narrower in mm than at 1×, so no more
        renders and no larger snapping error than at 1×.

    Returns
    -------
    list of MountSample
    """
    if n < 1:
        raise ValueError(f"need at least one sample, got {n}")
    if not (scale >= 0 and math.isfinite(scale)):
        raise ValueError(f"tolerance scale must be finite and ≥ 0, got {scale}")
    u = _unit_points(n, seed)
    k = position_levels_at(variation.position_levels, scale)
    values = np.stack([a.ppf(u[:, i]) for i, a in enumerate(variation.axes)], axis=1) * scale
    snapped = np.stack([a.ppf((np.floor(u[:, i] * k) + 0.5) / k) if a.varies else
                        np.zeros(n) for i, a in enumerate(variation.axes[:3])], axis=1) * scale
    cum = np.cumsum([s.probability for s in variation.load_states])
    load_idx = np.minimum(np.searchsorted(cum / cum[-1], u[:, -1], side="right"),
                          len(variation.load_states) - 1)
    return [MountSample(i, tuple(float(v) for v in values[i]),  # type: ignore[arg-type]
                        tuple(float(v) for v in snapped[i]),  # type: ignore[arg-type]
                        variation.load_states[int(load_idx[i])], float(scale))
            for i in range(n)]
