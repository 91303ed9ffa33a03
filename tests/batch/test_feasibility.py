"""batch.feasibility: the search-free check on real renders (vehicle A at 320 × 240) against
an independent computation on the label image and on plain vector geometry, and the
verdict a sweep gives a mount where F and G are out of view."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
import yaml

from rvmsim import labels as L
from rvmsim.batch import LocalExecutor, infeasible_ecs, load_sweep, run_sweep
from rvmsim.criteria import patch_view
from rvmsim.criteria import criteria_from_text, default_criteria
from rvmsim.render import cached_render
from rvmsim.scene import scene_from_dict

from rvmsim.testing.scenes import small_scene_doc
from .conftest import write_sweep


def _render(mount=None, edit=None):
    mount_edit = {f"camera.mount.{k}": v for k, v in (mount or {}).items()}
    doc = small_scene_doc("a", variation=None, edit={**mount_edit, **(edit or {})})
    scene = scene_from_dict(doc, source="test")
    images, _ = cached_render(scene)
    return scene, images


def _label_view(labels: np.ndarray, label: int) -> str:
    """Independent of the module: the patch as the label image shows it ("absent",
    "circle" (touching void), "border" (touching the sensor edge), "body" (next to the car
    body) or "whole")."""
    mask = (labels == label).astype(np.uint8)
    if mask.sum() == 0:
        return "absent"
    ys, xs = np.nonzero(mask)
    grown = cv2.dilate(mask, np.ones((3, 3), np.uint8)) > 0
    ring = set(np.unique(labels[grown & (mask == 0)]).tolist())
    if L.VOID in ring:
        return "circle"
    if xs.min() == 0 or ys.min() == 0 or xs.max() == labels.shape[1] - 1 or \
            ys.max() == labels.shape[0] - 1:
        return "border"
    if ring & {L.BUMPER, L.GARNISH, L.TRUNK}:
        return "body"
    return "whole"


_KIND = {None: "whole", "out of view": "absent", "cut by image circle": "circle",
         "cut by sensor border": "border"}


@pytest.mark.parametrize("mount, edit", [
    ({}, None), ({"yaw_deg": 30.0}, None),
    ({"yaw_deg": 50.0}, None),  # F cut by the image circle
    ({"yaw_deg": 70.0}, None), ({"yaw_deg": 90.0}, None), ({"yaw_deg": -60.0}, None),
    ({"pitch_deg": -30.0}, None),
    ({"position": [0.0, -0.95, -0.14]}, None),  # behind the bumper
    ({"position": [0.0, -1.0, -0.14], "pitch_deg": 60.0}, None),
    ({}, {"camera.intrinsics": {"fx": 160.0, "fy": 160.0}}),  # F cut by the sensor border
    ({}, {"camera.intrinsics": {"fx": 200.0, "fy": 200.0}}),  # F off the sensor
], ids=str)
def test_patch_check_agrees_with_the_label_image(mount, edit):
    scene, images = _render(mount, edit)
    for letter in "FG":
        view = patch_view(scene, images.camera, images.labels, letter)
        problem = view.problem()
        kind = None if problem is None else problem[1]
        if kind is not None and kind.startswith("behind"):
            kind = "body"
        expected = _label_view(images.labels, L.object_patch(letter))
        assert _KIND.get(kind, kind) == expected, (letter, view)


def _corner_angles(scene, camera, letter):
    """Incidence angles (degrees) of the patch's four corners, from plain vector geometry:
    the angle between the optical axis (the camera's third column) and the ray to each."""
    site = scene.test_site
    cx, cz = site.object_centre(letter)
    r = site.object_diameter / 2
    from rvmsim.scene import stripe_azimuth_deg

    az = math.radians(stripe_azimuth_deg(scene, letter, (cx, cz)))
    half = site.stripe_width / r / 2
    axis = camera.rotation[:, 2]
    out = []
    for a in (az - half, az + half):
        for h in (0.0, site.lower_patch_height):
            p = np.array([cx + r * math.sin(a), -h, cz + r * math.cos(a)])
            d = (p - camera.position) / np.linalg.norm(p - camera.position)
            out.append(math.degrees(math.acos(np.clip(d @ axis, -1, 1))))
    return out


@pytest.mark.parametrize("yaw", [0.0, 40.0, 55.0, 75.0, 95.0])
def test_field_of_view_agrees_with_plain_geometry(yaw):
    scene, images = _render({"yaw_deg": yaw})
    half_fov = images.camera.fov_deg / 2
    for letter in "FG":
        angles = _corner_angles(scene, images.camera, letter)
        view = patch_view(scene, images.camera, images.labels, letter)
        if min(angles) > half_fov + 1:
            assert view.in_view == 0 and "field of view" in view.problem()[0]
        elif max(angles) < half_fov - 1:
            assert view.outside_circle == 0
        else:
            assert view.outside_circle > 0 or max(angles) < half_fov + 1


def test_infeasible_ecs_follow_the_criteria_and_the_scene():
    crit = default_criteria()
    scene, images = _render()
    assert infeasible_ecs(scene, images.camera, images.labels, crit) == []
    scene, images = _render({"yaw_deg": 90.0})
    found = infeasible_ecs(scene, images.camera, images.labels, crit)
    assert found[0].ec == "1-1"
    assert found[0].reason == ("1-1: object F's lower patch is outside the lens's field of "
                               "view at this mount")
    off = criteria_from_text(yaml.safe_dump({"criteria": {"1-1": {"enabled": False}}}), "c")
    assert all(x.ec != "1-1" for x in infeasible_ecs(scene, images.camera, images.labels,
                                                     off))
    scene, images = _render(edit={"test_site.board.enabled": False})
    assert [x.ec for x in infeasible_ecs(scene, images.camera, images.labels, crit)] == ["4-1"]
    assert (images.labels == L.BOARD).sum() == 0


SWEEP = """\
name: yaw study
base_scene: base.yaml
axes:
  yaw_deg: [0, 90]
tune:
  strategy: cmaes
  budget: 30
  seed: 0
  config: {output: {size: [320, 180]}}
  recheck: {rounds: 1, budget_factor: 1}
sensitivity: false
"""


def test_a_mount_with_f_out_of_view_is_reported_infeasible(tmp_path):
    f = write_sweep(tmp_path, SWEEP)
    spec = load_sweep(f)
    res = run_sweep(spec, tmp_path / "o", executor=LocalExecutor(1))
    straight, turned = (res.results[p.key] for p in res.points)
    assert turned["verdict"] == "infeasible" and turned["rechecks"] == 0
    assert "1-1: object F's lower patch is outside the lens's field of view" in turned["reason"]
    assert straight["verdict"] != "infeasible" and straight["reason"] is None
