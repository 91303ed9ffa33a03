"""Bad sweep files (issue #14, groups 2 and 7): axis values that are not numbers, ranges
with NaN or endless counts, RVM output sizes over the limits (refused at load, not when a
point runs), too many design points (counted before any is built), YAML over the limits."""

from __future__ import annotations

import pytest

from .bombs import BOMBS
from .conftest import SMALL_SCENE
from .harness import ENDLESS, MEMORY, Case, check_case

S = "s.yaml"
SWEEP = ("sweep", S, "--out", "so", "--workers", "1", "--no-progress")
HEAD = f"name: bad\nbase_scene: {SMALL_SCENE}\ntune: {{strategy: random, budget: 4}}\naxes:\n"


def _file(axes: str, head: str = HEAD):
    return lambda folder: (folder / S).write_text(head + axes)


#: (case id, axes section, key named)
FILES = [
    ("value-text", "  pitch_deg: [28, abc]\n", "axes.pitch_deg"),
    ("value-bool", "  camera_height_m: [true]\n", "axes.camera_height_m"),
    ("value-nan", "  yaw_deg: [.nan]\n", "axes.yaw_deg"),
    ("value-inf", "  lens_fov_deg: [.inf]\n", "axes.lens_fov_deg"),
    ("value-list", "  focal_length_px: [[1, 2]]\n", "axes.focal_length_px"),
    ("value-400-digits", "  roll_deg: [" + "9" * 400 + "]\n", "axes.roll_deg"),
    ("stop-nan", "  pitch_deg: {start: 1, stop: .nan, num: 3}\n", "axes.pitch_deg.stop"),
    ("start-inf", "  pitch_deg: {start: -.inf, stop: 3, num: 3}\n", "axes.pitch_deg.start"),
    ("step-nan", "  pitch_deg: {start: 1, stop: 3, step: .nan}\n", "axes.pitch_deg.step"),
    ("step-endless", "  pitch_deg: {start: 0, stop: 1.0e300, step: 1.0e-300}\n",
     "axes.pitch_deg"),
    ("num-400-digits", "  pitch_deg: {start: 1, stop: 3, num: " + "9" * 400 + "}\n",
     "axes.pitch_deg.num"),
    ("range-unknown-key", "  pitch_deg: {start: 1, stop: 3, count: 3}\n",
     "axes.pitch_deg.count"),
    ("axis-scalar", "  pitch_deg: 30\n", "axes.pitch_deg"),
    ("list-too-long", "  pitch_deg: [" + ", ".join(["30"] * 1001) + "]\n", "axes.pitch_deg"),
    ("output-size-huge", "  output_size: [[100000, 100000]]\n", "axes.output_size"),
    ("output-size-pixels", "  output_size: [[8192, 8192]]\n", "axes.output_size"),
    ("output-size-text", "  output_size: [[320, wide]]\n", "axes.output_size"),
    ("million-points", "  pitch_deg: {start: 0, stop: 45, num: 1000}\n"
                       "  yaw_deg: {start: -45, stop: 45, num: 1000}\n", "axes"),
    ("points-over-limit", "  pitch_deg: {start: 0, stop: 45, num: 40}\n"
                          "  yaw_deg: {start: -45, stop: 45, num: 40}\n", "axes"),
    ("scene-key-nan", "  vehicle.bumper.width: [.inf]\n", "vehicle.bumper.width"),
    ("scene-size-huge", "  camera.image_size: [[100000, 100000]]\n", "camera.image_size"),
]
#: Cases run in a child of their own (the others run in this process).
ISOLATED = {"step-endless": ENDLESS, "million-points": ENDLESS, "points-over-limit": ENDLESS,
            "list-too-long": ENDLESS, "output-size-huge": MEMORY, "output-size-pixels": MEMORY,
            "scene-size-huge": MEMORY}
CASES = [Case(f"sweep-{i}", SWEEP, (S, key), _file(axes),
              isolate=ISOLATED.get(i, "")) for i, axes, key in FILES]
CASES += [Case(f"sweep-yaml-{i}", SWEEP, (S, "limit"),
               _file("  pitch_deg: [28]\n" + text), isolate=why)
          for i, text, why in BOMBS]
CASES += [
    Case("sweep-tune-config-size", SWEEP, (S, "tune.config.output.size"),
         _file("  pitch_deg: [28]\n", HEAD.replace("budget: 4", "budget: 4, config: "
                                                   "{output: {size: [8192, 8192]}}")), isolate=MEMORY),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_sweep_file(case, case_dir):
    check_case(case, case_dir)
