"""The console in a real browser (Chromium through Playwright): drive the page as an
expert does, and check what it shows against ``rvmsim evaluate``."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest

from rvmsim.console import check_access, open_session
from rvmsim.isp import load_params

from ..cli_runner import run_in_child
from .conftest import serving

@pytest.fixture(scope="module")
def served_run(small_run, browser, tmp_path_factory):
    """The small run's console, served on loopback without a token (a copy of the run, so
    saves land in a folder of this module)."""
    import shutil

    folder = tmp_path_factory.mktemp("served")
    shutil.copy(small_run / "scene.yaml", folder / "scene.yaml")
    shutil.copytree(small_run / "run", folder / "run")
    session = open_session(folder / "run")
    with serving(session, check_access("127.0.0.1", None)) as url:
        yield folder, session, url


def _new_page(browser):
    """A page whose scripts the test may evaluate (bypass_csp: the page's CSP forbids
    eval, which Playwright's wait_for_function uses; the page itself never needs it)."""
    return browser.new_context(bypass_csp=True, viewport={"width": 1400, "height": 900}
                               ).new_page()


def _open(browser, url):
    page = _new_page(browser)
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(url)
    page.wait_for_function("window.rvmConsole && window.rvmConsole.frames >= 1", timeout=30000)
    return page, errors


#: True when the image ``sel`` holds a ``src`` containing ``part`` other than ``old`` and
#: has loaded it (``naturalWidth`` is 0 until then, also for a moment after ``src`` changes).
_IMAGE_LOADED = ("([sel, part, old]) => { const i = document.querySelector(sel); "
                 "return !!i && !!i.src && i.src.includes(part) && i.src !== old && "
                 "i.complete && i.naturalWidth > 0; }")


def _image_loaded(page, selector: str, part: str = "", old: str | None = None,
                  timeout: float = 30000) -> None:
    """Wait until the image ``selector`` shows a new picture and has loaded it: its ``src``
    contains ``part`` and differs from ``old`` (the src before the action; None: any), and
    ``complete && naturalWidth > 0``."""
    page.wait_for_function(_IMAGE_LOADED, arg=[selector, part, old], timeout=timeout)


def _settled(page, timeout: float = 30000) -> None:
    """Wait until the newest value has been shown (nothing in flight, nothing pending) and
    its picture has loaded, in the main view and as A of the A/B view."""
    page.wait_for_function("(() => { const s = window.rvmConsole; return !s.inflight && "
                           "!s.pending && s.last && s.shown && !s.shown.draft && "
                           "Object.keys(s.current).every(k => s.last.params[k] === s.current[k]);"
                           " })()", timeout=timeout)
    _image_loaded(page, "#rvm", timeout=timeout)
    page.wait_for_function("(() => { const a = document.getElementById('ab-a'); "
                           "return a.hidden || (a.src === document.getElementById('rvm').src && "
                           "a.complete && a.naturalWidth > 0); })()", timeout=timeout)


def _drag(page, selector: str, fraction: float) -> None:
    """Drag a slider's thumb with the mouse from where it is to ``fraction`` of its width."""
    page.locator(selector).scroll_into_view_if_needed()
    box = page.locator(selector).bounding_box()
    assert box is not None
    value = page.eval_on_selector(selector, "e => (e.value - e.min) / (e.max - e.min)")
    y = box["y"] + box["height"] / 2
    page.mouse.move(box["x"] + 8 + value * (box["width"] - 16), y)
    page.mouse.down()
    for k in range(1, 9):
        t = value + (fraction - value) * k / 8
        page.mouse.move(box["x"] + 8 + t * (box["width"] - 16), y)
    page.mouse.up()


def _table(page) -> list[list[str]]:
    return page.eval_on_selector_all(
        "#ec-table tbody tr", "rows => rows.map(r => [...r.cells].map(c => c.textContent))")


def test_zoom_slider_updates_the_picture_and_the_ecs_as_evaluate(served_run, browser, tmp_path):
    folder, session, url = served_run
    page, errors = _open(browser, url)
    _settled(page)
    before_frame = page.get_attribute("#rvm", "src")
    before_table = _table(page)
    before_zoom = page.evaluate("window.rvmConsole.current.zoom")
    _drag(page, "#slider-zoom", 0.9)
    _settled(page)
    state = page.evaluate("window.rvmConsole.last")
    assert state["params"]["zoom"] != before_zoom
    assert page.get_attribute("#rvm", "src") != before_frame
    after_table = _table(page)
    assert after_table != before_table
    # what the page shows is the evaluation it got, EC by EC
    assert [row[0] for row in after_table] == [e["id"] for e in state["ecs"]]
    for row, ec in zip(after_table, state["ecs"]):
        assert row[6] == f"{ec['score']:.4f}"
        assert row[2] == ("—" if ec["value"] is None else f"{ec['value']:.3f}")
    # save it: the page shows the file's absolute path and the command that checks it;
    # run that very command: the same ECs
    page.click("#save")
    page.wait_for_function("window.rvmConsole.lastWrite !== undefined")
    saved = page.evaluate("window.rvmConsole.lastWrite")
    command = shlex.split(saved["command"])
    assert command == ["rvmsim", "evaluate", str(session.scene_file.resolve()), "--params",
                       saved["path"]]
    assert Path(saved["path"]).is_absolute() and Path(saved["path"]).is_file()
    assert page.text_content("#saved-command") == saved["command"]
    assert page.text_content("#saved-path") == saved["path"]
    assert saved["path"] in page.text_content("#message")
    res = run_in_child([*command[1:], "--out", tmp_path / "ev", "--no-progress"], timeout_s=300)
    doc = json.loads((tmp_path / "ev" / "ec.json").read_text())
    assert res.code == (0 if doc["passed"] else 1), res.stderr  # evaluate judges
    assert doc["ec_score"] == pytest.approx(state["ec_score"], rel=1e-9, abs=1e-300)
    for mine, theirs in zip(state["ecs"], doc["ecs"]):
        assert mine["id"] == theirs["id"]
        assert mine["passed"] == theirs["passed"]
        assert mine["score"] == pytest.approx(theirs["score"], rel=1e-9, abs=1e-12)
        if theirs["value"] is None:
            assert mine["value"] is None
        else:
            assert mine["value"] == pytest.approx(theirs["value"], rel=1e-9, abs=1e-12)
    assert not errors


def test_load_candidate_3_and_save_it(served_run, browser):
    folder, session, url = served_run
    page, errors = _open(browser, url)
    _settled(page)
    page.click('#candidates tr[data-rank="3"] button.load')
    _settled(page)
    third = session.candidates[2].params
    shown = page.evaluate("window.rvmConsole.last.params")
    assert shown == {n: getattr(third, n) for n in shown}
    page.fill("#label", "third try")
    page.click("#save")
    page.wait_for_function("window.rvmConsole.lastWrite !== undefined")
    saved = page.evaluate("window.rvmConsole.lastWrite")
    path = (folder / "run" / saved["file"])
    assert path.parent == folder / "run" / "console" and "third-try" in path.name
    params, output = load_params(path)
    assert params == third
    assert (output.width, output.height) == (session.ec_output.width, session.ec_output.height)
    assert saved["path"] in page.text_content("#message")
    # undo goes back to rank 1, reset too
    page.click("#undo")
    _settled(page)
    assert page.evaluate("window.rvmConsole.last.params.zoom") == session.start.zoom
    assert not errors


def _type(page, name: str, value: str) -> None:
    page.fill(f"#box-{name}", value)
    page.press(f"#box-{name}", "Enter")


def test_out_of_range_value_shows_a_message(served_run, browser):
    """A value outside what is allowed: a message, beside the field too; fixed, both go.  A
    value allowed beyond the search range pins the slider and says so; the failing ECs are
    named above the fold; a small value is shown whole in its box."""
    folder, session, url = served_run
    page, errors = _open(browser, url)
    _settled(page)
    _type(page, "zoom", "50")
    page.wait_for_function("document.getElementById('message').className === 'error'")
    text = page.text_content("#message")
    assert "zoom" in text and "outside" in text and "Traceback" not in text
    assert page.is_visible("#err-zoom")
    spec = next(c for c in page.evaluate("window.rvmConsole.session.controls")
                if c["name"] == "zoom")
    assert spec["high"] < spec["spec_high"]
    _type(page, "zoom", repr(spec["spec_high"]))  # allowed, beyond the search range
    _settled(page)
    assert not page.is_visible("#err-zoom") and page.text_content("#message") == ""
    note = page.locator('.control[data-param="zoom"] .beyond')
    assert note.is_visible() and "outside the search range" in note.text_content()
    assert "pinned" in page.get_attribute("#slider-zoom", "class")
    # the failing ECs of the frame shown, named above the fold of a 1400 x 900 window
    last = page.evaluate("window.rvmConsole.last")
    failing = [e["id"] for e in last["ecs"] if e["enabled"] and not e["passed"]]
    assert failing and not last["passed"]
    page.evaluate("window.scrollTo(0, 0)")
    box = page.locator("#failing").bounding_box()
    assert box is not None and box["y"] + box["height"] <= 900
    shown = page.text_content("#failing")
    assert [i for i in re.findall(r"\b(\d+-\d+)\b", shown)] == failing
    # a small value is shown whole: its box does not scroll
    _type(page, "h_shift", "-0.0001234567")
    _settled(page)
    assert page.input_value("#box-h_shift") == "-0.0001234567"
    assert page.eval_on_selector("#box-h_shift", "b => b.scrollWidth <= b.clientWidth")
    # back inside the search range: the note goes
    _type(page, "zoom", repr(session.start.zoom))
    _settled(page)
    assert not note.is_visible()
    assert not errors


def test_non_loopback_host_needs_the_token(small_run, browser):
    access = check_access("0.0.0.0", None)  # what `--host 0.0.0.0` gets: a made token
    assert access.token and access.generated
    session = open_session(small_run / "run")
    with serving(session, access) as url:  # listening on loopback, with that rule
        page = _new_page(browser)
        response = page.goto(url + "/")
        assert response is not None and response.status == 403
        assert "token" in page.text_content("body")
        response = page.goto(url + "/api/session?token=" + "x" * 32)
        assert response is not None and response.status == 403
        page.goto(f"{url}/?token={access.token}")
        page.wait_for_function("window.rvmConsole && window.rvmConsole.frames >= 1",
                               timeout=30000)
        assert page.text_content("#title") == session.scene.name


def test_user_strings_are_shown_as_text(tmp_path, browser):
    from rvmsim.testing.scenes import write_small_scene

    name = '<img src=x id=injected onerror="window.pwned=1">'
    scene = write_small_scene(tmp_path, name="scene.yaml",
                              edit={"name": name, "description": "<b>bold</b> & co"})
    session = open_session(scene, out_root=tmp_path / "out")
    with serving(session, check_access("127.0.0.1", None)) as url:
        page, errors = _open(browser, url)
        assert page.text_content("#title") == name
        assert "<b>bold</b> & co" in page.text_content("#subtitle")
        assert page.locator("#injected").count() == 0
        assert page.evaluate("window.pwned") is None
        assert not errors


def test_annotation_toggle_pin_b_and_reset(served_run, browser):
    folder, session, url = served_run
    page, errors = _open(browser, url)
    _settled(page)
    before = page.get_attribute("#rvm", "src")
    assert "/display.jpg?v=" in before
    assert page.get_attribute('#candidates tr[data-rank="1"]', "data-mark") == "A"
    page.check("#annotate")
    _image_loaded(page, "#rvm", "/annotated.jpg", before)
    width, height, shown = page.evaluate("(() => { const i = document.getElementById('rvm'); "
                                         "return [i.naturalWidth, i.naturalHeight, "
                                         "i.clientWidth]; })()")
    # the EC image of record with its results panel, at the report column's width or wider,
    # shown at its own size (its text is made for 1:1), and the heading names that image
    assert width >= min(session.ec_output.width, 1200)
    assert shown == width
    assert page.text_content("#rvm-size") == f"(annotated: {width}×{height} px)"
    page.click("#pin")
    page.wait_for_function("window.rvmConsole.bResult !== null")
    assert page.get_attribute('#candidates tr[data-rank="1"]', "data-mark") == "AB"
    b_cells = page.eval_on_selector_all("#ec-table tbody tr td:nth-child(8)",
                                        "cells => cells.map(c => c.textContent)")
    assert all(b_cells)
    page.fill("#box-fov", "150")
    page.press("#box-fov", "Enter")
    _settled(page)
    assert page.evaluate("window.rvmConsole.last.params.fov") == 150.0
    assert page.get_attribute('#candidates tr[data-rank="1"]', "data-mark") == "B"
    assert page.text_content('#candidates tr[data-rank="1"] .mark') == "B"
    page.click("#reset")
    _settled(page)
    assert page.evaluate("window.rvmConsole.last.params.fov") == session.start.fov
    assert not errors


def test_guidelines_toggle_draws_them_and_shows_their_ground_error(served_run, browser):
    """The toggle draws the guidelines over the picture (the picture on the page changes),
    their ground error appears ("measuring…" first, then px and cm per line), and the
    steering slider brings the trajectory lines of its angle."""
    folder, session, url = served_run
    page, errors = _open(browser, url)
    _settled(page)
    before = page.locator("#rvm-box").screenshot()
    assert page.locator("#guides-svg polyline").count() == 0
    page.check("#guides")
    page.wait_for_function("document.body.dataset.guidesError === 'ready'", timeout=60000)
    assert page.locator("#guides-svg polyline").count() > 0
    assert page.locator("#rvm-box").screenshot() != before  # drawn over the picture
    rows = page.eval_on_selector_all(
        "#guides-table tbody tr", "rows => rows.map(r => [...r.cells].map(c => c.textContent))")
    last = page.evaluate("window.rvmConsole.guides.last")
    assert last["params"] == page.evaluate("window.rvmConsole.shown.params")
    lines = last["error"]["static"]["lines"] + last["error"]["trajectory"]["lines"]
    assert [r[0] for r in rows] == [line["name"] for line in lines]
    measured = [(r, line) for r, line in zip(rows, lines) if line["offset_px"] is not None]
    assert measured
    for r, line in measured:
        assert float(r[3]) == pytest.approx(line["offset_px"], rel=1e-3)
        assert float(r[4]) == pytest.approx(line["offset_cm"], rel=1e-3)
    summary = page.text_content("#guides-summary")
    assert "static: worst" in summary and " px, " in summary and " cm " in summary
    # full lock to the left: the trajectories of that angle, measured too
    page.fill("#steer", "-100")
    page.dispatch_event("#steer", "input")
    page.wait_for_function("(() => { const g = window.rvmConsole.guides.last; return "
                           "g.steering_pct === -100 && document.body.dataset.guidesError === "
                           "'ready'; })()", timeout=60000)
    angle = page.evaluate("window.rvmConsole.guides.last.error.trajectory.lines[0].steering_deg")
    assert angle == pytest.approx(-page.evaluate(
        "window.rvmConsole.session.guidelines.steering_range_deg"))
    assert "guides=1" in page.evaluate("location.hash")
    page.uncheck("#guides")
    assert page.locator("#guides-svg polyline").count() == 0
    assert page.is_hidden("#guides-view")
    assert not errors
