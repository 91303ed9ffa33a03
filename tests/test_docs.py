"""Every Python example in the README and docs/ runs.

A page's fenced blocks are taken in order, as a reader of the page would use them:
a block with a title (```` ```yaml title="acme/criteria.yaml" ````) is a file the page shows,
written to that path; every other ```` ```python ```` block is code, run top to bottom in one
fresh interpreter per page, in a scratch folder where ``scenes/``, ``params/`` and ``docs/``
are the checkout's (the paths the pages use).  And the site (mkdocs.yml) builds with
warnings as errors.

These are .ci/run's second step (``python3 -m pytest -m docs``), after the README's test
command, which leaves them out (about 80 worker-seconds)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.docs

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: A fenced block: its language, the rest of its opening line, its text.
FENCE = re.compile(r"^```(\w*)([^\n]*)\n(.*?)^```[ \t]*$", re.M | re.S)
TITLE = re.compile(r'title="([^"]+)"')


def _blocks(page: Path) -> list[tuple[str, str | None, str, int]]:
    """(language, title or None, text, line of the opening fence) of each fenced block."""
    text = page.read_text(encoding="utf-8")
    out = []
    for m in FENCE.finditer(text):
        title = TITLE.search(m.group(2))
        out.append((m.group(1), title.group(1) if title else None, m.group(3),
                    text.count("\n", 0, m.start()) + 1))
    return out


EXAMPLES = [p for p in PAGES if any(lang == "python" and title is None
                                    for lang, title, _, _ in _blocks(p))]


def test_the_pages_have_examples_to_run():
    assert len(EXAMPLES) >= 5, EXAMPLES


@pytest.mark.parametrize("page", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_the_python_examples_of_a_page_run(page: Path, tmp_path: Path):
    for name in ("scenes", "params", "docs"):
        (tmp_path / name).symlink_to(ROOT / name)
    code = []
    for lang, title, text, line in _blocks(page):
        if title is not None:
            target = tmp_path / title
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(text, encoding="utf-8")
        elif lang == "python":
            code.append(f"# {page.name}:{line}\n{text}")
    script = tmp_path / "example.py"
    script.write_text("\n".join(code), encoding="utf-8")
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True,
                         text=True, timeout=600)
    assert res.returncode == 0, f"{page.name}:\n{res.stdout[-3000:]}\n{res.stderr[-5000:]}"


def test_the_site_builds_with_warnings_as_errors(tmp_path: Path):
    res = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet",
                          "--site-dir", str(tmp_path / "site")], cwd=ROOT, capture_output=True,
                         text=True, timeout=600, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert res.returncode == 0, res.stderr[-5000:]
    assert (tmp_path / "site" / "api" / "index.html").is_file()
