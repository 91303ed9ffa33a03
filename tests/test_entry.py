"""The command line's entry point: which commands start the worker fork server first."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from rvmsim.cli.entry import WORKER_COMMANDS, command_of
from rvmsim.cli.group import COMMAND_MODULES

from .cli_runner import child_env
from .conftest import SCENES


def test_the_command_is_the_first_argument_that_is_not_an_option():
    assert command_of(["render", "scene.yaml", "--out", "x"]) == "render"
    assert command_of(["--no-color", "tune", "-h"]) == "tune"
    assert command_of(["--help"]) is None and command_of([]) is None


def test_every_worker_command_is_a_command_and_every_renderer_is_one():
    commands = set(COMMAND_MODULES)
    assert WORKER_COMMANDS <= commands
    # the commands that render or start pools (by what they do), and none of the readers
    assert {"render", "evaluate", "tune", "robustness", "sweep", "eol"} <= WORKER_COMMANDS
    assert not {"status", "select", "report"} & WORKER_COMMANDS


def test_the_rvmsim_script_renders_in_a_worker(tmp_path):
    """The installed ``rvmsim`` script (``rvmsim.cli.entry:main``) as the main module: the fork
    server and the render worker import it again, which must start nothing (a start at
    import failed every render)."""
    script = Path(sys.executable).parent / "rvmsim"
    res = subprocess.run([str(script), "render", str(SCENES / "vehicle_a.yaml"), "--scale",
                          "0.1", "--out", str(tmp_path / "r"), "--no-progress"],
                         env=child_env({"RVMSIM_CACHE": str(tmp_path / "cache")}),
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert "Traceback" not in res.stderr
    assert (tmp_path / "r" / "fisheye_labels.png").is_file()
