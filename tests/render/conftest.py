"""Render-test helpers."""

from __future__ import annotations

import numpy as np


def label_boundary(labels: np.ndarray) -> np.ndarray:
    """Pixels with a different label among their 8 neighbours (the label borders)."""
    pad = np.pad(labels, 1, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(pad, (3, 3))
    return ~(windows == labels[..., None, None]).all(axis=(-1, -2))
