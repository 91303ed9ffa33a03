"""Custom ECs for the evaluator tests: more label groups than one distance image holds
(eight), one read in the upper region only, one reading a fixed region besides its groups,
and an EC from a plugin module."""

from __future__ import annotations

from rvmsim import labels as L
from rvmsim.criteria import (Criteria, EcDefinition, LabelGroup, LabelSource, Measurement,
                             MeasureOptions, Sigmoid, count_label, default_criteria,
                             load_plugin)


def _area(group: LabelGroup):
    def measure(src: LabelSource, options: MeasureOptions) -> Measurement:
        h, w = src.shape
        sub = src.pixels(src.window(group))
        return Measurement(1000.0 * sum(count_label(sub, i) for i in group.labels) / (h * w))
    return measure


#: More groups than one distance image holds (eight), one read in the upper region only,
#: and one EC that reads a fixed region (the bottom rows) besides its groups.
SIDES = [LabelGroup(f"side{i}", (i,)) for i in (L.GUIDE_SIDE_NEG_X, L.GUIDE_SIDE_POS_X)]
CROSS = [LabelGroup(f"cross{n}", (L.guide_cross(n),)) for n in (1, 4)]
SKY_UP = LabelGroup("sky_up", (L.SKY,), upper_region=True)


def _sky_up(src: LabelSource, options: MeasureOptions) -> Measurement:
    x0, y0, x1, y1 = src.window(SKY_UP)
    rows = options.upper_rows(src.shape[0])
    sub = src.pixels((x0, y0, x1, min(y1, rows)))
    return Measurement(float(count_label(sub, L.SKY)) if sub.size else 0.0)


def _bottom_ground(src: LabelSource, options: MeasureOptions) -> Measurement:
    h, w = src.shape
    return Measurement(count_label(src.pixels((0, h - 6, w, h)), L.GROUND) / (6.0 * w))


CUSTOM = [EcDefinition(g.name, g.name, "‰", (g,), _area(g), default_range=(0.1, None),
                       default_sigmoid=Sigmoid(2.0, 0.1)) for g in SIDES + CROSS]
CUSTOM += [
    EcDefinition("sky-up", "sky_up", "px", (SKY_UP,), _sky_up, default_range=(None, 50),
                 default_sigmoid=Sigmoid(c3=0.1, c4=50)),
    EcDefinition("bottom-ground", "bottom_ground", "", (), _bottom_ground,
                 regions=lambda shape, o: [(0, shape[0] - 6, shape[1], shape[0])],
                 default_range=(0.2, None), default_sigmoid=Sigmoid(10, 0.2)),
    load_plugin("tests.criteria.ec_plugin_example")[0],
]


def custom_criteria() -> Criteria:
    """The paper's ECs and :data:`CUSTOM`."""
    base = default_criteria()
    ecs = base.ecs + tuple(CUSTOM)
    items = {**base.items, **{ec.id: ec.default_criterion() for ec in CUSTOM}}
    return Criteria("custom", items, 0.4, base.edge_columns, "test", ecs)
