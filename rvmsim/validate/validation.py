"""Validate a scene against a real capture from the vehicle's rear-view camera.

A tuning is only worth as much as the synthetic frame it is tuned on.  :func:`validate`
compares the scene's rendered fisheye frame with a capture of the physical camera at the
test site and says what to fix in the scene, in these steps:

1. **Landmarks and pose** (:func:`rvmsim.pose.find_mount`): the scene's checker corners
   that the synthetic frame shows, found in the capture, and the mount pose that best
   explains them, by fisheye PnP in the scene's mount parameters, alternating with the
   matching.
3. **Edges** (:mod:`.edges`): symmetric chamfer distance of the Canny edges over the part of
   the view the scene models, with the scene's pose and after a re-render at the corrected
   pose.
4. **RVM** (:mod:`.rvm`, with ISP parameters): both frames through our ISP, and the ECs.
5. **Verdict** (:mod:`.verdict`) against :class:`~.verdict.Tolerances`.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..criteria import Criteria, default_criteria
from ..isp import IspParams, OutputSpec
from ..pipeline import record_output
from ..pose import (PoseFailure, PoseSettings, board_picture, find_mount, landmark_picture,
                    render_corrected)
from ..render import FisheyeImages, cached_render, render_fisheye
from ..scene import Scene
from .failure import ValidationFailure
from .outputs import compare_with_pictures
from .rvm import compare_rvm
from .verdict import Tolerances, Validation, judge

__all__ = ["validate", "ValidationSettings"]


@dataclass(frozen=True)
class ValidationSettings:
    """How a capture is judged (``rvmsim validate``'s options).

    Parameters
    ----------
    params, output, criteria : IspParams, OutputSpec, Criteria, optional
        With ISP parameters, the capture and the synthetic frame are also compared as RVM
        images (of ``output``'s size), and the ECs (``criteria``, default the paper's)
        evaluated on both.
    tolerances : Tolerances
        The verdict's limits.
    search_px : float
        How far from its prediction a landmark is searched for at first, px
        (:class:`rvmsim.pose.PoseSettings`).
    rerender : bool
        Render the scene again at the corrected pose (for the corrected overlay, the
        edge comparison after correction and the capture's ECs).
    global_start, dense_align : bool
        Where the pose search starts (:class:`rvmsim.pose.PoseSettings`).
    """

    params: IspParams | None = None
    output: OutputSpec | None = None
    criteria: Criteria | None = None
    tolerances: Tolerances = Tolerances()
    search_px: float = 30.0
    rerender: bool = True
    global_start: bool = True
    dense_align: bool = True

    @property
    def pose(self) -> PoseSettings:
        """The pose search's settings."""
        return PoseSettings(min_landmarks=self.tolerances.min_landmarks,
                            search_px=float(self.search_px), global_start=self.global_start,
                            dense_align=self.dense_align)


def validate(scene: Scene, capture: np.ndarray,
             settings: ValidationSettings = ValidationSettings(), *,
             synthetic: FisheyeImages | None = None, use_cache: bool = False,
             capture_name: str = "<array>", progress: bool = False) -> Validation:
    """Compare a real capture with the scene's synthetic frame.

    Parameters
    ----------
    scene : Scene
    capture : (H, W, 3) uint8
        RGB capture of the physical camera (see :func:`rvmsim.pose.load_capture`).
    synthetic : FisheyeImages, optional
        The scene's rendered frame; rendered when missing, through the render cache
        (:func:`rvmsim.render.cached_render`, keyed on the scene's content) with
        ``use_cache``.
    settings : ValidationSettings
        The ISP comparison, the verdict's tolerances, the search radius, the re-render and
        the board start.
    capture_name : str
        For messages and the JSON summary.
    progress : bool
        Progress bars while rendering.

    Raises
    ------
    RvmsimError
        Capture of the wrong size, or a scene without enough visible checker corners.
    ValidationFailure
        A step failed (``detection``: fewer than ``tolerances.min_landmarks`` landmarks
        found; ``correspondence``: a one-square alias; ``pose fit``), with the pictures.
    """
    if synthetic is None:
        synthetic = (cached_render(scene, progress=progress)[0] if use_cache
                     else render_fisheye(scene, progress=progress))
    try:
        mount = find_mount(scene, capture, synthetic, settings.pose,
                           capture_name=capture_name, progress=progress)
    except PoseFailure as fail:
        _, images = compare_with_pictures(capture, synthetic.color, synthetic.labels,
                                          "overlay", "edges")
        images["landmarks"] = landmark_picture(capture, fail.landmarks)
        if fail.board_corners is not None:
            images["board"] = board_picture(capture, fail.board_corners, fail.board_outlines)
        raise ValidationFailure(fail.step, fail.detail, images, fail.found) from None
    err_before, err_after = mount.errors_px()
    edges_before, images = compare_with_pictures(capture, synthetic.color, synthetic.labels,
                                                 "overlay", "edges")
    images["landmarks"] = landmark_picture(capture, mount.landmarks)
    corrected, edges_after = None, None
    if settings.rerender:
        corrected = render_corrected(scene, synthetic, mount.correction, mount.position_m,
                                     mount.rotation, progress)
        edges_after, corrected_images = compare_with_pictures(
            capture, corrected.color, corrected.labels, "overlay_corrected", "edges_corrected")
        images.update(corrected_images)
    rvm = None
    if settings.params is not None:
        # the ECs judged at the RVM image of record, whatever size the params were searched at
        mirror = settings.output.mirror if settings.output is not None else True
        record = record_output(settings.criteria or default_criteria(), scene, mirror)
        rvm, rvm_images = compare_rvm(capture, synthetic, corrected, settings.params,
                                      record, settings.criteria)
        images.update(rvm_images)

    rms_after = _rms(err_after)
    cam = synthetic.camera
    return Validation(
        scene_name=scene.name, capture=capture_name, image_size=(cam.width, cam.height),
        landmarks=mount.landmarks, n_predicted=mount.n_predicted,
        rms_before_px=_rms(err_before), max_before_px=float(err_before.max()),
        rms_after_px=rms_after, max_after_px=float(err_after.max()),
        correction=mount.correction, edges_before=edges_before, edges_after=edges_after,
        rvm=rvm, checks=judge(rms_after, mount.correction, edges_before, settings.tolerances),
        images=images, start=mount.start,
    )


def _rms(err: np.ndarray) -> float:
    return float(np.sqrt(np.mean(err ** 2)))
