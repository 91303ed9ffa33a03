"""Robustness after end-of-line compensation (``rvmsim robustness --compensation``)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from rvmsim.compensation import DEFAULT_COMPENSATION, CompensationLaw
from rvmsim.errors import CompensationError
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.pipeline import make_evaluator
from rvmsim.report import write_robustness_outputs
from rvmsim.robust import (RobustnessSettings, SampleSet, draw_samples, robustness,
                           station_readings, variation_from_scene)

from ..cli_runner import run_in_process
from rvmsim.testing.scenes import load_small_scene, write_small_scene
from .conftest import ANGLES_ONLY
from .test_robustness import settings  # noqa: F401 - the fixture

OUTPUT = OutputSpec(640, 360)
PERFECT = DEFAULT_COMPENSATION.with_station(0.0, 0.0, 0.0)
#: The reference-point law alone (``law: reference-points``): it restores the nominal picture.
POINTS = dataclasses.replace(PERFECT, law="reference-points")
#: ±2.5° on every angle: EC 2-1 in the middle of its range still fails on many samples.
WIDE_ANGLES = {"mount": {a: {"uniform": {"half_width": 2.5}}
                         for a in ("yaw_deg", "pitch_deg", "roll_deg")}}


@pytest.fixture(scope="module")
def edge(settings):
    """The small scene with ±2.5° on every angle, and the setting with EC 2-1 (bumper
    centre height, [4, 8] %) in the middle of its range (test_robustness's): mount pitch
    still makes many samples fail it."""
    _, crit, mid, _ = settings
    return load_small_scene("a", 0.25, variation=WIDE_ANGLES), crit, mid


def test_the_reference_point_law_restores_the_nominal_picture(edge, tmp_path: Path):
    sc, crit, params = edge
    wide = dataclasses.replace(POINTS, ranges=(("h_pan", 0.0, 5.0), ("tilt", -5.0, 5.0)))
    how = RobustnessSettings(OUTPUT, crit, samples=24, seed=2, scales=(1.0, 0.5),
                             scale_samples=8, compensation=wide)
    r = robustness(sc, params, how)
    assert r.before_estimate is not None and r.before_estimate.yield_ < 0.8
    assert r.yield_ == 1.0 and r.compensated is not None
    # every corrected car measures what the car as designed measures, to about a pixel (EC
    # 2-1 is a height in % of the image's 360 px: the bumper's edge in whole rows)
    nominal = r.nominal.ec["2-1"].value
    j = list(crit.ids).index("2-1")
    row_pct = 100 / OUTPUT.height
    assert np.abs(r.before.values[:, j] - nominal).max() > 6 * row_pct
    assert np.abs(r.evaluation.values[:, j] - nominal).max() <= 2 * row_pct + 1e-9
    assert r.compensated.within_range.all()
    assert r.scale_curve[1].estimate.yield_ == 1.0  # the curve is after compensation too
    # the cars the law corrected most are those the pitch moved most
    pitch = np.array([s.angles_deg[1] for s in r.samples])
    turn = np.array([c.offsets["h_pan"] for c in r.compensated.corrections])
    assert np.corrcoef(np.abs(pitch), turn)[0, 1] > 0.8
    doc = json.loads(write_robustness_outputs(r, tmp_path)[0].read_text())
    before = doc["yield_before_compensation"]
    assert before["n_pass"] == r.before_estimate.n_pass and before["n"] == 24
    assert [e["id"] for e in before["ecs"]] == list(crit.ids)
    assert doc["yield"] == 1.0 and set(doc["compensation"]["offsets"]) == {"pan_turn", "tilt"}
    assert doc["compensation"]["n_out_of_range"] == 0
    row = doc["samples"][int(np.argmax(turn))]
    assert not row["passed_before_compensation"] and row["passed"]
    assert set(row["correction"]["values"]) == {"h_pan", "v_pan", "tilt"}
    html = (tmp_path / "robustness.html").read_text()
    assert "before compensation" in html and "after compensation" in html
    assert html.count("data:image/png;base64,") == 5
    # a station that measures exactly: each car's guideline table lands where it claims (no
    # load states: the field is the station); the platform's table does not
    lines = doc["compensation"]["guidelines"]
    assert r.guidelines is not None and lines["groups"][1] == "mark_1m"
    for name, d in lines["eol_table"]["in_field"].items():
        assert d["cars"] == 24 and d["cm"]["max"] < 1e-3 and d["px"]["max"] < 1e-3, name
    assert lines["platform_table"]["in_field"]["mark_1m"]["cm"]["max"] > 1.0
    assert "Parking guidelines after the EOL step" in html and "mark_1m" in html


def test_per_car_values_take_the_fast_path_to_the_full_paths_values(edge):
    """The per-car RVM pixels (rays looked up, not recomputed) give what the full remap of
    each sample's fisheye labels gives."""
    sc, crit, params = edge
    from rvmsim.criteria import default_criteria

    samples = draw_samples(variation_from_scene(sc), 6, seed=4)
    law = CompensationLaw(sc, params, OUTPUT, DEFAULT_COMPENSATION)
    readings = station_readings(sc, samples, DEFAULT_COMPENSATION, 4,
                                variation_from_scene(sc).load_states[0])
    per_car = [law.correct(d).params for d in readings]
    assert len(set(per_car)) == 6
    images = SampleSet.of(sc, samples)
    fast = make_evaluator(images, OUTPUT, default_criteria())
    full = make_evaluator(images, OUTPUT, default_criteria(), path="full")
    np.testing.assert_array_equal(fast(per_car).values, full(per_car).values)


def test_cars_out_of_the_eol_range_fail_and_are_named(edge):
    sc, crit, params = edge
    narrow = dataclasses.replace(POINTS, ranges=(("h_pan", 0.0, 1.5), ("tilt", -3.0, 3.0)))
    r = robustness(sc, params, RobustnessSettings(OUTPUT, crit, samples=16, seed=2,
                                                  scales=(1.0,), compensation=narrow),
                   frames=False)
    assert r.compensated is not None
    out = ~r.compensated.within_range
    assert 0 < out.sum() < 16
    assert not r.passed[out].any()  # whatever their ECs say
    doc = r.as_dict()
    rows = [doc["samples"][i] for i in np.flatnonzero(out)]
    assert all(any(f.startswith("EOL range exceeded: ") for f in row["failed"])
               for row in rows)
    assert doc["compensation"]["n_out_of_range"] == int(out.sum())
    assert "fail the EOL step itself" in r.summary()


def test_cli_compensation_writes_before_and_after(tmp_path: Path):
    scene = write_small_scene(tmp_path, "a", variation=ANGLES_ONLY)  # ±1°
    (tmp_path / "p.yaml").write_text("rad: 160\nv_shift: 12\n")
    (tmp_path / "c.yaml").write_text("compensation:\n  station: {angle_sigma_deg: 0}\n")
    res = run_in_process(["robustness", str(scene), "--params", str(tmp_path / "p.yaml"),
                          "--samples", "8", "--scales", "1", "--out", str(tmp_path / "o"),
                          "--compensation", str(tmp_path / "c.yaml"), "--no-progress"])
    assert res.code in (0, 1), res.stderr
    assert "yield after EOL compensation" in res.stdout and "before compensation" in res.stdout
    doc = json.loads((tmp_path / "o" / "robustness.json").read_text())
    assert doc["compensation"]["station"]["angle_sigma_deg"] == 0.0
    assert doc["compensation"]["source"].endswith("c.yaml")
    assert doc["yield_before_compensation"] is not None


def test_a_setting_that_shows_no_ground_is_refused_before_any_render(edge):
    """The law's reference ground points are counted before the viewpoints are rendered:
    the one-line refusal comes at once (it came after a render of every sample's
    viewpoint)."""
    sc, crit, _ = edge
    calls = []

    class Runner:  # a TaskRunner that records what it is given
        def run(self, fn, items):
            calls.append(dict(items))
            for key, item in items.items():
                yield key, fn(item)

    how = RobustnessSettings(OUTPUT, crit, samples=4, seed=2, compensation=POINTS)
    with pytest.raises(CompensationError, match="reference ground points"):
        robustness(sc, IspParams(h_pan=90, v_pan=-90, zoom=3), how, runner=Runner())
    assert calls == []
