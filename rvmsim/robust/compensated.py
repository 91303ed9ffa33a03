"""Variation samples after end-of-line compensation: each car's per-car values from its
measured deviation (:mod:`rvmsim.compensation`), and what they add up to.

A sample's camera deviates from the nominal mount by its angles and the position it is
rendered at (the image judged is the rendered one: the snapping of positions is the image's
approximation, not the station's error).  The station reads that deviation with its error
(:func:`rvmsim.compensation.measured_deviation`, seeded per car) in the load state it
measures at, against the design pose; the law turns it into the car's values; the car is
then judged in its own load state with those values, as in the field.  A car whose correction leaves the allowed range
fails, named as such.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..compensation import (CompensationLaw, CompensationModel, Correction, Deviation,
                            loaded_deviation, measured_deviation)
from ..isp import IspParams
from ..scene import Scene
from .samples import MountSample
from .variation import LoadState

__all__ = ["CompensatedSamples", "compensate_samples", "true_deviation", "station_readings"]


def true_deviation(sample: MountSample) -> Deviation:
    """The deviation of ``sample``'s rendered camera from the nominal mount."""
    return Deviation.from_offsets((*sample.render_position_mm, *sample.angles_deg))


@dataclass(frozen=True)
class CompensatedSamples:
    """Per sample: the deviation the station measured and the correction the law wrote."""

    model: CompensationModel
    measured: tuple[Deviation, ...]
    corrections: tuple[Correction, ...]

    @property
    def params(self) -> list[IspParams]:
        """Each car's parameters (full sensor; clipped to the allowed ranges)."""
        return [c.params for c in self.corrections]

    @property
    def within_range(self) -> np.ndarray:
        """(n,) bool: the correction fits the allowed ranges."""
        return np.array([c.within_range for c in self.corrections], dtype=bool)

    def distribution(self) -> dict[str, object]:
        """JSON-ready: per written parameter (and the pan's turn) the spread of the per-car
        offsets from the platform, and the cars out of range."""
        out: dict[str, object] = {}
        names = list(self.corrections[0].offsets) if self.corrections else []
        for name in names:
            v = np.array([c.offsets[name] for c in self.corrections])
            low, high = self.model.range_of(name)
            out["pan_turn" if name == "h_pan" else name] = {
                "range": [low, high], "mean": float(v.mean()), "sd": float(v.std()),
                "min": float(v.min()), "p1": float(np.percentile(v, 1)),
                "median": float(np.median(v)), "p99": float(np.percentile(v, 99)),
                "max": float(v.max())}
        res = np.array([c.residual_rms_px for c in self.corrections])
        return {"offsets": out, "n_out_of_range": int((~self.within_range).sum()),
                "residual_rms_px": {"median": float(np.median(res)) if res.size else 0.0,
                                    "max": float(res.max()) if res.size else 0.0}}


def compensate_samples(law: CompensationLaw, samples: Sequence[MountSample], seed: int,
                       measured_at: LoadState) -> CompensatedSamples:
    """The station's reading and the law's correction for every sample.

    Parameters
    ----------
    law : CompensationLaw
    samples : sequence of MountSample
    seed : int
        The run's seed: with each sample's index and tolerance scale it seeds the sample's
        station error.
    measured_at : LoadState
        The load state the car stands in at the station: the station compares the camera's
        pose then with the design pose (:func:`rvmsim.compensation.loaded_deviation`), so a
        load state other than the scene's own attitude reads as a deviation too.
    """
    measured = station_readings(law.scene, samples, law.model, seed, measured_at)
    return CompensatedSamples(law.model, measured, tuple(law.correct(m) for m in measured))


def station_readings(scene: Scene, samples: Sequence[MountSample], model: CompensationModel,
                     seed: int, measured_at: LoadState) -> tuple[Deviation, ...]:
    """What the station reads for each sample (see :func:`compensate_samples`)."""
    return tuple(measured_deviation(
        loaded_deviation(scene, true_deviation(s), measured_at.height_mm, measured_at.pitch_deg),
        model, seed, s.index, s.scale) for s in samples)
