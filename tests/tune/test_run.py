"""Tuning runs in run folders: resume after kill -9 and Ctrl-C gives the unbroken result; a
scene object or a cluster task records the paths it is given; failures are recorded; run
folders of rvmsim 0.1 are read by status, select, report and --resume, or refused with what
to do."""

from __future__ import annotations

import dataclasses

import json
import signal
import sqlite3
import subprocess
import time

import pytest
import yaml

from rvmsim.batch import portable_scene_doc, tune_task
from rvmsim.tune import TuneRequest, resume, tune
from rvmsim.search import STRATEGIES, Strategy, TuningConfig, register_strategy
from rvmsim.runs import RunStatus, RunStore, StopReason, run_settings, status_lines

from ..cli_runner import run_in_process, start_in_child, tune_status
from ..conftest import SCENES
from .common import make_legacy_run
from .conftest import CONFIG, top_of

def test_the_store_holds_the_settings_run_json_exports_them(clean):
    store = RunStore(clean / "run.sqlite")
    settings = store.settings()
    state = store.state()
    store.close()
    assert settings is not None and settings.scene == str((SCENES / "vehicle_a.yaml").resolve())
    assert (settings.strategy, settings.seed, settings.budget) == ("random", 2, 60)
    assert settings.config == TuningConfig.model_validate(CONFIG)
    assert (state.status, state.stopped, state.total) == (RunStatus.DONE, StopReason.DONE, 60)
    assert json.loads((clean / "run.json").read_text()) == settings.as_json()


def test_a_scene_object_and_a_task_record_the_paths_they_are_given(clean, tmp_path):
    """tune() takes a loaded Scene with the path to record; tune_task builds its scene
    from the portable document (no temporary scene file) and records the submitter's path."""
    from rvmsim.scene import load_scene

    path = SCENES / "vehicle_a.yaml"
    run = tmp_path / "obj"
    tune(TuneRequest((load_scene(path),), "random", TuningConfig.model_validate(CONFIG),
                     seed=2, budget=60, scene_file=path), run)
    assert top_of(run) == top_of(clean)
    assert json.loads((run / "run.json").read_text()) == json.loads((clean / "run.json").read_text())
    res = tune_task({"scene": portable_scene_doc(path), "config": CONFIG, "strategy": "random",
                     "seed": 2, "budget": 60, "scene_file": str(path)})
    assert "error" not in res and res["evaluated"] == 60
    task_run = tmp_path / "task"
    for rel, data in res["files"].items():
        (task_run / rel).parent.mkdir(parents=True, exist_ok=True)
        (task_run / rel).write_bytes(data)
    assert top_of(task_run) == top_of(clean)
    store = RunStore(task_run / "run.sqlite")
    assert store.settings() == run_settings(clean, RunStore(clean / "run.sqlite"))
    store.close()
    assert (task_run / "best" / "ec_annotated.png").is_file()


class _FailsAfterOneBatch(Strategy):
    name = "fails-after-one-batch"

    @classmethod
    def from_settings(cls, space, settings, *, seed, budget, batch):
        return cls(space, seed=seed)

    def batches(self):
        yield "first", [(self.space.low + self.space.high) / 2] * 5
        raise ValueError("this strategy gives up")


def test_a_failing_search_is_recorded_as_failed(cache, tmp_path):
    register_strategy(_FailsAfterOneBatch)
    try:
        with pytest.raises(ValueError, match="gives up"):
            tune(TuneRequest((SCENES / "vehicle_a.yaml",), "fails-after-one-batch",
                             TuningConfig.model_validate(CONFIG)), tmp_path / "r")
    finally:
        del STRATEGIES["fails-after-one-batch"]
    store = RunStore(tmp_path / "r" / "run.sqlite")
    assert store.state().status is RunStatus.FAILED and store.count() == 5
    store.close()
    assert status_lines(tmp_path / "r")[0].endswith(": failed, strategy fails-after-one-batch, "
                                                    "5 evaluations")


def test_an_interrupted_old_run_resumes_to_the_unbroken_result(clean, tmp_path):
    old = make_legacy_run(clean, tmp_path / "old", keep=20,
                          status="interrupted (continue with --resume)")
    assert "interrupted (continue with --resume), strategy random, 20 / 60" in status_lines(old)[0]
    res = resume(old)
    assert (res.outcome.replayed, res.outcome.evaluated) == (20, 40)
    assert top_of(old) == top_of(clean)
    store = RunStore(old / "run.sqlite")
    # resumed, it is a run of this version: settings and state in its store (a run from
    # before runs recorded their size of record keeps "not recorded")
    resumed = store.settings()
    assert resumed is not None and resumed.judged_at is None
    assert dataclasses.replace(resumed, judged_at=(1280, 720)) == run_settings(
        clean, RunStore(clean / "run.sqlite"))
    assert store.state().status is RunStatus.DONE
    store.close()


@pytest.mark.parametrize("strategy", [pytest.param("grid-random", marks=pytest.mark.slow),
                                      "cmaes-solved"])
def test_resume_after_kill_gives_the_clean_result(tmp_path, strategy):
    """A real `rvmsim tune` subprocess is killed with SIGKILL mid-run, resumed, and ends with
    exactly the top-M of an uninterrupted run (the paper's search, and the default one,
    whose stored trials hold solved parameters)."""
    env = {"RVMSIM_CACHE": str(tmp_path / "cache")}
    cfg = tmp_path / "tune.yaml"
    cfg.write_text(yaml.safe_dump({
        "tuned": ["fov", "rad", "zoom", "adv_v_shift"], "batch": 40, "top_m": 5,
        "output": {"size": [320, 180]}, "grid_random": {"top_n": 2, "trials": 1000},
        "cmaes_solved": {"budget": 1000},
    }))
    scene = str(SCENES / "vehicle_d.yaml")

    def tune(out, *extra):
        return ["tune", *extra, "--no-progress", "--workers", "1",
                *([scene, "--out", out, "--config", cfg, "--strategy", strategy]
                  if "--resume" not in extra else [])]

    clean = run_in_process(tune(tmp_path / "clean"), env=env)
    assert clean.code == tune_status(tmp_path / "clean"), clean.stderr
    run = tmp_path / "killed"
    proc = start_in_child(tune(run), env=env)
    db = run / "run.sqlite"
    deadline = time.time() + 300
    count = 0
    while time.time() < deadline:
        if db.exists():
            try:
                count = sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0]
            except sqlite3.Error:
                count = 0
            if count >= 200:
                break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    stored = sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0]
    total = 81 + 2 * 1000 if strategy == "grid-random" else 1000  # grid, then top_n × trials
    assert 200 <= stored < total, stored  # killed mid-run, completed batches kept
    if strategy == "grid-random":
        assert stored % 40 in (0, 81 % 40)  # whole batches only
    resumed = run_in_process(tune(None, "--resume", run), env=env)
    assert resumed.code == clean.code, resumed.stderr
    assert "replayed" in resumed.stdout

    def top(path):
        s = RunStore(path / "run.sqlite")
        t = [(r.idx, r.params, r.score) for r in s.top(5)]
        n = s.count()
        s.close()
        return t, n

    assert top(run) == top(tmp_path / "clean")
    for k in range(1, 6):
        assert (run / "top" / f"rank_{k}.yaml").is_file()
    # best/ judges rank 1 at the RVM image of record: its verdict is the stored one, and
    # so is its score when it could pass (a clear fail keeps the search size's values)
    doc = json.loads((run / "best" / "ec.json").read_text())
    store = RunStore(run / "run.sqlite")
    best = store.trials_at([doc["trial"]])[0]
    store.close()
    assert doc["passed"] == bool(best.passed)
    if best.passed:
        assert doc["ec_score"] == pytest.approx(best.score)


@pytest.mark.slow  # tests/test_process_lifetime.py stops tune by SIGINT and resumes it
def test_ctrl_c_stops_cleanly_and_resumes(tmp_path):
    env = {"RVMSIM_CACHE": str(tmp_path / "cache")}
    cfg = tmp_path / "tune.yaml"
    cfg.write_text(yaml.safe_dump({"tuned": ["fov", "rad", "zoom", "adv_v_shift"], "batch": 40,
                                   "output": {"size": [320, 180]},
                                   "grid_random": {"top_n": 2, "trials": 1500}}))
    run = tmp_path / "run"
    proc = start_in_child(  # with SIGINT at its default, as from a terminal
        ["tune", SCENES / "vehicle_a.yaml", "--out", run, "--config", cfg, "--workers", "1",
         "--no-progress", "--strategy", "grid-random"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    db = run / "run.sqlite"
    deadline = time.time() + 300
    while time.time() < deadline:
        if db.exists():
            try:
                if sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0] >= 120:
                    break
            except sqlite3.Error:
                pass
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "interrupted" in err and "Traceback" not in err
    store = RunStore(db)
    assert store.state().status is RunStatus.INTERRUPTED and 120 <= store.count() < 81 + 3000
    assert store.state().text == "interrupted (continue with --resume)"
    store.close()
    res = run_in_process(["tune", "--resume", run, "--workers", "1", "--no-progress"], env=env)
    assert res.code == tune_status(run), res.stderr
    store = RunStore(db)
    assert store.count() == 81 + 2 * 1500 and store.state().status is RunStatus.DONE
    store.close()
