"""The design points whose verdict or pass state differs between two sweeps (not a test).

    python tools/compare_sweeps.py BEFORE_DIR AFTER_DIR [--all]

Both folders are ``rvmsim sweep`` outputs (their ``sweep.json``), e.g. the example sweep
before and after a change of the search.  Prints a markdown table, one row per design point
(matched by its axis values) whose verdict or pass state changed, then the verdict counts
of both.  A ``sweep.json`` written before verdicts existed reads as pass / not found (what
its map called infeasible was only "not passing").  ``--all`` lists every point.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path
from typing import Any

from rvmsim.batch import VERDICTS, point_verdict


def _points(folder: Path) -> tuple[list[str], dict[str, dict[str, Any]]]:
    """(axis names, point results by their values as JSON) from ``folder/sweep.json``."""
    path = folder / "sweep.json"
    try:
        doc = json.loads(path.read_text())
        axes = [name for name, _ in doc["axes"]]
        points = {json.dumps([p["values"][a] for a in axes]): p for p in doc["points"]}
    except (OSError, ValueError, KeyError, TypeError) as err:
        sys.exit(f"compare_sweeps: {path}: not a sweep.json ({err})")
    return axes, points


def _state(p: dict[str, Any] | None) -> str:
    """A point's verdict, "error" or "—" (not in that sweep)."""
    if p is None:
        return "—"
    return point_verdict(p) or "error"


def _cell(p: dict[str, Any] | None) -> str:
    """Verdict, best score and limiting EC (or the reason) of one point, for a table cell."""
    state = _state(p)
    if p is None or state == "error":
        return state
    text = f"{state} {p['score']:.3g}"
    if state == "infeasible" and p.get("reason"):
        return f"{text} ({p['reason']})"
    if p.get("limiting_ec"):
        text += f", limited by {p['limiting_ec']}"
    return text


def table(before: Path, after: Path, every: bool = False) -> str:
    """The markdown table and the verdict counts (see the module docstring)."""
    axes, old = _points(before)
    axes_new, new = _points(after)
    if axes != axes_new:
        sys.exit(f"compare_sweeps: the sweeps have different axes ({axes} / {axes_new})")
    rows = []
    for key in sorted(set(old) | set(new), key=lambda k: json.loads(k)):
        a, b = old.get(key), new.get(key)
        changed = _state(a) != _state(b) or bool(a and a.get("passed")) != bool(
            b and b.get("passed"))
        if changed or every:
            evals = [str(p.get("evaluations", "")) if p else "" for p in (a, b)]
            rows.append("| " + " | ".join([*map(str, json.loads(key)), _cell(a), _cell(b),
                                            *evals]) + " |")
    head = "| " + " | ".join([*axes, "before", "after", "evaluations before",
                              "evaluations after"]) + " |"
    lines = [head, "|" + "---|" * (len(axes) + 4), *rows]
    if not rows:
        lines.append("| " + " | ".join(["(no point changed)"] + [""] * (len(axes) + 3)) + " |")
    for name, points in (("before", old), ("after", new)):
        counts = Counter(_state(p) for p in points.values())
        lines.append("")
        lines.append(f"{name}: " + ", ".join(f"{counts[v]} {v}" for v in VERDICTS)
                     + (f", {counts['error']} error" if counts["error"] else ""))
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before", type=Path)
    ap.add_argument("after", type=Path)
    ap.add_argument("--all", action="store_true", help="List every point, changed or not.")
    args = ap.parse_args()
    print(table(args.before, args.after, args.all))


if __name__ == "__main__":
    main()
