"""The console's gate, in front of every route (a pure ASGI middleware, so it sees a request
before any of its body is read):

- **who**: with a token, every request must carry it (``X-Rvm-Token`` header, ``token``
  query parameter, or the cookie the page gets when opened with ``?token=``); without one
  (loopback only) the ``Host`` header must name a loopback address (stops DNS rebinding);
- **from where**: a request whose ``Origin`` is not the console's own, or whose
  ``Sec-Fetch-Site`` says another site sent it, is refused (403) — except a plain
  navigation to a page;
- **how**: a state-changing request (anything but GET, HEAD, OPTIONS) must send its body
  as ``application/json``, a type no other site's form or simple request can send without
  a CORS preflight, which the console never grants (415 otherwise);
- **how much**: a request target (path and query) over :data:`MAX_TARGET_BYTES` gets 414,
  header fields over :data:`MAX_HEADER_BYTES` 431 (a request head too large to parse gets
  the same from the connection itself, :mod:`.protocol`);
  a body over :data:`MAX_BODY_BYTES` gets 413 — at once when its ``Content-Length`` says
  so, else as soon as the bytes read pass the limit (the body is read in the chunks the
  server receives and never held beyond the limit), and the connection is closed.

Every refusal is a JSON ``{"error": "…", "key": ""}``.
"""

from __future__ import annotations

import json
import secrets
from http.cookies import SimpleCookie
from typing import Any, Awaitable, Callable, MutableMapping
from urllib.parse import parse_qs

__all__ = ["Guard", "MAX_BODY_BYTES", "MAX_TARGET_BYTES", "MAX_HEADER_BYTES", "TOKEN_HEADER",
           "TOKEN_COOKIE",
           "LOOPBACK_HOSTS", "SAFE_METHODS"]

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
App = Callable[[Scope, Receive, Send], Awaitable[None]]

TOKEN_HEADER = "X-Rvm-Token"
TOKEN_COOKIE = "rvm_token"
#: ``Host`` names accepted when the console runs without a token (loopback only).
LOOPBACK_HOSTS = frozenset({"127.0.0.1", "localhost", "::1"})
#: Largest request body (bytes): a parameter set is a few hundred.
MAX_BODY_BYTES = 64 * 1024
#: Longest request target, path and query (bytes): an evaluation's query is about 1 kB.
MAX_TARGET_BYTES = 8 * 1024
#: Largest request header fields, all together (bytes; ``name: value\r\n`` each).
MAX_HEADER_BYTES = 16 * 1024
#: Methods that change nothing.
SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
_CSP = ("default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
        "connect-src 'self'; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
_EXTRA = [(b"content-security-policy", _CSP.encode()), (b"x-content-type-options", b"nosniff"),
          (b"referrer-policy", b"no-referrer")]


def _host_name(host_header: str) -> str:
    """The host of a ``Host`` header, without its port (``[::1]:8000`` → ``::1``)."""
    if host_header.startswith("["):
        return host_header[1:].split("]", 1)[0]
    return host_header.rsplit(":", 1)[0] if host_header.count(":") == 1 else host_header


async def _refuse(send: Send, status: int, message: str, *, close: bool = False) -> None:
    body = json.dumps({"error": message, "key": ""}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
               (b"cache-control", b"no-store"), *_EXTRA]
    if close:
        headers.append((b"connection", b"close"))
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})


class Guard:
    """The gate of the console app ``app`` (see the module docstring); ``token``: required
    on every request (None: loopback ``Host`` names only)."""

    def __init__(self, app: App, token: str | None) -> None:
        self.app = app
        self.token = token

    def _token_given(self, headers: dict[str, str], query: str) -> str:
        given = headers.get(TOKEN_HEADER.lower()) or (parse_qs(query).get("token") or [""])[0]
        if not given and "cookie" in headers:
            cookie: SimpleCookie = SimpleCookie()
            try:
                cookie.load(headers["cookie"])
            except Exception:  # noqa: BLE001 - a malformed cookie is no token
                return ""
            morsel = cookie.get(TOKEN_COOKIE)
            given = morsel.value if morsel is not None else ""
        return given

    def _who(self, headers: dict[str, str], query: str) -> str | None:
        """Why the request may not come in (None: it may)."""
        if self.token is None:
            if _host_name(headers.get("host", "")) not in LOOPBACK_HOSTS:
                return "forbidden: this console answers loopback host names only"
            return None
        given = self._token_given(headers, query)
        if not secrets.compare_digest(given.encode(), self.token.encode()):
            return "forbidden: a valid token is required (open the URL the console printed at start)"
        return None

    @staticmethod
    def _from_where(scope: Scope, headers: dict[str, str]) -> str | None:
        """Why the request's origin is refused (None: it is the console's own, or none)."""
        navigation = scope["method"] == "GET" and headers.get("sec-fetch-mode") == "navigate"
        origin = headers.get("origin")
        own = f"{scope.get('scheme', 'http')}://{headers.get('host', '')}"
        if origin is not None and origin != own and not navigation:
            return f"forbidden: a request from another site ({origin[:80]})"
        site = headers.get("sec-fetch-site")
        if site is not None and site not in ("same-origin", "none") and not navigation:
            return f"forbidden: a request from another site (Sec-Fetch-Site: {site[:20]})"
        return None

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", [])}
        query = scope.get("query_string", b"").decode("latin-1")
        target = len(scope.get("raw_path") or scope["path"].encode()) + len(query)
        if target > MAX_TARGET_BYTES:
            await _refuse(send, 414, f"request target over {MAX_TARGET_BYTES} bytes")
            return
        if sum(len(k) + len(v) + 4 for k, v in scope.get("headers", [])) > MAX_HEADER_BYTES:
            await _refuse(send, 431, f"request header fields over {MAX_HEADER_BYTES} bytes")
            return
        why = self._who(headers, query) or self._from_where(scope, headers)
        if why is not None:
            await _refuse(send, 403, why)
            return
        if scope["method"] not in SAFE_METHODS:
            kind = headers.get("content-type", "").split(";", 1)[0].strip().lower()
            if kind != "application/json":
                await _refuse(send, 415, "send the request body as application/json")
                return
            replay = await self._read_body(headers, receive, send)
            if replay is None:
                return
            receive = replay
        await self.app(scope, receive, self._send_with_headers(send, scope, query))

    async def _read_body(self, headers: dict[str, str], receive: Receive, send: Send
                         ) -> Receive | None:
        """Read the body up to the limit and hand it on whole; None when refused (413,
        connection closed) or the client went away."""
        declared = headers.get("content-length", "")
        if declared.strip().isdigit() and int(declared) > MAX_BODY_BYTES:
            await _refuse(send, 413, f"request body over {MAX_BODY_BYTES} bytes", close=True)
            return None
        body = bytearray()
        more = True
        while more:
            message = await receive()
            if message["type"] == "http.disconnect":
                return None
            body += message.get("body", b"")
            more = bool(message.get("more_body", False))
            if len(body) > MAX_BODY_BYTES:
                await _refuse(send, 413, f"request body over {MAX_BODY_BYTES} bytes",
                              close=True)
                return None
        data = bytes(body)
        sent = False

        async def replay() -> Message:
            nonlocal sent
            if not sent:
                sent = True
                return {"type": "http.request", "body": data, "more_body": False}
            return await receive()  # the disconnect, when it comes

        return replay

    def _send_with_headers(self, send: Send, scope: Scope, query: str) -> Send:
        cookie = (self.token is not None
                  and (parse_qs(query).get("token") or [""])[0] == self.token)

        async def wrapped(message: Message) -> None:
            if message["type"] == "http.response.start":
                extra = list(_EXTRA)
                if cookie:
                    assert self.token is not None
                    extra.append((b"set-cookie", f"{TOKEN_COOKIE}={self.token}; HttpOnly; "
                                                 f"Path=/; SameSite=strict".encode()))
                message = {**message, "headers": [*message.get("headers", []), *extra]}
            await send(message)

        return wrapped
