"""Robust tuning for the yield after end-of-line compensation (``rvmsim tune --robust
--compensation FILE|default``).

Each sample member carries what the end-of-line station has of its car
(:class:`rvmsim.robust.StationReading`: the deviation it reads, the car at the station's load
state, the station's pose and edge errors, seeded by the run's seed per sample, so a resumed
run reads the same).  A candidate is the platform setting; each sample member is judged with
the per-car values the model's law writes for it (:mod:`rvmsim.percar`, the same call as
``rvmsim robustness --compensation`` and ``rvmsim eol`` make), in its own load state, as the
car leaves the line; a car the station rejects (infeasible, marginal under the ``fail``
policy, out of range) fails (one violation more, so the pass-first objective pulls away from
it).  Nominal members are judged with the candidate itself.

A candidate that fails on a nominal member cannot pass, and its cars are not put through the
station: they are judged with the reference-point law's values (the law's own start), one
evaluation each, which is what the search needs of such a candidate (``law:
reference-points`` judges every candidate so).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..compensation import CompensationLaw, CompensationModel, Correction
from ..criteria import Criteria
from ..isp import IspParams, OutputSpec
from ..percar import (ImagePicture, PerCarLaw, SplitEvaluator, StationDraws, StationView,
                      make_law, nominal_draws)
from ..pipeline import FisheyeLabels
from ..robust import StationReading
from ..scene import Scene

__all__ = ["MembersCompensation", "MemberCar"]


@dataclass(frozen=True)
class MemberCar:
    """One member's per-car values for one candidate: its full setting and whether the
    station lets the car go (a reason when not)."""

    params: IspParams
    accepted: bool
    reason: str = ""


class MembersCompensation:
    """Per-car values for every member of a robust run (picklable: it goes to the worker
    processes with the members' evaluators).

    Parameters
    ----------
    model : CompensationModel
    record : OutputSpec
        The RVM image of record (the law's pictures and reference points).
    criteria : Criteria
    scenes : sequence of (Scene or None)
        Each member's scene.
    stations : sequence of (StationReading or None)
        Each member's station reading (None: a nominal member, judged as it is).
    nominal : sequence of int
        The nominal members (one per scene, the first of its members), whose pictures give
        the station's uncertainty of each EC.
    nominal_images : sequence of FisheyeLabels
        Their images (in ``nominal``'s order).
    """

    def __init__(self, model: CompensationModel, record: OutputSpec, criteria: Criteria,
                 scenes: Sequence[Scene | None], stations: Sequence[StationReading | None],
                 nominal: Sequence[int], nominal_images: Sequence[FisheyeLabels]):
        self.model = model
        self.record = record
        self.criteria = criteria
        self.scenes = tuple(scenes)
        self.stations = tuple(stations)
        self.nominal = tuple(nominal)
        self._views: list[StationView | None] = [
            None if st is None else st.picture(record, criteria) for st in stations]
        # each sample member's nominal member: the last nominal one before it
        self._owner = [max((n for n in self.nominal if n <= m), default=0)
                       for m in range(len(self.stations))]
        self._nominal_pictures = {n: ImagePicture(SplitEvaluator(img, record, criteria))
                                  for n, img in zip(self.nominal, nominal_images)}
        #: The station's errors each nominal member's EC uncertainty is read with: the
        #: same for every candidate, so drawn once (in the worker, at first use).
        self._draws: dict[int, StationDraws] = {}

    def cars(self, params: Sequence[IspParams], nominal_passed: np.ndarray
             ) -> list[list[MemberCar | None]]:
        """Per member, per candidate: the car's setting and the station's verdict (None
        where the member is judged with the candidate itself).

        Parameters
        ----------
        params : sequence of IspParams
            The candidates (full sensor).
        nominal_passed : (n_nominal, n) bool
            Whether each nominal member passes each candidate (in :attr:`nominal` order).
        """
        passed = {n: np.asarray(row, bool) for n, row in zip(self.nominal, nominal_passed)}
        out: list[list[MemberCar | None]] = [[None] * len(params) for _ in self.stations]
        for i, p in enumerate(params):
            laws: dict[int, PerCarLaw | CompensationLaw] = {}
            for m, (scene, station, view) in enumerate(zip(self.scenes, self.stations,
                                                            self._views)):
                if scene is None or station is None or view is None:
                    continue
                owner = self._owner[m]
                through = self.model.law == "reference-points" or bool(passed[owner][i])
                if owner not in laws:
                    nominal = self._nominal_pictures[owner]
                    if through and owner not in self._draws:
                        self._draws[owner] = nominal_draws(scene, self.model, nominal)
                    laws[owner] = (make_law(scene, p, self.record, self.model, self.criteria,
                                            nominal, station=self._draws[owner]) if through
                                   else CompensationLaw(scene, p, self.record, self.model))
                law = laws[owner]
                if isinstance(law, PerCarLaw):
                    sol = law.solve(station.measured, view)
                    reason = "" if law.accepts(sol) else "; ".join(sol.reasons)
                    out[m][i] = MemberCar(sol.params, law.accepts(sol), reason)
                else:
                    c: Correction = law.correct(station.measured)
                    out[m][i] = MemberCar(c.params, c.within_range, "; ".join(c.exceeded))
        return out
