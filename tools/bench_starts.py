"""How often `rvmsim validate` gets from a CAD-level start to the true pose (issue 28; not a
test).

    python tools/bench_starts.py [--n 8] [--corners 2] [--cases hard,board,...] [--seed 0]
                                 [--jobs 2] [--json OUT.json]
    python tools/bench_starts.py --table OUT.json

For each capture, the scene's mount is moved from the true one by ``--n`` starts drawn
uniformly within ±10° on each angle and ±0.3 m on each axis (seeded), plus ``--corners``
starts at the box's corners (every axis at its extreme, alternating signs, and the
negation), and ``rvmsim.validate.validate`` runs from each with
``ValidationSettings(rerender=False)``.  A run is

- **converged**: the corrected mount within 5 mm (length) and 0.1° (each angle) of the
  true mount (the BAIC frame: of ``validate``'s result from the scene's own pose);
- **wrong**: a pose reported (no exception) but farther off: the worst outcome, and worst
  of all when its landmark RMS passes the verdict's 2 px (column ``w/fit``: only the
  position and angle limits can then tell, and their hint is ``--write-scene``);
- **refused**: ``ValidationFailure`` (counted by its ``.step``), or another
  ``RvmsimError`` (counted as ``error``);
- **crash**: any other exception (a bug: the command would end in a traceback).

Captures (``--cases``, comma-separated names or groups): ``hard`` (every case of
rvmsim/testing/hard_captures.py, or ``hard:<name>``), ``base`` and ``perturbed`` (the mat
scene of rvmsim/testing/captures.py, its own render and the degraded perturbed capture),
``board`` (the board-only capture), ``baic`` (the real BAIC EU5 frame; skipped when
missing).  Prints one row per capture and the totals; ``--json`` writes every run.
Workers are spawned processes that end when this process ends.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import platform
import statistics
import sys
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

#: Converged: the corrected mount within these of the truth (mm, length; degrees, each).
POSITION_MM, ANGLE_DEG = 5.0, 0.1
#: The start box: ± degrees on each angle, ± metres on each axis.
START_DEG, START_M = 10.0, 0.3
#: A wrong pose "fits" when its landmark RMS passes the verdict's default limit (px).
FIT_RMS_PX = 2.0
GROUPS = ("hard", "base", "perturbed", "board", "baic")


@dataclass(frozen=True)
class Run:
    """One validation from one start: the start (m, degrees), the outcome and its figures."""

    case: str
    start: int
    d_position_m: tuple[float, ...]
    d_ypr_deg: tuple[float, ...]
    outcome: str  # converged, wrong, refused, crash
    step: str  # the failed step of a refused run (the exception's type of a crash), else ""
    message: str  # its message's first 100 characters (a crash's last 100)
    position_error_mm: float | None
    angle_error_deg: float | None
    rms_after_px: float | None
    verdict_passed: bool | None  # the validation's verdict (its checks) when a pose came back
    start_text: str
    seconds: float


def starts(n: int, corners: int, seed: int) -> list[tuple[tuple[float, ...], tuple[float, ...]]]:
    """``corners`` corner starts then ``n`` uniform ones: (Δposition m, Δyaw/pitch/roll °)."""
    signs = [(1, -1, 1, 1, -1, 1), (-1, 1, -1, -1, 1, -1), (1, 1, -1, -1, -1, 1),
             (-1, -1, 1, 1, 1, -1)]
    out = [(tuple(START_M * s for s in sg[:3]), tuple(START_DEG * s for s in sg[3:]))
           for sg in signs[:corners]]
    import numpy as np

    rng = np.random.default_rng(seed)
    for _ in range(n):
        out.append((tuple(float(v) for v in rng.uniform(-START_M, START_M, 3)),
                    tuple(float(v) for v in rng.uniform(-START_DEG, START_DEG, 3))))
    return out


def _moved(mount: dict, d_pos: tuple[float, ...], d_ypr: tuple[float, ...]) -> dict:
    from rvmsim.testing.hard_captures import moved

    return moved(mount, d_pos, d_ypr)


def _case(name: str) -> tuple[Callable[..., Any], Any, dict]:
    """(scene at a start, capture, true mount) of capture ``name`` (in a worker)."""
    from rvmsim.validate import ValidationSettings, validate
    from rvmsim.testing import captures as T
    from rvmsim.testing import hard_captures as H

    if name.startswith("hard:"):
        hard = name[5:]
        return (lambda p, a: H.hard_scene(hard, p, a), H.hard_capture(hard),
                H.CASES[hard].mount)
    if name in ("base", "perturbed"):
        truth = T.MOUNT if name == "base" else T.perturbed_mount()
        cap = T.base()[1].color if name == "base" else T.perturbed()[1]
        return (lambda p, a: T.make_scene(T.scene_dict(_moved(truth, p, a))), cap, truth)
    if name == "board":
        return T.board_scene, T.board_capture(), T.BOARD_MOUNT
    if name == "baic":
        sc, cap, syn = T.baic()
        ref = validate(sc, cap, ValidationSettings(rerender=False), synthetic=syn).correction
        truth = {"position": list(ref.position_m), "yaw_deg": ref.yaw_deg,
                 "pitch_deg": ref.pitch_deg, "roll_deg": ref.roll_deg}
        own = sc.camera.mount.model_dump()

        def scene_at(p: tuple[float, ...], a: tuple[float, ...]) -> Any:
            m = _moved(own, p, a)
            return sc.with_mount(m["position"], m["yaw_deg"], m["pitch_deg"], m["roll_deg"])
        return scene_at, cap, truth
    raise ValueError(f"unknown capture {name!r} (groups: {', '.join(GROUPS)})")


_CASES: dict[str, tuple[Callable[..., Any], Any, dict]] = {}


def run_one(task: tuple[str, int, tuple[float, ...], tuple[float, ...]]) -> Run:
    """Validate capture ``task[0]`` from start ``task[1]`` (Δposition m ``task[2]``, Δangles °
    ``task[3]``) and classify the outcome."""
    import numpy as np

    from rvmsim.errors import RvmsimError
    from rvmsim.validate import ValidationFailure, ValidationSettings, validate

    name, k, d_pos, d_ypr = task
    if name not in _CASES:
        _CASES[name] = _case(name)
    scene_at, capture, truth = _CASES[name]
    scene = scene_at(d_pos, d_ypr)
    t = time.perf_counter()
    try:
        res = validate(scene, capture, ValidationSettings(rerender=False))
    except ValidationFailure as fail:
        return Run(name, k, d_pos, d_ypr, "refused", fail.step, fail.detail[:100], None, None,
                   None, None, "", time.perf_counter() - t)
    except RvmsimError as err:
        return Run(name, k, d_pos, d_ypr, "refused", "error", str(err)[:100], None, None,
                   None, None, "", time.perf_counter() - t)
    except Exception as err:  # a bug in validate (a traceback for the user): counted apart
        return Run(name, k, d_pos, d_ypr, "crash", type(err).__name__,
                   " ".join(str(err).split())[-100:], None, None, None, None, "",
                   time.perf_counter() - t)
    seconds = time.perf_counter() - t
    c = res.correction
    d_mm = float(np.linalg.norm((np.array(c.position_m) - truth["position"]) * 1000))
    d_ang = np.array([c.yaw_deg - truth["yaw_deg"], c.pitch_deg - truth["pitch_deg"],
                      c.roll_deg - truth["roll_deg"]])
    d_deg = float(np.abs((d_ang + 180.0) % 360.0 - 180.0).max())
    ok = d_mm <= POSITION_MM and d_deg <= ANGLE_DEG
    return Run(name, k, d_pos, d_ypr, "converged" if ok else "wrong", "", "", d_mm, d_deg,
               res.rms_after_px, res.passed, res.start[:100], seconds)


def _die_with_parent() -> None:
    """Worker initializer: the kernel ends this worker when its parent dies (Linux
    PR_SET_PDEATHSIG), and a watchdog thread ends it if the parent is gone anyway."""
    import ctypes
    import signal
    import threading

    parent = os.getppid()
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except OSError as err:  # not glibc: the watchdog below still ends the worker
        print(f"bench_starts: no PR_SET_PDEATHSIG ({err}); using the watchdog", file=sys.stderr)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)
    threading.Thread(target=watch, daemon=True).start()


def capture_names(spec: str) -> list[str]:
    """The captures ``--cases`` names (groups expanded; BAIC dropped when its frame is
    missing)."""
    from rvmsim.testing import captures as T
    from rvmsim.testing import hard_captures as H

    names: list[str] = []
    for part in (p.strip() for p in spec.split(",") if p.strip()):
        if part == "hard":
            names += [f"hard:{n}" for n in H.CASES]
        elif part == "baic" and not T.BAIC.is_file():
            print(f"baic: skipped, no capture at {T.BAIC}", file=sys.stderr)
        elif part in GROUPS or (part.startswith("hard:") and part[5:] in H.CASES):
            names.append(part)
        else:
            raise SystemExit(f"--cases: unknown capture {part!r} (groups: {', '.join(GROUPS)}, "
                             f"or hard:<{'|'.join(H.CASES)}>)")
    return names


def table(runs: list[Run], names: list[str]) -> str:
    """One row per capture and the totals: n, converged, wrong (of them fitting the
    landmarks within :data:`FIT_RMS_PX`), crashed, refused by step, median seconds per run."""
    rows = [f"{'capture':<22} {'n':>3} {'conv':>4} {'wrong':>5} {'w/fit':>6} {'crash':>5}  "
            f"{'refused (by step)':<34} {'median s':>8}"]

    def row(label: str, rs: list[Run]) -> str:
        count = Counter(r.outcome for r in rs)
        steps = Counter(r.step for r in rs if r.outcome == "refused")
        refused = ", ".join(f"{s} {n}" for s, n in sorted(steps.items())) or "-"
        med = statistics.median(r.seconds for r in rs) if rs else float("nan")
        passed = sum(r.outcome == "wrong" and (r.rms_after_px or 0.0) <= FIT_RMS_PX
                     for r in rs)
        return (f"{label:<22} {len(rs):>3} {count['converged']:>4} {count['wrong']:>5} "
                f"{passed:>6} {count['crash']:>5}  {refused:<34} {med:>8.1f}")
    for name in names:
        rows.append(row(name, [r for r in runs if r.case == name]))
    rows.append(row("total", runs))
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=8, help="uniform starts per capture")
    ap.add_argument("--corners", type=int, default=2, choices=range(5),
                    help="corner starts per capture (every axis at ±its extreme)")
    ap.add_argument("--cases", default="hard,base,perturbed,board,baic")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", type=Path, help="write every run here")
    ap.add_argument("--table", type=Path, metavar="RUNS.json",
                    help="print the table of a --json file and stop")
    args = ap.parse_args(argv)
    if args.table:
        runs = [Run(**{k: tuple(v) if isinstance(v, list) else v for k, v in r.items()})
                for r in json.loads(args.table.read_text())]
        print(table(runs, list(dict.fromkeys(r.case for r in runs))))
        return 0
    names = capture_names(args.cases)
    tasks = [(name, k, p, a) for name in names
             for k, (p, a) in enumerate(starts(args.n, args.corners, args.seed))]
    print(f"{platform.python_version()} on {cpu_model()} ({os.cpu_count()} cores); "
          f"{len(tasks)} runs on {args.jobs} workers", flush=True)
    t0 = time.perf_counter()
    runs: list[Run] = []
    with mp.get_context("spawn").Pool(args.jobs, initializer=_die_with_parent) as pool:
        for r in pool.imap_unordered(run_one, tasks):
            runs.append(r)
            extra = (f"{r.step}: {r.message}" if r.outcome in ("refused", "crash") else
                     f"{r.position_error_mm:.1f} mm, {r.angle_error_deg:.3f}°, "
                     f"RMS {r.rms_after_px:.2f} px, verdict "
                     f"{'PASS' if r.verdict_passed else 'FAIL'}")
            print(f"  {r.case} #{r.start}: {r.outcome} ({extra}) {r.seconds:.1f} s",
                  flush=True)
    runs.sort(key=lambda r: (names.index(r.case), r.start))
    print(table(runs, names))
    print(f"wall time {time.perf_counter() - t0:.0f} s")
    if args.json:
        args.json.write_text(json.dumps([asdict(r) for r in runs], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
