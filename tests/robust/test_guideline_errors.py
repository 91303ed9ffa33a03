"""The parking guidelines' errors over a fleet after the EOL step (no renders: geometry only)."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.compensation import DEFAULT_COMPENSATION, deviated_camera, loaded_deviation
from rvmsim.guidelines import compute_guidelines, guideline_view
from rvmsim.isp import OutputSpec
from rvmsim.robust import (GuidelineErrors, draw_samples, fleet_guideline_errors,
                           station_readings, true_deviation, variation_from_scene)
from rvmsim.testing.scenes import load_small_scene
from rvmsim.testing.stations import platform

OUTPUT = OutputSpec(640, 360, mirror=True)


@pytest.fixture(scope="module")
def fleet():
    """Sixteen cars of vehicle A (its own tolerances and load states) read by the default
    station, each with the platform setting as its own (the ground error does not depend
    on the setting)."""
    sc = load_small_scene("a", 0.25)
    var = variation_from_scene(sc)
    assert len(var.load_states) > 1
    samples = draw_samples(var, 16, 3)
    load = var.load_states[0]
    measured = station_readings(sc, samples, DEFAULT_COMPENSATION, 3, load)
    params = platform(0.25)[0]
    lines = fleet_guideline_errors(sc, samples, measured, [params] * len(samples), params,
                                   OUTPUT, load)
    assert lines is not None
    return sc, samples, measured, params, load, lines


def _cast(ground: np.ndarray, measured, true) -> np.ndarray:
    """Where the ray the measured camera sees ``ground`` ((N, 2) x, z m) along meets the
    ground when it leaves the true camera: C_t + λ·R_t·R_mᵀ·(G − C_m), y = 0."""
    g = np.column_stack([ground[:, 0], np.zeros(len(ground)), ground[:, 1]])
    d = (g - measured.position) @ measured.rotation @ true.rotation.T
    lam = -true.position[1] / d[:, 1]
    return (true.position + lam[:, None] * d)[:, [0, 2]]


def test_the_ground_error_is_the_measured_ray_cast_from_the_true_pose(fleet):
    """Per car, the 1 m mark's and the width lines' ground error at the station is the
    largest distance between their points and where the ray of each from the measured pose
    meets the ground from the true pose (closed form, no lens or ISP)."""
    sc, samples, measured, params, load, lines = fleet
    for i, (s, m) in enumerate(zip(samples, measured)):
        cam_m = deviated_camera(sc, m)
        cam_t = deviated_camera(sc, loaded_deviation(sc, true_deviation(s), load.height_mm,
                                                     load.pitch_deg))
        drawn = compute_guidelines(sc, guideline_view(sc, params, OUTPUT, camera=cam_m))
        for group, names in (("mark_1m", ("mark_1m",)),
                             ("width", ("width_neg_x", "width_pos_x"))):
            g = np.concatenate([p.ground_m for l in drawn.static if l.name in names
                                for p in l.pieces])
            want = 100 * np.hypot(*(_cast(g, cam_m, cam_t) - g).T).max()
            assert lines.eol_station.of(group)[i] == pytest.approx(want, rel=1e-6, abs=1e-6)
            assert want > 0.01  # the station's error moves the lines


def test_errors_grow_from_the_station_to_the_field_and_without_the_eol_step(fleet):
    """In the field a load state the station did not stand the car in moves the lines
    more; the platform table (no EOL step) is further off than each car's own."""
    *_, lines = fleet
    cm = {k: np.nanmax(getattr(lines, k).of("mark_1m"))
          for k in ("eol_station", "eol_field", "platform_station", "platform_field")}
    assert cm["eol_field"] > cm["eol_station"]
    assert cm["platform_station"] > cm["eol_station"]
    assert np.isfinite(lines.eol_field.px).any()
    doc = lines.as_dict()
    assert doc["groups"][:4] == ["mark_0.5m", "mark_1m", "mark_2m", "mark_3m"]
    assert set(doc["steering_deg"]) == {"trajectory_0pct", "trajectory_50pct",
                                        "trajectory_100pct"}
    lock = doc["steering_deg"]["trajectory_100pct"]
    assert len(lock) == 2 and lock[0] == -lock[1] != 0
    assert "mark_1m" in lines.summary_line()


def test_the_distribution_over_the_cars():
    """Median, 99th percentile and worst over the cars counted (a NaN car: its line not
    shown), and the car with the worst ground error."""
    cm = np.r_[np.arange(101.0), np.nan][:, None]
    dist = GuidelineErrors(("mark_1m",), cm / 10, cm).distribution()["mark_1m"]
    assert dist["cm"] == {"median": 50.0, "p99": 99.0, "max": 100.0}
    assert dist["px"]["max"] == 10.0
    assert dist["worst_sample"] == 100 and dist["cars"] == 101
    none = GuidelineErrors(("width",), np.full((3, 1), np.nan), np.full((3, 1), np.nan))
    assert none.distribution()["width"] == {"px": {"median": None, "p99": None, "max": None},
                                            "cm": {"median": None, "p99": None, "max": None},
                                            "worst_sample": None, "cars": 0}


def test_a_vehicle_without_running_gear_has_none(fleet):
    sc, samples, measured, params, load, _ = fleet
    bare = load_small_scene("a", 0.25, edit={"vehicle.steering_ratio": None})
    assert fleet_guideline_errors(bare, samples, measured, [params] * len(samples), params,
                                  OUTPUT, load) is None
