"""The sign-off sheet (`rvmsim signoff`), with the run report's and the robustness page's
new contents: a real small tuning run, a real robustness run of its best setting (with
end-of-line compensation), real validation and EOL folders, and the sheet made from them."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import re
import shlex
import shutil
from pathlib import Path

import cv2
import numpy as np
import pypdfium2 as pdfium
import pypdfium2.raw as pdfium_c
import pytest

from rvmsim.compensation import Deviation
from rvmsim.criteria.closeup import closeup, text_px_for_print
from rvmsim.errors import RvmsimError
from rvmsim.isp import OutputSpec, load_params
from rvmsim.pipeline import evaluate_params
from rvmsim.render import cached_render
from rvmsim.report import signoff, write_report
from rvmsim.report.page import path_html
from rvmsim.report.signoff import EC_PICTURE_MM, EC_PICTURE_PX, EC_TEXT_MM
from rvmsim.report.signoff_page import NO_ROBUSTNESS, SECTION_IDS
from rvmsim.scene import load_scene
from rvmsim.tune import DISPLAY_SIZE, TuneRequest, tune
from rvmsim.search import TuningConfig

from ..cli_runner import run_in_process
from rvmsim.testing.stations import write_capture, write_inputs
from rvmsim.testing.scenes import write_small_scene
from .test_run import (_assert_self_contained, _decode_data_png, _parse, _record_scene,
                       guideline_table)

#: A scene file name and vehicle name a page must escape.
SCENE_NAME = "scene <script>alert(1) & co.yaml"
VEHICLE = 'Evil <script>alert(2)</script> & "Co"'
LOAD = "full <load> & co"
REVIEWER = "Jane <b>Doe</b> & Co"
#: ±1° on every angle, two load states (two viewpoints: a quick robustness run).
VARIATION = {"mount": {a: {"uniform": {"half_width": 1.0}}
                       for a in ("yaw_deg", "pitch_deg", "roll_deg")},
             "load_states": [{"name": "curb", "height_mm": 0, "pitch_deg": 0, "weight": 1},
                             {"name": LOAD, "height_mm": -45, "pitch_deg": 0.9, "weight": 1}]}
SAMPLES = 8


def _rvmsim(*args: object, env: dict[str, str] | None = None, cwd: Path | None = None):
    return run_in_process(args, env=env, cwd=cwd)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A tuned run of an evil-named quarter-size vehicle A, robustness of its rank 1 with
    compensation, an EOL folder (one car), a validation folder (two captures the scene's
    board cannot be found in: two ERROR rows), and the sign-off of all of it (CLI)."""
    root = tmp_path_factory.mktemp("signoff")
    env = {"RVMSIM_CACHE": str(root / "cache")}
    old = os.environ.get("RVMSIM_CACHE")
    os.environ["RVMSIM_CACHE"] = env["RVMSIM_CACHE"]
    try:
        scene = write_small_scene(root, "a", name=SCENE_NAME, edit={"name": VEHICLE},
                                  variation=VARIATION)
        cfg = TuningConfig.model_validate({"output": {"size": [320, 180]}, "top_m": 2,
                                           "batch": 20})
        run = root / "run"
        tune(TuneRequest((scene,), "cmaes-solved", cfg, budget=60), run)
        params = run / "top" / "rank_1.yaml"
        res = _rvmsim("robustness", scene, "--params", params, "--samples", SAMPLES,
                      "--scales", "1", "--workers", "1", "--compensation", "default",
                      "--out", root / "rob", "--no-progress", env=env)
        assert res.code in (0, 1), res.stderr
        # the station of this vehicle (its name), writing on the platform setting signed
        eol_scene, _ = write_inputs(root / "eol_in", edit={"name": VEHICLE})
        car = write_capture(root / "eol_in" / "car <1> & co.png", Deviation())
        res = _rvmsim("eol", eol_scene, "--params", params, "--capture", car, "--out",
                      root / "eol", "--no-progress", env=env)
        assert res.code in (0, 1), res.stderr
        fisheye = cached_render(load_scene(scene))[0].color
        for k in (1, 2):
            cv2.imwrite(str(root / f"capture_{k}.png"), np.roll(fisheye, k, axis=1)[..., ::-1])
        res = _rvmsim("validate", scene, "--capture", root / "capture_1.png", "--capture",
                      root / "capture_2.png", "--out", root / "val", "--no-progress", env=env)
        assert (root / "val" / "summary.json").is_file(), res.stderr
        out = run / "signoff"
        res = _rvmsim("signoff", run, "--robustness", root / "rob", "--validation",
                      root / "val", "--eol", root / "eol", "--reviewer", REVIEWER, "--out",
                      out, "--no-progress", env=env)
        # the two captures are ERROR rows: the sheet fails, and says why on one line
        assert res.code == 1, res.stderr
        [line] = res.stderr.splitlines()
        assert line.startswith("the sheet fails: ") and \
            "Validation against a real capture: fails" in line, line
        yield {"root": root, "env": env, "scene": scene, "run": run, "params": params,
               "out": out, "stdout": res.stdout}
    finally:
        if old is None:
            os.environ.pop("RVMSIM_CACHE", None)
        else:
            os.environ["RVMSIM_CACHE"] = old


def _page(made) -> str:
    return (made["out"] / "signoff.html").read_text(encoding="utf-8")


def _text(fragment: str) -> str:
    """What a reader sees of an HTML fragment: its text without tags, unescaped (a path
    drawn in pieces, to break only after a /, reads whole)."""
    import html as html_lib

    return html_lib.unescape(re.sub(r"<[^>]+>", "", fragment))


def _section(text: str, sid: str) -> str:
    start = text.index(f'<section id="{sid}">')
    return text[start: text.index("</section>", start)]


def test_every_section_is_there_and_the_page_is_self_contained(made):
    text = _page(made)
    doc = _parse(text)
    ids = [a.get("id") for _, a in doc.tags if a.get("id")]
    assert [s for s in ids if s in SECTION_IDS] == list(SECTION_IDS)
    _assert_self_contained(text, doc)
    words = doc.all_text()
    for heading in ("The setting", "Input files", "Tool", "Evaluation criteria at the display",
                    "Production yield", "Failing samples", "Validation against a real capture",
                    "End-of-line station", "Signature"):
        assert heading in words, heading
    assert "0 of 2 captures pass" in words and "ERROR" in words
    assert "1 of 1 cars pass" in words or "0 of 1 cars pass" in words
    js = json.loads((made["out"] / "signoff.json").read_text())
    tool = js["tool"]
    assert tool["version"] and re.fullmatch(r"[0-9a-f]{40}|not a git checkout", tool["commit"])
    assert tool["date"].endswith("+00:00") and tool["cpu_count"] >= 1
    for value in (tool["version"], tool["commit"], tool["date"]):
        assert value in _section(text, "tool")


def test_the_ecs_are_judged_at_the_display_size_with_margins(made):
    text = _page(made)
    settings = json.loads((made["run"] / "run.json").read_text())
    mirror = settings["config"]["output"]["mirror"]
    params, _ = load_params(made["params"])
    images, _ = cached_render(load_scene(made["scene"]))
    frame = evaluate_params(images, params, OutputSpec(*DISPLAY_SIZE, mirror))
    js = json.loads((made["out"] / "signoff.json").read_text())
    assert js["record_output"] == list(DISPLAY_SIZE)
    assert [e["value"] for e in js["ecs"]["ecs"]] == pytest.approx(
        [i.value for i in frame.ec.items])
    section = _section(text, "ecs")
    rows = re.findall(r'<tr class="(pass|fail|off)"><td class="ecid">([^<]+)</td>.*?</tr>',
                      section, re.S)
    assert [r[1] for r in rows] == [i.id for i in frame.ec.items]
    for item in frame.ec.items:
        assert item.low is not None or item.high is not None
        margin = min(item.value - item.low if item.low is not None else np.inf,
                     item.high - item.value if item.high is not None else np.inf)
        assert f"{margin:+.4g}" in section, item.id
    imgs = _parse(section).find("img")
    shapes = [_decode_data_png(a["src"]).shape for a in imgs]
    assert (DISPLAY_SIZE[1], DISPLAY_SIZE[0], 3) in shapes  # the display picture
    assert len(imgs) == len(frame.ec.items) + 2  # one per EC, the picture, all ECs drawn


def test_the_hash_on_the_page_is_that_of_the_params_file(made, tmp_path):
    text = _page(made)
    shas = re.findall(r'<code class="sha">([0-9a-f]{64})</code>', _section(text, "setting"))
    params = made["params"]
    assert shas == [hashlib.sha256(params.read_bytes()).hexdigest()]
    assert str(params.resolve()) in _text(_section(text, "setting"))
    values, _ = load_params(params)
    for name in values.names():
        assert repr(getattr(values, name)) in _section(text, "setting")
    # A run whose top/ is gone: the sheet writes the params file itself and hashes that.
    run = tmp_path / "run"
    shutil.copytree(made["run"], run, ignore=shutil.ignore_patterns("signoff"))
    shutil.rmtree(run / "top")
    res = signoff(run, tmp_path / "so", pdf=False)
    assert res.params_file == tmp_path / "so" / "params.yaml"
    assert load_params(res.params_file) == load_params(params)
    page = res.html.read_text()
    assert re.findall(r'<code class="sha">([0-9a-f]{64})</code>',
                      _section(page, "setting")) == [
        hashlib.sha256(res.params_file.read_bytes()).hexdigest()] == [res.params_sha256]


def test_the_input_files_carry_their_hashes(made):
    section = _section(_page(made), "inputs")
    for path in (made["scene"], made["params"], made["root"] / "rob" / "robustness.json",
                 made["root"] / "eol" / "eol.json", made["root"] / "val" / "summary.json"):
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        assert digest in section, path
    assert "redbox" not in section  # nothing changed since the robustness run


def test_the_yield_before_and_after_compensation_per_ec_and_load(made):
    section = _section(_page(made), "yield")
    rob = json.loads((made["root"] / "rob" / "robustness.json").read_text())
    before = rob["yield_before_compensation"]
    for est in (rob, before, *rob["yield_by_load"].values(), *before["by_load"].values()):
        assert f"{100 * est['yield']:.1f} %" in section
    assert "full &lt;load&gt; &amp; co" in section and LOAD not in section
    for e in rob["ecs"]:
        assert f"<td class=\"ecid\">{e['id']}</td>" in section
        assert f"{100 * e['failure_rate']:.1f} %" in section
    assert "uniform ±1" in section  # the tolerance figures


def test_each_failing_sample_has_a_command_that_reproduces_it(made, tmp_path):
    rob = json.loads((made["root"] / "rob" / "robustness.json").read_text())
    failing = [s for s in rob["samples"] if not s["passed"]]
    section = _section(_page(made), "failing-samples")
    if not failing:
        assert "None of the" in section
        return
    import html as html_lib

    # one command per distinct failure (the same failing ECs), in the appendix
    appendix = _section(_page(made), "reproduce")
    commands = [html_lib.unescape(c) for c in re.findall(r"<code>(rvmsim robustness.*?)</code>",
                                                         appendix)]
    assert len(commands) == len({tuple(sorted(s["failed"])) for s in failing})
    assert "rvmsim robustness" not in section
    first = failing[0]
    cmd = next(c for c in commands if f"--export-sample {first['index']} " in c)
    produce, evaluate = cmd.split(" && ")
    res = _rvmsim(*shlex.split(produce)[1:], env=made["env"], cwd=tmp_path)
    assert res.code in (0, 1), res.stderr
    exported = json.loads(Path(shlex.split(evaluate)[2]).with_suffix(".json").read_text())
    # The same car, measured the same: the ECs that failed fail again, and only they.
    ids = {e["id"] for e in rob["ecs"]}
    assert {e for e, v in exported["ecs"].items() if not v["passed"]} == \
        {f for f in first["failed"] if f in ids}
    res = _rvmsim(*shlex.split(evaluate)[1:], env=made["env"], cwd=tmp_path)
    assert res.code == 1, res.stderr  # evaluate judges the failing car: exit 1, as recorded
    assert res.stderr.splitlines()[-1].startswith("not every EC passes: ")


def test_the_pdf_is_printed(made):
    if shutil.which("chromium") is None:
        pytest.skip("chromium is not installed (tools/setup.sh installs it)")
    pdf = made["out"] / "signoff.pdf"
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF") and len(data) > 20_000
    assert data.rstrip().endswith(b"%%EOF")


def _pdf_pages(path: Path) -> list[str]:
    """Each page's text as PDFium reads it (lines as laid out on the page)."""
    doc = pdfium.PdfDocument(str(path))
    try:
        return [doc[k].get_textpage().get_text_range() for k in range(len(doc))]
    finally:
        doc.close()


def test_the_pdf_pages_are_numbered_headed_and_keep_hashes_whole(made):
    """Every page: "page N of M" and a running header (the vehicle, the setting's hash, the
    date); the signature block on the summary's page or the next; every SHA-256 on the
    sheet whole on one line."""
    if shutil.which("chromium") is None:
        pytest.skip("chromium is not installed (tools/setup.sh installs it)")
    js = json.loads((made["out"] / "signoff.json").read_text())
    pages = _pdf_pages(made["out"] / "signoff.pdf")
    assert len(pages) >= 3
    for k, text in enumerate(pages, 1):
        assert f"page {k} of {len(pages)}" in text, (k, text[-200:])
        assert "Sign-off:" in text and js["params_sha256"][:16] in text
        assert js["tool"]["date"][:10] in text
    signature = [k for k, text in enumerate(pages) if "Decision (approved / rejected)" in text]
    summary = [k for k, text in enumerate(pages) if "Least yield that passes" in text]
    assert signature and summary and signature[0] - summary[0] in (0, 1)
    lines = [ln.strip() for text in pages for ln in text.splitlines()]
    digests = {f["sha256"] for f in js["files"] if f["sha256"]} | {
        js["params_sha256"], js["guidelines"]["sha256"]}
    for digest in digests:
        assert any(digest in ln for ln in lines), digest  # never split across lines


#: Resolution the close-ups' page is rendered at to measure its text (dots per inch).
_DPI = 300


def _glyph_height_px(box: np.ndarray) -> float:
    """The height (px) of a label's tall glyphs (capitals, digits, ascenders) in a rendered
    label box: light text on the box's dark ground, its outline trimmed."""
    gray = cv2.cvtColor(box[3:-3, 3:-3], cv2.COLOR_RGB2GRAY)
    n, _, stats, _ = cv2.connectedComponentsWithStats((gray > 128).astype(np.uint8), 8)
    heights = stats[1:, cv2.CC_STAT_HEIGHT]
    tall = heights[heights >= 0.85 * heights.max()]  # not the x-height letters
    return float(np.median(tall))


def test_the_pdf_close_ups_are_wide_and_their_labels_readable_on_paper(made):
    """Each enabled EC has a close-up in the PDF, printed at least 60 mm wide, whose label
    text, measured in the page rendered at 300 dpi, is at least 2.5 mm tall."""
    if shutil.which("chromium") is None:
        pytest.skip("chromium is not installed (tools/setup.sh installs it)")
    settings = json.loads((made["run"] / "run.json").read_text())
    params, _ = load_params(made["params"])
    images, _ = cached_render(load_scene(made["scene"]))
    frame = evaluate_params(images, params, OutputSpec(*DISPLAY_SIZE,
                                                       settings["config"]["output"]["mirror"]))
    text_px = text_px_for_print(EC_PICTURE_PX, EC_PICTURE_MM, EC_TEXT_MM)
    wanted = {}
    for k, item in enumerate(frame.ec.items):
        if item.enabled:
            one = dataclasses.replace(frame.ec, items=(item,), definitions=(
                (frame.ec.definitions[k],) if frame.ec.definitions else ()))
            wanted[item.id] = closeup(frame.color, frame.labels, one, width_px=EC_PICTURE_PX,
                                      text_px=text_px)
    doc = pdfium.PdfDocument(str(made["out"] / "signoff.pdf"))
    found, measured = {}, []
    try:
        for page in doc:
            text = page.get_textpage()
            bitmap = None
            for obj in page.get_objects(filter=[pdfium_c.FPDF_PAGEOBJ_IMAGE]):
                left, bottom, right, top = obj.get_bounds()
                caption = text.get_text_bounded(left, bottom - 16, right, bottom).strip()
                ec_id = caption.split(" ")[0] if caption else ""
                if ec_id not in wanted or ec_id in found:
                    continue
                found[ec_id] = (right - left) / 72 * 25.4  # printed width, mm
                if bitmap is None:
                    bitmap = page.render(scale=_DPI / 72).to_numpy()
                h_page = page.get_height()
                per_px = (right - left) / EC_PICTURE_PX * _DPI / 72  # page px per close-up px
                for lab in wanted[ec_id].labels:
                    x0, y0, x1, y1 = lab.box
                    px0 = int(round(left * _DPI / 72 + x0 * per_px))
                    py0 = int(round((h_page - top) * _DPI / 72 + y0 * per_px))
                    box = bitmap[py0: py0 + int((y1 - y0) * per_px),
                                 px0: px0 + int((x1 - x0) * per_px), :3]
                    measured.append((ec_id, lab.text, _glyph_height_px(box) / _DPI * 25.4))
    finally:
        doc.close()
    assert sorted(found) == sorted(wanted)
    assert min(found.values()) >= 60.0, found
    assert measured and min(mm for _, _, mm in measured) >= 2.5, measured


def test_without_robustness_the_page_says_so_in_red(made, tmp_path):
    res = signoff(made["run"], tmp_path / "so", pdf=False)
    assert res.yield_ is None
    text = res.html.read_text()
    assert f'<span class="red">{NO_ROBUSTNESS}</span>' in _section(text, "verdict")
    assert "Robustness not run" in _section(text, "yield")
    assert "Not given" in _section(text, "validation") and "Not given" in _section(text, "eol")


def test_names_from_files_are_escaped(made):
    text = _page(made)
    for raw in (SCENE_NAME, VEHICLE, REVIEWER, LOAD):
        assert raw not in text
    assert "scene &lt;script&gt;alert(1) &amp; co.yaml" in text
    assert "Evil &lt;script&gt;alert(2)&lt;/script&gt; &amp; &quot;Co&quot;" in text
    assert "Jane &lt;b&gt;Doe&lt;/b&gt; &amp; Co" in _section(text, "signature")
    assert "car &lt;1&gt; &amp; co" in _section(text, "eol")
    rob = (made["root"] / "rob" / "robustness.html").read_text()
    assert SCENE_NAME not in rob and "scene &lt;script&gt;" in rob


def test_the_robustness_page_shows_the_setting_tolerances_and_load_states(made):
    text = (made["root"] / "rob" / "robustness.html").read_text()
    setting = text[text.index('<h2 id="setting">'): text.index('<h2 id="inputs">')]
    digest = hashlib.sha256(made["params"].read_bytes()).hexdigest()
    assert digest in setting and str(made["params"].resolve()) in _text(setting)
    values, _ = load_params(made["params"])
    for name in values.names():
        assert repr(getattr(values, name)) in text
    assert "uniform ±1" in text and "full &lt;load&gt; &amp; co" in text and "-45" in text
    rob = json.loads((made["root"] / "rob" / "robustness.json").read_text())
    files = {f["role"]: f for f in rob["inputs"]["files"]}
    assert files["params"]["sha256"] == digest
    assert files["scene"]["sha256"] == hashlib.sha256(made["scene"].read_bytes()).hexdigest()


def test_the_run_report_gains_margins_tool_display_picture_and_yield(made, tmp_path):
    report = write_report(made["run"]).read_text()
    doc = _parse(report)
    assert "<th>margin</th>" in report
    assert re.search(r'<figure id="display"><img src="([^"]+)"', report)
    src = re.search(r'<figure id="display"><img src="([^"]+)"', report).group(1)
    assert _decode_data_png(src).shape[:2] == (DISPLAY_SIZE[1], DISPLAY_SIZE[0])
    tool = json.loads((made["out"] / "signoff.json").read_text())["tool"]
    assert tool["version"] in doc.all_text() and "commit" in doc.all_text()
    rob = json.loads((made["root"] / "rob" / "robustness.json").read_text())
    assert f"{100 * rob['yield']:.1f} %" in re.search(r'id="yield-note".*?</p>', report).group(0)
    assert 'href="signoff/signoff.html"' in report
    # The same run without a sign-off or robustness result: a neutral note, and how to make one.
    run = tmp_path / "run"
    shutil.copytree(made["run"], run, ignore=shutil.ignore_patterns("signoff"))
    bare = write_report(run).read_text()
    note = re.search(r'id="yield-note".*?</p>', bare, re.S).group(0)
    assert "nominal pose" in note and "not measured" in note
    assert "rvmsim signoff" in re.search(r'id="signoff-link".*?</p>', bare).group(0)


def test_a_robustness_result_of_other_values_or_changed_files_is_flagged(made, tmp_path):
    """A robustness.json whose setting is not the run's rank 1, or whose recorded scene hash
    is not the scene's now: red boxes naming them, and the report ignores that yield."""
    rob = tmp_path / "rob"
    shutil.copytree(made["root"] / "rob", rob)
    doc = json.loads((rob / "robustness.json").read_text())
    doc["isp"]["zoom"] += 0.01
    scene_rec = next(f for f in doc["inputs"]["files"] if f["role"] == "scene")
    scene_rec["sha256"] = "0" * 64
    (rob / "robustness.json").write_text(json.dumps(doc))
    with pytest.raises(RvmsimError, match=r"robustness\.json: judged another setting .*"
                                          r"--allow-other-setting"):
        signoff(made["run"], tmp_path / "refused", robustness=rob, pdf=False)
    assert not (tmp_path / "refused").exists()
    res = signoff(made["run"], tmp_path / "so", robustness=rob, pdf=False,
                  allow_other_setting=True)
    text = res.html.read_text()
    assert len(res.other_setting) == 1 and "judged another setting" in res.other_setting[0]
    banner = re.search(r'<p class="redbox"><b>Signed with records of another setting.*?</p>',
                       text)
    assert banner and text.index(banner.group(0)) < text.index('<section id="verdict">')
    assert "judged a different setting" in _section(text, "yield")
    changed = re.search(r'<p class="redbox">Changed since.*?</p>', _section(text, "inputs"))
    assert changed and str(made["scene"].resolve()) in _text(changed.group(0))
    assert str(made["params"].resolve()) not in _text(changed.group(0))
    js = json.loads((tmp_path / "so" / "signoff.json").read_text())
    assert js["robustness"]["same_setting"] is False
    assert js["other_setting"] == list(res.other_setting)
    assert js["changed_files"] == [str(made["scene"].resolve())]


def test_signoff_refuses_an_eol_record_of_another_vehicle_unless_allowed(made, tmp_path):
    """The command line: exit 2 and one line naming eol.json and both vehicles; with
    --allow-other-setting, exit 0, a warning on stderr and the banner on the sheet."""
    eol = tmp_path / "eol"
    shutil.copytree(made["root"] / "eol", eol)
    doc = json.loads((eol / "eol.json").read_text())
    assert doc["scene"] == VEHICLE and doc["platform_isp"]  # the fixture's is this vehicle's
    doc["scene"] = "Vehicle B"
    (eol / "eol.json").write_text(json.dumps(doc))
    out = tmp_path / "so"
    res = _rvmsim("signoff", made["run"], "--eol", eol, "--out", out, "--no-pdf",
                  "--no-progress", env=made["env"])
    assert res.code == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
    assert "eol.json: judged vehicle 'Vehicle B'" in res.stderr and "Traceback" not in res.stderr
    assert not out.exists()
    res = _rvmsim("signoff", made["run"], "--eol", eol, "--out", out, "--no-pdf",
                  "--no-progress", "--allow-other-setting", env=made["env"])
    signed = json.loads((out / "signoff.json").read_text())
    assert res.code == (0 if signed["passed"] else 1), res.stderr
    assert "warning:" in res.stderr and "Vehicle B" in res.stderr
    assert "Signed with records of another setting" in (out / "signoff.html").read_text()


def html_escape(s: str) -> str:
    import html

    return html.escape(s, quote=True)


def test_the_summary_gives_the_verdict_both_yields_the_limiting_ec_and_the_model(made):
    """The summary says PASS/FAIL and why (from the records themselves), the yield after
    and before compensation with their intervals, the limiting EC (the enabled EC failing
    on most samples, counted here from robustness.json's rows), that no least yield was
    given, and the compensation model the yield assumes (the built-in default, in full)."""
    text = _page(made)
    summary = _section(text, "verdict")
    js = json.loads((made["out"] / "signoff.json").read_text())
    rob = json.loads((made["root"] / "rob" / "robustness.json").read_text())
    eol = json.loads((made["root"] / "eol" / "eol.json").read_text())
    ecs_pass = all(e["passed"] for e in js["ecs"]["ecs"] if e["enabled"])
    expected_fail = {"Validation against a real capture"} | (
        set() if ecs_pass else {"ECs at the display output of record"}) | (
        set() if eol["passed"] == eol["cars"] else {"End-of-line station"})
    assert {c["name"] for c in js["checks"] if c["passed"] is False} == expected_fail
    assert js["passed"] is False and '<span class="badge fail">FAIL</span>' in summary
    # both yields, each with its interval and counts, as robustness.json has them
    for est in (rob, rob["yield_before_compensation"]):
        lo, hi = est["ci95"]
        assert (f"{100 * est['yield']:.1f} % (95 % CI {100 * lo:.1f}–{100 * hi:.1f} %, "
                f"{est['n_pass']} of {est['n']} samples)") in summary
    assert "before compensation" in summary
    # the limiting EC, counted from the per-EC rows
    failing = [e for e in rob["ecs"] if e["enabled"] and e["n_fail"]]
    if failing:
        most = max(e["n_fail"] for e in failing)
        tops = [e for e in failing if e["n_fail"] == most]
        lim = min(tops, key=lambda e: e["worst_margin"])
        assert f"{lim['id']} " in summary and rob["limiting"]["id"] == lim["id"]
        assert f"{100 * lim['failure_rate']:.1f} % of the samples" in summary
    else:
        assert rob["limiting"] is None and "no EC fails on any sample" in summary
    assert "no least yield given" in summary and js["min_yield"] is None
    # the compensation model: built-in, its law, values, σ, and every value in the section
    assert "law ec-solve" in summary and "built-in default" in summary
    from rvmsim.compensation import DEFAULT_COMPENSATION as D
    yield_section = _section(text, "yield")
    assert "End-of-line compensation model" in yield_section
    for value in (f"{D.angle_sigma_deg}°, {D.position_sigma_mm} mm", f"{D.edge_sigma_px} px",
                  D.law, D.marginal, D.stop, str(D.budget)):
        assert value in yield_section, value
    for name, lo, hi in D.ranges:
        assert f"<th>range of {name}</th><td>{lo:g} … {hi:g}°</td>" in yield_section
    rows = [f for f in js["files"] if f["role"] == "compensation (robustness)"]
    assert len(rows) == 1 and rows[0]["sha256"] is None and "built-in" in rows[0]["path"]


def test_the_least_yield_gates_the_sheet_and_a_model_file_is_named_with_its_hash(made,
                                                                               tmp_path):
    """A copy of the robustness record that names a least yield above its yield, and a
    compensation model read from a file: the yield check fails (exit 1, the line says
    which figure), the sheet names the model's file with that file's SHA-256; --min-yield
    0 overrides the record and the yield check passes."""
    rob = tmp_path / "rob"
    shutil.copytree(made["root"] / "rob", rob)
    doc = json.loads((rob / "robustness.json").read_text())
    n = int(doc["n"])
    if doc["n_pass"] == n:  # a yield below 100 %
        doc.update({"yield": (n - 1) / n, "n_pass": n - 1})
    model = tmp_path / "station <model>.yaml"
    model.write_text("station: {angle_sigma_deg: 0.2}\n")
    digest = hashlib.sha256(model.read_bytes()).hexdigest()
    doc["min_yield"] = 1.0
    doc["compensation"]["source"] = str(model)
    doc["inputs"]["compensation"] = str(model)
    doc["inputs"]["files"].append({"role": "compensation", "path": str(model),
                                   "sha256": digest, "note": ""})
    (rob / "robustness.json").write_text(json.dumps(doc))
    res = _rvmsim("signoff", made["run"], "--robustness", rob, "--out", tmp_path / "a",
                  "--no-pdf", "--no-progress", env=made["env"])
    js = json.loads((tmp_path / "a" / "signoff.json").read_text())
    [check] = [c for c in js["checks"] if c["name"] == "Production yield"]
    assert check["passed"] is False and js["min_yield"] == 1.0
    assert res.code == 1 and f"Production yield: {100 * doc['yield']:.1f} % < 100 %" in \
        res.stderr, res.stderr
    page = (tmp_path / "a" / "signoff.html").read_text()
    assert "the robustness run&#x27;s, in robustness.json" in _section(page, "verdict")
    assert f'{path_html(model)} sha256 <code class="sha">{digest}</code>' in \
        _section(page, "yield")
    assert [f["sha256"] for f in js["files"] if f["role"] == "compensation (robustness)"] \
        == [digest]
    res = _rvmsim("signoff", made["run"], "--robustness", rob, "--out", tmp_path / "b",
                  "--min-yield", "0", "--no-pdf", "--no-progress", env=made["env"])
    js = json.loads((tmp_path / "b" / "signoff.json").read_text())
    [check] = [c for c in js["checks"] if c["name"] == "Production yield"]
    ecs_pass = all(e["passed"] for e in js["ecs"]["ecs"] if e["enabled"])
    assert check["passed"] is True and js["min_yield"] == 0.0
    assert res.code == (0 if ecs_pass else 1), res.stderr


def test_the_sheet_signs_the_guidelines_table_by_its_hash(made):
    """The sheet shows the guidelines' picture, the steering angles covered and the
    SHA-256 of guidelines.bin, written beside it: the table made here for the same
    setting; the summary, signoff.json and the command's output give the same hash."""
    out = made["out"]
    table, gset = guideline_table(made["scene"], made["params"])
    digest = hashlib.sha256(table).hexdigest()
    assert (out / "guidelines.bin").read_bytes() == table
    text = _page(made)
    section = _section(text, "guidelines")
    assert re.findall(r'<code class="sha">([0-9a-f]{64})</code>', section) == [digest]
    assert digest in _section(text, "verdict")
    angles = gset.steering_deg
    covered = f"{len(angles)} steering-wheel angles, {min(angles):+.1f}° to {max(angles):+.1f}°"
    assert covered in _text(section) and covered in _text(_section(text, "verdict"))
    [src] = [a["src"] for a in _parse(section).find("img") if a["alt"] ==
             "guidelines straight ahead"]
    assert _decode_data_png(src).shape[:2] == (DISPLAY_SIZE[1], DISPLAY_SIZE[0])
    js = json.loads((out / "signoff.json").read_text())["guidelines"]
    assert js["sha256"] == digest and js["bytes"] == len(table)
    assert js["steering_deg"] == sorted(angles) and js["file"] == str(out / "guidelines.bin")
    assert f"guidelines: guidelines.bin sha256 {digest}; {covered}" in made["stdout"]


def test_a_sheet_without_the_running_gear_says_why_it_has_no_guidelines(made, tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text(re.sub(r"(?m)^\s*max_road_wheel_deg:.*\n", "", made["scene"].read_text()))
    run = tmp_path / "run"
    shutil.copytree(made["run"], run, ignore=shutil.ignore_patterns("signoff"))
    _record_scene(run, scene)
    res = signoff(run, tmp_path / "so", pdf=False)
    text = res.html.read_text()
    why = "no guidelines: vehicle.max_road_wheel_deg: missing"
    assert why in _text(_section(text, "guidelines")) and why in _text(_section(text, "verdict"))
    assert res.guidelines_sha256 is None and res.guidelines_file is None
    assert res.guidelines_text.startswith(why)
    assert not (tmp_path / "so" / "guidelines.bin").exists()
    js = json.loads((tmp_path / "so" / "signoff.json").read_text())
    assert js["guidelines"]["none"].startswith("vehicle.max_road_wheel_deg: missing")
