"""The RVM comparison (``--params``): the capture and the synthetic frame through the ISP.

The two RVM images' edges are compared, and the ECs are evaluated on the scene's labels and
on the labels of the pose-corrected scene: a capture has no labels of its own, and the
corrected scene is the synthetic frame that explains it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..criteria import Criteria, EcResult
from ..isp import IspParams, OutputSpec, process
from ..render import FisheyeImages
from .outputs import compare_with_pictures
from .verdict import RvmComparison
from ..pipeline import evaluate_params

__all__ = ["compare_rvm"]


def compare_rvm(capture: np.ndarray, synthetic: FisheyeImages,
                corrected: FisheyeImages | None, params: IspParams,
                output: OutputSpec | None,
                criteria: Criteria | None) -> tuple[RvmComparison, dict[str, np.ndarray]]:
    """Both frames through the ISP, their edges compared, the ECs of both label images.

    Parameters
    ----------
    capture : (H, W, 3) uint8
    synthetic : FisheyeImages
        The scene's frame.
    corrected : FisheyeImages or None
        The frame at the corrected pose; None: the scene's labels stand in for the
        capture's.
    params : IspParams
        As applied to the fisheye frames (scaled to their size).
    output : OutputSpec or None
        RVM image size; None: the default.
    criteria : Criteria or None
        EC definitions; None: the paper's.

    Returns
    -------
    comparison : RvmComparison
    images : dict of str to (h, w, 3) uint8
        ``rvm_capture``, ``rvm_synthetic``, ``rvm_overlay``, ``rvm_edges``.
    """
    rvm = _rvm_images_and_ecs(capture, synthetic, corrected, params, output or OutputSpec(),
                              criteria)
    edges, pictures = compare_with_pictures(rvm.capture, rvm.synthetic, rvm.labels,
                                            "rvm_overlay", "rvm_edges")
    images = {"rvm_capture": rvm.capture, "rvm_synthetic": rvm.synthetic, **pictures}
    return RvmComparison(edges, rvm.ec_scene, rvm.ec_capture), images


@dataclass(frozen=True)
class _RvmImages:
    """The RVM images (uint8 RGB / labels) and the ECs of :func:`_rvm_images_and_ecs`."""

    capture: np.ndarray
    synthetic: np.ndarray
    labels: np.ndarray
    ec_scene: EcResult
    ec_capture: EcResult


def _rvm_images_and_ecs(capture: np.ndarray, synthetic: FisheyeImages,
                        corrected: FisheyeImages | None, params: IspParams, output: OutputSpec,
                        criteria: Criteria | None) -> _RvmImages:
    """params -> RVM images -> ECs, the one step of validation that evaluates ISP parameters.

    The capture's colour, the synthetic frame's colour and labels, and the corrected frame's
    labels (the scene's when None) go through the ISP; the ECs are evaluated on both label
    images.
    """

    rvm_cap = process(capture, None, params, output)[0]
    if rvm_cap is None:
        raise TypeError("process() returned no image for an input it was given")
    syn = evaluate_params(synthetic, params, output, criteria, annotate=False)
    cap = syn if corrected is None else evaluate_params(corrected, params, output, criteria,
                                                        annotate=False)
    return _RvmImages(rvm_cap, syn.color, syn.labels, syn.ec, cap.ec)
