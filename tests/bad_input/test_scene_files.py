"""Bad scene files (issue #14, groups 1 and 2): values the schema used to accept but the
pipeline could not handle (huge images, infinite or absurd intrinsics, NaN anywhere), and
YAML over the limits; every section of a scene, through every command that reads one."""

from __future__ import annotations

import math

import pytest

from .bombs import BOMBS
from .conftest import SMALL_SCENE, small_scene
from .harness import MEMORY, Case, check_case

RENDER = ("render", SMALL_SCENE, "--out", "r", "--no-progress")


def _edit(key: str, value, *more) -> object:
    edits = {key: value, **dict(zip(more[::2], more[1::2]))}
    return lambda folder: small_scene(folder, edits)


#: (case id, dotted key set, value, key named in the error)
VALUES = [
    ("size-huge", "camera.image_size", [100000, 100000], "camera.image_size"),
    ("size-pixels", "camera.image_size", [8000, 8000], "camera.image_size"),
    ("size-tiny", "camera.image_size", [8, 8], "camera.image_size"),
    ("size-400-digits", "camera.image_size", [10**400, 240], "camera.image_size"),
    ("fx-inf", "camera.intrinsics.fx", math.inf, "camera.intrinsics.fx"),
    ("fx-1e308", "camera.intrinsics.fx", 1e308, "camera.intrinsics.fx"),
    ("fx-tiny", "camera.intrinsics.fx", 1e-6, "camera.intrinsics.fx"),
    ("fy-nan", "camera.intrinsics.fy", math.nan, "camera.intrinsics.fy"),
    ("fy-huge", "camera.intrinsics.fy", 5e6, "camera.intrinsics.fy"),
    ("cx-1e6", "camera.intrinsics.cx", 1.0e6, "camera.intrinsics.cx"),
    ("cy-far", "camera.intrinsics.cy", -1.0e5, "camera.intrinsics.cy"),
    ("cx-nan", "camera.intrinsics.cx", math.nan, "camera.intrinsics.cx"),
    ("skew-nan", "camera.intrinsics.skew", math.nan, "camera.intrinsics.skew"),
    ("skew-huge", "camera.intrinsics.skew", 50.0, "camera.intrinsics.skew"),
    ("lens-fov-nan", "camera.lens.fov_deg", math.nan, "camera.lens.fov_deg"),
    ("position-nan", "camera.mount.position", [0.0, math.nan, 0.1], "camera.mount.position.1"),
    ("position-far", "camera.mount.position", [1e9, -1.0, 0.1], "camera.mount.position.0"),
    ("position-inf", "camera.mount.position", [0.0, -1.0, -math.inf], "camera.mount.position.2"),
    ("pitch-inf", "camera.mount.pitch_deg", math.inf, "camera.mount.pitch_deg"),
    ("yaw-nan", "camera.mount.yaw_deg", math.nan, "camera.mount.yaw_deg"),
    ("roll-nan", "camera.mount.roll_deg", math.nan, "camera.mount.roll_deg"),
    ("bumper-width-inf", "vehicle.bumper.width", math.inf, "vehicle.bumper.width"),
    ("bumper-width-1e30", "vehicle.bumper.width", 1e30, "vehicle.bumper.width"),
    ("bumper-top-nan", "vehicle.bumper.top", math.nan, "vehicle.bumper.top"),
    ("bumper-lean-nan", "vehicle.bumper.lean_deg", math.nan, "vehicle.bumper.lean_deg"),
    ("garnish-depth-inf", "vehicle.garnish.depth", math.inf, "vehicle.garnish.depth"),
    ("trunk-sweep-nan", "vehicle.trunk.sweep", math.nan, "vehicle.trunk.sweep"),
    ("paint-nan", "vehicle.paint", [math.nan, 0.5, 0.5], "vehicle.paint.0"),
    ("object-height-nan", "test_site.object_height", math.nan, "test_site.object_height"),
    ("object-position-nan", "test_site.objects", {"A": {"position": [math.nan, 1.0]}},
     "test_site.objects.A.position.0"),
    ("object-position-far", "test_site.objects", {"B": {"position": [0.0, 1e12]}},
     "test_site.objects.B.position.1"),
    ("guidelines-side-inf", "test_site.guidelines", {"side_x": [-math.inf, 0.9]},
     "test_site.guidelines.side_x.0"),
    ("guidelines-cross-nan", "test_site.guidelines", {"cross_z": [0.5, math.nan]},
     "test_site.guidelines.cross_z.1"),
    ("guidelines-width-inf", "test_site.guidelines", {"line_width": math.inf},
     "test_site.guidelines.line_width"),
    ("board-square-nan", "test_site.board", {"square_size": math.nan},
     "test_site.board.square_size"),
    ("board-position-far", "test_site.board", {"position": [0.0, 0.0, 1e9]},
     "test_site.board.position.2"),
    ("pattern-square-nan", "test_site.ground_patterns",
     [{"square_size": math.nan, "checker": [[0, 0, 1, 1]]}],
     "test_site.ground_patterns.0.square_size"),
    ("pattern-checker-inf", "test_site.ground_patterns",
     [{"square_size": 0.1, "checker": [[0, 0, math.inf, 1]]}],
     "test_site.ground_patterns.0.checker.0.2"),
    ("ground-size-inf", "test_site.ground_size", math.inf, "test_site.ground_size"),
    ("ground-size-1e12", "test_site.ground_size", 1e12, "test_site.ground_size"),
    ("oversample-nan", "render.oversample", math.nan, "render.oversample"),
    ("sky-nan", "render.sky_color", [math.nan, 0.5, 0.5], "render.sky_color.0"),
]

#: Ways of giving the intrinsics whose focal length is out of range: (id, intrinsics, key)
INTRINSICS = [
    ("K-inf", {"K": [[math.inf, 0, 160], [0, 100, 120], [0, 0, 1]]}, "camera.intrinsics.K"),
    ("K-huge-f", {"K": [[1e6, 0, 160], [0, 100, 120], [0, 0, 1]]}, "camera.intrinsics.K"),
    ("K-far-centre", {"K": [[100, 0, 1e6], [0, 100, 120], [0, 0, 1]]}, "camera.intrinsics.K"),
    ("hfov-tiny", {"horizontal_fov_deg": 1e-9}, "camera.intrinsics.horizontal_fov_deg"),
    ("focal-mm-tiny", {"focal_length_mm": 1e-6, "pixel_pitch_um": 3.0},
     "camera.intrinsics.focal_length_mm"),
    ("pitch-um-nan", {"focal_length_mm": 1.0, "pixel_pitch_um": math.nan},
     "camera.intrinsics.pixel_pitch_um"),
]


#: Cases run in a child of their own (the others run in this process): sensors over the
#: pixel limit, and focal lengths that would ask for the largest cube faces.
ISOLATED = {"size-huge": MEMORY, "size-pixels": MEMORY, "fx-1e308": MEMORY, "fy-huge": MEMORY,
            "K-huge-f": MEMORY}


def _yaml_bomb(text: str):
    def setup(folder):
        scene = small_scene(folder)
        scene.write_text(scene.read_text() + text)
    return setup


CASES = (
    [Case(f"scene-{i}", RENDER, (SMALL_SCENE, key), _edit(k, v),
          isolate=ISOLATED.get(i, "")) for i, k, v, key in VALUES]
    + [Case(f"scene-{i}", RENDER, (SMALL_SCENE, key), _edit("camera.intrinsics", v), isolate=ISOLATED.get(i, "")) for i, v, key in INTRINSICS]
    + [Case(f"scene-yaml-{i}", RENDER, (SMALL_SCENE, "limit"), _yaml_bomb(text),
            isolate=why) for i, text, why in BOMBS]
    + [
        Case("process-fx-inf", ("process", SMALL_SCENE, "--out", "p", "--no-progress"),
             (SMALL_SCENE, "camera.intrinsics.fx"), _edit("camera.intrinsics.fx", math.inf)),
        Case("evaluate-position-nan", ("evaluate", SMALL_SCENE, "--out", "e", "--no-progress"),
             (SMALL_SCENE, "camera.mount.position.1"),
             _edit("camera.mount.position", [0.0, math.nan, 0.1])),
        Case("tune-size-huge", ("tune", SMALL_SCENE, "--out", "new", "--budget", "4",
                                "--strategy", "random", "--workers", "1", "--no-progress"),
             (SMALL_SCENE, "camera.image_size"), _edit("camera.image_size", [100000, 100000]), isolate=MEMORY),
        Case("validate-cx-far", ("validate", SMALL_SCENE, "--capture", "cap.png",
                                 "--no-progress"),
             (SMALL_SCENE, "camera.intrinsics.cx"), _edit("camera.intrinsics.cx", 1.0e6)),
        Case("render-scaled-over-the-limit", RENDER + ("--scale", "4"),
             (SMALL_SCENE, "camera.image_size", "RVMSIM_MAX_IMAGE_PIXELS"),
             _edit("name", "scaled"), env={"RVMSIM_MAX_IMAGE_PIXELS": "1000000"}),
    ]
)


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_scene_file(case, case_dir):
    check_case(case, case_dir)
