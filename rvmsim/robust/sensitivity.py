"""What drives an EC over the samples, as a formula: a sensitivity fit of its value to the
mount offsets and the load state.

Per EC the measured value ``v`` of every sample (NaN: not measured, left out) is fitted by
least squares with two models over the varying axes (x, y, z in mm; yaw, pitch, roll in
degrees) and, when the samples hold several load states, one 0/1 indicator per state other
than the reference (the variation's first):

* **linear**: ``v ≈ c + Σ b_a · offset_a + Σ d_s · [state s]`` (numpy ``lstsq``);
* **abs**: ``v ≈ |c + Σ b_a · offset_a + Σ d_s · [state s]|``, for ECs that measure a size
  of a difference (EC 2-3, the bumper's left/right difference, is ``|16.0·yaw + 16.5·roll|``
  px on vehicle A).  Fitted by alternating signs: with the signs of the linear part fixed,
  the model is linear in the sign-flipped values; the signs are re-chosen from the fit until
  they stop changing.  The starts are the linear fit, the rank-one part of a quadratic fit
  of ``v²`` (whose leading eigenvector is the direction of ``b``; when there are samples
  enough for it) and the signs of each axis and of each sum and difference of two, so a
  symmetric EC, which a linear fit sees as flat, is found.

The model with the higher R² is kept (the abs model only when its linear part changes sign
within the samples: otherwise it is the linear one).  The columns are standardised for the
fit (zero mean, unit variance) and the coefficients given back per unit: EC unit per mm or
per degree, a state's ``d`` in the EC's unit.  A term is reported when its contribution over
the samples (``|b| ×`` the axis's range; ``|d|`` for a state) is at least twice the fit's
residual RMS and at least 5 % of the largest contribution; the chosen model is then fitted
again on those terms, and its R² is the one reported.

Position offsets are taken where the samples were *rendered* (``render_position_mm``, the
centre of their bin): that is where the EC saw the camera, so the fitted ``b`` is the EC's
sensitivity itself (the drawn offset would dilute it by the bins' share of the variance).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .samples import MountSample
from .variation import MOUNT_AXES, Variation

__all__ = ["Sensitivity", "fit_sensitivity", "sensitivity_axes", "GOOD_R2", "SHORT_NAMES"]

#: A fit explains an EC when its R² is at least this.
GOOD_R2 = 0.8
#: Below this R² a fit explains so little that its formula is not shown.
_PARTLY_R2 = 0.5
#: A term is kept when its contribution is at least this many residual RMS …
_RESIDUAL_FACTOR = 2.0
#: … and at least this share of the largest contribution.
_MIN_SHARE = 0.05
#: Sign alternations of the abs fit at most (they settle in a few).
_MAX_FLIPS = 60
#: Short names of the mount axes in descriptions.
SHORT_NAMES = {"x_mm": "x", "y_mm": "y", "z_mm": "z", "yaw_deg": "yaw", "pitch_deg": "pitch",
               "roll_deg": "roll"}
_LOAD = "load:"


@dataclass(frozen=True)
class Sensitivity:
    """An EC's value as a function of the mount offsets and the load state.

    Attributes
    ----------
    ec_id, unit : str
        The EC and its unit.
    model : {"linear", "abs"}
        ``v ≈ c + Σ b·x`` or ``v ≈ |c + Σ b·x|`` (see the module docstring).
    intercept : float
        ``c``: at zero offsets in the reference load state (inside the bars for abs), EC unit.
    coefficients : tuple of (str, float)
        The reported terms, largest contribution first: a mount axis (``yaw_deg``: EC unit
        per degree; ``x_mm``: per mm) or ``load:<state>`` (EC unit, in that state against
        the reference).
    contributions : tuple of float
        Each term's ``|b|`` times its axis's range over the samples (``|d|`` for a state),
        EC unit.
    dropped : tuple of str
        Terms fitted but not reported (contribution too small, see the module docstring).
    r2 : float
        Coefficient of determination of the reported model (1: exact; 1 also for a value
        that never changes).
    r2_linear, r2_abs : float
        R² of each model on every term (``abs``: NaN when its linear part never changes
        sign, where it is the linear model).
    rms : float
        Residual RMS of the reported model, EC unit.
    n : int
        Samples fitted (those where the EC was measured).
    reference_load : str or None
        The load state the indicators are measured against (None: one state).
    """

    ec_id: str
    unit: str
    model: Literal["linear", "abs"]
    intercept: float
    coefficients: tuple[tuple[str, float], ...]
    contributions: tuple[float, ...]
    dropped: tuple[str, ...]
    r2: float
    r2_linear: float
    r2_abs: float
    rms: float
    n: int
    reference_load: str | None = None

    @property
    def good(self) -> bool:
        """Whether the fit explains the EC (R² ≥ :data:`GOOD_R2`)."""
        return self.r2 >= GOOD_R2

    def formula(self) -> str:
        """``|16.0·yaw + 16.5·roll| px``: the reported terms, with the intercept when it
        matters (by the rule terms are kept by, or when no term is)."""
        parts: list[tuple[float, str]] = []
        c = abs(self.intercept)
        if not self.coefficients or (c >= _RESIDUAL_FACTOR * self.rms
                                     and c >= _MIN_SHARE * max(self.contributions)):
            parts.append((self.intercept, ""))
        for term, b in self.coefficients:
            name = (f"[{term[len(_LOAD):]}]" if term.startswith(_LOAD)
                    else SHORT_NAMES.get(term, term))
            parts.append((b, name))
        text = ""
        for k, (b, name) in enumerate(parts):
            mag = _num(abs(b)) + (f"·{name}" if name else "")
            text += (("-" if b < 0 else "") + mag) if k == 0 else (
                (" - " if b < 0 else " + ") + mag)
        text = f"|{text}|" if self.model == "abs" else text
        return f"{text} {self.unit}".rstrip()

    def describe(self) -> str:
        """One line: ``2-3 ≈ |16.0·yaw + 16.5·roll| px, R² 0.99``; that the EC follows none
        of the offsets (R² < 0.5: no formula) or only partly (the formula with its R²); or
        ``1-1 = 0.00 on every sample``."""
        if not self.coefficients and self.rms <= 1e-9 * max(1.0, abs(self.intercept)):
            return f"{self.ec_id} = {self.formula()} on every sample"
        if self.good:
            return f"{self.ec_id} ≈ {self.formula()}, R² {self.r2:.2f}"
        if self.r2 < _PARTLY_R2:  # a formula that explains nothing is noise to a reader
            return (f"{self.ec_id}: follows none of the mount offsets or the load (no linear "
                    f"or |linear| fit, R² {self.r2:.2f})")
        return (f"{self.ec_id}: only partly follows the mount offsets and load (R² "
                f"{self.r2:.2f}: {self.formula()})")

    def as_dict(self) -> dict[str, object]:
        return {"model": self.model, "intercept": self.intercept,
                "coefficients": dict(self.coefficients),
                "contributions": dict(zip((t for t, _ in self.coefficients),
                                          self.contributions)),
                "dropped": list(self.dropped), "r2": self.r2,
                "r2_linear": self.r2_linear,
                "r2_abs": None if math.isnan(self.r2_abs) else self.r2_abs,
                "rms": self.rms, "n": self.n, "reference_load": self.reference_load,
                "good": self.good, "description": self.describe()}


def _num(x: float) -> str:
    """Three significant digits, trailing zeros kept (16.0, 0.840, 123)."""
    s = f"{x:#.3g}"
    return s[:-1] if s.endswith(".") else s


def sensitivity_axes(samples: Sequence[MountSample],
                     variation: Variation) -> dict[str, np.ndarray]:
    """The offsets each sample's ECs saw, per varying axis: the rendered position (mm) and
    the drawn angles (degrees)."""
    out: dict[str, np.ndarray] = {}
    for i, name in enumerate(MOUNT_AXES):
        if not variation.axes[i].varies:
            continue
        out[name] = np.array([s.render_position_mm[i] if i < 3 else s.offsets[i]
                              for s in samples], dtype=np.float64)
    return out


@dataclass(frozen=True)
class _Design:
    """The fit's columns: intercept, standardised axes, state indicators."""

    x: np.ndarray
    names: tuple[str, ...]
    centre: np.ndarray
    spread: np.ndarray
    ranges: np.ndarray
    n_axes: int

    def raw(self, g: np.ndarray) -> tuple[float, np.ndarray]:
        """Intercept and per-unit coefficients of standardised coefficients ``g``."""
        b = g[1:].copy()
        b[: self.n_axes] /= self.spread
        c = float(g[0] - np.sum(g[1: 1 + self.n_axes] * self.centre / self.spread))
        return c, b

    def subset(self, keep: Sequence[int]) -> _Design:
        """The design of the terms ``keep`` (indices into ``names``, axes first)."""
        axes = [k for k in keep if k < self.n_axes]
        assert list(keep) == axes + [k for k in keep if k >= self.n_axes]
        return _Design(self.x[:, [0, *(k + 1 for k in keep)]],
                       tuple(self.names[k] for k in keep), self.centre[axes],
                       self.spread[axes], self.ranges[list(keep)], len(axes))


def _design(axes: Mapping[str, np.ndarray], loads: np.ndarray | None,
            states: Sequence[str], ok: np.ndarray) -> tuple[_Design, str | None]:
    cols, names, centre, spread, ranges = [], [], [], [], []
    for name, values in axes.items():
        v = np.asarray(values, dtype=np.float64)[ok]
        sd = float(v.std())
        if sd <= 1e-12 * max(1.0, float(np.abs(v).max(initial=0.0))):
            continue  # the axis does not vary over these samples
        cols.append((v - v.mean()) / sd)
        names.append(name)
        centre.append(float(v.mean()))
        spread.append(sd)
        ranges.append(float(np.ptp(v)))
    n_axes = len(cols)
    reference = None
    if loads is not None:
        here = np.asarray(loads)[ok].astype(str)
        present = [s for s in dict.fromkeys([*states, *here]) if np.any(here == s)]
        if len(present) > 1:
            reference = present[0]
            for s in present[1:]:
                cols.append((here == s).astype(np.float64))
                names.append(_LOAD + s)
                ranges.append(1.0)
    x = np.column_stack([np.ones(int(ok.sum())), *cols])
    return _Design(x, tuple(names), np.array(centre), np.array(spread), np.array(ranges),
                   n_axes), reference


def _r2(pred: np.ndarray, y: np.ndarray) -> float:
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    ss_res = float(np.sum((pred - y) ** 2))
    if ss_tot <= 1e-24 * max(1.0, float(np.sum(y ** 2))):
        return 1.0 if ss_res <= 1e-18 * max(1.0, float(np.sum(y ** 2))) else 0.0
    return 1.0 - ss_res / ss_tot


def _linear(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.linalg.lstsq(x, y, rcond=None)[0]


def _abs_start(d: _Design, y: np.ndarray) -> np.ndarray | None:
    """A start for the abs model from a quadratic fit of y²: its quadratic form's leading
    eigenvector is b's direction, the linear terms give c (indicators start at 0)."""
    k = d.n_axes
    if k == 0:
        return None
    z = d.x[:, 1: 1 + k]
    pairs = [(i, j) for i in range(k) for j in range(i, k)]
    feats = np.column_stack([d.x, *(z[:, i] * z[:, j] for i, j in pairs)])
    if feats.shape[0] <= feats.shape[1]:
        return None
    beta = _linear(feats, y ** 2)
    q = np.zeros((k, k))
    for (i, j), v in zip(pairs, beta[d.x.shape[1]:]):
        q[i, j] = q[j, i] = v if i == j else v / 2.0
    lam, vec = np.linalg.eigh(q)
    if lam[-1] <= 0:
        return None
    b = math.sqrt(lam[-1]) * vec[:, -1]
    c = float(beta[1: 1 + k] @ b) / (2.0 * float(b @ b))
    g = np.zeros(d.x.shape[1])
    g[0], g[1: 1 + k] = c, b
    return g


def _axis_starts(d: _Design) -> list[np.ndarray]:
    """Starts for the abs model that need no more samples than it has terms: each axis
    alone and each pair of axes, both ways (the signs of its inside follow one axis, or a
    sum or difference of two)."""
    k = d.n_axes
    out = []
    for i in range(k):
        for j in range(i, k):
            for sign in ((1.0,) if i == j else (1.0, -1.0)):
                g = np.zeros(d.x.shape[1])
                g[1 + i] += 1.0
                g[1 + j] += sign if i != j else 0.0
                out.append(g)
    return out


def _abs(x: np.ndarray, y: np.ndarray, starts: Sequence[np.ndarray]) -> np.ndarray:
    """The abs model's standardised coefficients: alternate signs and linear fits of the
    sign-flipped values from each start; the least residual wins."""
    pinv = np.linalg.pinv(x)  # every sign pattern's least squares: one product
    best, best_ss = starts[0], math.inf
    seen: set[bytes] = set()  # sign patterns already followed (the path from one is known)
    for g in starts:
        for _ in range(_MAX_FLIPS):
            pred = x @ g
            ss = float(np.sum((np.abs(pred) - y) ** 2))
            if ss < best_ss:
                best, best_ss = g, ss
            s = pred >= 0.0
            key = np.packbits(s).tobytes()
            if key in seen:
                break
            seen.add(key)
            g = pinv @ (np.where(s, 1.0, -1.0) * y)
    return best


def _folds(x: np.ndarray, g: np.ndarray) -> bool:
    """Whether the linear part changes sign within the samples (on both sides at least
    2 samples and 2 %)."""
    neg = int(np.sum(x @ g < 0.0))
    least = max(2, math.ceil(0.02 * x.shape[0]))
    return min(neg, x.shape[0] - neg) >= least


def _fit(d: _Design, y: np.ndarray, model: str,
         start: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Standardised coefficients and predictions of ``model`` on ``d``."""
    g = _linear(d.x, y)
    if model == "abs":
        starts = [g] + ([start] if start is not None else [])
        quad = _abs_start(d, y)
        g = _abs(d.x, y, starts + ([quad] if quad is not None else []) + _axis_starts(d))
        return g, np.abs(d.x @ g)
    return g, d.x @ g


def fit_sensitivity(values: np.ndarray, axes: Mapping[str, np.ndarray],
                    loads: np.ndarray | None = None, *, states: Sequence[str] = (),
                    ec_id: str = "", unit: str = "") -> Sensitivity | None:
    """Fit an EC's values to the offsets and load states (see the module docstring).

    Parameters
    ----------
    values : (n,) float
        The EC's value per sample, EC unit; NaN (not measured) is left out.
    axes : dict
        Mount axis name (:data:`~rvmsim.scene.MOUNT_AXES`) → (n,) offsets the EC saw (mm,
        degrees; :func:`sensitivity_axes`).  Axes that do not vary are left out.
    loads : (n,) str, optional
        Each sample's load state.
    states : sequence of str
        The load states in order; the first present is the reference (default: the order
        they first appear in).
    ec_id, unit : str
        For the description.

    Returns
    -------
    Sensitivity or None
        None when too few samples were measured for the terms (fewer than terms + 3).
    """
    y_all = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(y_all)
    y = y_all[ok]
    if y.size < 3:
        return None
    full, reference = _design(axes, loads, states, ok)
    if y.size < full.x.shape[1] + 3:
        return None
    g_lin, p_lin = _fit(full, y, "linear")
    r2_lin = _r2(p_lin, y)
    g_abs, p_abs = _fit(full, y, "abs", g_lin)
    folds = _folds(full.x, g_abs)
    r2_abs = _r2(p_abs, y) if folds else math.nan
    model: Literal["linear", "abs"] = "abs" if folds and r2_abs > r2_lin else "linear"
    g, pred = (g_abs, p_abs) if model == "abs" else (g_lin, p_lin)
    rms = float(np.sqrt(np.mean((pred - y) ** 2)))
    _, b = full.raw(g)
    contrib = np.abs(b) * full.ranges
    top = float(contrib.max(initial=0.0))
    keep = [k for k in range(contrib.size) if contrib[k] > 0.0
            and contrib[k] >= _RESIDUAL_FACTOR * rms and contrib[k] >= _MIN_SHARE * top]
    reduced = full.subset(keep)
    g_r, pred_r = _fit(reduced, y, model, g[[0, *(k + 1 for k in keep)]])
    c_r, b_r = reduced.raw(g_r)
    lead = b_r[int(np.argmax(np.abs(b_r) * reduced.ranges))] if b_r.size else c_r
    if model == "abs" and lead < 0:
        c_r, b_r = -c_r, -b_r  # |z| = |−z|: shown with the largest term positive
    contrib_r = np.abs(b_r) * reduced.ranges
    order = np.argsort(-contrib_r, kind="stable")
    return Sensitivity(
        ec_id, unit, model, c_r,
        tuple((reduced.names[k], float(b_r[k])) for k in order),
        tuple(float(contrib_r[k]) for k in order),
        tuple(n for k, n in enumerate(full.names) if k not in keep),
        _r2(pred_r, y), r2_lin, r2_abs, float(np.sqrt(np.mean((pred_r - y) ** 2))),
        int(y.size), reference)
