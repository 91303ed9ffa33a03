"""Bad run and sweep folders (issue #14, groups 4 and 5 and data safety): every command that
reads a run folder (status, select, report, tune --resume) or writes one (tune --out,
--force; sweep --out) fails with one line naming the file and key, and leaves the stored
run or sweep byte-identical."""

from __future__ import annotations

import json
import shutil
import sqlite3
from pathlib import Path

import pytest

from .conftest import SMALL_SCENE
from ..cli_runner import run_in_process
from .harness import Case, check_case

DB = "run/run.sqlite"
RUN_JSON = "run/run.json"

SWEEP_FILE = "sweep.yaml"
SWEEP = f"""\
name: tiny
base_scene: {SMALL_SCENE}
axes:
  camera_height_m: [0.9, 1.0]
tune:
  strategy: random
  budget: 20
  seed: 1
  config: {{output: {{size: [160, 90]}}}}
  recheck: {{rounds: 0}}
robustness: {{samples: 0}}
"""
SWEEP_DB = "sw/sweep.sqlite"


# ---------------------------------------------------------------------------- setups
def _sql(db: str, *statements: tuple[str, tuple]):
    def setup(folder: Path) -> None:
        con = sqlite3.connect(folder / db)
        with con:
            for sql, args in statements:
                con.execute(sql, args)
        con.close()
    return setup


def _bytes(path: str, data: bytes):
    def setup(folder: Path) -> None:
        (folder / path).write_bytes(data)
    return setup


def _truncate(path: str, keep: float = 0.5):
    def setup(folder: Path) -> None:
        p = folder / path
        p.write_bytes(p.read_bytes()[:int(p.stat().st_size * keep)])
    return setup


def _text(path: str, text: str):
    def setup(folder: Path) -> None:
        (folder / path).write_text(text)
    return setup


def _meta(db: str, key: str, value: str):
    """Set the meta ``key`` to the raw text ``value`` (JSON or not)."""
    return _sql(db, ("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)", (key, value)))


def _trials(column: str, value):
    return _sql(DB, (f"UPDATE trials SET {column} = ?", (value,)))


def _legacy(run_json=None, drop_run_json: bool = False):
    """Turn run/ into a run of rvmsim 0.1: settings in run.json only (``run_json``: a
    replacement text for it), the store's meta only strategy, total and a status text."""
    def setup(folder: Path) -> None:
        con = sqlite3.connect(folder / DB)
        with con:
            con.execute("DELETE FROM meta WHERE key NOT IN ('strategy', 'total', 'status')")
        con.close()
        if drop_run_json:
            (folder / RUN_JSON).unlink()
        elif run_json is not None:
            (folder / RUN_JSON).write_text(run_json)
    return setup


def _legacy_json(edit):
    def setup(folder: Path) -> None:
        doc = json.loads((folder / RUN_JSON).read_text())
        _legacy(json.dumps(edit(doc)))(folder)
    return setup


def _params_edit(edit):
    """Every trial's params JSON changed by ``edit(dict) -> dict``."""
    def setup(folder: Path) -> None:
        con = sqlite3.connect(folder / DB)
        rows = con.execute("SELECT idx, params FROM trials").fetchall()
        with con:
            con.executemany("UPDATE trials SET params = ? WHERE idx = ?",
                            [(json.dumps(edit(json.loads(p))), i) for i, p in rows])
        con.close()
    return setup


def _drop(key):
    return lambda d: {k: v for k, v in d.items() if k != key}


def _settings_edit(key, value):
    """The stored settings' ``key`` set to JSON ``value`` (None: deleted)."""
    if value is None:
        return _sql(DB, ("DELETE FROM meta WHERE key = ?", (key,)))
    return _meta(DB, key, json.dumps(value))


def _both(*setups):
    def setup(folder: Path) -> None:
        for s in setups:
            s(folder)
    return setup


JUNK = bytes(range(256)) * 40
TUNE_NEW = ("tune", SMALL_SCENE, "--strategy", "random", "--budget", "10", "--workers", "1",
            "--no-progress")
FORCE = (*TUNE_NEW, "--out", "run", "--force")
RESUME = ("tune", "--resume", "run", "--workers", "1", "--no-progress")
K = ("run",)

# ---------------------------------------------------------------------------- run folders
RUN_CASES = [
    # status: junk, truncated, empty and wrong-schema stores, corrupt rows
    Case("status-junk-db", ("status", "run"), ("run.sqlite",), _bytes(DB, JUNK), K),
    Case("status-text-db", ("status", "run"), ("run.sqlite",), _bytes(DB, b"hello\n"), K),
    Case("status-truncated-db", ("status", "run"), ("run.sqlite",), _truncate(DB), K),
    Case("status-header-only-db", ("status", "run"), ("run.sqlite",), _truncate(DB, 0.02), K),
    Case("status-zero-byte-db", ("status", "run"), ("run.sqlite", "meta"), _bytes(DB, b""), K),
    Case("status-no-trials-table", ("status", "run"), ("run.sqlite", "trials"),
         _sql(DB, ("DROP TABLE trials", ())), K),
    Case("status-no-meta-table", ("status", "run"), ("run.sqlite", "meta"),
         _sql(DB, ("DROP TABLE meta", ())), K),
    Case("status-wrong-schema", ("status", "run"), ("run.sqlite",),
         _sql(DB, ("DROP TABLE trials", ()), ("CREATE TABLE trials (x TEXT)", ())), K),
    Case("status-meta-not-json", ("status", "run"), ("run.sqlite", "meta", "status"),
         _meta(DB, "status", "{running"), K),
    Case("status-unknown-status", ("status", "run"), ("run.sqlite", "status", "paused"),
         _meta(DB, "status", '"paused"'), K),
    Case("status-total-not-a-number", ("status", "run"), ("run.sqlite", "total"),
         _meta(DB, "total", '"lots"'), K),
    Case("status-score-not-a-number", ("status", "run"), ("run.sqlite", "trials", "score"),
         _trials("score", "high"), K),
    Case("status-ec-junk", ("status", "run"), ("run.sqlite", "trials", "ec"),
         _trials("ec", "[[["), K),
    Case("status-params-junk", ("status", "run"), ("run.sqlite", "trials", "params"),
         _trials("params", "not json"), K),
    # select
    Case("select-junk-db", ("select", "run"), ("run.sqlite",), _bytes(DB, JUNK), K),
    Case("select-truncated-db", ("select", "run"), ("run.sqlite",), _truncate(DB), K),
    Case("select-zero-byte-db", ("select", "run"), ("run.sqlite",), _bytes(DB, b""), K),
    Case("select-no-trials-table", ("select", "run"), ("run.sqlite", "trials"),
         _sql(DB, ("DROP TABLE trials", ())), K),
    Case("select-params-junk", ("select", "run"), ("run.sqlite", "trials", "params"),
         _trials("params", "{{"), K),
    Case("select-params-a-list", ("select", "run"), ("run.sqlite", "trials", "params"),
         _trials("params", "[1, 2]"), K),
    Case("select-params-missing-zoom", ("select", "run"), ("run.sqlite", "params"),
         _params_edit(_drop("zoom")), K),
    Case("select-params-not-a-number", ("select", "run"), ("run.sqlite", "params"),
         _params_edit(lambda d: {**d, "zoom": "big"}), K),
    Case("select-params-out-of-range", ("select", "run"), ("run.sqlite", "params", "fov"),
         _params_edit(lambda d: {**d, "fov": -5.0}), K),
    Case("select-settings-bad-config", ("select", "run"), ("run.sqlite", "settings"),
         _settings_edit("config", {"top_m": "many"}), K),
    Case("select-settings-no-strategy", ("select", "run"), ("run.sqlite", "strategy"),
         _settings_edit("strategy", None), K),
    Case("select-newer-format", ("select", "run"), ("run.sqlite", "format"),
         _meta(DB, "format", "99"), K),
    Case("select-rank-beyond-the-run", ("select", "run", "--rank", "99"), ("run", "rank 99"),
         None, K),
    Case("select-legacy-junk-run-json", ("select", "run"), ("run.json",),
         _legacy("{{ not json"), K),
    Case("select-legacy-run-json-a-list", ("select", "run"), ("run.json",), _legacy("[1, 2]"), K),
    Case("select-legacy-run-json-no-scene", ("select", "run"), ("run.json", "scene"),
         _legacy_json(_drop("scene")), K),
    Case("select-legacy-no-run-json", ("select", "run"), ("run.json",),
         _legacy(drop_run_json=True), K),
    Case("select-output-dir-missing", ("select", "run", "--out", "no/such/dir/p.yaml"),
         ("p.yaml",), None, K),
    # report
    Case("report-junk-db", ("report", "run"), ("run.sqlite",), _bytes(DB, JUNK), K),
    Case("report-zero-byte-db", ("report", "run"), ("run.sqlite",), _bytes(DB, b""), K),
    Case("report-params-junk", ("report", "run"), ("run.sqlite", "params"),
         _trials("params", "zzz"), K),
    Case("report-legacy-junk-run-json", ("report", "run"), ("run.json",), _legacy("{"), K),
    # tune --resume
    Case("resume-junk-db", RESUME, ("run.sqlite",), _bytes(DB, JUNK), K),
    Case("resume-zero-byte-db", RESUME, ("run.sqlite",), _bytes(DB, b""), K),
    Case("resume-no-db", RESUME, ("run.sqlite",), lambda d: (d / DB).unlink(), K),
    Case("resume-params-junk", RESUME, ("run.sqlite", "trials", "params"),
         _trials("params", "??"), K),
    Case("resume-unknown-status", RESUME, ("run.sqlite", "status"),
         _meta(DB, "status", '"paused"'), K),
    Case("resume-settings-no-scene", RESUME, ("run.sqlite", "scene"),
         _settings_edit("scene", None), K),
    Case("resume-stored-seed-negative", RESUME, ("run.sqlite", "seed"),
         _settings_edit("seed", -1), K),
    Case("resume-scene-file-gone", RESUME, ("gone.yaml",),
         _settings_edit("scene", "/nonexistent/gone.yaml"), K),
    Case("resume-legacy-junk-run-json", RESUME, ("run.json",), _legacy("not json at all"), K),
    Case("resume-legacy-run-json-no-scene", RESUME, ("run.json", "scene"),
         _legacy_json(_drop("scene")), K),
    Case("resume-legacy-run-json-bad-seed", RESUME, ("run.json", "seed"),
         _legacy_json(lambda d: {**d, "seed": "one"}), K),
    Case("resume-legacy-no-run-json", RESUME, ("run.json",), _legacy(drop_run_json=True), K),
    # tune --out: a file, a run already there; --force with bad inputs keeps the old run
    Case("tune-out-is-a-file", (*TUNE_NEW, "--out", "f"), ("f", "folder"),
         _text("f", "not a folder\n")),
    Case("tune-out-holds-a-run", (*TUNE_NEW, "--out", "run"), ("run", "--force"), None, K),
    Case("force-junk-scene", FORCE, (SMALL_SCENE,), _text(SMALL_SCENE, "camera: [\n"), K),
    Case("force-empty-scene", FORCE, (SMALL_SCENE,), _text(SMALL_SCENE, ""), K),
    Case("force-missing-scene", (*FORCE[:1], "nope.yaml", *FORCE[2:]), ("nope.yaml",), None, K),
    Case("force-junk-criteria", (*FORCE, "--criteria", "c.yaml"), ("c.yaml",),
         _text("c.yaml", "ecs: {{{\n"), K),
    Case("force-junk-config", (*FORCE, "--config", "t.yaml"), ("t.yaml",),
         _text("t.yaml", "tuned: [nope_param]\n"), K),
    Case("force-negative-seed", (*FORCE, "--seed", "-1"), ("--seed", "4294967295"), None, K),
    Case("force-seed-beyond-range", (*FORCE, "--seed", str(2**32)), ("--seed", "4294967295"),
         None, K),
    Case("force-run-dir-is-a-file", (*TUNE_NEW, "--out", "run/run.json", "--force"),
         ("run.json", "folder"), None, K),
    # seeds (issue group 4): refused before a run starts
    Case("tune-negative-seed", (*TUNE_NEW, "--out", "new", "--seed", "-7"),
         ("--seed", "-7", "4294967295")),
    Case("tune-cmaes-seed-beyond-range",
         ("tune", SMALL_SCENE, "--strategy", "cmaes", "--budget", "10", "--workers", "1",
          "--no-progress", "--out", "new", "--seed", str(2**40)), ("--seed", "4294967295")),
]


@pytest.mark.parametrize("case", RUN_CASES, ids=[c.id for c in RUN_CASES])
def test_bad_run_folder(case, case_dir):
    check_case(case, case_dir)
    assert not (case_dir / "new").exists()  # a refused new run leaves no folder behind


def test_there_are_enough_cases():
    assert len(RUN_CASES) + len(SWEEP_CASES) >= 40
    assert len({c.id for c in RUN_CASES + SWEEP_CASES}) == len(RUN_CASES) + len(SWEEP_CASES)


# ---------------------------------------------------------------------------- sweep folders
@pytest.fixture(scope="module")
def finished_sweep(tmp_path_factory, finished_run) -> Path:
    """A finished two-point sweep of the small scene (folder ``sw``)."""
    folder = tmp_path_factory.mktemp("finished_sweep")
    shutil.copy(finished_run / SMALL_SCENE, folder / SMALL_SCENE)
    (folder / SWEEP_FILE).write_text(SWEEP)
    out = run_in_process(["sweep", SWEEP_FILE, "--out", "sw", "--workers", "1",
                          "--no-progress"], cwd=folder)
    assert out.code == 0, out.stderr
    return folder


@pytest.fixture
def sweep_dir(tmp_path, finished_sweep) -> Path:
    for name in (SMALL_SCENE, SWEEP_FILE):
        shutil.copy(finished_sweep / name, tmp_path / name)
    shutil.copytree(finished_sweep / "sw", tmp_path / "sw")
    return tmp_path


SWEEP_RUN = ("sweep", SWEEP_FILE, "--out", "sw", "--workers", "1", "--no-progress")
KS = ("sw",)
SWEEP_CASES = [
    Case("sweep-junk-db", SWEEP_RUN, ("sweep.sqlite",), _bytes(SWEEP_DB, JUNK), KS),
    Case("sweep-truncated-db", SWEEP_RUN, ("sweep.sqlite",), _truncate(SWEEP_DB), KS),
    Case("sweep-zero-byte-db", SWEEP_RUN, ("sweep.sqlite", "meta"), _bytes(SWEEP_DB, b""), KS),
    Case("sweep-no-points-table", SWEEP_RUN, ("sweep.sqlite", "points"),
         _sql(SWEEP_DB, ("DROP TABLE points", ())), KS),
    Case("sweep-result-junk", SWEEP_RUN, ("sweep.sqlite", "points", "result"),
         _sql(SWEEP_DB, ("UPDATE points SET result = 'x{'", ())), KS),
    Case("sweep-result-not-an-object", SWEEP_RUN, ("sweep.sqlite", "result"),
         _sql(SWEEP_DB, ("UPDATE points SET result = '[1]'", ())), KS),
    Case("sweep-result-no-score", SWEEP_RUN, ("sweep.sqlite", "result", "score"),
         _sql(SWEEP_DB, ("UPDATE points SET result = '{\"passed\": true}'", ())), KS),
    Case("sweep-meta-not-json", SWEEP_RUN, ("sweep.sqlite", "meta", "fingerprint"),
         _meta(SWEEP_DB, "fingerprint", "{"), KS),
    Case("sweep-sessions-not-a-number", SWEEP_RUN, ("sweep.sqlite", "sessions"),
         _meta(SWEEP_DB, "sessions", '"x"'), KS),
    Case("sweep-of-another-sweep", SWEEP_RUN, ("sw", "--force"),
         _meta(SWEEP_DB, "fingerprint", '"another"'), KS),
    Case("sweep-out-is-a-file", (*SWEEP_RUN[:2], "--out", "f", *SWEEP_RUN[4:]), ("f", "folder"),
         _text("f", "x\n")),
    Case("sweep-force-junk-sweep-file", (*SWEEP_RUN, "--force"), (SWEEP_FILE,),
         _text(SWEEP_FILE, "axes: [[[\n"), KS),
    Case("sweep-force-out-is-a-file", ("sweep", SWEEP_FILE, "--out", "sw/sweep.csv", "--force",
                                       "--workers", "1", "--no-progress"),
         ("sweep.csv", "folder"), None, KS),
]


@pytest.mark.parametrize("case", SWEEP_CASES, ids=[c.id for c in SWEEP_CASES])
def test_bad_sweep_folder(case, sweep_dir):
    check_case(case, sweep_dir)
