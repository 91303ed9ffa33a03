"""A markets run (``rvmsim tune --markets``) in its report, its sign-off sheet and
``rvmsim robustness RUN``: a real small run at two markets' sites."""

from __future__ import annotations

import base64
import json
import re
import shutil
from pathlib import Path

import pytest

from ..cli_runner import run_in_process, tune_status
from ..robust.conftest import ANGLES_ONLY
from rvmsim.testing.scenes import write_small_scene

MARKETS = ["fmvss111", "unr158"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A short markets run of a quarter-size vehicle A (too short to pass FMVSS: the report
    must say why), its report and its sign-off (no PDF)."""
    root = tmp_path_factory.mktemp("markets_report")
    write_small_scene(root, "a", name="scene.yaml", variation=ANGLES_ONLY)
    tuned = run_in_process(["tune", "scene.yaml", "--markets", ",".join(MARKETS), "--budget",
                            "24", "--out", "run", "--no-progress"], cwd=root)
    assert tuned.code in (0, 1), tuned.stderr
    before = _mtimes(root / "run")
    rep = run_in_process(["report", "run"], cwd=root)
    assert rep.code == 0, rep.stderr
    assert _mtimes(root / "run") == before  # a report only reads the run
    sign = run_in_process(["signoff", "run", "--out", "so", "--no-pdf", "--no-progress"],
                          cwd=root)
    assert sign.code == _sheet_status(root / "so"), sign.stderr
    return root, json.loads((root / "run" / "best" / "markets.json").read_text()), sign


def _sheet_status(out):
    """The exit status a sign-off must have: 0 when its ECs at the display and every
    market pass (nothing else was given to it), else 1."""
    doc = json.loads((out / "signoff.json").read_text())
    ok = all(e["passed"] for e in doc["ecs"]["ecs"] if e["enabled"]) and \
        all(m["passed"] for m in doc["markets"])
    return 0 if ok else 1


def _mtimes(run):
    """Every file of ``run`` but its report's own (the page and the guidelines' table
    beside it), with its modification time (ns)."""
    return {f: f.stat().st_mtime_ns for f in run.rglob("*")
            if f.is_file() and f.name not in ("report.html", "guidelines.bin")}


def _market_rows(html: str) -> list[str]:
    return re.findall(r'<tr class="(?:pass|fail) market"><td>([^<]*)</td>', html)


def _images(html: str) -> dict[str, bytes]:
    """The markets section's annotated images by their alt text."""
    return {alt: base64.b64decode(data) for data, alt in re.findall(
        r'<img src="data:image/png;base64,([^"]+)" alt="([^"]*) annotated ECs">', html)}


def test_the_report_has_a_row_and_an_image_per_market(run):
    root, doc, _ = run
    html = (root / "run" / "report.html").read_text()
    assert _market_rows(html) == MARKETS
    images = _images(html)
    for r in doc["markets"]:
        png = root / "run" / "best" / r["images"] / "ec_annotated.png"
        assert images[r["member"]] == png.read_bytes()
        b = r["binding"]
        assert f"{b['ec']} {b['name']} = " in html
    passed = [r["passed"] for r in doc["markets"]]
    assert ("all markets pass" in html) == all(passed)
    if not all(passed):  # the reasons, as tune printed them
        assert "No setting found passes every market" in html
        assert "<li>" in html.split('id="markets"')[1].split("</section>")[0]


def test_the_signoff_lists_the_markets(run):
    root, doc, sign = run
    so = json.loads((root / "so" / "signoff.json").read_text())
    assert [m["member"] for m in so["markets"]] == MARKETS
    assert [m["passed"] for m in so["markets"]] == [r["passed"] for r in doc["markets"]]
    assert so["all_markets_pass"] == all(r["passed"] for r in doc["markets"])
    html = (root / "so" / "signoff.html").read_text()
    assert _market_rows(html) == MARKETS and len(_images(html)) == 2
    assert ("all markets pass" in html) == so["all_markets_pass"]
    assert ("markets: all markets pass" in sign.stdout) == so["all_markets_pass"]


def test_the_signoff_says_all_markets_pass_only_when_every_one_does(run, tmp_path):
    """The same run with its markets.json edited: every market passing, then one failing."""
    root, doc, _ = run
    copy = tmp_path / "run"
    shutil.copytree(root / "run", copy)
    for flags, expect in (([True, True], True), ([True, False], False)):
        edited = {**doc, "passed": all(flags),
                  "markets": [{**r, "passed": f, "failing": [] if f else ["R158-2"]}
                              for r, f in zip(doc["markets"], flags)]}
        (copy / "best" / "markets.json").write_text(json.dumps(edited))
        out = run_in_process(["signoff", str(copy), "--out", str(tmp_path / f"so{expect}"),
                              "--no-pdf", "--no-progress"])
        assert out.code == _sheet_status(tmp_path / f"so{expect}"), out.stderr
        if not expect:  # a failing market fails the sheet, whatever its ECs
            assert out.code == 1 and "Markets: not every market passes" in out.stderr
        so = json.loads((tmp_path / f"so{expect}" / "signoff.json").read_text())
        assert so["all_markets_pass"] is expect
        assert ("markets: all markets pass (2)" in out.stdout) is expect
        html = (tmp_path / f"so{expect}" / "signoff.html").read_text()
        assert ("all markets pass (2)" in html) is expect
        if not expect:
            assert "not every market passes: unr158 fail" in html


def test_robustness_of_a_run_uses_its_markets(run):
    root, _, _ = run
    out = run_in_process(["robustness", "run", "--samples", "6", "--scales", "1", "--out",
                          "rob", "--no-progress"], cwd=root)
    assert out.code == 0, out.stderr
    doc = json.loads((root / "rob" / "robustness.json").read_text())
    assert [m["market"] for m in doc["markets"]] == MARKETS
    assert doc["inputs"]["params_file"].endswith("top/rank_1.yaml")
    assert doc["n_pass"] == sum(s["passed"] for s in doc["samples"])


def test_a_plain_run_is_judged_in_markets_by_report_and_signoff(run, tmp_path):
    """``report RUN --markets`` and ``signoff RUN --markets`` on a run tuned without markets:
    the best setting judged at each market's site, measured as evaluate measures it; the
    run's own results kept; a markets run refuses other markets."""
    root, _, _ = run
    shutil.copy(root / "scene.yaml", tmp_path / "scene.yaml")
    tuned = run_in_process(["tune", "scene.yaml", "--strategy", "random", "--budget", "20",
                            "--out", "plain", "--no-progress", "--workers", "1"], cwd=tmp_path)
    assert tuned.code == tune_status(tmp_path / "plain"), tuned.stderr
    table = (tmp_path / "plain" / "best" / "ec_table.txt").read_bytes()
    rep = run_in_process(["report", "plain", "--markets", ",".join(MARKETS)], cwd=tmp_path)
    assert rep.code == 0, rep.stderr
    html = (tmp_path / "plain" / "report.html").read_text()
    assert _market_rows(html) == MARKETS
    doc = json.loads((tmp_path / "plain" / "best" / "markets.json").read_text())
    assert doc["searched"] is False and doc["conflicts"] == []
    assert (tmp_path / "plain" / "best" / "ec_table.txt").read_bytes() == table
    # the judge step alone writes the same verdicts into the run and exits by them (the
    # fixture checks that a report then only reads the run)
    written = (tmp_path / "plain" / "best" / "markets.json").read_bytes()
    (tmp_path / "plain" / "best" / "markets.json").unlink()
    judge = run_in_process(["judge", "plain", "--markets", ",".join(MARKETS)], cwd=tmp_path)
    assert judge.code == (0 if doc["passed"] else 1), judge.stderr
    assert (tmp_path / "plain" / "best" / "markets.json").read_bytes() == written
    assert all(m in judge.stdout for m in MARKETS)
    # the same verdicts as evaluate gives the run's rank-1 setting in those markets
    ev = run_in_process(["evaluate", "scene.yaml", "--params", "plain/top/rank_1.yaml",
                         "--markets", ",".join(MARKETS), "--out", "ev", "--no-progress"],
                        cwd=tmp_path)
    judged = json.loads((tmp_path / "ev" / "markets.json").read_text())
    assert ev.code == (0 if judged["passed"] else 1)
    assert [r["passed"] for r in judged["markets"]] == [r["passed"] for r in doc["markets"]]
    assert [r["binding"]["ec"] for r in judged["markets"]] == \
        [r["binding"]["ec"] for r in doc["markets"]]
    sign = run_in_process(["signoff", "plain", "--markets", ",".join(MARKETS), "--out", "so",
                           "--no-pdf", "--no-progress"], cwd=tmp_path)
    assert sign.code == _sheet_status(tmp_path / "so"), sign.stderr
    assert [m["member"] for m in json.loads((tmp_path / "so" / "signoff.json").read_text())
            ["markets"]] == MARKETS
    other = run_in_process(["report", str(root / "run"), "--markets", "jp"])
    assert other.code == 2 and "tuned for the markets" in other.stderr
    assert len(other.stderr.strip().splitlines()) == 1
