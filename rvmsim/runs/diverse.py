"""The diverse top-M: M candidates for the expert's final choice that are genuinely different.

The best trials of a converged search are near-copies of one another (CMA-ES puts its last
generations within a percent of each parameter's span of the optimum), so the M best by
score show one view M times.  The candidates offered instead (docs/tuning.md, "The diverse
top-M"):

1. **rank 1** is the best trial (highest EC score, then objective, then earliest): the
   one ``best/`` shows.  A robust run (``tune --robust``) ranks first by whether every
   member passes, then whether the car as designed (the nominal members) passes, then by
   its EC score where that is not flat, the yield over its samples and the nominal EC
   score (:func:`robust_keys`): it never offers a setting that fails the nominal car above
   one that passes it;
2. then the **all-pass** trials, each next one the trial farthest from every candidate
   chosen so far (greedy farthest-point selection; ties to the higher score);
3. only if fewer than M came from them: the failing trials whose EC score is within
   ``score_tolerance`` (a fraction) of the best one, farthest-point as well (a score of
   0 is near nothing);
4. only if still fewer than M: the remaining trials in score order (the best-scoring
   ones that are different, not the far-away worst of the search).

A trial is taken only if its distance to **every** candidate chosen before is at least
``min_distance``; fewer than M are offered when the trials hold no more such points.
Distances are Euclidean in normalised parameter space: each tuned parameter divided by its
search span (a difference of 0.05 in one parameter alone is 5 % of its span); fixed
parameters, and tuned ones with an empty span, do not count.  The rule is deterministic.

Each candidate carries ``differs``, one line saying how it differs from rank 1 as a camera
engineer reads it (:func:`differs_text`), and its EC margins (:func:`margins_of`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from ..isp import PARAM_SPECS, IspParams, OutputSpec
from ..search.space import SearchSpace
from .records import TrialRecord
from ..robust import ec_margins
from ..isp.exact import map_points
from ..scene import load_scene
from ..criteria import load_criteria

if TYPE_CHECKING:
    from ..criteria import Criteria
    from .records import RunSettings
    from .store import RunStore

__all__ = ["Candidate", "select_diverse", "differs_text", "margins_of", "normalised",
           "POOLS", "candidates_json", "choose", "make_candidates", "run_space",
           "store_candidates", "robust_keys", "FLAT_SCORE"]

#: Where a candidate came from (:attr:`Candidate.pool`), in the order they are drawn on.
POOLS = ("all-pass", "score-tolerance", "by-score")

_SPEC = {s.name: s for s in PARAM_SPECS}
_UNIT = {"deg": "°", "px": " px", "": ""}
#: A view this much wider or narrower (relative), or moved by this fraction of its width,
#: is named in ``differs`` ("wider view", "view lower").
_WIDTH_WORD, _SHIFT_WORD = 0.03, 0.05
#: A margin change is named when it is at least this fraction of the EC's scale.
_MARGIN_WORD = 0.05


@dataclass(frozen=True)
class Candidate:
    """One of the diverse top-M.

    ``distance``: to rank 1 in normalised parameter space (0 for rank 1); ``differs``: how
    it differs from rank 1 (empty for rank 1); ``margins``: EC id → signed distance of its
    value to the nearer end of the EC's acceptable range, in the EC's unit (> 0 inside,
    NaN: not measured, or no range); ``pool``: which of :data:`POOLS` it was drawn from
    (``all-pass``; ``score-tolerance``: fails, but scores within the tolerance of the best;
    ``by-score``: fails, taken in score order to fill M); ``stage``: the search stage that
    proposed it.
    """

    rank: int
    trial: int
    score: float
    passed: bool
    params: IspParams
    distance: float
    differs: str
    margins: dict[str, float]
    pool: str = "all-pass"
    stage: str = ""

    def as_json(self) -> dict[str, Any]:
        """The candidate as ``top/candidates.json`` lists it (NaN margins as null)."""
        return {"rank": self.rank, "trial": self.trial, "score": self.score,
                "passed": self.passed, "pool": self.pool, "distance": self.distance,
                "differs": self.differs,
                "margins": {k: None if math.isnan(v) else v for k, v in self.margins.items()},
                "params": {n: getattr(self.params, n) for n in IspParams.names()}}


def candidates_json(candidates: Sequence[Candidate], m: int, min_distance: float,
                    score_tolerance: float, by_score: bool = False) -> dict[str, Any]:
    """``top/candidates.json``: the rule and the candidates."""
    rule = "by-score" if by_score else "diverse"
    return {"rule": rule, "m": m, "min_distance": min_distance,
            "score_tolerance": score_tolerance,
            "candidates": [c.as_json() for c in candidates]}


def normalised(space: SearchSpace, x: np.ndarray) -> np.ndarray:
    """Rows of tuned values (``space.names`` order) as fractions of each parameter's search
    span, measured from its low end; parameters with an empty span are dropped."""
    low, span = space.low, space.high - space.low
    keep = span > 0
    return (np.asarray(x, dtype=np.float64)[:, keep] - low[keep]) / span[keep]


def choose(x: np.ndarray, score: np.ndarray, objective: np.ndarray, idx: np.ndarray,
           passed: np.ndarray, m: int, min_distance: float,
           score_tolerance: float, keys: Sequence[np.ndarray] = ()) -> list[tuple[int, str, float]]:
    """The rule of the module docstring on arrays (one row per trial; ``x`` normalised):
    (row, pool, distance to rank 1) of each candidate in rank order.  Vectorised: M passes
    over all rows, none over pairs.  ``keys``: arrays ranked by before the EC score (the
    first first, higher better; a robust run's, :func:`robust_keys`)."""
    n = len(score)
    if n == 0 or m < 1:
        return []
    # best first; ties: objective, earliest
    order = np.lexsort((idx, -objective, -score, *(-k for k in reversed(keys))))
    xs, sc, ok = x[order], score[order], passed[order]
    near = ~ok & (sc > 0) & (sc >= sc[0] * (1 - score_tolerance))  # a 0 is near nothing
    tiers = (ok, near, ~ok & ~near)

    def dist(j: int) -> np.ndarray:
        return np.sqrt(((xs - xs[j]) ** 2).sum(axis=1))

    to_first = dist(0)
    nearest = to_first.copy()  # distance of every row to the nearest chosen one
    taken = np.zeros(n, bool)
    taken[0] = True
    chosen = [(0, POOLS[0] if ok[0] else POOLS[1] if near[0] else POOLS[2])]
    for tier, (pool, farthest) in zip(tiers, ((POOLS[0], True), (POOLS[1], True),
                                              (POOLS[2], False))):
        while len(chosen) < m:
            free = tier & ~taken & (nearest >= min_distance)
            if not free.any():
                break
            # rows are in score order, so argmax's first hit is the best score among ties
            j = int(np.argmax(np.where(free, nearest, -np.inf)) if farthest else np.argmax(free))
            chosen.append((j, pool))
            taken[j] = True
            nearest = np.minimum(nearest, dist(j))
    return [(int(order[j]), pool, float(to_first[j])) for j, pool in chosen]


def select_diverse(records: Sequence[TrialRecord], space: SearchSpace, criteria: Criteria,
                   m: int, min_distance: float, score_tolerance: float, *,
                   output: OutputSpec | None = None) -> list[Candidate]:
    """The diverse top-M of ``records`` (the rule of the module docstring).

    Parameters
    ----------
    records : sequence of TrialRecord
        The trials to choose from (typically every trial of a run).
    space : SearchSpace
        The space they were searched in: its tuned parameters and spans set the distances.
    criteria : Criteria
        The ECs' acceptable ranges, for the margins and the ``differs`` lines.
    m : int
        Candidates wanted (at most; fewer when the trials hold no more).
    min_distance : float
        Least distance between any two candidates, in fractions of span (> 0).
    score_tolerance : float
        Failing trials within this fraction of the best EC score come before the rest.
    output : OutputSpec, optional
        The RVM image, for the view words of ``differs`` (default 1280 × 720).
    """
    if not records:
        return []
    recs = list(records)
    x = normalised(space, np.array([space.vector(r.params) for r in recs]).reshape(len(recs), -1))
    picks = choose(x, np.array([r.score for r in recs]), np.array([r.objective for r in recs]),
                   np.array([r.idx for r in recs]), np.array([r.passed for r in recs], bool),
                   m, min_distance, score_tolerance)
    return make_candidates([(recs[i], pool, d) for i, pool, d in picks], space, criteria, output)


def make_candidates(picks: Sequence[tuple[TrialRecord, str, float]], space: SearchSpace,
                    criteria: Criteria, output: OutputSpec | None = None) -> list[Candidate]:
    """Candidates of chosen trials (record, pool, distance to rank 1), in rank order; the
    first is rank 1."""
    if not picks:
        return []
    first = picks[0][0]
    first_margins = margins_of(first, criteria)
    out = []
    for k, (rec, pool, d) in enumerate(picks, start=1):
        margins = first_margins if k == 1 else margins_of(rec, criteria)
        text = "" if k == 1 else differs_text(first, rec, space, criteria, output,
                                              (first_margins, margins))
        out.append(Candidate(k, rec.idx, rec.score, rec.passed, rec.params, d, text,
                             dict(margins), pool, rec.stage))
    return out


def margins_of(rec: TrialRecord, criteria: Criteria) -> dict[str, float]:
    """EC id → margin of ``rec``'s value (:func:`rvmsim.robust.ec_margins`; NaN where not
    measured or the EC has no range), for the ECs of ``criteria`` the record holds."""

    out = {}
    for ec in criteria.ids:
        o = rec.ecs.get(ec)
        if o is None:
            continue
        c = criteria.items[ec]
        value = np.nan if o.value is None else o.value
        out[ec] = float(ec_margins(np.array([value]), c.low, c.high)[0])
    return out


def _label(name: str) -> str:
    """A parameter's short name: the paper's (``FOV``, ``RAD``, ``zoom``, ``adv V scale``)."""
    label = _SPEC[name].paper_name.replace("Advanced ", "adv ")
    return label.lower() if " " not in label and not label.isupper() else label


def _param_changes(first: IspParams, other: IspParams, space: SearchSpace) -> list[str]:
    """The two or three largest parameter changes (relative to span), a third only when it
    is at least a third of the largest: each as its value beside rank 1's, with its unit
    (``FOV 162° (rank 1: 195°)``), never a bare signed change, which could read as the
    opposite of the view words beside it."""
    rows = []
    for r in space.ranges:
        span = r.high - r.low
        d = getattr(other, r.name) - getattr(first, r.name)
        if span > 0 and d != 0:
            rows.append((abs(d) / span, r.name, d))
    rows.sort(key=lambda t: -t[0])
    keep = [t for i, t in enumerate(rows[:3]) if i < 2 or t[0] >= rows[0][0] / 3]
    out = []
    for _, n, d in keep:
        unit = _UNIT.get(_SPEC[n].unit, " " + _SPEC[n].unit)
        places = max(0, 1 - math.floor(math.log10(abs(d))))  # the change to 2 digits
        mine, theirs = getattr(other, n), getattr(first, n)
        out.append(f"{_label(n)} {mine:.{places}f}{unit} (rank 1: {theirs:.{places}f}{unit})")
    return out


def _view(p: IspParams, out: OutputSpec) -> tuple[float, float]:
    """Where the RVM image reads the fisheye image: the distance (px) between the input
    points of its left and right edge at its middle row (its width), and the input row of
    its centre."""

    w, h = out.width - 1, out.height - 1
    u, v, _ = map_points(p, np.array([0.0, w, w / 2]), np.array([h / 2] * 3), (1, 1), out)
    return float(np.hypot(u[1] - u[0], v[1] - v[0])), float(v[2])


def _view_words(first: IspParams, other: IspParams, out: OutputSpec) -> list[str]:
    """``wider view``/``narrower view`` (the RVM image spans a larger/smaller width of the
    fisheye image across its middle row), ``view lower``/``view higher`` (its centre reads a
    lower/higher row of the fisheye image), each when the change is clear."""
    (w1, v1), (w2, v2) = _view(first, out), _view(other, out)
    words = []
    if w1 > 0 and abs(w2 / w1 - 1) >= _WIDTH_WORD:
        words.append("wider view" if w2 > w1 else "narrower view")
    if w1 > 0 and abs(v2 - v1) / w1 >= _SHIFT_WORD:
        words.append("view lower" if v2 > v1 else "view higher")
    return words


def _ec_scale(low: float | None, high: float | None) -> float | None:
    """The size a margin change is judged against: half the range's width (two ends), the
    bound's magnitude (one end); None for a point range (binary ECs) or no range."""
    if low is not None and high is not None:
        return (high - low) / 2 if high > low else None
    bound = low if low is not None else high
    return abs(bound) if bound else None


def _margin_change(first: Mapping[str, float], other: Mapping[str, float],
                   criteria: Criteria) -> str:
    """The enabled EC whose margin changes most (relative to :func:`_ec_scale`), as
    ``2-1 bumper center ratio margin lower (2 → 0.6 %)``; empty when none changes clearly."""
    best: tuple[float, str] | None = None
    for ec in criteria.ids:
        c = criteria.items[ec]
        scale = _ec_scale(c.low, c.high)
        a, b = first.get(ec, math.nan), other.get(ec, math.nan)
        if not c.enabled or scale is None or math.isnan(a) or math.isnan(b):
            continue
        change = (b - a) / scale
        if abs(change) >= _MARGIN_WORD and (best is None or abs(change) > abs(best[0])):
            best = (change, ec)
    if best is None:
        return ""
    change, ec = best
    d = {e.id: e for e in criteria.ecs}[ec]
    unit = f" {d.unit}" if d.unit else ""
    return (f"{ec} {d.name.replace('_', ' ')} margin {'lower' if change < 0 else 'higher'} "
            f"({first[ec]:.2g} → {other[ec]:.2g}{unit})")


def differs_text(first: TrialRecord, rec: TrialRecord, space: SearchSpace, criteria: Criteria,
                 output: OutputSpec | None = None,
                 margins: tuple[Mapping[str, float], Mapping[str, float]] | None = None) -> str:
    """How ``rec`` differs from rank 1 (``first``), in one line: what the view does (where
    it clearly does), the largest parameter changes, the EC margin that changes most, and the
    ECs it fails, e.g. ``wider view: FOV 168° (rank 1: 180°), zoom 0.62 (rank 1: 0.70); 2-1
    bumper center ratio margin lower (1.9 → 0.6 %)``.

    Parameters
    ----------
    output : OutputSpec, optional
        The RVM image (default 1280 × 720) the view words are measured on.
    margins : (dict, dict), optional
        :func:`margins_of` of ``first`` and ``rec``, when already computed.
    """
    out = output or OutputSpec(1280, 720)
    words = _view_words(first.params, rec.params, out)
    changes = ", ".join(_param_changes(first.params, rec.params, space)) or "same parameters"
    parts = [f"{', '.join(words)}: {changes}" if words else changes]
    m1, m2 = margins or (margins_of(first, criteria), margins_of(rec, criteria))
    margin = _margin_change(m1, m2, criteria)
    if margin:
        parts.append(margin)
    if not rec.passed:
        enabled = [e for e in rec.failing() if e in criteria.items and criteria.items[e].enabled]
        parts.append("fails " + ",".join(enabled or rec.failing()))
    return "; ".join(parts)


def run_space(store: RunStore, settings: RunSettings) -> SearchSpace:
    """The space a run searched: as its store records it, else (a run of an earlier
    version) the tuning config's on the run's (first) scene's camera.

    Raises
    ------
    RvmsimError
        One line: a run without a recorded space whose scene file is gone or unreadable.
    """

    space = store.space()
    if space is not None:
        return space
    return settings.config.space(load_scene(settings.scene).fisheye_camera())


#: A robust aggregate below this carries no ranking (where no setting passes a tenth of the
#: samples, the 10 % quantile of their EC scores is ~0 for every trial).
FLAT_SCORE = 1e-3


def robust_keys(store: RunStore, settings: RunSettings, idx: np.ndarray, score: np.ndarray,
                passed: np.ndarray) -> tuple[np.ndarray, ...]:
    """A robust run's ranking before its EC score (the robust aggregate), for trials
    ``idx`` (with their ``score`` and all-members ``passed``): every member passes, then
    every *nominal* member passes (a setting that fails the car as designed never ranks
    above one that passes it), then the aggregate where it is not flat
    (:data:`FLAT_SCORE`), then the yield over the samples, then the nominal EC score
    (the worst scene's)."""
    robust = settings.kind.robust
    t_idx, member, m_score, m_passed = store.member_table()
    if robust is None or not len(t_idx):
        return ()
    per = 1 + robust.samples
    pos = {int(i): r for r, i in enumerate(idx)}
    rows = np.array([pos.get(int(i), -1) for i in t_idx])
    keep = rows >= 0
    rows, member, m_score, m_passed = rows[keep], member[keep], m_score[keep], m_passed[keep]
    nominal = member % per == 0
    n = len(idx)
    nom_pass = np.ones(n, bool)
    np.logical_and.at(nom_pass, rows[nominal], m_passed[nominal])
    nom_score = np.full(n, np.inf)
    np.minimum.at(nom_score, rows[nominal], m_score[nominal])
    counts = np.bincount(rows[~nominal], minlength=n).astype(np.float64)
    hits = np.bincount(rows[~nominal], weights=m_passed[~nominal].astype(np.float64),
                       minlength=n)
    yields = np.divide(hits, counts, out=np.zeros(n), where=counts > 0)
    return (passed.astype(np.float64), nom_pass.astype(np.float64),
            np.where(score >= FLAT_SCORE, score, 0.0), yields,
            np.where(np.isfinite(nom_score), nom_score, 0.0))


def store_candidates(store: RunStore, settings: RunSettings, m: int | None = None,
                     min_distance: float | None = None, *, by_score: bool = False,
                     criteria: Criteria | None = None) -> list[tuple[Candidate, TrialRecord]]:
    """The diverse top-M of the run in ``store`` (``by_score``: the M best by score
    instead), each with its trial record; ``m`` and ``min_distance`` default to the run's
    tuning config (``diverse``), ``criteria`` to the run's criteria file.  Reads every
    trial's parameters and scores at once, and the full records of the chosen only."""

    cfg = settings.config
    m = cfg.diverse_m if m is None else m
    dmin = cfg.diverse.min_distance if min_distance is None else min_distance
    crit = criteria if criteria is not None else load_criteria(settings.criteria_file)
    space = run_space(store, settings)
    if by_score:
        recs = store.top(m)
        if not recs:
            return []
        x = normalised(space, np.array([space.vector(r.params) for r in recs]).reshape(len(recs), -1))
        d = np.sqrt(((x - x[0]) ** 2).sum(axis=1))
        picks = [(r, POOLS[2], float(dk)) for r, dk in zip(recs, d)]
    else:
        idx, score, objective, passed, x = store.vectors(space.names)
        chosen = choose(normalised(space, x), score, objective, idx, passed, m, dmin,
                        cfg.diverse.score_tolerance,
                        robust_keys(store, settings, idx, score, passed))
        recs = store.trials_at([int(idx[i]) for i, _, _ in chosen])
        picks = [(r, pool, d) for r, (_, pool, d) in zip(recs, chosen)]
    cands = make_candidates(picks, space, crit, cfg.output_spec())
    return list(zip(cands, [p[0] for p in picks]))
