"""The station's geometry: load states, cars' cameras, the deviation the station reads."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvmsim.compensation import DEFAULT_COMPENSATION, Deviation, loaded_deviation
from rvmsim.eol import car_camera, deviation_of, station_load
from rvmsim.errors import CompensationError
from rvmsim.robust import LoadState, MountSample, sample_camera, variation_from_scene

from ..conftest import bundled_scene

FULL = LoadState("full load", height_mm=-45.0, pitch_deg=0.9)
DEVIATIONS = [Deviation(), Deviation(3, -2, 5, 0.7, -0.4, 0.9), Deviation(-5, 5, -1, -1, 1, -0.3)]


@pytest.mark.parametrize("d", DEVIATIONS)
def test_the_station_reads_back_a_cars_deviation(d: Deviation):
    sc = bundled_scene("a")
    cam = car_camera(sc, d)
    got = deviation_of(sc, cam.position, cam.rotation)
    assert got.as_offsets() == pytest.approx(d.as_offsets(), abs=1e-9)


@pytest.mark.parametrize("d", DEVIATIONS)
def test_in_a_load_state_it_reads_what_robustness_models(d: Deviation):
    """The loaded car's camera is robustness's sample camera, and the station reads it as
    rvmsim.compensation.loaded_deviation says (against the design pose)."""
    sc = bundled_scene("a")
    cam = car_camera(sc, d, FULL)
    sample = MountSample(0, d.as_offsets(), (d.x_mm, d.y_mm, d.z_mm), FULL)
    ref = sample_camera(sc, sample)
    assert cam.rotation == pytest.approx(ref.rotation, abs=1e-12)
    assert cam.position == pytest.approx(ref.position, abs=1e-12)
    got = deviation_of(sc, cam.position, cam.rotation)
    want = loaded_deviation(sc, d, FULL.height_mm, FULL.pitch_deg)
    assert got.as_offsets() == pytest.approx(want.as_offsets(), abs=1e-9)
    assert got.y_mm == pytest.approx(d.y_mm + 45.0, abs=1.0)  # the body is 45 mm lower


def test_the_station_measures_at_the_named_load_state():
    sc = bundled_scene("a")
    assert station_load(sc, DEFAULT_COMPENSATION).name == "curb"  # the first
    model = dataclasses.replace(DEFAULT_COMPENSATION, measured_at="full load")
    assert station_load(sc, model).pitch_deg == 0.9
    names = [s.name for s in variation_from_scene(sc).load_states]
    assert names == ["curb", "driver", "full load"]
    with pytest.raises(CompensationError, match="'trailer' is not a load state"):
        station_load(sc, dataclasses.replace(DEFAULT_COMPENSATION, measured_at="trailer"))
    no_var = sc.model_copy(update={"variation": None})
    assert station_load(no_var, DEFAULT_COMPENSATION).name == "nominal"
    assert np.isfinite(car_camera(no_var, Deviation(1, 1, 1, 0, 0, 0)).position).all()
