"""The laws by name (a compensation model's ``law:``), and building one for a platform
setting."""

from __future__ import annotations

from ..compensation import CompensationLaw, CompensationModel
from ..criteria import Criteria
from ..errors import CompensationError
from ..isp import IspParams, OutputSpec
from ..scene import Scene
from .law import EcSolveLaw, PerCarLaw, ReferencePointsLaw
from ..camera import FisheyeCamera
from .picture import ImagePicture
from .uncertainty import ec_uncertainty

__all__ = ["LAWS", "make_law"]

#: ``law:`` name → the law's class.
LAWS: dict[str, type[PerCarLaw]] = {"ec-solve": EcSolveLaw,
                                    "reference-points": ReferencePointsLaw}


def make_law(scene: Scene, platform: IspParams, output: OutputSpec, model: CompensationModel,
             criteria: Criteria, nominal: ImagePicture | None = None,
             camera: FisheyeCamera | None = None) -> PerCarLaw:
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

    Raises
    ------
    CompensationError
        An unknown law, or too few reference points for the start.
    """
    cls = LAWS.get(model.law)
    if cls is None:
        raise CompensationError(model.source, "law", f"unknown law {model.law!r} (known: "
                                f"{', '.join(LAWS)})")
    reference = CompensationLaw(scene, platform, output, model)
    law = cls(reference, criteria, output)
    if nominal is not None:
        cam = camera or scene.fisheye_camera()
        if camera is None and nominal.input_scale != 1.0:
            cam = cam.scaled(nominal.input_scale)
        law.uncertainty, values = ec_uncertainty(nominal, platform, model, cam)
        law.target = float(law.scale.least(values, law.uncertainty)[0])
    return law
