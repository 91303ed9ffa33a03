"""What the README's main set-up brings: everything ``rvmsim signoff`` needs for its PDF
(Playwright as a dependency of the package itself, not of an extra; Debian's Chromium from
tools/setup.sh whether or not the tests are installed)."""

from __future__ import annotations

import importlib.metadata
import re
import subprocess
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parent.parent


def test_playwright_is_a_dependency_of_the_package_not_of_an_extra():
    reqs = [Requirement(r) for r in importlib.metadata.requires("rvmsim") or []]
    main = {r.name for r in reqs if r.marker is None}
    assert "playwright" in main, sorted(main)


def test_the_main_set_up_installs_chromium_too():
    """setup.sh without --test adds chromium to the packages it installs on a machine
    without it (its package list, run up to the first install with `command -v chromium`
    failing)."""
    script = (ROOT / "tools" / "setup.sh").read_text()
    head = script[:script.index("missing=()")]  # the package list, before any install
    no_chromium = 'command() { [[ "$*" != *chromium* ]] && builtin command "$@"; }\n'
    res = subprocess.run(["bash", "-c", no_chromium + head + '\necho "${apt_pkgs[@]}"'],
                         capture_output=True, text=True, cwd=ROOT / "tools")
    assert res.returncode == 0, res.stderr
    assert re.search(r"\bchromium\b", res.stdout), res.stdout
