"""The run report's top-M gallery cards: how a candidate differs from rank 1, and its EC
margins as a row of chips."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from .page import escape
from ..criteria.canvas import unit_text

if TYPE_CHECKING:
    from ..criteria import Criteria
    from ..runs import TrialRecord

__all__ = ["differences", "margins_html"]


def differences(rec: TrialRecord, first: TrialRecord, criteria: Criteria) -> list[str]:
    """ECs (enabled ones) whose pass/fail differs from rank 1, as 'EC: pass → fail'."""
    out = []
    for ec, item in first.ecs.items():
        crit = criteria.items.get(ec)
        if crit is not None and not crit.enabled:
            continue
        mine = rec.ecs.get(ec)
        if mine is None:
            continue
        if mine.passed != item.passed:
            out.append(f"{ec}: {'pass' if mine.passed else 'fail'} "
                       f"(#1 {'passes' if item.passed else 'fails'})")
    return out


def _margin_chip(margin: float) -> str:
    """A margin in two significant digits with its sign (whole numbers from 10 on)."""
    if abs(margin) >= 10:
        return f"{margin:+.0f}"
    return f"{margin:+.2g}"


def margins_html(margins: dict[str, float], rec: TrialRecord, criteria: Criteria) -> str:
    """A gallery card's row of EC margins: per enabled EC its id and margin (signed
    distance of its value inside the acceptable range, EC unit; ✓/✗ for binary ECs, n/a
    when not measured), coloured by pass/fail; the name, margin and unit on hover."""

    defs = {d.id: d for d in criteria.ecs}
    chips = []
    for ec in criteria.ids:
        crit, outcome, d = criteria.items[ec], rec.ecs.get(ec), defs.get(ec)
        if not crit.enabled or outcome is None or d is None:
            continue
        m = margins.get(ec, math.nan)
        if d.binary:
            shown = "✓" if outcome.passed else "✗"
        elif math.isnan(m):
            shown = "n/a"
        else:
            shown = _margin_chip(m) + unit_text(d.unit).strip()
        st = "pass" if outcome.passed else "fail"
        tip = (f"{ec} {d.name.replace('_', ' ')}: "
               + ("not measured" if math.isnan(m) and not d.binary else
                  st if d.binary else f"margin {m:+.4g}{unit_text(d.unit)}") + f" ({st})")
        chips.append(f'<span class="{st}" title="{escape(tip)}"><b>{escape(ec)}</b> '
                     f"{escape(shown)}</span>")
    return f'<p class="margins">{"".join(chips)}</p>'
