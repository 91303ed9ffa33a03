"""Compensation files: the keys at the top level, in a ``compensation`` section, or in a
scene's ``variation.compensation``; bad values named by file, line and key."""

from __future__ import annotations

import pytest

from rvmsim.compensation import (DEFAULT_COMPENSATION, compensation_for, load_compensation,
                                 measured_load_index)
from rvmsim.errors import CompensationError

from rvmsim.testing.scenes import write_small_scene


def test_the_three_places_a_model_is_read_from(tmp_path):
    top = tmp_path / "c.yaml"
    top.write_text("params: [tilt]\nstation: {angle_sigma_deg: 0.05}\n")
    section = tmp_path / "v.yaml"
    section.write_text("mount: {}\ncompensation:\n  params: [tilt]\n"
                       "  station: {angle_sigma_deg: 0.05}\n")
    scene = write_small_scene(tmp_path, edit={"variation.compensation": {
        "params": ["tilt"], "station": {"angle_sigma_deg": 0.05}}})
    models = [load_compensation(p) for p in (top, section, scene)]
    assert all(m.params == ("tilt",) and m.angle_sigma_deg == 0.05 for m in models)
    assert models[0].ranges == (("tilt", -3.0, 3.0),)  # the documented default range
    assert compensation_for("default") == DEFAULT_COMPENSATION
    assert compensation_for(None) is None


def test_a_bad_value_in_a_scenes_section_names_its_whole_key(tmp_path):
    scene = write_small_scene(tmp_path, edit={"variation.compensation": {
        "station": {"angle_sigma_deg": -1}}})
    with pytest.raises(CompensationError) as err:
        load_compensation(scene)
    assert err.value.key == "variation.compensation.station.angle_sigma_deg"
    assert err.value.line is not None and str(scene) in str(err.value)


def test_the_measured_load_state_must_be_the_variations():
    model = DEFAULT_COMPENSATION.with_station(0.1, 1.0)
    assert measured_load_index(model, ["curb", "full"]) == 0
    import dataclasses

    full = dataclasses.replace(model, measured_at="full")
    assert measured_load_index(full, ["curb", "full"]) == 1
    with pytest.raises(CompensationError, match="station.measured_at"):
        measured_load_index(full, ["curb", "driver"])
