"""batch.tasks: `rvmsim batch` as a library call (local runs, the summary table and files)
and on a Dask LocalCluster (run folders written here, usable by status and report)."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest

from rvmsim.batch import (BatchSettings, SceneRun, run_batch, summary_ec_ids, summary_table,
                          write_summary)
from rvmsim.criteria import default_criteria
from rvmsim.search import TuningConfig

from ..cli_runner import run_in_child, run_in_process
from rvmsim.testing.scenes import small_scene_text


def test_local_batch_runs_good_scenes_and_reports_bad_ones(tmp_path):
    good = tmp_path / "small_b.yaml"
    good.write_text(small_scene_text("b", variation=None))
    broken = tmp_path / "broken.yaml"
    broken.write_text("name: x\ncamera: {\n")
    settings = BatchSettings("random", TuningConfig.model_validate(
        {"tuned": ["zoom", "adv_v_shift"], "output": {"size": [320, 180]}, "batch": 20}),
        budget=40)
    started: list[tuple[int, Path]] = []
    out = tmp_path / "runs"
    runs = list(run_batch([good, broken], out, settings,
                          on_start=lambda k, s: started.append((k, s))))
    assert started == [(1, good), (2, broken)]
    ok, bad = runs
    assert ok.ok and ok.run_dir == out / "small_b" and ok.evaluations == 40
    assert (ok.run_dir / "run.sqlite").is_file()
    ec_doc = json.loads((ok.run_dir / "best" / "ec.json").read_text())
    assert ok.vehicle == ec_doc["vehicle"] and ok.ec_score == ec_doc["ec_score"]
    assert list(ok.ecs) == [e["id"] for e in ec_doc["ecs"]] == list(default_criteria().ids)
    assert not bad.ok and "broken.yaml" in bad.error and bad.run_dir is None
    ids = summary_ec_ids(runs, None)
    table = summary_table(runs, ids)
    header, row_ok, row_bad = table.splitlines()
    assert header.split()[3:3 + len(ids)] == list(ids)
    assert row_ok.split()[-1].endswith("s") and "error" in row_bad
    write_summary(out, runs, table)
    rows = json.loads((out / "summary.json").read_text())
    assert rows[0] == ok.summary_row() and rows[0]["run"] == str(ok.run_dir)
    assert rows[1] == {"scene": str(broken), "error": bad.error}
    assert (out / "summary.txt").read_text() == table + "\n"


def test_summary_columns_are_the_ecs_of_the_runs():
    """The EC columns come from the runs' own ECs (a customer's selection), not a global list;
    with no finished run, from the criteria."""
    runs = [SceneRun(Path("a.yaml"), Path("runs/a"), vehicle="A", ec_score=0.5, passed=False,
                     ecs={"1-1": True, "3-2": False}, evaluations=10, seconds=1.0),
            SceneRun.failed(Path("b.yaml"), "b.yaml: broken")]
    assert summary_ec_ids(runs, None) == ("1-1", "3-2")
    lines = summary_table(runs, summary_ec_ids(runs, None)).splitlines()
    assert lines[0].split() == ["vehicle", "EC", "score", "1-1", "3-2", "evals", "time"]
    assert lines[1].split() == ["A", "0.5", "ok", "X", "10", "1.0s"]
    assert summary_ec_ids(runs[1:], None) == default_criteria().ids


def test_unwritable_summary_is_a_one_line_error(tmp_path):
    from rvmsim.errors import RvmsimError

    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(RvmsimError, match=f"{blocker}: "):
        write_summary(blocker, [], "table")


def test_batch_on_the_dask_cluster_writes_normal_run_folders(cluster, tmp_path):
    """`rvmsim batch --scheduler`: one task per scene on the cluster; the run folders land
    here with this machine's scene path and fingerprint, so status and report work on them."""
    c, _ = cluster
    scenes = []
    for letter in "ab":
        p = tmp_path / f"small_{letter}.yaml"
        p.write_text(small_scene_text(letter, variation=None))
        scenes.append(p)
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text("output: {size: [320, 180]}\n")
    out = tmp_path / "runs"
    # In a child: a Dask client's threads would outlive the command in this process.
    res = run_in_child(["batch", *scenes, "--out", out, "--strategy", "cmaes", "--budget",
                        "150", "--config", cfg, "--scheduler", c.scheduler_address,
                        "--no-progress"])
    assert res.code in (0, 1), res.stderr  # 1: some vehicle failed an EC, not an error
    rows = json.loads((out / "summary.json").read_text())
    assert [Path(r["scene"]).name for r in rows if "error" not in r] and len(rows) == 2
    for p in scenes:
        run = out / p.stem
        meta = json.loads((run / "run.json").read_text())
        assert meta["scene"] == str(p.resolve())
        row = next(r for r in rows if Path(r["scene"]).name == p.name)
        with sqlite3.connect(run / "run.sqlite") as db:
            n = db.execute("SELECT COUNT(*) FROM trials").fetchone()[0]
        assert n == row["evaluations"] and 150 <= n < 150 + 12  # CMA-ES ends a generation
        assert (run / "best" / "ec.json").is_file()
        rep = run_in_process(["report", run])
        assert rep.code == 0, rep.stderr
        assert "changed since" not in (run / "report.html").read_text()
