"""Evaluation criteria: the paper's eleven EC functions (section V), scored by sigmoids.

Each EC measures on the RVM *label* image exactly what the paper's expert measures by hand,
then the bidirectional sigmoid of the paper's equation (4) turns the measurement into a score
in [0, 1]; the EC score is the product of the enabled ECs' scores.

========  =====================================================================  ======
EC        measurement (on the RVM label image, H × W px)                          unit
========  =====================================================================  ======
1-1       the F and G lower 150 × 150 mm stripe patches are wholly visible: present,  0/1
          not touching the image border, not next to void or vehicle-body pixels
1-2       area of the F and G vertical stripes (incl. patches) / image area         ‰
1-3       d = rows above the highest pixel of objects A, B, C, / H                   %
1-4       area of the horizontal stripe on B / image area                           ‰
2-1       t_c: bumper height at the horizontal centre / H                           %
2-2       (t_l + t_r)/2: bumper heights at the left and right edges / H             %
2-3       |t_l − t_r|                                                               px
2-4       no garnish or trunk pixel in the upper part of the image                  0/1
3-1       |x of the centre of cross guideline 2 − x of the image centre|           px
3-2       y of the centre of cross guideline 3 / H                                  %
4-1       width / height of the pattern board's bounding box                        –
========  =====================================================================  ======

Conventions: pixel centres at integer (column, row); distances from the top of the image are
measured to pixel edges (a pixel in row r starts r px below the top).  Bumper heights are
counts of bumper pixels per column, averaged over ``edge_columns`` columns (at each edge,
and centred on the middle), which gives the sub-pixel figures the paper reports.  The centre
of a guideline is the midpoint of its leftmost and rightmost pixels; its height there is the
mean row of its pixels in the three columns around that midpoint.

A measurement that cannot be made (its object is not in the image) has value ``None``, score
0 and fails; nothing here raises or returns NaN for a degenerate image.

The hot path uses OpenCV primitives (``calcHist``, ``LUT``, ``boundingRect``); all eleven ECs
on a 640×480 label image take well under a millisecond (``tools/bench_criteria.py``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from .. import labels as L
from .._io import input_error_from_validation, key_lines, parse_yaml, read_text
from ..errors import CriteriaError

__all__ = [
    "EC_IDS",
    "criteria_from_text",
    "EcDefinition",
    "EC_DEFINITIONS",
    "Sigmoid",
    "Criterion",
    "Criteria",
    "Measurements",
    "EcValue",
    "EcResult",
    "EcBatch",
    "score_batch",
    "values_array",
    "measure",
    "measure_source",
    "LabelSource",
    "GROUPS",
    "score",
    "evaluate",
    "load_criteria",
    "default_criteria",
]


@dataclass(frozen=True)
class EcDefinition:
    id: str
    name: str
    unit: str
    binary: bool
    description: str


EC_DEFINITIONS: tuple[EcDefinition, ...] = (
    EcDefinition("1-1", "fg_lower_patches_visible", "", True,
                 "lower 150 × 150 mm of the F and G stripes wholly visible"),
    EcDefinition("1-2", "fg_stripe_area_ratio", "‰", False,
                 "area of the F and G vertical stripes / image area"),
    EcDefinition("1-3", "abc_top_margin_ratio", "%", False,
                 "distance d from the image top to the highest point of A, B, C / height"),
    EcDefinition("1-4", "b_stripe_area_ratio", "‰", False,
                 "area of the horizontal stripe on B / image area"),
    EcDefinition("2-1", "bumper_center_ratio", "%", False,
                 "bumper height t_c at the horizontal centre / image height"),
    EcDefinition("2-2", "bumper_side_ratio", "%", False,
                 "mean of the bumper heights t_l, t_r at the image edges / image height"),
    EcDefinition("2-3", "bumper_side_difference", "px", False, "|t_l − t_r|"),
    EcDefinition("2-4", "no_body_in_upper_region", "", True,
                 "no garnish or trunk in the upper part of the image"),
    EcDefinition("3-1", "guide2_center_offset", "px", False,
                 "|x of the centre of guideline 2 − x of the image centre|"),
    EcDefinition("3-2", "guide3_height_ratio", "%", False,
                 "y of the centre of guideline 3 / image height"),
    EcDefinition("4-1", "board_aspect_ratio", "", False,
                 "width / height of the calibration pattern board"),
)
EC_IDS = tuple(d.id for d in EC_DEFINITIONS)
_DEF = {d.id: d for d in EC_DEFINITIONS}


# ---------------------------------------------------------------------------- sigmoids
def _logistic(z: float) -> float:
    # 1 / (1 + e^-z), without overflow for large |z|
    return 0.5 * (1.0 + math.tanh(0.5 * z))


@dataclass(frozen=True)
class Sigmoid:
    """The bidirectional sigmoid of the paper's equation (4).

    ``f(x) = 1/(1 + e^(−c1·(x − c2))) · 1/(1 + e^(c3·(x − c4)))``; c2 and c4 are the lower
    and upper thresholds (``-inf`` / ``inf`` for a one-sided criterion), c1 and c3 the slopes.
    """

    c1: float = 1.0
    c2: float = -math.inf
    c3: float = 1.0
    c4: float = math.inf

    def __post_init__(self) -> None:
        if self.c1 < 0 or self.c3 < 0:
            raise ValueError("sigmoid slopes c1, c3 must be >= 0")
        if math.isnan(self.c2) or math.isnan(self.c4) or self.c2 > self.c4:
            raise ValueError("sigmoid thresholds need c2 <= c4")

    def __call__(self, x: float) -> float:
        lower = 1.0 if self.c2 == -math.inf else _logistic(self.c1 * (x - self.c2))
        upper = 1.0 if self.c4 == math.inf else _logistic(-self.c3 * (x - self.c4))
        return lower * upper

    @classmethod
    def from_range(cls, low: float | None, high: float | None, tolerance: float) -> Sigmoid:
        """Coefficients from an acceptable range and a tolerance (paper's future work 1–2).

        Each side scores 0.95 at the range's edge and 0.05 at ``tolerance`` beyond it: the
        threshold sits ``tolerance/2`` outside the edge and the slope is 2·ln(19)/tolerance.
        """
        if tolerance <= 0:
            raise ValueError("tolerance must be > 0")
        slope = 2.0 * math.log(19.0) / tolerance
        return cls(
            c1=slope if low is not None else 0.0,
            c2=low - tolerance / 2 if low is not None else -math.inf,
            c3=slope if high is not None else 0.0,
            c4=high + tolerance / 2 if high is not None else math.inf,
        )


# ---------------------------------------------------------------------------- criteria
@dataclass(frozen=True)
class Criterion:
    """One EC's acceptable range (pass/fail), its sigmoid (score) and whether it counts."""

    id: str
    low: float | None = None
    high: float | None = None
    sigmoid: Sigmoid | None = None  # None: binary, the score is the 0/1 measurement
    enabled: bool = True

    def passes(self, value: float | None) -> bool:
        if value is None:
            return False
        if self.sigmoid is None and self.low is None and self.high is None:
            return value >= 1.0
        return (self.low is None or value >= self.low) and (self.high is None or value <= self.high)

    def score(self, value: float | None) -> float:
        if value is None:
            return 0.0
        if self.sigmoid is None:
            return 1.0 if value >= 1.0 else 0.0
        return self.sigmoid(value)


@dataclass(frozen=True)
class Criteria:
    """A customer's criteria: one :class:`Criterion` per EC plus measurement options.

    ``upper_region_fraction``: the top fraction of the image EC 2-4 keeps free of body parts.
    ``edge_columns``: columns averaged for the bumper heights t_c, t_l, t_r.
    """

    name: str
    items: dict[str, Criterion]
    upper_region_fraction: float = 0.5
    edge_columns: int = 4
    source: str = "<default>"

    def __post_init__(self) -> None:
        if set(self.items) != set(EC_IDS):
            raise ValueError(f"criteria must define every EC {EC_IDS}")

    @property
    def ids(self) -> tuple[str, ...]:
        """The ids of the ECs these criteria hold, in evaluation order (the columns of
        :class:`EcBatch` and of the run store's ``ec`` column)."""
        return EC_IDS

    @functools.cached_property
    def arrays(self) -> tuple[np.ndarray, ...]:
        """Per EC in ``EC_IDS`` order, for :func:`score_batch`: low, high (±max float when
        open), binary, pass-flag-only, c1, c2, c3, c4, enabled."""
        items = [self.items[ec] for ec in EC_IDS]
        big = np.finfo(np.float64).max
        sig = [c.sigmoid or Sigmoid() for c in items]
        return (
            np.array([-big if c.low is None else c.low for c in items]),
            np.array([big if c.high is None else c.high for c in items]),
            np.array([c.sigmoid is None for c in items]),
            np.array([c.sigmoid is None and c.low is None and c.high is None for c in items]),
            np.array([s.c1 for s in sig]), np.array([s.c2 for s in sig]),
            np.array([s.c3 for s in sig]), np.array([s.c4 for s in sig]),
            np.array([c.enabled for c in items]),
        )


class _SigmoidModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    c1: Annotated[float, Field(ge=0)] = 1.0
    c2: float = -math.inf
    c3: Annotated[float, Field(ge=0)] = 1.0
    c4: float = math.inf


class _CriterionModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    enabled: bool = True
    range: tuple[float | None, float | None] | None = None
    sigmoid: _SigmoidModel | None = None
    tolerance: Annotated[float, Field(gt=0)] | None = None

    @model_validator(mode="after")
    def _check(self) -> _CriterionModel:
        if self.sigmoid is not None and self.tolerance is not None:
            raise ValueError("give either sigmoid coefficients or a tolerance, not both")
        if self.tolerance is not None and self.range is None:
            raise ValueError("a tolerance needs a range to derive the sigmoid from")
        if self.range is not None:
            lo, hi = self.range
            if lo is not None and hi is not None and lo > hi:
                raise ValueError("range must be [low, high] with low <= high")
        if self.sigmoid is not None and self.sigmoid.c2 > self.sigmoid.c4:
            raise ValueError("sigmoid thresholds need c2 <= c4")
        return self


class _CriteriaModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str = "criteria"
    upper_region_fraction: Annotated[float, Field(gt=0, le=1)] = 0.5
    edge_columns: Annotated[int, Field(ge=1, le=64)] = 4
    criteria: dict[str, _CriterionModel] = {}

    @model_validator(mode="after")
    def _ids(self) -> _CriteriaModel:
        unknown = sorted(set(self.criteria) - set(EC_IDS))
        if unknown:
            raise ValueError(f"unknown EC {unknown[0]!r} (known: {', '.join(EC_IDS)})")
        return self


def _build(model: _CriteriaModel, base: Criteria | None, source: str) -> Criteria:
    items: dict[str, Criterion] = {}
    for ec in EC_IDS:
        prev = base.items[ec] if base is not None else Criterion(ec)
        m = model.criteria.get(ec)
        if m is None:
            items[ec] = prev
            continue
        low, high = (prev.low, prev.high) if m.range is None else m.range
        if _DEF[ec].binary:
            sig = None
        elif m.sigmoid is not None:
            sig = Sigmoid(m.sigmoid.c1, m.sigmoid.c2, m.sigmoid.c3, m.sigmoid.c4)
        elif m.tolerance is not None:
            sig = Sigmoid.from_range(low, high, m.tolerance)
        else:
            sig = prev.sigmoid
        items[ec] = Criterion(ec, low, high, sig, m.enabled)
    return Criteria(model.name, items, model.upper_region_fraction, model.edge_columns, source)


def _load(text: str, source: str, base: Criteria | None) -> Criteria:
    data = parse_yaml(text, source, CriteriaError)
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise CriteriaError(source, "", "a criteria file must be a YAML mapping")
    if isinstance(data.get("criteria"), dict):  # YAML may read 1-1 … as strings already
        data["criteria"] = {str(k): v for k, v in data["criteria"].items()}
    try:
        model = _CriteriaModel.model_validate(data)
    except ValidationError as err:
        raise input_error_from_validation(err, source, key_lines(text), CriteriaError) from None
    return _build(model, base, source)


def default_criteria() -> Criteria:
    """The shipped defaults: the paper's thresholds and sigmoid coefficients (see the file
    ``rvmsim/criteria_default.yaml`` for how each was derived from the paper's figures)."""
    text = resources.files("rvmsim.criteria").joinpath("criteria_default.yaml").read_text("utf-8")
    return _load(text, "criteria_default.yaml", None)


def load_criteria(path: str | Path | None) -> Criteria:
    """Read a criteria file; ECs it does not mention keep the defaults.

    Raises
    ------
    CriteriaError
        One line naming the file, line and key for any problem.
    """
    if path is None:
        return default_criteria()
    path = Path(path)
    return _load(read_text(path, CriteriaError), str(path), default_criteria())


def criteria_from_text(text: str, source: str = "<criteria>") -> Criteria:
    """A criteria file's text (as :func:`load_criteria` reads it) → :class:`Criteria`."""
    return _load(text, source, default_criteria())


# ---------------------------------------------------------------------------- measuring
@dataclass(frozen=True)
class Measurements:
    """Raw measurements of one RVM label image, with the geometry the annotation draws.

    Values are ``None`` where the object measured is not in the image.  Geometry is in
    output px (pixel centres at integers).
    """

    values: dict[str, float | None]
    image_size: tuple[int, int]
    abc_top_row: int | None = None
    bumper_columns: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    guide2_center: tuple[float, float] | None = None
    guide3_center: tuple[float, float] | None = None
    board_box: tuple[int, int, int, int] | None = None  # x, y, w, h
    patch_visible: dict[str, bool] = field(default_factory=dict)
    upper_region_rows: int = 0


_BODY = (L.BUMPER, L.GARNISH, L.TRUNK)


def _bbox(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    import cv2

    x, y, w, h = cv2.boundingRect(mask)
    return None if w == 0 else (x, y, w, h)


#: Label groups the ECs look at, each measured inside its own window of the image.
GROUPS: dict[str, tuple[int, ...]] = {
    "F": (L.object_stripe("F"), L.object_patch("F")),
    "G": (L.object_stripe("G"), L.object_patch("G")),
    "ABC": tuple(L.object_body(c) for c in "ABC") + tuple(L.object_stripe(c) for c in "ABC"),
    "guide2": (L.guide_cross(2),),
    "guide3": (L.guide_cross(3),),
    "board": (L.BOARD,),
    "upper_body": (L.GARNISH, L.TRUNK),
}

_LUT_ABC = L.lut(GROUPS["ABC"])
_LUT_UPPER_BODY = L.lut(GROUPS["upper_body"])
_LUT_BLOCKERS = L.lut(list(_BODY) + [L.VOID] + list(range(L.EXTRA_PART_BASE, 256)))

Window = tuple[int, int, int, int]  # x0, y0, x1, y1 (exclusive), output px


class LabelSource:
    """Where :func:`measure_source` reads label pixels from: here the whole RVM label image;
    :class:`rvmsim.evaluator.CandidateEvaluator` remaps only the windows it is asked for.

    Each group's window is found in one pass: the image is mapped to one bit per group
    (``cv2.LUT``), OR-ed over 8×8 blocks, and a group's window is the box of its blocks
    grown by 1 px (the ring :func:`_patch_visible` inspects), so every measurement then
    reads only small windows.
    """

    def __init__(self, labels: np.ndarray):
        labels = np.asarray(labels)
        if labels.ndim != 2 or labels.dtype != np.uint8:
            raise TypeError(f"labels must be a 2-D uint8 image, got {labels.dtype} {labels.shape}")
        self.labels = np.ascontiguousarray(labels)
        self.shape = self.labels.shape
        self._windows = _group_windows(self.labels)

    def window(self, group: str) -> Window:
        """A window that holds every pixel of ``group`` and the pixels next to them."""
        return self._windows[group]

    def pixels(self, win: Window) -> np.ndarray:
        """The label pixels of a window, (y1 − y0, x1 − x0) uint8."""
        x0, y0, x1, y1 = win
        return self.labels[y0:y1, x0:x1]


_GROUP_BITS = np.zeros(256, np.uint8)
_BLOCK = 8


for _k, _ids in enumerate(GROUPS.values()):
    _GROUP_BITS[list(_ids)] |= np.uint8(1 << _k)


def _group_windows(labels: np.ndarray) -> dict[str, Window]:
    import cv2

    h, w = labels.shape
    bits = cv2.LUT(labels, _GROUP_BITS)
    gh, gw = -(-h // _BLOCK), -(-w // _BLOCK)
    if (gh * _BLOCK, gw * _BLOCK) != (h, w):
        bits = cv2.copyMakeBorder(bits, 0, gh * _BLOCK - h, 0, gw * _BLOCK - w,
                                  cv2.BORDER_CONSTANT, value=0)
    # OR over 8 rows, then over the 8 bytes of each 64-bit word (8 columns)
    # (slices, not ufunc.reduce: numpy reduces short strided axes slowly)
    rows = bits.view(np.uint64).reshape(gh, _BLOCK, gw)
    words = functools.reduce(np.bitwise_or, (rows[:, i] for i in range(_BLOCK)))
    cols = words.view(np.uint8).reshape(gh, gw, 8)
    blocks = functools.reduce(np.bitwise_or, (cols[..., i] for i in range(8)))
    out: dict[str, Window] = {}
    for k, name in enumerate(GROUPS):
        bx, by, bw, bh = cv2.boundingRect(blocks & np.uint8(1 << k))
        if bw == 0:
            out[name] = (0, 0, 0, 0)
        else:
            out[name] = (max(0, bx * _BLOCK - 1), max(0, by * _BLOCK - 1),
                         min(w, (bx + bw) * _BLOCK + 1), min(h, (by + bh) * _BLOCK + 1))
    return out


def _eq(sub: np.ndarray, label: int) -> np.ndarray:
    """255 where ``sub == label``, else 0 (uint8).  OpenCV takes a 1×1 image for a scalar,
    so that case goes through numpy."""
    import cv2

    if sub.size <= 1:
        return (sub == label).astype(np.uint8) * 255
    return cv2.compare(sub, label, cv2.CMP_EQ)


def _count(sub: np.ndarray, label: int) -> int:
    import cv2

    return 0 if sub.size == 0 else int(cv2.countNonZero(_eq(sub, label)))


def _bumper_height(sub: np.ndarray, ncols: int) -> float:
    return float(np.count_nonzero(sub == L.BUMPER)) / max(ncols, 1)


def _patch_visible(sub: np.ndarray, win: Window, label: int, shape: tuple[int, int]) -> bool:
    """Present (≥ 4 px), not touching the image border, no void/body pixel next to it."""
    import cv2

    if sub.size == 0:
        return False
    mask = _eq(sub, label)
    if cv2.countNonZero(mask) < 4:
        return False
    h, w = shape
    bx, by, bw, bh = cv2.boundingRect(mask)
    x, y = bx + win[0], by + win[1]
    if x == 0 or y == 0 or x + bw == w or y + bh == h:
        return False  # cut by the image border
    crop = sub[max(by - 1, 0) : by + bh + 1, max(bx - 1, 0) : bx + bw + 1]
    grown = cv2.dilate((crop == label).astype(np.uint8), np.ones((3, 3), np.uint8),
                       borderType=cv2.BORDER_CONSTANT, borderValue=0)
    blockers = cv2.LUT(crop, _LUT_BLOCKERS)
    return not np.any(blockers[grown > 0])


def bumper_spans(width: int, edge_columns: int) -> dict[str, tuple[int, int]]:
    """Column spans [a, b) of the bumper heights t_l, t_r (image edges) and t_c (centred)."""
    k = max(1, min(edge_columns, width // 3))
    c0 = int(round(width / 2.0 - k / 2))
    return {"t_l": (0, k), "t_r": (width - k, width), "t_c": (c0, c0 + k)}


def measure(labels: np.ndarray, *, upper_region_fraction: float = 0.5,
            edge_columns: int = 4) -> Measurements:
    """Measure the eleven ECs on an RVM label image.

    Parameters
    ----------
    labels : (H, W) uint8
        RVM label image (IDs from :mod:`rvmsim.labels`).
    upper_region_fraction : float
        Top fraction of the image that EC 2-4 checks for garnish/trunk pixels.
    edge_columns : int
        Columns averaged for each bumper height (t_l, t_r at the edges, t_c centred).

    Returns
    -------
    Measurements
    """
    return measure_source(LabelSource(labels), upper_region_fraction=upper_region_fraction,
                          edge_columns=edge_columns)


def measure_source(src: LabelSource, *, upper_region_fraction: float = 0.5,
                   edge_columns: int = 4) -> Measurements:
    """:func:`measure` on any :class:`LabelSource` (the same measurements, window by window)."""
    import cv2

    h, w = src.shape
    area = float(h * w)
    v: dict[str, float | None] = {}

    # EC 1-1, 1-2: F and G stripes
    visible, fg = {}, 0
    for c in "FG":
        win = src.window(c)
        sub = src.pixels(win)
        visible[c] = _patch_visible(sub, win, L.object_patch(c), (h, w))
        fg += _count(sub, L.object_stripe(c)) + _count(sub, L.object_patch(c))
    v["1-1"] = 1.0 if all(visible.values()) else 0.0
    v["1-2"] = 1000.0 * fg / area

    # EC 1-3: highest point of A, B, C (all three must be in the image); 1-4: B's stripe
    win = src.window("ABC")
    sub = src.pixels(win)
    top_row = None
    if sub.size and all(_count(sub, L.object_body(c)) + _count(sub, L.object_stripe(c)) > 0
                        for c in "ABC"):
        box = _bbox(cv2.LUT(sub, _LUT_ABC))
        top_row = None if box is None else box[1] + win[1]
    v["1-3"] = None if top_row is None else 100.0 * top_row / h
    v["1-4"] = 1000.0 * _count(sub, L.object_stripe("B")) / area

    # EC 2-1 … 2-3: bumper heights
    spans = bumper_spans(w, edge_columns)
    t = {n: _bumper_height(src.pixels((a, 0, b, h)), b - a) for n, (a, b) in spans.items()}
    v["2-1"] = 100.0 * t["t_c"] / h
    v["2-2"] = 100.0 * (t["t_l"] + t["t_r"]) / 2.0 / h
    v["2-3"] = abs(t["t_l"] - t["t_r"])
    bumper_columns = {n: ((a + b - 1) / 2.0, float(h) - t[n], float(t[n]))
                      for n, (a, b) in spans.items()}

    # EC 2-4: no garnish/trunk in the upper region
    rows = int(round(upper_region_fraction * h))
    x0, y0, x1, y1 = src.window("upper_body")
    y1 = min(y1, rows)
    body_up = 0
    if x1 > x0 and y1 > y0:
        body_up = cv2.countNonZero(cv2.LUT(src.pixels((x0, y0, x1, y1)), _LUT_UPPER_BODY))
    v["2-4"] = 1.0 if body_up == 0 else 0.0

    # EC 3-1, 3-2: guideline centres
    g2 = _guide_center(src, "guide2", L.guide_cross(2))
    v["3-1"] = None if g2 is None else abs(g2[0] - (w - 1) / 2.0)
    g3 = _guide_center(src, "guide3", L.guide_cross(3))
    v["3-2"] = None if g3 is None else 100.0 * (g3[1] + 0.5) / h

    # EC 4-1: board aspect
    win = src.window("board")
    sub = src.pixels(win)
    board = None
    if sub.size:
        box = _bbox(_eq(sub, L.BOARD))
        if box is not None:
            board = (box[0] + win[0], box[1] + win[1], box[2], box[3])
    v["4-1"] = None if board is None else board[2] / board[3]

    values = {key: (None if x is None else float(x)) for key, x in v.items()}
    return Measurements(
        values=values, image_size=(w, h), abc_top_row=top_row, bumper_columns=bumper_columns,
        guide2_center=g2, guide3_center=g3, board_box=board, patch_visible=visible,
        upper_region_rows=rows,
    )


def _guide_center(src: LabelSource, group: str, label: int) -> tuple[float, float] | None:
    win = src.window(group)
    sub = src.pixels(win)
    if sub.size == 0:
        return None
    box = _bbox(_eq(sub, label))
    if box is None:
        return None
    x, y, bw, bh = box
    xc = x + (bw - 1) / 2.0
    c0 = max(int(math.floor(xc)) - 1, x)
    c1 = min(int(math.ceil(xc)) + 2, x + bw)
    band = sub[y : y + bh, c0:c1] == label
    rows = np.nonzero(band)[0]
    yc = y + float(rows.mean()) if rows.size else y + (bh - 1) / 2.0
    return (xc + win[0], yc + win[1])


# ---------------------------------------------------------------------------- scoring
@dataclass(frozen=True)
class EcValue:
    """One EC's outcome."""

    id: str
    name: str
    value: float | None
    unit: str
    low: float | None
    high: float | None
    score: float
    passed: bool
    enabled: bool

    def as_dict(self) -> dict[str, Any]:
        return {
            "id": self.id, "name": self.name, "value": self.value, "unit": self.unit,
            "range": [self.low, self.high], "score": self.score, "passed": self.passed,
            "enabled": self.enabled,
        }


@dataclass(frozen=True)
class EcResult:
    """All eleven ECs: their values and scores, the EC score (product of the enabled
    scores) and whether every enabled EC passes its acceptable range."""

    items: tuple[EcValue, ...]
    score: float
    passed: bool
    measurements: Measurements
    criteria_name: str = ""

    def __getitem__(self, ec: str) -> EcValue:
        for item in self.items:
            if item.id == ec:
                return item
        raise KeyError(ec)

    def as_dict(self) -> dict[str, Any]:
        return {"criteria": self.criteria_name, "ec_score": self.score, "passed": self.passed,
                "ecs": [i.as_dict() for i in self.items]}

    def table(self) -> str:
        """A plain-text table for terminals."""
        lines = [f"{'EC':4} {'measurement':26} {'value':>10} {'unit':4} {'range':>15} "
                 f"{'score':>7}  result"]
        for i in self.items:
            val = "—" if i.value is None else f"{i.value:10.3f}"
            rng = f"[{_fmt(i.low)}, {_fmt(i.high)}]"
            res = "off" if not i.enabled else ("pass" if i.passed else "FAIL")
            lines.append(f"{i.id:4} {i.name:26} {val:>10} {i.unit:4} {rng:>15} "
                         f"{i.score:7.3f}  {res}")
        lines.append(f"EC score {self.score:.4g}  ({'all pass' if self.passed else 'not all pass'})")
        return "\n".join(lines)


def _fmt(x: float | None) -> str:
    return "–" if x is None else f"{x:g}"


@dataclass(frozen=True)
class EcBatch:
    """The ECs of many candidates at once (rows; columns in ``EC_IDS`` order): what tuning
    stores for every candidate, without building an :class:`EcResult` per candidate.

    ``values`` is NaN where the measured object is not in the image (``None`` in
    :class:`EcResult`)."""

    values: np.ndarray  # (n, 11) float64
    scores: np.ndarray  # (n, 11) float64
    passed: np.ndarray  # (n, 11) bool
    enabled: np.ndarray  # (11,) bool

    @property
    def score(self) -> np.ndarray:
        """EC score per candidate: the product of the enabled ECs' scores, (n,)."""
        return np.prod(np.where(self.enabled, self.scores, 1.0), axis=1)

    @property
    def all_passed(self) -> np.ndarray:
        """Whether every enabled EC passes, (n,) bool."""
        return np.all(self.passed | ~self.enabled, axis=1)

    def objective(self, floor: float) -> np.ndarray:
        """Σ log(max(score_i, floor)) over the enabled ECs, (n,)."""
        return np.sum(np.where(self.enabled, np.log(np.maximum(self.scores, floor)), 0.0), axis=1)


def values_array(m: Measurements) -> np.ndarray:
    """The eleven measured values in ``EC_IDS`` order, NaN for ``None``: (11,) float64."""
    return np.array([np.nan if m.values.get(ec) is None else m.values[ec] for ec in EC_IDS])


def score_batch(values: np.ndarray, criteria: Criteria) -> EcBatch:
    """Score many candidates' measurements at once (vectorised :meth:`Criterion.score` and
    :meth:`Criterion.passes`; the tests check they agree).

    Parameters
    ----------
    values : (n, 11) float
        Measured values in ``EC_IDS`` order, NaN where not measured.
    criteria : Criteria
    """
    x = np.atleast_2d(np.asarray(values, dtype=np.float64))
    low, high, binary, only_flag, c1, c2, c3, c4, enabled = criteria.arrays
    measured = ~np.isnan(x)
    xs = np.where(measured, x, 0.0)
    with np.errstate(invalid="ignore", over="ignore"):
        # 1/(1 + e^(−z)) = (1 + tanh(z/2))/2, as Sigmoid does; an infinite threshold is 1
        lower = np.where(np.isneginf(c2), 1.0, 0.5 * (1.0 + np.tanh(0.5 * (c1 * (xs - c2)))))
        upper = np.where(np.isposinf(c4), 1.0, 0.5 * (1.0 + np.tanh(0.5 * (-c3 * (xs - c4)))))
    graded = lower * upper
    scores = np.where(measured, np.where(binary, (xs >= 1.0).astype(np.float64), graded), 0.0)
    in_range = (xs >= low) & (xs <= high)
    passed = measured & np.where(only_flag, xs >= 1.0, in_range)
    return EcBatch(x, scores, passed, enabled)


def score(m: Measurements, criteria: Criteria) -> EcResult:
    """Score measurements with a customer's criteria (one candidate; :func:`score_batch`
    scores many at once, and the tests check that the two agree)."""
    items = []
    total = 1.0
    passed = True
    for d in EC_DEFINITIONS:
        c = criteria.items[d.id]
        value = m.values.get(d.id)
        s = float(c.score(value))
        ok = c.passes(value)
        items.append(EcValue(d.id, d.name, value, d.unit, c.low, c.high, s, ok, c.enabled))
        if c.enabled:
            total *= s
            passed &= ok
    return EcResult(tuple(items), total, passed, m, criteria.name)


def evaluate(rvm_labels: np.ndarray, criteria: Criteria | None = None) -> EcResult:
    """Measure and score an RVM label image (the EC score of one ISP parameter set).

    Parameters
    ----------
    rvm_labels : (H, W) uint8
        RVM label image.
    criteria : Criteria, optional
        Default: :func:`default_criteria`.

    Returns
    -------
    EcResult
    """
    criteria = criteria or default_criteria()
    m = measure(rvm_labels, upper_region_fraction=criteria.upper_region_fraction,
                edge_columns=criteria.edge_columns)
    return score(m, criteria)
