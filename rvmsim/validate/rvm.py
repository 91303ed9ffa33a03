"""The RVM comparison (``--params``): the capture and the synthetic frame through the ISP.

The two RVM images' edges are compared, and the ECs are evaluated on the scene's labels and
on the labels of the pose-corrected scene: a capture has no labels of its own, and the
corrected scene is the synthetic frame that explains it.
"""

from __future__ import annotations

import numpy as np

from ..criteria import Criteria, EcResult, evaluate
from ..isp import IspParams, OutputSpec, process
from ..render import FisheyeImages
from .outputs import compare_with_pictures
from .verdict import RvmComparison

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
    output = output or OutputSpec()
    rvm_cap = process(capture, None, params, output)[0]
    rvm_syn, lab_syn = process(synthetic.color, synthetic.labels, params, output)
    assert rvm_cap is not None and rvm_syn is not None and lab_syn is not None
    # TODO(#13 merge): the process + evaluate pairs below are the single evaluation path of
    # rvmsim.pipeline (params -> RVM colour + labels -> ECs); swap it in here.
    ec_scene = evaluate(lab_syn, criteria)
    ec_capture = _ecs_of_labels(corrected, lab_syn, params, output, criteria)
    edges, pictures = compare_with_pictures(rvm_cap, rvm_syn, lab_syn, "rvm_overlay",
                                            "rvm_edges")
    images = {"rvm_capture": rvm_cap, "rvm_synthetic": rvm_syn, **pictures}
    return RvmComparison(edges, ec_scene, ec_capture), images


def _ecs_of_labels(corrected: FisheyeImages | None, lab_syn: np.ndarray, params: IspParams,
                   output: OutputSpec, criteria: Criteria | None) -> EcResult:
    """ECs "of the capture": the corrected frame's RVM labels, else the scene's."""
    if corrected is None:
        return evaluate(lab_syn, criteria)
    lab_cap = process(None, corrected.labels, params, output)[1]
    assert lab_cap is not None
    return evaluate(lab_cap, criteria)
