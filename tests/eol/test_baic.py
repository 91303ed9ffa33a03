"""`rvmsim eol` on the real BAIC EU5 capture: its calibration mat is the station's target."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from rvmsim.isp import IspParams, OutputSpec, load_params, params_to_dict

from ..cli_runner import run_in_process
from ..conftest import SCENES
from rvmsim.testing.captures import BAIC
from ..conftest import needs_real


@needs_real
def test_the_real_capture_runs_end_to_end(tmp_path: Path):
    """The bundled scene's mount is the pose ``rvmsim validate`` found on this frame, so the
    station reads (almost) no deviation.  The scene has no FMVSS test site, so the car is
    judged by the ECs of its body alone, in a view that shows the bumper (zoomed out): they
    are measured on the body the capture shows (its outline found there, 2–3 px from the
    scene's rough bumper model), and whatever the verdict, it names only them."""
    params = tmp_path / "params.yaml"
    params.write_text(yaml.safe_dump(params_to_dict(
        IspParams(zoom=0.6).for_input_scale(960 / 1280), OutputSpec()), sort_keys=False))
    criteria = tmp_path / "body.yaml"
    criteria.write_text('name: the body\necs: ["2-1", "2-2", "2-3", "2-4"]\n')
    out = tmp_path / "out"
    res = run_in_process(["eol", SCENES / "real" / "baic_eu5_rear.yaml", "--params", params,
                          "--capture", BAIC, "--out", out, "--criteria", criteria,
                          "--no-progress"], env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    assert res.code in (0, 1), res.stdout + res.stderr
    assert res.stderr == ""
    assert "target calibration mat" in res.stdout
    doc = json.loads((out / "eol.json").read_text())
    car = doc["results"][0]
    assert car["name"] == "back" and car["landmarks"] >= 35 and car["rms_px"] < 1.0
    d = car["deviation"]
    assert max(abs(d[a]) for a in ("x_mm", "y_mm", "z_mm")) < 3.0
    assert max(abs(d[a]) for a in ("yaw_deg", "pitch_deg", "roll_deg")) < 0.06
    edge = car["body_edge"]
    assert edge["found"] >= 0.9 * edge["outline_points"] >= 500
    assert 1.0 < abs(edge["offset_median_px"]) < 4.0
    ecs = car["station"]["station_ecs"]
    assert ecs["2-1"]["value"] > 2.0 and ecs["2-3"]["value"] is not None  # the bumper shows
    assert ecs["2-3"]["sigma"] > 0  # the edge finder's σ, propagated
    assert all(r.startswith(("infeasible car: 2-", "EC 2-", "marginal: EC 2-"))
               for r in car["reasons"]), car["reasons"]
    written, output = load_params(out / "back.yaml")
    assert (output.width, output.height) == (1280, 720)
    assert written.rad == pytest.approx(480.0) and written.zoom == pytest.approx(0.6)
    for name in ("back_rvm.png", "back_annotated.png", "eol.csv", "eol.html"):
        assert (out / name).is_file()
