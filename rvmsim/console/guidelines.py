"""The parking guidelines in the console: the lines over the live picture and their ground
error for the setting shown (issue #46).

The lines come from :func:`rvmsim.guidelines.compute_guidelines` through the setting's view
(the scene's camera, the setting, the console's display of record): a few ms, made with every
frame the page asks them for.  Their **ground error** is the renderer check of
:mod:`rvmsim.guidelines.check`: the same lines painted on the site's ground, rendered once
per group (the static lines; the trajectory lines of one steering angle) and measured per
setting with :func:`~rvmsim.guidelines.check.measure_painted` (tens of ms).  The painted
renders do not depend on the ISP setting, so each is made once per console, in a background
thread (a render takes a few seconds at full size): until it is in, a group's error is
``"measuring"`` and the page asks again.

Convention
----------
Display px of the console's display (``session.display``), pixel centres at integer
coordinates; steering as a percentage of the car's steering range (−100 … +100 %, positive
toward +X), and the steering-wheel angle in degrees.
"""

from __future__ import annotations

import logging
import threading
from collections import OrderedDict
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ..errors import RvmsimError
from ..guidelines import (GroundLine, GuidelineView, RunningGear, compute_guidelines,
                          running_gear, scene_spec, static_lines, trajectory_lines)
from ..guidelines.check import LineCheck, measure_painted, painted_scene
from ..guidelines.project import DisplayLine
from ..isp import IspParams
from ..render import RenderProcess, cached_render
from ..scene import GuidelineSpec, PaintedLine, scene_vehicle_width
from .inputs import ConsoleInputError

if TYPE_CHECKING:
    from .session import ConsoleSession

__all__ = ["ConsoleGuidelines", "GroupError", "STATIC", "steering_key", "MAX_PENDING",
           "KEPT_RENDERS"]

_log = logging.getLogger("rvmsim.console")

#: The key of the static lines' painted render (trajectory groups: their angle, degrees).
STATIC = "static"
#: Trajectory renders waiting at most (the oldest wish is dropped: the page asks again).
MAX_PENDING = 4
#: Trajectory renders kept in memory (the static one always is).
KEPT_RENDERS = 24
#: Measurements kept (per setting and group).
_KEPT_MEASURES = 64

GroupKey = str | float
Status = Literal["measuring", "ready", "failed"]


def steering_key(pct: float, range_deg: float) -> float:
    """The steering-wheel angle (degrees, rounded to 1e-6) of ``pct`` % of the range."""
    return round(float(pct) / 100.0 * range_deg, 6) + 0.0


@dataclass(frozen=True)
class _Painted:
    """A group's painted render: the fisheye labels and the painted lines they carry (or
    why the render failed)."""

    labels: np.ndarray | None
    lines: tuple[PaintedLine, ...]
    failed: str | None = None


@dataclass(frozen=True)
class GroupError:
    """One group's ground error for one setting.

    Attributes
    ----------
    status : str
        ``"measuring"`` (its painted render is not in yet), ``"ready"`` or ``"failed"``.
    lines : tuple of LineCheck
        Each line's check (when ready).
    why : str
        What failed (when failed).
    """

    status: Status
    lines: tuple[LineCheck, ...] = ()
    why: str = ""

    def as_json(self) -> dict[str, Any]:
        """The page's view: per line its offset in display px and on the ground in cm
        (None: not measured, e.g. out of the picture), and the worst line."""
        rows = [_line_json(c) for c in self.lines]
        measured = [r for r in rows if r["offset_px"] is not None]
        worst = max(measured, key=lambda r: r["offset_px"]) if measured else None
        return {"status": self.status, "why": self.why, "lines": rows, "worst": worst}


def _finite(x: float) -> float | None:
    return round(float(x), 3) if np.isfinite(x) else None


def _line_json(c: LineCheck) -> dict[str, Any]:
    return {"name": c.name, "kind": c.kind, "steering_deg": c.steering_deg,
            "offset_px": _finite(c.offset_px), "offset_cm": _finite(c.offset_cm),
            "scans": int(len(c.offsets_px))}


def _hex(color: tuple[float, float, float]) -> str:
    return "#" + "".join(f"{int(round(min(max(c, 0.0), 1.0) * 255)):02x}" for c in color)


def _display_json(line: DisplayLine) -> dict[str, Any]:
    return {"name": line.name, "kind": line.kind, "color": _hex(line.color),
            "steering_deg": line.steering_deg,
            "pieces": [np.round(p.uv_px, 2).tolist() for p in line.pieces]}


class ConsoleGuidelines:
    """The guidelines of one console session (thread-safe).

    ``available`` says whether the scene can have them (its ``vehicle`` carries the running
    gear); when not, ``why`` says what is missing and every request for them is refused
    (409).  The painted renders are made by one background thread while any is wished
    for (started by the first wish, ended when none is left), the static lines first, then
    the newest wish.
    """

    def __init__(self, session: ConsoleSession) -> None:
        self.session = session
        self.gear: RunningGear | None = None
        self.spec: GuidelineSpec = scene_spec(session.scene)
        self.width_m = float("nan")
        self.why: str | None = None
        try:
            self.gear = running_gear(session.scene)
            self.width_m = scene_vehicle_width(session.scene)
        except RvmsimError as err:
            self.gear, self.why = None, f"no guidelines: {err}"
        self._lock = threading.Lock()
        self._painted: OrderedDict[GroupKey, _Painted] = OrderedDict()
        self._pending: OrderedDict[GroupKey, None] = OrderedDict()
        self._measured: OrderedDict[tuple[IspParams, GroupKey], GroupError] = OrderedDict()
        self._worker: threading.Thread | None = None

    @property
    def available(self) -> bool:
        return self.gear is not None

    @property
    def range_deg(self) -> float:
        """The steering range (±100 %), steering-wheel degrees (NaN when unavailable)."""
        return self.gear.steering_range_deg if self.gear is not None else float("nan")

    def as_json(self) -> dict[str, Any]:
        """What the page needs to offer them: whether it can, why not, the range, the line
        width (display px)."""
        return {"available": self.available, "why": self.why,
                "steering_range_deg": self.range_deg if self.available else None,
                "line_width_px": float(self.spec.line_width_px)}

    def _need(self) -> RunningGear:
        if self.gear is None:
            raise ConsoleInputError("guidelines", self.why or "no guidelines", 409)
        return self.gear

    def view(self, params: IspParams) -> GuidelineView:
        """The view the lines are drawn through: the scene's camera, ``params``, the
        console's display."""
        return GuidelineView(self.session.scene.fisheye_camera(), params, self.session.display)

    # ------------------------------------------------------------------ the lines
    def lines_json(self, params: IspParams, pct: float) -> dict[str, Any]:
        """The static lines and the trajectory lines of ``pct`` % of the steering range
        through ``params``: per line its colour and pieces (display px)."""
        gear = self._need()
        deg = steering_key(pct, gear.steering_range_deg)
        gset = compute_guidelines(self.session.scene, self.view(params), (deg,), spec=self.spec)
        out = self.session.display
        return {"steering_pct": float(pct), "steering_deg": deg,
                "output": {"width": out.width, "height": out.height},
                "line_width_px": float(self.spec.line_width_px),
                "lines": [_display_json(line) for line in gset.at(deg)]}

    # ------------------------------------------------------------------ the ground error
    def error(self, params: IspParams, pct: float) -> dict[str, Any]:
        """The ground error of ``params``' lines: ``static`` and ``trajectory`` (at ``pct``
        % of the steering range), each a :class:`GroupError`'s JSON; a group whose painted
        render is not in yet is ``"measuring"`` (its render is asked for)."""
        gear = self._need()
        deg = steering_key(pct, gear.steering_range_deg)
        return {"steering_pct": float(pct), "steering_deg": deg,
                "static": self.group_error(params, STATIC).as_json(),
                "trajectory": self.group_error(params, deg).as_json()}

    def group_error(self, params: IspParams, key: GroupKey) -> GroupError:
        """One group's ground error for ``params`` (see :meth:`error`)."""
        with self._lock:
            painted = self._painted.get(key)
            if painted is not None:
                self._painted.move_to_end(key)
            done = self._measured.get((params, key))
        if done is not None:
            return done
        if painted is None:
            self._ask(key)
            return GroupError("measuring")
        if painted.failed is not None:
            return GroupError("failed", why=painted.failed)
        assert painted.labels is not None
        result = GroupError("ready", tuple(measure_painted(painted.labels, self.view(params),
                                                           painted.lines)))
        with self._lock:
            self._measured[(params, key)] = result
            while len(self._measured) > _KEPT_MEASURES:
                self._measured.popitem(last=False)
        return result

    def ground_lines(self, key: GroupKey) -> list[GroundLine]:
        """The ground lines of a group (the static lines, or one angle's trajectories)."""
        gear = self._need()
        if key == STATIC:
            return static_lines(self.width_m, self.spec)
        return trajectory_lines(gear, self.width_m, self.spec, float(key))

    def _ask(self, key: GroupKey) -> None:
        """Put ``key``'s painted render at the front of the wishes (start the worker)."""
        with self._lock:
            if key in self._painted:
                return
            self._pending[key] = None
            self._pending.move_to_end(key)
            while len(self._pending) > MAX_PENDING + 1:  # the static group counts once
                oldest = next(k for k in self._pending if k != STATIC)
                del self._pending[oldest]
            if self._worker is None:
                self._worker = threading.Thread(target=self._work, name="rvmsim-guidelines",
                                                daemon=True)
                self._worker.start()

    def _next(self) -> GroupKey | None:
        with self._lock:
            if not self._pending:
                return None
            # the static group first (every frame needs it), then the newest wish
            key = STATIC if STATIC in self._pending else next(reversed(self._pending))
            del self._pending[key]
            return key

    def _work(self) -> None:
        """The background thread: paint, render and keep each wished group, in one render
        worker, until no wish is left (then the thread ends; the next wish starts another)."""
        while True:
            with RenderProcess():
                while (key := self._next()) is not None:
                    self._keep(key, self._render(key))
            with self._lock:
                if not self._pending:
                    self._worker = None
                    return

    def _render(self, key: GroupKey) -> _Painted:
        """``key``'s group painted on the ground and rendered (the render cache), or why
        not."""
        try:
            lines = self.ground_lines(key)
            if not lines:
                return _Painted(np.zeros((0, 0), np.uint8), ())
            scene = painted_scene(self.session.scene, lines)
            labels = cached_render(scene)[0].labels
        except RvmsimError as err:
            return _Painted(None, (), failed=str(err))
        except Exception as err:  # noqa: BLE001 - the page says so; the console keeps serving
            _log.exception("console: the guidelines' painted render failed")
            return _Painted(None, (), failed=f"render failed ({type(err).__name__}); "
                                             "see the console's terminal")
        return _Painted(labels, scene.test_site.painted_lines)

    def _keep(self, key: GroupKey, painted: _Painted) -> None:
        with self._lock:
            self._painted[key] = painted
            trajectories = [k for k in self._painted if k != STATIC]
            for old in trajectories[:max(0, len(trajectories) - KEPT_RENDERS)]:
                del self._painted[old]
