"""The console's gate (:mod:`rvmsim.console.guard`): cross-site writes, content types, the
request size limits — through the app, and against the real server process (``rvmsim
console`` as a child), where the body limit must hold while the body is read."""

from __future__ import annotations

import json
import re
import signal
import socket
import subprocess
import threading
import time
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from rvmsim.console import MAX_BODY_BYTES, MAX_TARGET_BYTES, create_app, open_session

from ..cli_runner import start_in_child

LOCAL = "http://127.0.0.1:8765"
SAVE = {"params": {"zoom": 0.8}}


@pytest.fixture
def app_and_folder(run_copy):
    return create_app(open_session(run_copy / "run")), run_copy / "run" / "console"


def _saved(folder: Path) -> list[Path]:
    return sorted(folder.glob("*")) if folder.is_dir() else []


@pytest.mark.parametrize("headers, status", [
    ({"Origin": "http://evil.example.com", "Content-Type": "text/plain"}, 403),
    ({"Origin": "http://evil.example.com", "Content-Type": "application/json"}, 403),
    ({"Origin": "null", "Content-Type": "application/json"}, 403),
    ({"Origin": "http://127.0.0.1:9999", "Content-Type": "application/json"}, 403),  # another port
    ({"Sec-Fetch-Site": "cross-site", "Content-Type": "application/json"}, 403),
    ({"Sec-Fetch-Site": "same-site", "Content-Type": "application/json"}, 403),
    ({"Origin": LOCAL, "Content-Type": "text/plain"}, 415),
    ({"Content-Type": "application/x-www-form-urlencoded"}, 415),
    ({"Content-Type": "multipart/form-data; boundary=x"}, 415),
    ({}, 415),
], ids=["evil-text", "evil-json", "null-origin", "other-port", "cross-site", "same-site",
        "own-text", "form", "multipart", "no-type"])
def test_cross_site_and_simple_writes_are_refused(app_and_folder, headers, status):
    app, folder = app_and_folder
    client = TestClient(app, base_url=LOCAL)
    for path in ("/api/save", "/api/report"):
        r = client.post(path, content=json.dumps(SAVE), headers=headers)
        assert r.status_code == status, (path, r.text)
        assert r.json()["error"] and "Traceback" not in r.text
    assert client.delete("/api/save", headers=headers).status_code == status
    assert _saved(folder) == []


def test_own_json_writes_pass(app_and_folder):
    app, folder = app_and_folder
    client = TestClient(app, base_url=LOCAL)
    for headers in ({"Origin": LOCAL, "Sec-Fetch-Site": "same-origin"}, {}):
        r = client.post("/api/save", content=json.dumps(SAVE),
                        headers={**headers, "Content-Type": "application/json; charset=utf-8"})
        assert r.status_code == 200, r.text
    assert len(_saved(folder)) == 2


def test_foreign_pages_cannot_run_evaluations_but_links_open_the_page(app_and_folder):
    app, _ = app_and_folder
    client = TestClient(app, base_url=LOCAL)
    q = {"q": json.dumps({"params": {}})}
    assert client.get("/api/evaluate", params=q,
                      headers={"Origin": "http://evil.example.com"}).status_code == 403
    assert client.get("/api/evaluate", params=q,
                      headers={"Sec-Fetch-Site": "cross-site"}).status_code == 403
    assert client.get("/api/evaluate", params=q,
                      headers={"Sec-Fetch-Site": "same-origin"}).status_code == 200
    link = client.get("/", headers={"Sec-Fetch-Site": "cross-site", "Sec-Fetch-Mode": "navigate"})
    assert link.status_code == 200


def test_overlong_request_targets_get_414(app_and_folder):
    app, _ = app_and_folder
    client = TestClient(app, base_url=LOCAL)
    r = client.get("/api/evaluate?q=" + "x" * (MAX_TARGET_BYTES + 1))
    assert r.status_code == 414 and r.json()["error"]
    assert client.get("/" + "a" * (MAX_TARGET_BYTES + 1)).status_code == 414
    ok = json.dumps({"params": {n: 1.0 for n in ("zoom", "adv_h_scale", "adv_v_scale")}})
    assert client.get("/api/evaluate", params={"q": ok}).status_code == 200


def test_a_declared_oversize_body_is_refused_unread(app_and_folder):
    app, folder = app_and_folder
    client = TestClient(app, base_url=LOCAL)
    r = client.post("/api/save", content=b"{" + b" " * MAX_BODY_BYTES + b"}",
                    headers={"Content-Type": "application/json"})
    assert r.status_code == 413 and r.headers["connection"] == "close"
    assert _saved(folder) == []


# ------------------------------------------------------------------ the real server
@pytest.fixture
def server(run_copy):
    """``rvmsim console run --port 0`` in a child process: (pid, host, port, console dir)."""
    proc = start_in_child(["console", "run", "--port", "0", "--no-browser"], cwd=run_copy,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None
    line = proc.stdout.readline()
    match = re.search(r"http://(127\.0\.0\.1):(\d+)/", line)
    try:
        assert match, line
        yield proc.pid, match.group(1), int(match.group(2)), run_copy / "run" / "console"
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()


def _status_bytes(pid: int, key: str) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1]) * 1024
    raise AssertionError(f"no {key}")


class _PeakRss:
    """The largest resident set of process ``pid`` while the block runs: its kernel peak
    (VmHWM, reset at the start through ``/proc/PID/clear_refs``) and, as well, RSS sampled
    every few ms (memory freed again by the end must still count)."""

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.peak = 0
        self._stop = threading.Event()

    def _sample(self) -> None:
        while not self._stop.is_set():
            self.peak = max(self.peak, _status_bytes(self.pid, "VmRSS"))
            time.sleep(0.003)

    def __enter__(self) -> _PeakRss:
        Path(f"/proc/{self.pid}/clear_refs").write_text("5")  # VmHWM := VmRSS
        self.start = _status_bytes(self.pid, "VmRSS")
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, _status_bytes(self.pid, "VmHWM"))


def _exchange(host: str, port: int, head: str, chunks, limit_s: float = 60) -> bytes:
    """Send ``head`` and then the ``chunks`` until the server stops taking them; the
    answer (b"" when the connection was closed without one)."""
    with socket.create_connection((host, port), timeout=limit_s) as sock:
        sock.sendall(head.encode())
        try:
            for chunk in chunks:
                sock.sendall(chunk)
        except (BrokenPipeError, ConnectionResetError):
            pass  # the server closed the connection: what a refusal mid-body is
        data = b""
        try:
            while True:
                part = sock.recv(65536)
                if not part:
                    break
                data += part
        except (ConnectionResetError, socket.timeout):
            pass
        return data


def test_real_server_refuses_a_cross_site_text_plain_save(server):
    pid, host, port, folder = server
    body = json.dumps(SAVE)
    answer = _exchange(host, port, (
        f"POST /api/save HTTP/1.1\r\nHost: {host}:{port}\r\nOrigin: http://evil.example.com\r\n"
        f"Content-Type: text/plain\r\nContent-Length: {len(body)}\r\nConnection: close\r\n\r\n"
        f"{body}"), [])
    assert answer.startswith(b"HTTP/1.1 403"), answer[:200]
    answer = _exchange(host, port, (
        f"POST /api/save HTTP/1.1\r\nHost: {host}:{port}\r\nContent-Type: text/plain\r\n"
        f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n{body}"), [])
    assert answer.startswith(b"HTTP/1.1 415"), answer[:200]
    assert _saved(folder) == []
    answer = _exchange(host, port, (
        f"POST /api/save HTTP/1.1\r\nHost: {host}:{port}\r\nOrigin: http://{host}:{port}\r\n"
        f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n"
        f"Connection: close\r\n\r\n{body}"), [])
    assert answer.startswith(b"HTTP/1.1 200"), answer[:200]
    assert len(_saved(folder)) == 1


@pytest.mark.parametrize("declared", [True, False], ids=["content-length", "chunked"])
def test_real_server_stops_reading_a_400_mib_body_at_the_limit(server, declared):
    """A 400 MiB POST, its length declared or not (chunked): the server answers 413 (or
    closes the connection) having read at most a little over the limit; its memory grows
    by a few MB at most (it grew by 799 MB when it read the whole body first)."""
    pid, host, port, folder = server
    total = 400 * 1024 * 1024
    piece = b" " * (1024 * 1024)

    def chunks():
        sent = 0
        while sent < total:
            yield piece if declared else b"%x\r\n" % len(piece) + piece + b"\r\n"
            sent += len(piece)
        if not declared:
            yield b"0\r\n\r\n"

    # warm: the first request's imports and buffers are not the body's
    _exchange(host, port, f"GET /api/session HTTP/1.1\r\nHost: {host}:{port}\r\n"
                          f"Connection: close\r\n\r\n", [])
    length = f"Content-Length: {total}" if declared else "Transfer-Encoding: chunked"
    t0 = time.monotonic()
    with _PeakRss(pid) as rss:
        answer = _exchange(host, port, (
            f"POST /api/save HTTP/1.1\r\nHost: {host}:{port}\r\n"
            f"Content-Type: application/json\r\n{length}\r\n\r\n"), chunks())
    assert answer == b"" or answer.startswith(b"HTTP/1.1 413"), answer[:200]
    assert rss.peak - rss.start < 8 * 1024 * 1024, (rss.start, rss.peak)
    assert time.monotonic() - t0 < 60
    assert _saved(folder) == []
    # and it still serves
    ok = _exchange(host, port, f"GET /api/session HTTP/1.1\r\nHost: {host}:{port}\r\n"
                               f"Connection: close\r\n\r\n", [])
    assert ok.startswith(b"HTTP/1.1 200")
