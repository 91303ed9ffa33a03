"""The display the driver sees the RVM image on: a scene's (or criteria file's) ``display``
section.

FMVSS No. 111 S5.5.2 judges the image *on the display*, from the driver's eye point, so the
image-size EC (``1-6``) needs the display's size, resolution and distance.  Every key is
optional; the defaults are named in :mod:`rvmsim.scene.fmvss111` (one place to correct)::

    display:
      width_mm: 154.08          # active area, mm (> 0)
      height_mm: 85.92
      resolution_px: [800, 480] # width, height, px (> 0)
      eye_distance_mm: 700      # driver's eye point → display centre, mm (> 0)
      viewing_angle_deg: 0      # line of sight vs the display normal, horizontal, [0, 89]
      rvm_image_px: [1280, 720] # the RVM image of record: what the ISP sends the display

``rvm_image_px`` is the size every pixel-unit EC (2-3, 3-1: "≤ 5 px") is judged at, whatever
size a search measures at (:mod:`rvmsim.criteria.record`): a pass means a pass on the image
the car shows.  It is the ISP's output, not the panel's resolution (``resolution_px``).

Convention: the RVM image is shown scaled to fit the active area (aspect kept, centred), so
one RVM px is ``display_px_per_rvm_px`` display px of ``pitch_mm`` each.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

from . import fmvss111

__all__ = ["Display", "RVM_IMAGE_OF_RECORD_PX"]

#: The RVM image of record when no ``display`` section sets ``rvm_image_px``: 1280 × 720 px,
#: the usual output of an RVM camera's ISP to the head unit (not from the regulation).
RVM_IMAGE_OF_RECORD_PX = (1280, 720)

_Mm = Annotated[float, Field(gt=0, le=10_000)]
_Px = Annotated[int, Field(gt=0, le=100_000)]
_ImagePx = Annotated[int, Field(ge=16, le=8192)]


class Display(BaseModel):
    """The display of the RVM image (mm, px, degrees); see the module docstring."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)
    width_mm: _Mm = fmvss111.DISPLAY_WIDTH_MM
    height_mm: _Mm = fmvss111.DISPLAY_HEIGHT_MM
    resolution_px: tuple[_Px, _Px] = fmvss111.DISPLAY_RESOLUTION_PX
    eye_distance_mm: _Mm = fmvss111.EYE_TO_DISPLAY_MM
    viewing_angle_deg: Annotated[float, Field(ge=0, le=89)] = fmvss111.DISPLAY_VIEWING_ANGLE_DEG
    rvm_image_px: tuple[_ImagePx, _ImagePx] = RVM_IMAGE_OF_RECORD_PX

    def mm_per_rvm_px(self, rvm_size: tuple[int, int]) -> tuple[float, float]:
        """(horizontal, vertical) mm on the display of one RVM px, for an RVM image of
        ``rvm_size`` = (W, H) px shown scaled to fit the active area."""
        res_w, res_h = self.resolution_px
        w, h = rvm_size
        scale = min(res_w / w, res_h / h)  # display px per RVM px
        return (scale * self.width_mm / res_w, scale * self.height_mm / res_h)
