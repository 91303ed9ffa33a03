"""rvmsim.robust.images: re-folds of turned cameras against full renders; viewpoints."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.render import CameraRays, cover_layout, refold_layout, render_fisheye
from rvmsim.robust import (LoadState, MountSample, body_pose, draw_samples, sample_camera,
                           sample_images, variation_from_scene)
from rvmsim.scene import checker_corners
from rvmsim.pose.landmarks import spacing_px, usable_corners

from rvmsim.testing.scenes import load_small_scene
from .conftest import ANGLES_ONLY


@pytest.fixture(scope="module")
def fine_scene():
    """640×480 with dense faces (nearest label sampling puts a border within 0.5 / 4 px of
    its true place, in a re-fold as in a full render) and a board of large squares (its
    checker corners are the landmarks)."""
    board = {"square_size": 0.3, "squares": [4, 4], "position": [0.0, 0.0, 1.8]}
    return load_small_scene("a", 0.5, variation=ANGLES_ONLY,
                            edit={"render": {"oversample": 4.0}, "test_site.board": board})


@pytest.fixture(scope="module")
def turned(fine_scene):
    """Three turned samples (±1° draws), their re-folds and full renders of their cameras."""
    samples = draw_samples(variation_from_scene(fine_scene), 8, seed=3)[:3]
    assert all(max(abs(a) for a in s.angles_deg) > 0.2 for s in samples)
    refolds = sample_images(fine_scene, samples)
    fulls = [render_fisheye(fine_scene, camera=im.camera) for im in refolds]
    return samples, refolds, fulls


def test_refold_labels_agree_with_a_full_render(turned):
    _, refolds, fulls = turned
    for im, full in zip(refolds, fulls):
        assert im.labels.shape == full.labels.shape
        agree = float(np.mean(im.labels == full.labels))
        assert agree >= 0.999, agree


def _corners_found(color: np.ndarray, start: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    grey = cv2.cvtColor(np.ascontiguousarray(color), cv2.COLOR_RGB2GRAY).astype(np.float32)
    out = []
    for p, s in zip(start, spacing):
        w = int(np.clip(round(0.3 * s), 3, 12))
        q = cv2.cornerSubPix(grey, p.astype(np.float32).reshape(1, 1, 2), (w, w), (-1, -1),
                             (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-3))
        out.append(q.ravel())
    return np.array(out)


def test_refold_landmarks_match_a_full_render_within_half_a_pixel(fine_scene, turned):
    """The board's checker corners, projected analytically with each turned camera, found
    (cornerSubPix) in the re-fold and in the full render: within 0.5 px of each other, and
    both at the analytic projection."""
    corners = [c for c in checker_corners(fine_scene) if c.label == L.BOARD]
    pts = np.array([c.point for c in corners])
    for im, full in zip(turned[1], turned[2]):
        cam = im.camera
        uv, _ = cam.project(pts)
        spacing = spacing_px(cam, cam.position, cam.rotation, corners)
        usable = usable_corners(cam, corners, full.labels, uv, spacing)
        assert usable.sum() >= 8
        a = _corners_found(im.color, uv[usable], spacing[usable])
        b = _corners_found(full.color, uv[usable], spacing[usable])
        assert np.max(np.linalg.norm(a - b, axis=1)) <= 0.5
        assert np.max(np.linalg.norm(a - uv[usable], axis=1)) <= 0.6


def test_label_centroids_match_a_full_render(turned):
    """Compact label regions (the objects, their stripes and patches, the board, the body
    parts: at least 40 px filling a third of a box at least 5 px a side; thin lines'
    centroids move with
    single pixels at their ends) have their centroids within 0.5 px."""
    checked = 0
    for im, full in zip(turned[1], turned[2]):
        for lab in np.unique(full.labels):
            ys, xs = np.nonzero(full.labels == lab)
            if lab in (L.VOID, L.SKY) or xs.size < 40:
                continue
            bw, bh = np.ptp(xs) + 1, np.ptp(ys) + 1
            if min(bw, bh) < 5 or xs.size < bw * bh / 3:
                continue
            checked += 1
            ys2, xs2 = np.nonzero(im.labels == lab)
            d = np.hypot(xs.mean() - xs2.mean(), ys.mean() - ys2.mean())
            assert d <= 0.5, (int(lab), d)
    assert checked >= 3 * 15


def test_the_unturned_sample_is_the_scene_render():
    sc = load_small_scene("a", 0.25, variation=ANGLES_ONLY)
    nominal = MountSample(0, (0.0,) * 6, (0.0, 0.0, 0.0), LoadState("curb"))
    im = sample_images(sc, [nominal])[0]
    full = render_fisheye(sc)
    assert np.mean(im.labels == full.labels) >= 0.9995
    np.testing.assert_allclose(im.camera.rotation, sc.fisheye_camera().rotation, atol=1e-12)


def test_a_moved_camera_and_a_lowered_body_are_rendered_from_their_viewpoint():
    """A sample 4 mm to the side under a load that lowers the body 40 mm (no pitch) is the
    render of a scene whose camera and vehicle parts are moved so."""
    sc = load_small_scene("a", 0.25, variation=None)
    load = LoadState("full", height_mm=-40.0)
    s = MountSample(0, (4.0, 0.0, 0.0, 0.0, 0.0, 0.0), (4.0, 0.0, 0.0), load)
    im = sample_images(sc, [s])[0]
    doc = sc.model_dump(mode="json")
    doc["camera"]["mount"]["position"][0] += 0.004
    doc["camera"]["mount"]["position"][1] += 0.040
    for part in ("bumper", "garnish", "trunk"):
        doc["vehicle"][part]["bottom"] -= 0.040
        doc["vehicle"][part]["top"] -= 0.040
    moved = type(sc).model_validate({**doc, "base_dir": sc.base_dir, "source": "moved"})
    full = render_fisheye(moved)
    np.testing.assert_allclose(im.camera.position, moved.fisheye_camera().position, atol=1e-12)
    assert np.mean(im.labels == full.labels) >= 0.9995
    unmoved = sample_images(sc, [dataclasses.replace(s, load=LoadState("curb"))])[0]
    assert np.mean(unmoved.labels == im.labels) < 0.99  # the load does change the view


def test_body_pose_pitches_about_the_camera_and_lowers_it():
    sc = load_small_scene("a", 0.25, variation=None)
    pose = body_pose(sc, LoadState("full", height_mm=-50.0, pitch_deg=1.0))
    assert pose is not None
    p0 = np.array([*sc.camera.mount.position, 1.0])
    np.testing.assert_allclose(pose @ p0, [*(p0[:3] + [0.0, 0.05, 0.0]), 1.0], atol=1e-12)
    bumper_rear = np.array([0.0, -0.6, 0.0, 1.0])  # below and behind the camera
    assert (pose @ bumper_rear)[1] > bumper_rear[1] + 0.05  # rear down: lower still
    cam = sample_camera(sc, MountSample(0, (0.0,) * 6, (0.0,) * 3,
                                        LoadState("full", 0.0, 1.0)))
    base = sc.fisheye_camera()
    angle = np.degrees(np.arccos(np.clip(cam.rotation[:, 2] @ base.rotation[:, 2], -1, 1)))
    assert cam.rotation[1, 2] > base.rotation[1, 2] and abs(angle - 1.0) < 1e-9
    assert body_pose(sc, LoadState("curb")) is None


def test_a_rotation_beyond_the_cover_is_refused():
    sc = load_small_scene("a", 0.25, variation=None)
    cam = sc.fisheye_camera()
    cover = cover_layout(cam, [], oversample=1.5)
    rays = CameraRays.of(cam)
    refold_layout(cover, np.eye(3), rays)
    from rvmsim.camera import rotation_from_ypr

    with pytest.raises(ValueError, match="outside the rendered cube"):
        refold_layout(cover, rotation_from_ypr(10.0, 0.0, 0.0), rays)


def test_viewpoint_cubes_come_from_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RVMSIM_CACHE", str(tmp_path))
    sc = load_small_scene("a", 0.25, variation=ANGLES_ONLY)
    samples = draw_samples(variation_from_scene(sc), 4, seed=0)
    first = sample_images(sc, samples)
    entries = list(tmp_path.iterdir())
    assert len(entries) == 1 and (entries[0] / "cube_labels.png").is_file()
    again = sample_images(sc, samples, color=False)
    for a, b in zip(first, again):
        np.testing.assert_array_equal(a.labels, b.labels)
        assert not b.color.any() and b.color.shape == a.color.shape
    assert list(tmp_path.iterdir()) == entries


def test_a_labels_only_cube_is_rendered_again_for_colour(tmp_path, monkeypatch):
    monkeypatch.setenv("RVMSIM_CACHE", str(tmp_path))
    sc = load_small_scene("a", 0.25, variation=ANGLES_ONLY)
    samples = draw_samples(variation_from_scene(sc), 2, seed=0)
    labels_only = sample_images(sc, samples, color=False)
    (entry,) = tmp_path.iterdir()
    assert (entry / "cube_labels.png").is_file() and not (entry / "cube_color.png").exists()
    assert not labels_only[0].color.any()
    both = sample_images(sc, samples)
    assert (entry / "cube_color.png").is_file() and both[0].color.any()
    for a, b in zip(labels_only, both):
        np.testing.assert_array_equal(a.labels, b.labels)


def test_rvm_labels_of_samples_equal_the_isp_on_their_fisheye_labels():
    """sample_rvm_labels re-folds only the pixels the RVM image shows; the result is the
    ISP (rvmsim.isp.process) run on the whole re-folded fisheye label image."""
    from rvmsim.isp import IspParams, OutputSpec, process
    from rvmsim.pipeline import rvm_pixels
    from rvmsim.robust import refolder, sample_rvm_labels

    sc = load_small_scene("a", 0.25, variation={**ANGLES_ONLY, "load_states": [
        {"name": "curb"}, {"name": "full", "height_mm": -40, "pitch_deg": 1.0}]})
    samples = draw_samples(variation_from_scene(sc), 6, seed=5)
    assert len({s.load.name for s in samples}) == 2
    params = IspParams(v_shift=4.0, zoom=1.2).for_input_scale(0.25)
    output = OutputSpec(320, 180)
    shared = refolder(sc, samples)
    rvm = rvm_pixels(sc.fisheye_camera(), params, output)
    direct = sample_rvm_labels(sc, samples, rvm, shared=shared)
    for im, lab in zip(sample_images(sc, samples, color=False, shared=shared), direct):
        _, ref = process(None, im.labels, params, output)
        np.testing.assert_array_equal(lab, ref)
    assert len({d.tobytes() for d in direct}) == len(direct)  # the samples differ
