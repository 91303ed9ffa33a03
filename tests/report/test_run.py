"""Review reports (`rvmsim report`): real small tuning runs rendered into self-contained HTML."""

from __future__ import annotations

import base64
import dataclasses
import hashlib
import html
import io
import json
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from urllib.parse import unquote

import numpy as np
import yaml
import pytest

from rvmsim.errors import RvmsimError
from rvmsim.guidelines import compute_guidelines, guideline_view, running_gear, steering_angles
from rvmsim.guidelines.coverage import required_coverage
from rvmsim.guidelines.draw import draw_lines
from rvmsim.guidelines.files import shown_angle
from rvmsim.guidelines.table import table_bytes
from rvmsim.isp import load_params
from rvmsim.pipeline import rvm_color
from rvmsim.render import cached_render
from rvmsim.report import EC_GROUP_NAMES, SECTION_IDS, write_batch_report, write_report
from rvmsim.scene import load_scene

from ..cli_runner import run_in_process
from ..conftest import SCENES

EVIL_NAME = 'Evil <script>alert(1)</script> & "Co"'
EVIL_DESC = "notes: <img src=x onerror=alert(2)> & 'quoted'"
EVIL_CRITERIA = "OEM <b>bold</b> & co"
TOP_M = 4


class _Collector(HTMLParser):
    """Every start tag with its attributes, the text, and the raw inline <svg> blocks."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_startendtag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data):
        self.text.append(data)

    def all_text(self) -> str:
        return " ".join(self.text)

    def find(self, tag: str) -> list[dict[str, str | None]]:
        return [a for t, a in self.tags if t == tag]


def _parse(text: str) -> _Collector:
    p = _Collector()
    p.feed(text)
    p.close()
    return p


def _decode_data_png(src: str) -> np.ndarray:
    import cv2

    prefix = "data:image/png;base64,"
    assert src.startswith(prefix), src[:40]
    raw = base64.b64decode(src[len(prefix):], validate=True)
    img = cv2.imdecode(np.frombuffer(raw, np.uint8), cv2.IMREAD_UNCHANGED)
    assert img is not None and img.size > 0 and min(img.shape[:2]) >= 8
    return img


def _assert_self_contained(text: str, doc: _Collector) -> None:
    assert "<script" not in text.lower() and not doc.find("script")
    assert "http://" not in text and "https://" not in text
    assert "@import" not in text and "url(" not in text
    assert not doc.find("link")  # no external stylesheets or fonts
    for attrs in doc.find("img"):
        _decode_data_png(attrs["src"] or "")
    for tag in ("a", "link", "iframe", "object", "embed", "source"):
        for attrs in doc.find(tag):
            for key in ("href", "src", "data"):
                v = attrs.get(key)
                assert v is None or ":" not in v.split("/")[0] or v.startswith("data:"), v
    # Inline SVGs (if any plot is embedded that way) are well-formed XML.
    start = 0
    while (i := text.find("<svg", start)) != -1:
        j = text.index("</svg>", i) + len("</svg>")
        ET.fromstring(text[i:j])
        start = j


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Two real tiny runs in one folder: an evil-named copy of vehicle A (custom criteria with
    4-1 off, CMA-ES) and vehicle B (random search)."""
    from rvmsim.tune import TuneRequest, tune
    from rvmsim.search import TuningConfig

    root = tmp_path_factory.mktemp("report")
    old = os.environ.get("RVMSIM_CACHE")
    os.environ["RVMSIM_CACHE"] = str(root / "cache")
    try:
        text = (SCENES / "vehicle_a.yaml").read_text()
        lines = [ln for ln in text.splitlines()
                 if not ln.startswith("name:") and not ln.startswith("description:")]
        scene = root / 'scene <i>&"x".yaml'
        scene.write_text(f"name: {json.dumps(EVIL_NAME)}\ndescription: {json.dumps(EVIL_DESC)}\n"
                         + "\n".join(lines) + "\n")
        crit = root / "crit <&>.yaml"
        crit.write_text(f"name: {json.dumps(EVIL_CRITERIA)}\ncriteria:\n  4-1: {{enabled: false}}\n")
        cfg = TuningConfig.model_validate({
            "tuned": ["fov", "rad", "zoom", "adv_v_shift"], "output": {"size": [320, 180]},
            "top_m": TOP_M, "batch": 20})
        runs_dir = root / "runs"
        evil_run = runs_dir / "a & <b>"
        tune(TuneRequest((scene,), "cmaes", cfg, criteria_file=crit, budget=80), evil_run)
        tune(TuneRequest((SCENES / "vehicle_b.yaml",), "random", cfg, budget=60),
             runs_dir / "b")
        report = write_report(evil_run)
        yield {"root": root, "runs_dir": runs_dir, "evil_run": evil_run, "report": report,
               "scene": scene, "crit": crit}
    finally:
        if old is None:
            os.environ.pop("RVMSIM_CACHE", None)
        else:
            os.environ["RVMSIM_CACHE"] = old


def test_report_has_every_section_and_decodable_images(runs):
    path = runs["report"]
    assert path == runs["evil_run"] / "report.html"
    text = path.read_text(encoding="utf-8")
    doc = _parse(text)
    ids = [a.get("id") for _, a in doc.tags if a.get("id")]
    for sid in SECTION_IDS:
        assert sid in ids, sid
    words = doc.all_text()
    for heading in ("Scene summary", "Images", "Evaluation criteria", "ISP parameters",
                    "Convergence", f"Top-{TOP_M} candidates"):
        assert heading in words
    # Scene summary: camera intrinsics, lens, mount, criteria file.
    for fact in ("fx 390.00", "equidistance", "pitch 32°", "1280 × 960 px", EVIL_CRITERIA,
                 str(runs["crit"]), str(runs["scene"])):
        assert fact in words, fact
    _assert_self_contained(text, doc)
    # a yes/no EC's margin is ✓ or ✗ (as in the sign-off, the console and the gallery)
    for ec in ("1-1", "2-4"):
        row = re.search(rf'<tr class="\w+"><td>{ec}</td>.*?</tr>', text)
        assert row is not None and re.search(r'<td class="num">[✓✗]</td>', row.group(0)), ec
    # fisheye+ROI, RVM, annotated, RVM at the display size, the guidelines straight ahead
    # and at full lock, convergence, histogram, and one per top-M candidate
    imgs = doc.find("img")
    assert len(imgs) == 8 + TOP_M
    assert _decode_data_png(imgs[3]["src"]).shape[:2] == (720, 1280)
    fisheye = _decode_data_png(imgs[0]["src"])
    assert fisheye.shape[1] <= 640 and fisheye.shape[0] > 100
    # the RVM image the report shows is the one its verdict refers to: the image of record
    assert _decode_data_png(imgs[1]["src"]).shape[:2] == (720, 1280)


def test_report_tables_gallery_and_escaping(runs):
    text = runs["report"].read_text(encoding="utf-8")
    doc = _parse(text)
    # Every user string is escaped: never raw in the file, shown verbatim as text.
    for s in (EVIL_NAME, EVIL_DESC, EVIL_CRITERIA, runs["evil_run"].name, runs["scene"].name,
              runs["crit"].name):
        assert s not in text, s
        assert html.escape(s, quote=True) in text, s
        assert s in doc.all_text(), s
    assert "<img src=x" not in text and "<b>bold" not in text
    # EC table: one row per EC, coloured by status; 4-1 is off under the custom criteria.
    from rvmsim.criteria import EC_IDS

    classes = [a.get("class") for t, a in doc.tags if t == "tr" and a.get("class") in
               ("pass", "fail", "off")]
    assert len(classes) == len(EC_IDS) and classes[EC_IDS.index("4-1")] == "off"
    assert ".pass" in text and ".fail" in text and "background" in text
    # Parameter table: all 14 parameters, the 4 tuned ones marked.
    from rvmsim.isp import IspParams

    words = doc.all_text()
    for name in IspParams.names():
        assert name in words
    assert len([a for t, a in doc.tags if t == "tr" and a.get("class") == "tuned"]) == 4
    assert "(search)" in words and "(Table 2)" in words
    # Gallery: one card per candidate with the params file tune wrote for it (top/), not a
    # command that prints it again.
    cards = [a for t, a in doc.tags if t == "div" and (a.get("id") or "").startswith("rank-")]
    assert len(cards) == TOP_M
    flat = " ".join(words.split())
    for k in range(1, TOP_M + 1):
        assert f"Its params file: {runs['evil_run']}/top/rank_{k}.yaml" in flat
        assert (runs["evil_run"] / "top" / f"rank_{k}.yaml").is_file()
    assert "rvmsim select" not in words
    assert "EC score" in words


def test_a_card_without_its_params_file_gives_the_command_that_writes_one(runs, tmp_path):
    run = tmp_path / "run"
    shutil.copytree(runs["evil_run"], run)
    (run / "top" / "rank_2.yaml").unlink()
    # a rank_3.yaml of another selection (another setting) is not this card's file either
    third = yaml.safe_load((run / "top" / "rank_3.yaml").read_text())
    third["zoom"] = third["zoom"] * 0.9 + 0.01
    (run / "top" / "rank_3.yaml").write_text(yaml.safe_dump(third))
    words = " ".join(_parse(write_report(run).read_text(encoding="utf-8")).all_text().split())
    assert f"Its params file: {run}/top/rank_1.yaml" in words
    for k in (2, 3):
        assert f"rvmsim select {run} --rank {k} --out rank_{k}.yaml" in words
        assert f"top/rank_{k}.yaml" not in words


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_batch_index_links_and_groups(runs, tmp_path, monkeypatch):
    err = _Terminal()  # a terminal: tqdm's bar (off one, plain lines: tests/test_progress.py)
    monkeypatch.setattr(sys, "stderr", err)
    index = write_batch_report(runs["runs_dir"], progress=True)
    bar = err.getvalue()
    assert "reports:" in bar and "| 8/8 " in bar and "gallery" in bar, bar  # 2 runs × 4 steps
    assert index == runs["runs_dir"] / "index.html"
    text = index.read_text(encoding="utf-8")
    doc = _parse(text)
    _assert_self_contained(text, doc)
    rows = [a for t, a in doc.tags if t == "tr"]
    assert len(rows) == 1 + 2  # header + one row per vehicle
    hrefs = [a["href"] for a in doc.find("a")]
    assert len(hrefs) == 2
    for h in hrefs:
        target = index.parent / unquote(h)
        assert target.is_file() and target.name == "report.html", h
        assert (target.parent / "guidelines.bin").is_file()  # each report's table beside it
    assert len(doc.find("img")) == 2
    words = doc.all_text()
    assert EVIL_NAME in words and "Vehicle B" in words and EVIL_NAME not in text
    for g, name in EC_GROUP_NAMES.items():
        assert f"{g}-x {name}" in words
    # pass/fail/off per group; group 4 is off for the evil run (4-1 disabled)
    cells = [a.get("class") for t, a in doc.tags if t == "td" and a.get("class") in
             ("pass", "fail", "off")]
    assert len(cells) == 2 * len(EC_GROUP_NAMES) and "off" in cells
    # --out elsewhere: links still resolve relative to the index.
    other = write_batch_report(runs["runs_dir"], tmp_path / "elsewhere" / "idx.html")
    for a in _parse(other.read_text()).find("a"):
        assert (other.parent / unquote(a["href"])).is_file()


def _record_scene(run, scene) -> None:
    """Point the run's recorded scene (in run.sqlite, the run's truth) at ``scene``, and its
    export run.json with it (a run.json that disagrees with the store blocks a resume)."""
    from rvmsim.runs import RunStore

    store = RunStore(run / "run.sqlite")
    store.write_settings(dataclasses.replace(store.settings(), scene=str(scene)))
    store.close()
    doc = json.loads((run / "run.json").read_text())
    if "scene" in doc:
        doc["scene"] = str(scene)
        (run / "run.json").write_text(json.dumps(doc, indent=2))


def test_report_missing_scene_is_one_line_error(runs, tmp_path):
    run = tmp_path / "copy"
    shutil.copytree(runs["evil_run"], run)
    _record_scene(run, tmp_path / "gone.yaml")
    with pytest.raises(RvmsimError) as err:
        write_report(run)
    assert "gone.yaml" in str(err.value) and "\n" not in str(err.value)


def test_changed_scene_warns_in_the_report_and_blocks_resume(runs, tmp_path):
    """The run records the scene's fingerprint: a report of a run whose scene file has
    changed since says so, and --resume refuses to mix two scenes."""
    from rvmsim.tune import resume

    scene = tmp_path / "scene.yaml"
    scene.write_text(runs["scene"].read_text())
    run = tmp_path / "run"
    shutil.copytree(runs["evil_run"], run)
    _record_scene(run, scene)
    assert "scene file changed" not in write_report(run).read_text()
    scene.write_text(scene.read_text().replace("pitch_deg: 32.0", "pitch_deg: 31.0"))
    assert "scene file changed after this run" in write_report(run).read_text()
    with pytest.raises(RvmsimError) as err:
        resume(run)
    assert "scene changed" in str(err.value) and "\n" not in str(err.value)


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        if path := shutil.which(name):
            return path
    return None


def test_report_renders_in_headless_chromium(runs, tmp_path):
    browser = _chromium()
    if browser is None:
        pytest.skip("Chromium is not installed (tools/setup.sh --test installs it)")
    import cv2

    shot = tmp_path / "shot.png"
    res = subprocess.run(
        [browser, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
         f"--user-data-dir={tmp_path / 'profile'}", f"--screenshot={shot}",
         "--window-size=1280,2000", runs["report"].resolve().as_uri()],
        capture_output=True, text=True, timeout=120)
    assert shot.is_file(), res.stderr[-2000:]
    img = cv2.imread(str(shot), cv2.IMREAD_COLOR)
    assert img is not None and img.shape[:2] == (2000, 1280)
    assert float(img.std()) > 10
    colours = np.unique(img.reshape(-1, 3)[::7], axis=0)
    assert len(colours) > 100


def _rvmsim(*args, env=None):
    return run_in_process(args, env=env)


def test_cli_report_run_batch_and_bad_path(runs, tmp_path):
    env = {"RVMSIM_CACHE": str(runs["root"] / "cache")}
    out = tmp_path / "r.html"
    res = _rvmsim("report", str(runs["runs_dir"] / "b"), "--out", str(out), env=env)
    assert res.code == 0, res.stderr
    assert str(out) in res.stdout and out.is_file()
    _assert_self_contained(out.read_text(), _parse(out.read_text()))
    # a page named other than report.html: its table beside it under its own name
    table = tmp_path / "r.guidelines.bin"
    assert table.is_file() and not (tmp_path / "guidelines.bin").exists()
    assert _guideline_shas(_section_of(out.read_text(), "guidelines")) == [
        hashlib.sha256(table.read_bytes()).hexdigest()]
    assert 'href="r.guidelines.bin"' in out.read_text()
    res = _rvmsim("report", str(runs["runs_dir"]), "--out", str(tmp_path / "i.html"), env=env)
    assert res.code == 0, res.stderr
    assert (tmp_path / "i.html").is_file() and "i.html" in res.stdout
    for bad in (tmp_path / "nothing", tmp_path):
        res = _rvmsim("report", str(bad), env=env)
        assert res.code == 2
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("rvmsim: error:") and str(bad) in lines[0]
        assert "Traceback" not in res.stderr


def _margin_cards(text: str) -> dict[int, list[tuple[str, str, str]]]:
    """Per gallery card (rank): its margin chips as (class, EC id, shown text)."""
    import re

    cards = {}
    for rank, body in re.findall(r'id="rank-(\d+)">(.*?)</div>', text, re.S):
        row = re.search(r'<p class="margins">(.*?)</p>', body, re.S)
        assert row is not None, f"card {rank} has no margins"
        cards[int(rank)] = [(c, html.unescape(e), html.unescape(s)) for c, e, s in re.findall(
            r'<span class="(pass|fail)" title="[^"]*"><b>([^<]*)</b> ([^<]*)</span>',
            row.group(1))]
    return cards


def test_gallery_cards_show_every_ecs_margin(runs):
    """Each top-M card has a row of EC margins (the enabled ECs: 4-1 is off), coloured by
    pass/fail, whose numbers are the signed distances of the stored values inside their
    ranges; no card says "same pass/fail as #1" any more."""
    import re

    from rvmsim.criteria import EcValue, load_criteria
    from rvmsim.runs import open_run, run_settings, store_candidates

    text = runs["report"].read_text(encoding="utf-8")
    assert "same pass/fail" not in text
    cards = _margin_cards(text)
    assert sorted(cards) == list(range(1, TOP_M + 1))
    criteria = load_criteria(runs["crit"])
    enabled = [e for e in criteria.ids if criteria.items[e].enabled]
    assert "4-1" not in enabled and len(enabled) == 10
    store = open_run(runs["evil_run"])
    try:
        pairs = store_candidates(store, run_settings(runs["evil_run"], store),
                                 criteria=criteria)
    finally:
        store.close()
    binary = {d.id for d in criteria.ecs if d.binary}
    for cand, rec in pairs:
        chips = cards[cand.rank]
        assert [e for _, e, _ in chips] == enabled
        for cls, ec, shown in chips:
            outcome, crit = rec.ecs[ec], criteria.items[ec]
            assert cls == ("pass" if outcome.passed else "fail"), (cand.rank, ec)
            if ec in binary:
                assert shown == ("✓" if outcome.passed else "✗")
                continue
            margin = EcValue(ec, ec, outcome.value, "", crit.low, crit.high, outcome.score,
                             outcome.passed, True).margin
            if margin is None:
                assert shown == "n/a"
                continue
            number = float(re.match(r"[+-][0-9.e+-]+?(?=[^0-9.e]|$)", shown).group(0))
            assert abs(number - margin) <= (0.5 if abs(margin) >= 10 else 0.05 * abs(margin)
                                            + 1e-12), (cand.rank, ec, shown, margin)
            assert (margin >= 0) == outcome.passed


def shown_text_px(page_file, alts: tuple[str, ...], viewport_width: int = 1280
                  ) -> dict[str, float]:
    """Open ``page_file`` in Chromium (Playwright) at ``viewport_width``: per image alt
    text, the annotation's text size (px per em) as the page shows it (the font size times
    the image's shown width over its own width)."""
    from playwright.sync_api import sync_playwright

    from rvmsim.criteria.annotate import TEXT_PX

    chromium = shutil.which("chromium")
    if chromium is None:
        pytest.skip("Chromium is not installed (tools/setup.sh --test installs it)")
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": viewport_width, "height": 900})
            page.goto(page_file.resolve().as_uri())
            sizes = page.evaluate("""alts => alts.map(alt => {
                const img = [...document.images].find(i => i.alt === alt);
                return img ? [img.naturalWidth, img.getBoundingClientRect().width] : null; })""",
                                  list(alts))
        finally:
            browser.close()
    out = {}
    for alt, size in zip(alts, sizes):
        assert size is not None, f"no image {alt!r} on {page_file}"
        natural, shown = size
        assert natural > 0
        out[alt] = TEXT_PX * shown / natural
    return out


def test_annotated_text_is_legible_on_the_report_page(runs):
    from rvmsim.criteria.annotate import MIN_TEXT_PX

    px = shown_text_px(runs["report"], ("annotated EC image",))
    assert px["annotated EC image"] >= MIN_TEXT_PX, px


def test_the_display_picture_is_at_the_scenes_size_of_record(tmp_path, monkeypatch):
    """A scene whose display is 480 × 270 px: the report's display picture is drawn at that
    size, the RVM image of record, not at a fixed 1280 × 720 (issue #42)."""
    from rvmsim.tune import TuneRequest, tune
    from rvmsim.search import TuningConfig

    from rvmsim.testing.scenes import write_small_scene

    monkeypatch.setenv("RVMSIM_CACHE", str(tmp_path / "cache"))
    scene = write_small_scene(tmp_path, edit={"display": {"rvm_image_px": [480, 270]}})
    cfg = TuningConfig.model_validate({"output": {"size": [320, 180]}, "top_m": 2})
    run = tmp_path / "run"
    tune(TuneRequest((scene,), "random", cfg, budget=12), run)
    imgs = _parse(write_report(run).read_text(encoding="utf-8")).find("img")
    assert _decode_data_png(imgs[3]["src"]).shape[:2] == (270, 480)


def guideline_table(scene_file, params_file) -> tuple[bytes, object]:
    """The ECU table of a setting's guidelines made here, apart from the pages: the
    scene's car over its whole steering range, drawn through the params file's values
    (and mirroring) into the scene's image of record; and the guideline set."""
    scene = load_scene(scene_file)
    params, output = load_params(params_file)
    view = guideline_view(scene, params, output)
    gset = compute_guidelines(scene, view, steering_angles(running_gear(scene)))
    return table_bytes(gset), gset


def _guideline_shas(fragment: str) -> list[str]:
    return re.findall(r'<code class="sha">([0-9a-f]{64})</code>', fragment)


def _section_of(text: str, sid: str) -> str:
    start = text.index(f'<section id="{sid}">')
    return text[start: text.index("</section>", start)]


def test_the_report_shows_rank_1s_guidelines_and_their_tables_hash(runs):
    """The guidelines section: the picture is rank 1's RVM image of record with the static
    lines and the straight-ahead trajectory drawn; guidelines.bin beside the page is the
    table made here for the same setting, and the page shows its SHA-256."""
    text = runs["report"].read_text(encoding="utf-8")
    section = _section_of(text, "guidelines")
    table, gset = guideline_table(runs["scene"], runs["evil_run"] / "top" / "rank_1.yaml")
    digest = hashlib.sha256(table).hexdigest()
    assert (runs["evil_run"] / "guidelines.bin").read_bytes() == table
    assert _guideline_shas(section) == [digest]
    assert 'href="guidelines.bin"' in section and f"{len(table)} bytes" in section
    angles = gset.steering_deg
    words = " ".join(html.unescape(re.sub(r"<[^>]+>", " ", section)).split())
    assert f"{len(angles)} steering-wheel angles, {min(angles):+.1f}° to {max(angles):+.1f}°" \
        in words
    for line in gset.static:
        assert line.name in words
    pics = {a["alt"]: a["src"] for a in _parse(section).find("img")}
    assert set(pics) == {"guidelines straight ahead", "guidelines at full lock"}
    shown = _decode_data_png(pics["guidelines straight ahead"])[..., ::-1]  # BGR → RGB
    params, _ = load_params(runs["evil_run"] / "top" / "rank_1.yaml")
    rvm = rvm_color(cached_render(load_scene(runs["scene"]))[0], params, gset.view.output)
    want = draw_lines(rvm, gset.at(shown_angle(gset)), gset.spec.line_width_px)
    assert shown.shape == (720, 1280, 3) and np.array_equal(shown, want)
    assert not np.array_equal(shown, rvm)  # the lines are on it
    # the required-visible areas the lines are drawn over (FMVSS 111's, UN R158's), or none
    sc = load_scene(runs["scene"])
    covers = required_coverage(sc, gset, cached_render(sc)[0].labels)
    named = [(site, name) for site, objs in covers.items() for name in objs]
    if named:
        for site, name in named:
            assert f"{site} {name}" in words
    else:
        assert "The lines cover none of the test objects' required-visible areas" in words


def test_a_scene_without_the_running_gear_gets_the_reason_not_guidelines(runs, tmp_path):
    """The same run with the scene's wheelbase taken out (the render is the same): the
    section says why there are no guidelines, and no table is written."""
    scene = tmp_path / "scene.yaml"
    scene.write_text(re.sub(r"(?m)^\s*wheelbase:.*\n", "", runs["scene"].read_text()))
    run = tmp_path / "run"
    shutil.copytree(runs["evil_run"], run, ignore=shutil.ignore_patterns("*.html", "*.bin"))
    _record_scene(run, scene)
    section = _section_of(write_report(run).read_text(encoding="utf-8"), "guidelines")
    words = " ".join(html.unescape(re.sub(r"<[^>]+>", " ", section)).split())
    assert "no guidelines: vehicle.wheelbase: missing" in words, words
    assert "<img" not in section and not _guideline_shas(section)
    assert not (run / "guidelines.bin").exists()
