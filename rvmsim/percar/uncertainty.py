"""The station's uncertainty of each EC: how far a car's true value may lie from the value
the station judged.

- An EC that reads the **test site** inherits the pose error: the station renders the site
  at the pose it measured, off by σ per angle (the model's ``angle_sigma_deg``).  The EC's
  sensitivity to each of the camera's three angles is read on the image of the camera
  turned by :data:`PROBE_DEG` about its x, y and z axes (:class:`rvmsim.percar.TurnWarp`);
  ``σ_EC = sqrt(Σ (ΔEC/δ · σ)²)``.
- An EC that reads only the **body** (:func:`rvmsim.percar.body_ecs`) is measured on the
  capture and inherits the edge finder's error instead (``edge_sigma_px``): read with the
  body's edge moved by :data:`PROBE_PX` px, and tilted by as much at the image's sides
  (:class:`rvmsim.percar.EdgeWarp`).

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
from ..camera import FisheyeCamera
from .picture import EdgeWarp, ImagePicture, TurnWarp, body_ecs

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


def ec_uncertainty(picture: ImagePicture, platform: IspParams, model: CompensationModel,
                   camera: FisheyeCamera) -> np.ndarray:
    """Each EC's 1 σ (its own unit) at the station, read on the nominal car's ``picture``
    at the ``platform`` setting (the module docstring; 6 EC evaluations).

    Parameters
    ----------
    picture : ImagePicture
        The nominal car (its true picture).
    platform : IspParams
        Full sensor.
    model : CompensationModel
        Its station's σ.
    camera : FisheyeCamera
        The picture's camera (its lens at the picture's size).

    Returns
    -------
    (k,) float64
        0 where the EC is not measured at the platform setting or the station's σ is 0.
    """
    s = picture.input_scale
    probes = [picture] + [picture.warped(TurnWarp(camera, axis_turn(a, PROBE_DEG)), None)
                          for a in range(3)]
    probes += [picture.warped(None, EdgeWarp(d0 * s, d1 * s, camera.cx, camera.width / 2.0))
               for d0, d1 in ((PROBE_PX, 0.0), (0.0, PROBE_PX))]
    v = np.array([pic.values([platform])[0] for pic in probes])
    with np.errstate(invalid="ignore"):
        slopes = np.nan_to_num(np.abs(v[1:] - v[0]), nan=0.0)
    site = np.sqrt(np.sum((slopes[:3] / PROBE_DEG * model.angle_sigma_deg) ** 2, axis=0))
    body = np.sqrt(np.sum((slopes[3:] / PROBE_PX * model.edge_sigma_px) ** 2, axis=0))
    return np.where(body_ecs(picture.criteria), body, site)
