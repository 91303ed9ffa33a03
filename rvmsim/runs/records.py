"""The run model: typed, frozen records of a tuning run and their stored (JSON) forms.

A run is its settings (:class:`RunSettings`: what was run), its state (:class:`RunState`:
:class:`RunStatus` and, once it has stopped, a :class:`StopReason`) and its trials
(:class:`TrialRecord`, one per evaluated candidate, each EC's outcome an :class:`EcOutcome`).
:class:`~rvmsim.runs.RunStore` keeps all three in ``run.sqlite``, the single source of truth;
``run.json`` is a human-readable export of the settings.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, Mapping, Sequence

from ..isp import IspParams, OutputSpec
from ..search.config import TuningConfig
from ..scene.display import RVM_IMAGE_OF_RECORD_PX

__all__ = ["RunStatus", "StopReason", "EcOutcome", "TrialRecord", "RunSettings", "RunState",
           "SceneRef", "RunKind", "RobustRecord",
           "params_json", "ec_json", "ecs_from_json"]


class RunStatus(StrEnum):
    """Where a run is: still running, interrupted (Ctrl-C; resumable), done (the strategy
    finished or a stop condition was met), or failed (an error ended it)."""

    RUNNING = "running"
    INTERRUPTED = "interrupted"
    DONE = "done"
    FAILED = "failed"


class StopReason(StrEnum):
    """Why a finished search stopped: the strategy ran out of candidates (``done``), the
    ``max_time`` passed (resumable), or the ``target_score`` was reached."""

    DONE = "done"
    MAX_TIME = "max-time"
    TARGET_SCORE = "target-score"


@dataclass(frozen=True)
class EcOutcome:
    """One EC of one candidate: the measured value (None where the measured object is not
    in the image), its sigmoid score in [0, 1] and whether it is in the acceptable range."""

    value: float | None
    score: float
    passed: bool

    def as_dict(self) -> dict[str, Any]:
        """``{"value", "score", "passed"}`` (JSON-ready)."""
        return {"value": self.value, "score": self.score, "passed": self.passed}


@dataclass(frozen=True)
class TrialRecord:
    """One evaluated candidate: its index in the run, the search stage that proposed it,
    all 14 ISP parameters, the EC score, the objective the strategy maximised, whether every
    enabled EC passes, and each EC's outcome (keyed by EC id, in the criteria's order)."""

    idx: int
    stage: str
    params: IspParams
    score: float
    objective: float
    passed: bool
    ecs: Mapping[str, EcOutcome]

    def failing(self) -> list[str]:
        """Ids of the ECs that do not pass, in order."""
        return [ec for ec, o in self.ecs.items() if not o.passed]


@dataclass(frozen=True)
class SceneRef:
    """One scene of a shared run as recorded: its file (absolute path), its fingerprint
    when the run started (:func:`rvmsim.render.scene_key`) and its vehicle name."""

    scene: str
    scene_key: str | None
    vehicle: str

    def as_json(self) -> dict[str, Any]:
        return {"scene": self.scene, "scene_key": self.scene_key, "vehicle": self.vehicle}


@dataclass(frozen=True)
class RobustRecord:
    """A robust run as recorded: ``samples`` variation samples per scene, drawn with the
    run's seed from ``variation_file`` (None: each scene's own ``variation`` section), whose
    fingerprint was ``variation_key`` when the run started (``--resume`` checks it), judged
    after end-of-line compensation with ``compensation``
    (:meth:`rvmsim.compensation.CompensationModel.as_dict`; None: before it)."""

    samples: int
    variation_file: str | None = None
    variation_key: str | None = None
    compensation: dict[str, Any] | None = None


@dataclass(frozen=True)
class RunKind:
    """What kind of run, as recorded (:class:`RunSettings`\\ ``.kind``; the run kinds'
    behaviour is :mod:`rvmsim.tune.kinds`).

    Attributes
    ----------
    aggregate : str, optional
        How a run of several members combines their EC scores (``min`` or ``quantile Q``,
        :func:`rvmsim.tune.parse_aggregate`); None for a one-scene run that is not robust.
    robust : RobustRecord, optional
        A robust run's samples and compensation (None: judged on the nominal images only).
    markets : tuple of str
        A run for several markets (:mod:`rvmsim.markets`): their recorded forms
        (:attr:`rvmsim.markets.Market.spec`), each a member per scene of the run's
        ``scenes``; (): the run's criteria at each scene's own site.
    """

    aggregate: str | None = None
    robust: RobustRecord | None = None
    markets: tuple[str, ...] = ()

    def as_json(self, shared: bool) -> dict[str, Any]:
        """The keys a run's stored settings hold for its kind (``markets`` aside, which
        follows ``judged_at``): ``aggregate`` for a run of several scenes (``shared``) or a
        robust one, and ``robust``."""
        doc: dict[str, Any] = {}
        if shared:
            doc["aggregate"] = self.aggregate
        if self.robust is not None:  # (the keys in the order rvmsim has always written them)
            doc["robust"] = {"samples": self.robust.samples,
                             "variation_file": self.robust.variation_file,
                             "variation_key": self.robust.variation_key}
            if self.robust.compensation is not None:
                doc["robust"]["compensation"] = self.robust.compensation
            doc["aggregate"] = self.aggregate
        return doc


@dataclass(frozen=True)
class RunSettings:
    """What a run is: everything ``--resume`` needs to continue it exactly.

    ``scene`` and ``criteria_file`` are the files as recorded (absolute paths);
    ``scene_key`` is the scene's fingerprint when the run started
    (:func:`rvmsim.render.scene_key`); ``budget`` the ``--budget`` given (None: the
    config's).  A shared or markets run (one parameter set for several members) records
    every scene in ``scenes`` (the first is ``scene``); a one-scene run has none, and its
    stored form is that of rvmsim before shared tuning.  What else defines the run's kind
    (how members' scores combine, the robust samples, the markets) is ``kind``; its stored
    form keeps the keys it always had (``aggregate``, ``robust``, ``markets``)."""

    scene: str
    scene_key: str | None
    vehicle: str
    strategy: str
    seed: int
    budget: int | None
    criteria_file: str | None
    config: TuningConfig
    scenes: tuple[SceneRef, ...] = ()
    #: What kind of run: a shared, robust (and compensated) or markets run's own settings
    #: (:class:`RunKind`; the default: one scene on its own image, or a shared run's
    #: scenes with the ``min`` aggregate).
    kind: RunKind = RunKind()
    #: The RVM image of record (W, H px) the run's verdicts refer to
    #: (:mod:`rvmsim.criteria.record`); None: a run from before it was recorded.
    judged_at: tuple[int, int] | None = None
    #: ECs left out because the scene cannot support them (``tune --only-supported``,
    #: :func:`rvmsim.criteria.unsupported_ecs`): not scored, not in the verdict; ().
    left_out: tuple[str, ...] = ()

    @property
    def record_px(self) -> tuple[int, int]:
        """(W, H) px of the RVM image of record (a run from before it was recorded: the
        default, :data:`rvmsim.scene.RVM_IMAGE_OF_RECORD_PX`)."""

        return self.judged_at or RVM_IMAGE_OF_RECORD_PX

    def record_output(self) -> OutputSpec:
        """The RVM image of record (:attr:`record_px`), mirrored as the run's search."""
        w, h = self.record_px
        return OutputSpec(w, h, self.config.output.mirror)

    @property
    def shared(self) -> bool:
        """Whether this is a shared run (several scenes)."""
        return bool(self.scenes)

    @property
    def robust(self) -> bool:
        """Whether this is a robust run (judged on variation samples)."""
        return self.kind.robust is not None

    def as_json(self) -> dict[str, Any]:
        """The settings as ``run.json`` holds them (and ``run.sqlite``'s meta table)."""
        doc: dict[str, Any] = {"scene": self.scene, "scene_key": self.scene_key,
                               "vehicle": self.vehicle,
                               "strategy": self.strategy, "seed": self.seed,
                               "budget": self.budget, "criteria_file": self.criteria_file,
                               "config": self.config.model_dump(mode="json")}
        if self.scenes:
            doc["scenes"] = [r.as_json() for r in self.scenes]
        doc.update(self.kind.as_json(bool(self.scenes)))
        if self.judged_at is not None:
            doc["judged_at"] = list(self.judged_at)
        if self.kind.markets:
            doc["markets"] = list(self.kind.markets)
        if self.left_out:
            doc["only_supported"] = {"left_out": list(self.left_out)}
        return doc

    @classmethod
    def from_json(cls, doc: Mapping[str, Any]) -> RunSettings:
        """Inverse of :meth:`as_json`; for a document that is not one raises KeyError (the
        key missing), ValueError naming the key (``KEY: problem``; pydantic's
        ValidationError for ``config``) or TypeError (not a mapping)."""
        if not isinstance(doc, Mapping):
            raise TypeError(f"not an object of run settings but {type(doc).__name__}")

        def need(key: str) -> Any:
            if doc.get(key) is None:
                raise KeyError(key)
            return doc[key]

        def whole(key: str, value: Any) -> int:
            if not isinstance(value, int) or isinstance(value, bool):
                raise ValueError(f"{key}: {value!r} is not a whole number")
            return value

        def text(key: str, value: Any) -> str | None:
            if value is not None and not isinstance(value, str):
                raise ValueError(f"{key}: {value!r} is not a text")
            return value

        try:
            config = TuningConfig.model_validate(need("config"))
        except ValueError as err:  # pydantic's ValidationError
            raise ValueError(f"config: {err}") from None
        budget = doc.get("budget")
        scenes = doc.get("scenes") or []
        if not isinstance(scenes, list) or not all(isinstance(r, Mapping) for r in scenes):
            raise ValueError(f"scenes: {str(scenes)[:40]!r} is not a list of scenes")
        refs = tuple(SceneRef(str(text("scenes: scene", r.get("scene")) or ""),
                              text("scenes: scene_key", r.get("scene_key")),
                              str(text("scenes: vehicle", r.get("vehicle")) or ""))
                     for r in scenes)
        if any(not r.scene for r in refs):
            raise KeyError("scenes: scene")
        robust = doc.get("robust")
        if robust is not None and not isinstance(robust, Mapping):
            raise ValueError(f"robust: {str(robust)[:40]!r} is not an object")
        samples = 0 if robust is None else whole("robust: samples", robust.get("samples"))
        if robust is not None and samples < 1:
            raise ValueError(f"robust: samples: {samples} is not at least 1")
        return cls(str(text("scene", need("scene"))), text("scene_key", doc.get("scene_key")),
                   str(text("vehicle", doc.get("vehicle", "")) or ""),
                   str(text("strategy", need("strategy"))), whole("seed", need("seed")),
                   None if budget is None else whole("budget", budget),
                   text("criteria_file", doc.get("criteria_file")), config, refs,
                   RunKind(text("aggregate", doc.get("aggregate")) if refs or robust else None,
                           None if robust is None else RobustRecord(
                               samples,
                               text("robust: variation_file", robust.get("variation_file")),
                               text("robust: variation_key", robust.get("variation_key")),
                               _mapping("robust: compensation", robust.get("compensation"))),
                           _texts("markets", doc.get("markets"))),
                   _size("judged_at", doc.get("judged_at")),
                   _texts("only_supported: left_out",
                          (_mapping("only_supported", doc.get("only_supported"))
                           or {}).get("left_out")))


def _texts(key: str, value: Any) -> tuple[str, ...]:
    """``value`` as a tuple of texts (None: empty)."""
    if value is None:
        return ()
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise ValueError(f"{key}: {str(value)[:40]!r} is not a list of names")
    return tuple(value)


def _size(key: str, value: Any) -> tuple[int, int] | None:
    """``value`` as (W, H) px, or None."""
    if value is None:
        return None
    if (not isinstance(value, list) or len(value) != 2 or not all(
            isinstance(x, int) and not isinstance(x, bool) and 16 <= x <= 8192 for x in value)):
        raise ValueError(f"{key}: {str(value)[:40]!r} is not [width, height] in px")
    return int(value[0]), int(value[1])


def _mapping(key: str, value: Any) -> dict[str, Any] | None:
    """``value`` if it is None or an object (a JSON mapping)."""
    if value is not None and not isinstance(value, Mapping):
        raise ValueError(f"{key}: {str(value)[:40]!r} is not an object")
    return None if value is None else dict(value)


@dataclass(frozen=True)
class RunState:
    """A run's status, why it stopped (once it has), its strategy and the evaluations it
    will make (None when the strategy does not know in advance); ``killed``: the run was
    recorded as running but its writer has gone without a word (killed: SIGKILL, a power
    cut), so it is interrupted, and resumable (:func:`rvmsim.runs.run_state` tells)."""

    status: RunStatus
    stopped: StopReason | None
    strategy: str
    total: int | None
    killed: bool = False

    @property
    def text(self) -> str:
        """The status as ``rvmsim status`` shows it: ``running``, ``done``,
        ``stopped (max-time)``, ``interrupted (continue with --resume)`` (Ctrl-C),
        ``interrupted (resumable)`` (its writer was killed), ``failed``."""
        if self.killed:
            return "interrupted (resumable)"
        if self.status is RunStatus.INTERRUPTED:
            return "interrupted (continue with --resume)"
        if self.status is RunStatus.DONE and self.stopped not in (None, StopReason.DONE):
            return f"stopped ({self.stopped})"
        return str(self.status)


# ---------------------------------------------------------------------------- stored forms
def params_json(p: IspParams) -> str:
    """The ``params`` column: all 14 ISP parameters as a JSON object."""
    return json.dumps({n: getattr(p, n) for n in IspParams.names()})


def ec_json(ids: Sequence[str], values: Sequence[float], scores: Sequence[float],
            passed: Sequence[bool]) -> str:
    """The ``ec`` column: each EC (``ids``, the criteria's order) as ``[value, score,
    passed]``, the value ``null`` where it was not measured (NaN)."""
    return json.dumps({e: [None if math.isnan(v) else v, s, ok]
                       for e, v, s, ok in zip(ids, values, scores, passed)})


def ecs_from_json(text: str) -> dict[str, EcOutcome]:
    """Inverse of :func:`ec_json`."""
    return {ec: EcOutcome(None if v is None else float(v), float(s), bool(ok))
            for ec, (v, s, ok) in json.loads(text).items()}
