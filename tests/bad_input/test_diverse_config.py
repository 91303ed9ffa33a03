"""Bad input to the diverse top-M (issue #17, item 1): the tuning config's ``diverse``
section, the ``--min-distance`` option of status and select, and a run's recorded search
space or diverse settings that cannot be read; each one stderr line naming the key."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest

from .conftest import SMALL_SCENE
from .harness import Case, check_case

T = "t.yaml"
TUNE = ("tune", SMALL_SCENE, "--config", T, "--out", "new", "--strategy", "random",
        "--budget", "4", "--workers", "1", "--no-progress")
DB = "run/run.sqlite"
K = ("run",)


def _file(text: str):
    return lambda folder: (folder / T).write_text(text)


def _meta(key: str, value: str):
    """The run's meta ``key`` set to the raw text ``value``."""
    def setup(folder: Path) -> None:
        con = sqlite3.connect(folder / DB)
        with con:
            con.execute("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)", (key, value))
        con.close()
    return setup


def _config(edit: dict):
    """The run's stored tuning config with ``edit`` merged in."""
    def setup(folder: Path) -> None:
        con = sqlite3.connect(folder / DB)
        (text,) = con.execute("SELECT value FROM meta WHERE key = 'config'").fetchone()
        with con:
            con.execute("UPDATE meta SET value = ? WHERE key = 'config'",
                        (json.dumps({**json.loads(text), **edit}),))
        con.close()
    return setup


#: (case id, config text, key named)
FILES = [
    ("min-distance-zero", "diverse: {min_distance: 0}\n", "diverse.min_distance"),
    ("min-distance-negative", "diverse: {min_distance: -0.1}\n", "diverse.min_distance"),
    ("min-distance-above-one", "diverse: {min_distance: 2}\n", "diverse.min_distance"),
    ("min-distance-nan", "diverse: {min_distance: .nan}\n", "diverse.min_distance"),
    ("min-distance-text", "diverse: {min_distance: far}\n", "diverse.min_distance"),
    ("m-zero", "diverse: {m: 0}\n", "diverse.m"),
    ("m-400-digits", f"diverse: {{m: {'9' * 400}}}\n", "diverse.m"),
    ("m-fraction", "diverse: {m: 2.5}\n", "diverse.m"),
    ("tolerance-one", "diverse: {score_tolerance: 1}\n", "diverse.score_tolerance"),
    ("tolerance-negative", "diverse: {score_tolerance: -0.01}\n", "diverse.score_tolerance"),
    ("tolerance-inf", "diverse: {score_tolerance: .inf}\n", "diverse.score_tolerance"),
    ("unknown-key", "diverse: {spread: 3}\n", "diverse.spread"),
    ("not-a-mapping", "diverse: 5\n", "diverse"),
]
CASES = [Case(f"diverse-config-{i}", TUNE, (T, key), _file(text))
         for i, text, key in FILES]
CASES += [
    Case("diverse-status-min-distance-zero", ("status", "run", "--min-distance", "0"),
         ("--min-distance",), None, K),
    Case("diverse-status-min-distance-nan", ("status", "run", "--min-distance", "nan"),
         ("--min-distance",), None, K),
    Case("diverse-select-min-distance-above-one", ("select", "run", "--min-distance", "1.5"),
         ("--min-distance",), None, K),
    Case("diverse-select-by-score-with-a-value", ("select", "run", "--by-score=yes"),
         ("--by-score",), None, K),
    Case("diverse-select-space-junk", ("select", "run"), ("run.sqlite", "space"),
         _meta("space", '{"ranges": [{"name": "zoom"}], "base": {}}'), K),
    Case("diverse-select-space-not-json", ("select", "run"), ("run.sqlite", "space"),
         _meta("space", "{ranges"), K),
    Case("diverse-report-space-junk", ("report", "run"), ("run.sqlite", "space"),
         _meta("space", '"here"'), K),
    Case("diverse-select-stored-min-distance", ("select", "run"),
         ("run.sqlite", "settings", "min_distance"), _config({"diverse": {"min_distance": -1}}),
         K),
    Case("diverse-select-rank-beyond-the-list", ("select", "run", "--rank", "41"),
         ("run", "rank 41", "--by-score"), None, K),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_diverse_input(case, case_dir):
    check_case(case, case_dir)
