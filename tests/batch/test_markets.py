"""Sweeps over markets (batch.markets): a two-point sweep of vehicle A at 320 × 240 tuned for
fmvss111 and unr158 at once on spawned local processes; each market's verdict checked by
evaluating the point's best setting on that market's own render; a point whose R158 far
row is cut by the sensor border reported infeasible naming unr158's EC (the cut checked on
the label image); bad ``tune.markets`` keys as one line, exit 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rvmsim.batch import (LocalExecutor, infeasible_ecs, load_sweep, run_sweep, sweep_table)
from rvmsim.isp import IspParams
from rvmsim.markets import market_criteria, market_scene, parse_markets
from rvmsim.pipeline import make_evaluator
from rvmsim.render import cached_render
from rvmsim.report import write_sweep_outputs
from rvmsim.report.sweep import feasibility_grid
from rvmsim.scene import scene_from_dict
from rvmsim.search import TuningConfig

from ..cli_runner import run_in_process
from .conftest import write_sweep

MARKETS_SWEEP = """\
name: tiny markets study
base_scene: base.yaml
axes:
  pitch_deg: [32, 75]
tune:
  strategy: cmaes
  budget: 100
  seed: 3
  config: {output: {size: [320, 180]}}
  markets: [fmvss111, unr158]
  recheck: {rounds: 0}
"""


@pytest.fixture(scope="module")
def markets_run(tmp_path_factory):
    path = write_sweep(tmp_path_factory.mktemp("markets"), MARKETS_SWEEP)
    spec = load_sweep(path)
    res = run_sweep(spec, path.parent / "out", executor=LocalExecutor(2))
    write_sweep_outputs(res)
    return spec, res


def _market_renders(spec, point):
    """Per market: (name, scene at its site, its render, its criteria), built here."""
    from rvmsim.batch import point_scene_doc

    doc, _ = point_scene_doc(spec, point.values)
    scene = scene_from_dict(doc, source=point.label)
    out = []
    for m in parse_markets(["fmvss111", "unr158"]):
        sc = market_scene(scene, m)
        out.append((m.name, sc, cached_render(sc)[0], market_criteria(m)))
    return out


def test_each_market_verdict_is_that_markets_own(markets_run):
    spec, res = markets_run
    assert spec.markets == ("fmvss111", "unr158")
    for p in res.points:
        r = res.results[p.key]
        assert "error" not in r, r
        params = IspParams(**r["params"])
        config = TuningConfig.model_validate(dict(spec.config))
        failing = []
        for name, sc, images, criteria in _market_renders(spec, p):
            ec = make_evaluator(images, config.output_spec(), criteria, path="full")(params)
            own = r["markets"][name]
            assert own["passed"] == ec.passed
            assert own["score"] == pytest.approx(ec.score, abs=1e-6)
            assert own["failing"] == [v.id for v in ec.items if v.enabled and not v.passed]
            failing += [(v.score, name, v.id) for v in ec.items if v.enabled and not v.passed]
        # A point passes only when every market does; the limiting EC names its market.
        assert r["passed"] == all(o["passed"] for o in r["markets"].values())
        assert r["score"] == pytest.approx(min(o["score"] for o in r["markets"].values()))
        if failing:
            _, market, ec_id = min(failing)
            assert (r["limiting_market"], r["limiting_ec"]) == (market, ec_id)
        else:
            assert r["limiting_ec"] is None and r["limiting_market"] is None


def test_far_row_cut_by_the_border_is_infeasible_for_unr158(markets_run):
    spec, res = markets_run
    steep = next(p for p in res.points if dict(p.values)["pitch_deg"] == 75)
    r = res.results[steep.key]
    assert r["verdict"] == "infeasible" and not r["passed"]
    # proven before any search: one candidate, failing the infeasible ECs, no probe
    assert r["evaluations"] == 1 and r["stopped"] == "infeasible" and "sensitivity" not in r
    assert set(r["phases"]) == {"render", "tune", "yield"}
    unr = [x for x in r["infeasible"] if x["market"] == "unr158"]
    assert unr and unr[0]["ec"] == "R158-3" and unr[0]["reason"].startswith("unr158: R158-3: ")
    assert "unr158: R158-3" in r["reason"]
    renders = {name: (sc, im, crit) for name, sc, im, crit in _market_renders(spec, steep)}
    sc, im, crit = renders["unr158"]
    # The stored findings are the check's on unr158's own render, with its criteria ...
    direct = infeasible_ecs(sc, im.camera, im.labels, crit)
    assert [(x["ec"], x["reason"]) for x in unr] == [(f.ec, "unr158: " + f.reason)
                                                     for f in direct]
    # ... and the label image shows why: a row-3 cylinder's pixels touch the sensor border.
    touching = []
    for obj in sc.test_site.site_objects:
        if obj.name.startswith("row3"):
            mask = np.isin(im.labels, obj.labels)
            edge = mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any()
            if edge:
                touching.append(obj.name)
    assert touching and any(name in unr[0]["reason"] for name in touching)
    # At the moderate pitch no R158 EC is proven impossible.
    mild = next(p for p in res.points if dict(p.values)["pitch_deg"] == 32)
    assert not [x for x in res.results[mild.key]["infeasible"] if x["market"] == "unr158"]


def test_table_page_and_map_show_every_market(markets_run):
    spec, res = markets_run
    header, rows = sweep_table(spec, res.points, res.results)
    for col in ("limiting_market", "pass_fmvss111", "pass_unr158", "ec_1-1", "ec_R158-3"):
        assert col in header
    assert header.index("limiting_market") == header.index("limiting_ec") + 1
    for p, row in zip(res.points, rows):
        r = res.results[p.key]
        cells = dict(zip(header, row))
        assert cells["pass_unr158"] == r["markets"]["unr158"]["passed"]
        assert cells["passed"] == (cells["pass_fmvss111"] and cells["pass_unr158"])
    g = feasibility_grid(spec, res.points, res.results)
    for j, x in enumerate(g.xs):
        r = next(res.results[p.key] for p in res.points if dict(p.values)["pitch_deg"] == x)
        assert g.passed[0, j] == all(o["passed"] for o in r["markets"].values())
    out = res.out_dir
    doc = json.loads((out / "sweep.json").read_text())
    assert doc["markets"] == ["fmvss111", "unr158"]
    assert "pass_unr158" in (out / "sweep.csv").read_text().splitlines()[0]
    html = (out / "sweep.html").read_text()
    assert "markets fmvss111 + unr158" in html and "<th>pass_unr158</th>" in html


def test_a_changed_market_list_refuses_to_resume(markets_run, tmp_path):
    spec, res = markets_run
    other = MARKETS_SWEEP.replace("[fmvss111, unr158]", "[fmvss111, jp]")
    path = write_sweep(tmp_path, other)
    assert load_sweep(path).fingerprint() != spec.fingerprint()


@pytest.mark.parametrize("tune_lines, message", [
    ("  criteria: fmvss111-full\n  markets: [fmvss111, unr158]\n",
     "tune.markets: give tune.criteria or tune.markets, not both"),
    ("  markets: [fmvss111, eu2030]\n", "tune.markets: 'eu2030': unknown market"),
    ("  markets: []\n", "tune.markets: give at least one market"),
    ("  markets: [unr158, unr158]\n", "tune.markets: unr158 given twice"),
    ("  markets: [./nowhere.yaml:unr158]\n", "no such file"),
])
def test_bad_markets_keys_are_one_line_exit_2(tmp_path, tune_lines, message):
    text = ("name: bad\nbase_scene: base.yaml\naxes:\n  pitch_deg: [30]\ntune:\n"
            "  budget: 10\n" + tune_lines)
    f = write_sweep(tmp_path, text)
    res = run_in_process(["sweep", f, "--out", tmp_path / "o", "--no-progress"])
    assert res.code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.stderr, res.stderr
    assert message in lines[0] and str(f) in lines[0]
    assert not (tmp_path / "o").exists()


def test_markets_yield_counts_a_sample_only_when_every_market_passes(markets_run):
    from rvmsim.batch import markets_yield
    from rvmsim.markets import market_members
    from rvmsim.robust import RobustnessSettings, robustness

    from .test_yields import VARIATION

    spec, res = markets_run
    mild = next(p for p in res.points if dict(p.values)["pitch_deg"] == 32)
    params = IspParams(**res.results[mild.key]["params"])
    from rvmsim.batch import point_scene_doc

    doc, _ = point_scene_doc(spec, mild.values)
    scene = scene_from_dict({**doc, "variation": VARIATION}, source=mild.label)
    pairs = market_members([scene], parse_markets(["unr158", "fmvss111"]))
    output = TuningConfig.model_validate(dict(spec.config)).output_spec()
    y = markets_yield(pairs, params, output, samples=12, seed=5)
    assert "error" not in y, y
    # Each market on its own (independently of markets_yield), then a sample passes only
    # where it passes in both.
    own = [robustness(p.scene, params, RobustnessSettings(output, p.criteria, samples=12,
                                                          seed=5, scales=(1.0,)), frames=False)
           for p in pairs]
    both = own[0].passed & own[1].passed
    assert (y["n"], y["n_pass"]) == (12, int(both.sum()))
    assert y["yield"] <= min(r.estimate.yield_ for r in own)
    for p, r in zip(pairs, own):
        for e in r.ecs:
            if e.enabled:
                assert y["failure_rates"][f"{p.market.name}: {e.id}"] == e.failure_rate
    top = max(y["failure_rates"].values())
    if top > 0:
        assert y["failure_rates"][y["limiting_ec"]] == top
