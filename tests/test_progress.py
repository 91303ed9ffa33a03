"""Progress bars off a terminal (rvmsim._progress): plain lines, at most one every
PLAIN_INTERVAL_S seconds, nothing for a short bar."""

from __future__ import annotations

import io
import sys

from rvmsim._progress import PLAIN_INTERVAL_S, _PlainLines, progress_bar


def test_each_state_tqdm_draws_becomes_one_plain_line():
    out = io.StringIO()
    lines = _PlainLines(out)
    lines.write("\rtune A:  10%|#         | 10/100 [00:01<00:09]   ")
    lines.write("\n")  # a bar that is left: its closing newline
    lines.write("\x1b[A")  # a move between stacked bars
    lines.write("\r" + " " * 40 + "\r")  # a bar that is cleared
    lines.write("\rtune A: 100%|##########| 100/100")
    assert out.getvalue() == ("tune A:  10%|#         | 10/100 [00:01<00:09]\n"
                              "tune A: 100%|##########| 100/100\n")


def test_a_short_bar_off_a_terminal_writes_nothing(monkeypatch):
    assert PLAIN_INTERVAL_S == 10.0
    err = io.StringIO()  # not a terminal, as a log file or CI
    monkeypatch.setattr(sys, "stderr", err)
    bar = progress_bar(total=50, desc="short", unit="step")
    for _ in range(50):
        bar.update(1)
        bar.set_postfix_str("a postfix redraws at once on a terminal, not here")
    bar.close()
    assert err.getvalue() == ""
