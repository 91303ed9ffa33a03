"""``rvmsim robustness --export-sample N``: a sample written as a scene, which ``rvmsim
evaluate`` renders in full and measures as robustness did."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from rvmsim.criteria import default_criteria
from rvmsim.isp import IspParams, OutputSpec, build_map, load_params, params_to_dict
from rvmsim.render import render_fisheye
from rvmsim.testing.stations import TUNED
from rvmsim.robust import draw_samples, sample_camera, sample_images, variation_from_scene
from rvmsim.scene import load_scene

from ..cli_runner import run_in_process
from rvmsim.testing.scenes import QUARTER, write_small_scene

#: ±1° on every angle, ±4 mm on every position axis (rendered at ±2 mm), two load states.
VARIATION = {"mount": {**{a: {"uniform": {"half_width": 1.0}}
                          for a in ("yaw_deg", "pitch_deg", "roll_deg")},
                       **{a: {"uniform": {"half_width": 4.0}} for a in ("x_mm", "y_mm", "z_mm")}},
             "load_states": [{"name": "curb", "height_mm": 0, "pitch_deg": 0, "weight": 1},
                             {"name": "full", "height_mm": -45, "pitch_deg": 0.9, "weight": 1}]}
OUTPUT = OutputSpec(640, 360)
#: The paper's defaults on the quarter sensor, the view lowered to show the bumper, the
#: guidelines and the board.
PARAMS = dataclasses.replace(IspParams().for_input_scale(QUARTER), v_shift=17.0)


def _magnification(scene_file: Path) -> float:
    """Most RVM px per fisheye px of the setting: 1 / the smallest singular value of the
    map's Jacobian (fisheye px per RVM px) where it reads the fisheye image."""
    cam = load_scene(scene_file).fisheye_camera()
    xy = build_map(PARAMS, (cam.width, cam.height), OUTPUT).xy.astype(np.float64)
    du_dy, du_dx = np.gradient(xy[..., 0])
    dv_dy, dv_dx = np.gradient(xy[..., 1])
    jac = np.stack([np.stack([du_dx, du_dy], -1), np.stack([dv_dx, dv_dy], -1)], -2)
    inside = ((xy[..., 0] >= 0) & (xy[..., 0] <= cam.width - 1) & (xy[..., 1] >= 0)
              & (xy[..., 1] <= cam.height - 1))
    return float(1.0 / np.linalg.svd(jac[inside], compute_uv=False)[:, -1].min())


def _border(labels: np.ndarray) -> np.ndarray:
    """Pixels with another label among their 8 neighbours."""
    lab = np.pad(labels, 1, mode="edge")
    h, w = labels.shape
    return np.any([lab[1 + dy: 1 + dy + h, 1 + dx: 1 + dx + w] != labels
                   for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0)


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory):
    """A robustness run of the small scene exporting its first loaded sample with a position
    offset, and ``rvmsim evaluate`` of that file run from another folder."""
    here = tmp_path_factory.mktemp("export")
    scene_file = write_small_scene(here, "a", name="scene.yaml", variation=VARIATION)
    (here / "params.yaml").write_text(yaml.safe_dump(params_to_dict(PARAMS, OUTPUT)))
    scene = load_scene(scene_file)
    samples = draw_samples(variation_from_scene(scene), 16, seed=0)
    n = next(i for i, s in enumerate(samples)
             if s.load.name == "full" and all(samples[i].render_position_mm))
    run = run_in_process(["robustness", "scene.yaml", "--params", "params.yaml", "--samples",
                          "16", "--scales", "1", "--workers", "1", "--export-sample", str(n),
                          "--out", "out", "--no-progress"], cwd=here)
    assert run.code in (0, 1), run.stderr
    elsewhere = here / "elsewhere"
    elsewhere.mkdir()
    ev = run_in_process(["evaluate", str(here / "out" / f"sample_{n}.yaml"), "--params",
                         str(here / "params.yaml"), "--out", "ev", "--no-progress"],
                        cwd=elsewhere)
    assert ev.code in (0, 1), ev.stderr  # 1: the sample's car fails an EC
    return here, scene, samples[n], n, elsewhere / "ev"


def test_the_exported_scene_is_the_samples_car(exported):
    here, scene, sample, n, _ = exported
    out = here / "out"
    assert {p.name for p in out.iterdir()} >= {"robustness.json", "robustness.html",
                                                 f"sample_{n}.yaml", f"sample_{n}.json"}
    car = load_scene(out / f"sample_{n}.yaml")
    assert car.variation is None and car.load_state is not None
    assert (car.load_state.name, car.load_state.height_mm, car.load_state.pitch_deg) == (
        "full", -45.0, 0.9)
    cam, ref = car.fisheye_camera(), sample_camera(scene, sample)
    np.testing.assert_allclose(cam.rotation, ref.rotation, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cam.position, ref.position, rtol=0, atol=1e-12)
    # a full render of it against robustness's re-fold: the same labels but at borders
    full = render_fisheye(car).labels
    refold = sample_images(scene, draw_samples(variation_from_scene(scene), 16, seed=0),
                           color=False)[n].labels
    differ = full != refold
    assert differ.mean() < 0.01
    assert not (differ & ~_border(full) & ~_border(refold)).any()
    record = json.loads((out / f"sample_{n}.json").read_text())
    assert record["sample"]["index"] == n and record["sample"]["load"] == "full"
    assert record["reproduce"].startswith(f"rvmsim evaluate sample_{n}.yaml --params ")
    assert record == {**record, "seed": 0, "criteria": default_criteria().name}


def test_evaluate_on_it_reproduces_the_samples_ec_values(exported):
    """A full render of the exported car against robustness's re-fold of its viewpoint's
    cube: every label border within one fisheye pixel, so each EC within what that moves in
    the RVM image (docs/robustness.md, "Any sample as a scene"): positions by at most
    m RVM px (m: the setting's largest magnification), a difference of two by 2 m, plus
    one RVM px of the measurement's own rounding."""
    here, _, _, n, ev_dir = exported
    record = json.loads((here / "out" / f"sample_{n}.json").read_text())["ecs"]
    full = {e["id"]: e for e in json.loads((ev_dir / "ec.json").read_text())["ecs"]}
    m = _magnification(here / "scene.yaml")
    px = 2 * m + 1  # RVM px
    tolerance = {"px": px, "%": 100 * px / OUTPUT.height}
    compared = 0
    for ec, robust in record.items():
        value = full[ec]["value"]
        assert (value is None) == (robust["value"] is None), ec
        if value is None:
            continue
        unit = full[ec]["unit"]
        if unit in tolerance:  # positions and their differences (area ratios, counts and
            # the board's aspect: the benchmark's table in docs/robustness.md)
            assert value == pytest.approx(robust["value"], abs=tolerance[unit]), (ec, m)
            compared += 1
    assert compared >= 5


def test_a_compensated_sample_exports_its_own_values_and_reproduces_its_verdict(tmp_path):
    """With --compensation the car was judged with its per-car values: they are exported as
    sample_N.params.yaml, and the recorded command (run as written, in the output folder)
    reproduces the recorded verdict, which the platform values would not (the sample is
    one that fails before compensation and passes after)."""
    # half the sensor: a fisheye pixel is two of the 1280 × 720 image of record, so a fresh
    # render's label borders move EC 2-3 by a few px at most (a quarter: by up to 8)
    write_small_scene(tmp_path, "a", 0.5, name="scene.yaml", variation=VARIATION)
    tuned, _ = load_params(TUNED)
    (tmp_path / "params.yaml").write_text(yaml.safe_dump(params_to_dict(
        tuned.for_input_scale(0.5), OUTPUT)))
    (tmp_path / "comp.yaml").write_text("station: {angle_sigma_deg: 0, position_sigma_mm: 0, "
                                        "edge_sigma_px: 0}\n")
    # every sample exported in the one run (the run is what costs): the test picks its car
    run = run_in_process(["robustness", "scene.yaml", "--params", "params.yaml", "--samples",
                          "12", "--scales", "1", "--workers", "1", "--compensation",
                          "comp.yaml", "--no-progress", "--out", "out",
                          *(f"--export-sample={k}" for k in range(12))], cwd=tmp_path)
    assert run.code in (0, 1), run.stderr
    rows = json.loads((tmp_path / "out" / "robustness.json").read_text())["samples"]
    # the clearest such car: the highest EC score after compensation
    n = max((i for i, r in enumerate(rows) if r["passed"]
             and not r["passed_before_compensation"]), key=lambda i: rows[i]["ec_score"])
    out = tmp_path / "out"
    record = json.loads((out / f"sample_{n}.json").read_text())
    assert record["params"] == f"sample_{n}.params.yaml" and record["passed"]
    assert not record["passed_before_compensation"] and record["station"]["accepted"]
    assert record["reproduce"] == (f"rvmsim evaluate sample_{n}.yaml --params "
                                   f"sample_{n}.params.yaml")
    written, _ = load_params(out / f"sample_{n}.params.yaml")
    assert written.h_pan == pytest.approx(rows[n]["correction"]["values"]["h_pan"], abs=1e-5)
    assert "reproduce: rvmsim evaluate" in (out / f"sample_{n}.params.yaml").read_text()
    ev = run_in_process(record["reproduce"].split()[1:] + ["--out", "ev", "--no-progress"],
                        cwd=out)
    doc = json.loads((out / "ev" / "ec.json").read_text())
    assert ev.code == (0 if doc["passed"] else 1), ev.stderr
    assert doc["passed"] == record["passed"], doc
