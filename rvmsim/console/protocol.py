"""The console's HTTP/1.1 connection: uvicorn's h11 protocol, with an answer for a request
whose head is too large to parse.

h11 holds at most :data:`MAX_HEAD_BYTES` of a request's head (its request line and header
fields) before it gives up; uvicorn then answers 400 and closes the socket while the client
is still sending, and the kernel resets the connection: the client sees a reset instead of
an answer.  Here such a request gets **414** (its request line alone is over the limit: a
huge query string) or **431** (its header fields are), as the console's other refusals a
JSON ``{"error": "…", "key": ""}`` (:mod:`.guard`), and the connection is closed gently:
the answer is sent, the console's side shut for writing, and whatever more the client
sends read and dropped until it closes (at most :data:`DRAIN_S`).  Smaller requests reach
the app, whose guard answers 414 for a target over
:data:`~rvmsim.console.guard.MAX_TARGET_BYTES`.
"""

from __future__ import annotations

import json

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

__all__ = ["ConsoleHttp", "MAX_HEAD_BYTES", "DRAIN_S"]

#: h11's limit on a request head it has not parsed yet (bytes; uvicorn's default).
MAX_HEAD_BYTES = 16 * 1024
#: Longest wait (s) for a refused client to stop sending before the connection is closed.
DRAIN_S = 5.0


class ConsoleHttp(H11Protocol):
    """uvicorn's h11 protocol; a request head over :data:`MAX_HEAD_BYTES` gets 414 or 431
    and a gentle close (see the module docstring)."""

    _draining = False

    def data_received(self, data: bytes) -> None:
        if self._draining:
            return  # the rest of a refused request: read and dropped
        super().data_received(data)

    def send_400_response(self, msg: str) -> None:
        """uvicorn's answer to what h11 cannot parse: 414/431 for a head over the limit,
        else its own 400."""
        pending, _ = self.conn.trailing_data
        if len(pending) <= MAX_HEAD_BYTES:
            super().send_400_response(msg)
            return
        line_ended = b"\r\n" in pending[:MAX_HEAD_BYTES] or b"\n" in pending[:MAX_HEAD_BYTES]
        status, what = ((431, "request header fields") if line_ended
                        else (414, "request line (path and query)"))
        body = json.dumps({"error": f"{what} over {MAX_HEAD_BYTES} bytes", "key": ""}).encode()
        head = h11.Response(status_code=status, headers=[
            (b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
            (b"connection", b"close")])
        for event in (head, h11.Data(data=body), h11.EndOfMessage()):
            self.transport.write(self.conn.send(event))
        self._draining = True
        if self.transport.can_write_eof():
            self.transport.write_eof()
        self.loop.call_later(DRAIN_S, self.transport.close)
