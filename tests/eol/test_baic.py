"""`rvmsim eol` on the real BAIC EU5 capture: its calibration mat is the station's target."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from rvmsim.isp import IspParams, OutputSpec, load_params, params_to_dict

from ..cli_runner import run_in_process
from ..conftest import SCENES
from ..validate.captures import BAIC, needs_real


@needs_real
def test_the_real_capture_runs_end_to_end(tmp_path: Path):
    """The bundled scene's mount is the pose ``rvmsim validate`` found on this frame, so the
    station reads (almost) no deviation and writes (almost) the platform's values.  The
    scene has no FMVSS test site (no guidelines, objects or board), so the ECs that need
    one are not measured and the car fails on them, named, not on its pose."""
    params = tmp_path / "params.yaml"
    params.write_text(yaml.safe_dump(params_to_dict(IspParams().for_input_scale(960 / 1280),
                                                    OutputSpec()), sort_keys=False))
    out = tmp_path / "out"
    res = run_in_process(["eol", SCENES / "real" / "baic_eu5_rear.yaml", "--params", params,
                          "--capture", BAIC, "--out", out, "--no-progress"],
                         env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    assert res.code == 1, res.stdout + res.stderr
    assert res.stderr == ""
    assert "target calibration mat" in res.stdout and "0 of 1 cars pass" in res.stdout
    doc = json.loads((out / "eol.json").read_text())
    car = doc["results"][0]
    assert car["name"] == "back" and car["landmarks"] >= 35 and car["rms_px"] < 1.0
    d = car["deviation"]
    assert max(abs(d[a]) for a in ("x_mm", "y_mm", "z_mm")) < 3.0
    assert max(abs(d[a]) for a in ("yaw_deg", "pitch_deg", "roll_deg")) < 0.06
    assert car["correction"]["within_range"] and car["correction"]["offsets"]["h_pan"] < 0.1
    assert len(car["reasons"]) == 1 and car["reasons"][0].startswith("EC ")
    assert "3-1" in car["reasons"][0] and "2-3" not in car["reasons"][0]
    written, output = load_params(out / "back.yaml")
    assert (output.width, output.height) == (1280, 720)
    assert written.rad == pytest.approx(480.0)
    for name in ("back_rvm.png", "back_annotated.png", "eol.csv", "eol.html"):
        assert (out / name).is_file()
