"""tools/compare_sweeps.py on two sweep.json files: only the changed points, old files
without verdicts read as pass / not found."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

TOOL = Path(__file__).resolve().parents[2] / "tools" / "compare_sweeps.py"


def _sweep(folder: Path, points: list[dict]) -> Path:
    folder.mkdir()
    (folder / "sweep.json").write_text(json.dumps({
        "axes": [["camera_height_m", [1.0, 1.1]], ["pitch_deg", [25]]],
        "points": [{"index": i, "values": {"camera_height_m": h, "pitch_deg": 25}, **p}
                   for i, (h, p) in enumerate(zip((1.0, 1.1), points))]}))
    return folder


def test_changed_points_only(tmp_path):
    # Before: a sweep.json from before verdicts (no "verdict" key).
    before = _sweep(tmp_path / "before", [
        {"score": 0.6, "passed": True, "limiting_ec": None, "evaluations": 2000},
        {"score": 1e-9, "passed": False, "limiting_ec": "2-2", "evaluations": 2000}])
    after = _sweep(tmp_path / "after", [
        {"score": 0.6, "passed": True, "limiting_ec": None, "evaluations": 2000,
         "verdict": "pass"},
        {"score": 0.8, "passed": True, "limiting_ec": None, "evaluations": 6000,
         "verdict": "pass"}])
    out = subprocess.run([sys.executable, str(TOOL), str(before), str(after)],
                         capture_output=True, text=True, check=True).stdout
    rows = [line for line in out.splitlines() if line.startswith("| 1.")]
    assert rows == ["| 1.1 | 25 | not found 1e-09, limited by 2-2 | pass 0.8 | 2000 | 6000 |"]
    assert "before: 1 pass, 1 not found, 0 infeasible" in out
    assert "after: 2 pass, 0 not found, 0 infeasible" in out
    every = subprocess.run([sys.executable, str(TOOL), str(before), str(after), "--all"],
                           capture_output=True, text=True, check=True).stdout
    assert len([line for line in every.splitlines() if line.startswith("| 1.")]) == 2
