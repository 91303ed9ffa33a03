"""The console's web app (FastAPI): the page, its assets and a small JSON API.

Routes: ``GET /`` (the page), ``/static/…`` (its JS and CSS, from the package),
``GET /api/session`` (scene, controls, start values, candidates), ``GET /api/fisheye.jpg``,
``GET /api/evaluate?q=JSON`` (a parameter set → its ECs, margins, ROI and picture URLs, and
with ``draft`` and ``inline`` the draft picture itself, base64; a GET: it changes nothing), ``GET /api/picture/{display|draft|annotated}.jpg?p=VALUES`` (the
picture of a parameter set, :mod:`.pictures`), ``GET /api/guidelines?q=JSON`` (a parameter
set's parking guidelines and their ground error, :mod:`.guidelines`; a GET too),
``POST /api/save``, ``POST /api/report``.

Every request passes :class:`~.guard.Guard` first (token or loopback ``Host``, the origin,
JSON bodies for writes, size limits).  Every error is a JSON ``{"error": "…", "key": "…"}``
(4xx for bad input), never a traceback.

Evaluations run in worker threads, several at once (one per request: the pages each keep
at most one evaluation and one picture in flight), so three pages on two cores share them.
"""

from __future__ import annotations

import base64
import itertools
import json
import logging
import secrets
import shlex
import time
from pathlib import Path
from collections.abc import Callable
from typing import Any

import numpy as np
from fastapi import FastAPI, Request
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException as StarletteHTTPException

from ..errors import RvmsimError
from ..isp import IspParams, params_to_dict, roi_outline
from .candidates import candidate_json
from .guard import LOOPBACK_HOSTS, MAX_BODY_BYTES, MAX_TARGET_BYTES, TOKEN_HEADER, Guard
from .guidelines import ConsoleGuidelines
from .inputs import (ConsoleInputError, parse_flag, parse_label, parse_params,
                     parse_steering)
from .outputs import save_params, write_setting_report
from .pictures import PICTURE_KINDS, Pictures, params_key, parse_params_key
from .session import ConsoleFrame, ConsoleSession, ec_margin, human_name
from ..pipeline import evaluate_params

__all__ = ["create_app", "session_json", "TOKEN_HEADER", "LOOPBACK_HOSTS", "MAX_BODY_BYTES",
           "MAX_TARGET_BYTES", "evaluate_command"]

STATIC = Path(__file__).resolve().parent / "static"
_log = logging.getLogger("rvmsim.console")


def _error(status: int, message: str, key: str = "") -> JSONResponse:
    return JSONResponse({"error": message, "key": key}, status_code=status,
                        headers={"Cache-Control": "no-store"})


def session_json(session: ConsoleSession) -> dict[str, Any]:
    """What the page is built from (every string is set as text by the page, never HTML)."""
    sc, im = session.scene, session.images.color
    return {
        "vehicle": sc.name, "description": sc.description, "kind": session.kind,
        "source": str(session.source), "save_dir": str(session.save_dir.resolve()),
        "scene_file": str(session.scene_file.resolve()),
        "criteria": session.criteria.name,
        "ec_output": {"width": session.ec_output.width, "height": session.ec_output.height,
                      "mirror": session.ec_output.mirror},
        "display": {"width": session.display.width, "height": session.display.height},
        "fisheye": {"width": int(im.shape[1]), "height": int(im.shape[0]),
                    "url": "/api/fisheye.jpg"},
        "controls": [{**c.as_json(), "human": human_name(c.name)} for c in session.controls],
        "order": list(IspParams.names()),
        "start": params_to_dict(session.start),
        "candidates": [candidate_json(c) for c in session.candidates],
    }


def evaluate_command(session: ConsoleSession, params_file: Path) -> str:
    """The shell command that reproduces a saved file's ECs: ``rvmsim evaluate SCENE
    --params FILE`` (absolute paths, quoted for a POSIX shell)."""
    return shlex.join(["rvmsim", "evaluate", str(session.scene_file.resolve()), "--params",
                       str(params_file.resolve())])


def _json_object(raw: bytes | str) -> dict[str, Any]:
    """A JSON object from the browser (413 too large, 400 not JSON, 422 not an object)."""
    if len(raw) > MAX_BODY_BYTES:
        raise ConsoleInputError("", f"request body over {MAX_BODY_BYTES} bytes", 413)
    try:
        doc = json.loads(raw or b"{}")
    except (ValueError, RecursionError):
        raise ConsoleInputError("", "the request body is not JSON", 400) from None
    if not isinstance(doc, dict):
        raise ConsoleInputError("", "the request body must be a JSON object")
    return doc


async def _body(request: Request) -> dict[str, Any]:
    """The request body's JSON object (:func:`_json_object`; the guard has already cut it
    off at the limit)."""
    return _json_object(await request.body())


def _errors(app: FastAPI) -> None:
    @app.exception_handler(ConsoleInputError)
    async def bad_input(request: Request, err: ConsoleInputError) -> JSONResponse:
        return _error(err.status, str(err), err.key)

    @app.exception_handler(RvmsimError)
    async def failed(request: Request, err: RvmsimError) -> JSONResponse:
        return _error(500, str(err))

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, err: StarletteHTTPException) -> JSONResponse:
        return _error(err.status_code, str(err.detail))

    @app.exception_handler(Exception)
    async def internal(request: Request, err: Exception) -> JSONResponse:
        _log.exception("console: internal error on %s", request.url.path)  # logged, not sent
        return _error(500, f"internal error ({type(err).__name__}); see the console's terminal")


def _roi(session: ConsoleSession, params: IspParams) -> list[list[float]]:
    poly = roi_outline(params, (session.images.color.shape[1], session.images.color.shape[0]),
                       session.ec_output, samples_per_side=32)
    return [[round(float(x), 2), round(float(y), 2)] for x, y in poly[np.isfinite(poly).all(1)]]


def _evaluation(session: ConsoleSession, pictures: Pictures, doc: dict[str, Any], frame_id: int,
                picture_url: Callable[[str, IspParams], str],
                guides: ConsoleGuidelines) -> dict[str, Any]:
    """One ``/api/evaluate`` answer: the ECs at the RVM image of record, the ROI, the
    draft or annotated picture when asked (``frame_id``: the answer's number), and with
    ``guidelines`` (a steering angle, % of the range) the parking guidelines of the same
    setting (``guides``), so the page draws them with the picture they belong to."""

    params = parse_params(doc.get("params", {}), session.start)
    annotate = parse_flag(doc.get("annotate"), "annotate")
    draft = parse_flag(doc.get("draft"), "draft")
    inline = parse_flag(doc.get("inline"), "inline")
    steer = doc.get("guidelines")
    pct = None if steer is None else parse_steering(steer, "guidelines")
    t0 = time.perf_counter()
    color = None
    if annotate:  # the whole EC image of record, drawn
        frame = evaluate_params(session.images, params, session.ec_output,
                                session.criteria, annotate=True)
        ec_result, color = frame.ec, frame.color
        pictures.annotated(params, frame.annotated)
    else:  # the windowed evaluator at the size of record: the same values, faster
        ec_result = session.ecs(params)
    t1 = time.perf_counter()
    draft_jpeg = pictures.draft(params, color) if draft else b""
    t2 = time.perf_counter()
    roi = _roi(session, params)
    t3 = time.perf_counter()
    lines = None if pct is None else guides.lines_json(params, pct)
    t4 = time.perf_counter()
    ec = ec_result.as_dict()
    for item, value in zip(ec["ecs"], ec_result.items):
        item["yes_no"] = value.yes_no  # ✓/✗, no margin bar (EcValue.margin_text)
        item["margin"] = None if value.yes_no else ec_margin(item["value"], *item["range"])
    ms = {"ecs": t1 - t0, "pictures": t2 - t1, "roi": t3 - t2, "guidelines": t4 - t3}
    return {"frame": frame_id, "params": params_to_dict(params), **ec, "roi": roi,
            "image": picture_url("display", params),
            "draft": picture_url("draft", params) if draft else None,
            "annotated": picture_url("annotated", params) if annotate else None,
            # the draft itself, when asked: one round trip per frame while dragging
            **({"draft_jpeg": base64.b64encode(draft_jpeg).decode()} if draft and inline
               else {}),
            "guidelines": lines,
            "timings_ms": {k: round(1e3 * v, 2) for k, v in ms.items()}}


def _guidelines(session: ConsoleSession, guides: ConsoleGuidelines, doc: dict[str, Any]
                ) -> dict[str, Any]:
    """One ``/api/guidelines`` answer: the guidelines of ``doc``'s ``params`` at its
    ``steering_pct`` (% of the steering range) and their ground error (a group whose painted
    render is not in yet: ``"measuring"``)."""
    params = parse_params(doc.get("params", {}), session.start)
    pct = parse_steering(doc.get("steering_pct"))
    t0 = time.perf_counter()
    lines = guides.lines_json(params, pct)
    t1 = time.perf_counter()
    error = guides.error(params, pct)
    t2 = time.perf_counter()
    return {"params": params_to_dict(params), **lines, "error": error,
            "timings_ms": {"lines": round(1e3 * (t1 - t0), 2),
                           "error": round(1e3 * (t2 - t1), 2)}}


def create_app(session: ConsoleSession, *, token: str | None = None) -> Guard:
    """The console app of ``session`` behind its :class:`~.guard.Guard`; ``token``:
    required on every request (None: no token, and loopback ``Host`` names only)."""
    app = FastAPI(title="rvmsim console", docs_url=None, redoc_url=None, openapi_url=None)
    pictures = Pictures(session)
    guides = ConsoleGuidelines(session)
    server = secrets.token_hex(6)  # in picture URLs: no browser cache of another console
    frames = itertools.count(1)
    _errors(app)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")

    def picture_url(kind: str, params: IspParams) -> str:
        return f"/api/picture/{kind}.jpg?v={server}&p={params_key(params)}"

    def evaluate(doc: dict[str, Any]) -> dict[str, Any]:
        return _evaluation(session, pictures, doc, next(frames), picture_url, guides)

    @app.get("/")
    async def index() -> FileResponse:
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    @app.get("/favicon.ico")
    async def favicon() -> Response:
        return Response(status_code=204)

    @app.get("/api/session")
    async def get_session() -> JSONResponse:
        return JSONResponse({**session_json(session), "server": server,
                             "guidelines": guides.as_json()},
                            headers={"Cache-Control": "no-store"})

    @app.get("/api/fisheye.jpg")
    async def fisheye() -> Response:
        return Response(session.fisheye_jpeg, media_type="image/jpeg")

    @app.get("/api/evaluate")
    async def get_evaluate(q: str = "{}") -> JSONResponse:
        doc = _json_object(q)
        return JSONResponse(await run_in_threadpool(evaluate, doc),
                            headers={"Cache-Control": "no-store"})

    @app.get("/api/guidelines")
    async def get_guidelines(q: str = "{}") -> JSONResponse:
        doc = await run_in_threadpool(_guidelines, session, guides, _json_object(q))
        return JSONResponse(doc, headers={"Cache-Control": "no-store"})

    @app.get("/api/picture/{kind}.jpg")
    async def picture(kind: str, p: str = "") -> Response:
        if kind not in PICTURE_KINDS:
            return _error(404, f"no picture {kind!r} (one of {', '.join(PICTURE_KINDS)})")
        params = parse_params_key(p)
        t0 = time.perf_counter()
        data = await run_in_threadpool(pictures.picture, kind, params)
        # a picture of given parameters never changes (v: this server's id)
        return Response(data, media_type="image/jpeg",
                        headers={"Cache-Control": "private, max-age=600, immutable",
                                 "Server-Timing": f"render;dur={1e3 * (time.perf_counter() - t0):.2f}"})

    @app.post("/api/save")
    async def post_save(request: Request) -> JSONResponse:
        doc = await _body(request)
        label = parse_label(doc.get("label"))
        params = parse_params(doc.get("params", {}), session.start)
        frame = await run_in_threadpool(_frame, session, params)
        path = await run_in_threadpool(save_params, session, frame, label)
        return JSONResponse({"file": str(path.relative_to(session.root.resolve())),
                             "path": str(path.resolve()),
                             "scene": str(session.scene_file.resolve()),
                             "command": evaluate_command(session, path),
                             "ec_score": frame.ec.score})

    @app.post("/api/report")
    async def post_report(request: Request) -> JSONResponse:
        doc = await _body(request)
        label = parse_label(doc.get("label"))
        params = parse_params(doc.get("params", {}), session.start)
        path = await run_in_threadpool(write_setting_report, session, params, label)
        return JSONResponse({"file": str(path.relative_to(session.root.resolve())),
                             "path": str(path.resolve())})

    return Guard(app, token)


def _frame(session: ConsoleSession, params: IspParams) -> ConsoleFrame:
    """The ECs of ``params`` as a frame to save (no pictures)."""

    return ConsoleFrame(params, session.ecs(params), b"", None, [], {})
