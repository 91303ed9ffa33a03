"""rvmsim.report.validation: the summary of several captures (table, JSON, CSV, one page)."""

from __future__ import annotations

import csv
import json

import numpy as np

from rvmsim.report.validation import SUMMARY_COLUMNS, summary_table, write_validation_summary
from rvmsim.validate import CaptureOutcome, ValidationFailure, ValidationSettings, validate

from rvmsim.testing.captures import base


def _outcomes(tmp_path):
    sc, syn = base()
    ok = validate(sc, syn.color, ValidationSettings(rerender=False), synthetic=syn,
                  capture_name="own.png")
    noise = np.random.default_rng(0).integers(0, 255, syn.color.shape, np.uint8)
    try:
        validate(sc, noise, ValidationSettings(rerender=False), synthetic=syn,
                 capture_name="<noise>")
    except ValidationFailure as fail:
        bad = CaptureOutcome("<noise>", tmp_path / "noise", None, str(fail), fail.step,
                             fail.images)
    return [CaptureOutcome("own.png", tmp_path / "own", ok), bad]


def test_summary_has_one_row_per_capture_and_one_page(tmp_path):
    outcomes = _outcomes(tmp_path)
    paths = write_validation_summary(outcomes, tmp_path / "sum")
    assert [p.name for p in paths] == ["summary.json", "summary.csv", "validation.html"]
    rows = json.loads(paths[0].read_text())
    assert [r["verdict"] for r in rows] == ["PASS", "ERROR"]
    assert rows[0]["inliers"] == outcomes[0].result.n_inliers
    assert rows[1]["step_failed"] == "detection" and "step failed: detection" in rows[1]["error"]
    with paths[1].open() as f:
        table = list(csv.DictReader(f))
    assert tuple(table[0]) == SUMMARY_COLUMNS and table[1]["verdict"] == "ERROR"
    page = paths[2].read_text()
    assert "1 of 2 captures pass" in page and "&lt;noise&gt;" in page and "<noise>" not in page
    # The error's pictures are on the page too (overlay, edges, landmarks; the board's grid
    # the detector took for the board in the noise).
    assert page.count("<img") == len(outcomes[0].result.images) + len(outcomes[1].images)
    assert {"overlay", "edges", "landmarks"} <= set(outcomes[1].images)
    text = summary_table(outcomes).splitlines()
    assert len(text) == 3 and "PASS" in text[1] and "ERROR" in text[2] and "detection" in text[2]
