"""The station's uncertainty of each EC: how far a car's true value may lie from the value
the station judged.

- An EC that reads the **test site** inherits the pose error: the station renders the site
  at the pose it measured, off by σ per angle (the model's ``angle_sigma_deg``).
- An EC that reads only the **body** (:func:`rvmsim.percar.body_ecs`) is measured on the
  capture and inherits the edge finder's error instead (``edge_sigma_px``: the found edge's
  offset and tilt, :class:`rvmsim.percar.EdgeWarp`).

Each σ is read on the nominal car at the platform setting by drawing the station's errors
:data:`DRAWS` times (a fixed seed: the same setting, the same σ): the site's ECs on the
image of the camera turned by the drawn pose error (:class:`rvmsim.percar.TurnWarp`), the
body's with the drawn edge error, and σ is the root mean square of the change.  Drawing
rather than differentiating keeps what the label images' pixels do to a value: a bumper
height averaged over a few columns moves in quarter pixels, and a small move of the edge
changes EC 2-3 by up to 2 px at the image's sides where a slope read from one probe says
0.3 px.  The position error's parallax is not included (its move of the test site at 1 mm:
docs/compensation.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..compensation import CompensationModel
from ..isp import InputWarp, IspParams
from ..camera import FisheyeCamera
from .picture import EdgeWarp, GridWarp, ImagePicture, TurnWarp

__all__ = ["ec_uncertainty", "station_draws", "StationDraws", "DRAWS", "axis_turn"]

#: The station's errors drawn per EC uncertainty (each draw one EC evaluation).
DRAWS = 12
_SEED = 0x51D


def axis_turn(axis: int, degrees: float) -> np.ndarray:
    """A turn by ``degrees`` about the camera's x (0), y (1) or z (2) axis, (3, 3)."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.eye(3)
    r[i, i] = r[j, j] = c
    r[i, j], r[j, i] = -s, s
    return r


@dataclass(frozen=True)
class StationDraws:
    """The station's errors :func:`ec_uncertainty` draws, as the warps the nominal picture
    is read through: one ``(site, body)`` pair per draw (None: that error is 0).  The seed
    is fixed, so the draws are the same for every platform setting: a caller that judges
    many settings of one car (a tuning run) draws them once."""

    warps: tuple[tuple[InputWarp | None, InputWarp | None], ...]
    draws: int


def station_draws(model: CompensationModel, camera: FisheyeCamera, input_scale: float = 1.0,
                  draws: int = DRAWS) -> StationDraws:
    """The station's errors for :func:`ec_uncertainty` (``draws`` of them; none when both
    of the model's σ are 0).

    Parameters
    ----------
    model : CompensationModel
        Its station's σ.
    camera : FisheyeCamera
        The picture's camera (its lens at the picture's size).
    input_scale : float
        The fraction of the sensor the picture is at (the edge error is full-sensor px).
    draws : int
    """
    rng = np.random.default_rng(_SEED)
    s = input_scale
    warps: list[tuple[InputWarp | None, InputWarp | None]] = []
    for _ in range(draws):
        a = rng.standard_normal(3) * model.angle_sigma_deg
        e = rng.standard_normal(2) * model.edge_sigma_px
        turn = axis_turn(2, a[2]) @ axis_turn(1, a[1]) @ axis_turn(0, a[0])
        site = None if model.angle_sigma_deg == 0 else GridWarp(
            TurnWarp(camera, turn), (camera.width, camera.height))
        body = None if model.edge_sigma_px == 0 else EdgeWarp(e[0] * s, e[1] * s, camera.cx,
                                                             camera.width / 2.0)
        if site is None and body is None:
            break
        warps.append((site, body))
    return StationDraws(tuple(warps), draws)


def ec_uncertainty(picture: ImagePicture, platform: IspParams, model: CompensationModel,
                   camera: FisheyeCamera, draws: int = DRAWS, *,
                   station: StationDraws | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each EC's 1 σ (its own unit) at the station, read on the nominal car's ``picture``
    at the ``platform`` setting (the module docstring; ``draws`` + 1 EC evaluations), and
    its values there.

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
    draws : int
    station : StationDraws, optional
        The draws, when already made (:func:`station_draws` of ``model``, ``camera``, the
        picture's input scale and ``draws``: the same values).

    Returns
    -------
    sigma : (k,) float64
        0 where the EC is not measured at the platform setting or the station's σ is 0.
    nominal : (k,) float64
        The nominal car's values at the platform setting.
    """
    if station is None:
        station = station_draws(model, camera, picture.input_scale, draws)
    base = picture.values([platform])[0]
    sq = np.zeros(len(base))
    for site, body in station.warps:
        v = picture.warped(site, body).values([platform])[0]
        with np.errstate(invalid="ignore"):
            sq += np.nan_to_num(v - base, nan=0.0) ** 2
    return np.sqrt(sq / station.draws), base
