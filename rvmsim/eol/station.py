"""The station's step for one car: its camera's pose from the target, its deviation, its
per-car ISP values and the ECs on its corrected picture.

For each capture (:meth:`Station.car`):

1. **Pose.** The pose search ``rvmsim validate`` uses too (:func:`rvmsim.pose.find_mount`;
   no edge comparison, pictures or verdict of a validation) on the
   station scene (:func:`rvmsim.scene.station_scene`: the car in front of the target) with
   the camera at its nominal pose at the station's load state: the target's checker corners
   matched and the mount pose fitted (fisheye PnP).  A car is usually within a few px of its
   nominal pose, so the dense pre-alignment on a ground target is skipped; when the pose
   is then not found (too few corners, or corners matched to their neighbours: a fit worse
   than ``max_rms_px``), it runs again with it (a camera several degrees off).
2. **Deviation.** The measured pose relative to the design pose (the scene's mount), as
   the station reads it in its load state (:func:`~.geometry.deviation_of`; a load state
   that moves the body reads as a deviation too, as ``rvmsim robustness --compensation``
   models the station).
3. **The car's picture.** The scene (its full test site) is rendered at the measured pose
   (labels only, and only of the fisheye pixels the car's RVM image can show under any
   per-car values in the allowed ranges, when no EC reads the fisheye labels elsewhere):
   the test site as the station sees it.  The body's outline is then found in the capture
   itself and the body region re-drawn from it (:mod:`.body`): the ECs that read the body
   do not inherit the pose error.
4. **Per-car values.** The compensation model's law on that picture
   (:func:`rvmsim.percar.make_law`; ``ec-solve`` by default: every enabled EC passes with
   the largest least margin), the same call ``rvmsim robustness --compensation`` makes.
   The station's verdict: ``pass``, ``marginal`` (an EC's margin inside the station's
   uncertainty; failed unless the model's ``marginal`` is ``accept``), ``infeasible`` (no
   setting within the allowed ranges passes, with the ECs that conflict named).
5. **ECs.** The capture's colour and the picture's labels through the car's values: every
   EC evaluated (:func:`rvmsim.pipeline.evaluate_params`) at the RVM image of record, and
   the pictures of the car's RVM image drawn.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .._io import key_lines, line_of
from ..camera import FisheyeCamera, rotation_from_ypr
from ..compensation import DEFAULT_COMPENSATION, CompensationModel
from ..criteria import Criteria, default_criteria
from ..errors import RvmsimError, SceneError
from ..isp import IspParams, OutputSpec
from ..percar import ImagePicture, PerCarLaw, SplitEvaluator, make_law
from ..pipeline import evaluate_params, record_output, rvm_pixels
from ..render import FisheyeImages
from ..robust import Variation, body_pose
from ..scene import Scene, station_scene
from ..pose import (LandmarkMatch, MountFit, PoseFailure, PoseSettings, blend, find_mount,
                    landmark_picture, visible_landmarks)
from .body import capture_labels, find_body_edge
from .frames import PoseRenderer
from .geometry import deviation_of, mount_at, moved_camera, station_load
from .records import CarResult, StationResult
from .tables import car_table, guideline_angles

__all__ = ["StationSettings", "Station"]


@dataclass(frozen=True)
class StationSettings:
    """What the station judges cars by (``rvmsim eol``'s options).

    Parameters
    ----------
    params : IspParams
        The platform setting (full sensor).
    output : OutputSpec
        Its mirroring: every car is judged at the RVM image of record
        (:func:`rvmsim.pipeline.record_output`: the scene's or criteria's display size,
        default 1280 × 720), whatever size is given here.
    compensation : CompensationModel
        What the EOL step writes, within which ranges, and the load state it measures at.
    criteria : Criteria, optional
        The ECs (default: the paper's).
    variation : Variation, optional
        The load states ``compensation.measured_at`` names (default: the scene's variation
        section).
    min_landmarks : int
        Fewer target corners matched: the pose is not recovered.
    search_px : float
        How far from its nominal place a corner is first searched for, px.
    max_rms_px : float
        A pose whose corners fit worse than this (RMS, px) is not believed.
    """

    params: IspParams
    output: OutputSpec
    compensation: CompensationModel = DEFAULT_COMPENSATION
    criteria: Criteria | None = None
    variation: Variation | None = None
    min_landmarks: int = 8
    search_px: float = 30.0
    max_rms_px: float = 2.0


def _line(scene: Scene, key: str) -> int | None:
    """The line of the dotted ``key`` in the scene's file, when it is one (for messages)."""
    path = Path(scene.source)
    try:
        text = path.read_text() if path.is_file() else ""
    except OSError:  # the line number is a nicety; the message names the file anyway
        return None
    return line_of(key_lines(text), tuple(key.split("."))) if text else None


class Station:
    """One scene's EOL station, set up once for many cars.

    Parameters
    ----------
    scene : Scene
        The car as designed, with its test site (the ECs) and ``eol`` section (the target).
    settings : StationSettings
    progress : bool
        Progress bars while rendering the station's nominal frame.

    Raises
    ------
    SceneError
        No ``eol`` section, an unusable one, a target the camera does not see well enough at
        its nominal pose (fewer than ``min_landmarks`` usable corners), or a scene with a
        ``load_state`` of its own (the station's load state is ``measured_at``).
    CompensationError
        ``measured_at`` names no load state, or the law has too few reference points in
        the platform setting's RVM image.
    """

    def __init__(self, scene: Scene, settings: StationSettings, *, progress: bool = False):
        self.scene = scene
        self.settings = settings
        self.criteria = settings.criteria or default_criteria()
        if scene.load_state is not None:
            raise SceneError(scene.source, "load_state", "a scene with a load state is one "
                             "loaded car; the station stands every car in the compensation "
                             "model's station.measured_at (a load state of the variation): "
                             "remove load_state", _line(scene, "load_state"))
        station = station_scene(scene)
        self.load = station_load(scene, settings.compensation, settings.variation)
        self.body_pose = body_pose(scene, self.load)
        cam = scene.fisheye_camera()
        self.nominal_camera = moved_camera(cam, self.body_pose)
        #: The station with the camera at its nominal pose at the load state.
        self.station = mount_at(station, self.nominal_camera)
        self._station_renderer = PoseRenderer(self.station, cam, self.body_pose)
        self.frame: FisheyeImages = self._station_renderer.frame(self.nominal_camera,
                                                                 progress=progress)
        self._check_target_in_view()
        #: The RVM image of record every car is judged at.
        self.record = record_output(self.criteria, scene, settings.output.mirror)
        self._renderer = PoseRenderer(scene, cam, self.body_pose)
        # the car as designed at the station: where the station's EC uncertainty is read
        nominal = self._renderer.frame(self.nominal_camera, progress=progress)
        #: The steering angles of every car's guideline table (None: no running gear).
        self.guideline_angles = guideline_angles(scene)
        self.law: PerCarLaw = make_law(
            scene, settings.params, self.record, settings.compensation, self.criteria,
            ImagePicture(SplitEvaluator(nominal, self.record, self.criteria)), nominal.camera)

    def prepare(self) -> None:
        """Build the scene's meshes now (else the first car does, ~1 s)."""
        self._renderer.parts()

    def result(self, cars: Sequence[CarResult], params_file: str = "",
               timings: dict[str, float] | None = None) -> StationResult:
        """The record of a run of this station over ``cars``."""
        s, load = self.settings, self.load
        assert self.scene.eol is not None
        return StationResult(
            scene_name=self.scene.name, scene_file=self.scene.source,
            target=self.scene.eol.target,
            load_state={"name": load.name, "height_mm": load.height_mm,
                        "pitch_deg": load.pitch_deg},
            params_file=params_file, output=(self.record.width, self.record.height),
            compensation=s.compensation.as_dict(), criteria=self.criteria.name,
            written=tuple(s.compensation.params), cars=tuple(cars), timings=dict(timings or {}),
            platform_isp={n: float(getattr(s.params, n)) for n in IspParams.names()},
            guideline_angles=self.guideline_angles)

    def _check_target_in_view(self) -> None:
        spec = self.scene.eol
        assert spec is not None  # station_scene checked it
        need = self.settings.min_landmarks
        try:
            seen = visible_landmarks(self.station, self.frame, 0).n_usable
        except RvmsimError:  # the target has no inner checker corners at all
            seen = 0
        if seen < need:
            key = "eol.pose" if spec.pose is not None else "eol.target"
            raise SceneError(self.scene.source, key, f"the target ({spec.target}) is not in "
                             f"the camera's view: {seen} of its checker corners are usable at "
                             f"the nominal pose (load state {self.load.name}; need {need}: "
                             "unoccluded, inside the lens's field, ≥ 8 px apart)",
                             _line(self.scene, key))

    def _shown(self, camera: FisheyeCamera) -> np.ndarray | None:
        """The fisheye pixels the car's RVM image can show ((H, W) bool): those the platform
        setting shows, grown by what the per-car values may turn the view by (the allowed
        turn and roll at the image's corner, + 8 px); only their labels are rendered,
        unless an EC reads the scene's fisheye labels elsewhere (None)."""

        if self.criteria.uses_scene:
            return None
        m = self.settings.compensation
        turn = math.radians(m.range_of("h_pan")[1] if m.pans else 0.0)
        roll = math.radians(max(abs(v) for v in m.range_of("tilt"))) if "tilt" in m.params \
            else 0.0
        shifts = sum(max(abs(v) for v in m.range_of(n)) for n in ("h_shift", "v_shift")
                     if n in m.params)
        grow = int(math.ceil(camera.fx * turn + math.hypot(camera.width, camera.height) / 2
                             * roll + shifts)) + 8
        flat = np.zeros(camera.width * camera.height, np.uint8)
        flat[rvm_pixels(camera, self.settings.params, self.record).pixels] = 1
        k = 2 * grow + 1
        return cv2.dilate(flat.reshape(camera.height, camera.width),
                          cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))) > 0

    def _pose(self, capture: np.ndarray, capture_name: str, *, dense: bool
              ) -> MountFit | tuple[str, int, float | None, dict[str, np.ndarray]]:
        """The car's pose found on the target, or why it is not (reason, landmarks, RMS px,
        pictures: the capture blended with the nominal frame and the corners predicted and
        found): too few corners found, or a fit worse than ``max_rms_px`` (corners matched
        to their neighbours)."""
        s = self.settings
        ps = PoseSettings(min_landmarks=s.min_landmarks, search_px=s.search_px,
                          dense_align=dense)
        try:
            fit = find_mount(self.station, capture, self.frame, ps, capture_name=capture_name)
        except PoseFailure as fail:
            return (f"pose not recovered ({fail.step}): {fail.detail}", 0, None,
                    self._pictures(capture, fail.landmarks))
        if fit.rms_after_px > s.max_rms_px:
            return (f"pose not recovered: the target's corners fit it with RMS "
                    f"{fit.rms_after_px:.2f} px > {s.max_rms_px:g} px", fit.n_inliers,
                    fit.rms_after_px, self._pictures(capture, fit.landmarks))
        return fit

    def _pictures(self, capture: np.ndarray,
                  landmarks: tuple[LandmarkMatch, ...]) -> dict[str, np.ndarray]:
        """A car without a pose: its capture blended with the nominal frame (``overlay``)
        and the target's corners predicted and found (``landmarks``)."""
        return {"overlay": blend(capture, self.frame.color),
                "landmarks": landmark_picture(capture, landmarks)}

    def car(self, capture: np.ndarray, capture_name: str, name: str) -> CarResult:
        """One car's station step on its ``capture`` ((H, W, 3) uint8 RGB, the camera's
        size); ``name`` is the stem of its output files.  A pose that cannot be recovered
        is a failing car, not an error."""
        t0 = time.perf_counter()
        s = self.settings
        v = self._pose(capture, capture_name, dense=False)
        if isinstance(v, tuple) and self.station.test_site.ground_patterns:
            v = self._pose(capture, capture_name, dense=True)  # a car far off: align first
        if isinstance(v, tuple):
            return CarResult(capture_name, name, (v[0],), landmarks=v[1], rms_px=v[2],
                             images=v[3], seconds=time.perf_counter() - t0)
        c = v.correction
        sigma = (*c.sigma_position_mm, *c.sigma_angles_deg)
        rotation = rotation_from_ypr(c.yaw_deg, c.pitch_deg, c.roll_deg)
        position = np.asarray(c.position_m, dtype=np.float64)
        deviation = deviation_of(self.scene, position, rotation)
        pose = dataclasses.replace(self.nominal_camera, rotation=rotation, position=position)
        rendered = self._renderer.labels(pose, self._shown(pose))
        edge = find_body_edge(capture, rendered)
        images = FisheyeImages(color=capture, labels=capture_labels(rendered, edge),
                               camera=pose, scene=self.scene)
        sol = self.law.solve(deviation, ImagePicture(SplitEvaluator(images, self.record,
                                                                    self.criteria)))
        frame = evaluate_params(images, sol.params, self.record, self.criteria)
        reasons = () if self.law.accepts(sol) else sol.reasons
        assert frame.annotated is not None  # asked for
        table = None if self.guideline_angles is None else car_table(
            self.scene, pose, sol.correction.params, self.record, self.guideline_angles)
        return CarResult(capture_name, name, tuple(reasons), deviation, sigma, v.n_inliers,
                         v.rms_after_px, sol.correction, frame.ec,
                         {"rvm": frame.color, "annotated": frame.annotated},
                         time.perf_counter() - t0, solution=sol, body_edge=edge.as_dict(),
                         guidelines=table)
