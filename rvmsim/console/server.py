"""Serving the console: the access rule (loopback, or a token), the listening socket and
uvicorn.

The socket is bound here, before uvicorn starts, so a bad ``--host`` or a port in use is a
one-line error, and port 0 picks a free port (tests).
"""

from __future__ import annotations

import asyncio
import ipaddress
import re
import secrets
import socket
import threading
import webbrowser
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import cv2
import uvicorn

from ..errors import RvmsimError
from .app import create_app
from .protocol import MAX_HEAD_BYTES, ConsoleHttp

if TYPE_CHECKING:
    from .session import ConsoleSession

__all__ = ["Access", "check_access", "is_loopback", "listen", "make_server", "serve",
           "console_url", "TOKEN_PATTERN"]

#: What a token may be: URL-safe characters, 16 to 128 of them.
TOKEN_PATTERN = re.compile(r"[A-Za-z0-9_-]{16,128}")


@dataclass(frozen=True)
class Access:
    """Where the console listens and the token every request must carry (None: none,
    loopback only); ``generated``: the token was made here (so it is printed)."""

    host: str
    token: str | None
    generated: bool = False


def is_loopback(host: str) -> bool:
    """Whether ``host`` is ``localhost`` or a loopback address (127.0.0.0/8, ::1)."""
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def check_access(host: str, token: str | None) -> Access:
    """The access rule: on loopback a token is optional; on any other host one is needed,
    and made (``secrets.token_urlsafe``) when not given.

    Raises
    ------
    RvmsimError
        One line naming ``--host`` or ``--token``: an empty host, a malformed token.
    """
    host = host.strip()
    if not host:
        raise RvmsimError("--host: give a host name or address (default 127.0.0.1)")
    if token is not None and not TOKEN_PATTERN.fullmatch(token):
        raise RvmsimError("--token: use 16-128 letters, digits, '-' or '_'")
    if token is None and not is_loopback(host):
        return Access(host, secrets.token_urlsafe(24), generated=True)
    return Access(host, token)


def listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (port 0: a free one).

    Raises
    ------
    RvmsimError
        One line naming ``--host`` or ``--port``: an unknown host, a port in use or not
        allowed.
    """
    try:
        infos = socket.getaddrinfo(host.strip("[]"), port, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as err:
        raise RvmsimError(f"--host {host}: not a known host name or address ({err})") from None
    family, kind, proto, _, address = infos[0]
    # proto IPPROTO_TCP (not 0): asyncio sets TCP_NODELAY only on sockets that say they are
    # TCP, and without it every keep-alive response waits ~40 ms for a delayed ACK
    sock = socket.socket(family, kind, proto or socket.IPPROTO_TCP)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(64)
    except OSError as err:
        sock.close()
        raise RvmsimError(f"--port {port}: cannot listen on {host}:{port} "
                          f"({err.strerror or err})") from None
    sock.set_inheritable(True)
    return sock


def console_url(host: str, port: int, token: str | None) -> str:
    """The page's URL (with the token as ``?token=``, which the page passes on)."""
    shown = "127.0.0.1" if host in ("0.0.0.0", "::") else host
    shown = f"[{shown}]" if ":" in shown else shown
    return f"http://{shown}:{port}/" + (f"?token={token}" if token else "")


def make_server(session: ConsoleSession, access: Access) -> uvicorn.Server:
    """A uvicorn server of the console app (not started)."""

    config = uvicorn.Config(create_app(session, token=access.token), log_level="warning",
                            access_log=False, lifespan="off", ws="none", http=ConsoleHttp,
                            h11_max_incomplete_event_size=MAX_HEAD_BYTES)
    return uvicorn.Server(config)


def serve(session: ConsoleSession, access: Access, port: int, *,
          on_ready: Callable[[str], None] = print, open_browser: bool = True) -> None:
    """Listen, serve, and once uvicorn is serving tell ``on_ready`` the URL and open it in
    a browser (unless not wanted); serve until Ctrl-C.

    ``on_ready`` runs only after uvicorn has taken over Ctrl-C, so a Ctrl-C any time after
    the URL is printed is a clean shutdown (KeyboardInterrupt, nothing on stderr).
    """

    # Requests are evaluated in parallel threads (a page's ECs and its picture, several
    # pages); OpenCV's own thread pool on top of that oversubscribes the cores, and under
    # load one late helper thread holds up a whole remap: one OpenCV thread per request.
    cv2.setNumThreads(1)
    sock = listen(access.host, port)
    url = console_url(access.host, sock.getsockname()[1], access.token)
    server = make_server(session, access)

    async def serve_and_tell() -> None:
        serving = asyncio.ensure_future(server.serve(sockets=[sock]))
        while not (server.started or serving.done()):
            await asyncio.sleep(0.005)
        if server.started:
            on_ready(url)
            if open_browser:
                threading.Timer(0.5, webbrowser.open, args=(url,)).start()
        await serving

    main = serve_and_tell()
    try:
        with asyncio.Runner() as runner:
            runner.run(main)
    finally:
        # A Ctrl-C before the loop ran it leaves the coroutine unstarted; closing it keeps
        # Python's "never awaited" warning off stderr.  (A no-op once it has finished.)
        main.close()
