"""Shared tuning: one ISP parameter set for several vehicles or variants (``rvmsim tune
SCENE1 SCENE2 … --shared``).

Every scene is a member (:mod:`rvmsim.tune.members`) of the run: a candidate's EC score is
the minimum of the scenes' (or a low quantile, ``--aggregate``), and it passes where it
passes on every scene.  The search space is the tuning config's on the **first** scene's
camera (RAD and the shifts fitted to it, as for a one-scene run); the scenes must share its
sensor size (one ISP setting is one camera part), else a one-line error.  The default
space's ranges (±60 px of H shift, ±160 px of V shift at 1280 px, RAD ×0.55…1.45) cover
the principal-point and focal-length spread of the bundled vehicles' cameras.

The run settings record every scene with its fingerprint (:class:`~rvmsim.runs.SceneRef`);
``--resume`` checks each.  The results are those of a one-scene run for the first scene
(``best/`` holds its images) plus ``best/members.json`` and ``best/ec_table.txt`` with every
scene's EC results.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from .._io import read_json_file
from ..errors import ResultFileError, RvmsimError
from ..search.config import TuningConfig
from .members import Member, check_cameras, member_conflicts
from ..runs.records import RunSettings
from ..scene import Scene, load_scene
from ..render import same_scene
from ..pipeline import make_evaluator

if TYPE_CHECKING:
    from ..criteria import Criteria
    from ..render import FisheyeImages
    from ..runs.store import RunStore

__all__ = ["resumed_scenes", "scene_members", "write_member_results", "shared_problem_lines", "shared_problems"]


def resumed_scenes(settings: RunSettings) -> list[Scene]:
    """The scenes of a shared run to resume, each checked against its fingerprint.

    Raises
    ------
    RvmsimError
        One line naming the scene that changed (or cannot be loaded).
    """

    out = []
    for ref in settings.scenes:
        sc = load_scene(ref.scene)
        if ref.scene_key is not None and not same_scene(ref.scene_key, sc, ref.scene):
            raise RvmsimError(f"{ref.scene}: the scene changed since this run started; "
                              "resuming would mix two scenes (start a new run)")
        out.append(sc)
    check_cameras([(f"{ref.scene} ({sc.name})", sc.fisheye_camera())
                   for ref, sc in zip(settings.scenes, out)])
    return out


def scene_members(scenes: Sequence[Scene], renders: Sequence[FisheyeImages]) -> list[Member]:
    """One member per scene: its vehicle name, label image and camera."""
    return [Member(sc.name, im.labels, im.camera, sc) for sc, im in zip(scenes, renders)]


def write_member_results(run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                         renders: Sequence[FisheyeImages], config: TuningConfig,
                         criteria: Criteria, aggregate: str
                         ) -> tuple[dict[str, Any], str] | None:
    """``best/members.json`` (each scene's EC results under the best parameters, and the
    aggregate) and ``best/ec_table.txt`` (each scene's EC table under its vehicle name);
    returns what they hold (None: no trials)."""

    top = store.top(1)
    if not top:
        return None
    best = top[0]
    out = config.output_spec()
    docs, tables = [], []
    for sc, im in zip(scenes, renders):
        ec = make_evaluator(im, out, criteria, path="full")(best.params)
        docs.append({"vehicle": sc.name, "scene": sc.source, **ec.as_dict()})
        tables.append(f"{sc.name}:\n{ec.table()}")
    (run_dir / "best").mkdir(parents=True, exist_ok=True)
    conflicts = [] if best.passed else member_conflicts(store, [sc.name for sc in scenes])
    doc = {"trial": best.idx, "aggregate": aggregate, "ec_score": best.score,
           "passed": best.passed, "members": docs, "conflicts": conflicts}
    table = (f"shared by {len(scenes)} scenes, EC score ({aggregate}) {best.score:.4g}, "
             f"{'all pass' if best.passed else 'fails ' + ','.join(best.failing())}\n\n"
             + "\n\n".join(tables) + "\n")
    (run_dir / "best" / "members.json").write_text(json.dumps(doc, indent=2))
    (run_dir / "best" / "ec_table.txt").write_text(table)
    return doc, table


def _limit(ec: dict[str, Any]) -> str:
    """An EC's acceptable range as a person reads it (``≤ 5 px``, ``45–55 %``)."""
    lo, hi = (list(ec.get("range") or []) + [None, None])[:2]
    unit = ec.get("unit") or ""
    unit = f" {unit}" if unit else ""
    if lo is not None and hi is not None:
        return f"{lo:g}–{hi:g}{unit}" if lo != hi else f"= {lo:g}{unit}"
    if hi is not None:
        return f"≤ {hi:g}{unit}"
    return f"≥ {lo:g}{unit}" if lo is not None else "any value"


def shared_problem_lines(run_dir: Path) -> list[str]:
    """Why the best setting of a shared run does not pass every scene (none when it does,
    or for other runs), from ``best/members.json``: each EC that fails on some scene with
    its value on every scene against its range (``EC 3-1 guide2_center_offset: 5.5 px on E
    and 5.5 px on B, passes on C; needs ≤ 5 px``), then the pairs of scenes that each pass
    alone in some trial but never together, with their conflicting ECs."""
    path = run_dir / "best" / "members.json"
    if not path.is_file() or (run_dir / "best" / "markets.json").is_file():
        return []
    doc = read_json_file(path, ResultFileError, what="members file")
    if not isinstance(doc, dict):
        raise ResultFileError(str(path), "", "not an object of member results")
    return shared_problems(doc)


def shared_problems(doc: dict[str, Any]) -> list[str]:
    """:func:`shared_problem_lines` from a ``members.json`` document (what
    :func:`write_member_results` returns)."""
    members = doc.get("members") or []
    # every scene passes (a robust shared run may still fail on a sample: robust.json says)
    if all(m.get("passed") for m in members):
        return []
    rows: dict[str, list[tuple[str, dict[str, Any]]]] = {}
    for m in members:
        for ec in m.get("ecs") or []:
            if ec.get("enabled", True):
                rows.setdefault(ec["id"], []).append((m["vehicle"], ec))
    lines = []
    for ec_id, per in rows.items():
        fails = [(v, e) for v, e in per if not e.get("passed")]
        if not fails:
            continue
        unit = f" {per[0][1].get('unit')}" if per[0][1].get("unit") else ""
        shown = " and ".join(("—" if e.get("value") is None else f"{e['value']:.4g}{unit}")
                             + f" on {v}" for v, e in fails)
        ok = [v for v, e in per if e.get("passed")]
        lines.append(f"EC {ec_id} {per[0][1].get('name', '')}: {shown}"
                     + (f", passes on {', '.join(ok)}" if ok else "")
                     + f"; needs {_limit(per[0][1])}")
    for c in doc.get("conflicts") or []:
        a, b = c["members"]
        ecs = ", ".join(f"{e['ec']} on {e['member']} ({e['fails_in']} of {e['of']} trials)"
                        for e in c["ecs"])
        lines.append(f"{a} and {b} each pass alone but never together; where one passes the "
                     f"other fails {ecs}")
    return lines
