"""The harness itself: it passes a clean failure and catches every way of not being one."""

from __future__ import annotations

import os
import sys

import pytest

from ..cli_runner import REPO, run_in_child, run_in_process
from .conftest import SMALL_SCENE, small_scene
from .harness import MEMORY, Case, Outcome, assert_clean_failure, check_case


def test_the_small_scene_is_valid(tmp_path):
    small_scene(tmp_path)
    out = run_in_process(["render", SMALL_SCENE, "--out", "r", "--no-progress"], cwd=tmp_path)
    assert out.code == 0, out.stderr
    assert "320x240" in out.stdout


def test_a_clean_failure_passes(case_dir):
    case = Case("missing-key", ("render", SMALL_SCENE, "--out", "r"), (SMALL_SCENE, "camera"),
                setup=lambda d: small_scene(d, {"camera": None}))
    check_case(case, case_dir)


@pytest.mark.parametrize("out, why", [
    (Outcome(1, "", "rvmsim: error: x.yaml: k: bad\n"), "exit"),
    (Outcome(2, "", "rvmsim: error: x.yaml: k: bad\nmore\n"), "lines"),
    (Outcome(2, "", "Traceback (most recent call last):\n"), "Traceback"),
    (Outcome(2, "", "rvmsim: error: x.yaml: bad\n"), "not named"),
])
def test_unclean_failures_are_caught(out, why):
    with pytest.raises(AssertionError, match=why):
        assert_clean_failure(out, ["x.yaml", "k:"])


def test_a_changed_run_folder_is_caught(case_dir, monkeypatch):
    """A command that fails cleanly but touched a stored run fails the case."""
    from . import harness

    def spoiling_run(case, folder):
        (folder / "run" / "run.sqlite").write_bytes(b"")
        return Outcome(2, "", "rvmsim: error: scene.yaml: camera: missing required key\n")

    monkeypatch.setattr(harness, "run_case", spoiling_run)
    with pytest.raises(AssertionError, match="run changed"):
        check_case(Case("spoils", ("report", "run"), (SMALL_SCENE,), keep=("run",)), case_dir)


def test_keep_names_only_folders_the_command_is_given(case_dir):
    """A kept folder the command is not given would be checked for nothing."""
    with pytest.raises(AssertionError, match="not given: \\['run'\\]"):
        check_case(Case("unread", ("render", SMALL_SCENE), (SMALL_SCENE,), keep=("run",)),
                   case_dir)


# ---------------------------------------------------------------------------- real failures
#: Criteria plugins (imported by module name) that make a real ``rvmsim evaluate`` fail in
#: a way that is not clean: (id, module source, what check_case must say).  rvmsim turns a
#: plugin's own failure on import (any exception, ``sys.exit`` and other ``BaseException``
#: subclasses too) into one clean line (issue #30), so these fail around that line: lines
#: of their own before it, a traceback they print, a Ctrl-C, a stderr they swallow.
HOSTILE = [
    ("two-lines", "import sys\nsys.stderr.write('rvmsim: error: c.yaml: one\\nand another\\n')\n"
     "raise SystemExit(2)\n", "3 stderr lines"),
    ("traceback", "import traceback\n\ntry:\n    raise ValueError('printed by the plugin')\n"
     "except ValueError:\n    traceback.print_exc()\n", "a traceback"),
    ("below-python", "import os\nimport sys\nos.write(2, b'written to the descriptor\\n')\n"
     "sys.stderr.write('rvmsim: error: c.yaml: x\\n')\nraise SystemExit(2)\n", "3 stderr lines"),
    ("a-warning", "import warnings\nwarnings.warn('careful', UserWarning)\n", "3 stderr lines"),
    ("interrupt", "raise KeyboardInterrupt\n", "exit 130"),
    ("stderr-swallowed", "import io\nimport sys\nsys.stderr = io.StringIO()\n"
     "raise SystemExit(2)\n", "0 stderr lines"),
]


def _hostile_case(folder, module: str) -> Case:
    (folder / "c.yaml").write_text(f"plugins: [{module}]\n")
    return Case("hostile", ("evaluate", SMALL_SCENE, "--criteria", "c.yaml", "--out", "e",
                            "--no-progress"), ("c.yaml",))


@pytest.mark.parametrize("source, why", [h[1:] for h in HOSTILE], ids=[h[0] for h in HOSTILE])
def test_an_unclean_failure_in_process_is_caught(source, why, case_dir, plugin_module):
    """The in-process runner sees what a child's pipes would: extra lines (from Python, from
    below it, from a warning), a traceback, the exit status."""
    case = _hostile_case(case_dir, plugin_module(source))
    with pytest.raises(AssertionError, match=why):
        check_case(case, case_dir)


@pytest.mark.parametrize("source", [h[1] for h in HOSTILE], ids=[h[0] for h in HOSTILE])
def test_in_process_and_child_fail_alike(source, case_dir, plugin_module):
    """The same exit status and stdout, the same stderr lines, a traceback in both or
    neither."""
    case = _hostile_case(case_dir, plugin_module(source))
    here = run_in_process(case.args, cwd=case_dir)
    path = os.pathsep.join((str(REPO), str(plugin_module.folder)))
    child = run_in_child(case.args, cwd=case_dir, env={"PYTHONPATH": path})
    assert here.code == child.code and here.stdout == child.stdout
    assert ("Traceback" in here.stderr) == ("Traceback" in child.stderr)
    if "Traceback" in here.stderr:  # the frames above the plugin's differ; the error not
        assert here.stderr.splitlines()[-1] == child.stderr.splitlines()[-1]
    else:  # Python's and the descriptor's lines are read one after the other here
        assert sorted(here.stderr.splitlines()) == sorted(child.stderr.splitlines())


def test_an_isolated_case_runs_under_the_memory_cap(case_dir):
    """A case marked isolate runs in a child whose allocations stop at the cap: a plugin
    asking for 3 GiB fails with MemoryError there (it would get them in this process)."""
    (case_dir / "hog.py").write_text("HOG = bytearray(3 * 1024**3)\n")
    (case_dir / "c.yaml").write_text("plugins: [hog.py]\n")
    case = Case("hog", ("evaluate", SMALL_SCENE, "--criteria", "c.yaml", "--out", "e",
                        "--no-progress"), ("hog.py", "MemoryError"), isolate=MEMORY)
    check_case(case, case_dir)
