"""The console's pictures: the RVM image at the display size (full quality), a draft while
a slider is dragged, and the annotated EC image, addressed by their parameters and kept in a
small cache.

A picture is named by what it shows (its kind and the 14 parameter values), never by a
frame number: any picture URL the page holds can be answered at any time (a pinned B, a
reload, the A/B view), from the cache or by rendering it again.  Rendering works on a BGR
copy of the fisheye image made once (no per-picture channel flip), reuses the ray planes of
views seen before (:class:`rvmsim.isp.RayCache`, for FOV, RAD and shift changes) and encodes
with ``cv2.imencode``.
"""

from __future__ import annotations

import math
import threading
from collections import OrderedDict
from typing import TYPE_CHECKING

import cv2
import numpy as np

from ..errors import RvmsimError
from ..isp import PARAM_SPECS, IspParams, OutputSpec, RayCache, map_nodes, remap_xy
from ..pipeline import evaluate_params
from .inputs import ConsoleInputError

if TYPE_CHECKING:
    from .session import ConsoleSession

__all__ = ["Pictures", "PICTURE_KINDS", "params_key", "parse_params_key", "FULL_QUALITY",
           "DRAFT_QUALITY"]

#: What a picture can be: the display picture, its draft, the annotated EC image.
PICTURE_KINDS = ("display", "draft", "annotated")
#: JPEG quality of the display and annotated pictures, and of drafts.
FULL_QUALITY = 85
DRAFT_QUALITY = 70
#: Pictures kept (about 100–250 kB each at 1280 × 720).
_KEPT = 48
_NAMES = tuple(s.name for s in PARAM_SPECS)


def params_key(params: IspParams) -> str:
    """The 14 values, comma-separated in :data:`rvmsim.isp.PARAM_SPECS` order (shortest
    round-trip form): the ``p`` query of a picture URL."""
    return ",".join(repr(float(getattr(params, n))) for n in _NAMES)


def parse_params_key(text: str) -> IspParams:
    """The parameters of a picture URL's ``p`` (see :func:`params_key`).

    Raises
    ------
    ConsoleInputError
        Not 14 numbers, or a value outside its parameter's range.
    """
    parts = text.split(",")
    if len(parts) != len(_NAMES):
        raise ConsoleInputError("p", f"expected {len(_NAMES)} comma-separated numbers")
    values: dict[str, float] = {}
    for spec, part in zip(PARAM_SPECS, parts):
        try:
            value = float(part)
        except ValueError:
            raise ConsoleInputError(spec.name, f"must be a number, got {part[:20]!r}") from None
        problem = spec.problem(value)
        if problem is not None:
            raise ConsoleInputError(spec.name, problem)
        values[spec.name] = value
    return IspParams(**values)


def _jpeg(bgr: np.ndarray, quality: int) -> bytes:

    ok, buf = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise RvmsimError("console: JPEG encoding failed")
    return buf.tobytes()


class _SharedRays(RayCache):
    """A :class:`RayCache` that several request threads may use at once."""

    def __init__(self, size: int) -> None:
        super().__init__(size)
        self._lock = threading.Lock()

    def planes(self, params: IspParams, output: OutputSpec,
               cell: int) -> tuple[np.ndarray, np.ndarray]:
        with self._lock:
            return super().planes(params, output, cell)


class Pictures:
    """The pictures of one console session (thread-safe)."""

    def __init__(self, session: ConsoleSession) -> None:

        self.session = session
        self._bgr = cv2.cvtColor(session.images.color, cv2.COLOR_RGB2BGR)
        self._rays = _SharedRays(64)
        self._lock = threading.Lock()
        # one full-size render at a time: with several pages, renders queue here and leave
        # the other core to the evaluations (whose answers, with their drafts, come first)
        self._rendering = threading.Lock()
        self._kept: OrderedDict[tuple[str, IspParams], bytes] = OrderedDict()
        d, e = session.display, session.ec_output
        #: the EC image is the draft when it is the display's view at a lower resolution
        self.ec_is_draft = (e.width < d.width and e.mirror == d.mirror
                            and math.isclose(e.width / e.height, d.width / d.height,
                                             rel_tol=1e-3))
        self.draft_output = (e if self.ec_is_draft
                             else OutputSpec(max(1, d.width // 2), max(1, d.height // 2),
                                             d.mirror))

    def cached(self, kind: str, params: IspParams) -> bytes | None:
        with self._lock:
            data = self._kept.get((kind, params))
            if data is not None:
                self._kept.move_to_end((kind, params))
            return data

    def keep(self, kind: str, params: IspParams, data: bytes) -> bytes:
        with self._lock:
            self._kept[(kind, params)] = data
            while len(self._kept) > _KEPT:
                self._kept.popitem(last=False)
        return data

    def render_bgr(self, params: IspParams, output: OutputSpec) -> np.ndarray:
        """The RVM colour image of ``params`` at ``output`` (BGR uint8): the pixels of
        :func:`rvmsim.pipeline.rvm_color` (the same map and bilinear remap), channels
        swapped."""

        size = (self._bgr.shape[1], self._bgr.shape[0])
        nodes = map_nodes(params, size, output, rays=self._rays)
        xy = nodes.window((0, 0, output.width, output.height))
        return remap_xy(self._bgr, xy, cv2.INTER_LINEAR, 0)

    def display(self, params: IspParams) -> bytes:
        """The full-quality picture (display size, JPEG)."""
        data = self.cached("display", params)
        if data is None:
            with self._rendering:
                data = self.cached("display", params)  # made while this one waited?
                if data is None:
                    data = self.keep("display", params, _jpeg(
                        self.render_bgr(params, self.session.display), FULL_QUALITY))
        return data

    def draft(self, params: IspParams, ec_color: np.ndarray | None = None) -> bytes:
        """The draft picture: the EC image (``ec_color``, RGB, when the evaluation has just
        made it) when it is the same view, else the view at half the display size; JPEG at
        :data:`DRAFT_QUALITY`."""

        data = self.cached("draft", params)
        if data is None:
            if ec_color is not None and self.ec_is_draft:
                bgr = cv2.cvtColor(ec_color, cv2.COLOR_RGB2BGR)
            else:
                bgr = self.render_bgr(params, self.draft_output)
            data = self.keep("draft", params, _jpeg(bgr, DRAFT_QUALITY))
        return data

    def annotated(self, params: IspParams, drawn: np.ndarray | None = None) -> bytes:
        """The EC image with its measurements drawn (``drawn``, RGB, when already made)."""

        data = self.cached("annotated", params)
        if data is None:
            if drawn is None:
                s = self.session
                drawn = evaluate_params(s.images, params, s.ec_output, s.criteria).annotated
                assert drawn is not None  # evaluate_params annotates by default
            data = self.keep("annotated", params,
                             _jpeg(cv2.cvtColor(drawn, cv2.COLOR_RGB2BGR), FULL_QUALITY))
        return data

    def picture(self, kind: str, params: IspParams) -> bytes:
        """The picture of ``kind`` (one of :data:`PICTURE_KINDS`)."""
        if kind == "display":
            return self.display(params)
        if kind == "draft":
            return self.draft(params)
        if kind == "annotated":
            return self.annotated(params)
        raise ConsoleInputError("kind", f"no picture {kind!r} (one of {', '.join(PICTURE_KINDS)})",
                                404)
