"""batch.recheck (with batch.run): the re-check rounds on a real 3 × 3 sweep, their verdicts,
determinism, SIGKILL during the re-check phase and resumption, and a store from before
re-checks existed."""

from __future__ import annotations

import json
import os
import shutil
import signal
import sqlite3
import time

import pytest

from rvmsim.batch import (LocalExecutor, design_points, grid_index, grid_neighbours,
                          load_sweep, merge_point, point_scene_doc, recheck_seed, run_sweep,
                          stored_sweep, sweep_table)
from rvmsim.isp import IspParams
from rvmsim.pipeline import evaluate_params
from rvmsim.render import cached_render
from rvmsim.scene import scene_from_dict
from rvmsim.search import TuningConfig

from ..cli_runner import run_in_process, start_in_child
from .conftest import write_sweep

#: Heights × pitches close together: with a budget of 600 the cold first pass misses some
#: points whose neighbours' optima pass there; 0.95 m hides F/G partly behind the bumper.
GRID = """\
name: recheck study
base_scene: base.yaml
axes:
  camera_height_m: [0.95, 1.0, 1.05]
  pitch_deg: [30, 32, 34]
tune:
  strategy: cmaes
  budget: 600
  seed: 0
  config: {output: {size: [320, 180]}}
  recheck: {rounds: 4, budget_factor: 2, neighbours: 8}
sensitivity: false
"""


@pytest.fixture(scope="module")
def grid_run(tmp_path_factory):
    f = write_sweep(tmp_path_factory.mktemp("grid"), GRID)
    spec = load_sweep(f)
    return f, spec, run_sweep(spec, f.parent / "out", executor=LocalExecutor(2))


def _passes_at(spec, point, params) -> bool:
    """Whether ``params`` pass every EC on ``point``'s render (evaluated directly, not by
    the sweep)."""
    doc, config = point_scene_doc(spec, point.values)
    images, _ = cached_render(scene_from_dict(doc, source=point.label))
    out = TuningConfig.model_validate(config).output_spec()
    frame = evaluate_params(images, IspParams(**params), out, spec.criteria(), annotate=False)
    return bool(frame.ec.passed)


def test_a_point_a_neighbours_optimum_solves_is_not_reported_failing(grid_run):
    _, spec, res = grid_run
    near = grid_neighbours(spec, res.points)
    solved_by_neighbour = 0
    for p in res.points:
        r = res.results[p.key]
        assert r["verdict"] in ("pass", "not found", "infeasible")
        assert (r["verdict"] == "pass") == r["passed"]
        if r["passed"]:  # the search-free check never contradicts a search
            assert r["infeasible"] == []
        passing = [q for q in near[p.key] if res.results[q.key]["verdict"] == "pass"]
        helps = [q for q in passing if _passes_at(spec, p, res.results[q.key]["params"])]
        if r["verdict"] != "pass":
            # Never failing where a neighbour's optimum passes.
            assert not helps, (p.label, [q.label for q in helps])
        elif not r["first_pass"]["passed"] and helps:
            solved_by_neighbour += 1
            assert r["found_in"] >= 1 and r["rechecks"] >= 1
            assert r["evaluations"] > r["first_pass"]["evaluations"]
    assert solved_by_neighbour >= 1, "the cold pass missed no point a neighbour solves"
    assert res.rechecked >= solved_by_neighbour


@pytest.mark.slow  # a cluster; test_tasks.py runs batches on Dask
def test_rechecks_on_dask_give_the_local_results(grid_run, cluster, tmp_path):
    from rvmsim.batch import DaskExecutor

    _, spec, local = grid_run
    _, client = cluster
    res = run_sweep(spec, tmp_path / "dask", executor=DaskExecutor(client=client))
    assert res.rechecked == local.rechecked >= 1
    assert sweep_table(spec, res.points, res.results) == \
        sweep_table(spec, local.points, local.results)


def test_infeasible_points_are_not_rechecked_and_say_why(grid_run):
    _, spec, res = grid_run
    infeasible = [p for p in res.points if res.results[p.key]["verdict"] == "infeasible"]
    assert infeasible  # 0.95 m: the patches are partly behind the bumper
    for p in infeasible:
        r = res.results[p.key]
        assert r["rechecks"] == 0 and r["reason"].startswith("1-1: object ")
        assert "behind the bumper" in r["reason"]
        assert not r["passed"]
    # Only points not found after the first pass were re-checked.
    with sqlite3.connect(res.out_dir / "sweep.sqlite") as db:
        rechecked = {k for (k,) in db.execute("SELECT DISTINCT key FROM rechecks")}
    assert rechecked and not rechecked & {p.key for p in infeasible}
    assert all(not res.results[k]["first_pass"]["passed"] for k in rechecked)


def _sweep_cmd(f, out):
    return ["sweep", f, "--out", out, "--workers", "1", "--no-progress"]


def _count(db, table):
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as con:
            return con.execute(f"SELECT COUNT(*) FROM {table}").fetchone()[0]
    except sqlite3.OperationalError:
        return 0


def test_sigkill_during_the_recheck_phase_resumes_to_the_unbroken_results(grid_run, tmp_path):
    f, spec, unbroken = grid_run
    out = tmp_path / "killed"
    # the unbroken sweep's store as it was when its first pass ended (the re-checks are
    # rows of their own; the first pass's are not changed by them): the killed sweep
    # starts in its re-check phase instead of searching every point again
    shutil.copytree(unbroken.out_dir, out, ignore=shutil.ignore_patterns("sweep.lock",
                                                                          "sweep.pid"))
    with sqlite3.connect(out / "sweep.sqlite") as con:
        assert con.execute("DELETE FROM rechecks").rowcount >= 1
    con.close()
    proc = start_in_child(_sweep_cmd(f, out), start_new_session=True)
    db = out / "sweep.sqlite"
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None and _count(db, "rechecks") < 1:
        time.sleep(0.05)
    assert proc.poll() is None, "the sweep ended before a re-check was stored"
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait(timeout=60)
    with sqlite3.connect(db) as con:
        points_before = dict(con.execute("SELECT key, finished FROM points"))
        rechecks_before = {(k, r): t for k, r, t in
                           con.execute("SELECT key, round, finished FROM rechecks")}
    assert len(points_before) == 9 and rechecks_before
    res = run_in_process(_sweep_cmd(f, out))
    assert res.code == 0, res.stderr
    assert "0 run now, 9 already done" in res.stdout
    with sqlite3.connect(db) as con:
        assert dict(con.execute("SELECT key, finished FROM points")) == points_before
        after = {(k, r): t for k, r, t in con.execute("SELECT key, round, finished FROM rechecks")}
    assert all(after[k] == t for k, t in rechecks_before.items())  # not redone
    resumed = stored_sweep(spec, out)
    assert sweep_table(spec, resumed.points, resumed.results) == \
        sweep_table(spec, unbroken.points, unbroken.results)
    assert set(after) == {(k, r) for k, r in _recheck_rows(unbroken.out_dir)}


def _recheck_rows(out):
    with sqlite3.connect(out / "sweep.sqlite") as con:
        return con.execute("SELECT key, round FROM rechecks").fetchall()


@pytest.mark.slow  # the sweep twice; test_run.py's resume tests compare runs too
def test_results_are_deterministic_per_seed(grid_run, tmp_path):
    """The same sweep again (one process instead of two) gives the same table; another
    seed searches differently."""
    f, spec, first = grid_run
    again = run_sweep(spec, tmp_path / "again", executor=LocalExecutor(1))
    assert sweep_table(spec, again.points, again.results) == \
        sweep_table(spec, first.points, first.results)
    assert recheck_seed(0, 1) == recheck_seed(0, 1)
    assert len({recheck_seed(0, 1), recheck_seed(0, 2), recheck_seed(1, 1), 0}) == 4


def test_neighbours_are_adjacent_in_axis_index_space(grid_run):
    _, spec, res = grid_run
    near = grid_neighbours(spec, res.points)
    by_index = {grid_index(spec, p): p for p in res.points}
    assert len(near[by_index[(1, 1)].key]) == 8  # the centre: every other point
    assert {grid_index(spec, q) for q in near[by_index[(0, 0)].key]} == {(0, 1), (1, 0),
                                                                         (1, 1)}


def test_merge_point_takes_the_best_run_and_sums_the_evaluations(grid_run):
    _, _, res = grid_run
    r = next(v for v in res.results.values() if v["found_in"] >= 1)
    first = {**r, "passed": False, "score": 0.001, "evaluations": 600, "infeasible": []}
    later = {**r, "passed": True, "score": 0.7, "evaluations": 1200}
    merged = merge_point(first, [(1, later), (2, {"error": "boom"})])
    assert merged["verdict"] == "pass" and merged["found_in"] == 1
    assert merged["evaluations"] == 1800 and merged["score"] == 0.7
    assert merge_point(first)["verdict"] == "not found"
    inf = {**first, "infeasible": [{"ec": "1-1", "reason": "1-1: why", "short": "1-1: w"}]}
    assert merge_point(inf)["verdict"] == "infeasible"
    assert merge_point(inf)["reason"] == "1-1: why"


def test_a_store_from_before_rechecks_is_read_and_resumed(tmp_path):
    """A sweep.sqlite as the previous version wrote it (no rechecks table, no re-check
    fingerprint, results without the infeasibility check): read, then resumed with
    re-checks only."""
    text = GRID.replace("[0.95, 1.0, 1.05]", "[1.0]").replace("[30, 32, 34]", "[30, 34]") \
        .replace("budget: 600", "budget: 100").replace("rounds: 4", "rounds: 1")
    f = write_sweep(tmp_path, text)
    spec = load_sweep(f)
    out = tmp_path / "old"
    run_sweep(spec, out, executor=LocalExecutor(1))
    with sqlite3.connect(out / "sweep.sqlite") as con:
        con.execute("DROP TABLE rechecks")
        con.execute("DELETE FROM meta WHERE key = 'recheck_fingerprint'")
        for key, text_ in con.execute("SELECT key, result FROM points").fetchall():
            r = json.loads(text_)
            for k in ("infeasible", "budget"):
                r.pop(k)
            con.execute("UPDATE points SET result = ? WHERE key = ?", (json.dumps(r), key))
    old = stored_sweep(spec, out)
    assert len(old.results) == 2
    assert {r["verdict"] for r in old.results.values()} <= {"pass", "not found"}
    res = run_sweep(spec, out, executor=LocalExecutor(1))
    assert res.ran == 0
    failing = [k for k, r in old.results.items() if not r["passed"]]
    assert res.rechecked == len(failing)
    assert all(res.results[k]["rechecks"] == 1 for k in failing)
    assert all(res.results[k]["evaluations"] > old.results[k]["evaluations"] for k in failing)


def test_rounds_zero_is_the_first_pass_only(tmp_path):
    text = GRID.replace("[0.95, 1.0, 1.05]", "[1.0]").replace("[30, 32, 34]", "[30]") \
        .replace("budget: 600", "budget: 20").replace("rounds: 4", "rounds: 0")
    f = write_sweep(tmp_path, text)
    spec = load_sweep(f)
    res = run_sweep(spec, tmp_path / "o")
    (p,) = design_points(spec)
    assert res.rechecked == 0 and res.results[p.key]["rechecks"] == 0
    assert res.results[p.key]["evaluations"] == res.results[p.key]["first_pass"]["evaluations"]
