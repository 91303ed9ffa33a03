"""The lens-model interface: a model written against it (here a stereographic lens, which
rvmsim does not ship) gets a working inverse from the shared Newton solver, and registered
by name a scene chooses it with ``camera.lens.model``."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvmsim.camera import LENS_MODELS, LensModel, make_lens, newton_undistort, register_lens_model
from rvmsim.errors import SceneError
from rvmsim.pose import PoseSettings, find_mount
from rvmsim.render import render_fisheye
from rvmsim.scene import checker_corners, load_scene
from rvmsim.testing.captures import board_scene, degrade

from rvmsim.testing.scenes import load_small_scene, small_scene_text


class Stereographic(LensModel):
    """θ_d = 2·tan(θ / 2)."""

    name = "stereographic"

    def distort(self, theta: np.ndarray) -> np.ndarray:
        return 2.0 * np.tan(theta / 2.0)

    def distort_derivative(self, theta: np.ndarray) -> np.ndarray:
        return 1.0 / np.cos(theta / 2.0) ** 2

    def undistort(self, theta_d: np.ndarray, *, theta_max: float) -> np.ndarray:
        return newton_undistort(self.distort, self.distort_derivative, theta_d, theta_max)


def test_newton_inverts_a_new_model_and_flags_out_of_range():
    lens = Stereographic()
    theta = np.linspace(0.0, 1.6, 400)
    np.testing.assert_allclose(lens.undistort(lens.distort(theta), theta_max=1.65), theta,
                               atol=1e-10)
    np.testing.assert_allclose(lens.undistort(np.array([1.0]), theta_max=1.65),
                               2 * np.arctan(0.5), atol=1e-12)
    # 2·tan(1.65·1.5 / 2) ≈ 5.2: θ_d = 50 lies beyond the lens's reach on [0, 1.5·θ_max]
    assert lens.undistort(np.array([50.0]), theta_max=1.65)[0] > 1.65


def test_monotonic_check_uses_the_derivative():
    class Folding(Stereographic):
        def distort_derivative(self, theta: np.ndarray) -> np.ndarray:
            return np.cos(theta)  # ≤ 0 from 90°

    assert Stereographic().is_monotonic(2.0)
    assert Folding().is_monotonic(1.5) and not Folding().is_monotonic(1.6)


@pytest.fixture
def stereographic():
    """The stereographic lens registered under its name for one test (then removed)."""
    def build(k):
        if k is not None and any(k):
            raise ValueError("model stereographic takes no k")
        return Stereographic()

    register_lens_model("stereographic", build)
    yield
    LENS_MODELS.pop("stereographic")


def test_a_registered_lens_model_is_chosen_by_name_and_projects_as_it_says(stereographic):
    """A scene's ``camera.lens.model`` chooses the lens by name (no coefficient sniffing):
    the stereographic lens projects points where r = f·2·tan(θ/2) puts them."""
    scene = load_small_scene("a", edit={"camera.lens.model": "stereographic"})
    cam = scene.fisheye_camera()
    assert cam.lens_model == "stereographic" and isinstance(cam.lens, Stereographic)
    rng = np.random.default_rng(0)
    rays = rng.normal(size=(200, 3))
    rays[:, 2] = np.abs(rays[:, 2]) + 0.2  # in front of the lens
    world = cam.position + 3.0 * (rays / np.linalg.norm(rays, axis=1, keepdims=True)) @ cam.rotation.T
    uv, ok = cam.project(world)
    local = (world - cam.position) @ cam.rotation  # camera frame
    theta = np.arctan2(np.hypot(local[:, 0], local[:, 1]), local[:, 2])
    phi = np.arctan2(local[:, 1], local[:, 0])
    r = 2.0 * np.tan(theta / 2.0)
    want = np.stack([cam.fx * r * np.cos(phi) + cam.skew * cam.fx * r * np.sin(phi) + cam.cx,
                     cam.fy * r * np.sin(phi) + cam.cy], axis=1)
    np.testing.assert_allclose(uv[ok], want[ok], atol=1e-6)
    # the scene's equidistance camera is not the same lens
    plain = load_small_scene("a").fisheye_camera()
    assert plain.lens_model == "equidistance" and not np.allclose(plain.project(world)[0], uv)
    # the camera copies made for load states and scaled sensors keep the model
    assert cam.scaled(0.5).lens_model == "stereographic"


def test_an_unknown_lens_model_is_one_line_naming_the_key(tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(small_scene_text("a", edit={"camera.lens.model": "pinhole9"}))
    with pytest.raises(SceneError) as err:
        load_scene(path)
    text = str(err.value)
    assert "camera.lens" in text and "unknown lens model 'pinhole9'" in text
    assert "equidistance" in text and len(text.splitlines()) == 1
    with pytest.raises(ValueError, match="unknown lens model"):
        make_lens("pinhole9", None)
    with pytest.raises(ValueError, match="taken"):
        register_lens_model("equidistance", lambda k: Stereographic())


def test_the_pose_search_works_through_a_registered_lens_model(stereographic):
    """The pose search (board start, matching, fisheye PnP) uses the camera's own lens, not
    cv2.fisheye's: a board seen through a stereographic lens from a mount 15 mm and 0.6° off
    the scene's is found where it is.  One board leaves pitch and height coupled (the same
    picture within a tenth of a degree), so the check is the picture: the board's corners
    projected from the recovered pose land within 0.5 px of where the true camera sees them,
    while the scene's pose puts them several px away."""
    def stereo(scene):
        lens = scene.camera.lens.model_copy(update={"model": "stereographic", "k": None})
        return scene.model_copy(update={"camera": scene.camera.model_copy(update={"lens": lens})})

    nominal = stereo(board_scene())
    truth = render_fisheye(stereo(board_scene((0.015, 0.0, -0.01), (0.6, -0.4, 0.3))))
    assert truth.camera.lens_model == "stereographic"
    fit = find_mount(nominal, degrade(truth.color, truth.labels), render_fisheye(nominal),
                     PoseSettings())
    c = fit.correction
    np.testing.assert_allclose(c.d_position_mm, (15.0, 0.0, -10.0), atol=3.0)
    assert c.max_d_angle_deg == pytest.approx(0.6, abs=0.1)
    corners = np.array([k.point for k in checker_corners(nominal)])
    want, ok = truth.camera.project(corners)
    found = dataclasses.replace(truth.camera, position=fit.position_m, rotation=fit.rotation)
    got, _ = found.project(corners)
    before, _ = nominal.fisheye_camera().project(corners)
    assert np.abs(got[ok] - want[ok]).max() < 0.5
    assert np.abs(before[ok] - want[ok]).max() > 5.0
