"""No process outlives its parent (issue #29; ``rvmsim._procs``).

Each command that starts processes runs as a real ``python -m rvmsim`` on a small scene with
2 workers.  Once its children exist (the workers, the fork server they come from and
multiprocessing's resource tracker, found with psutil) it is killed (SIGKILL) or stopped (SIGTERM; SIGINT for ``tune``), and
every child recorded must be gone, by pid, within :data:`GRACE_S` of the parent's end.
A stopped command exits 128 + the signal's number with one line and no traceback, and a
tuning run stopped any of those ways resumes to the unbroken run's result.

The tests of this file share a render cache (one module fixture), so under pytest-xdist they
form one group (tests/conftest.py groups every file that is not a shared-fixture folder).
"""

from __future__ import annotations

import itertools
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import psutil
import pytest

from rvmsim._procs import start_pool, stop_pool
from rvmsim.runs import RunStatus, RunStore

from .cli_runner import REPO, child_env, run_in_process, start_in_child
from rvmsim.testing.scenes import write_small_scene

#: The guarantee: every child has ended this long after its parent (s).
GRACE_S = 2.0
#: How long a command may take to start its children, or to stop after SIGTERM/SIGINT (s).
START_S = 180.0
#: Children of a pool command with 2 workers: the workers, the fork server they are forked
#: from (their parent) and the resource tracker.
POOL_CHILDREN = 4
#: A small search: at 160 × 90, judged at a 160 × 90 display (the unbroken run: EC 0.64).
CONFIG = {"output": {"size": [160, 90]}, "top_m": 3, "batch": 20}
SMALL_DISPLAY = {"display": {"rvm_image_px": [160, 90]}}
#: ±1° on every angle, one load state: the robust members need no render of their own.
ANGLES_ONLY = {"mount": {a: {"uniform": {"half_width": 1.0}}
                         for a in ("yaw_deg", "pitch_deg", "roll_deg")}}
#: The kill/resume run: its budget, and the trials stored before it is stopped.
BUDGET, STOP_AFTER = 400, 40
#: Numbers the output files of the commands started.
_RUNS = itertools.count()


@pytest.fixture(scope="module")
def case(tmp_path_factory) -> Path:
    """A folder with vehicles A and E at 320 × 240 (A with angle tolerances only, and as
    ``positions.yaml`` with the bundled variation: 2 positions per axis × 3 load states), the
    tuning config, a params file and a render cache (``cache/``) holding their renders."""
    from rvmsim.render import cached_render
    from rvmsim.scene import load_scene

    folder = tmp_path_factory.mktemp("lifetime")
    scenes = [write_small_scene(folder, "a", edit=SMALL_DISPLAY, variation=ANGLES_ONLY),
              write_small_scene(folder, "e", edit=SMALL_DISPLAY, variation=None),
              write_small_scene(folder, "a", name="positions.yaml", edit=SMALL_DISPLAY)]
    (folder / "tune.yaml").write_text(json.dumps(CONFIG))
    (folder / "params.yaml").write_text((REPO / "params" / "paper_defaults.yaml").read_text())
    with pytest.MonkeyPatch.context() as mp:  # the commands below find them cached
        mp.setenv("RVMSIM_CACHE", _env(folder)["RVMSIM_CACHE"])
        for scene in scenes:
            cached_render(load_scene(scene))
    return folder


def _env(folder: Path) -> dict[str, str]:
    return {"RVMSIM_CACHE": str(folder / "cache")}


def _trials(db: Path) -> int:
    try:  # read-only: connecting must not make the file the command is about to make
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True) as con:
            return int(con.execute("SELECT COUNT(*) FROM trials").fetchone()[0])
    except sqlite3.Error:  # not made yet
        return 0


def _alive(proc: psutil.Process) -> bool:
    """Running and not a zombie (an exited process whose status nobody has read yet)."""
    try:
        return proc.is_running() and proc.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def _describe(proc: psutil.Process) -> str:
    try:
        return f"{proc.pid} {' '.join(proc.cmdline())[-70:]}"
    except psutil.Error:  # ended meanwhile
        return f"{proc.pid} (ended)"


def stop_and_check(args: list[object], cwd: Path, sig: signal.Signals, *,
                   ready: Callable[[Path], bool] = lambda stdout: True,
                   children: int = POOL_CHILDREN) -> subprocess.CompletedProcess[str]:
    """Start ``python -m rvmsim ARGS``; once it has ``children`` processes below it and
    ``ready(its stdout file)`` (0 children: it must have none), send it ``sig`` (SIGINT to
    its whole process group, as Ctrl-C in a terminal, so its workers get it too); check that
    it ends (for SIGTERM and SIGINT: 128 + the signal and one line on stderr) and that none
    of the processes recorded below it just before the signal is alive :data:`GRACE_S`
    after.  Returns its status and output."""
    name = f"{args[0]}_{sig.name}_{next(_RUNS)}"
    out, err = cwd / f"{name}.stdout", cwd / f"{name}.stderr"
    with out.open("w") as fo, err.open("w") as fe:
        proc = start_in_child(args, cwd=cwd, env=_env(cwd), stdout=fo, stderr=fe,
                              start_new_session=sig is signal.SIGINT)
    kids: list[psutil.Process] = []
    try:
        parent = psutil.Process(proc.pid)
        deadline = time.monotonic() + START_S
        while time.monotonic() < deadline:
            assert proc.poll() is None, f"ended before it was stopped: {err.read_text()}"
            kids = parent.children(recursive=True)
            if len(kids) >= children and ready(out):
                break
            time.sleep(0.02)
        else:
            pytest.fail(f"no {children} children within {START_S} s: {kids}")
        kids = parent.children(recursive=True)
        assert children or not kids, f"a command that starts no process has {kids}"
        if sig is signal.SIGINT:  # Ctrl-C: a terminal signals the whole process group
            os.killpg(proc.pid, sig)
        else:
            proc.send_signal(sig)
        proc.wait(timeout=START_S)
        ended = time.monotonic()
        while any(_alive(k) for k in kids) and time.monotonic() < ended + GRACE_S:
            time.sleep(0.02)
        survivors = [_describe(k) for k in kids if _alive(k)]
        assert not survivors, f"alive {GRACE_S} s after rvmsim ended: {survivors}"
    finally:  # whatever failed: leave nothing behind
        for k in [proc_ for proc_ in kids if _alive(proc_)]:
            k.kill()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    res = subprocess.CompletedProcess(args, proc.returncode, out.read_text(), err.read_text())
    if sig is signal.SIGKILL:
        assert res.returncode == -signal.SIGKILL
    else:
        assert res.returncode == 128 + sig, res.stderr
        lines = res.stderr.strip().splitlines()  # one line: nothing from the workers either
        assert len(lines) == 1 and lines[0].startswith(
            "rvmsim: terminated (SIGTERM)" if sig is signal.SIGTERM else "rvmsim: interrupted"
        ), res.stderr
    return res


def _tune_args(run: Path | None, *extra: object, workers: int = 2) -> list[object]:
    if run is None:  # --resume RUN in extra
        return ["tune", *extra, "--workers", workers, "--no-progress"]
    return ["tune", "vehicle_a.yaml", "--config", "tune.yaml", "--budget", BUDGET,
            "--out", run, "--workers", workers, "--no-progress", *extra]


def _top(run: Path) -> tuple[list[tuple[int, dict[str, float], float]], int]:
    store = RunStore(run / "run.sqlite", readonly=True)
    try:
        return [(r.idx, r.params, r.score) for r in store.top(3)], store.count()
    finally:
        store.close()


@pytest.fixture(scope="module")
def clean(case: Path) -> Path:
    """The unbroken run (cmaes-solved, seed 0, :data:`BUDGET`), in this process."""
    res = run_in_process(_tune_args(case / "clean", workers=1), cwd=case, env=_env(case))
    assert res.code == 0, res.stderr
    return case / "clean"


#: SIGINT is SIGTERM's orderly stop (both raise a KeyboardInterrupt): the slow tier.
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM,
                                 pytest.param(signal.SIGINT, marks=pytest.mark.slow)],
                         ids=lambda s: s.name)
def test_tune_leaves_no_worker_and_resumes_to_the_unbroken_result(case, clean, sig):
    run = case / f"run_{sig.name}"
    stop_and_check(_tune_args(run), case, sig,
                   ready=lambda _: _trials(run / "run.sqlite") >= STOP_AFTER)
    stored = _trials(run / "run.sqlite")
    assert STOP_AFTER <= stored < BUDGET
    store = RunStore(run / "run.sqlite", readonly=True)
    state = store.state()
    store.close()
    if sig is not signal.SIGKILL:  # an orderly stop: recorded as such
        assert state.status is RunStatus.INTERRUPTED
    res = run_in_process(_tune_args(None, "--resume", run, workers=1), cwd=case, env=_env(case))
    assert res.code == 0, res.stderr
    assert f"{stored} replayed" in res.stdout
    assert _top(run) == _top(clean)


@pytest.mark.parametrize(("mode", "sig"), [("--robust", signal.SIGKILL),
                                         ("--shared", signal.SIGTERM)],
                         ids=["robust-SIGKILL", "shared-SIGTERM"])
def test_robust_and_shared_tuning_leave_no_worker(case, mode, sig):
    """Stopped as soon as their workers exist, while they start (the tests above stop plain
    runs at work; the pool, its workers and the stop are the same: ``BatchEvaluator``)."""
    run = case / f"run{mode}_{sig.name}"
    extra = (["--robust", "--samples", "4"] if mode == "--robust"
             else ["vehicle_e.yaml", "--shared"])
    stop_and_check(_tune_args(run, *extra), case, sig)


def test_batch_leaves_no_worker_and_stops_there(case):
    """SIGTERM during the first scene's tuning: the second scene is never started.  (Killed,
    batch is tune's case: the same pool in the same process.)"""
    out = case / "batch"
    stop_and_check(["batch", "vehicle_a.yaml", "vehicle_e.yaml", "--config", "tune.yaml",
                    "--out", out, "--workers", 2, "--budget", BUDGET, "--no-progress"], case,
                   signal.SIGTERM)
    assert not (out / "vehicle_e").exists()


SWEEP = """\
base_scene: vehicle_e.yaml
axes:
  pitch_deg: [28, 30, 32, 34]
tune:
  strategy: cmaes-solved
  budget: 2000
  config: {tuned: [zoom, adv_v_shift, adv_v_scale], output: {size: [160, 90]}}
"""


#: Killed, every pool's workers end the same way (the fork server's end, PR_SET_PDEATHSIG):
#: tune's and a robust run's SIGKILL cases above are the fast tier's.
_KILLED_SLOW = pytest.param(signal.SIGKILL, marks=pytest.mark.slow)


@pytest.mark.parametrize("sig", [_KILLED_SLOW, signal.SIGTERM], ids=lambda s: s.name)
def test_a_local_sweep_leaves_no_worker(case, sig):
    (case / "sweep.yaml").write_text(SWEEP)
    out = case / f"sweep_{sig.name}"
    res = stop_and_check(["sweep", "sweep.yaml", "--out", out, "--workers", 2,
                          "--no-progress"], case, sig)
    if sig is signal.SIGTERM:  # as after Ctrl-C: what is stored is written, resumable
        assert "run the same command again to resume" in res.stderr


@pytest.mark.parametrize("sig", [_KILLED_SLOW, signal.SIGTERM], ids=lambda s: s.name)
def test_robustness_leaves_no_render_worker(case, sig):
    """Stopped while its workers start to render the samples' viewpoints (16 samples: up to
    24 viewpoints, none cached)."""
    stop_and_check(["robustness", "positions.yaml", "--params", "params.yaml", "--samples", 16,
                    "--scales", "1", "--out", f"rob_{sig.name}", "--workers", 2,
                    "--no-progress"], case, sig)


def test_the_console_starts_no_process_and_stops_on_sigterm(case):
    """The console serves from its own process alone (so SIGKILL leaves nothing either);
    SIGTERM stops it as Ctrl-C does."""
    stop_and_check(["console", "vehicle_a.yaml", "--port", 0, "--no-browser"], case,
                   signal.SIGTERM, children=0,
                   ready=lambda stdout: bool(stdout.read_text()))


WATCH_ONLY = """\
import threading, time
from rvmsim._procs import start_pool

def start():  # made in a thread that ends (which the kernel's watch must not follow)
    global pool
    pool = start_pool(2)
    for f in [pool.submit(time.sleep, 0.2) for _ in range(4)]:
        f.result()
    pool.submit(time.sleep, 600)
    pool.submit(time.sleep, 600)

thread = threading.Thread(target=start)
thread.start()
thread.join()
time.sleep(0.5)
print("ready", flush=True)
time.sleep(600)
"""


def _kill_and_check(argv: list[str], children: Callable[[psutil.Process], list[psutil.Process]],
                    count: int) -> None:
    """Start ``argv``; once it prints "ready", its ``count`` ``children`` must be running;
    kill it (SIGKILL) and check that every one of them ends within :data:`GRACE_S`."""
    proc = subprocess.Popen(argv, env=child_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    kids: list[psutil.Process] = []
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "ready\n"
        kids = children(psutil.Process(proc.pid))
        assert len(kids) == count and all(_alive(k) for k in kids)
        proc.kill()
        proc.wait()
        ended = time.monotonic()
        while any(_alive(k) for k in kids) and time.monotonic() < ended + GRACE_S:
            time.sleep(0.02)
        assert not [k.pid for k in kids if _alive(k)]
    finally:
        for k in [k for k in kids if _alive(k)]:
            k.kill()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()


def test_workers_of_a_pool_made_in_a_thread_end_with_their_parent():
    """The workers of a pool started from a thread outlive that thread, and end with their
    process (killed: the fork server ends with it, and the kernel and each worker's watch
    of the pipe from the parent end the workers)."""
    _kill_and_check([sys.executable, "-c", WATCH_ONLY],
                    lambda proc: proc.children(recursive=True), POOL_CHILDREN)


WATCH_ALONE = """\
import multiprocessing as mp, os, time
from rvmsim._procs import die_with_parent

def watched(parent_pid, started):
    die_with_parent(parent_pid, kernel=False)
    started.release()
    time.sleep(600)

if __name__ == "__main__":
    ctx = mp.get_context("spawn")
    started = ctx.Semaphore(0)
    kids = [ctx.Process(target=watched, args=(os.getpid(), started)) for _ in range(2)]
    for k in kids:
        k.start()
    for k in kids:
        started.acquire()
    print("ready", flush=True)
    time.sleep(600)
"""


def test_the_watch_of_the_pipe_from_the_parent_ends_a_child_alone(tmp_path):
    """The portable watch (where there is no fork server and no PR_SET_PDEATHSIG):
    spawned children that only watch the pipe from their parent end when it is killed."""
    script = tmp_path / "watch_alone.py"
    script.write_text(WATCH_ALONE)
    _kill_and_check([sys.executable, str(script)],
                    lambda proc: [k for k in proc.children()
                                  if "resource_tracker" not in " ".join(k.cmdline())], 2)


def test_a_worker_has_the_environment_of_its_pool_s_making(monkeypatch):
    """Workers are forked from a fork server started once, with the environment of its own
    start; each pool's workers still see the caller's environment as it was when the pool
    was made (a render cache, a thread count set later)."""
    seen = []
    for value in ("one", "two"):
        monkeypatch.setenv("RVMSIM_PROBE", value)
        pool = start_pool(1)
        try:
            seen.append(pool.submit(os.getenv, "RVMSIM_PROBE").result(timeout=60))
        finally:
            stop_pool(pool, now=False)
    assert seen == ["one", "two"]


def _group_left(pgid: int) -> list[str]:
    """The processes of process group ``pgid`` still running (zombies count: not reaped)."""
    out = []
    for proc in psutil.process_iter():
        try:
            if os.getpgid(proc.pid) == pgid:
                out.append(_describe(proc))
        except (ProcessLookupError, psutil.Error):
            pass
    return out


#: tune's case stands for the others in the test command (same exit path); the rest: slow tier
@pytest.mark.parametrize("command", ["tune", "error",
                                     pytest.param("render", marks=pytest.mark.slow),
                                     pytest.param("tune-SIGTERM", marks=pytest.mark.slow)])
def test_nothing_of_a_command_runs_once_its_exit_status_is_read(case, command):
    """The command's process group (its own session, as a supervisor starts it) is empty
    the moment its exit status is read: its workers, the fork server and multiprocessing's
    resource tracker have ended before it (they used to end a moment after it)."""
    run = case / f"group_{command}_{next(_RUNS)}"
    args: list[object] = {
        "tune": _tune_args(run, "--budget", 60),
        "tune-SIGTERM": _tune_args(run),
        "render": ["render", "vehicle_a.yaml", "--out", run, "--no-progress"],
        "error": ["tune", "missing.yaml", "--out", run, "--workers", 2, "--no-progress"],
    }[command]
    proc = subprocess.Popen([sys.executable, "-m", "rvmsim", *map(str, args)], cwd=case,
                            env=child_env(_env(case)), stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    if command == "tune-SIGTERM":
        deadline = time.monotonic() + START_S
        while _trials(run / "run.sqlite") < STOP_AFTER and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=START_S)
    left = _group_left(proc.pid)
    expected = {"tune": {0, 1}, "render": {0}, "tune-SIGTERM": {143}, "error": {2}}[command]
    assert proc.returncode in expected, err
    assert left == [], left


#: The supervised runs: their budget, and the trials stored before the supervisor stops one.
SUPERVISED_BUDGET, SUPERVISED_STOP = 120, 20


@pytest.fixture(scope="module")
def clean_supervised(case: Path) -> Path:
    """The unbroken run of :data:`SUPERVISED_BUDGET` (seed 0), in this process."""
    run = case / "clean_supervised"
    res = run_in_process(_tune_args(run, "--budget", SUPERVISED_BUDGET, workers=1), cwd=case,
                         env=_env(case))
    assert res.code in (0, 1), res.stderr  # 1: its best fails an EC, as judged
    return run


def _supervised_stop(case: Path, run: Path, supervisor: str) -> subprocess.CompletedProcess[str]:
    """Tune into ``run`` under ``supervisor`` and stop it with SIGTERM once
    :data:`SUPERVISED_STOP` trials are stored: ``timeout`` (its own process group; SIGTERM
    to ``timeout`` runs the same step as its expiry: the signal to the command, then to the
    whole group) or ``group`` (the command in its own session, SIGTERM to the whole group,
    as a service manager stops it).  Returns the command's status (``timeout
    --preserve-status`` passes it on), its stderr, and checks its group is empty then."""
    args = [str(a) for a in _tune_args(run, "--budget", SUPERVISED_BUDGET)]
    command = [sys.executable, "-m", "rvmsim", *args]
    if supervisor == "timeout":
        command = ["timeout", "--preserve-status", str(int(START_S)), *command]
    proc = subprocess.Popen(command, cwd=case, env=child_env(_env(case)),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        deadline = time.monotonic() + START_S
        while _trials(run / "run.sqlite") < SUPERVISED_STOP:
            if proc.poll() is not None:
                pytest.fail(f"ended before it was stopped ({proc.returncode}): "
                            f"{proc.communicate()[1]}")
            assert time.monotonic() < deadline, "no trials in time"
            time.sleep(0.02)
        if supervisor == "timeout":
            proc.send_signal(signal.SIGTERM)
        else:
            os.killpg(proc.pid, signal.SIGTERM)
        _, err = proc.communicate(timeout=START_S)
        assert _group_left(proc.pid) == []
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return subprocess.CompletedProcess(command, proc.returncode, "", err)


#: 1 under timeout in the test command (timeout also signals the group: the workers get it
#: as under a group kill); the group kill and 10 of 10 under timeout in the slow tier.
@pytest.mark.parametrize("supervisor, attempts",
                         [("timeout", 1), pytest.param("group", 1, marks=pytest.mark.slow),
                          pytest.param("timeout", 10, marks=pytest.mark.slow)],
                         ids=["timeout-1", "group-1", "timeout-10"])
def test_sigterm_to_the_process_group_is_one_orderly_stop(case, clean_supervised, supervisor,
                                                          attempts):
    """A supervisor's SIGTERM reaches the command twice (``timeout``: to it, then to its
    group) or with its workers (a group kill): the same one orderly stop every time, exit
    143, one line, the run stored as interrupted and resumed to the unbroken run's trials."""
    for attempt in range(attempts):
        run = case / f"supervised_{supervisor}_{attempts}_{attempt}"
        res = _supervised_stop(case, run, supervisor)
        assert res.returncode == 128 + signal.SIGTERM, (attempt, res.stderr)
        assert res.stderr == "rvmsim: terminated (SIGTERM)\n", (attempt, res.stderr)
        store = RunStore(run / "run.sqlite", readonly=True)
        try:
            assert store.state().status is RunStatus.INTERRUPTED
            stored = store.count()
        finally:
            store.close()
        assert SUPERVISED_STOP <= stored < SUPERVISED_BUDGET
        res2 = run_in_process(_tune_args(None, "--resume", run, workers=1), cwd=case,
                              env=_env(case))
        assert res2.code in (0, 1), res2.stderr
        assert _top(run) == _top(clean_supervised)
        assert _trial_rows(run) == _trial_rows(clean_supervised)


def _trial_rows(run: Path) -> list[tuple[object, ...]]:
    """Every stored trial, in order, without its timing."""
    with sqlite3.connect(f"file:{run / 'run.sqlite'}?mode=ro", uri=True) as con:
        cols = [r[1] for r in con.execute("PRAGMA table_info(trials)")]
        keep = [c for c in cols if "time" not in c and "second" not in c]
        return con.execute(f"SELECT {', '.join(keep)} FROM trials ORDER BY idx").fetchall()
