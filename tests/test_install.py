"""The README's main set-up is enough for a sign-off PDF.

The package is installed alone (no extras: no pytest, no PDF reader) into a fresh virtual
environment that does not see this machine's site-packages; that environment's ``rvmsim``
tunes vehicle A, as the README's first command does, and prints the sign-off's PDF with
Debian's Chromium (which ``tools/setup.sh`` installs with or without ``--test``).

This is .ci/run's third step (``python3 -m pytest -m install``): the install fetches every
dependency (about 35 s from pip's cache) and is left out of the README's test command."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pypdfium2 as pdfium
import pytest

from .cli_runner import tune_status

pytestmark = pytest.mark.install

ROOT = Path(__file__).resolve().parents[1]
#: Installed by the test extra, never by the package itself.
TEST_ONLY = ("pytest", "pypdfium2", "psutil", "distributed", "mkdocs")


def _venv_env(venv: Path, tmp: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PYTHON", "VIRTUAL_ENV", "PIP_"))}
    env.update(PATH=f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}", VIRTUAL_ENV=str(venv),
               RVMSIM_CACHE=str(tmp / "cache"))
    return env


def test_the_main_install_alone_tunes_and_prints_the_signoff_pdf(tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    py = venv / "bin" / "python"
    res = subprocess.run([str(py), "-m", "pip", "install", "-q", "--disable-pip-version-check",
                          str(ROOT)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-3000:]
    env, work = _venv_env(venv, tmp_path), tmp_path / "work"
    work.mkdir()
    where = subprocess.run(
        [str(py), "-c", "import importlib.util as u, rvmsim; print(rvmsim.__file__); "
         f"print([m for m in {TEST_ONLY!r} if u.find_spec(m)])"],
        capture_output=True, text=True, env=env, cwd=work, check=True).stdout.splitlines()
    assert Path(where[0]).is_relative_to(venv), where  # the installed copy, not the checkout
    assert where[1] == "[]", f"the test extra leaked into the main install: {where[1]}"

    run, so = work / "runs" / "vehicle_a", work / "signoff"
    tune = subprocess.run([str(venv / "bin" / "rvmsim"), "tune",
                           str(ROOT / "scenes" / "vehicle_a.yaml"), "--out", str(run),
                           "--budget", "300", "--no-progress"],
                          capture_output=True, text=True, env=env, cwd=work)
    assert tune.returncode == tune_status(run), tune.stderr
    sign = subprocess.run([str(venv / "bin" / "rvmsim"), "signoff", str(run), "--out", str(so),
                           "--no-progress"], capture_output=True, text=True, env=env, cwd=work)
    assert sign.returncode in (0, 1) and "Traceback" not in sign.stderr, sign.stderr
    pdf = pdfium.PdfDocument(so / "signoff.pdf")
    try:
        assert len(pdf) >= 2
        first = pdf[0].get_textpage().get_text_range()
        assert "vehicle_a" in first or "Vehicle A" in first, first[:300]
    finally:
        pdf.close()
