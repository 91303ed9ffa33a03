"""Bad input of ``rvmsim console`` (issue #17): each is one stderr line naming the option,
argument or file at fault, exit status 2, no traceback, before anything is served, and the
run given to it byte-identical afterwards."""

from __future__ import annotations

import dataclasses
import socket
from pathlib import Path

import pytest

from .conftest import SMALL_SCENE, small_scene
from ..cli_runner import run_in_process, tune_status
from .harness import (MEMORY_CAP_BYTES, SERVER, TIMEOUT_S, Case, assert_clean_failure,
                      check_case, folder_digest, run_in_child)

RUN = ("run",)
NO_BROWSER = "--no-browser"


def _junk_store(folder: Path) -> None:
    (folder / "run" / "run.sqlite").write_bytes(b"not a database at all\n" * 40)


def _empty_folder(folder: Path) -> None:
    (folder / "empty").mkdir()


def _bad_scene(folder: Path) -> None:
    small_scene(folder, {"camera.image_size": "wide"})


def _run_without_its_scene(folder: Path) -> None:
    """A run of its own scene file (``own/scene.yaml``), which is then deleted."""
    own = folder / "own"
    own.mkdir()
    small_scene(own)
    out = run_in_process(["tune", SMALL_SCENE, "--strategy", "random", "--budget", "3",
                          "--workers", "1", "--out", "run", "--no-progress"], cwd=own)
    assert out.code == tune_status(own / "run"), out.stderr
    (own / SMALL_SCENE).unlink()


CASES = [
    Case("missing-source", ("console", "nope", NO_BROWSER), ("nope", "no such run folder")),
    Case("folder-not-a-run", ("console", "empty", NO_BROWSER), ("empty", "run.sqlite"),
         setup=_empty_folder),
    Case("junk-run-store", ("console", "run", NO_BROWSER), ("run.sqlite",), setup=_junk_store,
         keep=RUN),
    Case("bad-scene", ("console", SMALL_SCENE, NO_BROWSER), (SMALL_SCENE, "image_size"),
         setup=_bad_scene),
    Case("run-scene-gone", ("console", "own/run", NO_BROWSER), ("scene.yaml", "not found"),
         setup=_run_without_its_scene, keep=("own/run",)),
    Case("port-too-big", ("console", "run", "--port", "70000", NO_BROWSER), ("--port",),
         keep=RUN),
    Case("port-negative", ("console", "run", "--port", "-1", NO_BROWSER), ("--port",),
         keep=RUN),
    Case("port-not-a-number", ("console", "run", "--port", "http", NO_BROWSER), ("--port",),
         keep=RUN),
    Case("empty-host", ("console", "run", "--host", " ", NO_BROWSER), ("--host",), keep=RUN),
    Case("short-token", ("console", "run", "--host", "0.0.0.0", "--token", "abc",
                         NO_BROWSER), ("--token",), keep=RUN),
    Case("token-with-symbols", ("console", "run", "--token", "a" * 20 + "<&>", NO_BROWSER),
         ("--token",), keep=RUN),
]
#: Every console case runs in a child of its own: a regression would serve (forever).
CASES = [dataclasses.replace(c, isolate=SERVER) for c in CASES]


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_console_bad_input(case: Case, case_dir: Path) -> None:
    check_case(case, case_dir)


def test_console_port_in_use(case_dir: Path) -> None:
    """A port another program listens on: one line naming ``--port``, nothing served."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        before = folder_digest(case_dir / "run")
        out = run_in_child(["console", "run", "--port", str(port), NO_BROWSER], cwd=case_dir,
                           timeout_s=TIMEOUT_S, memory_cap=MEMORY_CAP_BYTES)  # SERVER
    assert_clean_failure(out, ("--port", str(port), "in use"))
    assert folder_digest(case_dir / "run") == before
