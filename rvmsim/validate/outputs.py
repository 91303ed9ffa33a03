"""What a validation leaves for people: the pictures, and the files in the output folder.

Convention
----------
Pictures are (H, W, 3) uint8 RGB; marker positions are (u, v) px with pixel centres at
integer coordinates, rounded to the nearest pixel for drawing.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._io import make_output_folder, write_png
from .edges import compare_edges, edge_overlay, model_mask
from ..pose import blend
from .verdict import EdgeComparison

__all__ = ["compare_with_pictures", "write_pictures"]


def compare_with_pictures(capture: np.ndarray, synthetic: np.ndarray, labels: np.ndarray,
                          overlay_key: str,
                          edges_key: str) -> tuple[EdgeComparison, dict[str, np.ndarray]]:
    """Edges of ``capture`` against ``synthetic`` over the modelled part of ``labels``
    (:func:`~.edges.model_mask`), with the pictures: the blend (``overlay_key``) and the
    edge overlay (``edges_key``).  Both images (H, W, 3) uint8 RGB, ``labels`` (H, W)."""
    edges, e_cap, e_syn = compare_edges(capture, synthetic, model_mask(labels))
    return edges, {overlay_key: blend(capture, synthetic),
                   edges_key: edge_overlay(capture, e_cap, e_syn)}


def write_pictures(images: dict[str, np.ndarray], out_dir: str | Path) -> list[Path]:
    """Write each picture as ``<key>.png`` into ``out_dir`` (created); also what a failed
    validation leaves (:attr:`rvmsim.validate.ValidationFailure.images`).

    Raises
    ------
    RvmsimError
        One line naming the folder or file that cannot be created or written.
    """
    out = make_output_folder(out_dir)
    return [write_png(out / f"{name}.png", img) for name, img in images.items()]
