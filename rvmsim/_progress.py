"""Progress bars: :func:`progress_bar` makes every bar rvmsim shows, and
:class:`ProgressBar` is the part of ``tqdm.tqdm`` rvmsim calls (tqdm has no type
information, so its bars are typed by this protocol).

On a terminal a bar is tqdm's own, redrawn in place.  Off one (a log file, a pipe, CI) a
bar would write a carriage-return update for every step (about 58 KB for one ``tune``), so
it writes plain lines instead: nothing for the first :data:`PLAIN_INTERVAL_S` seconds (a
short bar writes nothing at all), then at most one line every :data:`PLAIN_INTERVAL_S`
seconds, and its final state.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Iterable
from typing import Any, Final, Protocol, TextIO

from tqdm import tqdm

__all__ = ["ProgressBar", "progress_bar", "PLAIN_INTERVAL_S"]

#: Off a terminal: the least time between two progress lines, and before the first (s).
PLAIN_INTERVAL_S: Final = 10.0
#: Terminal control sequences tqdm writes to move between stacked bars.
_CONTROL = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


class ProgressBar(Protocol):
    """A progress bar (``tqdm.tqdm``): ``n`` steps done so far."""

    n: float
    total: float | None

    def update(self, n: float = 1) -> bool | None:
        """Advance by ``n`` steps."""

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Show ``s`` after the bar."""

    def close(self) -> None:
        """End the bar (leave it or clear it, as it was made)."""

    def write(self, s: str, file: TextIO | None = None) -> None:
        """Print ``s`` above the bar (``tqdm.write``)."""


class _PlainLines:
    """A text stream for a bar off a terminal: each state tqdm draws (``"\\r" + text``)
    becomes one line; cursor moves and blank clears are dropped."""

    def __init__(self, stream: TextIO):
        self._stream = stream

    def write(self, text: str) -> int:
        for piece in re.split(r"[\r\n]", _CONTROL.sub("", text)):
            if piece.strip():
                self._stream.write(piece.rstrip() + "\n")
        return len(text)

    def flush(self) -> None:
        self._stream.flush()


class _PlainBar(tqdm):
    """A bar off a terminal: a new postfix waits for the next line (on a terminal it
    redraws the bar at once, which off one would be a line per call)."""

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        super().set_postfix_str(s, refresh=False)


def progress_bar(iterable: Iterable[Any] | None = None, **options: Any) -> Any:
    """A tqdm bar over ``iterable`` (or counted by ``update``) with tqdm's ``options``
    (``total``, ``desc``, ``unit``, ``leave``, ``position``, ``disable``, …), on stderr:
    tqdm's own on a terminal, plain lines off one (see the module docstring)."""
    stream = sys.stderr
    isatty = getattr(stream, "isatty", None)
    if callable(isatty) and isatty():
        return tqdm(iterable, **options)
    return _PlainBar(iterable, **{**options, "file": _PlainLines(stream),
                                  "delay": PLAIN_INTERVAL_S, "mininterval": PLAIN_INTERVAL_S,
                                  "maxinterval": PLAIN_INTERVAL_S})
