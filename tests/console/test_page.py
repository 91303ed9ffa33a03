"""The console page's behaviour in a real browser (Chromium through Playwright): refused
values, stale marking, the setting in the URL, saving, the A/B view, margin bars, keys,
accessible names, number boxes and contrast."""

from __future__ import annotations

import json
import shlex
from urllib.parse import parse_qs, urlsplit

import pytest

from rvmsim.console import check_access, ec_margin, open_session

from ..cli_runner import run_in_child
from .conftest import serving
from .test_browser import _drag, _image_loaded, _new_page, _open, _settled

ZOOM_RANGE = (0.01, 10.0)  # zoom's allowed range (PARAM_SPECS)


@pytest.fixture(scope="module")
def served(small_run, browser, tmp_path_factory):
    import shutil

    folder = tmp_path_factory.mktemp("page")
    shutil.copy(small_run / "scene.yaml", folder / "scene.yaml")
    shutil.copytree(small_run / "run", folder / "run")
    session = open_session(folder / "run")
    with serving(session, check_access("127.0.0.1", None)) as url:
        yield folder, session, url


def _evaluated_zooms(page) -> list[float]:
    """The zoom of every evaluation the page asks for from now on (filled as it asks)."""
    seen: list[float] = []

    def note(request) -> None:
        if "/api/evaluate" in request.url:
            q = json.loads(parse_qs(urlsplit(request.url).query)["q"][0])
            seen.append(q["params"].get("zoom"))
    page.on("request", note)
    return seen


def test_a_value_out_of_range_never_enters_the_setting(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    _settled(page)
    zoom = page.evaluate("window.rvmConsole.current.zoom")
    asked = _evaluated_zooms(page)
    page.fill("#box-zoom", "50")
    page.press("#box-zoom", "Enter")
    beside = page.locator("#err-zoom")
    assert beside.is_visible() and "outside" in beside.text_content()
    assert "50" in page.text_content("#message")
    assert page.evaluate("window.rvmConsole.current.zoom") == zoom
    assert float(page.input_value("#box-zoom")) == pytest.approx(zoom, rel=1e-6)
    assert page.get_attribute("#box-zoom", "aria-invalid") == "true"
    assert page.evaluate("document.body.dataset.stale") == "0"
    # the next slider move is evaluated and shown, with no error
    _drag(page, "#slider-zoom", 0.7)
    _settled(page)
    assert 50 not in asked and asked
    assert page.evaluate("window.rvmConsole.last.params.zoom") != zoom
    assert page.get_attribute("#message", "class") != "error"
    assert page.evaluate("document.body.dataset.stale") == "0"
    assert not errors


def test_a_value_the_server_refuses_is_taken_back_and_its_message_shown_beside(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    _settled(page)
    good = page.evaluate("window.rvmConsole.current.zoom")
    # past the page's own check (as a server with a stricter rule would refuse it)
    page.evaluate("(() => { const s = window.rvmConsole; s.current.zoom = 50; s.request(); })()")
    page.wait_for_function("!document.getElementById('err-zoom').hidden")
    text = page.text_content("#err-zoom")
    assert "zoom" in text and "outside [0.01, 10]" in text  # the server's words
    _settled(page)
    assert page.evaluate("window.rvmConsole.current.zoom") == good
    assert page.evaluate("document.body.dataset.stale") == "0"
    _drag(page, "#slider-zoom", 0.3)
    _settled(page)
    assert page.evaluate("window.rvmConsole.last.params.zoom") != good
    assert page.get_attribute("#message", "class") != "error"
    assert not errors


def test_picture_and_badge_are_marked_stale_until_their_frame_is_shown(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    _settled(page)
    held = []
    page.route("**/api/evaluate*", lambda route: held.append(route))
    page.fill("#box-fov", "150")
    page.press("#box-fov", "Enter")
    page.wait_for_function("document.body.dataset.stale === '1'")
    assert page.locator("#rvm-view.stale").count() == 1
    assert page.locator("#score.stale").count() == 1
    assert page.locator("#stale-note").is_visible()
    page.wait_for_timeout(100)
    assert page.evaluate("document.body.dataset.stale") == "1"  # still: nothing came back
    for route in held:
        route.continue_()
    page.unroute("**/api/evaluate*")
    _settled(page)
    assert page.evaluate("document.body.dataset.stale") == "0"
    assert page.locator("#score.stale").count() == 0 and not page.locator("#stale-note").is_visible()
    assert page.evaluate("window.rvmConsole.last.params.fov") == 150.0
    assert not errors


def _state(page) -> dict:
    return page.evaluate("(() => { const s = window.rvmConsole; return {current: s.current, "
                         "annotate: s.annotate, b: s.b, shown: s.shown.params}; })()")


def test_the_setting_lives_in_the_url(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    _settled(page)
    page.fill("#box-fov", "150")
    page.press("#box-fov", "Enter")
    _settled(page)
    page.click("#pin")
    page.wait_for_function("window.rvmConsole.b !== null")
    page.fill("#box-zoom", "0.75")
    page.press("#box-zoom", "Enter")
    page.check("#annotate")
    _settled(page)
    page.wait_for_function("location.hash.includes('annotate=1') && location.hash.includes('b=')")
    before = _state(page)
    link = page.url
    page.reload()
    page.wait_for_function("window.rvmConsole && window.rvmConsole.frames >= 1", timeout=30000)
    _settled(page)
    page.wait_for_function("window.rvmConsole.b !== null")
    assert _state(page) == before
    assert before["current"]["fov"] == 150.0 and before["current"]["zoom"] == 0.75
    assert before["b"]["fov"] == 150.0 and before["b"]["zoom"] == session.start.zoom
    assert page.is_checked("#annotate") and page.input_value("#box-fov") == "150"
    # shared: a new browser context opening the link sees the same
    other, other_errors = _open(browser, link)
    _settled(other)
    other.wait_for_function("window.rvmConsole.b !== null")
    assert _state(other) == before
    # a bad value in a link is not used, and said so
    bad, bad_errors = _open(browser, f"{url}/#zoom=50&fov=150")
    _settled(bad)
    assert bad.evaluate("window.rvmConsole.current.zoom") == session.start.zoom
    assert bad.evaluate("window.rvmConsole.current.fov") == 150.0
    assert "zoom" in bad.text_content("#message") and "outside" in bad.text_content("#err-zoom")
    assert not errors and not other_errors and not bad_errors


def test_ab_side_by_side_above_the_fold_and_never_a_broken_image(served, browser):
    folder, session, url = served
    page = _new_page(browser)  # 1400 × 900
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    broken = ("[...document.images].filter(i => i.checkVisibility() && "
              "(!i.complete || i.naturalWidth === 0)).map(i => i.id)")
    held = []
    page.route("**/api/evaluate*", lambda route: held.append(route))
    page.goto(url)
    page.wait_for_function("document.body.dataset.ready === '1'")
    page.wait_for_function("document.getElementById('fisheye').complete")
    assert page.evaluate(broken) == []  # before any frame: placeholders, no empty picture
    assert page.locator("#ab-a-empty").is_visible() and page.locator("#ab-b-empty").is_visible()
    for route in held:
        route.continue_()
    page.unroute("**/api/evaluate*")
    _settled(page)
    assert page.evaluate(broken) == []
    assert not page.locator("#ab-b").is_visible()
    assert page.locator("#ab-b-empty").is_visible()
    a = page.locator("#ab-a").bounding_box()
    b = page.locator("#ab-b-empty").bounding_box()
    assert a and b and a["y"] + a["height"] <= 900 and b["y"] + b["height"] <= 900
    assert abs(a["y"] - b["y"]) < 2 and b["x"] >= a["x"] + a["width"]
    b_before = page.get_attribute("#ab-b", "src")
    page.click('#candidates tr[data-rank="2"] button.as-b')
    page.wait_for_function("window.rvmConsole.b !== null")
    _image_loaded(page, "#ab-b", "/display", b_before)
    assert page.locator("#ab-b").is_visible() and not page.locator("#ab-b-empty").is_visible()
    assert page.evaluate(broken) == []
    b = page.locator("#ab-b").bounding_box()
    cap = page.locator("#ab-b-cap").bounding_box()
    assert b and cap and cap["y"] + cap["height"] <= 900 and abs(a["y"] - b["y"]) < 2
    assert "candidate #2" in page.text_content("#ab-b-cap")
    assert page.evaluate("document.getElementById('ab-b').naturalWidth") == session.display.width
    assert not errors


def test_margin_bars_show_how_far_inside_or_outside_each_range(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    _settled(page)
    _drag(page, "#slider-zoom", 0.15)  # a view where some ECs fail
    _settled(page)
    ecs = page.evaluate("window.rvmConsole.last.ecs")
    rows = page.eval_on_selector_all("#ec-table tbody tr", """rows => rows.map(r => {
        const td = r.querySelector('td.margin'), fill = td.querySelector('.fill'),
              bar = td.querySelector('.mbar');
        return {margin: td.dataset.margin === undefined ? null : Number(td.dataset.margin),
                cls: fill ? fill.className : null, text: td.textContent,
                width: fill ? fill.getBoundingClientRect().width : null,
                left: fill ? fill.getBoundingClientRect().left : null,
                barLeft: bar ? bar.getBoundingClientRect().left : null,
                barWidth: bar ? bar.getBoundingClientRect().width : null}; })""")
    assert len(rows) == len(ecs)
    signs = set()
    yes_no = 0
    for row, ec in zip(rows, ecs):
        if ec["range"][0] is not None and ec["range"][0] == ec["range"][1]:  # 1-1, 2-4
            assert ec["yes_no"] and row["margin"] is None and row["cls"] is None
            assert row["text"] == ("—" if ec["value"] is None else
                                   "✓" if ec["passed"] else "✗")  # as report and sign-off
            yes_no += 1
            continue
        assert not ec["yes_no"]
        want = ec_margin(ec["value"], *ec["range"])
        if want is None:
            assert row["margin"] is None and row["text"] == "—"
            continue
        assert row["margin"] == pytest.approx(want, rel=1e-9)
        inside = want >= 0
        signs.add(inside)
        if ec["enabled"]:
            assert inside == ec["passed"], ec
        assert row["cls"].endswith("inside" if inside else "outside")
        inner = row["barWidth"] - 2  # the bar's border
        assert row["width"] == pytest.approx(min(1.0, abs(want)) * inner / 2, abs=1.5)
        middle = row["barLeft"] + 1 + inner / 2
        if inside:
            assert row["left"] == pytest.approx(middle, abs=1.5)
        else:
            assert row["left"] + row["width"] == pytest.approx(middle, abs=1.5)
    assert signs == {True, False}  # both kinds drawn
    assert yes_no == 2  # 1-1 and 2-4
    assert not errors


def test_page_keys_move_a_slider_by_at_most_1_percent(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    _settled(page)
    for name in ("zoom", "fov", "h_pan"):
        lo, hi = (float(page.get_attribute(f"#slider-{name}", k)) for k in ("min", "max"))
        page.focus(f"#slider-{name}")
        for key, sign in (("PageUp", 1), ("PageDown", -1), ("ArrowRight", 1)):
            before = page.evaluate(f"window.rvmConsole.current.{name}")
            page.keyboard.press(key)
            _settled(page)
            after = page.evaluate(f"window.rvmConsole.current.{name}")
            moved = (after - before) * sign
            at_end = after in (lo, hi)
            assert 0 < moved <= 0.01 * (hi - lo) * (1 + 1e-9) or at_end, (name, key, before, after)
            assert page.evaluate(f"window.rvmConsole.last.params.{name}") == after
    assert not errors


def test_sliders_have_human_names(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    slider = page.get_by_role("slider", name="Advanced vertical shift (adv_v_shift)", exact=True)
    assert slider.count() == 1 and slider.get_attribute("id") == "slider-adv_v_shift"
    box = page.get_by_role("spinbutton", name="Advanced vertical shift (adv_v_shift) value",
                           exact=True)
    assert box.count() == 1
    names = page.eval_on_selector_all("#controls input[type=range]", "els => els.map(e => e.name)")
    assert len(names) == 14
    for name in names:
        snap = page.locator(f"#slider-{name}").aria_snapshot()
        human = snap.split('"')[1]
        assert human.endswith(f"({name})") and len(human) > len(name) + 4
        assert human != name and "_" not in human.split(" (")[0]
    assert not errors


def test_number_boxes_show_7_digit_values_whole(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    for name in page.eval_on_selector_all("input[type=number]", "els => els.map(e => e.name)"):
        for text in ("-1234.567", "1234567", "-0.1234567", "-0.001234567", "0.005214949"):
            fits = page.eval_on_selector(f"#box-{name}", """(e, text) => {
                e.value = text;
                const cs = getComputedStyle(e), c = document.createElement('canvas').getContext('2d');
                c.font = `${cs.fontWeight} ${cs.fontSize} ${cs.fontFamily}`;
                const room = e.clientWidth - parseFloat(cs.paddingLeft) - parseFloat(cs.paddingRight)
                             - 16;  // the spin buttons
                return [c.measureText(text).width, room]; }""", text)
            assert fits[0] <= fits[1], (name, text, fits)
    assert not errors


_CONTRAST_JS = """() => {
  const rgb = (s) => (s.match(/[\\d.]+/g) || []).map(Number);
  const lum = (c) => { const f = (v) => { v /= 255; return v <= 0.03928 ? v / 12.92 :
      Math.pow((v + 0.055) / 1.055, 2.4); }; return 0.2126 * f(c[0]) + 0.7152 * f(c[1]) + 0.0722 * f(c[2]); };
  const bg = (el) => { for (let e = el; e; e = e.parentElement) {
      const c = rgb(getComputedStyle(e).backgroundColor);
      if (c.length === 3 || (c.length === 4 && c[3] > 0)) return c; } return [255, 255, 255]; };
  const out = [];
  for (const el of document.querySelectorAll('body *')) {
    if (!el.checkVisibility || !el.checkVisibility()) continue;
    const own = [...el.childNodes].some(n => n.nodeType === 3 && n.textContent.trim());
    if (!own || ['SCRIPT', 'STYLE', 'OPTION'].includes(el.tagName)) continue;
    const fg = rgb(getComputedStyle(el).color), b = bg(el);
    const [hi, lo] = [lum(fg), lum(b)].sort((x, y) => y - x);
    out.push({text: el.textContent.trim().slice(0, 30), id: el.id, cls: el.className,
              ratio: (hi + 0.05) / (lo + 0.05)});
  }
  return out;
}"""


def test_every_text_has_contrast_of_at_least_4_5(served, browser):
    folder, session, url = served
    page, errors = _open(browser, url)
    _settled(page)
    page.fill("#box-zoom", "50")  # a field error and an error message
    page.press("#box-zoom", "Enter")
    checked = set()
    for badge in ("pass", "fail", "stale"):
        page.evaluate(f"(() => {{ const b = document.getElementById('score'); "
                      f"b.className = 'badge {badge}'; "
                      f"document.getElementById('stale-note').hidden = false; }})()")
        for item in page.evaluate(_CONTRAST_JS):
            assert item["ratio"] >= 4.5, item
            checked.add(item["id"] or item["text"])
    assert "score" in checked and "err-zoom" in checked and "stale-note" in checked
    assert len(checked) > 40
    assert not errors
