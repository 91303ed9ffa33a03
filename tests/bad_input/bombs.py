"""YAML documents over the YAML limits (every file kind the tool reads gets each of them):
nesting thousands deep, a "billion laughs" alias expansion, a recursive alias, an
oversized file.  Each is a function of a valid document's first line, so the file is
otherwise of its kind."""

from __future__ import annotations

from .harness import MEMORY

#: A 5,000-deep ``[[[…]]]`` (a RecursionError with 3,000 lines of stderr, before the limit).
DEEP = "deep: " + "[" * 5000 + "]" * 5000 + "\n"
#: Nine levels of nine aliases: 9⁹ ≈ 3.9 × 10⁸ strings once expanded.
LAUGHS = "lol0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n" + "".join(
    f"lol{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]\n" for i in range(1, 10))
#: An alias inside its own anchor.
RECURSIVE = "loop: &self [1, *self]\n"
#: Over the 4 MiB size limit (a long comment, then a valid document).
HUGE = "# " + "x" * (5 * 1024**2) + "\n"

#: (case id suffix, text, why the case needs a child process ("": it does not)) of each
#: bomb.  Only the expansion needs the memory cap: without the depth limit the parser ends
#: in a RecursionError (a traceback, in this process too), a recursive alias is refused or
#: recurses the same way, and 5 MiB are read as quickly here.
BOMBS = (("deep", DEEP, ""), ("laughs", LAUGHS, MEMORY), ("recursive", RECURSIVE, ""),
         ("huge", HUGE, ""))
