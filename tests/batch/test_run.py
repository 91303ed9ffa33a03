"""batch.run (with batch.point): real renders and real CMA-ES runs per design point, on local
processes and on a Dask LocalCluster started on loopback; a worker killed mid-sweep; Ctrl-C +
resume."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import threading
import time

import pytest

from rvmsim.batch import DaskExecutor, load_sweep, run_sweep, stored_sweep, sweep_table
from rvmsim.errors import RvmsimError

from ..cli_runner import run_in_process, start_in_child
from .conftest import SWEEP, write_sweep

distributed = pytest.importorskip("distributed")


def test_local_sweep_results_and_sensitivity(local_run):
    spec, res = local_run
    assert res.ran == 6 and len(res.results) == 6
    criteria = spec.criteria()
    for p in res.points:
        r = res.results[p.key]
        assert "error" not in r, r
        assert list(r["ecs"]) == list(criteria.ids)
        # The limiting EC is a failing one with the lowest score (None when all pass).
        failing = {e: v["score"] for e, v in r["ecs"].items() if not v["passed"]}
        assert r["limiting_ec"] == (min(failing, key=failing.get) if failing else None)
        assert set(r["phases"]) == {"render", "tune", "yield"}
        assert sum(r["phases"].values()) <= r["seconds"]
        if r["infeasible"]:  # proven before any search: one candidate, failing those ECs
            assert r["evaluations"] == 1 and r["stopped"] == "infeasible"
            assert r["score"] == 0.0 and "sensitivity" not in r
            assert all(not r["ecs"][x["ec"]]["passed"] for x in r["infeasible"])
            continue
        assert 0.0 <= r["score"] <= 1.0 and r["evaluations"] == 200
        # Sensitivity: every tuned parameter, probed at ±2/5/10 % of its range; the optimum
        # is the point's best score.
        sens = r["sensitivity"]
        assert sens["optimum"] == pytest.approx(r["score"], rel=1e-9)
        assert set(sens["params"]) == set(r["tuned"])


def test_dask_cluster_gives_the_same_table(local_run, cluster, tmp_path):
    spec, res_local = local_run
    _, client = cluster
    res = run_sweep(spec, tmp_path / "dask", executor=DaskExecutor(client=client))
    assert res.ran == 6
    assert sweep_table(spec, res.points, res.results) == \
        sweep_table(spec, res_local.points, res_local.results)


def test_worker_killed_mid_sweep_still_completes_every_point_once(local_run, cluster, tmp_path):
    spec, res_local = local_run
    c, client = cluster
    client.wait_for_workers(2, timeout=60)
    pids = client.run(os.getpid)  # worker address -> worker process id
    killed: list[str] = []

    def killer():
        deadline = time.time() + 120
        while time.time() < deadline and not killed:
            busy = [a for a, keys in client.processing().items() if keys]
            if busy:
                time.sleep(0.5)  # let the task get going
                os.kill(pids[busy[0]], signal.SIGKILL)
                killed.append(busy[0])
                return
            time.sleep(0.05)

    t = threading.Thread(target=killer, daemon=True)
    t.start()
    arrivals: list[str] = []
    res = run_sweep(spec, tmp_path / "kill", executor=DaskExecutor(client=client),
                    on_result=lambda p, r: arrivals.append(p.key))
    t.join(timeout=5)
    assert killed, "no worker was busy to kill"
    assert sorted(arrivals) == sorted(p.key for p in res.points)  # each point once
    with sqlite3.connect(tmp_path / "kill" / "sweep.sqlite") as db:
        assert db.execute("SELECT COUNT(*) FROM points").fetchone()[0] == 6
    assert sweep_table(spec, res.points, res.results) == \
        sweep_table(spec, res_local.points, res_local.results)


def test_cli_interrupt_and_resume_without_rerunning_finished_points(tmp_path):
    f = write_sweep(tmp_path)
    out = tmp_path / "out"
    cmd = _sweep_cmd(f, out)
    proc = start_in_child(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    db = out / "sweep.sqlite"
    deadline = time.time() + 300
    n = 0
    while time.time() < deadline and proc.poll() is None:
        if db.exists():
            try:
                with sqlite3.connect(db) as con:
                    n = con.execute("SELECT COUNT(*) FROM points").fetchone()[0]
            except sqlite3.OperationalError:
                n = 0
            if n >= 2:
                break
        time.sleep(0.2)
    assert n >= 2, proc.communicate()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "run the same command again to resume" in err
    with sqlite3.connect(db) as con:
        first = dict(con.execute("SELECT key, finished FROM points"))
    assert 2 <= len(first) < 6
    # The partial outputs hold the finished points, the others as not run.
    partial = json.loads((out / "sweep.json").read_text())
    assert sum("error" not in p for p in partial["points"]) == len(first)
    assert sum(p.get("error") == "not run" for p in partial["points"]) == 6 - len(first)
    res = run_in_process(cmd)
    assert res.code == 0, res.stderr
    assert f"{6 - len(first)} run now, {len(first)} already done" in res.stdout
    with sqlite3.connect(db) as con:
        rows = con.execute("SELECT key, finished, session FROM points").fetchall()
    assert len(rows) == 6
    for key, finished, session in rows:
        if key in first:  # not run again
            assert finished == first[key] and session == 1
        else:
            assert session == 2
    doc = json.loads((out / "sweep.json").read_text())
    assert len(doc["points"]) == 6 and all("error" not in p for p in doc["points"])


def _sweep_cmd(f, out):
    return ["sweep", f, "--out", out, "--workers", "1", "--no-progress"]


def _wait_for_points(db, n, proc):
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None:
        if db.exists():
            try:
                with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as con:
                    if con.execute("SELECT COUNT(*) FROM points").fetchone()[0] >= n:
                        return
            except sqlite3.OperationalError:
                pass
        time.sleep(0.1)
    raise AssertionError(f"fewer than {n} points stored (exit {proc.poll()})")


@pytest.mark.slow  # a 6-point sweep; the killed sweep's lock test stays
def test_a_second_sweep_on_the_same_folder_is_refused(tmp_path):
    """Two `rvmsim sweep` processes on one folder: the second (and a --force one) exits 2
    naming the first's PID and writes nothing: the first stores every point once, in its
    own session, as an undisturbed sweep does."""
    f = write_sweep(tmp_path, SWEEP.replace("budget: 200", "budget: 400"))
    out = tmp_path / "out"
    first = start_in_child(_sweep_cmd(f, out), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        _wait_for_points(out / "sweep.sqlite", 1, first)
        others = [run_in_process(_sweep_cmd(f, out) + extra) for extra in ([], ["--force"])]
        assert first.poll() is None, "the first sweep ended before the others were tried"
    finally:
        stdout, err = first.communicate(timeout=600)
    assert first.returncode == 0, err
    assert "6 design points, 6 run now, 0 already done" in stdout
    for res in others:
        lines = res.stderr.strip().splitlines()
        assert res.code == 2 and len(lines) == 1, res.stderr
        assert f"out is in use by process {first.pid}" in lines[0]
    with sqlite3.connect(out / "sweep.sqlite") as con:
        sessions = [s for (s,) in con.execute("SELECT session FROM points")]
        meta = dict(con.execute("SELECT key, value FROM meta"))
    assert sessions == [1] * 6 and json.loads(meta["sessions"]) == 1
    assert not (out / "sweep.pid").exists()


def test_a_killed_sweep_leaves_its_lock_to_the_next_run(tmp_path):
    f = write_sweep(tmp_path, SWEEP.replace("camera_height_m: [0.9, 1.0, 1.1]",
                                            "camera_height_m: [0.9, 1.0]"))
    out = tmp_path / "out"
    proc = start_in_child(_sweep_cmd(f, out))
    _wait_for_points(out / "sweep.sqlite", 1, proc)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert (out / "sweep.pid").read_text().split()[0] == str(proc.pid)  # stale, still there
    res = run_in_process(_sweep_cmd(f, out))
    assert res.code == 0, res.stderr
    assert "already done" in res.stdout and " 0 already done" not in res.stdout
    assert not (out / "sweep.pid").exists()


def test_changed_sweep_refuses_to_resume(tmp_path):
    f = write_sweep(tmp_path, SWEEP.replace("camera_height_m: [0.9, 1.0, 1.1]",
                                            "camera_height_m: [1.0]"))
    spec = load_sweep(f)
    run_sweep(spec, tmp_path / "o")
    f.write_text(f.read_text().replace("seed: 3", "seed: 4"))
    with pytest.raises(RvmsimError, match="settings or base scene changed"):
        run_sweep(load_sweep(f), tmp_path / "o")
    res = run_sweep(load_sweep(f), tmp_path / "o", force=True)
    assert res.ran == 2


def test_dask_sweep_interrupted_then_resumed(local_run, cluster, tmp_path):
    """Stop a Dask sweep after two points (as Ctrl-C would), resume it: only the other four
    run, and the table is the local one."""
    spec, res_local = local_run
    _, client = cluster
    seen: list[str] = []

    def stop_after_two(point, result):
        seen.append(point.key)
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, tmp_path / "d", executor=DaskExecutor(client=client),
                  on_result=stop_after_two)
    with sqlite3.connect(tmp_path / "d" / "sweep.sqlite") as db:
        assert {k for (k,) in db.execute("SELECT key FROM points")} == set(seen)
    partial = stored_sweep(spec, tmp_path / "d")
    assert set(partial.results) == set(seen) and partial.ran == 0
    res = run_sweep(spec, tmp_path / "d", executor=DaskExecutor(client=client))
    assert res.ran == 4
    with sqlite3.connect(tmp_path / "d" / "sweep.sqlite") as db:
        sessions = dict(db.execute("SELECT key, session FROM points"))
    assert all(sessions[k] == 1 for k in seen) and sum(v == 2 for v in sessions.values()) == 4
    assert sweep_table(spec, res.points, res.results) == \
        sweep_table(spec, res_local.points, res_local.results)
