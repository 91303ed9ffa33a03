"""Measure and evaluate whole RVM label images (one ISP parameter set's EC score).

The measure functions use OpenCV primitives (``LUT``, ``compare``, ``boundingRect``) on small
windows of the image; the paper's eleven ECs on a 640×480 label image take well under a millisecond
(``tools/bench_criteria.py``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .config import default_criteria
from .context import IspView, SceneContext
from .groups import unique_groups
from .measure import LabelSource, Measurements, MeasureOptions, measure_ecs
from .registry import EcDefinition, builtin_ecs
from .scoring import Criteria, EcResult, score

__all__ = ["measure", "measure_source", "measure_labels", "evaluate"]


def measure(labels: np.ndarray, *, upper_region_fraction: float = 0.5, edge_columns: int = 4,
            ecs: Sequence[EcDefinition] | None = None) -> Measurements:
    """Measure ECs on an RVM label image.

    Parameters
    ----------
    labels : (H, W) uint8
        RVM label image (IDs from :mod:`rvmsim.labels`).
    upper_region_fraction : float
        Top fraction of the image that EC 2-4 checks for garnish/trunk pixels.
    edge_columns : int
        Columns averaged for each bumper height (t_l, t_r at the edges, t_c centred).
    ecs : sequence of EcDefinition, optional
        The ECs to measure, in order; default the paper's eleven.

    Returns
    -------
    Measurements
    """
    ecs = builtin_ecs() if ecs is None else ecs
    src = LabelSource(labels, unique_groups(g for ec in ecs for g in ec.groups))
    return measure_ecs(src, ecs, MeasureOptions(upper_region_fraction, edge_columns))


def measure_source(src: LabelSource, *, upper_region_fraction: float = 0.5,
                   edge_columns: int = 4,
                   ecs: Sequence[EcDefinition] | None = None) -> Measurements:
    """:func:`measure` on any :class:`LabelSource` (the same measurements, window by window)."""
    return measure_ecs(src, builtin_ecs() if ecs is None else ecs,
                       MeasureOptions(upper_region_fraction, edge_columns))


def evaluate(rvm_labels: np.ndarray, criteria: Criteria | None = None, *,
             context: SceneContext | None = None, isp: IspView | None = None) -> EcResult:
    """Measure and score an RVM label image (the EC score of one ISP parameter set).

    Parameters
    ----------
    rvm_labels : (H, W) uint8
        RVM label image.
    criteria : Criteria, optional
        Default: :func:`default_criteria`.
    context : SceneContext, optional
        The scene shown, for ECs that need it (``source.context``).
    isp : IspView, optional
        The ISP map that made ``rvm_labels``, for ECs that need it (``source.isp``).

    Returns
    -------
    EcResult
        One item per EC the criteria select, in their order.
    """
    criteria = criteria or default_criteria()
    return score(measure_labels(rvm_labels, criteria, context=context, isp=isp), criteria)


def measure_labels(rvm_labels: np.ndarray, criteria: Criteria, *,
                   context: SceneContext | None = None,
                   isp: IspView | None = None) -> Measurements:
    """The raw measurements of :func:`evaluate` (unscored): the criteria's ECs on an RVM
    label image, with the scene and map for the ECs that read them."""
    src = LabelSource(rvm_labels, criteria.groups, context=context, isp=isp)
    return measure_ecs(src, criteria.ecs, criteria.options)
