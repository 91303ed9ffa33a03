"""The writer lock of run folders (issue #14): real `rvmsim tune` processes.  A second writer
is refused while the first runs (which then ends as an undisturbed run does), a killed
writer's run reads as interrupted and its lock is taken over by --resume, --force with a bad
input leaves the old run as it was; and the lock itself, in this process."""

from __future__ import annotations

import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from rvmsim.errors import RvmsimError
from rvmsim.runs import RunStatus, RunStore, run_lock, status_lines
from rvmsim.storage import FolderLock, Writer

from ..bad_input.harness import folder_digest
from ..cli_runner import Outcome, run_in_process, start_in_child, tune_status
from rvmsim.testing.scenes import write_small_scene

SMALL_SCENE = "scene.yaml"
CONFIG = {"tuned": ["fov", "rad", "zoom", "adv_v_shift"], "batch": 40, "top_m": 5,
          "output": {"size": [160, 90]}}
#: Long enough for the other writers to be tried meanwhile (they run in this process, within
#: a second) and for a kill after 400 trials to fall mid-run.
BUDGET = 4000


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    """A folder with the small scene, a tuning config and a render cache of its own."""
    folder = tmp_path_factory.mktemp("lock")
    write_small_scene(folder, name=SMALL_SCENE)
    (folder / "tune.yaml").write_text(yaml.safe_dump(CONFIG))
    (folder / "cache").mkdir()
    return folder


def _env(work: Path) -> dict[str, str]:
    return {"RVMSIM_CACHE": str(work / "cache")}


def _tune_args(out: str, *extra: str) -> list[str]:
    return ["tune", SMALL_SCENE, "--out", out, "--config", "tune.yaml", "--strategy", "random",
            "--budget", str(BUDGET), "--seed", "5", "--workers", "1", "--no-progress", *extra]


def _rvmsim(work: Path, *args: str) -> Outcome:
    """A command in this process (the writer it meets is another process)."""
    return run_in_process(args, cwd=work, env=_env(work))


def _wait_for_trials(db: Path, n: int, proc: subprocess.Popen[str]) -> int:
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None:
        if db.exists():
            try:
                con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
                count = con.execute("SELECT COUNT(*) FROM trials").fetchone()[0]
                con.close()
            except sqlite3.Error:
                count = 0
            if count >= n:
                return count
        time.sleep(0.05)
    raise AssertionError(f"the writer stored fewer than {n} trials (exit {proc.poll()})")


def _result(run: Path):
    store = RunStore(run / "run.sqlite", readonly=True)
    try:
        return [(r.idx, r.params, r.score) for r in store.top(5)], store.count(), store.state()
    finally:
        store.close()


@pytest.fixture(scope="module")
def undisturbed(work) -> Path:
    res = _rvmsim(work, *_tune_args("undisturbed"))
    assert res.code == tune_status(work / "undisturbed"), res.stderr
    return work / "undisturbed"


def test_a_second_writer_is_refused_and_the_first_run_is_undisturbed(work, undisturbed):
    first = start_in_child(_tune_args("busy"), cwd=work, env=_env(work),
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        _wait_for_trials(work / "busy" / "run.sqlite", 40, first)
        second = [_rvmsim(work, *_tune_args("busy")),
                  _rvmsim(work, *_tune_args("busy", "--force")),
                  _rvmsim(work, "tune", "--resume", "busy", "--workers", "1", "--no-progress")]
        status = _rvmsim(work, "status", "busy")
        assert first.poll() is None, "the first run ended before the others were tried"
    finally:
        out, err = first.communicate(timeout=600)
    assert first.returncode == tune_status(work / "busy"), err
    for res in second:
        lines = res.stderr.strip().splitlines()
        assert res.code == 2 and len(lines) == 1, res.stderr
        assert f"busy is in use by process {first.pid}" in lines[0]
    assert status.code == 0 and ": running, strategy random" in status.stdout
    assert _result(work / "busy") == _result(undisturbed)
    assert not (work / "busy" / "run.pid").exists()  # the writer is gone: nothing recorded
    assert (work / "busy" / "top" / "rank_5.yaml").is_file()


def test_a_killed_writer_leaves_a_resumable_run_whose_lock_resume_takes_over(work, undisturbed):
    proc = start_in_child(_tune_args("killed"), cwd=work, env=_env(work))
    _wait_for_trials(work / "killed" / "run.sqlite", 400, proc)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    run = work / "killed"
    # the dead writer is still recorded beside the lock, and its status is still "running"
    assert Writer.parse((run / "run.pid").read_text()).pid == proc.pid
    assert _result(run)[2].status is RunStatus.RUNNING
    status = _rvmsim(work, "status", "killed")
    assert status.code == 0, status.stderr
    assert "killed: interrupted (resumable), strategy random" in status.stdout
    assert run_lock(run).writer() is None
    resumed = _rvmsim(work, "tune", "--resume", "killed", "--workers", "1", "--no-progress")
    assert resumed.code == tune_status(undisturbed), resumed.stderr
    assert "replayed" in resumed.stdout
    assert _result(run) == _result(undisturbed)
    assert _result(run)[2].status is RunStatus.DONE
    assert ": done, strategy random" in status_lines(run)[0]


def test_force_with_a_bad_scene_keeps_the_old_run(work, undisturbed, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(undisturbed, run)
    (run / "top" / "rank_11.yaml").write_text("# of an old run with top_m 11\n")
    before = folder_digest(run)
    (work / "bad.yaml").write_text("camera: {image_size: [320, 240]\n")
    res = _rvmsim(work, "tune", "bad.yaml", "--out", str(run), "--force", "--no-progress")
    assert res.code == 2 and "bad.yaml" in res.stderr, res.stderr
    assert folder_digest(run) == before
    # and with good inputs --force does replace it: a new run, none of the old one's files
    res = _rvmsim(work, "tune", SMALL_SCENE, "--out", str(run), "--force", "--strategy",
                  "random", "--budget", "30", "--workers", "1", "--no-progress")
    assert res.code == tune_status(run), res.stderr
    assert _result(run)[1] == 30
    assert {p.name for p in (run / "top").iterdir()} == \
        {f"rank_{k}.yaml" for k in range(1, 11)} | {"candidates.json"}  # the diverse top-M


# ---------------------------------------------------------------------------- in this process
def test_the_lock_admits_one_writer_and_records_it(tmp_path):
    a, b = FolderLock(tmp_path / "f", "run", "run"), FolderLock(tmp_path / "f", "run", "run")
    assert a.writer() is None
    with a:
        assert a.writer() == Writer.this_process()
        with pytest.raises(RvmsimError, match=f"is in use by process {os.getpid()}") as err:
            b.acquire()
        assert "\n" not in str(err.value)
    assert not a.pid_path.exists() and a.writer() is None
    with b:  # free again
        assert b.writer() is not None


def test_a_dead_or_reused_process_id_is_no_writer(tmp_path):
    lock = FolderLock(tmp_path, "sweep", "sweep")
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    me = Writer.this_process()
    lock.pid_path.write_text(Writer(dead.pid, me.host, "").text())
    assert lock.writer() is None
    lock.check_free()
    if me.started:  # this process id, but another start time: a reused process id
        lock.pid_path.write_text(Writer(me.pid, me.host, str(int(me.started) - 1)).text())
        assert lock.writer() is None
    lock.pid_path.write_text("junk\n")
    assert lock.writer() is None


def test_a_folder_that_is_a_file_cannot_be_locked(tmp_path):
    (tmp_path / "f").write_text("x")
    with pytest.raises(RvmsimError, match="not a folder"):
        FolderLock(tmp_path / "f", "run", "run").acquire()
