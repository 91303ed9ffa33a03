"""One car's guidelines on its RVM image: the static lines and the trajectory lines of every
steering angle asked for (:func:`compute_guidelines`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..camera import FisheyeCamera
from ..isp import IspParams, OutputSpec
from ..scene import Display, GuidelineSpec, Scene, scene_vehicle_width
from .kinematics import RunningGear, running_gear
from .lines import static_lines, trajectory_lines
from .project import DisplayLine, GuidelineView, project_lines

__all__ = ["GuidelineSet", "scene_spec", "guideline_output", "guideline_view",
           "compute_guidelines", "steering_angles"]


@dataclass(frozen=True, eq=False)
class GuidelineSet:
    """A car's guidelines on the RVM image of record.

    Attributes
    ----------
    view : GuidelineView
        The camera and ISP setting they were drawn through.
    spec : GuidelineSpec
    gear : RunningGear
    width_m : float
        The car's width the lines are placed by, m.
    static : tuple of DisplayLine
        Distance marks, then width lines.
    steering_deg : tuple of float
        Steering-wheel angles, degrees.
    trajectories : tuple of tuple of DisplayLine
        Per angle of ``steering_deg``, its trajectory lines (−X side, +X side).
    """

    view: GuidelineView
    spec: GuidelineSpec
    gear: RunningGear
    width_m: float
    static: tuple[DisplayLine, ...]
    steering_deg: tuple[float, ...]
    trajectories: tuple[tuple[DisplayLine, ...], ...]

    def lines(self) -> list[DisplayLine]:
        """Static lines, then every angle's trajectory lines."""
        return [*self.static, *(line for group in self.trajectories for line in group)]

    def at(self, steering_deg: float) -> tuple[DisplayLine, ...]:
        """The static lines and the trajectory lines of ``steering_deg`` (one of
        :attr:`steering_deg`)."""
        return (*self.static, *self.trajectories[self.steering_deg.index(steering_deg)])


def scene_spec(scene: Scene) -> GuidelineSpec:
    """The scene's guideline spec (``guidelines:``, read when the scene loaded), else the
    bundled default (:class:`~rvmsim.scene.GuidelineSpec`'s defaults)."""
    spec = scene.guidelines
    return spec if isinstance(spec, GuidelineSpec) else GuidelineSpec()


def guideline_output(scene: Scene, output: OutputSpec) -> OutputSpec:
    """The RVM image of record (the scene's ``display.rvm_image_px``, default 1280 × 720)
    with ``output``'s mirroring: the image guidelines are drawn on, whatever size a search
    measured at."""
    w, h = (scene.display or Display()).rvm_image_px
    return OutputSpec(int(w), int(h), output.mirror)


def guideline_view(scene: Scene, params: IspParams, output: OutputSpec, *,
                   camera: FisheyeCamera | None = None) -> GuidelineView:
    """The view guidelines are drawn through: ``camera`` (default: the scene's, at its
    mount), ``params`` and the image of record (:func:`guideline_output`)."""
    return GuidelineView(camera or scene.fisheye_camera(), params, guideline_output(scene, output))


def steering_angles(gear: RunningGear, spec: str | None = None) -> tuple[float, ...]:
    """Steering-wheel angles (degrees) from ``"start:stop:step"`` (both ends included when
    on the grid), ``"a,b,c"``, or None: the whole range in 10° steps plus its ends.

    Raises
    ------
    ValueError
        A malformed spec, a zero step, or more than 2001 angles.
    """
    if spec is None:
        r = gear.steering_range_deg
        inner = np.arange(-math.floor(r / 10) * 10, r, 10.0)
        values = np.unique(np.r_[-r, inner, r])
    elif ":" in spec:
        parts = spec.split(":")
        if len(parts) != 3:
            raise ValueError(f"{spec!r}: give start:stop:step")
        start, stop, step = (float(p) for p in parts)
        if step <= 0 or not all(map(math.isfinite, (start, stop, step))):
            raise ValueError(f"{spec!r}: the step must be a positive number")
        if stop < start or (stop - start) / step > 2000:
            raise ValueError(f"{spec!r}: start must not exceed stop, at most 2001 angles")
        n = int(math.floor((stop - start) / step + 1e-9)) + 1
        values = start + step * np.arange(n)
    else:
        values = np.array([float(p) for p in spec.split(",") if p.strip()])
        if values.size == 0 or values.size > 2001 or not np.isfinite(values).all():
            raise ValueError(f"{spec!r}: give 1 to 2001 finite angles")
    return tuple(float(round(v, 9)) + 0.0 for v in dict.fromkeys(values.tolist()))


def compute_guidelines(scene: Scene, view: GuidelineView,
                       steering_deg: Sequence[float] = (0.0,), *,
                       spec: GuidelineSpec | None = None) -> GuidelineSet:
    """The scene's guidelines through ``view``.

    Parameters
    ----------
    scene : Scene
        Its ``vehicle`` gives the width and the running gear.
    view : GuidelineView
    steering_deg : sequence of float
        Steering-wheel angles, degrees (positive toward +X).
    spec : GuidelineSpec, optional
        Default: :func:`scene_spec`.

    Raises
    ------
    SceneError
        The scene lacks a running-gear key the guidelines need.
    """
    spec = spec or scene_spec(scene)
    gear = running_gear(scene)
    width = scene_vehicle_width(scene)
    angles = tuple(float(a) for a in steering_deg)
    ground = static_lines(width, spec)
    per_angle = [trajectory_lines(gear, width, spec, a) for a in angles]
    shown = project_lines(view, [*ground, *(l for g in per_angle for l in g)])
    static, rest = shown[:len(ground)], shown[len(ground):]
    groups: list[tuple[DisplayLine, ...]] = []
    for g in per_angle:
        groups.append(tuple(rest[:len(g)]))
        rest = rest[len(g):]
    return GuidelineSet(view, spec, gear, width, tuple(static), angles, tuple(groups))
