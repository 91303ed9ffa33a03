"""How the members' objectives and sub-solves should combine in shared tuning (not a test).

    python tools/compare_shared_objectives.py e b --budget 1000 --seeds 8

Renders the named bundled vehicles at a quarter of their sensor (320×240 px, cached), and
for each seed runs ``search_members`` with ``cmaes-solved`` for every combination of the
objective combine (``sum-violation``, ``min``) and the sub-solve mode (``mean``, ``first``);
prints each run's aggregate EC score and each vehicle's score and verdict under the best
setting (P pass, F fail), then how many seeds pass on every vehicle and the median minimum
score per combination.  ``--alone`` also tunes each vehicle alone and judges it on the others.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

import yaml

from rvmsim.criteria import default_criteria
from rvmsim.pipeline import make_evaluator
from rvmsim.render import cached_render
from rvmsim.scene import load_scene
from rvmsim.tune import COMBINES, SOLVE_MODES, Member, score_params
from rvmsim.search import TuningConfig
from rvmsim.runs import RunStore
from rvmsim.tune import SearchSettings, search_members

ROOT = Path(__file__).resolve().parent.parent


def small_scene(letter: str, folder: Path) -> Path:
    """Bundled vehicle ``letter`` at 320×240 px (intrinsics scaled with it)."""
    doc = yaml.safe_load((ROOT / "scenes" / f"vehicle_{letter}.yaml").read_text())
    doc["camera"]["image_size"] = [320, 240]
    intr = doc["camera"]["intrinsics"]
    for k in ("fx", "fy", "cx", "cy"):
        if k in intr:
            intr[k] = float(intr[k]) / 4
    if "pixel_pitch_um" in intr:
        intr["pixel_pitch_um"] = float(intr["pixel_pitch_um"]) * 4
    path = folder / f"vehicle_{letter}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("letters", nargs="+")
    ap.add_argument("--budget", type=int, default=1000)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--alone", action="store_true")
    args = ap.parse_args()
    cfg = TuningConfig.model_validate({"output": {"size": [320, 180]}, "batch": 20})
    crit = default_criteria()
    folder = Path(tempfile.mkdtemp(prefix="rvmsim-shared-"))
    members = []
    for letter in args.letters:
        sc = load_scene(small_scene(letter, folder))
        images, _ = cached_render(sc)
        members.append(Member(letter, images.labels, images.camera))
    evs = [make_evaluator(m, cfg.output_spec(), crit) for m in members]

    def judge(params) -> tuple[float, bool, str]:
        res = [score_params(ev, [params]) for ev in evs]
        text = " ".join(f"{m.name}:{r.score[0]:.3f}{'P' if r.passed[0] else 'F'}"
                        for m, r in zip(members, res))
        return min(float(r.score[0]) for r in res), all(bool(r.passed[0]) for r in res), text

    if args.alone:
        for m in members:
            o = search_members([m], SearchSettings(cfg, crit, "cmaes-solved",
                                                   budget=args.budget), RunStore(":memory:"))
            print(f"{m.name} alone: {judge(o.best.params)[2]}")
    table: dict[tuple[str, str], list[tuple[float, bool]]] = {}
    for seed in range(args.seeds):
        for combine in COMBINES:
            for solve in SOLVE_MODES:
                how = SearchSettings(cfg, crit, "cmaes-solved", seed, args.budget,
                                     solve=solve, combine=combine)
                o = search_members(members, how, RunStore(":memory:"))
                low, ok, text = judge(o.best.params)
                table.setdefault((combine, solve), []).append((low, ok))
                print(f"seed {seed} {combine:13} {solve:5} agg {o.best.score:.3f}  {text}")
    print(f"\n{'combine':13} {'solve':5} {'all pass':>8} {'median min score':>17}")
    for (combine, solve), rows in table.items():
        print(f"{combine:13} {solve:5} {sum(ok for _, ok in rows):>4} / {len(rows):<2} "
              f"{statistics.median(low for low, _ in rows):17.3f}")


if __name__ == "__main__":
    main()
