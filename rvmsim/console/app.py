"""The console's web app (FastAPI): the page, its assets and a small JSON API.

Routes: ``GET /`` (the page), ``/static/…`` (its JS and CSS, from the package),
``GET /api/session`` (scene, controls, start values, candidates), ``GET /api/fisheye.jpg``,
``GET /api/evaluate?q=JSON`` (a parameter set → its ECs, ROI and picture URLs; a GET:
it changes nothing),
``GET /api/frame/{id}/{display|annotated}.jpg``, ``POST /api/save``, ``POST /api/report``.

Access: with a token, every request must carry it (``X-Rvm-Token`` header, ``token`` query
parameter, or the cookie the page gets when opened with ``?token=``), else 403.  Without one
(loopback only) the ``Host`` header must name a loopback address, which stops DNS-rebinding
pages.  Every error is a JSON ``{"error": "…"}`` (4xx for bad input), never a traceback.
"""

from __future__ import annotations

import json
import logging
import secrets
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Any, Awaitable, Callable

from fastapi import FastAPI, Request
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException as StarletteHTTPException

from ..errors import RvmsimError
from ..isp import params_to_dict
from .candidates import candidate_json
from .inputs import ConsoleInputError, parse_flag, parse_label, parse_params
from .outputs import save_params, write_setting_report
from .session import ConsoleFrame, ConsoleSession, evaluate_setting

__all__ = ["create_app", "session_json", "TOKEN_HEADER", "LOOPBACK_HOSTS", "MAX_BODY_BYTES"]

STATIC = Path(__file__).resolve().parent / "static"
TOKEN_HEADER = "X-Rvm-Token"
_COOKIE = "rvm_token"
#: ``Host`` names accepted when the console runs without a token (loopback only).
LOOPBACK_HOSTS = frozenset({"127.0.0.1", "localhost", "::1"})
#: Largest request body (bytes): a parameter set is a few hundred.
MAX_BODY_BYTES = 64 * 1024
#: Frames kept for their picture requests (the page asks for the newest at once).
_FRAMES_KEPT = 8
_CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self'; "
        "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
_log = logging.getLogger("rvmsim.console")


def _error(status: int, message: str, key: str = "") -> JSONResponse:
    return JSONResponse({"error": message, "key": key}, status_code=status,
                        headers={"Cache-Control": "no-store"})


def _host_name(host_header: str) -> str:
    """The host of a ``Host`` header, without its port (``[::1]:8000`` → ``::1``)."""
    if host_header.startswith("["):
        return host_header[1:].split("]", 1)[0]
    return host_header.rsplit(":", 1)[0] if host_header.count(":") == 1 else host_header


class _Frames:
    """The last few evaluated frames by id (thread-safe), for their picture requests."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._frames: OrderedDict[int, ConsoleFrame] = OrderedDict()
        self._next = 1

    def add(self, frame: ConsoleFrame) -> int:
        with self._lock:
            fid, self._next = self._next, self._next + 1
            self._frames[fid] = frame
            while len(self._frames) > _FRAMES_KEPT:
                self._frames.popitem(last=False)
            return fid

    def get(self, fid: int) -> ConsoleFrame | None:
        with self._lock:
            return self._frames.get(fid)


def _frame_json(fid: int, frame: ConsoleFrame, server: str) -> dict[str, Any]:
    """A frame as the page reads it; its picture URLs carry ``server`` (made per app), so a
    browser's cached frame 1 of an earlier console is never taken for this one's."""
    return {"frame": fid, "params": params_to_dict(frame.params), **frame.ec.as_dict(),
            "roi": frame.roi, "image": f"/api/frame/{fid}/display.jpg?v={server}",
            "annotated": (None if frame.annotated_jpeg is None
                          else f"/api/frame/{fid}/annotated.jpg?v={server}"),
            "timings_ms": frame.timings_ms}


def session_json(session: ConsoleSession) -> dict[str, Any]:
    """What the page is built from (every string is set as text by the page, never HTML)."""
    sc, im = session.scene, session.images.color
    return {
        "vehicle": sc.name, "description": sc.description, "kind": session.kind,
        "source": str(session.source), "save_dir": str(session.save_dir),
        "criteria": session.criteria.name,
        "ec_output": {"width": session.ec_output.width, "height": session.ec_output.height,
                      "mirror": session.ec_output.mirror},
        "display": {"width": session.display.width, "height": session.display.height},
        "fisheye": {"width": int(im.shape[1]), "height": int(im.shape[0]),
                    "url": "/api/fisheye.jpg"},
        "controls": [c.as_json() for c in session.controls],
        "start": params_to_dict(session.start),
        "candidates": [candidate_json(c) for c in session.candidates],
    }


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
    """The request body's JSON object (:func:`_json_object`)."""
    return _json_object(await request.body())


def _guard(app: FastAPI, token: str | None) -> None:
    """The access check in front of every route (see the module docstring)."""
    @app.middleware("http")
    async def check(request: Request, call_next: Callable[[Request], Awaitable[Response]]
                    ) -> Response:
        if token is None:
            if _host_name(request.headers.get("host", "")) not in LOOPBACK_HOSTS:
                return _error(403, "forbidden: this console answers loopback host names only")
        else:
            given = (request.headers.get(TOKEN_HEADER) or request.query_params.get("token")
                     or request.cookies.get(_COOKIE) or "")
            if not secrets.compare_digest(given.encode(), token.encode()):
                return _error(403, "forbidden: a valid token is required (open the URL the "
                                   "console printed at start)")
        response = await call_next(request)
        response.headers["Content-Security-Policy"] = _CSP
        response.headers["X-Content-Type-Options"] = "nosniff"
        response.headers["Referrer-Policy"] = "no-referrer"
        if token is not None and request.query_params.get("token") == token:
            response.set_cookie(_COOKIE, token, httponly=True, samesite="strict")
        return response


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


def create_app(session: ConsoleSession, *, token: str | None = None) -> FastAPI:  # long: routes
    """The console app of ``session``; ``token``: required on every request (None: no
    token, and loopback ``Host`` names only)."""
    app = FastAPI(title="rvmsim console", docs_url=None, redoc_url=None, openapi_url=None)
    frames = _Frames()
    server = secrets.token_hex(6)
    evaluating = threading.Lock()  # one evaluation at a time: the page sends one at a time
    _guard(app, token)
    _errors(app)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")

    def evaluate(doc: dict[str, Any]) -> ConsoleFrame:
        params = parse_params(doc.get("params", {}), session.start)
        annotate = parse_flag(doc.get("annotate"), "annotate")
        with evaluating:
            return evaluate_setting(session, params, annotate=annotate)

    @app.get("/")
    async def index() -> FileResponse:
        return FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    @app.get("/favicon.ico")
    async def favicon() -> Response:
        return Response(status_code=204)

    @app.get("/api/session")
    async def get_session() -> JSONResponse:
        return JSONResponse(session_json(session), headers={"Cache-Control": "no-store"})

    @app.get("/api/fisheye.jpg")
    async def fisheye() -> Response:
        return Response(session.fisheye_jpeg, media_type="image/jpeg")

    @app.get("/api/evaluate")
    async def get_evaluate(q: str = "{}") -> JSONResponse:
        doc = _json_object(q)
        frame = await run_in_threadpool(evaluate, doc)
        return JSONResponse(_frame_json(frames.add(frame), frame, server),
                            headers={"Cache-Control": "no-store"})

    @app.get("/api/frame/{fid}/{kind}.jpg")
    async def frame_picture(fid: int, kind: str) -> Response:
        frame = frames.get(fid)
        data = None if frame is None else {"display": frame.display_jpeg,
                                           "annotated": frame.annotated_jpeg}.get(kind)
        if data is None:
            return _error(404, f"no picture {kind} of frame {fid} (superseded)")
        # a frame's pictures never change: the A/B view reuses the one just shown
        return Response(data, media_type="image/jpeg",
                        headers={"Cache-Control": "private, max-age=600, immutable"})

    @app.post("/api/save")
    async def post_save(request: Request) -> JSONResponse:
        doc = await _body(request)
        label = parse_label(doc.get("label"))
        frame = await run_in_threadpool(evaluate, {"params": doc.get("params", {})})
        path = await run_in_threadpool(save_params, session, frame, label)
        return JSONResponse({"file": str(path.relative_to(session.root.resolve())),
                             "path": str(path), "ec_score": frame.ec.score})

    @app.post("/api/report")
    async def post_report(request: Request) -> JSONResponse:
        doc = await _body(request)
        label = parse_label(doc.get("label"))
        params = parse_params(doc.get("params", {}), session.start)
        path = await run_in_threadpool(write_setting_report, session, params, label)
        return JSONResponse({"file": str(path.relative_to(session.root.resolve())),
                             "path": str(path)})

    return app
