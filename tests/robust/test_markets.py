"""``rvmsim robustness --markets``: each variation sample judged at each market's site with
that market's criteria; the yield per market and over all markets."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from rvmsim import labels as L
from rvmsim.criteria import load_criteria
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.isp import IspParams, OutputSpec, params_to_dict
from rvmsim.render import render_fisheye
from rvmsim.robust import nominal_sample, refolder, sample_images, variation_from_scene
from rvmsim.scene import site_scene

from ..cli_runner import run_in_process
from rvmsim.testing.scenes import load_small_scene, write_small_scene
from .conftest import ANGLES_ONLY

OUTPUT = OutputSpec(640, 360)


def test_a_sample_at_a_site_keeps_its_site_objects():
    """The nominal sample of the scene at the R158 site, re-folded from its cube, shows the
    site's cylinders where a direct render of that scene does."""
    sc = site_scene(load_small_scene("a", 0.25, variation=ANGLES_ONLY), "unr158")
    objects = sc.test_site.site_objects
    assert objects
    direct = render_fisheye(sc).labels
    sample = nominal_sample(variation_from_scene(sc))
    folded = sample_images(sc, [sample], shared=refolder(sc, [sample]))[0].labels
    assert np.mean(folded == direct) >= 0.999
    shown = 0
    for k in range(len(objects)):
        body = L.site_object_labels(k)[0]
        n_direct, n_folded = int((direct == body).sum()), int((folded == body).sum())
        assert abs(n_folded - n_direct) <= max(2, 0.02 * n_direct), objects[k].name
        shown += n_direct > 0
    assert shown >= 2  # several cylinders are in the picture


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    """A quarter-size vehicle A (±1° on every angle), a setting that centres it (EC 2-1 in
    the middle of its range) and two markets whose failures have different drivers: EC 3-1
    (horizontal centring, driven by yaw and roll) at the FMVSS site, and R158-2 (row 2 whole) at the
    R158 site with its lower limit raised to the nominal car's value (so a car pitched up
    fails)."""
    root = tmp_path_factory.mktemp("markets_robustness")
    write_small_scene(root, "a", name="scene.yaml", variation=ANGLES_ONLY)
    sc = load_small_scene("a", 0.25, variation=ANGLES_ONLY)
    base = IspParams().for_input_scale(0.25)
    ev = CandidateEvaluator(render_fisheye(sc).labels, OUTPUT, load_criteria(None))
    shifts = np.arange(10.0, 25.0, 0.25)
    values = np.array([ev(dataclasses.replace(base, v_shift=float(s)))["2-1"].value or 0.0
                       for s in shifts])
    params = dataclasses.replace(base, v_shift=float(shifts[np.argmin(np.abs(values - 6))]))
    (root / "params.yaml").write_text(yaml.safe_dump(params_to_dict(params, OUTPUT)))
    (root / "centring.yaml").write_text(yaml.safe_dump({"name": "centring", "ecs": ["3-1"]}))
    r158 = site_scene(sc, "unr158")
    row2 = load_criteria("unr158")
    nominal = CandidateEvaluator(render_fisheye(r158).labels, OUTPUT, row2,
                                 scene=r158)(params)["R158-2"].value
    assert nominal is not None and 50 < nominal < 100
    (root / "row2.yaml").write_text(yaml.safe_dump({
        "name": "row 2 strict", "plugins": ["rvmsim.regulations.unr158.ecs"], "ecs": ["R158-2"],
        "criteria": {"R158-2": {"range": [float(nominal), None]}}}))
    markets = "fmvss111:centring.yaml,unr158:row2.yaml"
    args = ["robustness", "scene.yaml", "--params", "params.yaml", "--samples", "24",
            "--seed", "3", "--scales", "1", "--no-progress"]
    both = run_in_process([*args, "--markets", markets, "--out", "both"], cwd=root)
    alone = run_in_process([*args, "--markets", "fmvss111:centring.yaml", "--out", "alone"],
                           cwd=root)
    return root, both, alone


def test_the_yield_per_market_and_over_all_markets(case):
    root, both, _ = case
    assert both.code == 0, both.stderr
    doc = json.loads((root / "both" / "robustness.json").read_text())
    names = [m["market"] for m in doc["markets"]]
    assert names == ["fmvss111:centring.yaml", "unr158:row2.yaml"]
    samples = doc["samples"]
    assert len(samples) == doc["n"] == 24
    for m in doc["markets"]:  # each market's yield is that of its per-sample records
        flags = [s["markets"][m["market"]]["passed"] for s in samples]
        assert m["n_pass"] == sum(flags) and m["yield"] == pytest.approx(sum(flags) / 24)
        assert m["ci95"][0] <= m["yield"] <= m["ci95"][1]
    for s in samples:  # a car passes all markets when it passes every one
        assert s["passed"] == all(p["passed"] for p in s["markets"].values())
    all_pass = sum(s["passed"] for s in samples)
    assert doc["n_pass"] == all_pass and doc["yield"] == pytest.approx(all_pass / 24)
    assert doc["all_markets"]["yield"] == doc["yield"]
    assert doc["ci95"][0] <= doc["yield"] <= doc["ci95"][1]
    yields = [m["yield"] for m in doc["markets"]]
    assert all(doc["yield"] <= y for y in yields)
    # different drivers (yaw/roll, pitch): some cars fail only one market, so fewer pass both
    assert 0 < doc["yield"] < min(yields) and max(yields) < 1
    assert [m["limiting"]["ec"] for m in doc["markets"]] == ["3-1", "R158-2"]
    axes = {e["market"]: e["driver"] for e in doc["ecs"] if e["n_fail"]}
    assert axes["fmvss111:centring.yaml"].split("_")[0] in ("yaw", "roll")
    assert axes["unr158:row2.yaml"].startswith("pitch")


def test_one_market_gives_the_same_yield_as_in_several(case):
    root, both, alone = case
    assert alone.code == 0, alone.stderr
    a = json.loads((root / "alone" / "robustness.json").read_text())
    b = json.loads((root / "both" / "robustness.json").read_text())
    assert a["markets"][0]["n_pass"] == b["markets"][0]["n_pass"] == a["n_pass"]


def test_the_page_and_summary_have_a_row_per_market(case):
    root, both, _ = case
    html = (root / "both" / "robustness.html").read_text()
    assert html.count('market"><td><a href="#market-') == 2
    assert 'class="' in html and "all-markets" in html and "<script" not in html
    assert html.count("data:image/png;base64,") == 8  # per market: 2 plots, 2 frames
    lines = both.stdout.splitlines()
    assert lines[0].startswith("Vehicle A") and "yield over all markets" in lines[0]
    assert lines[1].split()[0] == "fmvss111:centring.yaml" and "limiting EC 3-1" in lines[1]
    assert lines[2].split()[0] == "unr158:row2.yaml" and "limiting EC R158-2" in lines[2]


@pytest.mark.parametrize("extra, needle", [
    (["--markets", "atlantis"], "--markets 'atlantis'"),
    (["--markets", "unr158,unr158"], "given twice"),
    (["--markets", "unr158", "--criteria", "unr158"], "--criteria with --markets"),
    (["--markets", "unr158", "--compensation", "default"], "--compensation with --markets"),
])
def test_bad_markets_is_one_line_and_exit_2(case, extra, needle):
    root, _, _ = case
    out = run_in_process(["robustness", "scene.yaml", "--params", "params.yaml", "--out",
                          "bad", *extra], cwd=root)
    assert out.code == 2
    assert len(out.stderr.strip().splitlines()) == 1 and needle in out.stderr
    assert not (root / "bad").exists()
