"""Feasibility reasons (:data:`~rvmsim.criteria.InfeasibilityFn`): why no ISP setting can pass
an EC at a design point, read from the fisheye labels and the scene, and those of the
paper's ECs, which :mod:`rvmsim.criteria.builtin` attaches to them.

The ISP only resamples the fisheye image (:mod:`rvmsim.isp`): every label the RVM image
shows is a label of the fisheye image, and anything cut off by the sensor border or the
lens's image circle, or hidden behind the car body, stays cut off or hidden whatever the
parameters.  So some failures need no search to prove:

- **1-1** (the lower 150 × 150 mm patches of objects F and G wholly visible,
  :func:`fg_patches_reason`): the patch's 3D surface, sampled on a grid and projected with
  the camera model (:func:`patch_view`), lies (partly) outside the lens's field of view or
  the sensor, or (partly) behind the car body (bumper, garnish, trunk, extra parts: the
  pixel there shows the body, not the patch); or the patch faces away from the camera, or
  the object is not in the scene.
- ECs that measure labels absent from the fisheye image altogether (:class:`LabelsAbsent`:
  1-2 the F and G stripes, 1-4 B's stripe, 2-1/2-2 the bumper, 3-1/3-2 guidelines 2 and 3,
  4-1 the board): the RVM image cannot show them either and the measurement is 0 or
  missing, out of range.

Everything is conservative: a patch that is only nicked (a sample less than about a pixel
outside, or an occluder seen only next to patch pixels) is *not* called infeasible, and the
search decides.

Convention
----------
Scene frame as in :mod:`rvmsim.camera.mount` (y negative up; heights are −y); pixels as
in :class:`~rvmsim.camera.FisheyeCamera` (centres at integer (u, v) = (column, row)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera
from ..scene import Scene, stripe_azimuth_deg
from .context import SceneContext
from .measure import MeasureOptions
from .sigmoid import Criterion

__all__ = ["PATCH_SAMPLES", "PatchView", "patch_view", "fg_patches_reason", "LabelsAbsent",
           "label_counts"]

#: Samples per side of the grid laid over a patch's surface (azimuth × height).
PATCH_SAMPLES = 11

#: Labels of the car body: a patch pixel next to one fails EC 1-1, so one in front of the
#: patch hides it (as the EC's own blockers, without void, which is checked geometrically).
_BODY_LABELS = L.BODY_LABELS

#: A sample counts as outside the sensor or the image circle only this far beyond it, px.
_MARGIN_PX = 1.0


@dataclass(frozen=True)
class PatchView:
    """How the camera sees one lower patch: counts of its surface samples.

    Attributes
    ----------
    letter : str
        F or G.
    samples : int
        Samples on the patch (0: the object is not in the scene).
    facing : int
        Samples whose surface faces the camera (the rest are behind the object's own body).
    outside_circle, outside_sensor : int
        Facing samples beyond the lens's field of view (θ > fov / 2 by more than about a
        pixel), or projecting more than a pixel outside the sensor.
    hidden : dict[int, int]
        Facing, in-view samples whose pixel shows a car-body label (key) with no patch pixel
        next to it: the body is in front of the patch there.
    """

    letter: str
    samples: int
    facing: int
    outside_circle: int
    outside_sensor: int
    hidden: dict[int, int]

    @property
    def in_view(self) -> int:
        """Facing samples inside the field of view and on the sensor."""
        return self.facing - self.outside_circle - self.outside_sensor

    def problem(self) -> tuple[str, str] | None:
        """Why the patch cannot be wholly visible: (a phrase after "object F's lower
        patch", a few words for a map cell), or None when nothing shows it cannot."""
        if self.samples == 0:
            return "is not in the scene (the object is disabled)", "not in scene"
        if self.facing == 0:
            return "faces away from the camera", "faces away"
        if self.in_view == 0:
            return "is outside the lens's field of view at this mount", "out of view"
        if self.outside_circle:
            return ("is cut by the edge of the lens's image circle at this mount",
                    "cut by image circle")
        if self.outside_sensor:
            return "is cut by the sensor border at this mount", "cut by sensor border"
        if self.hidden:
            names = L.label_names()
            body = " and ".join(names[k] for k in sorted(self.hidden))
            whole = sum(self.hidden.values()) == self.in_view
            return f"is {'' if whole else 'partly '}hidden behind the {body}", f"behind {body}"
        return None


def _patch_samples(scene: Scene, letter: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(points, outward normals), both (n·n, 3), metres / unit: a grid over the lower patch
    of object ``letter`` (azimuth × height, edges included); empty when it is disabled."""
    site = scene.test_site
    c = site.object_centre(letter)
    if c is None:
        return np.zeros((0, 3)), np.zeros((0, 3))
    r = site.object_diameter / 2
    az = math.radians(stripe_azimuth_deg(scene, letter, c))
    half = site.stripe_width / r / 2
    a_grid, h_grid = np.meshgrid(np.linspace(az - half, az + half, n),
                                 np.linspace(0.0, site.lower_patch_height, n))
    a, h = a_grid.ravel(), h_grid.ravel()
    normals = np.stack([np.sin(a), np.zeros_like(a), np.cos(a)], axis=1)
    points = np.stack([c[0] + r * np.sin(a), -h, c[1] + r * np.cos(a)], axis=1)
    return points, normals


def patch_view(scene: Scene, camera: FisheyeCamera, labels: np.ndarray, letter: str, *,
               samples: int = PATCH_SAMPLES) -> PatchView:
    """Where the lower patch of object ``letter`` (F or G) lies in the fisheye image.

    Parameters
    ----------
    scene : Scene
        The design point's scene (the patch's geometry).
    camera : FisheyeCamera
        The camera the label image was rendered with (pose included).
    labels : (H, W) uint8
        The rendered fisheye label image.
    samples : int
        Grid samples per side over the patch.

    Convention
    ----------
    A sample is outside the image circle when its incidence angle exceeds fov / 2 by more
    than ``_MARGIN_PX / min(fx, fy)`` rad, outside the sensor when it projects more than
    ``_MARGIN_PX`` px beyond the outer pixel edges (−0.5 … W − 0.5).
    """
    pts, normals = _patch_samples(scene, letter, samples)
    if len(pts) == 0:
        return PatchView(letter, 0, 0, 0, 0, {})
    facing = np.einsum("ij,ij->i", normals, camera.position - pts) > 0
    pts = pts[facing]
    cam = camera.scene_to_camera(pts)
    theta = np.arctan2(np.hypot(cam[:, 0], cam[:, 1]), cam[:, 2])
    out_circle = theta > camera.theta_max + _MARGIN_PX / min(camera.fx, camera.fy)
    uv, _ = camera.project_rays(cam)
    h, w = labels.shape
    lo = -0.5 - _MARGIN_PX
    out_sensor = ~out_circle & ((uv[:, 0] < lo) | (uv[:, 1] < lo)
                                | (uv[:, 0] > w - 0.5 + _MARGIN_PX)
                                | (uv[:, 1] > h - 0.5 + _MARGIN_PX))
    hidden = _hidden_by_body(labels, uv[~out_circle & ~out_sensor], L.object_patch(letter))
    return PatchView(letter, len(facing), int(facing.sum()), int(out_circle.sum()),
                     int(out_sensor.sum()), hidden)


def _hidden_by_body(labels: np.ndarray, uv: np.ndarray, patch: int) -> dict[int, int]:
    """Car-body label → how many of the points ``uv`` (px) show it with no ``patch`` pixel
    in the 3 × 3 pixels around (a body pixel next to the patch may be the patch's own
    rasterised edge, so only clear cases count)."""
    h, w = labels.shape
    col = np.clip(np.rint(uv[:, 0]).astype(int), 0, w - 1)
    row = np.clip(np.rint(uv[:, 1]).astype(int), 0, h - 1)
    body = np.isin(labels[row, col], _BODY_LABELS)
    out: dict[int, int] = {}
    for r, c in zip(row[body], col[body]):
        near = labels[max(r - 1, 0):r + 2, max(c - 1, 0):c + 2]
        if not np.any(near == patch):
            out[int(labels[r, c])] = out.get(int(labels[r, c]), 0) + 1
    return out


def fg_patches_reason(context: SceneContext, criterion: Criterion, options: MeasureOptions
                      ) -> tuple[str, str] | None:
    """EC 1-1's feasibility reason: the first of objects F and G whose lower patch cannot be
    wholly visible (:meth:`PatchView.problem`), e.g. ("object F's lower patch is hidden
    behind the bumper", "F behind bumper"); None when both may be."""
    for letter in ("F", "G"):
        problem = patch_view(context.scene, context.camera, context.fisheye_labels,
                             letter).problem()
        if problem is not None:
            return f"object {letter}'s lower patch {problem[0]}", f"{letter} {problem[1]}"
    return None


def label_counts(context: SceneContext) -> np.ndarray:
    """Pixels per label id in the fisheye label image, (256,) int (computed once per
    scene)."""
    labels = context.fisheye_labels
    return context.shared(("label_counts",),
                          lambda: np.bincount(labels.ravel(), minlength=256))


@dataclass(frozen=True)
class LabelsAbsent:
    """A feasibility reason: none of ``labels`` is in the fisheye image at all, so the RVM
    image cannot show them.  Call it as the hook
    (``LabelsAbsent((L.BOARD,), "the pattern board is not in the fisheye image at all",
    "no board in view")``).

    Parameters
    ----------
    labels : tuple of int
        The label ids the EC measures.
    reason, short : str
        What to say when they are all absent (one line; a few words), without the EC id.
    """

    labels: tuple[int, ...]
    reason: str
    short: str

    def __call__(self, context: SceneContext, criterion: Criterion, options: MeasureOptions
                 ) -> tuple[str, str] | None:
        counts = label_counts(context)
        if any(counts[i] for i in self.labels):
            return None
        return self.reason, self.short
