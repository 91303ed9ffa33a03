"""rvmsim.validate.edges: Canny edges and their truncated chamfer comparison."""

from __future__ import annotations

import numpy as np

from rvmsim import labels as L
from rvmsim.validate import CHAMFER_TRUNCATE_PX, compare_edges
from rvmsim.validate.edges import edge_overlay, model_mask

from rvmsim.testing.captures import base


def test_identical_images_have_no_edge_distance_and_shifts_show():
    _, syn = base()
    mask = model_mask(syn.labels)
    same, ea, eb = compare_edges(syn.color, syn.color, mask)
    assert same.chamfer_px == 0.0 and same.matched_fraction == 1.0
    assert same.edges_a == same.edges_b == int(ea.sum()) > 1000 and np.array_equal(ea, eb)
    assert not (ea & ~mask).any()
    shifted = np.roll(syn.color, 3, axis=1)
    moved, _, _ = compare_edges(syn.color, shifted, mask)
    # Edges move 3 px or less (edges along the shift do not move): 0 < chamfer ≤ 3 px.
    assert 0.5 < moved.chamfer_px <= 3.0 and moved.matched_fraction < 1.0


def test_an_image_without_edges_counts_as_far():
    _, syn = base()
    mask = model_mask(syn.labels)
    flat = np.full_like(syn.color, 128)
    res, _, e_flat = compare_edges(syn.color, flat, mask)
    assert not e_flat.any() and res.edges_b == 0
    assert res.a_to_b_px == CHAMFER_TRUNCATE_PX and res.b_to_a_px == CHAMFER_TRUNCATE_PX


def test_model_mask_leaves_out_void_and_sky_with_a_margin():
    _, syn = base()
    mask = model_mask(syn.labels)
    outside = (syn.labels == L.VOID) | (syn.labels == L.SKY)
    assert mask.any() and not (mask & outside).any()
    # Eroded by 4 px: pixels next to the void are out too.
    near = np.zeros_like(outside)
    near[:, :-1] |= outside[:, 1:]
    assert not (mask & near).any()


def test_edge_overlay_colours():
    _, syn = base()
    e1 = np.zeros(syn.labels.shape, bool)
    e2 = np.zeros_like(e1)
    e1[10, 10] = e1[20, 20] = True
    e2[20, 20] = e2[30, 30] = True
    out = edge_overlay(syn.color, e1, e2)
    assert tuple(out[10, 10]) == (40, 230, 40) and tuple(out[30, 30]) == (255, 40, 255)
    assert tuple(out[20, 20]) == (255, 255, 255)
    assert out[0, 0, 0] == out[0, 0, 1] == out[0, 0, 2]  # the rest is grey
