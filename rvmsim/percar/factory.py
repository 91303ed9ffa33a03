"""The laws by name (a compensation model's ``law:``), and building one for a platform
setting."""

from __future__ import annotations

from typing import Callable, TypeVar

from ..compensation import CompensationLaw, CompensationModel
from ..criteria import Criteria
from ..errors import CompensationError
from ..isp import IspParams, OutputSpec
from ..scene import Scene
from .law import EcSolveLaw, PerCarLaw, ReferencePointsLaw
from ..camera import FisheyeCamera
from .picture import ImagePicture
from .uncertainty import StationDraws, ec_uncertainty, station_draws

__all__ = ["LAWS", "make_law", "nominal_draws", "register_law", "check_law"]

#: ``law:`` name → the law's class, in registration order (the built-ins: ``ec-solve``, the
#: default, and ``reference-points``).  :func:`register_law` adds one (docs/extending.md).
LAWS: dict[str, type[PerCarLaw]] = {}

_L = TypeVar("_L", bound=type[PerCarLaw])


def register_law(name: str) -> Callable[[_L], _L]:
    """Class decorator: add a :class:`~rvmsim.percar.PerCarLaw` subclass to :data:`LAWS`
    under ``name`` (new), which a compensation model's ``law:`` then names.  The class is
    built as ``cls(reference, criteria, output)`` (:func:`make_law`) and answers
    ``solve(measured, picture)`` and ``accepts(solution)``.

    Raises
    ------
    ValueError
        ``name`` is empty or taken.
    """
    def add(cls: _L) -> _L:
        if not name or name in LAWS:
            raise ValueError(f"law name {name!r} is empty or taken")
        LAWS[name] = cls
        return cls
    return add


register_law("ec-solve")(EcSolveLaw)
register_law("reference-points")(ReferencePointsLaw)


def check_law(model: CompensationModel) -> None:
    """Refuse a compensation model whose ``law`` is not registered.

    Raises
    ------
    CompensationError
        One line naming the model's file and the key ``law``.
    """
    if model.law not in LAWS:
        raise CompensationError(model.source, model.key("law"), f"unknown law {model.law!r} "
                                f"(known: {', '.join(LAWS)})")


def make_law(scene: Scene, platform: IspParams, output: OutputSpec, model: CompensationModel,
             criteria: Criteria, nominal: ImagePicture | None = None,
             camera: FisheyeCamera | None = None, *,
             station: StationDraws | None = None) -> PerCarLaw:
    """The model's law for one platform setting.

    Parameters
    ----------
    scene : Scene
        The car as designed (full sensor).
    platform : IspParams
        Full sensor.
    output : OutputSpec
        The RVM image of record (what the ECs are judged at and the reference points are
        held on).
    model : CompensationModel
    criteria : Criteria
    nominal : ImagePicture, optional
        The nominal car's picture: the station's uncertainty of each EC is read there
        (:func:`rvmsim.percar.ec_uncertainty`), and the least margin a car is restored to
        (``stop: nominal``); without it no car is called marginal and the search always
        spends its budget.
    camera : FisheyeCamera, optional
        ``nominal``'s camera (default: the scene's, at the picture's scale).
    station : StationDraws, optional
        The station's errors the uncertainty is read with, when already drawn
        (:func:`nominal_draws` of the same scene, model, picture and camera: the same law).

    Raises
    ------
    CompensationError
        An unknown law, or too few reference points for the start.
    """
    check_law(model)
    cls = LAWS[model.law]
    reference = CompensationLaw(scene, platform, output, model)
    law = cls(reference, criteria, output)
    if nominal is not None:
        cam = _camera_of(scene, nominal, camera)
        law.uncertainty, values = ec_uncertainty(nominal, platform, model, cam,
                                                 station=station)
        law.target = float(law.scale.least(values, law.uncertainty)[0])
    return law


def nominal_draws(scene: Scene, model: CompensationModel, nominal: ImagePicture,
                  camera: FisheyeCamera | None = None) -> StationDraws:
    """The station's errors :func:`make_law` reads the EC uncertainty on ``nominal`` with
    (:func:`rvmsim.percar.station_draws`), drawn once for every platform setting of the
    car (``camera``: as :func:`make_law`'s)."""
    return station_draws(model, _camera_of(scene, nominal, camera), nominal.input_scale)


def _camera_of(scene: Scene, nominal: ImagePicture, camera: FisheyeCamera | None
               ) -> FisheyeCamera:
    """``nominal``'s camera: ``camera``, or the scene's at the picture's scale."""
    if camera is not None:
        return camera
    cam = scene.fisheye_camera()
    return cam if nominal.input_scale == 1.0 else cam.scaled(nominal.input_scale)
