"""rvmsim._procs: a pool worker's share of the cores (its lifetime: test_process_lifetime.py)."""

from __future__ import annotations

import os

from rvmsim._procs import THREAD_VARIABLES, spawn_pool, stop_pool, worker_threads


def _thread_settings() -> dict[str, object]:
    """What a pool worker runs with: OpenCV's thread count and the thread variables."""
    import cv2

    return {"cv2": cv2.getNumThreads(), **{v: os.environ.get(v) for v in THREAD_VARIABLES}}


def test_worker_threads_share_the_cores():
    assert worker_threads(2, cores=8) == 4
    assert worker_threads(3, cores=8) == 2
    assert worker_threads(4, cores=2) == 1  # never below one
    assert worker_threads(1, cores=6) == 6


def test_pool_workers_take_their_share_and_keep_the_users_settings(monkeypatch):
    for var in THREAD_VARIABLES:
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "3")  # set by the user: kept
    import cv2

    parent_cv2 = cv2.getNumThreads()
    pool = spawn_pool(2)
    try:
        got = pool.submit(_thread_settings).result(timeout=120)
    finally:
        stop_pool(pool, now=False)
    share = max(1, (os.cpu_count() or 1) // 2)
    assert got["cv2"] == share
    assert got["OPENCV_FOR_THREADS_NUM"] == got["LP_NUM_THREADS"] == str(share)
    assert got["OPENBLAS_NUM_THREADS"] == str(share)
    assert got["OMP_NUM_THREADS"] == "3"
    assert cv2.getNumThreads() == parent_cv2  # the parent is left alone
    assert "LP_NUM_THREADS" not in os.environ
