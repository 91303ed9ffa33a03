"""The compensation law: from a car's measured camera deviation to the per-car ISP values
that put the picture back where the nominal car shows it.

Method
------
Reference points on the ground (:func:`reference_points`: the guideline ends and the bases of
the test objects, or a grid of ground points over the RVM image) are projected by the
deviated camera (its real lens) into the fisheye image, and through the ISP's inverse map
(:func:`rvmsim.isp.input_to_output`, exact) into the RVM image.  The per-car values minimise
the squared distances, in RVM px, between those points and where the nominal car's RVM image
shows them (Levenberg–Marquardt, ``scipy.optimize.least_squares``).  Nothing is linearised:
the residual is the ISP's own geometry, so where the written parameters can undo a deviation
(a rotation of the camera, with the ISP's lens equal to the real one) the residual is zero,
and otherwise (position offsets: parallax; an ISP lens that differs from the real one) it is
the least-squares best the camera can do — :attr:`Correction.residual_rms_px` says how good.

The view's rotation is written as the pans (the view axis turned by ``h_pan`` toward the
azimuth ``v_pan``) and the tilt (its roll).  The fit varies the turn as a 2-vector
``h_pan·(cos v_pan, sin v_pan)`` (smooth where ``h_pan`` is 0, unlike the polar pair).

Conventions
-----------
A :class:`Deviation` is the camera's pose relative to its nominal mount, in the body frame
(scene frame of the car as modelled): angles add to the mount's yaw, pitch, roll (degrees),
the position offset (mm) adds to its position — as :class:`rvmsim.robust.MountSample`'s
offsets.  Reference points are in the scene frame, metres; RVM positions in output px of
the law's ``output`` (pixel centres at integers).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..camera import FisheyeCamera, rotation_from_ypr, ypr_from_rotation
from ..errors import CompensationError
from ..isp import IspParams, OutputSpec, input_to_output
from ..isp.exact import isp_rays, map_points, pixel_to_ray_matrix, plane_and_view, view_rotation
from ..scene import Scene
from .model import CompensationModel

__all__ = ["Deviation", "Correction", "CompensationLaw", "reference_points", "deviated_camera",
           "deviated_pose", "loaded_deviation", "MIN_REFERENCE_POINTS"]

#: The law needs at least this many reference points in the nominal RVM image.
MIN_REFERENCE_POINTS = 4
_DEVIATION_AXES = ("x_mm", "y_mm", "z_mm", "yaw_deg", "pitch_deg", "roll_deg")


@dataclass(frozen=True)
class Deviation:
    """A camera's pose relative to its nominal mount (see the module's conventions): mm for
    the position offset, degrees for the angles."""

    x_mm: float = 0.0
    y_mm: float = 0.0
    z_mm: float = 0.0
    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0

    @classmethod
    def from_offsets(cls, offsets: Sequence[float]) -> Deviation:
        """From six offsets in :data:`rvmsim.scene.MOUNT_AXES` order (x, y, z mm; yaw,
        pitch, roll degrees)."""
        return cls(*(float(v) for v in offsets))

    def as_offsets(self) -> tuple[float, float, float, float, float, float]:
        """The six offsets in :data:`rvmsim.scene.MOUNT_AXES` order."""
        return (self.x_mm, self.y_mm, self.z_mm, self.yaw_deg, self.pitch_deg, self.roll_deg)

    def __add__(self, other: Deviation) -> Deviation:
        return Deviation(*(a + b for a, b in zip(self.as_offsets(), other.as_offsets())))

    def as_dict(self, digits: int = 4) -> dict[str, float]:
        return {n: round(v, digits) for n, v in zip(_DEVIATION_AXES, self.as_offsets())}


def deviated_pose(scene: Scene, deviation: Deviation) -> tuple[np.ndarray, np.ndarray]:
    """The camera-to-scene rotation (3, 3) and the position (3,), metres, of the scene's
    camera at its mount moved by ``deviation`` (on the body: a scene's ``load_state`` then
    moves it with the body, as it moves the nominal one)."""
    m = scene.camera.mount
    d = deviation
    rot = rotation_from_ypr(m.yaw_deg + d.yaw_deg, m.pitch_deg + d.pitch_deg,
                            m.roll_deg + d.roll_deg)
    pos = np.asarray(m.position, dtype=np.float64) + np.array([d.x_mm, d.y_mm, d.z_mm]) / 1000.0
    if scene.load_state is not None:
        body = scene.load_state.motion(m.position)
        rot, pos = body[:3, :3] @ rot, body[:3, :3] @ pos + body[:3, 3]
    return rot, pos


def deviated_camera(scene: Scene, deviation: Deviation) -> FisheyeCamera:
    """The scene's camera (full sensor) at the pose :func:`deviated_pose` gives."""
    cam = scene.camera.to_camera()
    rot, pos = deviated_pose(scene, deviation)
    return dataclasses.replace(cam, rotation=rot, position=pos)


def loaded_deviation(scene: Scene, deviation: Deviation, height_mm: float,
                     pitch_deg: float) -> Deviation:
    """The camera's deviation from the nominal mount as seen from the ground when the body
    stands in a load state: the body pitched by ``pitch_deg`` (rear down > 0) about the
    camera's nominal centre, the camera lowered by ``-height_mm`` (as
    :func:`rvmsim.robust.body_pose` moves it).  What a station that compares the camera's
    pose with the design pose reads for a car in that load state."""
    if height_mm == 0.0 and pitch_deg == 0.0:
        return deviation
    m = scene.camera.mount
    rb = rotation_from_ypr(0.0, pitch_deg, 0.0)
    rot = rb @ rotation_from_ypr(m.yaw_deg + deviation.yaw_deg, m.pitch_deg + deviation.pitch_deg,
                                 m.roll_deg + deviation.roll_deg)
    ypr = ypr_from_rotation(rot) - np.array([m.yaw_deg, m.pitch_deg, m.roll_deg])
    ypr = (ypr + 180.0) % 360.0 - 180.0
    d = rb @ np.array([deviation.x_mm, deviation.y_mm, deviation.z_mm]) + np.array(
        [0.0, -height_mm, 0.0])
    return Deviation.from_offsets((*d, *ypr))


def _site_points(scene: Scene) -> np.ndarray:
    """The guideline ends and the bases of the test objects (scene frame, metres, on the
    ground): (N, 3)."""
    site = scene.test_site
    g = site.guidelines
    pts = [(x, 0.0, z) for x in g.side_x for z in g.side_z]
    pts += [(x, 0.0, z) for z in g.cross_z for x in g.side_x]
    for letter in "ABCDEFG":
        c = site.object_centre(letter)
        if c is not None:
            pts.append((c[0], 0.0, c[1]))
    return np.array(pts, dtype=np.float64).reshape(-1, 3)


def _ground_points(camera: FisheyeCamera, params: IspParams, output: OutputSpec,
                   grid: tuple[int, int] = (9, 6), max_range_m: float = 12.0) -> np.ndarray:
    """Ground points seen on a ``grid`` of RVM pixels (the RVM pixel's ray through the
    ISP map and the lens, met with the ground plane Y = 0), at most ``max_range_m`` away."""
    u = np.linspace(0.05, 0.95, grid[0]) * (output.width - 1)
    v = np.linspace(0.05, 0.95, grid[1]) * (output.height - 1)
    uu, vv = (a.ravel() for a in np.meshgrid(u, v))
    u_in, v_in, _ = map_points(params, uu, vv, (camera.width, camera.height), output)
    rays, in_fov = camera.pixel_rays(np.stack([u_in, v_in], axis=-1))
    d = rays @ camera.rotation.T
    t = -camera.position[1] / np.where(d[:, 1] > 1e-9, d[:, 1], np.nan)
    pts = camera.position + t[:, None] * d
    keep = in_fov & np.isfinite(t) & (t > 0) & (t * np.linalg.norm(d, axis=1) <= max_range_m)
    return pts[keep]


def reference_points(scene: Scene, params: IspParams, output: OutputSpec,
                     reference: str = "site") -> np.ndarray:
    """The ground points the law keeps in place: those of ``reference`` (``site``: the
    guideline ends and the bases of the test objects; ``ground``: a grid over the RVM image)
    that the nominal car's RVM image under ``params`` shows, with a ground grid added when
    fewer than :data:`MIN_REFERENCE_POINTS` of the site's are in view.

    Returns
    -------
    (N, 3) float64
        Scene frame, metres.
    """
    cam = scene.fisheye_camera()
    size = (cam.width, cam.height)

    def shown(points: np.ndarray) -> np.ndarray:
        if not len(points):
            return points
        uv, in_fov = cam.project(points)
        q, ahead = input_to_output(params, uv, size, output)
        inside = (ahead & in_fov & (q[:, 0] >= 0) & (q[:, 0] <= output.width - 1)
                  & (q[:, 1] >= 0) & (q[:, 1] <= output.height - 1))
        return points[inside]

    pts = shown(_site_points(scene)) if reference == "site" else np.zeros((0, 3))
    if len(pts) < MIN_REFERENCE_POINTS:
        pts = np.concatenate([pts, shown(_ground_points(cam, params, output))])
    return pts


@dataclass(frozen=True)
class Correction:
    """One car's per-car values.

    Attributes
    ----------
    params : IspParams
        The car's full parameter set (the platform's with the written values), clipped to
        the allowed ranges: what the camera shows.
    values : dict
        The written parameters' values (``params``' values of the model's parameters).
    offsets : dict
        Each written value's offset from the platform (``h_pan``: the turn of the view axis,
        degrees, ≥ 0, before clipping).
    exceeded : tuple of str
        One message per range the correction leaves ("EOL range exceeded: tilt +2.3° >
        3.0°"); empty when it fits.
    residual_rms_px, residual_max_px : float
        The reference points' remaining distance from where the nominal car shows them, RVM
        px (before clipping).
    """

    params: IspParams
    values: dict[str, float]
    offsets: dict[str, float]
    exceeded: tuple[str, ...] = ()
    residual_rms_px: float = 0.0
    residual_max_px: float = 0.0

    @property
    def within_range(self) -> bool:
        return not self.exceeded

    def as_dict(self) -> dict[str, object]:
        return {"values": {k: round(v, 6) for k, v in self.values.items()},
                "offsets": {k: round(v, 6) for k, v in self.offsets.items()},
                "within_range": self.within_range, "exceeded": list(self.exceeded),
                "residual_rms_px": round(self.residual_rms_px, 4),
                "residual_max_px": round(self.residual_max_px, 4)}


_UNITS = {"h_pan": "°", "tilt": "°", "h_shift": " px", "v_shift": " px", "adv_h_shift": "",
          "adv_v_shift": ""}
#: Typical size of each variable (degrees, input px, half-widths): the fit's scaling.
_TYPICAL = {"pan": 1.0, "tilt": 1.0, "h_shift": 10.0, "v_shift": 10.0, "adv_h_shift": 0.01,
            "adv_v_shift": 0.01}


class CompensationLaw:
    """The per-car values of one platform setting (see the module docstring).

    Parameters
    ----------
    scene : Scene
        The car as designed (its camera at the full sensor size).
    platform : IspParams
        The platform setting, for the full sensor.
    output : OutputSpec
        The RVM image the reference points are kept in place on (px).
    model : CompensationModel
    points : (N, 3) array, optional
        Reference points (scene frame, metres); default :func:`reference_points`.

    Raises
    ------
    CompensationError
        Fewer than :data:`MIN_REFERENCE_POINTS` reference points in the nominal RVM image
        (one line naming the model's file and ``reference``).
    """

    def __init__(self, scene: Scene, platform: IspParams, output: OutputSpec,
                 model: CompensationModel, *, points: np.ndarray | None = None):
        self.scene = scene
        self.platform = platform
        self.output = output
        self.model = model
        pts = reference_points(scene, platform, output, model.reference) if points is None \
            else np.asarray(points, dtype=np.float64).reshape(-1, 3)
        if len(pts) < MIN_REFERENCE_POINTS:
            raise CompensationError(model.source, "reference", (
                f"{scene.source}: only {len(pts)} reference ground points are in the RVM "
                f"image of this setting; the law needs {MIN_REFERENCE_POINTS} (does the view "
                "show the ground behind the car?)"))
        self.points = pts
        cam = scene.fisheye_camera()
        self._camera = cam  # its lens projects every car's points (the pose is theirs)
        self._size = (cam.width, cam.height)
        self.nominal_px = self._rvm(platform, cam.project(pts)[0])
        self._vars = (["pan_x", "pan_y"] if model.pans else []) + [
            n for n in model.params if n not in ("h_pan", "v_pan")]
        self._scale = np.array([_TYPICAL["pan" if v.startswith("pan") else v]
                                for v in self._vars])
        a0 = math.radians(platform.v_pan)
        self._pan0 = (platform.h_pan * math.cos(a0), platform.h_pan * math.sin(a0))
        # Writing the view's rotation only, the output pixel of an ISP ray d is
        # dehomog(M(x)⁻¹ d) with M(x) = R_view(x)·R_view(0)ᵀ·M(0): the fit then needs one
        # 3×3 product per step, not the ISP's inverse map.
        self._rotation_only = set(model.params) <= {"h_pan", "v_pan", "tilt"}
        m0 = pixel_to_ray_matrix(platform, output)
        self._unview = np.linalg.inv(plane_and_view(platform)[1].T @ m0)

    def _rvm(self, params: IspParams, uv: np.ndarray) -> np.ndarray:
        """RVM positions (N, 2), px, of the reference points seen at fisheye ``uv`` (NaN
        where not ahead)."""
        q, ahead = input_to_output(params, uv, self._size, self.output)
        return np.where(ahead[:, None], q, np.nan)

    def _rotated_px(self, x: np.ndarray, rays: np.ndarray) -> np.ndarray:
        """RVM positions (N, 2) of ISP ``rays`` (3, N) with the view turned by the fit's
        variables ``x`` (the rotation-only case; NaN where not ahead)."""
        p = self.platform
        h_pan, v_pan, tilt = p.h_pan, p.v_pan, p.tilt
        k = 0
        if self.model.pans:
            ax, ay = self._pan0[0] + x[0], self._pan0[1] + x[1]
            h_pan = math.hypot(ax, ay)
            v_pan = math.degrees(math.atan2(ay, ax)) if h_pan > 1e-12 else p.v_pan
            k = 2
        if "tilt" in self.model.params:
            tilt = p.tilt + float(x[k])
        h = self._unview @ (view_rotation(h_pan, v_pan, tilt).T @ rays)
        w = np.where(h[2] > 1e-12, h[2], np.nan)
        return np.stack([h[0] / w, h[1] / w], axis=1)

    def params_at(self, x: np.ndarray) -> IspParams:
        """The platform setting with the fit's variables ``x`` (pan turn 2-vector offset,
        degrees; then the other written parameters' offsets) applied."""
        p = self.platform
        changes: dict[str, float] = {}
        k = 0
        if self.model.pans:
            ax, ay = self._pan0[0] + x[0], self._pan0[1] + x[1]
            turn = math.hypot(ax, ay)
            changes["h_pan"] = turn
            changes["v_pan"] = math.degrees(math.atan2(ay, ax)) if turn > 1e-12 else p.v_pan
            k = 2
        for name in self._vars[k:]:
            changes[name] = getattr(p, name) + float(x[k])
            k += 1
        return p.replace(**changes)

    @property
    def variables(self) -> tuple[str, ...]:
        """The fit's variables, in the order of its vectors: ``pan_x``, ``pan_y`` (the
        offset of the view axis's turn as a 2-vector, degrees; when the pans are written),
        then the other written parameters' offsets."""
        return tuple(self._vars)

    @property
    def scales(self) -> np.ndarray:
        """Each variable's typical size (degrees, input px, half-widths): (n,) float64."""
        return self._scale.copy()

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Each variable's allowed offset (low, high), (n,) float64 each: the pans' components
        within ± the turn's limit (:meth:`clip` keeps the turn itself inside it)."""
        lows, highs = [], []
        k = 0
        if self.model.pans:
            high = self.model.range_of("h_pan")[1]
            lows += [-high, -high]
            highs += [high, high]
            k = 2
        for name in self._vars[k:]:
            low, high = self.model.range_of(name)
            lows.append(low)
            highs.append(high)
        return np.array(lows, np.float64), np.array(highs, np.float64)

    def clip(self, x: np.ndarray) -> np.ndarray:
        """``x`` moved into the allowed ranges (the pans' turn scaled back to its limit,
        the others clipped)."""
        low, high = self.bounds
        out = np.clip(np.asarray(x, dtype=np.float64), low, high)
        if self.model.pans:
            limit = self.model.range_of("h_pan")[1]
            turn = math.hypot(out[0], out[1])
            if turn > limit:
                out[:2] *= limit / turn
        return out

    def correct(self, deviation: Deviation) -> Correction:
        """The per-car values for a car whose camera deviates by ``deviation`` (as the
        station measured it)."""
        return self.correction_at(*self.fit(deviation))

    def fit(self, deviation: Deviation) -> tuple[np.ndarray, float, float]:
        """The least-squares fit for a car whose camera deviates by ``deviation``: its
        variables (:attr:`variables`; before any range check) and the reference points'
        residual RMS and largest distance, RVM px."""

        rot, pos = deviated_pose(self.scene, deviation)
        uv, _ = self._camera.project_rays((self.points - pos) @ rot)
        target = self.nominal_px
        rays = isp_rays(self.platform, uv, self._size)

        def residual(x: np.ndarray) -> np.ndarray:
            if self._rotation_only:
                q = self._rotated_px(x, rays) - target
            else:
                q = self._rvm(self.params_at(x), uv) - target
            return np.nan_to_num(q, nan=1e4).ravel()

        fit = least_squares(residual, np.zeros(len(self._vars)), method="lm",
                            x_scale=self._scale)
        res = residual(fit.x).reshape(-1, 2)
        dist = np.hypot(res[:, 0], res[:, 1])
        return fit.x, float(np.sqrt(np.mean(dist ** 2))), float(dist.max())

    def correction_at(self, x: np.ndarray, rms: float = 0.0, worst: float = 0.0) -> Correction:
        """The correction of variables ``x`` (:attr:`variables`): offsets, the range check,
        the parameters clipped to the allowed ranges; ``rms``, ``worst``: the reference
        points' residuals to record, RVM px."""
        exceeded: list[str] = []
        clipped = np.array(x, dtype=np.float64)
        offsets: dict[str, float] = {}
        k = 0
        if self.model.pans:
            turn = math.hypot(x[0], x[1])
            offsets["h_pan"] = turn
            _, high = self.model.range_of("h_pan")
            if turn > high:
                exceeded.append(f"EOL range exceeded: pan {turn:.2f}° > {high:g}°")
                clipped[:2] *= high / turn
            k = 2
        for name in self._vars[k:]:
            low, high = self.model.range_of(name)
            value = float(x[k])
            offsets[name] = value
            unit = _UNITS[name]
            if value > high:
                exceeded.append(f"EOL range exceeded: {name} {value:+.3g}{unit} > {high:g}{unit}")
            elif value < low:
                exceeded.append(f"EOL range exceeded: {name} {value:+.3g}{unit} < {low:g}{unit}")
            clipped[k] = min(max(value, low), high)
            k += 1
        params = self.params_at(clipped)
        values = {n: float(getattr(params, n)) for n in self.model.params}
        return Correction(params, values, offsets, tuple(exceeded), rms, worst)
