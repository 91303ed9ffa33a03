"""The cube layout: which faces a lens needs, the crops, and the seams between faces."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.camera import FisheyeCamera
from rvmsim.render import FACE_NAMES, GUARD_PX, cube_layout, face_coords, face_rotation

from ..conftest import small_render
from .conftest import label_boundary


def test_cube_seams_leave_no_gaps_or_doubles():
    """Turning the cube moves every seam; labels may only differ at label borders."""
    ref = small_render("a")
    turned = small_render("a", cube_yaw_deg=30.0)
    diff = ref.labels != turned.labels
    border = label_boundary(ref.labels) | label_boundary(turned.labels)
    assert not np.any(diff & ~border), np.argwhere(diff & ~border)[:10]
    assert diff.sum() < 0.1 * border.sum()  # a few of the border pixels, at any image size
    # And along the seams of the reference cube: each seam pixel's label matches the turned
    # cube (where it is not a label border), so no row or column is dropped or repeated.
    rays, ok = ref.camera.image_rays()
    face, _ = face_coords(rays, np.eye(3))
    seam = np.zeros_like(ok)
    seam[:, 1:] |= face[:, 1:] != face[:, :-1]
    seam[1:, :] |= face[1:, :] != face[:-1, :]
    seam &= ok
    assert seam.sum() > 500
    assert not np.any(diff[seam] & ~border[seam])


def _camera(fov_deg: float, width: int = 160, height: int = 120) -> FisheyeCamera:
    f = width / 2 / np.radians(min(fov_deg, 190.0) / 2)
    return FisheyeCamera(width, height, f, f, (width - 1) / 2, (height - 1) / 2, fov_deg=fov_deg)


@pytest.mark.parametrize("fov_deg, faces", [(190.0, {"+z", "+x", "-x", "+y", "-y"}),
                                            (60.0, {"+z"})])
def test_only_the_faces_the_lens_sees(fov_deg, faces):
    layout = cube_layout(_camera(fov_deg), face_size=64)
    assert {FACE_NAMES[f] for f in layout.faces} == faces


def test_face_rotations_are_proper_and_look_along_their_axis():
    for f, name in enumerate(FACE_NAMES):
        r = face_rotation(f)
        np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(r) == pytest.approx(1.0)
        axis = {"x": 0, "y": 1, "z": 2}[name[1]]
        assert r[axis, 2] == (1.0 if name[0] == "+" else -1.0)


def test_atlas_coordinates_reproject_to_the_pixel_rays():
    """Every in-field fisheye pixel's atlas position, taken back through its face camera,
    is that pixel's ray: the fold map is the exact dst → src map."""
    cam = _camera(190.0)
    layout = cube_layout(cam, face_size=96)
    rays, ok = cam.image_rays()
    face, _ = face_coords(rays, np.eye(3))
    for crop in layout.crops:
        sel = ok & (face == crop.face)
        ax = layout.atlas_x[sel] - crop.atlas_x0 + crop.x0
        ay = layout.atlas_y[sel] + crop.y0
        # inside the crop, one pixel of margin for bilinear reads
        assert ax.min() >= crop.x0 + 1 - 1e-3 and ax.max() <= crop.x0 + crop.width - 2 + 1e-3
        d = np.stack([(ax - layout.centre_px) / (layout.face_size / 2),
                      (ay - layout.centre_px) / (layout.face_size / 2), np.ones_like(ax)], 1)
        back = d @ face_rotation(crop.face).T
        back /= np.linalg.norm(back, axis=1, keepdims=True)
        np.testing.assert_allclose(back, rays[sel], atol=1e-5)
    assert np.all(layout.atlas_x[~ok] == -1.0)
    assert layout.atlas_shape[1] == sum(c.width for c in layout.crops)
    assert all(c.x0 >= 0 and c.x0 + c.width <= layout.face_size + 2 * GUARD_PX
               for c in layout.crops)


def test_automatic_face_size_follows_oversample():
    cam = _camera(190.0)
    n1 = cube_layout(cam, oversample=1.0).face_size
    n2 = cube_layout(cam, oversample=2.0).face_size
    assert 16 <= n1 < n2 <= 2 * n1 + 1
    assert cube_layout(cam, oversample=2.0, max_face_size=40).face_size == 40


def test_no_pixel_in_the_field_is_an_error():
    cam = FisheyeCamera(32, 32, 10.0, 10.0, 500.0, 500.0, fov_deg=10.0)
    with pytest.raises(ValueError, match="no pixel"):
        cube_layout(cam)
