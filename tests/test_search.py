"""Tuning: grid construction, fine-range narrowing, determinism, resume after kill -9, and
CMA-ES against random search on a real rendered scene."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time

import numpy as np
import pytest
import yaml

from rvmsim.criteria import default_criteria
from rvmsim.criteria import CandidateEvaluator
from rvmsim.isp import OutputSpec
from rvmsim.tune import (
    CmaEs,
    GridToRandom,
    ParamRange,
    RandomSearch,
    SearchSpace,
    default_space,
    run_search,
    score_vectors,
)
from rvmsim.tune import RunStore

from .conftest import SCENES, small_render


def test_param_grid_and_narrowing():
    r = ParamRange("zoom", init=0.7, low=0.25, high=1.45, step=0.3)
    np.testing.assert_allclose(r.grid(), [0.4, 0.7, 1.0])
    assert list(ParamRange("zoom", 0.3, 0.25, 1.45, 0.3).grid()) == pytest.approx([0.3, 0.6])
    assert len(ParamRange("fov", 180, 150, 210, 10, points=5).grid()) == 5
    space = SearchSpace((ParamRange("fov", 180, 150, 210, 20),
                         ParamRange("zoom", 0.7, 0.25, 1.45, 0.3),
                         ParamRange("adv_v_shift", 0.0, -0.8, 0.8, 0.4)))
    grid = list(space.grid())
    assert len(grid) == space.grid_size() == 27
    np.testing.assert_allclose(grid[0], [160, 0.4, -0.4])   # last parameter varies fastest
    np.testing.assert_allclose(grid[1], [160, 0.4, 0.0])
    lo, hi = space.narrowed(np.array([160.0, 1.3, 0.7]))
    np.testing.assert_allclose(lo, [150.0, 1.0, 0.3])       # clipped to the range below…
    np.testing.assert_allclose(hi, [180.0, 1.45, 0.8])      # … and above
    with pytest.raises(ValueError, match="zoom"):
        ParamRange("zoom", 0.1, 0.25, 1.45, 0.3)


def test_default_space_fits_the_camera():
    cam = small_render("b").camera
    space = default_space(cam)
    assert space.names == ("fov", "rad", "h_shift", "v_shift", "zoom", "adv_h_shift",
                           "adv_v_shift", "adv_h_scale", "adv_v_scale")
    rad = {r.name: r for r in space.ranges}["rad"]
    assert rad.init == pytest.approx(cam.fx * np.pi / 2)
    h = {r.name: r for r in space.ranges}["h_shift"]
    assert h.init == pytest.approx(cam.cx - (cam.width - 1) / 2)
    assert space.grid_size() == 3 ** 9


def _small_problem(letter="a"):
    img = small_render(letter)
    ev = CandidateEvaluator(img.labels, OutputSpec(320, 180), default_criteria())
    space = default_space(img.camera, ("fov", "rad", "v_shift", "zoom", "adv_v_shift",
                                        "adv_h_scale", "adv_v_scale"))
    return ev, space


def _run(strategy, ev, tmp_path, name):
    store = RunStore(tmp_path / f"{name}.sqlite")
    out = run_search(strategy, lambda xs: score_vectors(ev, strategy.space, xs), store)
    trials = store.trials()
    store.close()
    return out, trials


def test_grid_to_random_follows_the_protocol(tmp_path):
    ev, space = _small_problem()
    small = SearchSpace(space.ranges[:3], space.base)  # 27 coarse points
    strat = GridToRandom(small, seed=3, top_n=2, trials=40, batch=16)
    out, trials = _run(strat, ev, tmp_path, "g")
    assert out.evaluated == 27 + 2 * 40 == len(trials)
    coarse = [t for t in trials if t.stage == "coarse"]
    assert len(coarse) == 27
    ranked = sorted(coarse, key=lambda t: (-t.score, -t.objective, t.idx))
    for n, seed in enumerate(ranked[:2], start=1):
        fine = [t for t in trials if t.stage == f"fine-{n}"]
        assert len(fine) == 40
        lo, hi = small.narrowed(small.vector(seed.params))
        xs = np.array([small.vector(t.params) for t in fine])
        assert np.all(xs >= lo - 1e-9) and np.all(xs <= hi + 1e-9)
        assert np.all(xs.std(axis=0) > 0)  # really random inside the narrowed range


def test_search_is_deterministic(tmp_path):
    ev, space = _small_problem()
    a = _run(CmaEs(space, seed=5, budget=60), ev, tmp_path, "a")[1]
    b = _run(CmaEs(space, seed=5, budget=60), ev, tmp_path, "b")[1]
    c = _run(CmaEs(space, seed=6, budget=60), ev, tmp_path, "c")[1]
    assert [(t.params, t.score) for t in a] == [(t.params, t.score) for t in b]
    assert [t.params for t in a] != [t.params for t in c]


def test_cmaes_beats_random_search_on_a_small_budget(tmp_path):
    ev, space = _small_problem()
    wins = 0
    for seed in (0, 1):
        cma = _run(CmaEs(space, seed=seed, budget=240), ev, tmp_path, f"c{seed}")[0].best
        rnd = _run(RandomSearch(space, seed=seed, budget=240), ev, tmp_path, f"r{seed}")[0].best
        wins += (cma.objective, cma.score) > (rnd.objective, rnd.score)
    assert wins == 2


def test_cmaes_explores_first_and_starts_from_the_best_point():
    """The first batch is the uniform exploration (a tenth of the budget); the first CMA-ES
    generation is centred on the best explored point; the budget is kept exactly."""
    space = default_space(small_render("a").camera)
    target = (space.low + space.high) / 2 + 0.3 * (space.high - space.low)

    def objective(x):  # a smooth bowl in the scaled space, best at `target`
        return -float(np.sum(((x - target) / (space.high - space.low)) ** 2))

    strat = CmaEs(space, seed=3, budget=1000, sigma0=0.05)
    gen = strat.batches()
    stage, xs = next(gen)
    assert stage == "explore" and len(xs) == 100
    objs = [objective(x) for x in xs]
    best = xs[int(np.argmax(objs))]
    stage, ys = gen.send([(0.0, o) for o in objs])
    assert stage == "cmaes-1"
    scaled = (np.mean(ys, axis=0) - best) / (space.high - space.low)
    assert np.all(np.abs(scaled) < 0.1)  # σ0 = 0.05 around the best explored point
    used = len(xs)
    while True:
        used += len(ys)
        try:
            stage, ys = gen.send([(0.0, objective(y)) for y in ys])
        except StopIteration:
            break
    assert used >= 1000 and used - 1000 < 20  # stops at the first generation past the budget


def test_resume_after_kill_gives_the_clean_result(tmp_path):
    """A real `rvmsim tune` subprocess is killed with SIGKILL mid-run, resumed, and ends with
    exactly the top-M of an uninterrupted run."""
    env = {**os.environ, "RVMSIM_CACHE": str(tmp_path / "cache")}
    cfg = tmp_path / "tune.yaml"
    cfg.write_text(yaml.safe_dump({
        "tuned": ["fov", "rad", "zoom", "adv_v_shift"], "batch": 40, "top_m": 5,
        "output": {"size": [320, 180]}, "grid_random": {"top_n": 2, "trials": 3000},
    }))
    scene = str(SCENES / "vehicle_d.yaml")

    def tune(out, *extra):
        return [sys.executable, "-m", "rvmsim", "tune", *extra, "--no-progress",
                "--workers", "1", *( [scene, "--out", str(out), "--config", str(cfg)]
                                     if "--resume" not in extra else [])]

    clean = subprocess.run(tune(tmp_path / "clean"), env=env, capture_output=True, text=True,
                           timeout=600)
    assert clean.returncode == 0, clean.stderr
    run = tmp_path / "killed"
    proc = subprocess.Popen(tune(run), env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
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
    assert 200 <= stored < 81 + 6000, stored  # killed mid-run, completed batches kept
    assert stored % 40 in (0, 81 % 40)  # whole batches only
    resumed = subprocess.run(tune(None, "--resume", str(run)), env=env, capture_output=True,
                             text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
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
    doc = json.loads((run / "best" / "ec.json").read_text())
    assert doc["ec_score"] == pytest.approx(top(run)[0][0][2])


def test_ctrl_c_stops_cleanly_and_resumes(tmp_path):
    env = {**os.environ, "RVMSIM_CACHE": str(tmp_path / "cache")}
    cfg = tmp_path / "tune.yaml"
    cfg.write_text(yaml.safe_dump({"tuned": ["fov", "rad", "zoom", "adv_v_shift"], "batch": 40,
                                   "output": {"size": [320, 180]},
                                   "grid_random": {"top_n": 2, "trials": 6000}}))
    run = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-m", "rvmsim", "tune", str(SCENES / "vehicle_a.yaml"), "--out",
         str(run), "--config", str(cfg), "--workers", "1", "--no-progress"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        # a shell's background job ignores SIGINT, and children inherit that: restore it
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
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
    assert store.meta()["status"].startswith("interrupted") and 120 <= store.count() < 12081
    store.close()
    res = subprocess.run([sys.executable, "-m", "rvmsim", "tune", "--resume", str(run),
                          "--workers", "1", "--no-progress"], env=env, capture_output=True,
                         text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    store = RunStore(db)
    assert store.count() == 81 + 12000 and store.meta()["status"] == "done"
    store.close()


def test_batches_split_into_shrinking_chunks_that_cover_them():
    """Worker chunks (guided self-scheduling) partition the batch in order and shrink, so
    the last ones are small."""
    from rvmsim.tune.loop import _chunks

    for n, workers in ((1024, 2), (1000, 3), (10, 2), (1, 4)):
        c = _chunks(n, workers)
        assert c[0][0] == 0 and c[-1][1] == n
        assert all(a[1] == b[0] for a, b in zip(c, c[1:]))
        sizes = [b - a for a, b in c]
        assert sizes == sorted(sizes, reverse=True) and sizes[-1] <= 8
    assert _chunks(0, 2) == []
