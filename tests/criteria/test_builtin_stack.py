"""The paper's ECs measured on K images at once (their stack measures,
rvmsim.criteria.builtin_stack) give, image for image, the measurement of their measure
functions: value and detail, on rendered RVM label images of many views and on the
degenerate images the single-image tests use."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.criteria import LabelSource, LabelStack, default_criteria, measure_stack_ecs
from rvmsim.criteria.measure import measure_ecs
from rvmsim.isp import OutputSpec, apply_map, build_map
from rvmsim.search import TuningConfig

from ..conftest import sensor_render
from .views import VIEWS, rvm


def _check(images: list[np.ndarray]) -> None:
    """The stack's measurements equal each image's own, value and detail."""
    c = default_criteria()
    assert all(ec.measure_stack is not None for ec in c.ecs)
    got = measure_stack_ecs(LabelStack(np.stack(images, axis=2), c.groups), c.ecs, c.options)
    for k, img in enumerate(images):
        want = measure_ecs(LabelSource(img, c.groups), c.ecs, c.options)
        assert got[k].values == want.values, k
        assert got[k].details == want.details, k
        assert got[k].image_size == want.image_size


def _views(letter: str, n: int, seed: int, out: OutputSpec) -> list[np.ndarray]:
    """RVM label images of ``n`` views drawn from the tuning space (and the view in which
    every object shows)."""
    img = sensor_render(letter)
    space = TuningConfig().space(img.camera)
    rng = np.random.default_rng(seed)
    size = (img.camera.width, img.camera.height)
    ps = [VIEWS[letter]] + [
        space.params(space.low + rng.random(len(space.low)) * (space.high - space.low))
        for _ in range(n)]
    return [apply_map(img.labels, build_map(p, size, out)) for p in ps]


@pytest.mark.parametrize("letter,size", [("a", (320, 180)), ("b", (320, 180)),
                                         ("a", (160, 90))])
def test_stack_measures_equal_each_images_measures_on_rendered_views(letter, size):
    images = _views(letter, 11, 3, OutputSpec(*size))
    # objects in view on some images and not on others: the stack mixes both
    seen = [np.isin(im, [L.object_patch("F"), L.BOARD]).any() for im in images]
    assert any(seen) and not all(seen)
    _check(images)


def test_stack_measures_equal_each_images_measures_on_cut_and_hidden_objects():
    labels = rvm("a")
    rows, cols = np.nonzero(labels == L.object_patch("F"))
    cut = labels.copy()  # F's patch touching the image border
    cut[:, : cols.min() + 1] = L.GROUND
    cut[rows.min():rows.max() + 1, 0] = L.object_patch("F")
    hidden = labels.copy()  # G's patch next to the bumper
    rows, cols = np.nonzero(hidden == L.object_patch("G"))
    hidden[rows.max(), cols.min():cols.max() + 1] = L.BUMPER
    no_c = labels.copy()
    no_c[np.isin(no_c, [L.object_body("C"), L.object_stripe("C")])] = L.GROUND
    body = labels.copy()
    body[5, 5] = L.GARNISH
    few = labels.copy()  # a patch of 3 px
    few[few == L.object_patch("F")] = L.GROUND
    few[100, 100:103] = L.object_patch("F")
    # a blocker touching F's patch from each side and corner (1-1 reads the ring around it)
    rows, cols = np.nonzero(labels == L.object_patch("F"))
    top, bottom = np.argmin(rows), np.argmax(rows)
    left, right = np.argmin(cols), np.argmax(cols)
    touching = []
    for y, x, what in ((rows[top] - 1, cols[top] - 1, L.BUMPER),  # above left
                       (rows[left], cols[left] - 1, L.VOID),  # left
                       (rows[top] - 1, cols[top], L.GARNISH),  # above
                       (rows[bottom] + 1, cols[bottom] + 1, L.TRUNK),  # below right
                       (rows[right], cols[right] + 1, L.BUMPER),  # right
                       (rows[bottom] + 1, cols[bottom], L.VOID)):  # below
        t = labels.copy()
        t[y, x] = what
        touching.append(t)
    _check([labels, cut, hidden, no_c, body, few, np.full_like(labels, L.VOID), *touching])
    assert all(measure_ecs(LabelSource(t, default_criteria().groups), default_criteria().ecs,
                           default_criteria().options).values["1-1"] == 0.0 for t in touching)


@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (7, 1), (2, 2), (5, 9)])
def test_stack_measures_equal_each_images_measures_on_tiny_images(shape):
    rng = np.random.default_rng(1)
    ids = [L.VOID, L.GROUND, L.BUMPER, L.BOARD, L.object_patch("F"), L.object_stripe("B"),
           L.guide_cross(2), L.guide_cross(3), L.GARNISH, L.object_body("A")]
    _check([np.full(shape, L.object_patch("F"), np.uint8)]
           + [rng.choice(ids, size=shape).astype(np.uint8) for _ in range(6)])
