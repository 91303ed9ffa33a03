"""The robustness page shows the nominal and worst annotated images at a size whose text
reads (≥ 11 px per em in the browser)."""

from __future__ import annotations

import base64
import re

import numpy as np

from rvmsim.criteria import default_criteria
from rvmsim.criteria.annotate import MIN_TEXT_PX
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.report import write_robustness_outputs
from rvmsim.robust import RobustnessSettings, robustness

from rvmsim.testing.scenes import load_small_scene
from .test_run import shown_text_px

#: ±1° on the mount's angles: one viewpoint, so a handful of samples cost one render.
ANGLES = {"mount": {a: {"uniform": {"half_width": 1.0}} for a in ("yaw_deg", "pitch_deg",
                                                                   "roll_deg")}}


def test_robustness_page_shows_the_annotated_images_legibly(tmp_path):
    import cv2

    sc = load_small_scene("a", 0.25, variation=ANGLES)
    how = RobustnessSettings(OutputSpec(640, 360), default_criteria(), samples=4, seed=1,
                             scales=(1.0,))
    result = robustness(sc, IspParams().for_input_scale(0.25), how)
    assert result.nominal is not None and result.nominal.annotated is not None
    _, page = write_robustness_outputs(result, tmp_path)
    text = page.read_text()
    # embedded at the annotation's own size (not shrunk to a thumbnail)
    srcs = dict((alt, src) for src, alt in re.findall(r'<img src="([^"]+)" alt="([^"]+)"',
                                                      text))
    raw = base64.b64decode(srcs["nominal"].split(",", 1)[1])
    shown = cv2.imdecode(np.frombuffer(raw, np.uint8), cv2.IMREAD_COLOR)
    assert shown.shape[:2] == result.nominal.annotated.shape[:2]
    px = shown_text_px(page, ("nominal", "worst sample"))
    assert min(px.values()) >= MIN_TEXT_PX, px
