"""FMVSS No. 111 test-site defaults (49 CFR 571.111, S5.5 / S14), each in one named place.

Several values could not be checked against the authoritative text when this module was
written (see the project's FMVSS facts sheet).  Each such value carries its confidence
(H/M/L) here and is a default of the scene file's ``test_site`` section, so a user with the
official text corrects it in the scene (or here) without touching any other code.

Coordinates follow the scene frame (:mod:`rvmsim.camera`): ``x`` lateral (+ toward the
driver's side), ``z`` behind the plane of the rearmost point of the bumper, metres.
"""

from __future__ import annotations

import functools
from typing import Any

from .sitedefs import bundled_site

__all__ = [
    "SITE_VALUE_NAMES",
    "site_values",
    "OBJECT_HEIGHT_M",
    "OBJECT_DIAMETER_M",
    "STRIPE_WIDTH_M",
    "HORIZONTAL_STRIPE_TOP_M",
    "LOWER_PATCH_HEIGHT_M",
    "OBJECT_POSITIONS_M",
    "OBJECT_POSITION_REFERENCE",
    "VERTICAL_STRIPE_FACING",
    "EYE_TO_DISPLAY_MM",
    "DISPLAY_WIDTH_MM",
    "DISPLAY_HEIGHT_MM",
    "DISPLAY_RESOLUTION_PX",
    "DISPLAY_VIEWING_ANGLE_DEG",
    "IMAGE_SIZE_MEAN_ARCMIN",
    "IMAGE_SIZE_MIN_ARCMIN",
]

#: The values read from the bundled site file (``rvmsim/regulations/fmvss111/site.yaml``: the one
#: place to correct them; its ⚠ marks are the confidence of each value), by name.  They are
#: read on first use (:func:`site_values`), not when this module is imported:
#:
#: - ``OBJECT_HEIGHT_M``: test object height, 0.8 m (32 in), confirmed; exact S14 figure ⚠️H;
#: - ``OBJECT_DIAMETER_M``: external diameter, 0.3 m (12 in), confirmed; exact figure ⚠️H;
#: - ``STRIPE_WIDTH_M``: the horizontal band (A–E) and the vertical stripe (F, G), 150 mm ⚠️M;
#: - ``HORIZONTAL_STRIPE_TOP_M``: the A–E band sits at the top of the cylinder ⚠️M;
#: - ``LOWER_PATCH_HEIGHT_M``: the lower portion of the F/G stripe that S5.5.1(a) / EC 1-1
#:   look at ⚠️M;
#: - ``OBJECT_POSITIONS_M``: object positions (x lateral, z behind the bumper plane), metres.
#:   ⚠️M for the whole table: the row order (A–C far, D–E middle, F–G near) and the sides
#:   carrying A, D, F are the facts sheet's best reading of Figure 5, not verified;
#: - ``OBJECT_POSITION_REFERENCE``: whether those distances run to the cylinder centre or to
#:   its nearest surface ("centre" or "surface") ⚠️L.
SITE_VALUE_NAMES = ("OBJECT_HEIGHT_M", "OBJECT_DIAMETER_M", "STRIPE_WIDTH_M",
                    "HORIZONTAL_STRIPE_TOP_M", "LOWER_PATCH_HEIGHT_M", "OBJECT_POSITIONS_M",
                    "OBJECT_POSITION_REFERENCE")


@functools.cache
def site_values() -> dict[str, Any]:
    """The site-file values above (:data:`SITE_VALUE_NAMES`), read once per process."""
    site = bundled_site("fmvss111")
    rows = {row.name: row for row in site.rows}
    height = rows["far"].height
    return {
        "OBJECT_HEIGHT_M": height,
        "OBJECT_DIAMETER_M": rows["far"].diameter,
        "STRIPE_WIDTH_M": rows["far"].marking.top_band,
        "HORIZONTAL_STRIPE_TOP_M": height,
        "LOWER_PATCH_HEIGHT_M": rows["near"].marking.lower_patch,
        "OBJECT_POSITIONS_M": {name: (x, row.z) for row in site.rows
                               for name, x in zip(row.names or (), row.lateral(0.0))},
        "OBJECT_POSITION_REFERENCE": site.position_reference,
    }


def __getattr__(name: str) -> Any:
    """The site-file values by their constant names (``fmvss111.OBJECT_HEIGHT_M``)."""
    if name in SITE_VALUE_NAMES:
        return site_values()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: Which way the F/G vertical stripe faces. ⚠️L.  "vehicle_centreline": toward x = 0 at the
#: object's own z; alternatives in the scene file are "vehicle" (toward −Z), "camera", or an
#: azimuth in degrees.
VERTICAL_STRIPE_FACING = "vehicle_centreline"

# ---------------------------------------------------------------------------- the display
# S5.5.2 judges the image on the display, seen from the driver's eye point.  The defaults of
# the scene's (or criteria file's) ``display:`` section (:class:`rvmsim.scene.Display`).
#: Distance from the driver's eye point to the display, mm.  ⚠️L: the facts sheet's worked
#: example (0.70 m), not a value of the regulation (S14 derives the eye point from the seat's
#: H-point; the offsets were not retrieved).  Set the vehicle's own figure in ``display:``.
EYE_TO_DISPLAY_MM = 700.0
#: Active area of the display, mm: a 7-inch 800 × 480 panel (assumed typical; not from the
#: regulation, which sets no display size).
DISPLAY_WIDTH_MM = 154.08
DISPLAY_HEIGHT_MM = 85.92
#: Display resolution (width, height), px (the same assumed 7-inch panel).
DISPLAY_RESOLUTION_PX = (800, 480)
#: Angle between the eye's line of sight and the display's normal, in the horizontal plane,
#: degrees: 0 = square to the eye (assumed).
DISPLAY_VIEWING_ANGLE_DEG = 0.0
#: S5.5.2: the visual angle of the horizontal width of A, B and C averages at least 5′,
#: each at least 3′ (arc-minutes).  ⚠️H
IMAGE_SIZE_MEAN_ARCMIN = 5.0
IMAGE_SIZE_MIN_ARCMIN = 3.0
