"""Robust tuning for the yield after end-of-line compensation (``tune --robust
--compensation``): each sample member is judged with its per-car values; the model is part
of the run's settings."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rvmsim.compensation import DEFAULT_COMPENSATION, CompensationLaw, compensation_from_dict
from rvmsim.criteria import default_criteria
from rvmsim.isp import OutputSpec
from rvmsim.percar import ImagePicture, SplitEvaluator, make_law
from rvmsim.pipeline import record_output
from rvmsim.render import render_fisheye
from rvmsim.runs.records import RobustRecord, RunKind, RunSettings
from rvmsim.search import TuningConfig

from ..cli_runner import run_in_process, tune_status
from .test_robust import small  # noqa: F401 - the fixture (a small scene, its own cache)

CONFIG = {"output": {"size": [320, 180]}, "top_m": 2}


def test_each_sample_is_judged_with_the_values_its_law_writes():
    """Robust tuning's scorer on two candidates, vehicle D's tuned setting (it passes the
    nominal car) and one that fails it: each sample member's stored score is that of the
    values the model's law writes for its car (rvmsim.percar, the call robustness and eol
    make, computed here anew on the car's station reading), and, for the failing
    candidate, of the reference-point start's values."""
    import dataclasses

    from rvmsim.isp import load_params
    from rvmsim.tune import MembersScorer, member_evaluators
    from rvmsim.tune.compensated import MembersCompensation
    from rvmsim.tune.robust import robust_members

    from ..percar.test_law import SCALE
    from rvmsim.testing.scenes import load_small_scene

    scene = load_small_scene("d", SCALE)
    good, _ = load_params(Path(__file__).parents[1] / "percar" / "vehicle_d_tuned.yaml")
    good = good.for_input_scale(SCALE)
    bad = dataclasses.replace(good, zoom=good.zoom * 0.8)
    model = DEFAULT_COMPENSATION
    k, seed = 3, 4
    settings = RunSettings(str(scene.source), None, "v", "cmaes", seed, None, None,
                           TuningConfig(),
                           kind=RunKind("min", RobustRecord(k, compensation=model.as_dict())))
    nominal = render_fisheye(scene)
    members = robust_members([scene], [nominal], settings)
    crit = default_criteria()
    out = OutputSpec(640, 360)
    evaluators = member_evaluators(members, out, crit).evaluators
    record = record_output(crit, scene)
    stations = [m.station for m in members]
    comp = MembersCompensation(model, record, crit, [m.scene for m in members], stations, [0],
                               [members[0]])
    space = TuningConfig().space(nominal.camera)
    scorer = MembersScorer(evaluators, space, compensation=comp)
    batch = scorer([space.vector(good), space.vector(bad)])
    picture = ImagePicture(SplitEvaluator(nominal, record, crit))
    for i, params in enumerate((space.params(space.vector(good)),
                                space.params(space.vector(bad)))):
        rows = batch.members[i]
        if i == 0:
            assert rows[0][2], "the tuned setting fails the nominal car"
            law = make_law(scene, params, record, model, crit, picture)
            sols = [law.solve(st.measured, st.picture(record, crit)) for st in stations[1:]]
            cars = [(s.params, law.accepts(s)) for s in sols]
        else:
            assert not rows[0][2], "the changed setting passes the nominal car"
            ref = CompensationLaw(scene, params, record, model)
            cars = [(c.params, c.within_range) for c in
                    (ref.correct(st.measured) for st in stations[1:])]
        for j, (car, accepted) in enumerate(cars):
            want = evaluators[1 + j](car)
            assert rows[1 + j][0] == pytest.approx(want.score, rel=1e-12), (i, j)
            assert rows[1 + j][2] == (want.passed and accepted)


def test_the_model_round_trips_through_the_run_settings():
    model = DEFAULT_COMPENSATION.with_station(0.05, 0.5)
    doc = model.as_dict()
    assert compensation_from_dict(doc) == model
    s = RunSettings("s.yaml", None, "v", "cmaes", 0, None, None, TuningConfig(),
                    kind=RunKind("min", RobustRecord(4, compensation=doc)))
    back = RunSettings.from_json(json.loads(json.dumps(s.as_json())))
    assert back == s and back.kind.robust is not None and back.kind.robust.compensation == doc


def test_cli_refuses_compensation_without_robust_and_records_it_with(small, tmp_path):
    res = run_in_process(["tune", str(small), "--out", str(tmp_path / "r"), "--compensation",
                          "default", "--no-progress"])
    assert res.code == 2 and "--robust" in res.stderr and not (tmp_path / "r").exists()
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(json.dumps(CONFIG))
    res = run_in_process(["tune", str(small), "--robust", "--samples", "2", "--budget", "12",
                          "--compensation", "default", "--config", str(cfg), "--workers", "1",
                          "--out", str(tmp_path / "r"), "--no-progress"])
    assert res.code == tune_status(tmp_path / "r"), res.stderr
    run = json.loads((tmp_path / "r" / "run.json").read_text())
    assert run["robust"]["compensation"]["params"] == ["h_pan", "v_pan", "tilt"]
    assert np.isfinite(json.loads((tmp_path / "r" / "best" / "robust.json").read_text())
                       ["top"][0]["yield"])
