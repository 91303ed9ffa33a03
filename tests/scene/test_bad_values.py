"""Values a scene file may hold but the pipeline cannot use (huge images, infinite or absurd
intrinsics, NaN anywhere), in every section of a scene: each refused when the scene loads,
with one line naming the file and the dotted key (issue #14, groups 1 and 2).

This is the library's contract; every command loads scenes through :func:`load_scene`, and
tests/bad_input/test_scene_files.py runs one case per error class through the command line.
"""

from __future__ import annotations

import math

import pytest

from rvmsim.errors import SceneError
from rvmsim.scene import load_scene
from rvmsim.testing.scenes import write_small_scene

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

CASES = VALUES + [(i, "camera.intrinsics", v, key) for i, v, key in INTRINSICS]


@pytest.mark.parametrize("key, value, named", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_a_value_the_pipeline_cannot_use_is_refused_at_load(tmp_path, key, value, named):
    path = write_small_scene(tmp_path, "a", name="scene.yaml", edit={key: value})
    with pytest.raises(SceneError) as err:
        load_scene(path)
    key_named = err.value.key
    assert key_named == named or key_named.startswith(named + "."), str(err.value)
    line = str(err.value)
    assert "\n" not in line and str(path) in line and named in line
