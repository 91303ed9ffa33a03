"""Robust tuning for the yield after end-of-line compensation (``rvmsim tune --robust
--compensation FILE|default``).

Each sample member carries the deviation the station reads for it
(:func:`rvmsim.robust.station_readings`: the run's seed seeds the station's error per
sample, so a resumed run reads the same).  A candidate is the platform setting: for each
candidate the compensation law is made once per scene (:class:`rvmsim.compensation.
CompensationLaw`), and each sample member is judged with its own per-car values, as the car
leaves the line.  A member whose correction leaves the allowed range fails (one violation
more, so the pass-first objective pulls away from it).  Nominal members are judged with the
candidate itself.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..compensation import CompensationLaw, CompensationModel, Correction, Deviation
from ..isp import IspParams, OutputSpec
from ..scene import Scene

__all__ = ["MembersCompensation"]


@dataclass(frozen=True)
class MembersCompensation:
    """Per-car values for every member of a robust run (picklable: it goes to the worker
    processes with the members' evaluators).

    Parameters
    ----------
    model : CompensationModel
    output : OutputSpec
        The run's RVM output (the law keeps the reference points in place on it).
    scenes : tuple of (Scene or None)
        Each member's scene (None for members without one: judged uncompensated).
    measured : tuple of (Deviation or None)
        Each member's station reading (None: a nominal member, judged as it is).
    """

    model: CompensationModel
    output: OutputSpec
    scenes: tuple[Scene | None, ...]
    measured: tuple[Deviation | None, ...]

    def corrections(self, params: Sequence[IspParams]) -> list[list[Correction | None]]:
        """Per member, per candidate: the per-car correction (None where the member is
        judged with the candidate itself)."""
        laws: dict[tuple[int, int], CompensationLaw] = {}
        out: list[list[Correction | None]] = []
        for scene, dev in zip(self.scenes, self.measured):
            row: list[Correction | None] = []
            for i, p in enumerate(params):
                if scene is None or dev is None:
                    row.append(None)
                    continue
                key = (id(scene), i)
                if key not in laws:
                    laws[key] = CompensationLaw(scene, p, self.output, self.model)
                row.append(laws[key].correct(dev))
            out.append(row)
        return out
