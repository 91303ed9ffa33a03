"""K label images at once (rvmsim.criteria.stack): the helpers against per-image numpy and
OpenCV, the fallback for ECs without a stack measure, and a plugin's broken stack measure
reported in one line."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.criteria import (EcDefinition, EcFailedError, LabelGroup, LabelSource, LabelStack,
                             Measurement, MeasureOptions, measure_stack_ecs,
                             stack_boxes, stack_counts, stack_mask)
from rvmsim.criteria.measure import measure_ecs
from rvmsim.criteria.stack import union_box
from rvmsim.errors import CriteriaError

RNG = np.random.default_rng(7)


def _sparse_stack(h: int, w: int, k: int, density: float) -> np.ndarray:
    """Random labels where a few pixels carry label 9 (some images none)."""
    out = RNG.integers(0, 256, (h, w, k), dtype=np.uint8)
    out[out == 9] = 8
    hit = RNG.random((h, w, k)) < density
    hit[..., ::3] = False  # every third image holds none
    out[hit] = 9
    return out


@pytest.mark.parametrize("ids", [(3,), (0,), (255,), (10, 11, 12, 20, 21, 22),
                                 (0, 3, 4, 5, *range(100, 200)), (254, 255, 0), ()])
def test_stack_mask_is_isin(ids):
    sub = RNG.integers(0, 256, (31, 17, 6), dtype=np.uint8)
    want = np.isin(sub, ids).astype(np.uint8)
    np.testing.assert_array_equal(stack_mask(sub, ids), want)
    np.testing.assert_array_equal(stack_mask(sub[3:20, 2:15], ids), want[3:20, 2:15])


@pytest.mark.parametrize("shape", [(0, 5, 3), (1, 1, 1), (7, 3, 5), (300, 2, 17), (255, 3, 4),
                                   (256, 1, 2), (41, 33, 9)])
def test_stack_counts_are_per_image_counts(shape):
    m = (RNG.random(shape) < 0.7).astype(np.uint8)
    want = [int(np.count_nonzero(m[:, :, k])) for k in range(shape[2])]
    assert stack_counts(m).tolist() == want


@pytest.mark.parametrize("shape,density", [((1, 1, 3), 0.5), ((9, 1, 4), 0.2),
                                           ((1, 13, 4), 0.2), ((37, 51, 17), 0.001),
                                           ((64, 129, 5), 0.0004), ((20, 20, 2), 0.0)])
def test_stack_boxes_are_bounding_rects(shape, density):
    sub = _sparse_stack(*shape, density)
    mask = stack_mask(sub, (9,))
    for k, box in enumerate(stack_boxes(mask)):
        plane = np.ascontiguousarray(mask[:, :, k])
        x, y, w, h = cv2.boundingRect(plane)
        assert box == (None if w == 0 else (x, y, w, h))
    assert stack_boxes(np.zeros((0, 4, 3), np.uint8)) == [None] * 3


def test_union_box():
    assert union_box([(0, 0, 0, 0), (3, 4, 9, 8), (1, 6, 5, 12)]) == (1, 4, 9, 12)
    assert union_box([(0, 0, 0, 0)]) == (0, 0, 0, 0)


GROUP = LabelGroup("nine", (9,))


def _count_nine(src, options):
    sub = src.pixels(src.window(GROUP))
    return float(np.count_nonzero(sub == 9)) if sub.size else None


def test_ecs_without_a_stack_measure_are_measured_image_by_image():
    stack = _sparse_stack(40, 60, 5, 0.01)
    ec = EcDefinition("x-nine", "nine", "px", (GROUP,), _count_nine)
    got = measure_stack_ecs(LabelStack(stack, [GROUP]), [ec], MeasureOptions())
    want = [measure_ecs(LabelSource(np.ascontiguousarray(stack[:, :, k]), [GROUP]), [ec],
                        MeasureOptions()) for k in range(5)]
    assert [g.values for g in got] == [w.values for w in want]
    assert any(v.values["x-nine"] for v in want) and not all(v.values["x-nine"] for v in want)


def test_a_stack_measure_giving_another_count_or_raising_is_one_line():
    stack = LabelStack(np.zeros((8, 8, 3), np.uint8), [GROUP])

    def short(stack, options):
        return [Measurement(1.0)]

    def broken(stack, options):
        raise ZeroDivisionError("boom")

    for fn, what in ((short, "gave 1 measurements for 3 images"), (broken, "boom")):
        ec = EcDefinition("x-nine", "nine", "px", (GROUP,), _count_nine, measure_stack=fn,
                          plugin="acme_plugin.py")
        with pytest.raises(EcFailedError) as err:
            measure_stack_ecs(stack, [ec], MeasureOptions())
        assert err.value.part == "measure_stack" and what in str(err.value)
        assert "\n" not in str(err.value)


def test_a_plugin_whose_stack_measure_disagrees_on_an_empty_image_is_refused(tmp_path):
    plugin = tmp_path / "acme_stack.py"
    plugin.write_text(
        "from rvmsim.criteria import EcDefinition, LabelGroup\n"
        "G = LabelGroup('nine', (9,))\n"
        "def measure(src, options):\n    return 0.0\n"
        "def measure_stack(stack, options):\n    return [1.0] * stack.n\n"
        "ECS = [EcDefinition('acme-nine', 'nine', 'px', (G,), measure,"
        " measure_stack=measure_stack)]\n")
    from rvmsim.criteria import load_plugin

    with pytest.raises(CriteriaError, match="measure_stack gives") as err:
        load_plugin(str(plugin))
    assert "acme-nine" in str(err.value)


def test_a_stack_takes_uint8_stacks_only():
    with pytest.raises(TypeError):
        LabelStack(np.zeros((4, 4), np.uint8), [GROUP])
    with pytest.raises(TypeError):
        LabelStack(np.zeros((4, 4, 2), np.float32), [GROUP])
    assert L.VOID == 0  # the stack's remap fills channels past the fourth with 0
