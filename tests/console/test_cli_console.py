"""``rvmsim console`` as a command: it prints the URL (and a token it made off loopback),
serves the page, refuses requests without the token, and stops on Ctrl-C."""

from __future__ import annotations

import re
import signal
import subprocess
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from ..cli_runner import start_in_child


def _start(args: list[str], cwd: Path) -> tuple[subprocess.Popen[str], list[str]]:
    proc = start_in_child(["console", *args], cwd=cwd, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE)
    assert proc.stdout is not None
    lines = [proc.stdout.readline()]
    while not lines[-1].startswith("saves go to") and lines[-1]:
        lines.append(proc.stdout.readline())
    return proc, lines


def _status(url: str, headers: dict[str, str] | None = None) -> int:
    try:
        with urllib.request.urlopen(urllib.request.Request(url, headers=headers or {}),
                                    timeout=30) as r:
            return r.status
    except urllib.error.HTTPError as err:
        return err.code


def _stop(proc: subprocess.Popen) -> None:
    """Ctrl-C: it stops as every command does on Ctrl-C (exit 130, one line, no
    traceback)."""
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise
    assert proc.returncode == 130 and err.strip() == "rvmsim: interrupted", err


def test_on_loopback_it_serves_without_a_token(small_run):
    proc, lines = _start(["run", "--port", "0", "--no-browser"], small_run)
    try:
        url = re.search(r"http://127\.0\.0\.1:\d+/", lines[0])
        assert url, lines
        assert "token" not in "".join(lines)
        assert _status(url.group(0)) == 200
        assert _status(url.group(0) + "api/session") == 200
        assert "run/console" in lines[-1]
    finally:
        _stop(proc)


def test_off_loopback_it_makes_a_token_and_refuses_requests_without_it(small_run):
    proc, lines = _start(["run", "--host", "0.0.0.0", "--port", "0", "--no-browser"], small_run)
    try:
        found = re.search(r"http://127\.0\.0\.1:(\d+)/\?token=([A-Za-z0-9_-]+)", lines[0])
        assert found, lines
        port, token = found.groups()
        assert any(token in line for line in lines[1:])  # printed on its own line too
        base = f"http://127.0.0.1:{port}/"
        assert _status(base) == 403
        assert _status(base + "api/session") == 403
        assert _status(base + "api/session", {"X-Rvm-Token": "not-" + token}) == 403
        assert _status(base + "api/session", {"X-Rvm-Token": token}) == 200
        assert _status(f"{base}?token={token}") == 200
    finally:
        _stop(proc)


@pytest.mark.parametrize("source", ["scene.yaml"])
def test_a_scene_saves_into_its_out_folder(small_run, source):
    proc, lines = _start([source, "--port", "0", "--no-browser"], small_run)
    try:
        assert lines[-1].startswith("saves go to out/scene/console"), lines
    finally:
        _stop(proc)


def test_ctrl_c_right_after_the_url_is_clean_every_time(small_run):
    """Ctrl-C the moment the URL is printed, twice over: exit 130 and the one line each
    time (it once printed an asyncio warning first, under load)."""
    for _ in range(2):
        proc, lines = _start(["run", "--port", "0", "--no-browser"], small_run)
        assert lines[-1].startswith("saves go to"), lines
        _stop(proc)
