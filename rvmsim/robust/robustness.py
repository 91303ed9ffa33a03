"""The yield of one ISP setting over production variation (``rvmsim robustness``).

The samples are a batch of fisheye images (:class:`~rvmsim.robust.SampleSet`) judged by
the evaluator :func:`rvmsim.pipeline.make_evaluator` chooses: the ISP's map is the same for
all samples (the parameters are fixed), so only the fisheye pixels it shows are re-folded
from each sample's cube (:func:`~rvmsim.robust.sample_rvm_labels`, equal to running the ISP
on :func:`~rvmsim.robust.sample_images`' label image), and every EC is measured on it,
exactly as ``rvmsim evaluate`` does; criteria whose ECs read the scene
(:attr:`~rvmsim.criteria.Criteria.uses_scene`) get each sample's whole fisheye labels on the
full path instead.  The result
holds the yield with its 95 % interval (:mod:`.stats`), each EC's failure rate, worst
value and margin and the axis that drives its failures, the yield against a tolerance
scale factor, and the nominal and worst samples' RVM frames for the report.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..compensation import CompensationLaw, CompensationModel, measured_load_index
from ..criteria import Criteria, EcBatch, default_criteria, score_batch
from ..isp import IspParams, OutputSpec, params_to_dict
from ..pipeline import RvmFrame, evaluate_params, make_evaluator, record_output
from ..scene import Scene
from ..render import TaskRunner
from ..percar import ImagePicture, PerCarLaw, SplitEvaluator, check_law, make_law
from .compensated import CarJudge, CompensatedSamples, station_twin
from .ec_stats import EcStats, driver_text, ec_stats
from .guideline_errors import FleetGuidelines, fleet_guideline_errors
from .images import Refolder, SampleSet, cover_for, refolder, render_viewpoints, sample_images
from .samples import MountSample, draw_samples, nominal_sample
from .stats import YieldEstimate, YieldVerdict, limiting_dict, yield_estimate
from .variation import LoadState, Variation, variation_from_scene

__all__ = ["EcStats", "ScalePoint", "RobustnessResult", "RobustnessSettings", "evaluate_samples",
           "robustness", "DEFAULT_SCALES"]

#: Tolerance scale factors of the yield curve.
DEFAULT_SCALES = (0.5, 1.0, 1.5, 2.0)


def evaluate_samples(scene: Scene, samples: Sequence[MountSample],
                     params: IspParams | Sequence[IspParams], output: OutputSpec, criteria: Criteria | None = None, *,
                     scale: float = 1.0, shared: Refolder | None = None,
                     progress: bool = False) -> EcBatch:
    """Every EC of one ISP setting on every sample, through
    :func:`rvmsim.pipeline.make_evaluator` (the path the criteria allow).

    Parameters
    ----------
    scene, samples
        The scene and its variation samples.
    params : IspParams or sequence of IspParams
        For the full sensor (RAD and shifts follow ``scale``): one setting for every sample,
        or one per sample (per-car values after compensation).
    output : OutputSpec
    criteria : Criteria, optional
        Default: the paper's.
    scale : float
        Fraction of the sensor rendered.
    shared : Refolder, optional
        :func:`~rvmsim.robust.refolder` of ``samples`` (default: made here).
    progress : bool

    Returns
    -------
    EcBatch
        One row per sample (``values`` NaN where not measured, ``passed``, ``score``,
        ``all_passed``).
    """
    crit = criteria if criteria is not None else default_criteria()
    if not samples:
        return score_batch(np.zeros((0, len(crit.ids))), crit)
    evaluator = make_evaluator(SampleSet.of(scene, samples, scale=scale, shared=shared),
                               output, crit)
    desc = f"samples (tolerance x{samples[0].scale:g})" if progress else None
    if isinstance(params, IspParams):
        return evaluator(_scaled_params(scene, params, scale), progress=desc)
    return evaluator([_scaled_params(scene, p, scale) for p in params], progress=desc)


def _scaled_params(scene: Scene, params: IspParams, scale: float) -> IspParams:
    if scale == 1.0:
        return params
    width = scene.fisheye_camera().scaled(scale).width
    return params.for_input_scale(width / scene.camera.image_size[0])


@dataclass(frozen=True)
class ScalePoint:
    """The yield at one tolerance scale factor."""

    scale: float
    estimate: YieldEstimate


@dataclass(frozen=True)
class RobustnessResult(YieldVerdict):
    """What ``rvmsim robustness`` reports (see the module docstring).

    ``yield_`` and ``ci`` are the 95 % estimate's; ``ecs`` one :class:`EcStats` per EC in
    the criteria's order; ``nominal`` and ``worst`` the annotated RVM frames of the car as
    designed and of the worst sample (most ECs failing, then the lowest EC score), None
    when they were not asked for (``robustness(..., frames=False)``)."""

    scene_name: str
    scene_file: str
    params: IspParams
    output: OutputSpec
    criteria_name: str
    variation: Variation
    seed: int
    samples: tuple[MountSample, ...]
    evaluation: EcBatch
    estimate: YieldEstimate
    ecs: tuple[EcStats, ...]
    scale_curve: tuple[ScalePoint, ...]
    nominal: RvmFrame | None
    worst: RvmFrame | None
    worst_index: int
    min_yield: float | None = None
    timings: dict[str, float] = field(default_factory=dict)
    compensated: CompensatedSamples | None = None
    before: EcBatch | None = None
    ecs_before: tuple[EcStats, ...] = ()
    reference_points: int = 0
    #: The RVM image of record every verdict refers to (:mod:`rvmsim.criteria.record`;
    #: None: ``output``).
    judged_at: OutputSpec | None = None
    #: After compensation, how far the parking guidelines land from where they claim
    #: (:mod:`rvmsim.robust.guideline_errors`; None: no compensation, or the scene's vehicle
    #: has no running gear).
    guidelines: FleetGuidelines | None = None

    @property
    def passed(self) -> np.ndarray:
        """(n,) bool: the sample passes every EC (after compensation: the station let the
        car go, and its picture passes with its per-car values)."""
        ok = self.evaluation.all_passed
        return ok if self.compensated is None else ok & self.compensated.accepted

    def yield_by_load(self, *, before: bool = False) -> dict[str, Any]:
        """The yield in each load state (JSON-ready), after compensation (or without one),
        or ``before`` it."""
        if before and self.before is None:
            raise ValueError("no compensation: there is no yield before it")
        passed = self.before.all_passed if before and self.before is not None else self.passed
        return _by_load(passed, self.samples)

    @property
    def before_estimate(self) -> YieldEstimate | None:
        """The yield before compensation (None without compensation)."""
        return None if self.before is None else yield_estimate(self.before.all_passed)


    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (robustness.json)."""
        ev = self.evaluation
        return {
            "scene": self.scene_file, "vehicle": self.scene_name, "criteria": self.criteria_name,
            "isp": params_to_dict(self.params, self.output,
                                  judged_at=self.judged_at or self.output),
            "judged_at": [(self.judged_at or self.output).width,
                          (self.judged_at or self.output).height],
            "seed": self.seed,
            "variation": self.variation.as_dict(), **self.estimate.as_dict(),
            "min_yield": self.min_yield, "meets_min_yield": self.meets_min_yield,
            "nominal": None if self.nominal is None else self.nominal.ec.as_dict(),
            "worst_sample": self.worst_index,
            "ecs": [e.as_dict() for e in self.ecs], "limiting": limiting_dict(self.ecs),
            "yield_by_load": self.yield_by_load(),
            "scale_curve": [{"scale": p.scale, **p.estimate.as_dict()} for p in self.scale_curve],
            **self._compensation_dict(),
            "samples": [self._sample_dict(i) for i in range(len(self.samples))],
            "timings_s": {k: round(v, 3) for k, v in self.timings.items()},
        }

    def _compensation_dict(self) -> dict[str, Any]:
        """robustness.json's ``compensation`` and ``yield_before_compensation`` (None
        without compensation)."""
        comp, before, est = self.compensated, self.before, self.before_estimate
        if comp is None or before is None or est is None:
            return {"compensation": None, "yield_before_compensation": None}
        return {
            "compensation": {**comp.model.as_dict(), "reference_points": self.reference_points,
                             **comp.distribution(),
                             "guidelines": None if self.guidelines is None
                             else self.guidelines.as_dict()},
            "yield_before_compensation": {
                **est.as_dict(), "by_load": self.yield_by_load(before=True),
                "limiting": limiting_dict(self.ecs_before),
                "ecs": [{"id": e.id, "n_fail": e.n_fail, "failure_rate": e.failure_rate,
                         "worst_value": e.worst_value, "worst_margin": e.worst_margin}
                        for e in self.ecs_before]},
        }

    def _sample_dict(self, i: int) -> dict[str, Any]:
        """One sample's row of robustness.json."""
        ev, s = self.evaluation, self.samples[i]
        failed = [e for e, ok in zip(ev.ids, ev.passed[i]) if not ok]
        row: dict[str, Any] = {**s.as_dict(), "ec_score": float(ev.score[i]),
                               "passed": bool(self.passed[i]), "failed": failed}
        if self.compensated is not None and self.before is not None:
            sol = self.compensated.solutions[i]
            c = sol.correction
            row["failed"] = failed + list(c.exceeded) + [
                r for r in sol.reasons if r.startswith(("infeasible car", "marginal"))]
            row["passed_before_compensation"] = bool(self.before.all_passed[i])
            row["measured_deviation"] = self.compensated.measured[i].as_dict()
            row["correction"] = c.as_dict()
            row["station"] = {k: v for k, v in sol.as_dict().items()
                              if k in ("law", "status", "reasons", "evaluations",
                                       "station_ecs")}
            row["station"]["accepted"] = bool(self.compensated.accepted[i])
        return row

    def summary(self) -> str:
        """A few lines for the terminal."""
        lo, hi = self.ci
        after = "" if self.compensated is None else " after EOL compensation"
        lines = [f"{self.scene_name}: yield{after} {100 * self.yield_:.1f} % "
                 f"(95 % CI {100 * lo:.1f}–{100 * hi:.1f} %, {self.estimate.n_pass} of "
                 f"{self.estimate.n} samples pass every EC)"]
        est = self.before_estimate
        if est is not None and self.compensated is not None:
            blo, bhi = est.ci
            lines.append(f"  before compensation: {100 * est.yield_:.1f} % (95 % CI "
                         f"{100 * blo:.1f}–{100 * bhi:.1f} %)")
            lines += self.compensated.summary_lines(self.evaluation.all_passed)
            if self.guidelines is not None:
                lines.append("  " + self.guidelines.summary_line())
        for e in self.ecs:
            if e.enabled and e.n_fail:
                lines.append(f"  EC {e.id} fails on {100 * e.failure_rate:.1f} % (worst "
                             f"{_num(e.worst_value)} {e.unit}, margin {_num(e.worst_margin)})"
                             + driver_text(e, self.estimate.n))
        lines.append("  yield by tolerance scale: " + ", ".join(
            f"{p.scale:g}x {100 * p.estimate.yield_:.0f} %" for p in self.scale_curve))
        return "\n".join(lines)


def _by_load(passed: np.ndarray, samples: Sequence[MountSample]) -> dict[str, Any]:
    """The yield in each load state (JSON-ready)."""
    names = np.array([s.load.name for s in samples])
    return {name: yield_estimate(passed[names == name]).as_dict()
            for name in dict.fromkeys(names.tolist())}


def _num(x: float | None) -> str:
    return "—" if x is None else f"{x:.3g}"


def _frame(scene: Scene, sample: MountSample, params: IspParams, output: OutputSpec,
           crit: Criteria, scale: float, shared: Refolder) -> RvmFrame:
    images = sample_images(scene, [sample], scale=scale, shared=shared)[0]
    return evaluate_params(images, _scaled_params(scene, params, scale), output, crit,
                           annotate=True)


@dataclass(frozen=True)
class RobustnessSettings:
    """What a yield is judged with (``rvmsim robustness``'s options; recorded in the result).

    Parameters
    ----------
    output : OutputSpec
        The RVM image the ECs are measured on.
    criteria : Criteria, optional
        Default: the paper's.
    variation : Variation, optional
        Default: the scene's ``variation`` section (:func:`variation_from_scene`).
    samples : int
        Samples at tolerance scale 1.
    seed : int
        Sobol scrambling seed (the same seed, the same samples and result).
    scales : tuple of float
        Tolerance scale factors of the yield curve (1 reuses the main samples).
    scale_samples : int, optional
        Samples per other scale factor; default ``min(samples, 64)``.
    render_scale : float
        Fraction of the sensor rendered (small renders for tests).
    min_yield : float, optional
        The least yield (0–1) that passes (``meets_min_yield``); default: the variation's.
    compensation : CompensationModel, optional
        Judge every sample after end-of-line compensation (:mod:`.compensated`): the yield
        is then the yield after it, and the result also holds the yield before.
    """

    output: OutputSpec = OutputSpec()
    criteria: Criteria | None = None
    variation: Variation | None = None
    samples: int = 200
    seed: int = 0
    scales: tuple[float, ...] = DEFAULT_SCALES
    scale_samples: int | None = None
    render_scale: float = 1.0
    min_yield: float | None = None
    compensation: CompensationModel | None = None

    def least_yield(self, variation: Variation) -> float | None:
        """The least yield that passes: :attr:`min_yield`, else ``variation``'s."""
        return self.min_yield if self.min_yield is not None else variation.min_yield


def robustness(scene: Scene, params: IspParams,
               settings: RobustnessSettings = RobustnessSettings(), *,
               runner: TaskRunner | None = None, frames: bool = True,
               progress: bool = False) -> RobustnessResult:
    """The yield of ``params`` over ``scene``'s production variation.

    Parameters
    ----------
    scene : Scene
    params : IspParams
        For the full sensor.
    settings : RobustnessSettings
        The output, criteria, variation, samples, seed, yield curve and render scale.
    runner : TaskRunner, optional
        Where the viewpoints not yet in the render cache are rendered, all before the
        first sample is evaluated (``rvmsim.batch.LocalExecutor(workers)``, a Dask
        executor); default: here, as they are needed.
    frames : bool
        Make the nominal and worst samples' annotated RVM frames (for the report; each
        renders its viewpoint in colour).  A sweep's yield column does without.
    progress : bool

    Returns
    -------
    RobustnessResult
    """
    t0 = time.perf_counter()
    crit = settings.criteria if settings.criteria is not None else default_criteria()
    if settings.compensation is not None:
        check_law(settings.compensation)
        # its reference ground points in view, before any render (one line, at once)
        CompensationLaw(scene, params, record_output(crit, scene, settings.output.mirror),
                        settings.compensation)
    var = settings.variation if settings.variation is not None else variation_from_scene(scene)
    seed, output, render_scale = settings.seed, settings.output, settings.render_scale
    drawn = draw_samples(var, settings.samples, seed)
    n_extra = settings.scale_samples or min(settings.samples, 64)
    extra = {float(s): draw_samples(var, n_extra, seed, s)
             for s in settings.scales if s != 1.0}
    sets = {1.0: drawn, **extra}
    base = refolder(scene, drawn, scale=render_scale)
    folds = {1.0: base, **{s: Refolder(cover_for(scene, v, scale=render_scale), base.rays)
                           for s, v in extra.items()}}  # the same camera: the same rays
    station_load = _station_load(settings.compensation, var)
    rendered = 0
    if runner is not None:
        views = list(sets.values())
        if settings.compensation is not None:  # the cars at the station too
            views += [[station_twin(s, station_load) for s in v] for v in sets.values()]
        rendered = render_viewpoints(scene, views, scale=render_scale, runner=runner,
                                     shared=list(folds.values()) * (len(views) // len(sets)),
                                     progress=progress)
    judge_cars = _judge(scene, params, settings, crit, station_load, base)
    t_render = time.perf_counter()
    before: EcBatch | None = None

    def judge(samples: list[MountSample], fold: Refolder
              ) -> tuple[EcBatch, np.ndarray, CompensatedSamples | None]:
        """The samples' ECs (after compensation with a law), and who passes."""
        nonlocal before
        if judge_cars is None:
            e = evaluate_samples(scene, samples, params, output, crit, scale=render_scale,
                                 shared=fold, progress=progress)
            return e, e.all_passed, None
        b, e, fixed = judge_cars(samples, params, fold, progress=progress)
        if before is None:
            before = b
        return e, e.all_passed & fixed.accepted, fixed

    ev, passed, fixed = judge(drawn, folds[1.0])
    t1 = time.perf_counter()
    curve = [ScalePoint(float(s), yield_estimate(
        passed if s == 1.0 else judge(extra[float(s)], folds[float(s)])[1]))
        for s in settings.scales]
    t2 = time.perf_counter()
    lines = None if fixed is None else fleet_guideline_errors(
        scene, drawn, fixed.measured, fixed.params, params, output, station_load)
    t_lines = time.perf_counter() - t2
    n_fail = np.sum(~ev.passed & crit.arrays[-1], axis=1)
    if fixed is not None:  # a car the station rejects is worse than any EC failure
        n_fail = n_fail + len(crit.ids) * ~fixed.accepted
    worst = int(np.lexsort((ev.score, -n_fail))[0])
    nominal = worst_frame = None
    record = record_output(crit, scene, output.mirror)  # the frames show the verdicts' size
    if frames:
        nominal = _frame(scene, nominal_sample(var), params, record, crit, render_scale, base)
        worst_params = params if fixed is None else fixed.corrections[worst].params
        worst_frame = _frame(scene, drawn[worst], worst_params, record, crit, render_scale,
                             base)
    t3 = time.perf_counter()
    return RobustnessResult(
        scene.name, scene.source, params, output, crit.name, var, seed, tuple(drawn), ev,
        yield_estimate(passed), ec_stats(crit, drawn, ev, var), tuple(curve), nominal,
        worst_frame, worst, settings.least_yield(var),
        {"render": t_render - t0, "samples": t1 - t_render, "scale_curve": t2 - t1,
         "guidelines": t_lines, "frames": t3 - t2 - t_lines, "total": t3 - t0,
         "viewpoints_rendered": float(rendered)},
        fixed, before, () if before is None else ec_stats(crit, drawn, before, var),
        0 if judge_cars is None else len(judge_cars.law.reference.points), record, lines)


def _station_load(model: CompensationModel | None, var: Variation) -> LoadState:
    """The load state the station measures in (the variation's first without a model)."""
    if model is None:
        return var.load_states[0]
    return var.load_states[measured_load_index(model, [s.name for s in var.load_states])]


def _judge(scene: Scene, params: IspParams, settings: RobustnessSettings, crit: Criteria,
           station_load: LoadState, shared: Refolder) -> CarJudge | None:
    """The station's step for ``params`` (None without compensation): its law, with the
    station's uncertainty read on the nominal car standing at the station."""
    model = settings.compensation
    if model is None:
        return None
    record = record_output(crit, scene, settings.output.mirror)
    twin = station_twin(nominal_sample(settings.variation or variation_from_scene(scene)),
                        station_load)
    nominal = sample_images(scene, [twin], scale=settings.render_scale, color=False,
                            shared=shared)[0]
    picture = ImagePicture(SplitEvaluator(nominal, record, crit), settings.render_scale)
    law: PerCarLaw = make_law(scene, params, record, model, crit, picture, nominal.camera)
    return CarJudge(scene, law, settings.seed, station_load, crit, record,
                    settings.render_scale)
