"""CLI: `rvmsim render` writes the images people and later stages use."""

from __future__ import annotations

import json
import subprocess
import sys

import imageio.v3 as iio
import numpy as np

from rvmsim import labels as L

from .conftest import SCENES


def test_render_writes_color_labels_preview_and_metadata(tmp_path):
    out = tmp_path / "a"
    res = subprocess.run(
        [sys.executable, "-m", "rvmsim", "render", str(SCENES / "vehicle_a.yaml"), "--out",
         str(out), "--scale", "0.25", "--no-progress"],
        capture_output=True, text=True, timeout=300,
    )
    assert res.returncode == 0, res.stderr
    color = iio.imread(out / "fisheye_color.png")
    labels = iio.imread(out / "fisheye_labels.png")
    preview = iio.imread(out / "fisheye_labels_preview.png")
    assert color.shape == (240, 320, 3) and color.dtype == np.uint8
    assert labels.shape == (240, 320) and labels.dtype == np.uint8
    assert np.array_equal(preview, L.colorize(labels))
    meta = json.loads((out / "render.json").read_text())
    assert meta["image_size"] == [320, 240]
    present = {int(k) for k in meta["labels_present"]}
    assert present == set(np.unique(labels).tolist())
    assert {L.BUMPER, L.BOARD, L.object_patch("F")} <= present
    assert "rendered Vehicle A" in res.stdout


def test_render_unwritable_output_is_one_line(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    res = subprocess.run(
        [sys.executable, "-m", "rvmsim", "render", str(SCENES / "vehicle_a.yaml"), "--out",
         str(blocker / "sub"), "--scale", "0.1", "--no-progress"],
        capture_output=True, text=True, timeout=300,
    )
    assert res.returncode == 2
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr
