"""`rvmsim eol` on bad input: one line naming the file (and key), exit 2, nothing written
over in the output folder."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from rvmsim.compensation import Deviation

from ..cli_runner import run_in_process
from rvmsim.testing.stations import STATION_MAT, capture, write_capture, write_inputs

#: What a previous run left in the output folder: must stay as it is.
OLD = {"eol.json": '{"old": true}\n', "eol.csv": "old\n", "car.yaml": "# old\n",
       "car_rvm.png": "not a png"}


def _old_out(folder: Path) -> Path:
    out = folder / "out"
    out.mkdir(parents=True)
    for name, text in OLD.items():
        (out / name).write_text(text)
    return out


def _unchanged(out: Path) -> None:
    assert sorted(p.name for p in out.iterdir()) == sorted(OLD)
    for name, text in OLD.items():
        assert (out / name).read_text() == text


def _eol(tmp_path: Path, cap: Path, *, eol: dict[str, Any] | None = None):
    scene, params = write_inputs(tmp_path, eol=eol)
    out = _old_out(tmp_path)
    res = run_in_process(["eol", scene, "--params", params, "--capture", cap, "--out", out,
                          "--no-progress"], env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    return res, out, scene


def _one_line(res, *parts: str) -> None:
    assert res.code == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rvmsim: error: "), res.stderr
    assert "Traceback" not in res.stderr
    for p in parts:
        assert p in lines[0], (p, lines[0])


@pytest.fixture
def good_capture(tmp_path: Path) -> Path:
    return write_capture(tmp_path / "caps" / "car.png", Deviation(1, 0, 0, 0.2, 0, 0))


@pytest.mark.parametrize("eol, key, words", [
    ({"target": "no such mat", "ground_patterns": [STATION_MAT]}, "eol.target",
     "neither 'board' nor the name of a ground pattern ('station mat')"),
    ({"target": "station mat", "ground_patterns": [STATION_MAT], "pose": {"position": [0, 0, 1]}},
     "eol.pose", "position cannot place a ground pattern"),
    ({"target": "board", "pose": {"pitch_deg": 20}}, "eol.pose", "need placement: free"),
    ({"target": "station mat", "ground_patterns": [STATION_MAT, STATION_MAT]}, "eol.target",
     "names 2 ground patterns"),
    ({"target": "station mat"}, "eol.target", "(the scene has none)"),
], ids=["unknown target", "pattern placed like a board", "board pitched", "two mats",
        "pattern not defined"])
def test_a_bad_eol_section_is_one_line(tmp_path: Path, good_capture: Path, eol, key, words):
    res, out, scene = _eol(tmp_path, good_capture, eol=eol)
    _one_line(res, str(scene), key, words)
    _unchanged(out)


@pytest.mark.parametrize("pose, where", [
    ({"origin": [-3.0, 60.0]}, "60 m behind the car: its squares are too small"),
    ({"origin": [-3.0, -9.0]}, "under the car"),
])
def test_a_target_out_of_view_is_one_line(tmp_path: Path, good_capture: Path, pose, where):
    res, out, scene = _eol(tmp_path, good_capture,
                           eol={"target": "station mat", "ground_patterns": [STATION_MAT],
                                "pose": pose})
    _one_line(res, str(scene), "eol.pose", "the target (station mat) is not in the camera's view")
    _unchanged(out)


def test_a_scene_of_one_loaded_car_is_one_line(tmp_path: Path, good_capture: Path):
    """The station stands every car in the compensation's measured_at; a scene with a
    load_state of its own (an exported robustness sample) is refused, named."""
    scene, params = write_inputs(tmp_path, edit={"load_state": {"name": "full load",
                                                                "height_mm": -45}})
    out = _old_out(tmp_path)
    res = run_in_process(["eol", scene, "--params", params, "--capture", good_capture,
                          "--out", out, "--no-progress"],
                         env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    _one_line(res, str(scene), "load_state: a scene with a load state is one loaded car")
    _unchanged(out)


def test_a_corrupt_capture_is_one_line(tmp_path: Path, good_capture: Path):
    bad = tmp_path / "caps" / "broken.png"
    bad.write_bytes(good_capture.read_bytes()[:5000])
    res, out, _ = _eol(tmp_path, tmp_path / "caps")  # the folder: good car, then the broken
    _one_line(res, str(bad), "cannot read capture")
    _unchanged(out)


def test_a_capture_of_another_size_is_one_line(tmp_path: Path, good_capture: Path):
    from rvmsim._io import write_png

    small = write_png(tmp_path / "caps" / "small.png", capture(Deviation())[::2, ::2].copy())
    res, out, _ = _eol(tmp_path, tmp_path / "caps")
    _one_line(res, str(small), "capture is 320×240 px but the scene's camera.image_size is "
                               "640×480 px")
    _unchanged(out)


def test_a_missing_capture_and_a_bad_compensation_file_are_one_line(tmp_path: Path,
                                                                     good_capture: Path):
    res, out, _ = _eol(tmp_path, tmp_path / "caps" / "nope.png")
    _one_line(res, "nope.png", "capture not found")
    _unchanged(out)
    comp = tmp_path / "comp.yaml"
    comp.write_text("station:\n  measured_at: trailer\n")
    scene, params = write_inputs(tmp_path)
    res = run_in_process(["eol", scene, "--params", params, "--capture", good_capture, "--out",
                          out, "--compensation", comp, "--no-progress"],
                         env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    _one_line(res, str(comp), "station.measured_at", "'trailer' is not a load state")
    _unchanged(out)


def test_help_and_usage_errors(tmp_path: Path):
    res = run_in_process(["eol", "--help"])
    assert res.code == 0 and "eol [OPTIONS] SCENE" in res.stdout and "--compensation" in res.stdout
    res = run_in_process(["eol", "s.yaml", "--capture", "c.png", "--out", tmp_path / "o"])
    assert res.code == 2 and res.stderr == "rvmsim eol: --params: required option not given\n"
    res = run_in_process(["eol", "s.yaml", "--params", "p.yaml", "--capture", "c.png",
                          "--out", tmp_path / "o", "--min-landmarks", "3"])
    assert res.code == 2 and res.stderr.startswith("rvmsim eol: --min-landmarks: 3 is not")
    assert not (tmp_path / "o").exists()


def test_a_setting_whose_view_shows_no_ground_is_one_line(tmp_path: Path, good_capture: Path):
    """The law needs reference ground points in the platform setting's RVM image."""
    import yaml

    scene, params = write_inputs(tmp_path)
    doc = yaml.safe_load(params.read_text())
    doc.update(h_pan=80.0, v_pan=-90.0)  # the view turned up into the sky
    params.write_text(yaml.safe_dump(doc))
    out = _old_out(tmp_path)
    res = run_in_process(["eol", scene, "--params", params, "--capture", good_capture,
                          "--out", out, "--no-progress"],
                         env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    _one_line(res, "reference", "only 0 reference ground points are in the RVM image")
    _unchanged(out)


def test_a_capture_folders_dangling_link_is_refused(tmp_path: Path, good_capture):
    """A link to a missing capture beside a good one is an error naming it, not a car
    silently left out ("1 of 1 cars pass")."""
    entry = good_capture.parent / "car_b.png"
    entry.symlink_to(tmp_path / "gone.png")
    res, out, _ = _eol(tmp_path, good_capture.parent)
    _one_line(res, str(entry), "a link to a missing file")
    _unchanged(out)


@pytest.mark.parametrize("text, key", [
    ("", "empty: no ISP parameters"),
    ("# the platform setting\n", "empty: no ISP parameters"),
    ("fov: 190\nrad: 600\n", "h_shift: not given"),
    ("output: {size: [1280, 720]}\n", "fov: not given"),
], ids=["empty", "comments only", "two of 14", "output only"])
def test_a_platform_setting_that_leaves_parameters_to_the_defaults_is_refused(
        tmp_path: Path, good_capture: Path, text: str, key: str):
    """A station must never write the defaults into a car: every parameter named."""
    scene, _ = write_inputs(tmp_path)
    params = tmp_path / "platform.yaml"
    params.write_text(text)
    out = _old_out(tmp_path)
    res = run_in_process(["eol", scene, "--params", params, "--capture", good_capture,
                          "--out", out, "--no-progress"],
                         env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    _one_line(res, str(params), key)
    _unchanged(out)


def test_a_second_station_run_into_a_folder_in_use_is_refused(tmp_path: Path,
                                                              good_capture: Path):
    """Another process's station run holds the folder: one line naming it, exit 2, the
    folder as it was."""
    out = _old_out(tmp_path)
    holder = subprocess.Popen(
        [sys.executable, "-c", "import sys, time\n"
         "from rvmsim.eol.outputs import output_lock\n"
         "output_lock(sys.argv[1]).acquire(); print('held', flush=True); time.sleep(120)",
         str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "held\n"
        scene, params = write_inputs(tmp_path)
        res = run_in_process(["eol", scene, "--params", params, "--capture", good_capture,
                              "--out", out, "--no-progress"],
                             env={"RVMSIM_CACHE": str(tmp_path / "cache")})
        _one_line(res, str(out), f"in use by process {holder.pid}")
    finally:
        holder.kill()
        holder.communicate()
    assert sorted(p.name for p in out.iterdir()) == sorted([*OLD, "eol.lock", "eol.pid"])
    for name, text in OLD.items():
        assert (out / name).read_text() == text
