"""The access rule, the listening socket and the URL."""

from __future__ import annotations


import pytest

from rvmsim.console import check_access, console_url, is_loopback, listen
from rvmsim.errors import RvmsimError


@pytest.mark.parametrize("host, loop", [("127.0.0.1", True), ("127.8.0.1", True),
                                        ("localhost", True), ("::1", True), ("[::1]", True),
                                        ("0.0.0.0", False), ("192.168.1.4", False),
                                        ("example.org", False), ("::", False)])
def test_is_loopback(host, loop):
    assert is_loopback(host) is loop


def test_loopback_needs_no_token_and_others_get_one():
    assert check_access("127.0.0.1", None).token is None
    given = "a" * 20
    assert check_access("127.0.0.1", given).token == given
    made = check_access("0.0.0.0", None)
    assert made.generated and len(made.token or "") >= 16
    assert check_access("0.0.0.0", None).token != made.token
    assert check_access("0.0.0.0", given) == check_access("0.0.0.0", given)
    assert not check_access("0.0.0.0", given).generated


@pytest.mark.parametrize("host, token, word", [("", None, "--host"), ("0.0.0.0", "short", "--token"),
                                               ("0.0.0.0", "x" * 16 + "/", "--token")])
def test_bad_hosts_and_tokens(host, token, word):
    with pytest.raises(RvmsimError, match=word):
        check_access(host, token)


def test_listen_on_a_free_port_and_refuse_a_taken_one():
    sock = listen("127.0.0.1", 0)
    try:
        port = sock.getsockname()[1]
        assert port > 0
        with pytest.raises(RvmsimError, match=f"--port {port}"):
            blocker = listen("127.0.0.1", port)
            blocker.close()
    finally:
        sock.close()
    with pytest.raises(RvmsimError, match="--host"):
        listen("no-such-host.invalid", 0)


def test_console_url():
    assert console_url("127.0.0.1", 8765, None) == "http://127.0.0.1:8765/"
    assert console_url("0.0.0.0", 1, "tok") == "http://127.0.0.1:1/?token=tok"
    assert console_url("::1", 2, None) == "http://[::1]:2/"


def test_the_url_is_told_only_once_uvicorn_holds_ctrl_c(small_run):
    """``serve`` tells the URL after uvicorn has taken over SIGINT, so a Ctrl-C right after
    the URL is printed is uvicorn's clean shutdown, not a KeyboardInterrupt thrown into a
    half-started event loop (which left a "coroutine was never awaited" warning on stderr)."""
    import gc
    import signal
    import warnings

    from rvmsim.console import open_session, serve

    session = open_session(small_run / "run")
    seen: dict[str, object] = {}

    def ready(url: str) -> None:
        seen["url"] = url
        seen["handler"] = signal.getsignal(signal.SIGINT)
        signal.raise_signal(signal.SIGINT)  # Ctrl-C the instant the URL is shown

    # Ctrl-C as a program has it (a pytest-xdist worker ignores SIGINT)
    outer = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with pytest.raises(KeyboardInterrupt):
                serve(session, check_access("127.0.0.1", None), 0, on_ready=ready,
                      open_browser=False)
            gc.collect()
        given_back = signal.getsignal(signal.SIGINT)
    finally:
        signal.signal(signal.SIGINT, outer)
    assert str(seen["url"]).startswith("http://127.0.0.1:")
    assert seen["handler"] not in (signal.default_int_handler, signal.SIG_DFL), seen
    assert getattr(seen["handler"], "__self__", None).__class__.__name__ == "Server"
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], caught
    assert given_back is signal.default_int_handler  # given back


def _raw_get(url: str, target: bytes, header: bytes = b"") -> bytes:
    """Send ``GET target`` (with ``header``, a whole ``Name: value`` line or nothing) on a
    socket of its own and return the whole answer (read until the server closes)."""
    import socket
    from urllib.parse import urlsplit

    where = urlsplit(url)
    with socket.create_connection((where.hostname, where.port), timeout=30) as sock:
        sock.sendall(b"GET " + target + b" HTTP/1.1\r\nHost: " + where.netloc.encode()
                     + b"\r\n" + header + b"Connection: close\r\n\r\n")
        answer = b""
        while chunk := sock.recv(65536):  # a reset raises here
            answer += chunk
    return answer


@pytest.mark.parametrize("target, header, status", [
    (b"/?q=" + b"a" * 1_000_000, b"", 414),  # over h11's limit: the connection answers
    (b"/?q=" + b"a" * 12_000, b"", 414),  # within it: the app's guard answers
    (b"/", b"X-Big: " + b"a" * 1_000_000 + b"\r\n", 431),
    (b"/", b"X-Big: " + b"a" * 20_000 + b"\r\n", 431),
], ids=["1 MB query", "12 kB query", "1 MB header", "20 kB header"])
def test_a_huge_request_head_gets_414_or_431_not_a_reset(small_run, target, header, status):
    """A request head too large gets its status and a JSON reason, the connection closed
    gently (no reset), and the server answers the next request as before."""
    import json

    from rvmsim.console import open_session

    from .conftest import serving

    with serving(open_session(small_run / "run"), check_access("127.0.0.1", None)) as url:
        answer = _raw_get(url, target, header)
        head, _, body = answer.partition(b"\r\n\r\n")
        assert head.split(b" ")[1] == str(status).encode(), head
        assert json.loads(body)["error"]
        assert _raw_get(url, b"/").startswith(b"HTTP/1.1 200")
