"""The guideline ECs: ``G-1`` (static marks and width lines) and ``G-2`` (trajectory lines)
within N px of the lines painted on the ground.

A plugin of the EC registry (the bundled criteria set ``guidelines``), measured on a scene
whose site carries painted lines (:attr:`rvmsim.scene.TestSite.painted_lines`, made by
:func:`rvmsim.guidelines.check.painted_scene`): each painted line of the EC's kinds is
projected through the candidate's ISP map as the guidelines are, and measured against its
strip in the RVM label image (:func:`rvmsim.guidelines.check.measure_painted`).  The value is
the largest line offset (:attr:`~rvmsim.guidelines.check.LineCheck.offset_px`), px; a scene
without such lines is not measured.

========  =================================================================  ====
EC        measurement                                                        unit
========  =================================================================  ====
G-1       largest offset of a distance mark or width line from its painted     px
          line
G-2       largest offset of a trajectory line from its painted line            px
========  =================================================================  ====

Both accept up to ``limit_px`` (1 px of the RVM image of record by default).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from ..criteria import EcDefinition, LabelSource, Measurement, MeasureOptions, Sigmoid
from .check import STATIC_KINDS, TRAJECTORY_KINDS, measure_painted
from .project import GuidelineView

__all__ = ["ECS", "LIMIT_PX"]

#: Default acceptable offset of a guideline from its painted line, px of record.
LIMIT_PX = 1.0


def _measure(kinds: Sequence[str]) -> Callable[[LabelSource, MeasureOptions], Measurement]:
    def measure(src: LabelSource, options: MeasureOptions) -> Measurement:
        ctx, isp = src.context, src.isp
        if ctx is None or isp is None:
            return Measurement(None)
        painted = [p for p in ctx.scene.test_site.painted_lines if p.kind in kinds]
        if not painted:
            return Measurement(None)
        view = GuidelineView(ctx.camera, isp.params, isp.output)
        checks = [c for c in measure_painted(ctx.fisheye_labels, view, painted) if c.measured]
        if not checks:
            return Measurement(None)
        return Measurement(max(c.offset_px for c in checks), checks)
    return measure


def _whole_image(shape: tuple[int, int], options: MeasureOptions
                 ) -> list[tuple[int, int, int, int]]:
    return [(0, 0, shape[1], shape[0])]


ECS = [
    EcDefinition(
        id="G-1", name="static_guidelines_offset", unit="px", groups=(),
        measure=_measure(STATIC_KINDS), default_range=(None, LIMIT_PX),
        default_sigmoid=Sigmoid.from_range(None, LIMIT_PX, tolerance=0.5),
        description="largest offset of a distance mark or width line from its painted line",
        regions=_whole_image, uses_scene=True),
    EcDefinition(
        id="G-2", name="trajectory_guidelines_offset", unit="px", groups=(),
        measure=_measure(TRAJECTORY_KINDS), default_range=(None, LIMIT_PX),
        default_sigmoid=Sigmoid.from_range(None, LIMIT_PX, tolerance=0.5),
        description="largest offset of a trajectory line from its painted line",
        regions=_whole_image, uses_scene=True),
]
