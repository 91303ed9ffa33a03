"""What the per-car law judges a car by: its picture, as the end-of-line station has it.

A :class:`CarPicture` gives the car's EC values for any per-car ISP setting.  Two kinds:

- :class:`ImagePicture`: one fisheye label image (the station's own: the test site's labels
  rendered at the measured pose, the body's read on the capture; or a car's true one).
- :class:`StationView`: a car's true fisheye label image seen as the station sees it, for
  ``rvmsim robustness --compensation`` and ``tune --robust --compensation``, which hold each
  car's true picture and the station's errors, not a capture.  The station's picture of the
  **site** is the site seen from the measured pose, the car's camera turned by the station's
  error ``E`` (camera frame; ``R_measured = R_true · E``): at fisheye pixel q it shows what
  the true image shows at ``π(E · π⁻¹(q))`` (π the real lens; :class:`TurnWarp`), exactly
  for a turn.  Its picture of the **body** comes from the capture, whose body edge the edge
  finder places off by δ(u) = δ₀ + δ₁·(u − c_x)/(W/2) rows (:class:`EdgeWarp`, δ drawn with
  the model's ``edge_sigma_px``).  So the site's ECs read the true image through the ISP's
  map followed by the one warp, the body's (:func:`body_ecs`) followed by the other
  (:meth:`rvmsim.isp.MapNodes.warped`): no image is made for either.  The station's
  position error is not modelled in the picture (its parallax on the site: at 1 mm, a few
  tenths of a pixel; docs/compensation.md).

Convention
----------
Parameters are for the full sensor; a picture rendered at a fraction of it scales them
(RAD and shifts: :meth:`rvmsim.isp.IspParams.for_input_scale`).  Values are (n, k) in the
criteria's :attr:`~rvmsim.criteria.Criteria.ids` order, NaN where not measured, at the RVM
image of record.  Fisheye positions in px, pixel centres at integers.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera
from ..criteria import Criteria, ec_needs
from ..pipeline import CandidateEvaluator
from ..isp import InputWarp, IspParams, OutputSpec
from ..pipeline import FisheyeLabels, make_evaluator

__all__ = ["CarPicture", "ImagePicture", "StationView", "SplitEvaluator", "body_ecs",
           "criteria_subset", "TurnWarp", "GridWarp", "EdgeWarp", "WARP_GRID_PX"]


class CarPicture(Protocol):
    """A car's picture as the law judges it (see the module docstring)."""

    @property
    def criteria(self) -> Criteria: ...

    @property
    def fisheye(self) -> np.ndarray:
        """The fisheye label image the sub-solves read the outline of objects from."""
        ...

    @property
    def input_scale(self) -> float:
        """The fraction of the sensor the picture is at."""
        ...

    def values(self, params: Sequence[IspParams]) -> np.ndarray:
        """The EC values of each full-sensor parameter set, (n, k)."""
        ...


def body_ecs(criteria: Criteria) -> np.ndarray:
    """(k,) bool: the ECs that read only body-fixed parts (bumper, garnish, trunk, the
    vehicle's extra parts): those the station measures on the capture.  An EC reads what its
    label groups and :func:`rvmsim.criteria.ec_needs` name."""
    body = set(L.BODY_LABELS)
    out = []
    for ec in criteria.ecs:
        labels = {x for g in ec.groups for x in g.labels} | {
            x for ids in ec_needs(ec) for x in ids}
        out.append(bool(labels) and labels <= body)
    return np.array(out, bool)


def criteria_subset(criteria: Criteria, keep: np.ndarray) -> Criteria:
    """``criteria`` with only the ECs ``keep`` ((k,) bool) selected."""
    ecs = tuple(ec for ec, k in zip(criteria.ecs, keep) if k)
    return dataclasses.replace(criteria, ecs=ecs, items={ec.id: criteria.items[ec.id]
                                                         for ec in ecs})


@dataclass(frozen=True)
class TurnWarp:
    """The fisheye image of ``camera`` turned by ``turn`` ((3, 3), camera frame: the turned
    camera's ray d is the camera's ``turn · d``), read from the unturned camera's image:
    ``q → π(turn · π⁻¹(q))``.  Rays the lens does not see are left where they are."""

    camera: FisheyeCamera
    turn: np.ndarray

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        flat = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        rays, inside = self.camera.pixel_rays(flat)
        moved, ok = self.camera.project_rays(rays @ self.turn.T)
        keep = inside & ok & np.isfinite(moved).all(axis=1)
        return np.where(keep[:, None], moved, flat).reshape(np.shape(xy))


#: Fisheye px between the nodes of a :class:`GridWarp`.
WARP_GRID_PX = 8


class GridWarp:
    """A smooth warp sampled every ``step`` px over the fisheye image once, then read by
    bilinear interpolation of the sampled field: the same map to within the field's
    curvature over a cell (for the station's turns of a few tenths of a degree,
    under 0.001 px inside the lens's field; a cell straddling the field's edge, where
    :class:`TurnWarp` leaves positions unmoved, mixes the two).  Positions outside the image
    are read from its border cells."""

    def __init__(self, warp: InputWarp, size: tuple[int, int], step: int = WARP_GRID_PX):
        w, h = size
        self.step = step
        xs = np.arange(0, w + step, step, dtype=np.float64)
        ys = np.arange(0, h + step, step, dtype=np.float64)
        gx, gy = np.meshgrid(xs, ys)
        self.field = np.ascontiguousarray(warp(np.stack([gx, gy], axis=-1)), dtype=np.float64)

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        # bilinear in float64 (cv2.remap's fixed-point weights would read the field at
        # 1/32 of a cell: a quarter pixel at 8 px cells)
        pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2) / self.step
        rows, cols = self.field.shape[:2]
        gx = np.clip(pts[:, 0], 0.0, cols - 1.000001)
        gy = np.clip(pts[:, 1], 0.0, rows - 1.000001)
        i, j = gy.astype(np.intp), gx.astype(np.intp)
        fy, fx = (gy - i)[:, None], (gx - j)[:, None]
        # the four corners by flat index (one take each: 2.4x faster than f[i, j])
        f = self.field.reshape(-1, 2)
        k = i * cols + j
        top_left, top_right = f.take(k, axis=0), f.take(k + 1, axis=0)
        bottom_left, bottom_right = f.take(k + cols, axis=0), f.take(k + cols + 1, axis=0)
        out = ((top_left * (1 - fx) + top_right * fx) * (1 - fy)
               + (bottom_left * (1 - fx) + bottom_right * fx) * fy)
        return out.reshape(np.shape(xy))


@dataclass(frozen=True)
class EdgeWarp:
    """An edge found ``offset_px`` rows low at the image's centre column ``cx`` and tilted
    by ``tilt_px`` rows at ``half_width_px`` from it: ``(u, v) → (u, v − δ(u))``,
    ``δ(u) = offset_px + tilt_px · (u − cx) / half_width_px`` (the region below the edge
    then shows δ rows lower)."""

    offset_px: float
    tilt_px: float
    cx: float
    half_width_px: float

    def __call__(self, xy: np.ndarray) -> np.ndarray:
        delta = self.offset_px + self.tilt_px * (xy[..., 0] - self.cx) / self.half_width_px
        return np.stack([xy[..., 0], xy[..., 1] - delta], axis=-1)


class SplitEvaluator:
    """One fisheye label image's ECs as two windowed evaluators, the site's and the body's
    (:func:`body_ecs`), so that each part can be read through its own warp at the cost of
    one evaluation of all of them.

    Parameters
    ----------
    image : FisheyeLabels
    record : OutputSpec
        The RVM image of record (what the ECs are measured at).
    criteria : Criteria
    """

    def __init__(self, image: FisheyeLabels, record: OutputSpec, criteria: Criteria):
        self.criteria = criteria
        self.body = body_ecs(criteria)
        self.fisheye = np.asarray(image.labels)
        self._parts: list[tuple[np.ndarray, CandidateEvaluator]] = []
        for mask in (~self.body, self.body):
            if mask.any():
                ev = make_evaluator(image, record, criteria_subset(criteria, mask), record=record)
                assert isinstance(ev, CandidateEvaluator)  # one image at its size of record
                self._parts.append((mask, ev))

    def values(self, params: IspParams, site: InputWarp | None = None,
               body: InputWarp | None = None) -> np.ndarray:
        """The values of ``params``, (k,): the site's ECs read through ``site``, the body's
        through ``body`` (None: the image as it is)."""
        out = np.full(len(self.criteria.ids), np.nan)
        # both parts read the same image at the same size: one map for the two
        nodes = self._parts[0][1].map_nodes(params) if self._parts else None
        for mask, ev in self._parts:
            out[mask] = ev.values(params, body if mask is self.body else site, nodes)
        return out


class ImagePicture:
    """A car's picture as one fisheye label image (the station's picture, or a car's true
    one), read through optional warps (``site`` for the site's ECs, ``body`` for the
    body's; :class:`SplitEvaluator`).

    Parameters
    ----------
    evaluator : SplitEvaluator
    input_scale : float
        The fraction of the sensor the image is at.
    site, body : InputWarp, optional
    """

    def __init__(self, evaluator: SplitEvaluator, input_scale: float = 1.0,
                 site: InputWarp | None = None, body: InputWarp | None = None):
        self.evaluator = evaluator
        self.input_scale = input_scale
        self.site = site
        self.body = body

    @property
    def criteria(self) -> Criteria:
        return self.evaluator.criteria

    @property
    def fisheye(self) -> np.ndarray:
        return self.evaluator.fisheye

    def _at(self, params: IspParams) -> IspParams:
        return params if self.input_scale == 1.0 else params.for_input_scale(self.input_scale)

    def values(self, params: Sequence[IspParams]) -> np.ndarray:
        ev = self.evaluator
        return np.array([ev.values(self._at(p), self.site, self.body) for p in params]
                        ).reshape(len(params), len(self.criteria.ids))

    def warped(self, site: InputWarp | None, body: InputWarp | None) -> ImagePicture:
        """The same image read through other warps."""
        return ImagePicture(self.evaluator, self.input_scale, site, body)


class StationView(ImagePicture):
    """A car's true picture seen as the station sees it (the module docstring): built from
    the station's errors.

    Parameters
    ----------
    evaluator : SplitEvaluator
        Of the car's true fisheye label image at the station's load state.
    camera : FisheyeCamera
        The image's camera (its lens at the image's size).
    site_turn : (3, 3) float, optional
        ``E``: the measured camera's rotation relative to the true one, camera frame (None:
        none).
    edge_px : (float, float)
        The edge finder's offset and tilt, full-sensor px.
    input_scale : float
    """

    def __init__(self, evaluator: SplitEvaluator, camera: FisheyeCamera,
                 site_turn: np.ndarray | None, edge_px: tuple[float, float] = (0.0, 0.0),
                 input_scale: float = 1.0):
        site = None if site_turn is None else GridWarp(
            TurnWarp(camera, np.asarray(site_turn)), (camera.width, camera.height))
        s = input_scale
        body = None if edge_px == (0.0, 0.0) else EdgeWarp(
            edge_px[0] * s, edge_px[1] * s, camera.cx, camera.width / 2.0)
        super().__init__(evaluator, input_scale, site, body)
