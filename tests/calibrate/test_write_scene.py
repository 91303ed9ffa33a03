"""``--write-scene`` rewrites only the camera's image size, intrinsics and lens in the
scene file's text: its comments and layout elsewhere stay."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from rvmsim.calibrate import camera_block, write_scene_camera
from rvmsim.scene import load_scene

K = np.array([[201.5, 0.0, 321.25], [0.0, 204.75, 238.5], [0.0, 0.0, 1.0]])
D = np.array([-0.031, 0.0042, -0.0019, 0.00021])

BLOCK_STYLE = """\
# Bench scene (comment at the top)
name: Bench   # the name
camera:
  # the sensor
  image_size:
    - 640
    - 480
  intrinsics:            # from the datasheet
    fx: 200.0
    fy: 200.0
  lens:
    model: kannala_brandt
    k: [-0.02, 0.004, -0.001, 0.0]   # old lens
    fov_deg: 190
  # where it sits
  mount: {position: [0.0, -1.0, 0.0]}   # keep me
test_site:
  fmvss: false   # board only
  board: {placement: free, position: [0.2, -1.1, 1.2], squares: [8, 10], square_size: 0.06}
"""

FLOW_STYLE = """\
name: Bench
camera:
  mount: {position: [0.0, -1.0, 0.0]}   # keep me
  image_size: [640, 480]   # pixels
  intrinsics: {fx: 200.0, fy: 200.0}   # datasheet
  lens: {model: kannala_brandt, k: [-0.02, 0.004, -0.001, 0.0], fov_deg: 190}
test_site:
  fmvss: false   # board only
  board: {placement: free, position: [0.2, -1.1, 1.2], squares: [8, 10], square_size: 0.06}
"""


@pytest.mark.parametrize("text", [BLOCK_STYLE, FLOW_STYLE], ids=["block", "flow"])
def test_only_the_three_values_change_and_comments_stay(text, tmp_path):
    path = tmp_path / "bench.yaml"
    path.write_text(text)
    write_scene_camera(path, camera_block(K, D, (640, 480)))
    after = path.read_text()
    scene = load_scene(path)
    cam = scene.fisheye_camera()
    np.testing.assert_allclose(cam.K, K)
    np.testing.assert_allclose(cam.D.ravel(), D)
    assert scene.camera.lens.fov_deg == 190  # kept: the block has no fov
    old, new = yaml.safe_load(text), yaml.safe_load(after)
    assert {k: v for k, v in new.items() if k != "camera"} == \
        {k: v for k, v in old.items() if k != "camera"}
    assert new["camera"]["mount"] == old["camera"]["mount"]
    # every comment outside the replaced values is still there, in order
    kept = [ln.split("#", 1)[1] for ln in text.splitlines()
            if "#" in ln and not any(w in ln for w in ("old lens", "datasheet"))]
    got = [ln.split("#", 1)[1] for ln in after.splitlines() if "#" in ln]
    assert [c for c in got if c in kept] == kept, after


def test_a_flow_style_camera_is_dumped_again(tmp_path):
    """``camera: {…}`` on one line cannot be edited in place: the document is dumped
    again (still a valid scene with the new camera), as the docs say."""
    path = tmp_path / "flow.yaml"
    path.write_text("name: Flow\n"
                    "camera: {image_size: [640, 480], intrinsics: {fx: 200.0, fy: 200.0},"
                    " mount: {position: [0.0, -1.0, 0.0]}}  # gone\n"
                    "test_site: {fmvss: false, board: {placement: free, position: "
                    "[0.2, -1.1, 1.2], squares: [8, 10], square_size: 0.06}}\n")
    write_scene_camera(path, camera_block(K, D, (640, 480)))
    np.testing.assert_allclose(load_scene(path).fisheye_camera().K, K)
