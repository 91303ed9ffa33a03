"""Variation samples after end-of-line compensation: each car through the station's step
(:mod:`rvmsim.percar`) and judged in the field with the values it wrote.

For each car (a sample):

1. **At the station.** The car stands in the station's load state (its *twin*: the same
   mount deviation, the station's load; :func:`station_twin`).  The station reads its
   camera's deviation with its error (:func:`rvmsim.compensation.measured_deviation`, seeded
   per car) against the design pose, and the body's edge on the capture with the edge
   finder's error (:func:`rvmsim.compensation.edge_error`).  The law judges the car on the
   twin's true fisheye labels seen with those errors (:class:`rvmsim.percar.StationView`)
   and writes its values (or, ``law: reference-points``, the reference points' values).
2. **In the field.** The car in its own load state, judged with those values on its own
   true picture (the verdicts of ``rvmsim robustness``), before (platform values) and after.
   The ECs that read only the body (:func:`rvmsim.percar.body_ecs`) are read on the car at
   the station: the body moves with the camera, so a load state does not change them, and
   another render of the same body would only add its own sampling of the body's edge.

A car passes when the station lets it go (``pass``; ``marginal`` only under the ``accept``
policy) and its picture in the field passes every EC.  A sample's camera is at its rendered
position (the snapping of positions is the image's approximation, not the station's error).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._progress import progress_bar
from ..compensation import (CompensationModel, Correction, Deviation, deviated_pose, edge_error,
                            loaded_deviation, measured_deviation)
from ..criteria import Criteria, EcBatch, score_batch
from ..isp import IspParams, OutputSpec
from ..percar import CarSolution, PerCarLaw, SplitEvaluator, StationView
from ..render import FisheyeImages
from ..scene import Scene
from .images import Refolder, sample_images
from .samples import MountSample
from .variation import LoadState

__all__ = ["CompensatedSamples", "station_readings", "true_deviation", "station_twin",
           "CarJudge", "COMPENSATION_CHUNK", "StationReading", "read_at_station"]

#: Cars whose images are held at once (each a few MB of fisheye labels).
COMPENSATION_CHUNK = 24


def true_deviation(sample: MountSample) -> Deviation:
    """The deviation of ``sample``'s rendered camera from the nominal mount."""
    return Deviation.from_offsets((*sample.render_position_mm, *sample.angles_deg))


def station_twin(sample: MountSample, load: LoadState) -> MountSample:
    """``sample``'s car standing in the station's load state ``load``."""
    return sample if sample.load == load else dataclasses.replace(sample, load=load)


@dataclass(frozen=True)
class CompensatedSamples:
    """Per sample: the deviation the station measured, the law's solution (its values and
    the station's verdict), and whether the station lets the car go."""

    model: CompensationModel
    measured: tuple[Deviation, ...]
    solutions: tuple[CarSolution, ...]
    accepted: np.ndarray

    @property
    def corrections(self) -> tuple[Correction, ...]:
        """Each car's written values."""
        return tuple(s.correction for s in self.solutions)

    @property
    def params(self) -> list[IspParams]:
        """Each car's parameters (full sensor; within the allowed ranges)."""
        return [s.params for s in self.solutions]

    @property
    def within_range(self) -> np.ndarray:
        """(n,) bool: the written values needed no clipping to the allowed ranges."""
        return np.array([s.correction.within_range for s in self.solutions], dtype=bool)

    def count(self, status: str) -> int:
        """The cars the station gave ``status`` (:data:`rvmsim.percar.STATUSES`)."""
        return sum(s.status == status for s in self.solutions)

    def summary_lines(self, field_ok: np.ndarray) -> list[str]:
        """What the station did with the cars (terminal lines): out of range, infeasible,
        marginal (rejected or accepted), and the cars it let go that fail in the field
        (``field_ok``: (n,) bool, the cars' pictures in the field pass)."""
        lines = []
        n_out = int((~self.within_range).sum())
        if n_out:
            first = next(c for c in self.corrections if c.exceeded)
            lines.append(f"  {n_out} cars fail the EOL step itself (e.g. {first.exceeded[0]})")
        infeasible = [s for s in self.solutions if s.status == "infeasible"]
        if infeasible:
            lines.append(f"  {len(infeasible)} infeasible cars: no per-car setting within the "
                         f"allowed ranges passes every EC (e.g. {infeasible[0].reasons[0]})")
        marginal = self.count("marginal")
        if marginal:
            policy = "accepted" if self.model.marginal == "accept" else "failed"
            lines.append(f"  {marginal} marginal cars (an EC's margin inside the station's "
                         f"uncertainty), {policy} by the station's policy")
        escaped = int((self.accepted & ~field_ok).sum())
        if escaped:
            lines.append(f"  {escaped} cars the station passed fail in the field (the "
                         "station's error)")
        return lines

    def distribution(self) -> dict[str, object]:
        """JSON-ready: per written parameter (and the pan's turn) the spread of the per-car
        offsets from the platform, the cars out of range, the station's verdicts and the
        law's evaluations per car."""
        out: dict[str, object] = {}
        corrections = self.corrections
        names = list(corrections[0].offsets) if corrections else []
        for name in names:
            v = np.array([c.offsets[name] for c in corrections])
            low, high = self.model.range_of(name)
            out["pan_turn" if name == "h_pan" else name] = {
                "range": [low, high], "mean": float(v.mean()), "sd": float(v.std()),
                "min": float(v.min()), "p1": float(np.percentile(v, 1)),
                "median": float(np.median(v)), "p99": float(np.percentile(v, 99)),
                "max": float(v.max())}
        res = np.array([c.residual_rms_px for c in corrections])
        evals = np.array([s.evaluations for s in self.solutions])
        return {"offsets": out, "n_out_of_range": int((~self.within_range).sum()),
                "residual_rms_px": {"median": float(np.median(res)) if res.size else 0.0,
                                    "max": float(res.max()) if res.size else 0.0},
                "verdicts": {st: self.count(st) for st in ("pass", "marginal", "fail",
                                                          "infeasible")},
                "n_rejected": int((~self.accepted).sum()),
                "evaluations_per_car": {"median": float(np.median(evals)) if evals.size
                                        else 0.0,
                                        "max": int(evals.max()) if evals.size else 0}}


def station_readings(scene: Scene, samples: Sequence[MountSample], model: CompensationModel,
                     seed: int, measured_at: LoadState) -> tuple[Deviation, ...]:
    """What the station reads for each sample: its deviation in the station's load state
    (:func:`rvmsim.compensation.loaded_deviation`) plus the station's error."""
    return tuple(measured_deviation(
        loaded_deviation(scene, true_deviation(s), measured_at.height_mm, measured_at.pitch_deg),
        model, seed, s.index, s.scale) for s in samples)


@dataclass(frozen=True)
class StationReading:
    """What the station has of one car: its measured deviation, its true fisheye labels at
    the station's load state (``image``), the station's pose error as a turn of the camera
    (``site_turn``, camera frame; None: none) and the edge finder's error (``edge_px``:
    offset and tilt, full-sensor px).  Picklable (tuning's workers judge with it)."""

    measured: Deviation
    image: FisheyeImages
    site_turn: np.ndarray | None
    edge_px: tuple[float, float]
    scale: float = 1.0

    def picture(self, record: OutputSpec, criteria: Criteria) -> StationView:
        """The car's picture as the station has it (:class:`rvmsim.percar.StationView`)."""
        return StationView(SplitEvaluator(self.image, record, criteria), self.image.camera,
                           self.site_turn, self.edge_px, self.scale)


def read_at_station(scene: Scene, samples: Sequence[MountSample],
                    measured: Sequence[Deviation], twin_images: Sequence[FisheyeImages],
                    model: CompensationModel, seed: int, scale: float = 1.0
                    ) -> list[StationReading]:
    """The :class:`StationReading` of each car from its station reading ``measured`` and
    its true fisheye labels at the station's load state ``twin_images`` (as
    :func:`sample_images` makes them of :func:`station_twin`)."""
    out = []
    for s, m, img in zip(samples, measured, twin_images):
        error = img.camera.rotation.T @ deviated_pose(scene, m)[0]
        site = None if np.abs(error - np.eye(3)).max() < 1e-12 else error
        out.append(StationReading(m, img, site, edge_error(model, seed, s.index, s.scale),
                                  scale))
    return out


class CarJudge:
    """Every car of a sample set through the station and into the field (the module
    docstring).

    Parameters
    ----------
    scene : Scene
    law : PerCarLaw
        The platform setting's law (:func:`rvmsim.percar.make_law`).
    seed : int
        The run's seed (with each car's index and tolerance scale it seeds its errors).
    station_load : LoadState
        The load state the car stands in at the station.
    criteria : Criteria
    record : OutputSpec
        The RVM image of record (what the ECs are judged at).
    scale : float
        Fraction of the sensor rendered.
    """

    def __init__(self, scene: Scene, law: PerCarLaw, seed: int, station_load: LoadState,
                 criteria: Criteria, record: OutputSpec, scale: float = 1.0):
        self.scene = scene
        self.law = law
        self.model = law.model
        self.seed = seed
        self.station_load = station_load
        self.criteria = criteria
        self.record = record
        self.scale = scale

    def _at(self, params: IspParams) -> IspParams:
        return params if self.scale == 1.0 else params.for_input_scale(self.scale)

    def __call__(self, samples: Sequence[MountSample], platform: IspParams, shared: Refolder,
                 *, progress: bool = False) -> tuple[EcBatch, EcBatch, CompensatedSamples]:
        """Each car before compensation, after it, and what the station did.

        Returns
        -------
        before, after : EcBatch
            One row per sample: the ECs in the field with the platform values, and with
            the car's own values.
        compensated : CompensatedSamples
        """
        measured = station_readings(self.scene, samples, self.model, self.seed,
                                    self.station_load)
        k = len(self.criteria.ids)
        before, after = np.full((len(samples), k), np.nan), np.full((len(samples), k), np.nan)
        solutions: list[CarSolution] = []
        bar = _bar(progress, len(samples))
        for a in range(0, len(samples), COMPENSATION_CHUNK):
            part = list(samples[a:a + COMPENSATION_CHUNK])
            twins = [station_twin(s, self.station_load) for s in part]
            fields = [s for s in part if s.load != self.station_load]
            images = sample_images(self.scene, twins + fields, scale=self.scale,
                                   color=False, shared=shared)
            in_field = dict(zip((s.index for s in fields), images[len(twins):]))
            readings = read_at_station(self.scene, part, measured[a:a + len(part)],
                                       images[:len(twins)], self.model, self.seed, self.scale)
            for j, (s, reading) in enumerate(zip(part, readings)):
                i = a + j
                sol, b, v = self._car(reading, in_field.get(s.index), platform)
                solutions.append(sol)
                before[i], after[i] = b, v
                if bar is not None:
                    bar.update(1)
        if bar is not None:
            bar.close()
        accepted = np.array([self.law.accepts(s) for s in solutions], dtype=bool)
        return (score_batch(before, self.criteria), score_batch(after, self.criteria),
                CompensatedSamples(self.model, measured, tuple(solutions), accepted))

    def _car(self, reading: StationReading, field_img: FisheyeImages | None,
             platform: IspParams) -> tuple[CarSolution, np.ndarray, np.ndarray]:
        """One car: the law on its station picture, then its ECs in the field (its own
        image, or the station's when it stands in the station's load state)."""
        view = reading.picture(self.record, self.criteria)
        sol = self.law.solve(reading.measured, view)
        at_station = view.evaluator
        if field_img is None:
            return (sol, at_station.values(self._at(platform)),
                    at_station.values(self._at(sol.params)))
        # the body moves with the camera: its ECs do not change with the load state, and
        # are read on the car at the station (another render of the same body would only
        # add its own sampling of the bumper's edge, ±2 px of EC 2-3 at the image's sides)
        field_ev = SplitEvaluator(field_img, self.record, self.criteria)
        body = at_station.body
        return tuple([sol] + [np.where(body, at_station.values(self._at(p)),
                                       field_ev.values(self._at(p)))
                              for p in (platform, sol.params)])  # type: ignore[return-value]


def _bar(progress: bool, total: int):  # type: ignore[no-untyped-def]
    if not progress:
        return None

    return progress_bar(total=total, desc="cars through the station", unit="car", leave=False)
