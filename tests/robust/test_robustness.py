"""rvmsim.robust.robustness and ``rvmsim robustness``: yield of a setting over variation."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from rvmsim.criteria import Criteria, default_criteria
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.render import render_fisheye
from rvmsim.report import write_robustness_outputs
from rvmsim.robust import RobustnessSettings, robustness

from ..cli_runner import run_in_process
from rvmsim.testing.scenes import load_small_scene, write_small_scene
from .conftest import ANGLES_ONLY, ROOT

OUTPUT = OutputSpec(640, 360)


def _only(ec: str) -> Criteria:
    c = default_criteria()
    items = {k: v if k == ec else dataclasses.replace(v, enabled=False) for k, v in c.items.items()}
    return dataclasses.replace(c, items=items, name=f"only {ec}")


@pytest.fixture(scope="module")
def settings():
    """Two settings of the small scene found on its nominal render by scanning the vertical
    shift: EC 2-1 (bumper centre height, [4, 8] %) in the middle of its range, and just
    inside its upper edge."""
    sc = load_small_scene("a", 0.25, variation=ANGLES_ONLY)
    crit = _only("2-1")
    ev = CandidateEvaluator(render_fisheye(sc).labels, OUTPUT, crit)
    base = IspParams().for_input_scale(0.25)
    shifts = np.arange(10.0, 25.0, 0.25)
    values = np.array([ev(dataclasses.replace(base, v_shift=float(s)))["2-1"].value or 0.0
                       for s in shifts])
    mid = float(shifts[np.argmin(np.abs(values - 6.0))])
    inside = np.flatnonzero(values <= 8.0)
    edge = float(shifts[inside[np.argmax(values[inside])]])
    assert 5.5 <= values[shifts == mid][0] <= 6.5 and 7.5 <= values[shifts == edge][0] <= 8.0
    return sc, crit, dataclasses.replace(base, v_shift=mid), dataclasses.replace(base, v_shift=edge)


def test_a_setting_on_an_ecs_edge_has_a_lower_yield(settings, tmp_path: Path):
    sc, crit, mid, edge = settings
    how = RobustnessSettings(OUTPUT, crit, samples=32, seed=1, scales=(0.5, 1.0))
    r_mid = robustness(sc, mid, how)
    r_edge = robustness(sc, edge, how)
    assert r_edge.yield_ < r_mid.yield_
    assert r_mid.nominal.ec.passed and r_edge.nominal.ec.passed  # both pass as designed
    for r in (r_mid, r_edge):
        assert r.ci[0] <= r.yield_ <= r.ci[1] and r.estimate.n == 32
        assert [p.scale for p in r.scale_curve] == [0.5, 1.0]
        assert r.scale_curve[1].estimate == r.estimate
    e = r_edge.ecs[[x.id for x in r_edge.ecs].index("2-1")]
    assert e.n_fail == 32 - r_edge.estimate.n_pass and e.worst_margin is not None
    assert e.worst_margin < 0 and e.worst_value is not None and e.worst_value > 8.0
    assert e.driver is not None and e.driver.axis == "pitch_deg"
    assert not r_edge.worst.ec.passed
    # the worst sample's frame is that sample's: its EC value is the recorded one
    worst_2_1 = r_edge.evaluation.values[r_edge.worst_index, list(crit.ids).index("2-1")]
    assert r_edge.worst.ec["2-1"].value == pytest.approx(worst_2_1)
    written = write_robustness_outputs(r_edge, tmp_path)
    doc = json.loads(written[0].read_text())
    assert doc["yield"] == r_edge.yield_ and doc["interval"] == "Wilson score"
    assert len(doc["samples"]) == 32 and doc["ecs"][4]["id"] == "2-1"
    html = written[1].read_text()
    assert html.count("data:image/png;base64,") == 4 and "<script" not in html
    assert "Worst: sample" in html


def test_the_same_seed_gives_the_same_result(settings):
    """And without the report's frames (a sweep's yield column) the same samples and
    values, but no nominal or worst frame."""
    sc, crit, _, edge = settings
    how = RobustnessSettings(OUTPUT, crit, samples=16, seed=4, scales=(1.0,))
    a = robustness(sc, edge, how)
    b = robustness(sc, edge, how, frames=False)
    np.testing.assert_array_equal(a.evaluation.values, b.evaluation.values)
    assert a.as_dict()["samples"] == b.as_dict()["samples"]
    assert a.nominal is not None and a.worst is not None
    assert b.nominal is None and b.worst is None and b.as_dict()["nominal"] is None


def _cli_case(folder: Path) -> None:
    write_small_scene(folder, "a", name="scene.yaml", variation=ANGLES_ONLY)
    (folder / "params.yaml").write_text((ROOT / "params" / "paper_defaults.yaml").read_text())


def test_cli_exit_status_follows_min_yield(tmp_path: Path):
    """The paper's defaults do not pass on this car (yield 0): exit 1 below the least
    yield (the variation file's ``min_yield`` when no --min-yield is given), 0 at or above
    it (--min-yield overrides the file's); both write the outputs and record the least
    yield they judged by."""
    _cli_case(tmp_path)
    (tmp_path / "variation.yaml").write_text(yaml.safe_dump({**ANGLES_ONLY, "min_yield": 0.5}))
    args = ["robustness", "scene.yaml", "--params", "params.yaml", "--samples", "8",
            "--scale-samples", "4", "--variation", "variation.yaml", "--no-progress"]
    low = run_in_process([*args, "--out", "a"], cwd=tmp_path)
    assert low.code == 1, low.stderr
    assert "yield 0.0 %" in low.stdout
    ok = run_in_process([*args, "--out", "b", "--min-yield", "0"], cwd=tmp_path)
    assert ok.code == 0, ok.stderr
    for out, least in (("a", 0.5), ("b", 0.0)):
        doc = json.loads((tmp_path / out / "robustness.json").read_text())
        assert doc["min_yield"] == least and doc["meets_min_yield"] is (out == "b")
        assert doc["variation"]["min_yield"] == 0.5
    for out in ("a", "b"):
        assert (tmp_path / out / "robustness.html").is_file()
        assert json.loads((tmp_path / out / "robustness.json").read_text())["n"] == 8


#: ±1° on every angle, ±4 mm across and two load states: 2 x 2 viewpoints at 1x.
WITH_POSITIONS = {"mount": {**ANGLES_ONLY["mount"], "x_mm": {"uniform": {"half_width": 4}}},
                  "load_states": [{"name": "curb", "height_mm": 0, "pitch_deg": 0},
                                  {"name": "full", "height_mm": -40, "pitch_deg": 0.8}]}


def _runner_case(settings, cache: Path, monkeypatch: pytest.MonkeyPatch, runner):
    _, crit, mid, _ = settings
    monkeypatch.setenv("RVMSIM_CACHE", str(cache))
    sc = load_small_scene("a", 0.25, variation=WITH_POSITIONS)
    return robustness(sc, mid, RobustnessSettings(OUTPUT, crit, samples=16, seed=2,
                                                  scales=(0.5, 1.0, 2.0), scale_samples=8),
                      runner=runner)


def _same_evaluation(a, b) -> None:
    """The same samples and, up to a stray GL edge pixel, the same EC values."""
    assert a.as_dict()["samples"][0].keys() == b.as_dict()["samples"][0].keys()
    assert [s.offsets for s in a.samples] == [s.offsets for s in b.samples]
    va, vb = a.evaluation.values, b.evaluation.values
    assert (np.isnan(va) == np.isnan(vb)).all()
    ok = ~np.isnan(va)
    assert np.mean(va[ok] == vb[ok]) >= 0.99
    np.testing.assert_allclose(va[ok], vb[ok], rtol=0, atol=1.0)
    assert abs(a.estimate.n_pass - b.estimate.n_pass) <= 1


@pytest.fixture(scope="module")
def here(settings, tmp_path_factory: pytest.TempPathFactory):
    """The robustness of the small scene rendered as needed, in this process (a cache of
    its own): what every runner must give."""
    with pytest.MonkeyPatch.context() as mp:
        return _runner_case(settings, tmp_path_factory.mktemp("here"), mp, None)


def test_viewpoints_render_up_front_on_local_processes(settings, here, tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch):
    from rvmsim.batch import LocalExecutor

    with LocalExecutor(2) as ex:
        spread = _runner_case(settings, tmp_path / "b", monkeypatch, ex)
    # 1x: 2 x-levels x 2 loads; 0.5x: one level (position_levels_at) x 2; 2x: 2 x 2
    assert spread.timings["viewpoints_rendered"] == 4 + 2 + 4
    assert here.timings["viewpoints_rendered"] == 0  # rendered as needed, not up front
    assert len(list((tmp_path / "b").iterdir())) >= 10  # + the two colour frames' entries
    _same_evaluation(here, spread)
    again = _runner_case(settings, tmp_path / "b", monkeypatch, LocalExecutor(1))
    assert again.timings["viewpoints_rendered"] == 0  # all cached
    np.testing.assert_array_equal(again.evaluation.values, spread.evaluation.values)


@pytest.mark.slow  # a cluster; the local processes' test stays
def test_viewpoints_render_on_a_dask_cluster(settings, here, tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch):
    distributed = pytest.importorskip("distributed")
    from rvmsim.batch import DaskExecutor

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=":0") as c, \
            distributed.Client(c) as client:
        remote = _runner_case(settings, tmp_path / "b", monkeypatch, DaskExecutor(client=client))
    assert remote.timings["viewpoints_rendered"] == 10
    _same_evaluation(here, remote)


def test_ecs_that_read_the_scene_are_measured_on_every_sample(settings):
    """``fmvss111-full``'s 1-5, 1-6 and 6-1 read the scene, the sample's fisheye labels and
    the ISP map: every sample gets them measured (they came out "not measured", failing
    every sample), and the paper's eleven on that path equal the RVM-pixel path's."""
    from rvmsim.criteria import load_criteria

    sc, _, mid, _ = settings
    full = load_criteria("fmvss111-full")
    assert full.uses_scene and not default_criteria().uses_scene
    kw = dict(samples=8, seed=3, scales=(1.0,))
    res = robustness(sc, mid, RobustnessSettings(OUTPUT, full, **kw), frames=False)
    ev = res.evaluation
    cols = [ev.ids.index(e) for e in ("1-5", "1-6", "6-1")]
    assert np.isfinite(ev.values[:, cols]).all(), ev.values[:, cols]
    paper = robustness(sc, mid, RobustnessSettings(OUTPUT, default_criteria(), **kw),
                       frames=False).evaluation
    same = [ev.ids.index(e) for e in paper.ids]
    np.testing.assert_allclose(ev.values[:, same], paper.values, rtol=1e-9, equal_nan=True)
    np.testing.assert_array_equal(ev.passed[:, same], paper.passed)


def test_each_ec_gets_a_sensitivity_fit(settings):
    """EC 2-1 (the bumper centre's height) is a linear function of the pitch over ±1°: the
    fit names pitch first, its slope agrees with two cars pitched to the ends of the range,
    and the summary and robustness.json carry it."""
    from rvmsim.robust import NOMINAL_LOAD, MountSample, evaluate_samples

    sc, crit, _, edge = settings
    r = robustness(sc, edge, RobustnessSettings(OUTPUT, crit, samples=32, seed=3,
                                                scales=(1.0,)), frames=False)
    j = list(crit.ids).index("2-1")
    e = r.ecs[j]
    s = e.sensitivity
    assert s is not None and s.good and s.model == "linear" and s.n == 32
    assert s.coefficients[0][0] == "pitch_deg"
    probes = [MountSample(k, (0.0, 0.0, 0.0, 0.0, p, 0.0), (0.0, 0.0, 0.0), NOMINAL_LOAD)
              for k, p in enumerate((-1.0, 1.0))]
    ends = evaluate_samples(sc, probes, edge, OUTPUT, crit).values[:, j]
    assert s.coefficients[0][1] == pytest.approx((ends[1] - ends[0]) / 2.0, rel=0.25)
    assert e.n_fail and s.describe() in r.summary()
    doc = r.as_dict()["ecs"][j]["sensitivity"]
    assert doc["model"] == "linear" and doc["description"] == s.describe()
    assert doc["coefficients"]["pitch_deg"] == s.coefficients[0][1] and doc["r2"] == s.r2
