"""The run store: typed trial records, the run's settings and state in SQLite, and the free
text status of rvmsim 0.1's stores."""

from __future__ import annotations

import dataclasses
import math

import pytest

from rvmsim.camera import FisheyeCamera
from rvmsim.errors import RvmsimError
from rvmsim.isp import IspParams
from rvmsim.search import TuningConfig
from rvmsim.runs import (EcOutcome, RunSettings, RunStatus, RunStore, StopReason, ec_json,
                         params_json)


def _settings(**changes) -> RunSettings:
    s = RunSettings(scene="/data/scene.yaml", scene_key="abc", vehicle="Vehicle Q",
                    strategy="cmaes", seed=7, budget=300, criteria_file=None,
                    config=TuningConfig.model_validate({"tuned": ["zoom"], "top_m": 4}))
    return dataclasses.replace(s, **changes)


def test_begin_records_the_state_settings_and_space_of_a_starting_run(tmp_path):
    """``begin``: a stopped run resumed is running again (no stop reason left), with its
    settings, planned total and search space read back as they were given."""
    settings = _settings()
    space = settings.config.space(FisheyeCamera(640, 480, 200.0, 200.0, 319.5, 239.5))
    store = RunStore(tmp_path / "run.sqlite")
    store.set_state(RunStatus.DONE, StopReason.MAX_TIME)
    store.begin(settings, space, 300)
    store.close()
    store = RunStore(tmp_path / "run.sqlite", readonly=True)
    state = store.state()
    assert (state.status, state.stopped, state.strategy, state.total) == (
        RunStatus.RUNNING, None, "cmaes", 300)
    assert store.settings() == settings
    assert store.space() == space
    store.close()


def test_trials_come_back_as_typed_records(tmp_path):
    store = RunStore(tmp_path / "run.sqlite")
    ids = ("1-1", "3-2", "4-1")
    p = IspParams().replace(zoom=0.8)
    store.add_rows([
        (0, "coarse", params_json(IspParams()), 0.25, -3.0, 0,
         ec_json(ids, [1.0, math.nan, 1.2], [1.0, 0.0, 0.25], [True, False, False])),
        (1, "fine-1", params_json(p), 0.5, -1.0, 1,
         ec_json(ids, [1.0, 50.0, 1.0], [1.0, 0.5, 1.0], [True, True, True])),
    ])
    first, second = store.trials()
    assert first.ecs == {"1-1": EcOutcome(1.0, 1.0, True), "3-2": EcOutcome(None, 0.0, False),
                         "4-1": EcOutcome(1.2, 0.25, False)}
    assert list(first.ecs) == list(ids) and first.failing() == ["3-2", "4-1"]
    assert second.params == p and second.passed is True and second.failing() == []
    assert first.ecs["3-2"].as_dict() == {"value": None, "score": 0.0, "passed": False}
    assert store.top(1) == [second] and store.scores() == [0.25, 0.5]
    store.close()


def test_settings_and_state_live_in_the_store(tmp_path):
    store = RunStore(tmp_path / "run.sqlite")
    assert store.settings() is None  # nothing recorded: a run of rvmsim 0.1
    settings = _settings()
    store.write_settings(settings)
    store.set_state(RunStatus.RUNNING, strategy="cmaes", total=300)
    store.close()
    store = RunStore(tmp_path / "run.sqlite")  # read back from the file
    assert store.settings() == settings
    state = store.state()
    assert (state.status, state.stopped, state.strategy, state.total, state.text) == (
        RunStatus.RUNNING, None, "cmaes", 300, "running")
    for status, stopped, text in (
            (RunStatus.DONE, StopReason.DONE, "done"),
            (RunStatus.DONE, StopReason.MAX_TIME, "stopped (max-time)"),
            (RunStatus.DONE, StopReason.TARGET_SCORE, "stopped (target-score)"),
            (RunStatus.INTERRUPTED, None, "interrupted (continue with --resume)"),
            (RunStatus.FAILED, None, "failed")):
        store.set_state(status, stopped)
        state = store.state()
        assert (state.status, state.stopped, state.text) == (status, stopped, text)
        assert state.total == 300  # untouched
    meta = store.meta()
    assert meta["format"] == 2 and meta["status"] == "failed" and meta["config"]["top_m"] == 4
    store.close()


@pytest.mark.parametrize("text, status, stopped", [
    ("running", RunStatus.RUNNING, None),
    ("done", RunStatus.DONE, StopReason.DONE),
    ("stopped (max-time)", RunStatus.DONE, StopReason.MAX_TIME),
    ("stopped (target-score)", RunStatus.DONE, StopReason.TARGET_SCORE),
    ("interrupted (continue with --resume)", RunStatus.INTERRUPTED, None),
])
def test_the_free_text_status_of_rvmsim_0_1_is_read(tmp_path, text, status, stopped):
    store = RunStore(tmp_path / "run.sqlite")
    store.set_meta(strategy="random", total=120, status=text)  # as 0.1's tune wrote it
    state = store.state()
    assert (state.status, state.stopped, state.strategy, state.total) == (status, stopped,
                                                                          "random", 120)
    assert state.text == text  # `rvmsim status` prints what it printed
    store.close()


def test_unknown_status_or_format_is_a_one_line_error(tmp_path):
    store = RunStore(tmp_path / "run.sqlite")
    store.set_meta(status="paused (by a newer rvmsim)", strategy="random", total=None)
    with pytest.raises(RvmsimError, match="unknown run status 'paused") as err:
        store.state()
    assert "\n" not in str(err.value)
    store.write_settings(_settings())
    store.set_meta(format=3)
    with pytest.raises(RvmsimError, match="run format 3 is not 2: written by another rvmsim"):
        store.settings()
    store.set_meta(format=2, config={"tuned": ["zoom"], "top_m": "many"})
    with pytest.raises(RvmsimError, match="unreadable run settings") as err:
        store.settings()
    assert "\n" not in str(err.value) and "start a new run" in str(err.value)
    store.close()
