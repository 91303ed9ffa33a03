"""The documents a sweep or batch sends to its workers and gets back, as typed dicts.

They are plain JSON-ready dicts on purpose: a task is pickled to a local process or a Dask
worker, and a point's result is stored as it is in ``sweep.sqlite`` (``json.dumps``) and
copied into ``sweep.json``; keeping them dicts keeps those files exactly as they were.
The :class:`~typing.TypedDict` classes only name their keys and value types, so everything
between reading and writing them is type-checked.

``NotRequired`` keys are those a writer may leave out, or that a store made by an earlier
version may lack (a stored result is checked for the required ones when it is read,
:class:`~rvmsim.batch.store.SweepStore`).  The result types are ``@final``: no other key
is expected, so ``"error" in result`` tells an error from a run.

Documents (scene, tuning config) that come from YAML files stay plain dicts of YAML values:
their shape is the scene's and the config's pydantic models, checked where they are loaded.
"""

from __future__ import annotations

from typing import Any, Literal, NotRequired, TypedDict, final

from ..criteria.infeasible import InfeasibleDoc

__all__ = ["Verdict", "YieldRequest", "PointTask", "YieldTask", "EcOutcomeDoc",
           "InfeasibleDoc", "MarketOutcomeDoc", "ParamSensitivity", "SensitivityDoc", "YieldDoc",
           "YieldError",
           "PointRun", "PointError", "PointResult", "YieldOnly", "FirstPass", "MergedPoint",
           "MergedResult", "BatchTask", "BatchRun", "BatchError", "SceneSummary",
           "SceneSummaryError"]

#: A design point's verdict (:data:`rvmsim.batch.VERDICTS`).
Verdict = Literal["pass", "not found", "infeasible"]


# ---------------------------------------------------------------------------- tasks
class YieldRequest(TypedDict):
    """A point task's ``robustness``: the yield's variation samples and Sobol seed."""

    samples: int
    seed: int


class PointTask(TypedDict):
    """The argument of :func:`~rvmsim.batch.point.run_point`: one design point's tuning run
    (a first pass; a re-check adds the ``NotRequired`` keys,
    :func:`~rvmsim.batch.recheck.recheck_task`).

    ``scene`` and ``config`` are the point's scene and tuning-config documents (YAML);
    ``criteria`` is a criteria file's text (None: the default criteria), named
    ``criteria_source`` in messages; ``robustness``: the yield to measure (None: none).
    A re-check's ``starts`` are parameter sets (name → value) evaluated first, its budget is
    ``budget`` times ``budget_factor``, and ``beat`` is (passed, score) of the point's best
    so far.  A markets sweep's ``markets`` are the market specs every point must pass
    (``criteria`` is then None; :mod:`rvmsim.batch.markets`).
    """

    scene: dict[str, Any]
    config: dict[str, Any]
    label: str
    strategy: str
    budget: int | None
    seed: int
    criteria: str | None
    criteria_source: str
    sensitivity: bool
    robustness: YieldRequest | None
    starts: NotRequired[list[dict[str, float]]]
    budget_factor: NotRequired[float]
    beat: NotRequired[tuple[bool, float]]
    markets: NotRequired[list[str]]


class YieldTask(PointTask):
    """The argument of :func:`~rvmsim.batch.point.run_yield`: a point's task and the
    parameter set (name → value) whose yield is measured."""

    yield_of: dict[str, float]


class BatchTask(TypedDict):
    """The argument of :func:`~rvmsim.batch.tasks.tune_task`: one vehicle's tuning run.

    ``scene``: a :func:`~rvmsim.batch.tasks.portable_scene_doc`; ``config``: a tuning-config
    document; ``criteria``: a criteria file's text (None: the defaults); ``scene_file`` and
    ``criteria_file``: the paths the run records (on the submitting machine).
    """

    scene: dict[str, Any]
    config: dict[str, Any]
    strategy: str
    seed: int
    budget: int | None
    criteria: str | None
    workers: NotRequired[int]
    scene_file: NotRequired[str]
    criteria_file: NotRequired[str | None]


# ---------------------------------------------------------------------------- results
class EcOutcomeDoc(TypedDict):
    """One EC of a point's best candidate (:meth:`rvmsim.tune.EcOutcome.as_dict`)."""

    value: float | None
    score: float
    passed: bool


class MarketOutcomeDoc(TypedDict):
    """One market's verdict on a markets point's best setting
    (:func:`~rvmsim.batch.markets.market_outcomes`): its EC score, pass, failing enabled
    ECs, binding EC (least score) and each EC's result."""

    score: float
    passed: bool
    failing: list[str]
    binding: str | None
    ecs: dict[str, EcOutcomeDoc]


class ParamSensitivity(TypedDict):
    """One tuned parameter's sensitivity: the score per step (None outside its range) and
    the drop at ±5 % (None when the optimum scores 0)."""

    scores: list[float | None]
    drop_5pct: float | None


class SensitivityDoc(TypedDict):
    """:func:`~rvmsim.batch.point.sensitivity`'s result."""

    optimum: float
    steps: list[float]
    params: dict[str, ParamSensitivity]


#: A point's measured yield (:func:`~rvmsim.batch.yields.yield_summary`, with the
#: ``seconds`` it took); the functional form because ``yield`` is a keyword.
YieldDoc = TypedDict("YieldDoc", {
    "yield": float,
    "ci95": list[float],
    "n_pass": int,
    "n": int,
    "seed": int,
    "limiting_ec": str | None,
    "limiting_fail_rate": float | None,
    "limiting_axis": str | None,
    "limiting_driver": str | None,
    "failure_rates": dict[str, float],
    "seconds": NotRequired[float],
})


@final
class YieldError(TypedDict):
    """A yield that could not be measured (the tuning result is kept)."""

    error: str
    seconds: NotRequired[float]


class _RunKeys(TypedDict):
    """The keys of a point's tuning run (:class:`PointRun`, :class:`MergedPoint`)."""

    score: float
    passed: bool
    ecs: dict[str, EcOutcomeDoc]
    params: dict[str, float]
    tuned: NotRequired[list[str]]
    evaluations: int
    budget: NotRequired[int | None]
    stopped: NotRequired[str]
    infeasible: NotRequired[list[InfeasibleDoc]]
    limiting_ec: str | None
    limiting_market: NotRequired[str | None]
    markets: NotRequired[dict[str, MarketOutcomeDoc]]
    sensitivity: NotRequired[SensitivityDoc]
    robustness: NotRequired[YieldDoc | YieldError]
    #: Seconds per phase of the run: ``render``, ``tune`` (the search and the sensitivity
    #: probes), ``yield`` (absent in results stored before phases were timed).
    phases: NotRequired[dict[str, float]]
    seconds: NotRequired[float]


@final
class PointRun(_RunKeys):
    """A design point's tuning run (a first pass or a re-check), as stored in
    ``sweep.sqlite``; see :func:`~rvmsim.batch.point.run_point`."""


@final
class PointError(TypedDict):
    """A design point (or a task of one) that failed to run: the one-line message."""

    error: str
    seconds: NotRequired[float]


#: What a point's tuning run returns and the store keeps.
PointResult = PointRun | PointError


@final
class YieldOnly(TypedDict):
    """:func:`~rvmsim.batch.point.run_yield`'s result: the yield and the time taken."""

    robustness: YieldDoc | YieldError
    seconds: float


class FirstPass(TypedDict):
    """A merged point's first-pass run: score, passed, evaluations."""

    score: float
    passed: bool
    evaluations: int


@final
class MergedPoint(_RunKeys):
    """A point's final result (:func:`~rvmsim.batch.recheck.merge_point`): its best run
    (the keys of :class:`PointRun`) and the verdict, the reason (for ``infeasible``), the
    re-checks run, the round that found the best and the first pass."""

    verdict: Verdict
    reason: str | None
    rechecks: int
    found_in: int
    first_pass: FirstPass


#: A point's final result, or its first pass's error.
MergedResult = MergedPoint | PointError


@final
class BatchRun(TypedDict):
    """:func:`~rvmsim.batch.tasks.tune_task`'s result: the run folder's files (relative path
    → bytes) and the run's counts and wall time."""

    files: dict[str, bytes]
    evaluated: int
    replayed: int
    seconds: float


@final
class BatchError(TypedDict):
    """A batch task whose scene could not be tuned: the one-line message."""

    error: str


class SceneSummary(TypedDict):
    """One finished scene's entry of a batch's ``summary.json``."""

    scene: str
    vehicle: str
    ec_score: float
    passed: bool
    ecs: dict[str, bool]
    evaluations: int
    seconds: float
    run: str


class SceneSummaryError(TypedDict):
    """One skipped scene's entry of a batch's ``summary.json``."""

    scene: str
    error: str
