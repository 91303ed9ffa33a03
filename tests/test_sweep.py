"""Feasibility sweeps: real renders and real CMA-ES runs per design point, on local processes
and on a Dask LocalCluster started on loopback; a worker killed mid-sweep; Ctrl-C + resume."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from rvmsim.batch import sweep as S
from rvmsim.errors import RvmsimError
from rvmsim.batch import DaskExecutor, LocalExecutor

from .conftest import SCENES

distributed = pytest.importorskip("distributed")

SWEEP = """\
name: tiny mount study
base_scene: base.yaml
axes:
  camera_height_m: [0.9, 1.0, 1.1]
  pitch_deg: [28, 34]
tune:
  strategy: cmaes
  budget: 200
  seed: 3
  config: {output: {size: [320, 180]}}
"""


def _small_scene_text(letter: str) -> str:
    """Bundled vehicle ``letter`` at 320 × 240, its lens scaled to match."""
    d = yaml.safe_load((SCENES / f"vehicle_{letter}.yaml").read_text())
    d["camera"]["image_size"] = [320, 240]
    d["camera"]["intrinsics"] = {"fx": 97.5, "fy": 97.5}
    return yaml.safe_dump(d, sort_keys=False)


def _write_sweep(folder: Path, text: str = SWEEP) -> Path:
    """Vehicle A at 320 × 240 as the base scene, and a sweep."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "base.yaml").write_text(_small_scene_text("a"))
    (folder / "sweep.yaml").write_text(text)
    return folder / "sweep.yaml"


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory) -> Path:
    return _write_sweep(tmp_path_factory.mktemp("sweep"))


@pytest.fixture(scope="module")
def local_run(sweep_file):
    spec = S.load_sweep(sweep_file)
    res = S.run_sweep(spec, sweep_file.parent / "local", executor=LocalExecutor(2))
    return spec, res


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=":0") as c, \
            distributed.Client(c) as client:
        yield c, client


# ---------------------------------------------------------------------------- the file
def test_design_points_and_scenes(sweep_file):
    spec = S.load_sweep(sweep_file)
    pts = S.design_points(spec)
    assert [dict(p.values) for p in pts[:3]] == [
        {"camera_height_m": 0.9, "pitch_deg": 28}, {"camera_height_m": 0.9, "pitch_deg": 34},
        {"camera_height_m": 1.0, "pitch_deg": 28}]
    doc, config = S.point_scene_doc(spec, pts[3].values)
    assert doc["camera"]["mount"]["position"][1] == -1.0
    assert doc["camera"]["mount"]["pitch_deg"] == 34.0
    assert config == {"output": {"size": [320, 180]}}
    assert len({p.key for p in pts}) == 6


def test_ranges_paths_and_named_axes(tmp_path):
    f = _write_sweep(tmp_path, SWEEP.replace(
        "  pitch_deg: [28, 34]\n",
        "  pitch_deg: {start: 25, stop: 31, step: 3}\n  vehicle.bumper.top: [0.7, 0.8]\n"
        "  focal_length_px: [90.0]\n  output_size: [[320, 180]]\n"))
    spec = S.load_sweep(f)
    assert dict(spec.axes)["pitch_deg"] == (25.0, 28.0, 31.0)
    pts = S.design_points(spec)
    assert len(pts) == 3 * 3 * 2
    doc, config = S.point_scene_doc(spec, pts[-1].values)
    assert doc["vehicle"]["bumper"]["top"] == 0.8
    assert doc["camera"]["intrinsics"]["fx"] == 90.0 and doc["camera"]["intrinsics"]["fy"] == 90.0
    assert config["output"]["size"] == [320, 180]


@pytest.mark.parametrize("edit, message", [
    (("  pitch_deg: [28, 34]", "  tilt: [28, 34]"), "axes.tilt: unknown axis"),
    (("  pitch_deg: [28, 34]", "  vehicle.spoiler.top: [1]"), "axes.vehicle.spoiler.top: the base "
                                                               "scene has no key"),
    (("  pitch_deg: [28, 34]", "  pitch_deg: [28, 120]"), "pitch_deg=120: "),
    (("strategy: cmaes", "strategy: annealing"), "tune.strategy: 'annealing' is not one of"),
    (("base_scene: base.yaml", "base_scene: nothere.yaml"), "nothere.yaml"),
    (("  pitch_deg: [28, 34]", "  pitch_deg: {start: 1, stop: 2}"), "give a range either num or step"),
])
def test_bad_sweep_files_are_one_line_errors(tmp_path, edit, message):
    f = _write_sweep(tmp_path, SWEEP.replace(*edit))
    res = subprocess.run([sys.executable, "-m", "rvmsim", "sweep", str(f), "--out",
                          str(tmp_path / "o"), "--no-progress"], capture_output=True, text=True,
                         timeout=300)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.stderr, res.stderr
    assert message in lines[0] and str(f) in lines[0]


# ---------------------------------------------------------------------------- results
def test_local_sweep_table_map_and_sensitivity(local_run):
    spec, res = local_run
    assert res.ran == 6 and len(res.results) == 6
    header, rows = S.sweep_table(spec, res.points, res.results)
    assert [r[0] for r in rows] == list(range(6))
    assert header[1:3] == ["camera_height_m", "pitch_deg"]
    for p, row in zip(res.points, rows):
        r = res.results[p.key]
        assert "error" not in r, r
        assert row[header.index("ec_score")] == r["score"]
        assert 0.0 <= r["score"] <= 1.0 and r["evaluations"] == 200
        # The limiting EC is a failing one with the lowest score (None when all pass).
        failing = {e: v["score"] for e, v in r["ecs"].items() if not v["passed"]}
        assert r["limiting_ec"] == (min(failing, key=failing.get) if failing else None)
        # Sensitivity: every tuned parameter, probed at ±2/5/10 % of its range; the optimum
        # is the point's best score.
        sens = r["sensitivity"]
        assert sens["optimum"] == pytest.approx(r["score"], rel=1e-9)
        assert set(sens["params"]) == set(r["tuned"])
    written = S.write_sweep_outputs(res)
    names = {p.name for p in written}
    assert {"sweep.csv", "sweep.json", "feasibility.png", "sweep.html"} <= names
    img = cv2.imread(str(res.out_dir / "feasibility.png"))
    assert img is not None and img.std() > 10
    csv_lines = (res.out_dir / "sweep.csv").read_text().splitlines()
    assert len(csv_lines) == 7
    html = (res.out_dir / "sweep.html").read_text()
    assert html.count("data:image/png;base64,") >= 1 and "Feasibility map" in html
    # Point numbers 0 and 1 are not coloured as pass/fail (1 == True in Python).
    assert '<tr><td class="">0</td>' in html and '<tr><td class="">1</td>' in html
    assert html.count('class="fail">FAIL</td>') + html.count('class="pass">pass</td>') == 6 * 11


def test_map_takes_the_best_over_other_axes_and_outlines_passing_cells():
    """The feasibility grid from known results: best over a third axis, pass flags and the
    limiting EC per cell."""
    spec = S.SweepSpec("m", "m.yaml", Path("b.yaml"), {}, (("a", (1, 2)), ("b", (10, 20)),
                                                          ("c", ("x", "y"))),
                       "cmaes", 10, 0, {}, None, ("a", "b"), False)
    pts = S.design_points(spec)
    results = {}
    for p in pts:
        v = dict(p.values)
        score = 0.1 * v["a"] + 0.01 * v["b"] / 10 + (0.5 if v["c"] == "y" else 0.0)
        passed = v["a"] == 2 and v["c"] == "y"
        results[p.key] = {"score": score, "passed": passed, "limiting_ec": None if passed else "2-1"}
    xa, ya, xs, ys, score, passed, limiting, others = S._map_grid(spec, pts, results)
    assert (xa, ya, others) == ("a", "b", ["c"])
    np.testing.assert_allclose(score, [[0.61, 0.71], [0.62, 0.72]])
    assert passed.tolist() == [[False, True], [False, True]]
    assert limiting.tolist() == [["2-1", ""], ["2-1", ""]]
    png = S.feasibility_png(spec, pts, results)
    assert cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR) is not None


# ---------------------------------------------------------------------------- executors
def test_dask_cluster_gives_the_same_table(local_run, cluster, tmp_path):
    spec, res_local = local_run
    _, client = cluster
    res = S.run_sweep(spec, tmp_path / "dask", executor=DaskExecutor(client=client))
    assert res.ran == 6
    assert S.sweep_table(spec, res.points, res.results) == \
        S.sweep_table(spec, res_local.points, res_local.results)


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
    res = S.run_sweep(spec, tmp_path / "kill", executor=DaskExecutor(client=client),
                      on_result=lambda p, r: arrivals.append(p.key))
    t.join(timeout=5)
    assert killed, "no worker was busy to kill"
    assert sorted(arrivals) == sorted(p.key for p in res.points)  # each point once
    with sqlite3.connect(tmp_path / "kill" / "sweep.sqlite") as db:
        assert db.execute("SELECT COUNT(*) FROM points").fetchone()[0] == 6
    assert S.sweep_table(spec, res.points, res.results) == \
        S.sweep_table(spec, res_local.points, res_local.results)


def test_cli_interrupt_and_resume_without_rerunning_finished_points(tmp_path):
    f = _write_sweep(tmp_path)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "rvmsim", "sweep", str(f), "--out", str(out), "--workers", "1",
           "--no-progress"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
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
    with sqlite3.connect(db) as con:
        first = dict(con.execute("SELECT key, finished FROM points"))
    assert 2 <= len(first) < 6
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
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


def test_changed_sweep_refuses_to_resume(tmp_path):
    f = _write_sweep(tmp_path, SWEEP.replace("camera_height_m: [0.9, 1.0, 1.1]",
                                             "camera_height_m: [1.0]"))
    spec = S.load_sweep(f)
    S.run_sweep(spec, tmp_path / "o")
    f.write_text(f.read_text().replace("seed: 3", "seed: 4"))
    with pytest.raises(RvmsimError, match="settings or base scene changed"):
        S.run_sweep(S.load_sweep(f), tmp_path / "o")
    res = S.run_sweep(S.load_sweep(f), tmp_path / "o", force=True)
    assert res.ran == 2


def test_batch_on_the_dask_cluster_writes_normal_run_folders(cluster, tmp_path):
    """`rvmsim batch --scheduler`: one task per scene on the cluster; the run folders land
    here with this machine's scene path and fingerprint, so status and report work on them."""
    c, _ = cluster
    scenes = []
    for letter in "ab":
        p = tmp_path / f"small_{letter}.yaml"
        p.write_text(_small_scene_text(letter))
        scenes.append(p)
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text("output: {size: [320, 180]}\n")
    out = tmp_path / "runs"
    res = subprocess.run([sys.executable, "-m", "rvmsim", "batch", *map(str, scenes), "--out",
                          str(out), "--strategy", "cmaes", "--budget", "150", "--config",
                          str(cfg), "--scheduler", c.scheduler_address, "--no-progress"],
                         capture_output=True, text=True, timeout=600)
    assert res.returncode in (0, 1), res.stderr  # 1: some vehicle failed an EC, not an error
    rows = json.loads((out / "summary.json").read_text())
    assert [Path(r["scene"]).name for r in rows if "error" not in r] and len(rows) == 2
    for p in scenes:
        run = out / p.stem
        meta = json.loads((run / "run.json").read_text())
        assert meta["scene"] == str(p.resolve())
        row = next(r for r in rows if Path(r["scene"]).name == p.name)
        with sqlite3.connect(run / "run.sqlite") as db:
            n = db.execute("SELECT COUNT(*) FROM trials").fetchone()[0]
        assert n == row["evaluations"] and 150 <= n < 150 + 12  # CMA-ES ends a generation
        assert (run / "best" / "ec.json").is_file()
        rep = subprocess.run([sys.executable, "-m", "rvmsim", "report", str(run)],
                             capture_output=True, text=True, timeout=300)
        assert rep.returncode == 0, rep.stderr
        assert "changed since" not in (run / "report.html").read_text()


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
        S.run_sweep(spec, tmp_path / "d", executor=DaskExecutor(client=client),
                    on_result=stop_after_two)
    with sqlite3.connect(tmp_path / "d" / "sweep.sqlite") as db:
        assert {k for (k,) in db.execute("SELECT key FROM points")} == set(seen)
    res = S.run_sweep(spec, tmp_path / "d", executor=DaskExecutor(client=client))
    assert res.ran == 4
    with sqlite3.connect(tmp_path / "d" / "sweep.sqlite") as db:
        sessions = dict(db.execute("SELECT key, session FROM points"))
    assert all(sessions[k] == 1 for k in seen) and sum(v == 2 for v in sessions.values()) == 4
    assert S.sweep_table(spec, res.points, res.results) == \
        S.sweep_table(spec, res_local.points, res_local.results)
