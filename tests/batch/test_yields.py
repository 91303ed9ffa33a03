"""batch.yields: a sweep's design points get the yield of their final best setting over the
base scene's variation section, measured in the point's task, stored and resumed."""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import os
import signal
import sqlite3
import time

import pytest

from rvmsim.batch import (YIELD_COLUMNS, DaskExecutor, LocalExecutor, YieldSettings, csv_text,
                          design_points, load_sweep, point_scene_doc, point_task, run_point,
                          run_sweep, stored_sweep, sweep_table)
from rvmsim.criteria import default_criteria
from rvmsim.errors import RvmsimError
from rvmsim.isp import IspParams
from rvmsim.report import write_sweep_outputs
from rvmsim.robust import RobustnessSettings, robustness
from rvmsim.scene import scene_from_dict
from rvmsim.search import TuningConfig

from ..cli_runner import run_in_process, start_in_child
from .conftest import write_sweep

#: A small variation: ±1° on each angle, ±5 mm in height, one rendered position level and
#: two load states (two renders per point).
VARIATION = {
    "mount": {"y_mm": {"uniform": {"half_width": 5}},
              "yaw_deg": {"uniform": {"half_width": 1.0}},
              "pitch_deg": {"uniform": {"half_width": 1.0}},
              "roll_deg": {"normal": {"sigma": 0.5, "truncate": 2}},
              "position_levels": 1},
    "load_states": [{"name": "curb", "height_mm": 0, "pitch_deg": 0, "weight": 0.6},
                    {"name": "full", "height_mm": -40, "pitch_deg": 0.8, "weight": 0.4}],
}

SWEEP = """\
name: tiny yield study
base_scene: base.yaml
axes:
  pitch_deg: [28, 34]
tune:
  strategy: cmaes
  budget: 30
  seed: 1
  config: {output: {size: [320, 180]}}
  recheck: {rounds: 2, budget_factor: 1}
robustness: {samples: 12, seed: 5}
"""


@pytest.fixture(scope="module")
def yield_run(tmp_path_factory):
    f = write_sweep(tmp_path_factory.mktemp("yields"), SWEEP, VARIATION)
    spec = load_sweep(f)
    return f, spec, run_sweep(spec, f.parent / "out", executor=LocalExecutor(2))


def _direct(spec, point, params):
    """robustness() of ``params`` at ``point``, run here (not through the sweep)."""
    doc, config = point_scene_doc(spec, point.values)
    scene = scene_from_dict(doc, source="direct")
    output = TuningConfig.model_validate(config).output_spec()
    return robustness(scene, IspParams(**params), RobustnessSettings(
        output, default_criteria(), samples=spec.robustness.samples,
        seed=spec.robustness.seed, scales=(1.0,)))


def test_each_point_has_the_yield_of_its_stored_best_setting(yield_run):
    """The stored yield equals robustness() run directly on the point's final best
    parameters: yield, interval, failure rates and the EC failing most, recomputed from
    the per-sample pass flags."""
    _, spec, res = yield_run
    assert spec.has_variation
    crit = default_criteria()
    enabled = [e for e in crit.ids if crit.items[e].enabled]
    for p in res.points:
        r = res.results[p.key]
        y = r["robustness"]
        direct = _direct(spec, p, r["params"])
        ev = direct.evaluation
        assert y["n"] == 12 and y["n_pass"] == int(ev.all_passed.sum())
        assert y["yield"] == pytest.approx(ev.all_passed.mean())
        assert y["ci95"] == pytest.approx(list(direct.ci))
        rates = {e: float((~ev.passed[:, ev.ids.index(e)]).mean()) for e in enabled}
        assert y["failure_rates"] == pytest.approx(rates)
        top = max(rates.values())
        if top > 0:
            assert y["limiting_ec"] == next(e for e in enabled if rates[e] == top)
            assert y["limiting_fail_rate"] == pytest.approx(top)
        else:
            assert y["limiting_ec"] is None
    # Some sample's EC differs from another's: the yield is measured, not a constant.
    assert any(0 < v < 1 for p in res.points
               for v in res.results[p.key]["robustness"]["failure_rates"].values())


def test_only_a_recheck_that_becomes_the_best_measures_a_yield(yield_run):
    """Every first-pass run has a yield; a re-check has one exactly when it ranks above
    the point's best before it (so the final best always has its own)."""
    _, _, res = yield_run
    with sqlite3.connect(res.out_dir / "sweep.sqlite") as con:
        first = {k: json.loads(t) for k, t in con.execute("SELECT key, result FROM points")}
        rechecks = sorted(con.execute("SELECT key, round, result FROM rechecks"),
                          key=lambda row: row[1])
    assert rechecks  # the tiny budget passes nowhere: every point is re-checked
    best = {k: (r["passed"], r["score"]) for k, r in first.items()}
    assert all("robustness" in r for r in first.values())
    for key, _, text in rechecks:
        r = json.loads(text)
        beats = (r["passed"], r["score"]) > best[key]
        assert ("robustness" in r) == beats
        if beats:
            best[key] = (r["passed"], r["score"])
    for p in res.points:
        final = res.results[p.key]
        assert (final["passed"], final["score"]) == best[p.key]


def test_outputs_carry_the_yield_columns(yield_run):
    _, spec, res = yield_run
    written = {p.name for p in write_sweep_outputs(res)}
    assert {"yield.png", "sweep.html", "sweep.csv"} <= written
    rows = list(csv.DictReader(io.StringIO((res.out_dir / "sweep.csv").read_text())))
    doc = json.loads((res.out_dir / "sweep.json").read_text())
    for p, row, jp in zip(res.points, rows, doc["points"]):
        y = res.results[p.key]["robustness"]
        assert float(row["yield"]) == y["yield"] == jp["yield"]
        assert [float(row["yield_ci_low"]), float(row["yield_ci_high"])] == y["ci95"]
        assert row["yield_limiting_ec"] == (y["limiting_ec"] or "")
        assert jp["yield_limiting_axis"] == y["limiting_axis"]
        assert jp["yield_limiting_driver"] == y["limiting_driver"]
    assert doc["robustness"] == {"samples": 12, "seed": 5, "variation": True}
    html = (res.out_dir / "sweep.html").read_text()
    assert 'alt="yield map"' in html and "<th>yield</th>" in html


def test_a_base_scene_without_variation_gets_no_yield(tmp_path):
    """No variation section: no yield measured, empty yield columns (kept, for scripts),
    no yield map; a variation with ``samples: 0`` measures none either."""
    text = SWEEP.replace("[28, 34]", "[30]").replace("budget: 30", "budget: 8") \
        .replace("rounds: 2", "rounds: 0")
    spec = load_sweep(write_sweep(tmp_path / "plain", text))
    assert not spec.has_variation
    off = load_sweep(write_sweep(tmp_path / "off", text.replace("samples: 12", "samples: 0"),
                                 VARIATION))
    assert off.has_variation
    for s, folder in ((spec, "plain"), (off, "off")):
        res = run_sweep(s, tmp_path / folder / "out")
        (r,) = res.results.values()
        assert "robustness" not in r
        header, rows = sweep_table(s, res.points, res.results)
        assert set(YIELD_COLUMNS) <= set(header)
        assert all(rows[0][header.index(c)] is None for c in YIELD_COLUMNS)
        written = {p.name for p in write_sweep_outputs(res)}
        assert "yield.png" not in written
        html = (res.out_dir / "sweep.html").read_text()
        assert "yield map" not in html and "<th>yield</th>" not in html


def test_an_interrupted_sweep_resumes_keeping_the_stored_yields(yield_run, tmp_path):
    """Interrupted after its first point: resuming runs the other point only; the stored
    point (its yield included) is untouched and the table is the unbroken run's."""
    f, spec, unbroken = yield_run
    out = tmp_path / "broken"

    def stop(point, result):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, out, executor=LocalExecutor(1), on_result=stop)
    with sqlite3.connect(out / "sweep.sqlite") as con:
        before = con.execute("SELECT key, result, session, finished FROM points").fetchall()
    assert len(before) == 1 and "robustness" in json.loads(before[0][1])
    res = run_sweep(spec, out, executor=LocalExecutor(1))
    assert res.ran == 1
    with sqlite3.connect(out / "sweep.sqlite") as con:
        kept = con.execute("SELECT key, result, session, finished FROM points "
                           "WHERE key = ?", (before[0][0],)).fetchall()
    assert kept == before
    assert csv_text(*sweep_table(spec, res.points, res.results)) == \
        csv_text(*sweep_table(spec, unbroken.points, unbroken.results))


def test_changed_yield_settings_refuse_to_resume(yield_run):
    """Other samples or another seed would mix yields: refused, the store untouched."""
    _, spec, res = yield_run
    db = res.out_dir / "sweep.sqlite"
    before = db.read_bytes()
    for settings in (YieldSettings(16, 5), YieldSettings(12, 6), YieldSettings(0, 5)):
        with pytest.raises(RvmsimError, match="settings or base scene changed"):
            run_sweep(dataclasses.replace(spec, robustness=settings), res.out_dir)
    assert db.read_bytes() == before


def test_dask_workers_measure_the_same_yields(yield_run, cluster, tmp_path):
    """The yield runs inside the point's task: on Dask workers the table is the same."""
    _, spec, local = yield_run
    _, client = cluster
    res = run_sweep(spec, tmp_path / "dask", executor=DaskExecutor(client=client))
    assert csv_text(*sweep_table(spec, res.points, res.results)) == \
        csv_text(*sweep_table(spec, local.points, local.results))
    stored = stored_sweep(spec, tmp_path / "dask").results
    assert all("robustness" in stored[p.key] for p in res.points)


def test_a_recheck_task_measures_the_yield_only_when_it_beats_the_best(yield_run):
    """``beat`` above anything a run can reach: no yield (it cannot become the point's
    best); below: the yield, as for a first pass; no ``robustness`` setting: none."""
    _, spec, _ = yield_run
    p = design_points(spec)[0]
    task = {**point_task(spec, p), "budget": 6, "sensitivity": False}
    assert "robustness" not in run_point({**task, "beat": [True, 2.0]})
    beaten = run_point({**task, "beat": [False, -1.0]})
    assert beaten["robustness"]["n"] == spec.robustness.samples
    assert "robustness" not in run_point({**task, "robustness": None})


def _strip_yields(db):
    """Make ``db`` look as a sweep before yields wrote it: no yields, no yield
    fingerprint."""
    with sqlite3.connect(db) as con:
        con.execute("DELETE FROM meta WHERE key = 'yield_fingerprint'")
        for table, cols in (("points", "key"), ("rechecks", "key, round")):
            for *where, text in con.execute(f"SELECT {cols}, result FROM {table}").fetchall():
                r = json.loads(text)
                r.pop("robustness", None)
                cond = " AND ".join(f"{c.strip()} = ?" for c in cols.split(","))
                con.execute(f"UPDATE {table} SET result = ? WHERE {cond}",
                            (json.dumps(r), *where))


def test_a_store_from_before_yields_gets_them_on_resume(yield_run, tmp_path):
    """Resuming a store whose results have no yields (the previous version's) runs no
    point again and measures only each point's best setting's yield, equal to the yields
    of a sweep that measured them in its tasks; rows keep their session and time."""
    _, spec, unbroken = yield_run
    out = tmp_path / "old"
    out.mkdir()
    with sqlite3.connect(unbroken.out_dir / "sweep.sqlite") as src, \
            sqlite3.connect(out / "sweep.sqlite") as dst:
        src.backup(dst)
    _strip_yields(out / "sweep.sqlite")
    assert all("robustness" not in r for r in stored_sweep(spec, out).results.values())
    with sqlite3.connect(out / "sweep.sqlite") as con:
        times = con.execute("SELECT key, session, finished FROM points").fetchall()
    res = run_sweep(spec, out, executor=LocalExecutor(1))
    assert (res.ran, res.rechecked) == (0, 0)
    for p in res.points:
        got, want = res.results[p.key]["robustness"], unbroken.results[p.key]["robustness"]
        assert {k: v for k, v in got.items() if k != "seconds"} == \
            {k: v for k, v in want.items() if k != "seconds"}
    assert stored_sweep(spec, out).results.keys() == res.results.keys()
    assert all("robustness" in r for r in stored_sweep(spec, out).results.values())
    with sqlite3.connect(out / "sweep.sqlite") as con:
        assert con.execute("SELECT key, session, finished FROM points").fetchall() == times


def test_a_sweep_killed_mid_way_resumes_keeping_the_stored_yields(yield_run, tmp_path):
    """SIGKILL once a point is stored: the resumed CLI sweep keeps that row as it was (its
    yield included) and ends with the unbroken run's table."""
    f, spec, unbroken = yield_run
    out = tmp_path / "killed"
    cmd = ["sweep", f, "--out", out, "--workers", "1", "--no-progress"]
    proc = start_in_child(cmd, start_new_session=True)
    db = out / "sweep.sqlite"
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None and _points(db) < 1:
        time.sleep(0.05)
    assert proc.poll() is None, "the sweep ended before it could be killed"
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=60)
    with sqlite3.connect(db) as con:
        before = con.execute("SELECT key, result, session, finished FROM points").fetchall()
    assert before and all("robustness" in json.loads(r[1]) for r in before)
    done = run_in_process(cmd)
    assert done.code == 0, done.stderr
    with sqlite3.connect(db) as con:
        after = {r[0]: r for r in
                 con.execute("SELECT key, result, session, finished FROM points")}
    assert all(after[row[0]] == row for row in before)
    resumed = stored_sweep(spec, out)
    assert csv_text(*sweep_table(spec, resumed.points, resumed.results)) == \
        csv_text(*sweep_table(spec, unbroken.points, unbroken.results))


def _points(db):
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as con:
            return con.execute("SELECT COUNT(*) FROM points").fetchone()[0]
    except sqlite3.OperationalError:
        return 0


def test_an_infeasible_point_is_neither_searched_nor_given_a_yield(tmp_path):
    """Its verdict is proven from the render: one candidate, no sensitivity, and a yield
    'not measured' with the reason, empty in the table (issue #29)."""
    text = SWEEP.replace("axes:\n  pitch_deg: [28, 34]",
                         "axes:\n  camera_height_m: [0.8]\n  pitch_deg: [30]")
    spec = load_sweep(write_sweep(tmp_path, text, VARIATION))
    res = run_sweep(spec, tmp_path / "out", executor=LocalExecutor(1))
    (r,) = res.results.values()
    assert r["verdict"] == "infeasible" and r["evaluations"] == 1 and r["score"] == 0.0
    assert "sensitivity" not in r and r["rechecks"] == 0
    assert r["robustness"]["error"].startswith("not measured: the point is infeasible (")
    assert r["reason"] in r["robustness"]["error"]
    assert r["phases"]["yield"] < 0.5 and r["phases"]["tune"] < r["seconds"]
    header, rows = sweep_table(spec, res.points, res.results)
    assert all(rows[0][header.index(c)] is None for c in YIELD_COLUMNS)
