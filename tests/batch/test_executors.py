"""batch.executors: the local process pool survives a dead worker; task_malloc undoes Dask's low
malloc trim threshold for the duration of a task."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from rvmsim.batch import DaskExecutor, LocalExecutor


def _square_once(arg):
    x, marker = arg
    if x == 2 and not Path(marker).exists():
        Path(marker).write_text("died once")
        os.kill(os.getpid(), signal.SIGKILL)
    return x * x


def test_local_executor_reruns_tasks_of_a_dead_worker(tmp_path):
    marker = str(tmp_path / "died")
    got = dict(LocalExecutor(2).run(_square_once, {str(x): (x, marker) for x in range(6)}))
    assert got == {str(x): x * x for x in range(6)}
    assert Path(marker).exists()


def test_local_executor_in_process_keeps_order_and_results():
    got = list(LocalExecutor(1).run(abs, {"a": -1, "b": -2}))
    assert got == [("a", 1), ("b", 2)]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc mallopt")
@pytest.mark.parametrize("env, changed", [("65536", True), (None, False), ("999999999999", False)])
def test_task_malloc_raises_a_low_trim_threshold_only(env, changed):
    code = ("from rvmsim.batch import task_malloc\n"
            "with task_malloc() as changed: print(changed)\n")
    environ = {k: v for k, v in os.environ.items() if k != "MALLOC_TRIM_THRESHOLD_"}
    if env is not None:
        environ["MALLOC_TRIM_THRESHOLD_"] = env
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=environ, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == str(changed)


def test_unreachable_scheduler_is_a_one_line_error():
    pytest.importorskip("distributed")
    from rvmsim.errors import RvmsimError

    with pytest.raises(RvmsimError, match="tcp://127.0.0.1:9: cannot reach the Dask scheduler"
                       r" \(.*[Rr]efused\)"):
        # a port that refuses is said to refuse (the client itself would retry it until
        # timeout_s and then say only that it timed out)
        DaskExecutor("tcp://127.0.0.1:9", timeout_s=2)
