"""The EOL station on synthetic cars: deviations recovered, per-car outputs, exit status."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import dataclasses
import hashlib

from rvmsim.compensation import Deviation, deviated_camera
from rvmsim.eol import (CarResult, Station, StationResult, StationSettings, guideline_angles,
                        write_car)
from rvmsim.guidelines import compute_guidelines, guideline_view, running_gear, steering_angles
from rvmsim.guidelines.table import GuidelineTable, read_table, table_bytes
from rvmsim.isp import load_params
from rvmsim.scene import load_scene
from rvmsim.testing.scenes import load_small_scene

from ..cli_runner import run_in_process
from rvmsim.testing.stations import capture, platform, station_scene, write_capture, write_inputs

#: Cars at the corners of the tolerance box (±5 mm, ±1° on every axis).
CORNERS = [Deviation(5, 5, 5, 1, 1, 1), Deviation(5, -5, 5, -1, 1, -1),
           Deviation(-5, -5, -5, -1, -1, -1), Deviation(-5, 5, -5, 1, -1, 1)]
#: Two cars whose corrected pictures pass every EC with the tuned setting.
GOOD = [Deviation(2, -3, 4, 0.5, -0.4, 0.3), Deviation(-5, 5, 0, -1, 1, -1)]
#: A camera turned 6° in yaw: beyond the default ±3° of pan and tilt.
TURNED = Deviation(0, 0, 0, 6.0, 0, 0)


@pytest.fixture(scope="module")
def env(tmp_path_factory) -> dict[str, str]:
    """One render cache for the module's station runs (renders are the same bits in every
    process, so sharing them changes no result)."""
    return {"RVMSIM_CACHE": str(tmp_path_factory.mktemp("eol_cache"))}


@pytest.fixture(scope="module")
def station() -> Station:
    params, output = platform()
    return Station(station_scene(), StationSettings(params, output))


@pytest.fixture(scope="module")
def corner_cars(station: Station) -> list[CarResult]:
    """The station's step on each of :data:`CORNERS`, in this process (once per module)."""
    return [station.car(capture(truth), "car", "car") for truth in CORNERS]


@pytest.mark.parametrize("k", range(len(CORNERS)), ids=["{:+g},{:+g},{:+g}mm".format(
    d.x_mm, d.y_mm, d.z_mm) for d in CORNERS])
def test_a_synthetic_cars_deviation_is_recovered(corner_cars: list[CarResult], k: int):
    """Within 1 mm and 0.05° on every axis (the station's own corners only, 640 × 480)."""
    car, truth = corner_cars[k], CORNERS[k]
    assert car.deviation is not None, car.reason
    err = np.array(car.deviation.as_offsets()) - np.array(truth.as_offsets())
    assert np.abs(err[:3]).max() <= 1.0, err
    assert np.abs(err[3:]).max() <= 0.05, err
    assert car.landmarks >= 60 and car.rms_px is not None and car.rms_px < 0.5
    assert car.sigma is not None and max(car.sigma[3:]) < 0.05
    # The law corrected what was measured, within its range, and the ECs were measured.
    assert car.correction is not None and car.correction.within_range
    assert car.ec is not None and len(car.ec.items) == 11
    # judged at the RVM image of record, whatever size the settings give (640 × 360 here)
    assert car.images["rvm"].shape == (720, 1280, 3)


def _largest_gap(a: GuidelineTable, b: GuidelineTable) -> float:
    """The largest distance between two tables' points, px (inf when their lines, pieces or
    point counts differ)."""
    if (a.width, a.height, a.steering_deg) != (b.width, b.height, b.steering_deg) or len(
            a.lines) != len(b.lines):
        return float("inf")
    gap = 0.0
    for la, lb in zip(a.lines, b.lines):
        if (la.kind, la.color, la.steering_deg) != (lb.kind, lb.color, lb.steering_deg) or [
                len(p) for p in la.pieces] != [len(p) for p in lb.pieces]:
            return float("inf")
        for pa, pb in zip(la.pieces, lb.pieces):
            gap = max(gap, float(np.abs(pa - pb).max(initial=0.0)))
    return gap


def _direct_table(scene, deviation: Deviation, params, output) -> GuidelineTable:
    """The table of the car drawn directly: compute_guidelines with the camera at the
    measured pose and the car's own setting, every steering angle of its range."""
    view = guideline_view(scene, params, output, camera=deviated_camera(scene, deviation))
    return read_table(table_bytes(compute_guidelines(scene, view, steering_angles(
        running_gear(scene)))))


def test_a_cars_guideline_table_is_the_overlay_of_the_deviated_car(
        station: Station, corner_cars: list[CarResult]):
    """The station's table of each car is the overlay drawn directly for the car at its
    measured pose with its per-car values, to 1/16 px; the platform's table (design pose,
    platform values) lands pixels away from it, so the comparison can tell them apart."""
    sc = station.scene
    angles = steering_angles(running_gear(sc))
    platform_table = read_table(table_bytes(compute_guidelines(
        sc, guideline_view(sc, station.settings.params, station.record), angles)))
    for car in corner_cars:
        assert car.guidelines is not None and car.deviation is not None
        assert car.correction is not None
        got = read_table(car.guidelines.data)
        assert got.steering_deg == pytest.approx(angles, abs=0.05)
        assert len(got.steering_deg) > 50  # the whole range in 10° steps
        assert car.guidelines.sha256 == hashlib.sha256(car.guidelines.data).hexdigest()
        direct = _direct_table(sc, car.deviation, car.correction.params, station.record)
        assert _largest_gap(got, direct) <= 1 / 16
        assert _largest_gap(got, platform_table) > 1.0


def test_no_running_gear_no_guideline_table(corner_cars: list[CarResult], tmp_path: Path):
    """A vehicle without its running gear: no table angles, no table file beside the car's
    parameter file, and eol.json says null (for the run and the car)."""
    bare = load_small_scene("a", edit={"vehicle.wheelbase": None})
    assert guideline_angles(bare) is None
    assert guideline_angles(load_small_scene("a")) is not None
    car = dataclasses.replace(corner_cars[0], guidelines=None)
    files = write_car(car, tmp_path, platform()[1])
    assert "guidelines" not in files and "params" in files
    assert not list(tmp_path.glob("*.guidelines.bin"))
    assert car.as_dict()["guidelines"] is None
    run = StationResult("a", "a.yaml", "mat", {}, "p.yaml", (1280, 720), {}, "paper",
                        ("h_pan",), (car,))
    assert run.as_dict()["guidelines"] is None


def _run(folder: Path, *captures: Path, env: dict[str, str], extra: tuple[str, ...] = ()):
    scene, params = write_inputs(folder)
    args = ["eol", scene, "--params", params, *[a for c in captures for a in ("--capture", c)],
            "--out", folder / "out", "--no-progress", *extra]
    return run_in_process(args, env=env)


def test_every_car_passes_exit_0_and_outputs_per_car(tmp_path: Path, env):
    caps = tmp_path / "caps"
    for k, d in enumerate(GOOD):
        write_capture(caps / f"car{k}.png", d)
    res = _run(tmp_path, caps, env=env)
    assert res.code == 0, res.stdout + res.stderr
    assert res.stderr == ""
    assert "2 of 2 cars pass" in res.stdout
    out = tmp_path / "out"
    assert sorted(p.name for p in out.iterdir()) == [
        "car0.guidelines.bin", "car0.yaml", "car0_annotated.png", "car0_rvm.png",
        "car1.guidelines.bin", "car1.yaml", "car1_annotated.png", "car1_rvm.png", "eol.csv",
        "eol.html", "eol.json", "eol.lock"]
    doc = json.loads((out / "eol.json").read_text())
    # each car's guideline table: its hash in eol.json, and the overlay drawn directly for
    # the car at the pose eol.json records with the setting of its parameter file
    scene = load_scene(tmp_path / "station.yaml")
    assert doc["guidelines"]["steering_deg"] == list(steering_angles(running_gear(scene)))
    for k, row in enumerate(doc["results"]):
        data = (out / f"car{k}.guidelines.bin").read_bytes()
        assert row["guidelines"]["file"] == f"car{k}.guidelines.bin"
        assert row["guidelines"]["sha256"] == hashlib.sha256(data).hexdigest()
        assert row["files"]["guidelines"] == f"car{k}.guidelines.bin"
        params, output = load_params(out / f"car{k}.yaml")
        measured = Deviation.from_offsets([row["deviation"][a] for a in (
            "x_mm", "y_mm", "z_mm", "yaw_deg", "pitch_deg", "roll_deg")])
        assert _largest_gap(read_table(data), _direct_table(scene, measured, params,
                                                            output)) <= 1 / 16
    assert doc["all_pass"] and doc["cars"] == 2 and doc["target"] == "station mat"
    assert doc["load_state"]["name"] == "curb" and doc["written_params"] == ["h_pan", "v_pan",
                                                                              "tilt"]
    # the station's σ is the model's assumption, not a result of the run: labelled so
    assert "angle_sigma_deg" not in doc["compensation"]["station"]
    assert doc["assumed_station_sigma"]["angle_sigma_deg"] == 0.1
    assert "assumption" in doc["assumed_station_sigma"]["note"]
    assert doc["compensation"]["law"] == "ec-solve" and doc["by_status"]["pass"] == 2
    for k, (row, truth) in enumerate(zip(doc["results"], GOOD)):
        assert row["verdict"] == "PASS" and row["reasons"] == []
        got = [row["deviation"][a] for a in ("x_mm", "y_mm", "z_mm")]
        assert got == pytest.approx([truth.x_mm, truth.y_mm, truth.z_mm], abs=1.0)
        assert row["deviation"]["yaw_deg"] == pytest.approx(truth.yaw_deg, abs=0.05)
        assert all(e["passed"] for e in row["ecs"]["ecs"])
        # The car's parameter file is a params file with the per-car values written.
        params, output = load_params(out / f"car{k}.yaml")
        # every car judged (and its file written) at the RVM image of record
        assert (output.width, output.height) == (1280, 720)
        for name, value in row["correction"]["values"].items():
            assert getattr(params, name) == pytest.approx(value, abs=1e-5)
        assert params.rad == pytest.approx(platform()[0].rad)
    with (out / "eol.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["name"] for r in rows] == ["car0", "car1"]
    assert rows[0]["verdict"] == "PASS" and rows[0]["ec_2-3_pass"] == "pass"
    assert float(rows[1]["roll_deg"]) == pytest.approx(-1.0, abs=0.05)
    assert float(rows[1]["tilt"]) == doc["results"][1]["correction"]["values"]["tilt"]
    for row in rows:  # each car's guideline table and its hash
        table = (out / row["guidelines_file"]).read_bytes()
        assert row["guidelines_sha256"] == hashlib.sha256(table).hexdigest()
    html = (out / "eol.html").read_text()
    assert "2 of 2 cars pass" in html and 'src="car1_annotated.png"' in html
    assert all(f'href="{r["guidelines_file"]}"' in html and r["guidelines_sha256"][:16] in html
               for r in rows)

    # The next station run into the folder replaces this one: car0's files go, a killed
    # run's staging folder goes, a file of someone else's stays.
    (out / ".eol-0123456789ab.tmp").mkdir()
    (out / ".eol-0123456789ab.tmp" / "half.yaml").write_text("# a killed run's\n")
    (out / "notes.txt").write_text("the line's own notes\n")
    again = _run(tmp_path, caps / "car1.png", env=env)
    assert again.code == 0, again.stdout + again.stderr
    assert sorted(p.name for p in out.iterdir()) == [
        "car1.guidelines.bin", "car1.yaml", "car1_annotated.png", "car1_rvm.png", "eol.csv",
        "eol.html", "eol.json", "eol.lock", "notes.txt"]
    assert [r["name"] for r in json.loads((out / "eol.json").read_text())["results"]] == ["car1"]


def test_a_car_beyond_the_range_or_without_a_pose_fails_exit_1(tmp_path: Path, env):
    """A camera turned 6° needs more pan and tilt than the EOL step may write: no setting
    within the allowed ranges passes it, and the car is named infeasible with the ECs that
    fail and what the reference points would need; a capture of something else fails as a
    car whose pose was not recovered; the good car still passes."""
    caps = tmp_path / "caps"
    write_capture(caps / "a_good.png", GOOD[0])
    write_capture(caps / "b_turned.png", TURNED)
    noise = np.random.default_rng(5).integers(0, 255, capture(GOOD[0]).shape, dtype=np.uint8)
    from rvmsim._io import write_png
    write_png(caps / "c_noise.png", noise)
    res = _run(tmp_path, caps, env=env)
    assert res.code == 1, res.stdout + res.stderr
    assert "1 of 3 cars pass" in res.stdout
    doc = json.loads((tmp_path / "out" / "eol.json").read_text())
    good, turned, lost = doc["results"]
    assert good["verdict"] == "PASS"
    assert turned["verdict"] == "FAIL"
    assert turned["deviation"]["yaw_deg"] == pytest.approx(6.0, abs=0.05)
    assert turned["status"] == "infeasible"
    assert turned["reasons"][0].startswith("infeasible car: "), turned["reasons"]
    assert any(r.startswith("the reference points need more: EOL range exceeded: pan ")
               and r.endswith("> 3°") for r in turned["reasons"]), turned["reasons"]
    assert "infeasible car" in res.stdout
    # the values written stay within the allowed ranges
    assert turned["correction"]["within_range"] is True
    assert turned["correction"]["offsets"]["h_pan"] <= 3.0 + 1e-9
    assert doc["by_status"] == {"pass": 1, "marginal": 0, "infeasible": 1, "fail": 0,
                                "no pose": 1}
    assert lost["verdict"] == "FAIL" and lost["deviation"] is None
    assert lost["reasons"][0].startswith("pose not recovered (detection)")
    out = tmp_path / "out"
    assert (out / "b_turned.yaml").is_file() and not (out / "c_noise.yaml").exists()
    assert (out / "c_noise_landmarks.png").is_file()
    with (out / "eol.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert rows[1]["reason"].startswith("infeasible car: ")
    assert rows[2]["x_mm"] == "" and rows[2]["verdict"] == "FAIL"


def test_a_car_measured_in_a_load_state_reads_the_load_too():
    """At ``measured_at: full load`` (45 mm lower, 0.9° rear down) the station renders its
    nominal frame with the body there, and reads the camera against the design pose: the
    mount's deviation plus the load's (rvmsim.compensation.loaded_deviation)."""
    import dataclasses

    from rvmsim.compensation import DEFAULT_COMPENSATION, loaded_deviation
    from rvmsim.eol import synthetic_capture

    params, output = platform()
    model = dataclasses.replace(DEFAULT_COMPENSATION, measured_at="full load")
    st = Station(station_scene(), StationSettings(params, output, model))
    assert st.load.name == "full load" and st.body_pose is not None
    truth = Deviation(2, -3, 4, 0.5, -0.4, 0.3)
    cap = synthetic_capture(station_scene(), truth, st.load).color
    car = st.car(cap, "loaded", "loaded")
    want = loaded_deviation(station_scene(), truth, -45.0, 0.9)
    assert car.deviation is not None, car.reason
    err = np.array(car.deviation.as_offsets()) - np.array(want.as_offsets())
    assert np.abs(err[:3]).max() <= 1.0 and np.abs(err[3:]).max() <= 0.05, err
    assert car.deviation.pitch_deg == pytest.approx(-0.4 + 0.9, abs=0.05)


def test_cars_shared_out_to_workers_give_the_same_results(tmp_path: Path,
                                                          corner_cars: list[CarResult], env):
    caps = tmp_path / "caps"
    for k, d in enumerate(CORNERS):
        write_capture(caps / f"car{k}.png", d)
    res = _run(tmp_path, caps, env=env, extra=("--workers", "2"))
    assert res.code in (0, 1), res.stdout + res.stderr
    doc = json.loads((tmp_path / "out" / "eol.json").read_text())
    assert [r["name"] for r in doc["results"]] == [f"car{k}" for k in range(4)]
    for row, here in zip(doc["results"], corner_cars):  # the same cars, in this process
        assert here.deviation is not None and here.correction is not None
        assert row["deviation"] == pytest.approx(here.deviation.as_dict(), abs=1e-4)
        assert row["correction"]["values"] == pytest.approx(
            {k: round(v, 6) for k, v in here.correction.values.items()}, abs=1e-5)
        assert row["verdict"] == here.verdict
        assert here.guidelines is not None  # the same table from a worker process
        assert row["guidelines"]["sha256"] == here.guidelines.sha256
