"""`rvmsim tune` with a customer EC from a plugin file named in the criteria file, with two
worker processes (the ECs reach the spawned workers by reference to the plugin file)."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.criteria import EC_IDS

from ..cli_runner import run_in_child, tune_status
from ..conftest import SCENES

EXAMPLE = Path(__file__).with_name("ec_plugin_example.py")
EC = "acme-board-centred"


def _board_centre_offset(labels: np.ndarray) -> float | None:
    """The example EC computed independently: from the board's columns in the label image."""
    cols = np.nonzero((labels == L.BOARD).any(axis=0))[0]
    if cols.size == 0:
        return None
    w = labels.shape[1]
    return 100.0 * abs((cols.min() + cols.max()) / 2.0 - (w - 1) / 2.0) / w


def test_tune_with_workers_stores_a_plugin_ec(tmp_path, monkeypatch):
    # The plugin lives next to the criteria file, as a customer keeps it.
    crit_dir = tmp_path / "acme"
    crit_dir.mkdir()
    shutil.copy(EXAMPLE, crit_dir / "board_centred.py")
    crit = crit_dir / "criteria.yaml"
    crit.write_text("name: ACME\nplugins: [board_centred.py]\n"
                    f"criteria:\n  {EC}: {{range: [null, 4], tolerance: 4}}\n")
    cfg = tmp_path / "t.yaml"
    cfg.write_text("tuned: [zoom, adv_v_shift, adv_h_shift]\noutput: {size: [320, 180]}\n"
                   "top_m: 3\nbatch: 24\n")
    env = {"RVMSIM_CACHE": str(tmp_path / "cache")}
    run = tmp_path / "run"
    # In a child: a plugin file, once imported, stays cached in the process that read it.
    res = run_in_child(["tune", SCENES / "vehicle_a.yaml", "--out", run, "--config", cfg,
                        "--criteria", crit, "--strategy", "random", "--budget", "48",
                        "--workers", "2", "--seed", "3", "--no-progress"],
                       env=env, cwd=tmp_path, timeout_s=900)
    assert res.code == tune_status(tmp_path / run), res.stderr

    from rvmsim.criteria import load_criteria
    from rvmsim.isp import OutputSpec, process
    from rvmsim.render import cached_render
    from rvmsim.scene import load_scene
    from rvmsim.runs import RunStore

    store = RunStore(run / "run.sqlite")
    trials = store.trials()
    best = store.top(1)[0]
    store.close()
    # Every candidate carries the plugin EC after the paper's eleven, in the criteria's order.
    assert len(trials) == 48
    for t in trials:
        assert tuple(t.ecs) == EC_IDS + (EC,)
    measured = [t.ecs[EC].value for t in trials if t.ecs[EC].value is not None]
    assert len(measured) >= 10 and len(set(measured)) > 5
    # The stored value of the best candidate is the EC of its RVM labels, computed here
    # independently of the plugin.
    monkeypatch.setenv("RVMSIM_CACHE", str(tmp_path / "cache"))
    images, _ = cached_render(load_scene(SCENES / "vehicle_a.yaml"))

    def offset_at(size: tuple[int, int]) -> float | None:
        _, labels = process(None, images.labels, best.params, OutputSpec(*size))
        assert labels is not None
        return _board_centre_offset(labels)

    # The search measured at 320 × 180; what could pass was judged again at 1280 × 720.
    at_search, at_record = offset_at((320, 180)), offset_at((1280, 720))
    assert at_record is not None
    sig = load_criteria(crit).items[EC].sigmoid
    assert sig is not None
    # (the value of record when the whole candidate could pass, else the search's)
    expected = best.ecs[EC].value
    assert expected is not None and (math.isclose(expected, at_record, abs_tol=1e-9) or (
        not best.passed and at_search is not None
        and math.isclose(expected, at_search, abs_tol=1e-9)))
    # Its stored score is the sigmoid the criteria file gives it.
    assert best.ecs[EC].score == pytest.approx(sig(expected), rel=1e-12)
    assert best.ecs[EC].passed == (expected <= 4)
    # The best candidate's written results (at the RVM image of record) name the EC too.
    doc = json.loads((run / "best" / "ec.json").read_text())
    item = next(e for e in doc["ecs"] if e["id"] == EC)
    assert doc["judged_at"] == [1280, 720]
    assert math.isclose(item["value"], at_record, abs_tol=1e-9)
