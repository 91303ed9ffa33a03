"""Result files read back (issue #45): what one command wrote and another reads
(robustness.json, eol.json, validation.json and summary.json read by ``signoff``;
best/markets.json read by ``report``; run.json read by ``tune --resume`` and ``status``),
nested past the JSON limits, over the size limit, or of the wrong types, fail with one line
naming the file and the key, exit 2, no traceback, and leave the stored results as they were.
And what the writers write validates against the schemas the readers check."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from rvmsim.compensation import Deviation
from rvmsim.eol.result_file import EolFile
from rvmsim.robust.result_file import RobustnessFile
from rvmsim.testing.stations import write_capture, write_inputs
from rvmsim.tune.markets_file import MarketsFile
from rvmsim.validate.result_file import ValidationFile, ValidationSummaryFile

from ..cli_runner import run_in_process
from .conftest import SMALL_SCENE
from .harness import Case, check_case, folder_digest, run_case

#: Nested past any limit, and past Python's recursion limit.
DEEP = "[" * 100_000 + "]" * 100_000
#: A validation of one capture, as ``rvmsim validate`` writes it (the keys signoff reads).
VALIDATION = {"scene": "Vehicle A", "capture": "car.png", "passed": True, "image_size": [320, 240],
              "checks": [{"name": "landmark RMS", "value": 0.5, "limit": 2.0, "hint": "",
                          "passed": True}]}
SUMMARY = [{"capture": "car.png", "verdict": "PASS", "step_failed": "", "error": None}]


@pytest.fixture(scope="module")
def made(finished_run: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The finished small run, judged in a market (best/markets.json), a robustness run of
    its rank 1 (4 samples) and an EOL run of one car: each written by its command."""
    root = tmp_path_factory.mktemp("results")
    shutil.copy(finished_run / SMALL_SCENE, root / SMALL_SCENE)
    shutil.copytree(finished_run / "run", root / "run")
    out = run_in_process(["robustness", SMALL_SCENE, "--params", "run/top/rank_1.yaml",
                          "--samples", "4", "--scales", "1", "--workers", "1", "--out", "rob",
                          "--no-progress"], cwd=root)
    assert out.code in (0, 1), out.stderr
    station, _ = write_inputs(root / "eol_in")
    car = write_capture(root / "eol_in" / "car.png", Deviation())
    out = run_in_process(["eol", str(station), "--params", "run/top/rank_1.yaml", "--capture",
                          str(car), "--out", "eol", "--no-progress"], cwd=root)
    assert out.code in (0, 1), out.stderr
    out = run_in_process(["report", "run", "--markets", "unr158", "--no-progress"], cwd=root)
    assert out.code in (0, 1), out.stderr
    assert (root / "run" / "best" / "markets.json").is_file(), out.stderr
    for name, doc in (("val", VALIDATION), ("vals", SUMMARY)):
        (root / name).mkdir()
        (root / name / ("validation.json" if name == "val" else "summary.json")).write_text(
            json.dumps(doc))
    return root


def test_what_the_writers_write_validates(made: Path) -> None:
    """The schemas describe what the commands write (else a good file would be refused)."""
    RobustnessFile.model_validate(json.loads((made / "rob" / "robustness.json").read_text()))
    EolFile.model_validate(json.loads((made / "eol" / "eol.json").read_text()))
    MarketsFile.model_validate(json.loads((made / "run" / "best" / "markets.json").read_text()))
    ValidationFile.model_validate(VALIDATION)
    ValidationSummaryFile.model_validate(SUMMARY)


Edit = Callable[[Any], Any]


def _edit(file: str, change: Edit | str) -> Callable[[Path], None]:
    """A setup replacing ``file`` (below the case folder) by ``change`` of its document
    (a function of the document) or by the text ``change``."""
    def setup(folder: Path) -> None:
        path = folder / file
        if isinstance(change, str):
            path.write_text(change)
        else:
            path.write_text(json.dumps(change(json.loads(path.read_text()))))
    return setup


def _set(doc: Any, dotted: str, value: Any) -> Any:
    """``doc`` with the key ``dotted`` (list indices as numbers) set to ``value``."""
    *head, last = [int(p) if p.isdigit() else p for p in dotted.split(".")]
    node = doc
    for part in head:
        node = node[part]
    node[last] = value
    return doc


def _failing_sample(doc: Any) -> Any:
    doc["samples"][0].update(passed=False, yaw_deg="left")
    return doc


SIGN = ("signoff", "run", "--out", "so", "--no-pdf", "--allow-other-setting")
ROB = (*SIGN, "--robustness", "rob")
EOL = (*SIGN, "--eol", "eol")
VAL = (*SIGN, "--validation", "val")
VALS = (*SIGN, "--validation", "vals")
RJ = "rob/robustness.json"
EJ = "eol/eol.json"
MJ = "run/best/markets.json"

CASES = [
    # nested past the limits
    Case("robustness.json nested", ROB, (RJ, "nested"), _edit(RJ, DEEP), keep=("rob",)),
    Case("eol.json nested", EOL, (EJ, "nested"), _edit(EJ, DEEP), keep=("eol",)),
    Case("validation.json nested", VAL, ("val/validation.json", "nested"),
         _edit("val/validation.json", DEEP), keep=("val",)),
    Case("summary.json nested", VALS, ("vals/summary.json", "nested"),
         _edit("vals/summary.json", DEEP), keep=("vals",)),
    Case("markets.json nested", ("report", "run", "--no-progress"), (MJ, "nested"),
         _edit(MJ, DEEP), keep=("run",)),
    Case("run.json nested, resumed", ("tune", "--resume", "run", "--no-progress"),
         ("run/run.json", "nested"), _edit("run/run.json", DEEP), keep=("run",)),
    Case("robustness.json nested 65 deep", ROB, (RJ, "64 levels"),
         _edit(RJ, lambda d: {**d, "extra": json.loads("[" * 65 + "]" * 65)}), keep=("rob",)),
    # over the size limit
    Case("robustness.json over the size limit", ROB, (RJ, "RVMSIM_MAX_JSON_BYTES"),
         keep=("rob",), env={"RVMSIM_MAX_JSON_BYTES": "1000"}),
    # wrong types behind keys that exist (the issue's, and more)
    Case("robustness failure_rate text", ROB, (RJ, "ecs[2].failure_rate", "not a number"),
         _edit(RJ, lambda d: _set(d, "ecs.2.failure_rate", "lots")), keep=("rob",)),
    Case("robustness failing sample yaw text", ROB, (RJ, "samples[0].yaw_deg"),
         _edit(RJ, _failing_sample), keep=("rob",)),
    Case("robustness yield_by_load a number", ROB, (RJ, "yield_by_load.curb", "not an object"),
         _edit(RJ, lambda d: _set(d, "yield_by_load", {"curb": 5})), keep=("rob",)),
    Case("robustness variation.mount a list", ROB, (RJ, "variation.mount", "not an object"),
         _edit(RJ, lambda d: _set(d, "variation.mount", [1, 2])), keep=("rob",)),
    Case("robustness ci95 of three", ROB, (RJ, "ci95"),
         _edit(RJ, lambda d: _set(d, "ci95", [0.1, 0.2, 0.3])), keep=("rob",)),
    Case("robustness samples an object", ROB, (RJ, "samples", "not a list"),
         _edit(RJ, lambda d: _set(d, "samples", {"0": 1})), keep=("rob",)),
    Case("robustness recorded input path with NUL", ROB, (RJ, "inputs.files[0].path", "NUL"),
         _edit(RJ, lambda d: _set(d, "inputs.files.0.path", "a\x00b.yaml")), keep=("rob",)),
    Case("eol reasons a number", EOL, (EJ, "results[0].reasons", "not a list"),
         _edit(EJ, lambda d: _set(d, "results.0.reasons", 5)), keep=("eol",)),
    Case("eol cars text", EOL, (EJ, "cars", "not a whole number"),
         _edit(EJ, lambda d: _set(d, "cars", "two")), keep=("eol",)),
    Case("eol verdict a list", EOL, (EJ, "results[0].verdict", "not text"),
         _edit(EJ, lambda d: _set(d, "results.0.verdict", ["PASS"])), keep=("eol",)),
    Case("validation check value text", VAL, ("val/validation.json", "checks[0].value"),
         _edit("val/validation.json", lambda d: _set(d, "checks.0.value", "big")),
         keep=("val",)),
    Case("validation passed text", VAL, ("val/validation.json", "passed", "true or false"),
         _edit("val/validation.json", lambda d: _set(d, "passed", "yes")), keep=("val",)),
    Case("summary verdict a number", VALS, ("vals/summary.json", "[0].verdict"),
         _edit("vals/summary.json", lambda d: _set(d, "0.verdict", 5)), keep=("vals",)),
    Case("markets passed text", ("report", "run", "--no-progress"),
         (MJ, "markets[0].passed", "true or false"),
         _edit(MJ, lambda d: _set(d, "markets.0.passed", "yes")), keep=("run",)),
    Case("markets ec_score text", ("report", "run", "--no-progress"),
         (MJ, "markets[0].ec_score", "not a number"),
         _edit(MJ, lambda d: _set(d, "markets.0.ec_score", "high")), keep=("run",)),
    Case("markets binding a list", ("report", "run", "--no-progress"),
         (MJ, "markets[0].binding"),
         _edit(MJ, lambda d: _set(d, "markets.0.binding", [1])), keep=("run",)),
]


@pytest.fixture
def folder(made: Path, tmp_path: Path) -> Path:
    """A copy of the made folders (the render cache stays shared)."""
    for name in ("run", "rob", "eol", "val", "vals"):
        shutil.copytree(made / name, tmp_path / name)
    shutil.copy(made / SMALL_SCENE, tmp_path / SMALL_SCENE)
    return tmp_path


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_a_bad_result_file_is_one_line_and_exit_2(case: Case, folder: Path) -> None:
    check_case(case, folder)
    assert not (folder / "so").exists()


def test_status_says_run_json_is_nested_and_goes_on(folder: Path) -> None:
    """``status`` reads run.json only to say where it disagrees with the store: one line
    naming it, the run's status still printed, nothing changed."""
    (folder / "run" / "run.json").write_text(DEEP)
    before = folder_digest(folder / "run")
    out = run_case(Case("status", ("status", "run"), ()), folder)
    assert "Traceback" not in out.stderr, out.stderr
    assert out.code == 0, out.stderr
    [line] = [ln for ln in out.stdout.splitlines() if "run.json" in ln]
    assert "nested more than" in line
    assert folder_digest(folder / "run") == before


def test_a_good_file_still_signs(folder: Path) -> None:
    """The schemas refuse nothing the commands wrote: the sign-off of all of them is made."""
    out = run_case(Case("ok", (*SIGN, "--robustness", "rob", "--eol", "eol", "--validation",
                                "val"), ()), folder)
    assert out.code in (0, 1), out.stderr
    assert (folder / "so" / "signoff.html").is_file()

