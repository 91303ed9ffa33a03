"""rvmsim.validate.outputs and the validation page (rvmsim.report.validation)."""

from __future__ import annotations

import dataclasses
import json

import cv2
import numpy as np

from rvmsim.storage import json_default
from rvmsim.report import write_validation_outputs as write_outputs

from rvmsim.testing.captures import perturbed_validation


def test_write_outputs_writes_json_page_and_pictures(tmp_path):
    res, _ = perturbed_validation()
    res = dataclasses.replace(res, scene_name="<b>mat & board</b>")
    written = write_outputs(res, tmp_path / "out")
    names = [p.name for p in written]
    assert names == ["validation.json", "validation.html", "overlay.png", "edges.png",
                     "landmarks.png", "overlay_corrected.png", "edges_corrected.png"]
    doc = json.loads((tmp_path / "out" / "validation.json").read_text())
    assert doc == json.loads(json.dumps(res.to_dict(), default=json_default))
    assert doc["landmarks"]["found"] == res.n_found and doc["passed"] is res.passed
    for name, img in res.images.items():
        back = cv2.imread(str(tmp_path / "out" / f"{name}.png"))[..., ::-1]
        assert np.array_equal(back, img)
    html = (tmp_path / "out" / "validation.html").read_text()
    assert "&lt;b&gt;mat &amp; board&lt;/b&gt;" in html and "<b>mat" not in html
    assert html.count("data:image/png;base64,") == len(res.images)
    assert "pose_angle_correction_deg" in html and ": FAIL</h1>" in html
