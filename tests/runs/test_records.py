"""The run model: records, settings and state, and their stored JSON forms."""

from __future__ import annotations

import json
import math

import pytest

from rvmsim.isp import IspParams
from rvmsim.search import TuningConfig
from rvmsim.runs import (EcOutcome, RunSettings, RunState, RunStatus, StopReason, TrialRecord,
                         ec_json, ecs_from_json, params_json)


def _settings(**changes) -> RunSettings:
    doc = {"scene": "/data/scene.yaml", "scene_key": "abc", "vehicle": "Vehicle Q",
           "strategy": "cmaes", "seed": 7, "budget": 300, "criteria_file": None,
           "config": {"tuned": ["zoom"], "top_m": 4}}
    return RunSettings.from_json({**doc, **changes})


def test_run_settings_round_trip_through_json():
    s = _settings(budget=None, criteria_file="/data/crit.yaml")
    assert s.config == TuningConfig.model_validate({"tuned": ["zoom"], "top_m": 4})
    doc = json.loads(json.dumps(s.as_json()))
    assert RunSettings.from_json(doc) == s
    assert doc["config"]["random"] == {"budget": 2000}
    with pytest.raises(KeyError):
        RunSettings.from_json({k: v for k, v in doc.items() if k != "strategy"})


def test_ec_outcomes_round_trip_through_the_ec_column():
    text = ec_json(("1-1", "3-2"), [2.5, math.nan], [0.75, 0.0], [True, False])
    assert json.loads(text) == {"1-1": [2.5, 0.75, True], "3-2": [None, 0.0, False]}
    ecs = ecs_from_json(text)
    assert ecs == {"1-1": EcOutcome(2.5, 0.75, True), "3-2": EcOutcome(None, 0.0, False)}
    rec = TrialRecord(0, "coarse", IspParams(), 0.0, -9.2, False, ecs)
    assert rec.failing() == ["3-2"]
    assert json.loads(params_json(rec.params)) == {n: getattr(IspParams(), n)
                                                   for n in IspParams.names()}


@pytest.mark.parametrize("status, stopped, text", [
    (RunStatus.RUNNING, None, "running"),
    (RunStatus.DONE, StopReason.DONE, "done"),
    (RunStatus.DONE, None, "done"),
    (RunStatus.DONE, StopReason.MAX_TIME, "stopped (max-time)"),
    (RunStatus.INTERRUPTED, None, "interrupted (continue with --resume)"),
    (RunStatus.FAILED, None, "failed"),
])
def test_the_state_reads_as_status_prints_it(status, stopped, text):
    assert RunState(status, stopped, "random", None).text == text
    assert f"{status}" == status.value  # enums format as their stored value
