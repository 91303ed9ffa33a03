"""Figures of `rvmsim validate` (not a test): accuracy and time on the captures the tests use.

    python tools/bench_validate.py

Builds the same captures as the tests in ``tests/validate/`` (their scene and degradations
are imported from ``rvmsim/testing/captures.py``): unperturbed, perturbed by a known pose
error with other textures and sensor effects, a scene 60 mm / 3° off, and the real BAIC EU5
frame with the bundled scene and from its README's rough pose.  Prints the landmark errors, the recovered pose error
against the truth, and the seconds per validation (render excluded, re-render included).
"""

from __future__ import annotations

import os
import platform
import time

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

import rvmsim.validate as V  # noqa: E402
from rvmsim.render import render_fisheye  # noqa: E402
from rvmsim.testing import captures as T  # noqa: E402


def show(name: str, res: V.Validation, seconds: float) -> None:
    c = res.correction
    print(f"{name}: {res.n_inliers}/{res.n_found} inliers, RMS {res.rms_before_px:.2f} -> "
          f"{res.rms_after_px:.2f} px (max {res.max_after_px:.2f}); Δpos "
          "({:+.1f}, {:+.1f}, {:+.1f}) mm, Δypr ({:+.3f}, {:+.3f}, {:+.3f})°; {} in {:.1f} s".format(
              *c.d_position_mm, c.d_yaw_deg, c.d_pitch_deg, c.d_roll_deg,
              "PASS" if res.passed else "FAIL", seconds))


def main() -> None:
    print(f"{platform.python_version()} on {cpu_model()} ({os.cpu_count()} cores)")
    sc, syn = T.base()
    t = time.perf_counter()
    res = V.validate(sc, syn.color.copy(), synthetic=syn)
    show("unperturbed", res, time.perf_counter() - t)
    _, cap = T.perturbed()
    t = time.perf_counter()
    res = V.validate(sc, cap, synthetic=syn)
    show("perturbed", res, time.perf_counter() - t)
    c = res.correction
    got = (*c.d_position_mm, c.d_yaw_deg, c.d_pitch_deg, c.d_roll_deg)
    err = [g - w for g, w in zip(got, (*T.D_POS_MM, *T.D_YPR_DEG))]
    print("  recovered minus truth: ({:+.1f}, {:+.1f}, {:+.1f}) mm, ({:+.3f}, {:+.3f}, "
          "{:+.3f})°".format(*err))
    wrong = T.wrong_scene()
    wrong_syn = render_fisheye(wrong)
    t = time.perf_counter()
    show("scene 60 mm / 3° off", V.validate(wrong, cap, synthetic=wrong_syn),
         time.perf_counter() - t)
    if T.BAIC.is_file():
        sc, cap, syn = T.baic()
        t = time.perf_counter()
        show("BAIC EU5 real frame", V.validate(sc, cap, synthetic=syn), time.perf_counter() - t)
        rough_scene = T.baic_rough_scene(sc)
        rough_syn = render_fisheye(rough_scene)
        t = time.perf_counter()
        show("BAIC from the rough pose", V.validate(rough_scene, cap, synthetic=rough_syn),
             time.perf_counter() - t)


if __name__ == "__main__":
    main()
