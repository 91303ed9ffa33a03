"""ISP parameters: validation, defaults, params files (one-line ParamsFileError naming the
file, the line and the key), a resampled input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rvmsim.errors import ParamsFileError
from rvmsim.isp import (
    PARAM_SPECS,
    TUNED_BY_DEFAULT,
    IspParams,
    OutputSpec,
    build_map_exact,
    load_params,
    params_to_dict,
)

from ..conftest import SCENES
from .conftest import INPUT, PARAM_SETS


def test_params_validation_and_defaults():
    p = IspParams()
    assert (p.fov, p.rad, p.zoom, p.adv_h_scale) == (180, 640, 1, 1)
    assert len(IspParams.names()) == 14 and len(TUNED_BY_DEFAULT) == 9
    assert not {"h_pan", "v_pan", "tilt", "theta", "phi"} & set(TUNED_BY_DEFAULT)
    with pytest.raises(ValueError, match="zoom"):
        IspParams(zoom=0.0)
    with pytest.raises(ValueError, match="adv_h_scale"):
        IspParams(adv_h_scale=2.5)
    with pytest.raises(ValueError, match="h_pan"):
        IspParams(h_pan=-1)
    with pytest.raises(Exception):
        p.zoom = 2.0  # type: ignore[misc]


# ---------------------------------------------------------------------------- params files
def test_params_file_round_trip(tmp_path):
    p = PARAM_SETS[2]
    out = OutputSpec(800, 480, False)
    path = tmp_path / "p.json"
    path.write_text(json.dumps(params_to_dict(p, out)))
    assert load_params(path) == (p, out)
    ypath = tmp_path / "p.yaml"
    ypath.write_text("zoom: 1.3\nadv_v_shift: 0.2\n")
    q, o = load_params(ypath)
    assert q == IspParams(zoom=1.3, adv_v_shift=0.2) and o == OutputSpec()
    # where the verdict was judged rides along in the output section
    judged = params_to_dict(p, out, judged_at=OutputSpec(1280, 720))
    assert judged["output"]["judged_at"] == [1280, 720]
    path.write_text(json.dumps(judged))
    assert load_params(path) == (p, out)


@pytest.mark.parametrize("text, key, line, words", [
    ("zoom: 50\n", "zoom", 1, "zoom: 50 is outside [0.01, 10]"),
    ("fov: 100\nzooom: 1\n", "zooom", 2, "zooom: unknown ISP parameter"),
    ("zoom: wide\n", "zoom", 1, "zoom: must be a number"),
    ("zoom: [1\n", "", 2, "malformed params file"),
    ("- 1\n- 2\n", "", None, "must be a mapping"),
    ("output: {size: [0, 480]}\n", "output.size", 1, "output.size"),
    ("zoom: 1\noutput:\n  mirror: maybe\n", "output.mirror", 3, "output.mirror"),
    ("output: 3\n", "output", 1, "output: expected {size"),
    ("output: {judged_at: [1280]}\n", "output.judged_at", 1, "RVM image of record"),
    ("output: {judged_at: [0, 720]}\n", "output.judged_at", 1, "16..8192"),
])
def test_bad_params_file(tmp_path, text, key, line, words):
    path = tmp_path / "p.yaml"
    path.write_text(text)
    with pytest.raises(ParamsFileError) as info:
        load_params(path)
    err = info.value
    assert (err.file, err.key, err.line) == (str(path), key, line)
    assert words in str(err) and str(err).startswith(str(path))
    assert "\n" not in str(err)


def test_bad_json_params_file_names_the_line(tmp_path):
    path = tmp_path / "p.json"
    path.write_text('{"zoom": 1.0,\n "rad": 9999}')
    with pytest.raises(ParamsFileError) as info:
        load_params(path)
    assert (info.value.key, info.value.line) == ("rad", 2)
    path.write_text('{"zoom": 1,,}')
    with pytest.raises(ParamsFileError, match="malformed params file") as info:
        load_params(path)
    assert info.value.line == 1
    with pytest.raises(ParamsFileError, match="params file not found"):
        load_params(tmp_path / "missing.yaml")


def test_param_spec_problem_is_the_validation_message():
    zoom = next(s for s in PARAM_SPECS if s.name == "zoom")
    assert zoom.problem(1.0) is None and zoom.problem(np.float32(2.0)) is None
    assert zoom.problem(50) == "50 is outside [0.01, 10]"
    assert zoom.problem(float("nan")) == "nan is outside [0.01, 10]"
    assert zoom.problem(True) == "must be a number, got True"
    with pytest.raises(ValueError, match=r"^zoom: 50 is outside \[0.01, 10\]$"):
        IspParams(zoom=50)


def test_params_follow_a_resampled_input():
    p = PARAM_SETS[1]
    out = OutputSpec(320, 180)
    full = build_map_exact(p, INPUT, out)
    quarter = build_map_exact(p.for_input_scale(0.25), (320, 240), out)
    np.testing.assert_allclose(quarter.map_x, (full.map_x + 0.5) * 0.25 - 0.5, atol=1e-3)
    np.testing.assert_allclose(quarter.map_y, (full.map_y + 0.5) * 0.25 - 0.5, atol=1e-3)


def test_bundled_params_file_is_the_paper_defaults():
    assert load_params(SCENES.parent / "params" / "paper_defaults.yaml") == (IspParams(),
                                                                            OutputSpec())


@pytest.mark.parametrize("text, key, words", [
    ("rad: " + "9" * 400 + "\n", "rad", "400-digit number is outside [50, 2000]"),
    ("zoom: .nan\n", "zoom", "outside"),
    ("output: {size: [8192, 8192]}\n", "output.size", "RVMSIM_MAX_IMAGE_PIXELS"),
    ("output: {size: [100000, 100000]}\n", "output.size", "16..16384"),
    ("rad: 600\ndeep: " + "[" * 5000 + "]" * 5000 + "\n", "", "over the YAML limits"),
])
def test_params_values_and_yaml_over_the_limits(tmp_path, text, key, words):
    path = tmp_path / "p.yaml"
    path.write_text(text)
    with pytest.raises(ParamsFileError) as err:
        load_params(path)
    assert err.value.key == key and words in str(err.value) and "\n" not in str(err.value)


def test_json_params_nested_too_deeply(tmp_path):
    path = tmp_path / "p.json"
    path.write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(ParamsFileError, match="nested too deeply"):
        load_params(path)
