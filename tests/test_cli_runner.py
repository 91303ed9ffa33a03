"""The test runner of rvmsim commands (tests/cli_runner.py): in this process it gives what a
child gives, puts back what it changed, and refuses a command that leaves process state
behind; in a child it applies the memory cap."""

from __future__ import annotations

import os
import signal
import sys
import threading
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from .cli_runner import MEMORY_CAP_BYTES, REPO, child_env, run_in_child, run_in_process
from rvmsim.testing.scenes import write_small_scene


@pytest.fixture
def plugin_module(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                  request: pytest.FixtureRequest) -> Iterator[Callable[[str], str]]:
    """Write an importable module (``source`` → its name) on ``sys.path``, a criteria file
    naming it as a plugin, and forget the module after the test."""
    folder = tmp_path / "plugins"
    folder.mkdir()
    monkeypatch.syspath_prepend(str(folder))
    made: list[str] = []

    def write(source: str) -> str:
        name = f"rvmsim_test_runner_{request.node.name}_{len(made)}".replace("-", "_")
        (folder / f"{name}.py").write_text(source)
        (tmp_path / "c.yaml").write_text(f"plugins: [{name}]\n")
        made.append(name)
        return name

    yield write
    for name in made:
        sys.modules.pop(name, None)


EVALUATE = ("evaluate", "scene.yaml", "--criteria", "c.yaml", "--out", "e", "--no-progress")


def test_in_process_a_forked_child_and_python_m_rvmsim_answer_alike(tmp_path: Path) -> None:
    write_small_scene(tmp_path, name="scene.yaml")
    for args in (["tune", "scene.yaml", "--budget", "x"], ["render", "nope.yaml", "--out", "r"],
                 ["status"], [], ["--version"]):
        here = run_in_process(args, cwd=tmp_path)
        assert here == run_in_child(args, cwd=tmp_path), args
        if args[:1] in (["tune"], ["render"]):  # a new interpreter (2 s each): a usage
            assert here == run_in_child(args, cwd=tmp_path, fresh=True), args  # and a file error


def test_the_process_is_put_back_as_it_was(tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """argv, the working folder, the environment, the streams and pytest's warning filters
    are this process's again after a command (that rendered, so imported everything)."""
    write_small_scene(tmp_path, name="scene.yaml")
    monkeypatch.setenv("RVMSIM_RUNNER_PROBE", "kept")
    before = (list(sys.argv), os.getcwd(), dict(os.environ), sys.stdout, sys.stderr, sys.stdin,
              list(warnings.filters))
    out = run_in_process(["render", "scene.yaml", "--out", "r", "--no-progress"], cwd=tmp_path,
                         env={"RVMSIM_RUNNER_PROBE": None, "RVMSIM_CACHE": "c"})
    assert out.code == 0, out.stderr
    assert (tmp_path / "r" / "fisheye_color.png").is_file()  # it ran there
    assert os.environ["RVMSIM_RUNNER_PROBE"] == "kept"
    after = (list(sys.argv), os.getcwd(), dict(os.environ), sys.stdout, sys.stderr, sys.stdin,
             list(warnings.filters))
    assert after == before


def test_the_environment_is_the_childs(tmp_path: Path) -> None:
    """COLUMNS=200 and the variables given, as :func:`child_env` gives a child."""
    env = child_env({"RVMSIM_MAX_IMAGE_PIXELS": "1000", "HOME": None})
    assert env["COLUMNS"] == "200" and env["RVMSIM_MAX_IMAGE_PIXELS"] == "1000"
    assert "HOME" not in env and env["PYTHONPATH"].split(os.pathsep)[0] == str(REPO)
    write_small_scene(tmp_path, name="scene.yaml")
    args = ["render", "scene.yaml", "--out", "r"]
    here = run_in_process(args, cwd=tmp_path, env={"RVMSIM_MAX_IMAGE_PIXELS": "1000"})
    assert here == run_in_child(args, cwd=tmp_path, env={"RVMSIM_MAX_IMAGE_PIXELS": "1000"})
    assert here.code == 2 and "RVMSIM_MAX_IMAGE_PIXELS" in here.stderr


def test_a_plugin_file_is_refused(tmp_path: Path) -> None:
    """A plugin file stays imported in the process that read it: in-process, a second run
    would not see an edited file, so the runner refuses it."""
    write_small_scene(tmp_path, name="scene.yaml")
    (tmp_path / "p.py").write_text("ECS = []\n")
    (tmp_path / "c.yaml").write_text("plugins: [p.py]\n")
    with pytest.raises(AssertionError, match="imported plugin files .*run it with run_in_child"):
        run_in_process(EVALUATE, cwd=tmp_path)
    child = run_in_child(EVALUATE, cwd=tmp_path)
    assert child.code == 2 and "p.py" in child.stderr and "ECS" in child.stderr


def test_a_thread_left_running_is_refused(tmp_path: Path, plugin_module) -> None:
    write_small_scene(tmp_path, name="scene.yaml")
    name = plugin_module("import threading\nSTOP = threading.Event()\n"
                         "threading.Thread(target=STOP.wait, name='left-behind').start()\n")
    try:
        with pytest.raises(AssertionError, match="left threads running .*left-behind"):
            run_in_process(EVALUATE, cwd=tmp_path)
    finally:
        sys.modules[name].STOP.set()
        for t in threading.enumerate():
            if t.name == "left-behind":
                t.join(10)


def test_a_changed_signal_handler_is_refused_and_put_back(tmp_path: Path, plugin_module) -> None:
    write_small_scene(tmp_path, name="scene.yaml")
    before = signal.getsignal(signal.SIGTERM)
    plugin_module("import signal\nsignal.signal(signal.SIGTERM, signal.SIG_IGN)\n")
    with pytest.raises(AssertionError, match="changed the handler of SIGTERM"):
        run_in_process(EVALUATE, cwd=tmp_path)
    assert signal.getsignal(signal.SIGTERM) == before


def test_a_child_under_the_cap_cannot_allocate_past_it(tmp_path: Path) -> None:
    """The cap is the child's address space: 3 GiB (here only 1.5 × the cap) fail there."""
    write_small_scene(tmp_path, name="scene.yaml")
    (tmp_path / "hog.py").write_text("HOG = bytearray(3 * 1024**3)\n")
    (tmp_path / "c.yaml").write_text("plugins: [hog.py]\n")
    capped = run_in_child(EVALUATE, cwd=tmp_path, memory_cap=MEMORY_CAP_BYTES)
    assert capped.code == 2 and "MemoryError" in capped.stderr, capped.stderr
