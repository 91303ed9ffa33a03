"""The evaluation path: evaluate_params is the ISP, the ECs and the annotation, as the
separate steps give them; render_rvm renders first, at a fraction of the sensor if asked."""

from __future__ import annotations

import imageio.v3 as iio
import numpy as np
import pytest

from rvmsim.criteria import annotate, criteria_from_text, default_criteria, evaluate
from rvmsim.isp import IspParams, OutputSpec, process
from rvmsim.pipeline import evaluate_params, render_rvm, rvm_color, write_frame
from rvmsim.testing.scenes import QUARTER

from ..conftest import bundled_scene, small_render

PARAMS = IspParams().replace(rad=153.0, zoom=0.6, adv_v_shift=0.2)  # for the test scale
OUT = OutputSpec(320, 180)


def test_evaluate_params_is_the_separate_steps():
    images = small_render("a")
    criteria = criteria_from_text("name: no board\ncriteria:\n  4-1: {enabled: false}\n")
    frame = evaluate_params(images, PARAMS, OUT, criteria)
    color, labels = process(images.color, images.labels, PARAMS, OUT)
    assert np.array_equal(frame.color, color) and np.array_equal(frame.labels, labels)
    assert frame.color.shape == (180, 320, 3) and frame.labels.dtype == np.uint8
    ec = evaluate(labels, criteria)
    assert frame.ec.as_dict() == ec.as_dict() and frame.ec.criteria_name == "no board"
    assert not frame.ec["4-1"].enabled
    assert np.array_equal(frame.annotated, annotate(color, labels, ec))
    assert frame.fisheye is images and frame.params == PARAMS and frame.output == OUT
    bare = evaluate_params(images, PARAMS, OUT, annotate=False)
    assert bare.annotated is None
    assert bare.ec.as_dict() == evaluate(labels, default_criteria()).as_dict()
    assert np.array_equal(rvm_color(images, PARAMS, OUT), color)


def test_render_rvm_scales_the_parameters_with_the_render():
    scene = bundled_scene("a")
    full = IspParams().replace(rad=612.0, zoom=0.6, adv_v_shift=0.2)
    frame = render_rvm(scene, full, OUT, scale=QUARTER)
    assert frame.params == full.for_input_scale(QUARTER) and frame.annotated is None
    # the same as evaluating the test scale's render with the scaled parameters
    ref = evaluate_params(small_render("a"), full.for_input_scale(QUARTER), OUT,
                          annotate=False)
    assert np.array_equal(frame.labels, ref.labels)
    assert frame.ec.score == pytest.approx(ref.ec.score)


def test_write_frame_writes_what_the_frame_holds(tmp_path):
    frame = evaluate_params(small_render("a"), PARAMS, OUT)
    written = write_frame(frame, tmp_path / "f")
    assert [p.name for p in written] == ["rvm_color.png", "rvm_labels.png", "ec_annotated.png"]
    assert np.array_equal(iio.imread(tmp_path / "f" / "rvm_labels.png"), frame.labels)
    assert np.array_equal(iio.imread(tmp_path / "f" / "ec_annotated.png"), frame.annotated)
    bare = evaluate_params(small_render("a"), PARAMS, OUT, annotate=False)
    assert [p.name for p in write_frame(bare, tmp_path / "g")] == ["rvm_color.png",
                                                                   "rvm_labels.png"]
