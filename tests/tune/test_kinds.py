"""Run kinds as objects (:mod:`rvmsim.tune.kinds`): the settings choose the kind, and a run's
verdict is its kind's, given in memory, agreeing with what the run wrote (small real renders,
real searches)."""

from __future__ import annotations

import dataclasses
import json

import pytest

from rvmsim.compensation import DEFAULT_COMPENSATION
from rvmsim.runs import RunSettings, RunStore
from rvmsim.runs.records import RobustRecord, RunKind, SceneRef
from rvmsim.criteria import default_criteria
from rvmsim.errors import RvmsimError
from rvmsim.markets import market_criteria, market_scene, parse_markets
from rvmsim.scene import load_scene
from rvmsim.tune import (CompensatedSet, Markets, MarketsSet, Robust, RobustSet, Shared,
                         SharedSet, SingleSet, TopRows, TuneRequest, member_set, tune)
from rvmsim.tune.robust import ROBUST_AGGREGATE
from rvmsim.search import TuningConfig
from rvmsim.tune.markets import market_summary_lines
from rvmsim.tune.shared import shared_problem_lines

from rvmsim.testing.scenes import write_small_scene

from .test_markets import DISPLAY, _criteria, scene  # noqa: F401 - scene is a fixture

CONFIG = {"tuned": ["zoom", "adv_v_shift", "adv_v_scale"], "output": {"size": [160, 90]},
          "top_m": 3, "batch": 20}


def test_the_settings_choose_the_run_kind():
    base = RunSettings(scene="a.yaml", scene_key=None, vehicle="a", strategy="random", seed=0,
                       budget=None, criteria_file=None, config=TuningConfig())
    two = (SceneRef("a.yaml", None, "a"), SceneRef("b.yaml", None, "b"))
    comp = DEFAULT_COMPENSATION.as_dict()
    robust = RunKind("min", RobustRecord(4))
    cases = [
        (base, SingleSet, None),
        (dataclasses.replace(base, scenes=two), SharedSet, None),
        (dataclasses.replace(base, kind=robust), RobustSet, SingleSet),
        (dataclasses.replace(base, scenes=two, kind=robust), RobustSet, SharedSet),
        (dataclasses.replace(base, kind=RunKind("min", RobustRecord(4, compensation=comp))),
         CompensatedSet, SingleSet),
        (dataclasses.replace(base, scenes=two, kind=RunKind("min", markets=("fmvss111",))),
         MarketsSet, None),
    ]
    for settings, kind, inner in cases:
        chosen = member_set(settings)
        assert type(chosen) is kind, (settings, chosen)
        if inner is not None:
            assert type(chosen.inner) is inner
    assert member_set(cases[4][0]).compensation is not None
    assert member_set(cases[2][0]).compensation is None


def test_each_kind_is_stored_under_the_keys_runs_have_always_had():
    """``RunSettings.kind`` groups what the stored form keeps at its top level
    (``aggregate``, ``robust``, ``markets``): documents in that form, written by hand as
    rvmsim has stored them since shared, robust and markets runs began, read back as their
    kinds and are written again unchanged."""
    head = {"scene": "/r/a.yaml", "scene_key": None, "vehicle": "a", "strategy": "random",
            "seed": 0, "budget": None, "criteria_file": None,
            "config": TuningConfig().model_dump(mode="json")}
    two = [{"scene": "/r/a.yaml", "scene_key": None, "vehicle": "a"},
           {"scene": "/r/b.yaml", "scene_key": "k", "vehicle": "b"}]
    comp = DEFAULT_COMPENSATION.as_dict()
    robust = {"samples": 4, "variation_file": "/r/v.yaml", "variation_key": "abc"}
    cases = [
        ({}, RunKind()),
        ({"scenes": two, "aggregate": "quantile 0.25"}, RunKind("quantile 0.25")),
        ({"robust": robust, "aggregate": "quantile 0.1"},
         RunKind("quantile 0.1", RobustRecord(4, "/r/v.yaml", "abc"))),
        ({"scenes": two, "aggregate": "min", "robust": {**robust, "compensation": comp}},
         RunKind("min", RobustRecord(4, "/r/v.yaml", "abc", comp))),
        ({"scenes": two, "aggregate": "min", "markets": ["fmvss111", "unr158"]},
         RunKind("min", markets=("fmvss111", "unr158"))),
    ]
    for extra, kind in cases:
        doc = {**head, **extra}
        settings = RunSettings.from_json(json.loads(json.dumps(doc)))
        assert settings.kind == kind, extra
        assert settings.as_json() == doc
        assert list(settings.as_json()) == list(doc)  # in the same order


def test_a_request_takes_its_kind_as_an_object(scene, tmp_path):
    """What a request's kind asks for is what the run records: a markets kind's markets
    and aggregate; a kind that is not one is refused at once."""
    res = tune(TuneRequest((scene,), "random", TuningConfig.model_validate(CONFIG), seed=1,
                           budget=20, kind=Markets(("fmvss111", "unr158"),
                                                   aggregate="quantile 0.5")),
               tmp_path / "run")
    store = RunStore(res.run_dir / "run.sqlite", readonly=True)
    try:
        kind = store.settings().kind
    finally:
        store.close()
    assert kind == RunKind("quantile 0.5", markets=("fmvss111", "unr158"))
    with pytest.raises(TypeError, match="TuneRequest.kind"):
        TuneRequest((scene,), kind="robust")  # type: ignore[arg-type]


@pytest.mark.parametrize("make, says", [
    (lambda: Robust(0), "--samples 0"),
    (lambda: Robust(4, aggregate="median"), "median"),
    (lambda: Shared("quantile 2"), "quantile 2"),
    (lambda: Markets("fmvss111,eu2030"), "eu2030"),
    (lambda: Markets(("unr158", "unr158")), "unr158"),
])
def test_a_kind_checks_its_own_values_when_it_is_made(make, says):
    """A bad value of a kind is one line naming it, before any scene is read."""
    with pytest.raises(RvmsimError, match=says):
        make()


def test_a_kind_normalises_its_aggregate():
    assert Shared("quantile  0.25").aggregate == Shared("quantile 0.25").aggregate
    assert Robust(4).aggregate == ROBUST_AGGREGATE


def test_the_member_shown_is_the_first_markets_or_the_runs_own(scene):
    """What best/, the report and the console show: a markets run's first market (its site,
    its criteria); any other kind, the scene and criteria as the caller loaded them."""
    base = RunSettings(scene=str(scene), scene_key=None, vehicle="a", strategy="random",
                       seed=0, budget=None, criteria_file=None, config=TuningConfig())
    sc, crit = load_scene(scene), default_criteria()
    for kind in (RunKind(), RunKind("min", RobustRecord(4))):
        assert member_set(dataclasses.replace(base, kind=kind)).shown(sc, crit) == (sc, crit)
    markets = dataclasses.replace(base, kind=RunKind("min", markets=("unr158", "fmvss111")))
    shown, judged = member_set(markets).shown(sc, crit)
    r158 = parse_markets("unr158")[0]
    assert shown == market_scene(sc, r158) and shown.test_site != sc.test_site
    assert list(judged.ids) == list(market_criteria(r158).ids) != list(crit.ids)


def test_a_single_run_reports_its_verdict_and_exits_1_when_its_best_fails(scene, tmp_path):
    """A single run whose only EC cannot pass: its verdict fails, names the EC, and the
    exit status is 1 (as every judging command's)."""
    impossible = _criteria(tmp_path, "impossible", 99.0, 100.0)
    res = tune(TuneRequest((scene,), "random", TuningConfig.model_validate(CONFIG),
                           criteria_file=impossible, seed=1, budget=20), tmp_path / "run")
    ec = json.loads((tmp_path / "run" / "best" / "ec.json").read_text())
    assert res.verdict.passed is ec["passed"] is False
    assert res.verdict.problems == ("EC 3-2 fails",)
    assert res.verdict.exit_status == 1
    table = (tmp_path / "run" / "best" / "ec_table.txt").read_text().rstrip()
    assert res.verdict.lines == (table,)
    # one scene on its own image: the kind has nothing to add to a top candidate's score
    store = RunStore(tmp_path / "run" / "run.sqlite", readonly=True)
    try:
        assert member_set(store.settings()).top_rows(store, store.top(3)) == TopRows()
    finally:
        store.close()


def test_a_markets_verdict_fails_and_agrees_with_what_the_run_wrote(scene, tmp_path):
    low = _criteria(tmp_path, "low", 20.0, 40.0)
    high = _criteria(tmp_path, "high", 60.0, 80.0)
    run = tmp_path / "run"
    res = tune(TuneRequest((scene,), "random", TuningConfig.model_validate(CONFIG), seed=1,
                           budget=100, kind=Markets(f"fmvss111:{low},fmvss111:{high}")), run)
    doc = json.loads((run / "best" / "markets.json").read_text())
    assert res.verdict.passed is doc["passed"] is False
    assert res.verdict.exit_status == 1
    # the lines printed from memory are those the file gives a later reader
    assert list(res.verdict.lines[2:]) == market_summary_lines(run)
    assert all(p in res.verdict.lines for p in (f"  {q}" for q in res.verdict.problems))


def test_a_shared_verdict_agrees_with_what_the_run_wrote(cache, tmp_path):
    a = write_small_scene(tmp_path, "a", edit=DISPLAY)
    b = write_small_scene(tmp_path, "b", edit=DISPLAY)
    impossible = _criteria(tmp_path, "impossible", 99.0, 100.0)
    run = tmp_path / "run"
    res = tune(TuneRequest((a, b), "random", TuningConfig.model_validate(CONFIG),
                           criteria_file=impossible, seed=1, budget=20), run)
    assert res.verdict.passed is False and res.verdict.exit_status == 1
    assert list(res.verdict.problems) == shared_problem_lines(run) != []
