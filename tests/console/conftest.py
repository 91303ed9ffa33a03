"""Fixtures of the console tests: a small real tuning run (320×240 scene), a console
served by uvicorn on a free loopback port in a thread, and Chromium through Playwright."""

from __future__ import annotations

import shutil
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import pytest

from rvmsim.testing.scenes import write_small_scene

CHROMIUM = Path("/usr/bin/chromium")


@pytest.fixture(scope="session")
def small_run(tmp_path_factory) -> Path:
    """A folder holding ``scene.yaml`` (the 320×240 vehicle-A scene) and ``run/``, a
    finished tuning run of it (random search, 40 evaluations, top 10)."""
    from rvmsim.tune import TuneRequest, tune

    folder = tmp_path_factory.mktemp("console_run")
    scene = write_small_scene(folder, name="scene.yaml")
    tune(TuneRequest((scene,), "random", seed=3, budget=40), folder / "run")
    return folder


@pytest.fixture
def run_copy(tmp_path, small_run) -> Path:
    """A fresh copy of the small run's folder (scene.yaml and run/), for tests that write."""
    shutil.copy(small_run / "scene.yaml", tmp_path / "scene.yaml")
    shutil.copytree(small_run / "run", tmp_path / "run")
    return tmp_path


@contextmanager
def serving(session, access, host: str = "127.0.0.1") -> Iterator[str]:
    """Serve ``session`` with ``access``'s token on a free port of ``host`` in a thread;
    yields the base URL (``http://host:port``)."""
    from rvmsim.console import listen, make_server

    sock = listen(host, 0)
    server = make_server(session, access)
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the console server did not start")
        time.sleep(0.02)
    try:
        yield f"http://{host}:{sock.getsockname()[1]}"
    finally:
        server.should_exit = True
        thread.join(10)
        sock.close()


@pytest.fixture(scope="module")
def browser():
    """Debian's Chromium driven by Playwright (no browser download)."""
    if not CHROMIUM.is_file():
        pytest.skip("no /usr/bin/chromium (tools/setup.sh --test installs it)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(CHROMIUM), args=["--no-sandbox"])
        yield b
        b.close()
