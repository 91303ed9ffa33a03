"""rvmsim.validate.validate: the whole comparison of a scene with a capture."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.errors import RvmsimError
from rvmsim.validate import ValidationSettings, validate

from rvmsim.testing.captures import BAIC, baic, base, perturbed
from ..conftest import needs_real


def test_unperturbed_capture_gives_no_correction():
    sc, syn = base()
    res = validate(sc, syn.color.copy(), ValidationSettings(rerender=False), synthetic=syn)
    assert res.passed
    assert res.n_inliers >= 35 and res.n_inliers == res.n_found
    # The renderer puts edges within 0.5 / oversample px of their place: ~0.2 px RMS.
    assert res.rms_before_px < 0.35 and res.rms_after_px < 0.35
    c = res.correction
    assert c.d_position_norm_mm < 5.0 and c.max_d_angle_deg < 0.1
    assert res.edges_before.chamfer_px < 0.05
    assert res.edges_after is None and res.rvm is None
    assert list(res.images) == ["overlay", "edges", "landmarks"]


def test_capture_of_something_else_is_an_error():
    sc, syn = base()
    noise = np.random.default_rng(3).integers(0, 255, syn.color.shape, dtype=np.uint8)
    with pytest.raises(RvmsimError, match="fit the capture.s shade nowhere"):
        validate(sc, noise, ValidationSettings(rerender=False), synthetic=syn)
    with pytest.raises(RvmsimError, match="320×240 px but the scene's camera is 640×480"):
        validate(sc, syn.color[::2, ::2].copy(), ValidationSettings(rerender=False), synthetic=syn)


def test_rvm_comparison_and_ecs_follow_the_capture():
    """With ISP parameters: the capture's RVM image is compared with the synthetic one, and
    the ECs 'on the capture' (labels of the pose that explains it) are closer to the ECs of
    the true pose than the scene's are."""
    from rvmsim.criteria import evaluate
    from rvmsim.isp import IspParams, OutputSpec, process

    sc, syn = base()
    truth, cap = perturbed()
    params = IspParams().for_input_scale(640 / 1280)
    out = OutputSpec(320, 180)
    res = validate(sc, cap, ValidationSettings(params=params, output=out), synthetic=syn)
    assert res.rvm is not None
    # the ECs are judged at the RVM image of record, whatever size the params name
    record = OutputSpec(1280, 720, out.mirror)
    ec_truth = evaluate(process(None, truth.labels, params, record)[1])
    diffs_scene, diffs_capture = [], []
    for item in ec_truth.items:
        vt, vs, vc = item.value, res.rvm.ec_scene[item.id].value, res.rvm.ec_capture[item.id].value
        if vt is None or vs is None or vc is None:
            continue
        diffs_scene.append(abs(vs - vt) / max(abs(vt), 1e-3))
        diffs_capture.append(abs(vc - vt) / max(abs(vt), 1e-3))
    assert len(diffs_scene) >= 6
    assert sum(diffs_capture) < 0.5 * sum(diffs_scene), (diffs_capture, diffs_scene)
    for key in ("rvm_capture", "rvm_synthetic", "rvm_overlay", "rvm_edges"):
        assert res.images[key].shape == (720, 1280, 3)
    d = res.to_dict()
    assert set(d["rvm"]["ecs"]) == {i.id for i in ec_truth.items}


@needs_real
def test_real_capture_matches_the_bundled_scene():
    """The bundled BAIC EU5 scene explains its real frame: ≥ 35 mat corners matched with
    RMS ≤ 2 px (≈ 0.7 px), and its mount pose needs no correction beyond the tolerances."""
    sc, cap, syn = baic()
    res = validate(sc, cap, ValidationSettings(rerender=False), synthetic=syn,
                   capture_name=str(BAIC))
    assert res.n_inliers >= 35
    assert res.rms_after_px <= 2.0 and res.rms_before_px <= 2.0
    assert res.passed, res.summary()
    # The pose is plausible for a rear camera: the README's rough decomposition says
    # ~0.97 m up and ~38° down.
    c = res.correction
    assert 0.90 <= -c.position_m[1] <= 1.02
    assert 35.0 <= c.pitch_deg <= 40.0
