"""What the per-car law judges a car by: its picture, as the end-of-line station has it.

A :class:`CarPicture` gives the car's EC values for any per-car ISP setting.  Two kinds:

- :class:`ImagePicture`: one fisheye label image (the station's: the test site's labels
  rendered at the measured pose, the body's read on the capture; or a car's own, true one).
- :class:`StationView`: a car's true fisheye label image seen as the station sees it, for
  ``rvmsim robustness --compensation`` and ``tune --robust --compensation``, which hold each
  car's true picture and the station's errors, not a capture.  The station's picture of the
  **site** is the site seen from the measured pose: the car's camera turned by the
  station's error ``E`` (camera frame; ``R_measured = R_true · E``).  Through a view turned
  by ``R_view`` that is the true picture through the view turned by ``E · R_view``
  (:func:`turned`; exact where the ISP's lens model is the camera's, and otherwise off by
  the lens models' difference over the small angle of ``E``: at 0.1° and vehicle A's
  tuned setting, under 0.01° (docs/compensation.md)).  Its picture of the **body** comes
  from the capture, whose error is the edge finder's: modelled the same way, as the body
  region turned by a small ``B`` (a pitch that moves the edge by δ₀ px at the image centre
  and a roll that tilts it by ±δ₁ px at the image's sides, δ drawn with the model's
  ``edge_sigma_px``; :func:`edge_turn`).  So the site's ECs are read through ``E · R_view``
  and the body's (:func:`body_ecs`) through ``B · R_view``, both on the true image.

Convention
----------
Parameters are for the full sensor; a picture rendered at a fraction of it scales them
(RAD and shifts: :meth:`rvmsim.isp.IspParams.for_input_scale`).  Values are (n, k) in the
criteria's :attr:`~rvmsim.criteria.Criteria.ids` order, NaN where not measured, at the RVM
image of record.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from .. import labels as L
from ..criteria import Criteria, ec_needs
from ..isp import IspParams, OutputSpec, view_angles, view_rotation
from ..pipeline import FisheyeLabels, ImageEvaluator, make_evaluator

__all__ = ["CarPicture", "ImagePicture", "StationView", "SplitEvaluator", "body_ecs", "turned",
           "edge_turn", "criteria_subset"]


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


def turned(params: IspParams, turn: np.ndarray | None) -> IspParams:
    """``params`` with the view turned by ``turn`` ((3, 3), camera frame, applied after the
    view's own rotation: ``turn · R_view``); ``params`` itself for None."""
    if turn is None:
        return params
    h_pan, v_pan, tilt = view_angles(turn @ view_rotation(params.h_pan, params.v_pan,
                                                         params.tilt), params.v_pan)
    return params.replace(h_pan=h_pan, v_pan=v_pan, tilt=tilt)


def edge_turn(offset_px: float, tilt_px: float, f_px: float, half_width_px: float
              ) -> np.ndarray | None:
    """The turn of the body region that models an edge found ``offset_px`` off at the image
    centre and tilted by ``tilt_px`` at the image's sides: ``Rz(tilt_px / half_width_px) ·
    Rx(offset_px / f_px)`` (radians; camera frame, x right, y down, z the optical axis), a
    turn about x moving the image centre by ``f_px`` px per radian, a roll about z moving a
    point ``half_width_px`` from the centre by that many px per radian.  None when both
    are 0."""
    if offset_px == 0.0 and tilt_px == 0.0:
        return None
    a, r = offset_px / f_px, tilt_px / half_width_px
    rx = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(a), -math.sin(a)],
                   [0.0, math.sin(a), math.cos(a)]])
    rz = np.array([[math.cos(r), -math.sin(r), 0.0], [math.sin(r), math.cos(r), 0.0],
                   [0.0, 0.0, 1.0]])
    return rz @ rx


class ImagePicture:
    """A car's picture as one fisheye label image, judged by ``evaluator``
    (:func:`rvmsim.pipeline.make_evaluator` of the image at the RVM image of record).

    Parameters
    ----------
    evaluator : ImageEvaluator
    input_scale : float
        The fraction of the sensor the image is at.
    """

    def __init__(self, evaluator: ImageEvaluator, input_scale: float = 1.0):
        self.evaluator = evaluator
        self.input_scale = input_scale

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
        return np.array([ev.values(self._at(p)) for p in params]).reshape(
            len(params), len(self.criteria.ids))


def criteria_subset(criteria: Criteria, keep: np.ndarray) -> Criteria:
    """``criteria`` with only the ECs ``keep`` ((k,) bool) selected."""
    ecs = tuple(ec for ec, k in zip(criteria.ecs, keep) if k)
    return dataclasses.replace(criteria, ecs=ecs, items={ec.id: criteria.items[ec.id]
                                                         for ec in ecs})


class SplitEvaluator:
    """One fisheye label image's ECs as two evaluators, the site's and the body's
    (:func:`body_ecs`), so that each part can be read through its own view at the cost of
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
        self._parts = [(mask, make_evaluator(image, record, criteria_subset(criteria, mask)))
                       for mask in (~self.body, self.body) if mask.any()]

    def values(self, site: IspParams, body: IspParams | None = None) -> np.ndarray:
        """The values, (k,): the site's ECs with ``site``, the body's with ``body``
        (default ``site``)."""
        out = np.full(len(self.criteria.ids), np.nan)
        for mask, ev in self._parts:
            out[mask] = ev.values(body if mask is self.body and body is not None else site)
        return out


class StationView:
    """A car's true picture seen as the station sees it (the module docstring): the site's
    ECs through the view turned by ``site_turn``, the body's through ``body_turn``.

    Parameters
    ----------
    evaluator : SplitEvaluator
        Of the car's true fisheye label image (at the station's load state).
    site_turn, body_turn : (3, 3) float, optional
        ``E`` and ``B`` of the module docstring (None: no error).
    input_scale : float
    """

    def __init__(self, evaluator: SplitEvaluator, site_turn: np.ndarray | None,
                 body_turn: np.ndarray | None, input_scale: float = 1.0):
        self.evaluator = evaluator
        self.site_turn = site_turn
        self.body_turn = body_turn
        self.input_scale = input_scale

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
        return np.array([ev.values(self._at(turned(p, self.site_turn)),
                                   self._at(turned(p, self.body_turn))) for p in params]
                        ).reshape(len(params), len(self.criteria.ids))
