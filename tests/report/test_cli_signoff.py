"""`rvmsim signoff`'s bad inputs: each is one line on stderr naming the file (or the
option), exit status 2, no traceback, and the folders given left as they were.  (The
command's success path is tests/report/test_signoff.py's fixture.)"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rvmsim.cli import COMMAND_MODULES

from ..bad_input.harness import Case, check_case


def _folder(name: str, files: dict[str, str]):
    """A setup writing ``files`` (name → text) into the case folder's ``name``."""
    def setup(root: Path) -> None:
        (root / name).mkdir(parents=True, exist_ok=True)
        for file, text in files.items():
            (root / name / file).write_text(text)
    return setup


def _both(*setups):
    def setup(root: Path) -> None:
        for s in setups:
            s(root)
    return setup


_RUN = _folder("run", {})
_ROB_OK_BUT = {"yield": 0.5, "n": 2, "n_pass": 1, "ci95": [0.1, 0.9], "ecs": [],
               "samples": [], "variation": {}, "seed": 0, "scene": "s.yaml",
               "yield_by_load": {}}

CASES = [
    Case("run folder missing", ("signoff", "nothing", "--out", "so", "--no-pdf"),
         ("nothing", "no such run folder")),
    Case("not a run folder", ("signoff", "run", "--out", "so", "--no-pdf"),
         ("run", "run.sqlite"), setup=_RUN, keep=("run",)),
    Case("corrupt run.sqlite", ("signoff", "run", "--out", "so", "--no-pdf"),
         ("run.sqlite",), setup=_folder("run", {"run.sqlite": "not a database " * 100}),
         keep=("run",)),
    Case("robustness folder missing", ("signoff", "run", "--robustness", "rob", "--out", "so",
                                       "--no-pdf"), ("rob", "no such folder"), setup=_RUN),
    Case("robustness.json missing", ("signoff", "run", "--robustness", "rob", "--out", "so",
                                     "--no-pdf"), ("rob/robustness.json", "rvmsim robustness"),
         setup=_both(_RUN, _folder("rob", {"other.json": "{}"})), keep=("rob",)),
    Case("robustness.json corrupt", ("signoff", "run", "--robustness", "rob", "--out", "so",
                                     "--no-pdf"), ("rob/robustness.json", "line 1"),
         setup=_both(_RUN, _folder("rob", {"robustness.json": '{"yield": 0.5, '})),
         keep=("rob",)),
    Case("robustness.json without a key", ("signoff", "run", "--robustness", "rob", "--out",
                                           "so", "--no-pdf"),
         ("rob/robustness.json", "isp"),
         setup=_both(_RUN, _folder("rob", {"robustness.json": json.dumps(_ROB_OK_BUT)})),
         keep=("rob",)),
    Case("robustness.json with a bad yield", ("signoff", "run", "--robustness", "rob",
                                              "--out", "so", "--no-pdf"),
         ("rob/robustness.json", "yield"),
         setup=_both(_RUN, _folder("rob", {"robustness.json": json.dumps(
             {**_ROB_OK_BUT, "yield": "high", "isp": {}})})), keep=("rob",)),
    Case("validation folder without results", ("signoff", "run", "--validation", "val",
                                               "--out", "so", "--no-pdf"),
         ("val/validation.json", "rvmsim validate"), setup=_both(_RUN, _folder("val", {}))),
    Case("eol.json corrupt", ("signoff", "run", "--eol", "eol", "--out", "so", "--no-pdf"),
         ("eol/eol.json", "not valid JSON"),
         setup=_both(_RUN, _folder("eol", {"eol.json": "[1, 2"})), keep=("eol",)),
    Case("eol.json of something else", ("signoff", "run", "--eol", "eol", "--out", "so",
                                        "--no-pdf"), ("eol/eol.json", "results"),
         setup=_both(_RUN, _folder("eol", {"eol.json": "[1, 2]"})), keep=("eol",)),
    Case("--out parent missing", ("signoff", "run", "--out", "no/such/so", "--no-pdf"),
         ("no/such", "parent of --out"), setup=_RUN),
    Case("--out is a file", ("signoff", "run", "--out", "run/file", "--no-pdf"),
         ("run/file", "not a folder"), setup=_folder("run", {"file": "x"}), keep=("run",)),
    Case("--out not given", ("signoff", "run"), ("--out",), setup=_RUN),
    Case("no chromium for the PDF", ("signoff", "run", "--out", "so"), ("chromium",
                                                                       "--no-pdf"),
         setup=_RUN, env={"PATH": "/nonexistent"}),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_one_line_and_exit_2(case: Case, tmp_path: Path) -> None:
    out = check_case(case, tmp_path)
    assert not (tmp_path / "so").exists() or case.id == "--out is a file"
    assert out.stdout == "" or "wrote" not in out.stdout


def test_the_command_is_registered() -> None:
    assert "signoff" in COMMAND_MODULES
