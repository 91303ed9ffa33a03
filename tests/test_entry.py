"""The command line's entry point: which commands start the worker fork server first."""

from __future__ import annotations

from rvmsim._entry import WORKER_COMMANDS, command_of
from rvmsim.cli.group import cli


def test_the_command_is_the_first_argument_that_is_not_an_option():
    assert command_of(["render", "scene.yaml", "--out", "x"]) == "render"
    assert command_of(["--no-color", "tune", "-h"]) == "tune"
    assert command_of(["--help"]) is None and command_of([]) is None


def test_every_worker_command_is_a_command_and_every_renderer_is_one():
    commands = set(cli.commands)
    assert WORKER_COMMANDS <= commands
    # the commands that render or start pools (by what they do), and none of the readers
    assert {"render", "evaluate", "tune", "robustness", "sweep", "eol"} <= WORKER_COMMANDS
    assert not {"status", "select", "report"} & WORKER_COMMANDS
