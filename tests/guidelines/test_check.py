"""The overlay against the same lines painted on the rendered ground (the renderer check),
on two vehicles (equidistance and Kannala–Brandt lenses), and the G-1 / G-2 ECs."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from rvmsim.criteria import load_criteria
from rvmsim.guidelines import guideline_view, running_gear, static_lines, scene_spec
from rvmsim.guidelines.check import check_guidelines, measure_painted, painted_scene
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.pipeline import evaluate_params
from rvmsim.render import cached_render
from rvmsim.scene import Display, Scene, scene_vehicle_width
from tests.conftest import bundled_scene

#: Renders at half the sensor, so the RVM image of record is half of 1280 × 720 too: the
#: label pixels are as fine relative to the display as a full render's at 1280 × 720.
SCALE = 0.5
LIMIT_PX = 1.0


def _small(letter: str) -> Scene:
    return bundled_scene(letter).model_copy(update={"display": Display(rvm_image_px=(640, 360))})


class _Renders:
    """The fisheye labels of each painted scene the check asks for, kept for re-measuring."""

    def __init__(self) -> None:
        self.labels: dict[tuple[str, ...], np.ndarray] = {}

    def __call__(self, scene: Scene, scale: float) -> np.ndarray:
        labels = cached_render(scene, scale=scale)[0].labels
        self.labels[tuple(p.name for p in scene.test_site.painted_lines)] = labels
        return labels


@pytest.mark.parametrize("letter,params", [
    ("a", IspParams()),
    ("b", IspParams(fov=190.0, rad=620.0, h_shift=-15.0, v_shift=25.0, zoom=1.15,
                    adv_v_shift=-0.1, h_pan=6.0, v_pan=80.0)),
])
def test_the_overlay_lies_on_the_painted_lines(letter: str, params: IspParams) -> None:
    scene = _small(letter)
    rng = running_gear(scene).steering_range_deg
    angles = (0.0, rng, -0.5 * rng)
    renders = _Renders()
    result = check_guidelines(scene, params, OutputSpec(), steering_deg=angles, scale=SCALE,
                              render=renders)
    assert result.output.width == 640
    kinds = {c.kind for c in result.lines}
    assert kinds == {"mark", "width", "trajectory"}
    for c in result.lines:  # a line in the picture is measured (the body or board hide some)
        assert len(c.offsets_px) >= 0.3 * c.scans, c.name
    assert sum(c.measured for c in result.lines if c.kind != "trajectory") >= 5
    assert {c.steering_deg for c in result.lines if c.measured} == {None, *angles}
    assert result.worst_px(("mark", "width")) <= LIMIT_PX
    assert result.worst_px(("trajectory",)) <= LIMIT_PX
    for c in result.lines:  # on the ground: 1 px of 640 × 360 spans < 4 cm within 3.5 m
        assert not c.measured or 0.0 <= c.offset_cm < 4.0 * max(c.offset_px, 0.25), c.name
    # the check has teeth: an overlay drawn for a camera pitched 0.5° off its mount is off
    # the painted lines by more than the limit
    m = scene.camera.mount
    tilted = scene.with_mount(m.position, m.yaw_deg, m.pitch_deg + 0.5, m.roll_deg)
    moved = guideline_view(scene, params.for_input_scale(SCALE), OutputSpec(),
                           camera=tilted.fisheye_camera().scaled(SCALE))
    key = next(k for k in renders.labels if any(n.startswith("mark") for n in k))
    painted = painted_scene(scene, static_lines(scene_vehicle_width(scene),
                                                scene_spec(scene))).test_site.painted_lines
    off = measure_painted(renders.labels[key], moved, painted)
    assert max(c.offset_px for c in off if c.measured) > 2 * LIMIT_PX


def test_g1_is_measured_on_a_painted_scene_and_g2_needs_trajectories() -> None:
    scene = _small("a")
    lines = static_lines(scene_vehicle_width(scene), scene_spec(scene))
    images, _ = cached_render(painted_scene(scene, lines), scale=SCALE)
    frame = evaluate_params(images, IspParams().for_input_scale(SCALE), OutputSpec(640, 360),
                            load_criteria("guidelines"), annotate=False)
    by_id = {item.id: item for item in frame.ec.items}
    assert by_id["G-1"].value is not None and by_id["G-1"].passed
    assert by_id["G-2"].value is None  # no trajectory painted: not measured
    # the site's own scene (nothing painted) is not measured either
    plain, _ = cached_render(scene, scale=SCALE)
    frame = evaluate_params(plain, IspParams().for_input_scale(SCALE), OutputSpec(640, 360),
                            load_criteria("guidelines"), annotate=False)
    assert all(item.value is None for item in frame.ec.items)
