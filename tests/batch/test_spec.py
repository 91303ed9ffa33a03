"""batch.spec: sweep files, their axes and design points; bad files are one-line
SweepFileErrors naming the file, the key and its line."""

from __future__ import annotations


import pytest

from rvmsim.batch import design_points, load_sweep, point_scene_doc
from rvmsim.errors import CriteriaError, SweepFileError

from ..cli_runner import run_in_process
from .conftest import SWEEP, write_sweep


def test_design_points_and_scenes(sweep_file):
    spec = load_sweep(sweep_file)
    pts = design_points(spec)
    assert [dict(p.values) for p in pts[:3]] == [
        {"camera_height_m": 0.9, "pitch_deg": 28}, {"camera_height_m": 0.9, "pitch_deg": 34},
        {"camera_height_m": 1.0, "pitch_deg": 28}]
    doc, config = point_scene_doc(spec, pts[3].values)
    assert doc["camera"]["mount"]["position"][1] == -1.0
    assert doc["camera"]["mount"]["pitch_deg"] == 34.0
    assert config == {"output": {"size": [320, 180]}}
    assert len({p.key for p in pts}) == 6
    assert len({p.task_key for p in pts}) == 6
    assert pts[3].label == "camera_height_m=1.0, pitch_deg=34"


def test_ranges_paths_and_named_axes(tmp_path):
    f = write_sweep(tmp_path, SWEEP.replace(
        "  pitch_deg: [28, 34]\n",
        "  pitch_deg: {start: 25, stop: 31, step: 3}\n  vehicle.bumper.top: [0.7, 0.8]\n"
        "  focal_length_px: [90.0]\n  output_size: [[320, 180]]\n"))
    spec = load_sweep(f)
    assert dict(spec.axes)["pitch_deg"] == (25.0, 28.0, 31.0)
    pts = design_points(spec)
    assert len(pts) == 3 * 3 * 2
    doc, config = point_scene_doc(spec, pts[-1].values)
    assert doc["vehicle"]["bumper"]["top"] == 0.8
    assert doc["camera"]["intrinsics"]["fx"] == 90.0 and doc["camera"]["intrinsics"]["fy"] == 90.0
    assert config["output"]["size"] == [320, 180]


# (edit of SWEEP, part of the message, key, line)
BAD = [
    (("  pitch_deg: [28, 34]", "  tilt: [28, 34]"), "axes.tilt: unknown axis", "axes.tilt", 5),
    (("  pitch_deg: [28, 34]", "  vehicle.spoiler.top: [1]"),
     "axes.vehicle.spoiler.top: the base scene has no key", "axes.vehicle.spoiler.top", 5),
    (("  pitch_deg: [28, 34]", "  pitch_deg: [28, 120]"),
     "design point camera_height_m=0.9, pitch_deg=120: camera.mount.pitch_deg: ", "axes", 3),
    (("strategy: cmaes", "strategy: annealing"), "tune.strategy: 'annealing' is not one of",
     "tune.strategy", 7),
    (("base_scene: base.yaml", "base_scene: nothere.yaml"), "nothere.yaml", "base_scene", 2),
    (("  pitch_deg: [28, 34]", "  pitch_deg: {start: 1, stop: 2}"),
     "give a range either num or step", "axes.pitch_deg", 5),
]


@pytest.mark.parametrize("edit, message, key, line", BAD)
def test_bad_sweep_files_are_one_line_errors(tmp_path, edit, message, key, line):
    f = write_sweep(tmp_path, SWEEP.replace(*edit))
    with pytest.raises(SweepFileError) as info:
        load_sweep(f)
    assert (info.value.file, info.value.key, info.value.line) == (str(f), key, line)
    res = run_in_process(["sweep", f, "--out", tmp_path / "o", "--no-progress"])
    assert res.code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.stderr, res.stderr
    assert message in lines[0] and f"{f}:{line}: " in lines[0]


@pytest.mark.parametrize("edit, key, line", [
    (("config: {output: {size: [320, 180]}}", "config: {outpt: {size: [320, 180]}}"),
     "tune.config.outpt", 10),
    (("  pitch_deg: [28, 34]", "  pitch_deg: {start: 1, stop: 2000, step: 1}"),
     "axes.pitch_deg", 5),
    (("  pitch_deg: [28, 34]", "  pitch_deg: []"), "axes.pitch_deg", 5),
    (("  pitch_deg: [28, 34]", "  output_size: [5]"), "axes.output_size", 5),
    (("  pitch_deg: [28, 34]", "  name.x: [1]"), "axes.name.x", 5),
    ((SWEEP, SWEEP + "map: [a, b]\n"), "map", 11),
])
def test_more_sweep_file_errors_name_key_and_line(tmp_path, edit, key, line):
    f = write_sweep(tmp_path, SWEEP.replace(*edit))
    with pytest.raises(SweepFileError) as info:
        load_sweep(f)
    assert (info.value.key, info.value.line) == (key, line)
    assert str(info.value).startswith(f"{f}:{line}: {key}: ")


def test_a_bad_criteria_file_fails_when_the_sweep_is_loaded(tmp_path):
    f = write_sweep(tmp_path, SWEEP.replace("seed: 3", "seed: 3\n  criteria: c.yaml"))
    (tmp_path / "c.yaml").write_text("criteria: {9-9: {}}\n")
    with pytest.raises(CriteriaError, match="c.yaml"):
        load_sweep(f)
    with pytest.raises(CriteriaError, match="nope.yaml: file not found"):
        load_sweep(write_sweep(tmp_path / "n", SWEEP.replace("seed: 3",
                                                             "seed: 3\n  criteria: nope.yaml")))


@pytest.mark.parametrize("axes, key, words", [
    ("  pitch_deg: [28, abc]\n", "axes.pitch_deg", "value 2 ('abc'): must be a number"),
    ("  pitch_deg: {start: 1, stop: .nan, num: 3}\n", "axes.pitch_deg.stop", "finite"),
    ("  output_size: [[100000, 100000]]\n", "axes.output_size", "16..8192"),
    ("  output_size: [[8192, 8192]]\n", "axes.output_size", "RVMSIM_MAX_IMAGE_PIXELS"),
    ("  pitch_deg: {start: 0, stop: 1.0e300, step: 1.0e-300}\n", "axes.pitch_deg", "values"),
])
def test_axis_values_are_checked_at_load(tmp_path, axes, key, words):
    f = write_sweep(tmp_path, SWEEP.replace("  pitch_deg: [28, 34]\n", axes))
    with pytest.raises(SweepFileError) as err:
        load_sweep(f)
    assert err.value.key == key and words in str(err.value), str(err.value)


def test_the_point_count_is_refused_before_points_are_built_unless_allowed(tmp_path):
    import time

    from rvmsim.batch.spec import MAX_SWEEP_POINTS

    big = ("  pitch_deg: {start: 0, stop: 45, num: 1000}\n"
           "  yaw_deg: {start: -45, stop: 45, num: 1000}\n")
    f = write_sweep(tmp_path / "big", SWEEP.replace("  pitch_deg: [28, 34]\n", big))
    start = time.perf_counter()
    with pytest.raises(SweepFileError, match="3000000 design points.*--allow-large") as err:
        load_sweep(f)
    assert err.value.key == "axes" and time.perf_counter() - start < 5
    over = "  pitch_deg: {start: 28, stop: 34, num: %d}\n" % (MAX_SWEEP_POINTS // 3 + 1)
    f = write_sweep(tmp_path / "over", SWEEP.replace("  pitch_deg: [28, 34]\n", over))
    with pytest.raises(SweepFileError, match="over the limit"):
        load_sweep(f)
    spec = load_sweep(f, allow_large=True)
    assert len(design_points(spec)) == 3 * (MAX_SWEEP_POINTS // 3 + 1)
