"""FMVSS No. 111 test-site defaults (49 CFR 571.111, S5.5 / S14), each in one named place.

Several values could not be checked against the authoritative text when this module was
written (see the project's FMVSS facts sheet).  Each such value carries its confidence
(H/M/L) here and is a default of the scene file's ``test_site`` section, so a user with the
official text corrects it in the scene (or here) without touching any other code.

Coordinates follow the scene frame (:mod:`rvmsim.camera`): ``x`` lateral (+ toward the
driver's side), ``z`` behind the plane of the rearmost point of the bumper, metres.
"""

from __future__ import annotations

__all__ = [
    "OBJECT_HEIGHT_M",
    "OBJECT_DIAMETER_M",
    "STRIPE_WIDTH_M",
    "HORIZONTAL_STRIPE_TOP_M",
    "LOWER_PATCH_HEIGHT_M",
    "OBJECT_POSITIONS_M",
    "OBJECT_POSITION_REFERENCE",
    "VERTICAL_STRIPE_FACING",
]

#: Test object height: 0.8 m (32 in), confirmed; exact S14 figure ⚠️H.
OBJECT_HEIGHT_M = 0.80
#: Test object external diameter: 0.3 m (12 in), confirmed; exact S14 figure ⚠️H.
OBJECT_DIAMETER_M = 0.30
#: Width of the horizontal band (A–E) and of the vertical stripe (F, G): 150 mm. ⚠️M
STRIPE_WIDTH_M = 0.150
#: The A–E band sits at the top of the cylinder (its upper edge at the top). ⚠️M
HORIZONTAL_STRIPE_TOP_M = OBJECT_HEIGHT_M
#: Height of the lower portion of the F/G stripe that S5.5.1(a) / EC 1-1 look at. ⚠️M
LOWER_PATCH_HEIGHT_M = 0.150

#: Object positions (x lateral, z behind the bumper plane), metres.  ⚠️M for the whole table:
#: the row order (A–C far, D–E middle, F–G near) and the sides carrying A, D, F are the facts
#: sheet's best reading of Figure 5, not verified.
OBJECT_POSITIONS_M: dict[str, tuple[float, float]] = {
    "A": (-1.52, 6.10),
    "B": (0.00, 6.10),
    "C": (+1.52, 6.10),
    "D": (-1.52, 3.05),
    "E": (+1.52, 3.05),
    "F": (-1.52, 0.30),
    "G": (+1.52, 0.30),
}
#: Whether the distances above run to the cylinder centre or to its nearest surface. ⚠️L
#: ("centre" or "surface").
OBJECT_POSITION_REFERENCE = "centre"
#: Which way the F/G vertical stripe faces. ⚠️L.  "vehicle_centreline": toward x = 0 at the
#: object's own z; alternatives in the scene file are "vehicle" (toward −Z), "camera", or an
#: azimuth in degrees.
VERTICAL_STRIPE_FACING = "vehicle_centreline"
