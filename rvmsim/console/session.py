"""What the console works on: a run (or a scene), its fisheye images rendered once, and the
evaluation of one parameter set as the page shows it.

Convention
----------
The ECs are judged at the **RVM image of record** (:func:`rvmsim.pipeline.record_output`:
the scene's or criteria's ``display.rvm_image_px``, default 1280 × 720), where
``rvmsim evaluate --params FILE`` judges too, whatever size the run searched at: the page's
verdict is the display's.  They come from the windowed evaluator (the same values as the
full path, tested); the picture is the same view at that size; the annotated picture is the
EC image of record with its measurements drawn (with its results panel).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np

from ..criteria import annotate as annotate_ecs
from ..criteria import load_criteria
from ..errors import RvmsimError
from ..isp import PARAM_SPECS, IspParams, OutputSpec, roi_outline
from ..pipeline import evaluate_params, make_evaluator, record_output, rvm_color
from ..render import cached_render
from ..runs import is_run_folder, open_run, run_inputs, run_settings, store_candidates
from ..scene import load_scene
from ..search import TuningConfig
from ..tune import member_set
from .candidates import Candidate

if TYPE_CHECKING:
    from ..criteria import Criteria, EcResult
    from ..pipeline import ImageEvaluator
    from ..render import FisheyeImages
    from ..scene import Scene

__all__ = ["ParamControl", "ConsoleSession", "ConsoleFrame", "open_session", "evaluate_setting",
           "jpeg_bytes", "CONSOLE_DIR", "human_name", "ec_margin", "HUMAN_NAMES"]

#: The folder, inside the run folder (or the scene's ``out/<scene>/``), that the console
#: writes its params files and reports into.
CONSOLE_DIR = "console"
#: JPEG quality of the pictures sent to the page.
JPEG_QUALITY = 85
#: What the page calls each parameter (its sliders' accessible names add the short name).
HUMAN_NAMES = {
    "fov": "Field of view", "rad": "Image-circle radius", "h_shift": "Horizontal shift",
    "v_shift": "Vertical shift", "h_pan": "Horizontal pan", "v_pan": "Vertical pan",
    "zoom": "Zoom", "tilt": "Tilt", "adv_h_shift": "Advanced horizontal shift",
    "adv_v_shift": "Advanced vertical shift", "adv_h_scale": "Advanced horizontal scale",
    "adv_v_scale": "Advanced vertical scale", "theta": "Image-plane tilt theta",
    "phi": "Image-plane tilt azimuth phi",
}


def human_name(name: str) -> str:
    """A parameter's name for people ("Advanced vertical shift" for ``adv_v_shift``)."""
    return HUMAN_NAMES.get(name, name.replace("_", " ").capitalize())


def ec_margin(value: float | None, low: float | None, high: float | None) -> float | None:
    """How far inside (> 0) or outside (< 0) its acceptable range an EC's value is, as a
    fraction of the range's scale: the half-width of a two-sided range (1 at its middle,
    0 at a bound), the bound's magnitude for a one-sided one (1 when that is 0); ±1 for a
    single acceptable value (met or not).  None without a value or a range."""
    if value is None or not np.isfinite(value) or (low is None and high is None):
        return None
    if low is not None and high is not None:
        if high <= low:
            return 1.0 if value == low else -1.0
        return float(min(value - low, high - value) / ((high - low) / 2.0))
    if low is not None:
        return float((value - low) / (abs(low) or 1.0))
    assert high is not None
    return float((high - value) / (abs(high) or 1.0))


@dataclass(frozen=True)
class ParamControl:
    """One parameter's control on the page: the slider spans ``[low, high]`` (the search
    range of a tuned parameter, else the parameter's whole range), the number box accepts
    ``[spec_low, spec_high]`` (the range :class:`~rvmsim.isp.IspParams` accepts)."""

    name: str
    paper_name: str
    symbol: str
    unit: str
    note: str
    tuned: bool
    low: float
    high: float
    spec_low: float
    spec_high: float
    default: float

    def as_json(self) -> dict[str, Any]:
        return dict(self.__dict__)


@dataclass(frozen=True)
class ConsoleSession:
    """Everything the console serves, loaded once at start.

    ``run_dir`` is None for a scene without a run; ``save_dir`` is where the console
    writes (``RUN/console``, or ``out/<scene>/console`` for a scene); ``root`` is the folder
    it may never write outside of (the run folder, or ``out/<scene>``).
    """

    source: Path
    run_dir: Path | None
    root: Path
    save_dir: Path
    scene: Scene = field(repr=False)
    scene_file: Path
    images: FisheyeImages = field(repr=False)
    criteria: Criteria = field(repr=False)
    ec_output: OutputSpec
    display: OutputSpec
    start: IspParams
    controls: tuple[ParamControl, ...] = field(repr=False)
    candidates: tuple[Candidate, ...] = field(repr=False)
    fisheye_jpeg: bytes = field(repr=False)
    #: The size the run searched at (its params files' ``output``; None: ``ec_output``).
    search_output: OutputSpec | None = None
    #: The ECs at ``ec_output`` (the windowed evaluator; one call at a time, see :meth:`ecs`).
    evaluator: ImageEvaluator | None = field(default=None, repr=False)
    _evaluating: threading.Lock = field(default_factory=threading.Lock, repr=False)

    @property
    def kind(self) -> str:
        return "run" if self.run_dir is not None else "scene"

    def ecs(self, params: IspParams) -> EcResult:
        """The ECs of ``params`` at the RVM image of record (the requests' threads take
        turns: the evaluator's ray cache is not shared between threads)."""
        if self.evaluator is None:
            return evaluate_params(self.images, params, self.ec_output, self.criteria,
                                   annotate=False).ec
        with self._evaluating:
            return self.evaluator(params)


@dataclass(frozen=True)
class ConsoleFrame:
    """One parameter set as the page shows it: its ECs (at the EC output size), the
    picture at the display size (JPEG), the annotated EC image (JPEG, when asked), the ROI
    outline in fisheye px, and the time each step took (ms)."""

    params: IspParams
    ec: EcResult = field(repr=False)
    display_jpeg: bytes = field(repr=False)
    annotated_jpeg: bytes | None = field(repr=False)
    roi: list[list[float]] = field(repr=False)
    timings_ms: dict[str, float]


def jpeg_bytes(image: np.ndarray, quality: int = JPEG_QUALITY) -> bytes:
    """``image`` ((H, W, 3) RGB uint8) encoded as JPEG."""

    ok, buf = cv2.imencode(".jpg", cv2.cvtColor(image, cv2.COLOR_RGB2BGR),
                           [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise RvmsimError("console: JPEG encoding failed")
    return buf.tobytes()


def _controls(config: TuningConfig, scene: Scene) -> tuple[ParamControl, ...]:
    """The 14 controls, the tuned ones first (in the search space's order)."""
    ranges = {r.name: r for r in config.space(scene.fisheye_camera()).ranges}
    order = [*ranges, *(s.name for s in PARAM_SPECS if s.name not in ranges)]
    specs = {s.name: s for s in PARAM_SPECS}
    out = []
    for name in order:
        s, r = specs[name], ranges.get(name)
        out.append(ParamControl(s.name, s.paper_name, s.symbol, s.unit, s.note, r is not None,
                                r.low if r else s.low, r.high if r else s.high, s.low, s.high,
                                s.default))
    return tuple(out)


def open_session(source: str | Path, *, out_root: str | Path = "out") -> ConsoleSession:
    """Load a run folder (its scene, criteria, tuning config and candidates; it starts at
    rank 1) or a scene file (the paper's defaults, the default tuning config; it writes
    into ``out_root/<scene file stem>/console``), and render the fisheye images once (the
    render cache, as ``tune`` does).

    Raises
    ------
    RvmsimError
        One line: no such run or scene, an unreadable run, scene or criteria file, a run
        without candidates.
    """

    source = Path(source)
    if source.is_dir():
        if not is_run_folder(source):
            raise RvmsimError(f"{source}: not a run folder (no run.sqlite) and not a scene file")
        store = open_run(source)
        try:
            settings = run_settings(source, store)
            scene_file, crit_file = run_inputs(source, settings)
            kind = member_set(settings)
            scene, criteria = kind.shown(load_scene(scene_file), load_criteria(crit_file))
            candidates = tuple(c for c, _ in store_candidates(store, settings,
                                                              criteria=criteria))
        finally:
            store.close()
        config, run_dir, root = settings.config, source, source
        if not candidates:
            raise RvmsimError(f"{source}: no evaluated candidates yet")
        start = candidates[0].params
    elif source.is_file():
        scene_file, config, run_dir = source, TuningConfig(), None
        scene, criteria = load_scene(scene_file), load_criteria(None)
        root, candidates, start = Path(out_root) / source.stem, (), IspParams()
    else:
        raise RvmsimError(f"{source}: no such run folder or scene file")
    images, _ = cached_render(scene)

    ec_output = record_output(criteria, scene, config.output.mirror)
    return ConsoleSession(
        source=source, run_dir=run_dir, root=root, save_dir=root / CONSOLE_DIR, scene=scene,
        scene_file=scene_file, images=images, criteria=criteria, ec_output=ec_output,
        display=ec_output, start=start,
        controls=_controls(config, scene), candidates=candidates,
        fisheye_jpeg=jpeg_bytes(images.color),
        search_output=config.output_spec(), evaluator=make_evaluator(images, ec_output, criteria))


def evaluate_setting(session: ConsoleSession, params: IspParams, *,
                     annotate: bool = False) -> ConsoleFrame:
    """Evaluate ``params`` as the page shows it: the ECs at the EC output size (the one
    evaluation path, :func:`rvmsim.pipeline.evaluate_params`), the picture at the display
    size, and, with ``annotate``, the EC image with its measurements drawn."""

    t0 = time.perf_counter()
    ec = session.ecs(params)
    t1 = time.perf_counter()
    display = jpeg_bytes(rvm_color(session.images, params, session.display))
    t2 = time.perf_counter()
    annotated = None
    if annotate:
        frame = evaluate_params(session.images, params, session.ec_output, session.criteria,
                                annotate=False)
        annotated = jpeg_bytes(annotate_ecs(frame.color, frame.labels, frame.ec))
    t3 = time.perf_counter()
    poly = roi_outline(params, (session.images.color.shape[1], session.images.color.shape[0]),
                       session.ec_output, samples_per_side=32)
    roi = [[round(float(x), 2), round(float(y), 2)] for x, y in poly[np.isfinite(poly).all(1)]]
    t4 = time.perf_counter()
    ms = {"ecs": t1 - t0, "display": t2 - t1, "annotated": t3 - t2, "roi": t4 - t3}
    return ConsoleFrame(params, ec, display, annotated, roi,
                        {k: round(1e3 * v, 2) for k, v in ms.items()})
