"""The exit-code contract of the commands that judge (docs/errors.md): each one run once each
way, 0 when everything it judged passes, 1 when something fails, 2 on an error (one line).

One small scene and two criteria files judging EC 3-2 (guideline 3's height) alone: one
whose range every setting meets, one no setting can meet.  So the same inputs pass or fail
by the criteria alone, and every command is judged on what it actually measured."""

from __future__ import annotations

import re
from pathlib import Path

import cv2
import pytest

from rvmsim.compensation import Deviation
from rvmsim.testing.captures import perturbed, write_scene
from rvmsim.testing.scenes import write_small_scene
from rvmsim.testing.stations import write_capture, write_inputs

from .cli_runner import Outcome, run_in_process, tune_status
from .tune.test_markets import _criteria

ROOT = Path(__file__).resolve().parents[1]
#: The judging commands of docs/errors.md's table.
JUDGING = ("evaluate", "tune", "robustness", "signoff", "validate", "eol")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The scene, the two criteria files, a run tuned with each, a capture of a board scene
    (turned 0.8° in yaw) and an EOL station's inputs with one good car."""
    root = tmp_path_factory.mktemp("exit")
    scene = write_small_scene(root, "a", edit={"display": {"rvm_image_px": [320, 180]}})
    got = {"root": root, "scene": scene, "open": _criteria(root, "open", 0.0, 100.0),
           "closed": _criteria(root, "closed", 99.0, 100.0)}
    _, cap = perturbed()
    got["capture"] = root / "capture.png"
    cv2.imwrite(str(got["capture"]), cap[..., ::-1])
    got["board_scene"] = write_scene(root)
    got["eol_scene"], got["eol_params"] = (Path(p) for p in write_inputs(root / "eol"))
    got["car"] = write_capture(root / "eol" / "car.png", Deviation(2, -3, 4, 0.5, -0.4, 0.3))
    return got


def _run(inputs: dict[str, Path], *args: object) -> Outcome:
    return run_in_process([str(a) for a in args], cwd=inputs["root"])


def _tuned(inputs: dict[str, Path], which: str) -> Path:
    """The run tuned with criteria ``which`` (once per module; its own exit is checked)."""
    run = inputs["root"] / f"run_{which}"
    if not run.exists():
        res = _run(inputs, "tune", inputs["scene"], "--criteria", inputs[which], "--strategy",
                   "random", "--budget", "20", "--workers", "1", "--out", run, "--no-progress")
        assert res.code == tune_status(run) == (0 if which == "open" else 1), res.stdout
    return run


def _case(inputs: dict[str, Path], command: str, outcome: str) -> Outcome:
    """``command`` run so that it should end ``outcome`` (pass, fail, error)."""
    which = "open" if outcome == "pass" else "closed"
    root = inputs["root"]
    missing = root / "no such file.yaml"
    if command == "tune":
        scene = inputs["scene"] if outcome != "error" else missing
        return _run(inputs, "tune", scene, "--criteria", inputs[which], "--strategy",
                    "random", "--budget", "20", "--workers", "1", "--out",
                    root / f"tune_{outcome}", "--no-progress")
    params = _tuned(inputs, "open") / "top" / "rank_1.yaml"
    if command == "evaluate":
        return _run(inputs, "evaluate", inputs["scene"], "--params",
                    params if outcome != "error" else missing, "--criteria", inputs[which],
                    "--out", root / f"ev_{outcome}", "--no-progress")
    if command == "robustness":
        return _run(inputs, "robustness", inputs["scene"], "--params",
                    params if outcome != "error" else missing, "--samples", "2", "--scales",
                    "1", "--criteria",
                    inputs[which], "--min-yield", "0.5", "--workers", "1", "--out",
                    root / f"rob_{outcome}", "--no-progress")
    if command == "signoff":
        run = _tuned(inputs, which) if outcome != "error" else root / "no such run"
        return _run(inputs, "signoff", run, "--no-pdf", "--out", root / f"so_{outcome}",
                    "--no-progress")
    if command == "validate":
        capture = inputs["capture"] if outcome != "error" else root / "no such capture.png"
        return _run(inputs, "validate", inputs["board_scene"], "--capture", capture,
                    "--max-angle-deg", "1.0" if outcome == "pass" else "0.5",
                    "--out", root / f"val_{outcome}", "--no-progress")
    assert command == "eol"
    car = inputs["car"] if outcome != "error" else root / "no such car.png"
    return _run(inputs, "eol", inputs["eol_scene"], "--params", inputs["eol_params"],
                "--capture", car, "--criteria", inputs[which], "--out", root / f"eol_{outcome}",
                "--no-progress")


def test_the_table_lists_every_judging_command_with_its_three_codes():
    text = (ROOT / "docs" / "errors.md").read_text(encoding="utf-8")
    rows = {m.group(1): m.group(0) for m in re.finditer(r"^\| `(\w+)` \|.*$", text, re.M)}
    for command in JUDGING:
        cells = rows[command].split(" | ")
        assert len(cells) >= 4 and all(c.strip(" –") for c in cells[1:4]), rows[command]


@pytest.mark.parametrize("outcome,code", [("pass", 0), ("fail", 1), ("error", 2)])
@pytest.mark.parametrize("command", JUDGING)
def test_a_judging_command_exits_by_what_it_judged(inputs, command, outcome, code):
    res = _case(inputs, command, outcome)
    assert res.code == code, (res.stdout[-2000:], res.stderr)
    if code == 2:
        assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr
        assert res.stderr.startswith("rvmsim: error: ")
    else:
        assert "Traceback" not in res.stderr
