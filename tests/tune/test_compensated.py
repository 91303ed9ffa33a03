"""Robust tuning for the yield after end-of-line compensation (``tune --robust
--compensation``): each sample member is judged with its per-car values; the model is part
of the run's settings."""

from __future__ import annotations

import json
import numpy as np
import pytest

from rvmsim.compensation import DEFAULT_COMPENSATION, CompensationLaw, compensation_from_dict
from rvmsim.pipeline import make_evaluator
from rvmsim.robust import (draw_samples, sample_images, station_readings, variation_from_scene)
from rvmsim.runs import RunStore
from rvmsim.runs.records import RunSettings
from rvmsim.scene import load_scene
from rvmsim.tune import TuneRequest, TuningConfig, tune

from ..cli_runner import run_in_process
from .test_robust import small  # noqa: F401 - the fixture (a small scene, its own cache)

CONFIG = {"output": {"size": [320, 180]}, "top_m": 2}


def test_each_sample_is_judged_with_its_per_car_values(small, tmp_path):
    cfg = TuningConfig.model_validate(CONFIG)
    k = 3
    run = tmp_path / "run"
    tune(TuneRequest((small,), config=cfg, budget=40, seed=3, robust_samples=k,
                     compensation=DEFAULT_COMPENSATION), run)
    store = RunStore(run / "run.sqlite", readonly=True)
    try:
        rec = store.top(1)[0]
        members = store.member_results(rec.idx)
        settings = store.settings()
    finally:
        store.close()
    assert settings.compensation == DEFAULT_COMPENSATION.as_dict()
    # the stored sample members are the per-car values' scores, computed here anew
    scene = load_scene(small)
    var = variation_from_scene(scene)
    samples = draw_samples(var, k, 3)
    out = cfg.output_spec()
    law = CompensationLaw(scene, rec.params, out, DEFAULT_COMPENSATION)
    readings = station_readings(scene, samples, DEFAULT_COMPENSATION, 3, var.load_states[0])
    for i, im in enumerate(sample_images(scene, samples, color=False)):
        c = law.correct(readings[i])
        ev = make_evaluator(im, out)
        want = ev(c.params)
        assert members[1 + i][0] == pytest.approx(want.score, rel=1e-9)
        assert members[1 + i][2] == (want.passed and c.within_range)
        # and not the platform setting's (the correction changed what the car shows)
        assert ev.values(c.params).tolist() != ev.values(rec.params).tolist() or \
            c.offsets["h_pan"] < 0.05
    doc = json.loads((run / "best" / "robust.json").read_text())
    assert doc["compensation"]["station"]["angle_sigma_deg"] == 0.1


def test_the_model_round_trips_through_the_run_settings():
    model = DEFAULT_COMPENSATION.with_station(0.05, 0.5)
    doc = model.as_dict()
    assert compensation_from_dict(doc) == model
    s = RunSettings("s.yaml", None, "v", "cmaes", 0, None, None, TuningConfig(),
                    robust_samples=4, compensation=doc)
    back = RunSettings.from_json(json.loads(json.dumps(s.as_json())))
    assert back == s and back.compensation == doc


def test_cli_refuses_compensation_without_robust_and_records_it_with(small, tmp_path):
    res = run_in_process(["tune", str(small), "--out", str(tmp_path / "r"), "--compensation",
                          "default", "--no-progress"])
    assert res.code == 2 and "--robust" in res.stderr and not (tmp_path / "r").exists()
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(json.dumps(CONFIG))
    res = run_in_process(["tune", str(small), "--robust", "--samples", "2", "--budget", "12",
                          "--compensation", "default", "--config", str(cfg), "--workers", "1",
                          "--out", str(tmp_path / "r"), "--no-progress"])
    assert res.code == 0, res.stderr
    run = json.loads((tmp_path / "r" / "run.json").read_text())
    assert run["robust"]["compensation"]["params"] == ["h_pan", "v_pan", "tilt"]
    assert np.isfinite(json.loads((tmp_path / "r" / "best" / "robust.json").read_text())
                       ["top"][0]["yield"])
