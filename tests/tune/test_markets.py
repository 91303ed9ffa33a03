"""One setting for several markets (`rvmsim tune SCENE --markets …`): conflicts between
markets and ECs no setting can pass are named, with exit 1; a killed markets run resumes to
the unbroken result (small real renders, real searches)."""

from __future__ import annotations

import json
import signal
import sqlite3

import numpy as np
import pytest
import yaml

from rvmsim import labels as L
from rvmsim.criteria import load_criteria
from rvmsim.render import cached_render
from rvmsim.scene import bundled_site, load_scene, site_scene

from ..cli_runner import run_in_process, start_in_child
from .common import stored_trials, wait_for_trials
from rvmsim.testing.scenes import write_small_scene

#: The RVM image of record of the small scenes (their search size: quick).
DISPLAY = {"display": {"rvm_image_px": [320, 180]}}


@pytest.fixture(scope="module")
def scene(cache, tmp_path_factory):
    return write_small_scene(tmp_path_factory.mktemp("scene"), "a", edit=DISPLAY)


def _criteria(folder, name, low, high):
    """A criteria file judging EC 3-2 (guideline 3's height, %) alone in [low, high]."""
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump({"name": name, "ecs": ["3-2"],
                                    "criteria": {"3-2": {"range": [low, high],
                                                         "tolerance": 2.0}}}))
    return path


def test_markets_that_pass_alone_but_never_together_exit_1_naming_the_conflict(scene, tmp_path):
    """Two markets at the FMVSS site whose ranges of EC 3-2 do not overlap: a random search
    finds settings passing each, none passing both; the command says so and exits 1."""
    low = _criteria(tmp_path, "low", 20.0, 40.0)
    high = _criteria(tmp_path, "high", 60.0, 80.0)
    run = tmp_path / "run"
    out = run_in_process(["tune", scene, "--markets", f"fmvss111:{low},fmvss111:{high}",
                          "--strategy", "random", "--budget", "300", "--out", run,
                          "--no-progress", "--workers", "1"])
    assert out.code == 1, out.stderr
    doc = json.loads((run / "best" / "markets.json").read_text())
    assert not doc["passed"] and len(doc["markets"]) == 2
    assert all(n > 0 for n in doc["passes_alone"].values()), doc["passes_alone"]
    (conflict,) = doc["conflicts"]
    assert {e["ec"] for e in conflict["ecs"]} == {"3-2"}
    # in every trial where one market passes, the other's 3-2 fails
    assert all(e["fails_in"] == e["of"] for e in conflict["ecs"])
    assert "each pass alone but never together (conflicting ECs)" in out.stdout
    assert f"where fmvss111:{low} passes, fmvss111:{high} fails 3-2" in out.stdout
    assert {e["member"] for e in conflict["ecs"]} == {f"fmvss111:{low}", f"fmvss111:{high}"}
    # the store agrees: no trial passes both, some pass each
    con = sqlite3.connect(run / "run.sqlite")
    both = con.execute("SELECT COUNT(*) FROM (SELECT idx FROM members WHERE passed = 1 "
                       "GROUP BY idx HAVING COUNT(*) = 2)").fetchone()[0]
    con.close()
    assert both == 0
    status = run_in_process(["status", run])
    assert status.code == 0 and "one setting for 2 markets" in status.stdout


def _hidden_row2_site(folder):
    """UN R158's site with row 2 moved right behind the bumper and shortened: the bumper
    hides it from the camera whatever the ISP does."""
    doc = bundled_site("unr158").model_dump(mode="json", exclude_none=True)
    doc["rows"][1].update({"z": 0.2, "height": 0.3})
    for row in doc["rows"]:
        row.pop("names", None)
    path = folder / "hidden_row2.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def test_an_ec_no_setting_can_pass_is_named_from_the_fisheye_labels(scene, tmp_path):
    site = _hidden_row2_site(tmp_path)
    run = tmp_path / "run"
    out = run_in_process(["tune", scene, "--markets", f"{site}:unr158", "--strategy", "random",
                          "--budget", "40", "--out", run, "--no-progress", "--workers", "1"])
    assert out.code == 1, out.stderr
    doc = json.loads((run / "best" / "markets.json").read_text())
    reasons = [f for f in doc["infeasible"] if f["ec"] == "R158-2"]
    assert reasons and all("hidden behind the bumper" in f["reason"] for f in reasons)
    assert "(no setting can pass it)" in out.stdout
    # independently: where the camera model projects the middle of each row-2 cylinder's
    # front, the rendered label image shows the bumper
    at_site = site_scene(load_scene(scene), _load(site))
    images, _ = cached_render(at_site)
    cam = images.camera
    for obj in (o for o in at_site.test_site.site_objects if o.row == "row2"):
        toward = cam.position[[0, 2]] - (obj.x, obj.z)
        front = np.array([obj.x, 0.0, obj.z]) + obj.radius * np.insert(
            toward / np.linalg.norm(toward), 1, 0.0)
        front[1] = -obj.height / 2
        uv, ok = cam.project(front[None])
        assert ok[0]
        u, v = np.round(uv[0]).astype(int)
        assert images.labels[v, u] == L.BUMPER


def _load(path):
    from rvmsim.scene import load_site

    return load_site(path)


@pytest.mark.slow  # the resume path is tune's, tested in test_run.py
def test_a_killed_markets_run_resumes_to_the_unbroken_result(scene, tmp_path):
    def cmd(out):
        return ["tune", scene, "--markets", "fmvss111,unr158", "--budget", "600", "--out", out,
                "--no-progress", "--workers", "1"]

    clean = run_in_process(cmd(tmp_path / "clean"))
    assert clean.code in (0, 1), clean.stderr
    run = tmp_path / "killed"
    proc = start_in_child(cmd(run))
    db = run / "run.sqlite"
    wait_for_trials(db, 150)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    con = sqlite3.connect(db)
    stored = con.execute("SELECT COUNT(*) FROM trials").fetchone()[0]
    con.close()
    assert 150 <= stored < 600, stored
    resumed = run_in_process(["tune", "--resume", run, "--no-progress", "--workers", "1"])
    assert resumed.code == clean.code, resumed.stderr
    assert "replayed" in resumed.stdout

    assert stored_trials(run) == stored_trials(tmp_path / "clean")
    markets = json.loads((run / "run.json").read_text())["markets"]
    assert markets == ["fmvss111", "unr158"]
    # the R158 criteria were really applied to the second member
    ecs = json.loads(sqlite3.connect(run / "run.sqlite").execute(
        "SELECT ec FROM members WHERE member = 1 LIMIT 1").fetchone()[0])
    assert set(ecs) == {ec.id for ec in load_criteria("unr158").ecs}
