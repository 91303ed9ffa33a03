"""The run report's plots: convergence of the search and the distribution of EC scores."""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from .page import figure_png

__all__ = ["convergence_png", "histogram_png", "SCORE_FLOOR"]

#: Scores below this are drawn at this value on the log axes.
SCORE_FLOOR = 1e-15


def convergence_png(curve: list[tuple[int, float, str]]) -> bytes:
    """Best EC score so far vs evaluation index, one colour per search stage (log y axis).

    Parameters
    ----------
    curve : list of (idx, best so far, stage)
        As :meth:`rvmsim.runs.RunStore.best_curve` gives it.

    Returns
    -------
    bytes
        A PNG image.
    """

    fig = Figure(figsize=(6.4, 3.6))
    ax = fig.add_subplot()
    stages: list[str] = []
    for _, _, st in curve:
        if st not in stages:
            stages.append(st)
    colours = [f"C{i % 10}" for i in range(len(stages))]
    idx = np.array([c[0] for c in curve], dtype=float)
    best = np.maximum(np.array([c[1] for c in curve], dtype=float), SCORE_FLOOR)
    st_arr = np.array([c[2] for c in curve], dtype=object)
    for st, col in zip(stages, colours):
        mask = st_arr == st
        ax.plot(idx[mask], best[mask], ".", ms=2.5, color=col, label=str(st))
    if len(idx):
        ax.plot(idx, best, "-", lw=0.8, color="#555", zorder=0)
    ax.set_yscale("log")
    ax.set_ylim(SCORE_FLOOR / 10, 2.0)
    ax.set_xlabel("evaluation")
    ax.set_ylabel("best EC score so far")
    ax.set_title("Convergence")
    ax.grid(True, which="major", alpha=0.3)
    if stages:
        ax.legend(title="stage", fontsize=8, loc="lower right",
                  ncol=max(1, math.ceil(len(stages) / 6)))
    fig.tight_layout()
    return figure_png(fig)


def histogram_png(scores: np.ndarray) -> bytes:
    """Histogram of all trials' EC scores on log-spaced bins; zero scores counted apart.

    Returns
    -------
    bytes
        A PNG image.
    """

    scores = np.asarray(scores, dtype=float)
    zeros = int(np.sum(scores <= 0))
    pos = scores[scores > 0]
    fig = Figure(figsize=(6.4, 3.6))
    ax = fig.add_subplot()
    if pos.size:
        lo = max(float(pos.min()), SCORE_FLOOR)
        hi = max(float(pos.max()), lo * 10)
        bins = np.logspace(math.log10(lo), math.log10(hi), 40)
        ax.hist(np.clip(pos, lo, hi), bins=bins.tolist(), color="C0")
        ax.set_xscale("log")
    else:
        ax.text(0.5, 0.5, "no trial scored above 0", ha="center", va="center",
                transform=ax.transAxes)
    ax.set_xlabel("EC score")
    ax.set_ylabel("trials")
    ax.set_title(f"Score distribution ({scores.size} trials, {zeros} scored 0)")
    fig.tight_layout()
    return figure_png(fig)
