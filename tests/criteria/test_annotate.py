"""Annotation: every EC draws its own measurement, a plugin EC included; the panel lists
every selected EC."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np

from rvmsim.criteria import PASS, FAIL, annotate, default_criteria, evaluate, load_criteria
from rvmsim.isp import IspParams, OutputSpec, process

from ..conftest import small_render

EXAMPLE = Path(__file__).with_name("ec_plugin_example.py")


def _rvm():
    img = small_render("a")
    p = IspParams(fov=180, rad=300, zoom=0.5, adv_v_shift=0.2)
    return process(img.color, img.labels, p, OutputSpec(320, 240))


def test_plugin_ec_draws_its_measurement(tmp_path):
    shutil.copy(EXAMPLE, tmp_path / "ec.py")
    crit = tmp_path / "c.yaml"
    crit.write_text("plugins: [ec.py]\n")
    color, labels = _rvm()
    mine, paper = evaluate(labels, load_criteria(crit)), evaluate(labels, default_criteria())
    item = mine["acme-board-centred"]
    assert item.value is not None
    a, b = annotate(color, labels, mine), annotate(color, labels, paper)
    h, w = labels.shape
    assert a.shape[1] == b.shape[1] and a.shape[0] >= b.shape[0]
    # the example draws a vertical line through the board's centre, in its status colour
    x = int(round(mine.measurements.details["acme-board-centred"]))
    colour = np.array(PASS if item.passed else FAIL)
    line = np.all(a[:h, x] == colour, axis=1).sum()
    assert line > 0.8 * h and np.all(b[:h, x] == colour, axis=1).sum() < 0.3 * h
    # the built-ins draw the same with or without it (except where the line crosses them)
    differs = np.any(a[:h, :w] != b[:h, :w], axis=2)
    differs[:, max(0, x - 2) : x + 3] = False
    assert differs.sum() < 0.02 * h * w


def test_results_without_definitions_draw_the_builtins():
    color, labels = _rvm()
    r = evaluate(labels)
    bare = dataclasses.replace(r, definitions=())
    assert np.array_equal(annotate(color, labels, bare), annotate(color, labels, r))
    assert not np.array_equal(annotate(color, labels, r)[:, :320], color)
