"""A test EC plugin with both optional hooks (docs/criteria.md, "Hooks").

"Guideline 2 sits at a set height": the middle of cross guideline 2's vertical extent in the
RVM image, in % of the image height.  For a given view it depends on the advanced vertical
shift alone, so the EC declares a closed-form sub-solve that sets ``adv_v_shift`` (the
paper's EC 3-2 solves the same parameter for guideline 3: criteria using this EC disable
3-2).  It cannot pass when guideline 2 is not in the fisheye image at all, which its
feasibility reason says.
"""

from __future__ import annotations

import numpy as np

from rvmsim import labels as L
from rvmsim.criteria import (
    Criterion,
    EcDefinition,
    LabelGroup,
    LabelSource,
    Measurement,
    MeasureOptions,
    SceneContext,
    Sigmoid,
    SubSolve,
    bounding_box,
    label_mask,
    offset,
)
from rvmsim.isp import IspParams, OutputSpec

EC_ID = "acme-guide2-height"
GUIDE2 = LabelGroup("guide2", (L.guide_cross(2),))


def guide2_height(src: LabelSource, options: MeasureOptions) -> Measurement:
    """100 · (y + 0.5) / H, y the middle row of guideline 2's pixels' extent; None without
    it.

    Convention: pixel centres at integer rows; a pixel in row r spans r … r + 1 from the top.
    """
    win = src.window(GUIDE2)
    box = bounding_box(label_mask(src.pixels(win), L.guide_cross(2)))
    if box is None:
        return Measurement(None)
    _, y, _, h = offset(box, win)
    middle = y + (h - 1) / 2.0
    return Measurement(100.0 * (middle + 0.5) / src.shape[0], middle)


def solve_guide2_height(xy: np.ndarray, params: IspParams, output: OutputSpec,
                        target: float) -> float | None:
    """``adv_v_shift`` that puts the middle of the visible part of guideline 2 at ``target``
    % of the height.

    Convention (:class:`rvmsim.criteria.SubSolve`): plane x → column
    ``(x − adv_h_shift) · s_h · W/2 + (W − 1)/2``; plane y → row
    ``(y − adv_v_shift) · s_v · W/2 + (H − 1)/2``."""
    w, h = output.width, output.height
    half = w / 2.0
    u = (xy[:, 0] - params.adv_h_shift) * params.adv_h_scale * half + (w - 1) / 2.0
    seen = xy[(u >= -0.5) & (u <= w - 0.5), 1]
    if not len(seen):
        return None
    middle = (float(seen.min()) + float(seen.max())) / 2.0
    row = target / 100.0 * h - 0.5
    return middle - (row - (h - 1) / 2.0) / (params.adv_v_scale * half)


def guide2_missing(context: SceneContext, criterion: Criterion, options: MeasureOptions
                   ) -> tuple[str, str] | None:
    """Guideline 2 is nowhere in the fisheye image: no ISP setting shows it."""
    if np.any(context.fisheye_labels == L.guide_cross(2)):
        return None
    return "guideline 2 is not in the fisheye image", "no guideline 2"


ECS = [
    EcDefinition(
        id=EC_ID,
        name="guide2_height_ratio",
        unit="%",
        groups=(GUIDE2,),
        measure=guide2_height,
        default_range=(60.0, 70.0),
        default_sigmoid=Sigmoid.from_range(60.0, 70.0, tolerance=5.0),
        description="middle of cross guideline 2's vertical extent / image height",
        sub_solve=SubSolve("adv_v_shift", (L.guide_cross(2),), solve_guide2_height),
        infeasibility=guide2_missing,
    ),
]
