"""Shared pieces of the tuning tests: a small real problem, a search into a store, and run
folders in the layout of rvmsim 0.1 (what ``tune`` wrote before the run model)."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

from rvmsim.criteria import default_criteria
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.isp import OutputSpec
from rvmsim.tune import run_search, score_vectors
from rvmsim.search import SearchSpace, Strategy, default_space
from rvmsim.runs import RunStore

from ..conftest import small_render


def small_problem(letter: str = "a") -> tuple[CandidateEvaluator, SearchSpace]:
    """An evaluator on a test-scale render and a seven-parameter space."""
    img = small_render(letter)
    ev = CandidateEvaluator(img.labels, OutputSpec(320, 180), default_criteria())
    space = default_space(img.camera, ("fov", "rad", "v_shift", "zoom", "adv_v_shift",
                                        "adv_h_scale", "adv_v_scale"))
    return ev, space


def search(strategy: Strategy, ev: CandidateEvaluator, tmp_path: Path, name: str):
    """Run ``strategy`` into a new store; (outcome, every trial)."""
    store = RunStore(tmp_path / f"{name}.sqlite")
    out = run_search(strategy, lambda xs: score_vectors(ev, strategy.space, xs), store)
    trials = store.trials()
    store.close()
    return out, trials


#: rvmsim 0.1's run store schema, as its tune.py created it (meta first, then trials).
LEGACY_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS trials (
    idx INTEGER PRIMARY KEY,
    stage TEXT NOT NULL,
    params TEXT NOT NULL,
    score REAL NOT NULL,
    objective REAL NOT NULL,
    passed INTEGER NOT NULL,
    ec TEXT NOT NULL
);
CREATE INDEX IF NOT EXISTS trials_score ON trials (score DESC, idx);
"""


def make_legacy_run(run: Path, dest: Path, *, status: str = "done", keep: int | None = None,
                    run_json: bool = True) -> Path:
    """Copy the run folder ``run`` (written by this version) into ``dest`` in rvmsim 0.1's
    layout: settings in run.json only (its config dump with ``random.sigma0``, which 0.1
    had), the store's meta holding only ``strategy``, ``total`` and a free-text ``status``;
    ``keep``: only the first that many trials; ``run_json``: False leaves run.json out."""
    dest.mkdir(parents=True)
    src = sqlite3.connect(run / "run.sqlite")
    meta = {k: json.loads(v) for k, v in src.execute("SELECT key, value FROM meta")}
    rows = src.execute("SELECT idx, stage, params, score, objective, passed, ec FROM trials "
                       "ORDER BY idx").fetchall()
    src.close()
    if keep is not None:
        rows = rows[:keep]
    db = sqlite3.connect(dest / "run.sqlite")
    db.execute("PRAGMA journal_mode=WAL")
    db.executescript(LEGACY_SCHEMA)
    with db:
        db.executemany("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)",
                       [(k, json.dumps(v)) for k, v in (("strategy", meta["strategy"]),
                                                        ("total", meta["total"]),
                                                        ("status", status))])
        db.executemany("INSERT OR REPLACE INTO trials (idx, stage, params, score, objective, "
                       "passed, ec) VALUES (?, ?, ?, ?, ?, ?, ?)", rows)
    db.close()
    if run_json:
        config = dict(meta["config"])
        config["random"] = {**config["random"], "sigma0": 0.3}
        doc = {k: meta[k] for k in ("scene", "scene_key", "vehicle", "strategy", "seed",
                                    "budget", "criteria_file")}
        (dest / "run.json").write_text(json.dumps({**doc, "config": config}, indent=2))
    return dest


def wait_for_trials(db: Path, n: int, timeout_s: float = 300.0) -> None:
    """Wait until the run store ``db`` holds at least ``n`` trials (or the time is up)."""
    import time

    deadline = time.time() + timeout_s
    while time.time() < deadline:
        if db.exists():
            try:
                if sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0] >= n:
                    return
            except sqlite3.Error:
                pass  # not made yet
        time.sleep(0.02)


def stored_trials(run: Path) -> tuple[list[tuple], list[tuple]]:
    """Every stored trial (idx, params, score, objective, passed, ec) and member row of the
    run folder ``run``, in order: what an unbroken and a resumed run must share."""
    con = sqlite3.connect(run / "run.sqlite")
    trials = con.execute("SELECT idx, params, score, objective, passed, ec FROM trials "
                         "ORDER BY idx").fetchall()
    has = con.execute("SELECT 1 FROM sqlite_master WHERE name = 'members'").fetchone()
    members = con.execute("SELECT * FROM members ORDER BY idx, member").fetchall() if has else []
    con.close()
    return trials, members
