"""The label groups and bumper columns the paper's eleven ECs read
(:mod:`rvmsim.criteria.builtin`, whose measure functions and stack measure functions,
:mod:`rvmsim.criteria.builtin_stack`, share them)."""

from __future__ import annotations

from .. import labels as L
from .groups import LabelGroup

__all__ = ["F", "G", "FG", "ABC", "GUIDE2", "GUIDE3", "BOARD", "UPPER_BODY", "BLOCKERS",
           "bumper_spans"]

F = LabelGroup("F", (L.object_stripe("F"), L.object_patch("F")))
G = LabelGroup("G", (L.object_stripe("G"), L.object_patch("G")))
#: F and G by name.
FG = {"F": F, "G": G}
ABC = LabelGroup("ABC", tuple(L.object_body(c) for c in "ABC")
                 + tuple(L.object_stripe(c) for c in "ABC"))
GUIDE2 = LabelGroup("guide2", (L.guide_cross(2),))
GUIDE3 = LabelGroup("guide3", (L.guide_cross(3),))
BOARD = LabelGroup("board", (L.BOARD,))
UPPER_BODY = LabelGroup("upper_body", (L.GARNISH, L.TRUNK), upper_region=True)
#: What may not touch a visible patch: vehicle body, void, user-supplied parts.
BLOCKERS = (*L.BODY_LABELS, L.VOID)


def bumper_spans(width: int, edge_columns: int) -> dict[str, tuple[int, int]]:
    """Column spans [a, b) of the bumper heights t_l, t_r (image edges) and t_c (centred)."""
    k = max(1, min(edge_columns, width // 3))
    c0 = int(round(width / 2.0 - k / 2))
    return {"t_l": (0, k), "t_r": (width - k, width), "t_c": (c0, c0 + k)}
