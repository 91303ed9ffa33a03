"""Japan's rear-view monitor assessment (JNCAP, NASVA; FY2015–FY2022) where it asks more than
UN R158, as ECs: the plugin of the bundled criteria set ``jp`` (market ``jp``), measured on
a scene at the ``jp`` site (:mod:`rvmsim.scene.sitedefs`).  Japan's law applies UN R158
itself (market ``unr158``); a car for Japan is tuned for ``unr158,jp``.

=====  =================================================================================  ====
EC     measurement                                                                        unit
=====  =================================================================================  ====
JP-1   distant field (3.5 m): least shown % of a pole's whole silhouette                  %
JP-2   distant field: least visual angle of a pole's width on the display / 5.0'          ×
JP-3   adjacent field (beside the rear corners): min over poles of the largest shown        ×
       square of its side / 0.2 m (⚠ our reading of "a part 20 cm or more")
JP-4   proximity field (right behind the car): least shown % of a pole (any part: ≥ 1 %)  %
=====  =================================================================================  ====

Sources and every ⚠ choice: docs/markets.md.  The limits are EC parameters or ranges a
criteria file changes.
"""

from __future__ import annotations

from ..unr158.ecs import area_ec, size_ec, whole_ec

__all__ = ["ECS", "VISUAL_ANGLE_ARCMIN", "ADJACENT_AREA_M", "PROXIMITY_LEAST_PERCENT"]

#: NASVA: the distant poles' visual angle, at least 5.0'.
VISUAL_ANGLE_ARCMIN = 5.0
#: ⚠M "a part 20 cm or more" of an adjacent pole, read as a 0.2 m × 0.2 m square of its side.
ADJACENT_AREA_M = 0.20
#: ⚠L "any part" of a proximity pole: at least this % of its silhouette shown.
PROXIMITY_LEAST_PERCENT = 1.0

ECS = [
    whole_ec("JP-1", ("distant",), "jp_distant_whole",
             "distant poles (3.5 m): least shown % of a whole silhouette"),
    size_ec("JP-2", "distant", VISUAL_ANGLE_ARCMIN, "jp_distant_visual_angle",
            "distant poles: least visual angle of a pole's width on the display / 5.0'"),
    area_ec("JP-3", "adjacent", ADJACENT_AREA_M, "jp_adjacent_area",
            "adjacent poles: min over poles of the largest shown square / 0.2 m", top=False),
    whole_ec("JP-4", ("proximity",), "jp_proximity_any_part",
             "proximity poles: least shown % of a pole (any part: >= 1 %)",
             least_percent=PROXIMITY_LEAST_PERCENT),
]
