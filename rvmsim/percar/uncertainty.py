"""The station's uncertainty of each EC: how far a car's true value may lie from the value
the station judged.

- An EC that reads the **test site** inherits the pose error: the station renders the site
  at the pose it measured, off by σ per angle (the model's ``angle_sigma_deg``).  A turn of
  the camera by δ shows the site as the view turned by δ does (:func:`rvmsim.percar.turned`),
  so the EC's sensitivity to each of the camera's three angles is read by turning the view
  by :data:`PROBE_DEG` about its x, y and z axes; ``σ_EC = sqrt(Σ (ΔEC/δ · σ)²)``.
- An EC that reads only the **body** (:func:`rvmsim.percar.body_ecs`) is measured on the
  capture and inherits the edge finder's error instead (``edge_sigma_px``): the body
  region moved by :data:`PROBE_PX` px at the image centre and tilted by as much at its
  sides (:func:`rvmsim.percar.edge_turn`).

Each sensitivity is one-sided (the change from the platform setting to the probe: a value
such as |t_l − t_r| that sits at its kink then still shows its slope), read once per
platform setting on the nominal car.  The position error's parallax is not included: at
1 mm it moves the test site by under half the angle error's shift on the bundled vehicles
(docs/compensation.md).
"""

from __future__ import annotations

import math

import numpy as np

from ..compensation import CompensationModel
from ..isp import IspParams
from .picture import CarPicture, body_ecs, edge_turn, turned

__all__ = ["ec_uncertainty", "PROBE_DEG", "PROBE_PX", "axis_turn"]

#: The camera turn the site ECs' sensitivity is read with, degrees.
PROBE_DEG = 0.25
#: The edge move the body ECs' sensitivity is read with, fisheye px.
PROBE_PX = 2.0


def axis_turn(axis: int, degrees: float) -> np.ndarray:
    """A turn by ``degrees`` about the camera's x (0), y (1) or z (2) axis, (3, 3)."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.eye(3)
    r[i, i] = r[j, j] = c
    r[i, j], r[j, i] = -s, s
    return r


def ec_uncertainty(picture: CarPicture, platform: IspParams, model: CompensationModel,
                   f_px: float, half_width_px: float) -> np.ndarray:
    """Each EC's 1 σ (its own unit) at the station, read on the nominal car's ``picture``
    at the ``platform`` setting (the module docstring; 6 EC evaluations).

    Parameters
    ----------
    picture : CarPicture
        The nominal car (its true picture).
    platform : IspParams
        Full sensor.
    model : CompensationModel
        Its station's σ.
    f_px, half_width_px : float
        The camera's focal length (px/rad) and half its image width (px), full sensor:
        the edge's px to a turn (:func:`rvmsim.percar.edge_turn`).

    Returns
    -------
    (k,) float64
        0 where the EC is not measured at the platform setting or the station's σ is 0.
    """
    probes = [platform] + [turned(platform, axis_turn(a, PROBE_DEG)) for a in range(3)]
    probes += [turned(platform, edge_turn(PROBE_PX, 0.0, f_px, half_width_px)),
               turned(platform, edge_turn(0.0, PROBE_PX, f_px, half_width_px))]
    v = picture.values(probes)
    with np.errstate(invalid="ignore"):
        slopes = np.nan_to_num(np.abs(v[1:] - v[0]), nan=0.0)
    site = np.sqrt(np.sum((slopes[:3] / PROBE_DEG * model.angle_sigma_deg) ** 2, axis=0))
    body = np.sqrt(np.sum((slopes[3:] / PROBE_PX * model.edge_sigma_px) ** 2, axis=0))
    return np.where(body_ecs(picture.criteria), body, site)
