"""The console's API through FastAPI's TestClient (the real app over a real small run)."""

from __future__ import annotations

import json
import re

import pytest
from fastapi.testclient import TestClient

from rvmsim.console import create_app, ec_margin, evaluate_setting, open_session
from rvmsim.console.app import MAX_BODY_BYTES, MAX_TARGET_BYTES, STATIC, TOKEN_HEADER
from rvmsim.isp import IspParams, load_params

LOCAL = "http://127.0.0.1"
TOKEN = "t0ken-for-the-tests-0123456789"


def _evaluate(client, doc):
    """``GET /api/evaluate?q=JSON`` as the page sends it."""
    return client.get("/api/evaluate", params={"q": json.dumps(doc)})


@pytest.fixture(scope="module")
def session(small_run):
    return open_session(small_run / "run")


@pytest.fixture
def client(run_copy):
    return TestClient(create_app(open_session(run_copy / "run")), base_url=LOCAL)


def test_session_lists_the_controls_tuned_first_and_the_candidates(session):
    doc = TestClient(create_app(session), base_url=LOCAL).get("/api/session").json()
    controls = doc["controls"]
    assert len(controls) == 14 and len({c["name"] for c in controls}) == 14
    tuned = [c["tuned"] for c in controls]
    assert tuned == sorted(tuned, reverse=True) and any(tuned) and not all(tuned)
    assert doc["start"] == {n: getattr(session.candidates[0].params, n) for n in doc["start"]}
    assert [c["rank"] for c in doc["candidates"]] == list(range(1, len(doc["candidates"]) + 1))
    assert doc["vehicle"] == session.scene.name and doc["kind"] == "run"


def test_evaluate_gives_the_ecs_of_the_one_evaluation_path(session):
    from rvmsim.pipeline import evaluate_params

    client = TestClient(create_app(session), base_url=LOCAL)
    r = _evaluate(client, {"params": {"zoom": 0.9}, "annotate": True})
    assert r.status_code == 200
    doc = r.json()
    want = evaluate_params(session.images, session.start.replace(zoom=0.9), session.ec_output,
                           session.criteria, annotate=False).ec.as_dict()
    margins = [ec.pop("margin") for ec in doc["ecs"]]
    yes_no = [ec.pop("yes_no") for ec in doc["ecs"]]
    assert doc["ecs"] == want["ecs"] and doc["ec_score"] == want["ec_score"]
    # a yes/no EC (a range of one value: 1-1, 2-4) has no margin: the page shows ✓/✗
    assert yes_no == [ec["range"][0] is not None and ec["range"][0] == ec["range"][1]
                      for ec in want["ecs"]] and sum(yes_no) == 2
    assert margins == [None if y else ec_margin(ec["value"], *ec["range"])
                       for ec, y in zip(want["ecs"], yes_no)]
    assert any(m is not None for m in margins)
    pic = client.get(doc["image"])
    assert pic.status_code == 200 and pic.headers["content-type"] == "image/jpeg"
    import cv2
    import numpy as np

    img = cv2.imdecode(np.frombuffer(pic.content, np.uint8), cv2.IMREAD_COLOR)
    assert img.shape[:2] == (session.display.height, session.display.width)
    assert client.get(doc["annotated"]).status_code == 200
    assert len(doc["roi"]) > 8


def test_pictures_are_named_by_their_parameters_and_never_go_stale(session):
    """A picture URL names its parameters, so an early one (B's, the A/B view's) still
    answers after many newer evaluations, with the picture of those parameters."""
    import cv2
    import numpy as np

    from rvmsim.pipeline import rvm_color

    client = TestClient(create_app(session), base_url=LOCAL)
    first = _evaluate(client, {"params": {"zoom": 0.7}, "draft": True}).json()
    for k in range(60):  # more than the server keeps
        _evaluate(client, {"params": {"zoom": 0.5 + 0.01 * k}, "draft": True})
    # the draft: the view at half the display's size (the ECs are judged at the display's)
    from rvmsim.isp import OutputSpec

    d = session.display
    half = OutputSpec(d.width // 2, d.height // 2, d.mirror)
    for kind, url, size in (("display", first["image"], session.display),
                            ("draft", first["draft"], half)):
        r = client.get(url)
        assert r.status_code == 200 and r.headers["content-type"] == "image/jpeg", kind
        got = cv2.imdecode(np.frombuffer(r.content, np.uint8), cv2.IMREAD_COLOR)[:, :, ::-1]
        want = rvm_color(session.images, session.start.replace(zoom=0.7), size)
        assert got.shape == want.shape, kind
        other = rvm_color(session.images, session.start.replace(zoom=1.0), size)
        err = np.abs(got.astype(int) - want).mean()
        assert err < 4 and err < np.abs(got.astype(int) - other).mean() / 3, kind
    bad = first["image"].replace("p=", "p=999,")
    assert client.get(bad).status_code == 422
    assert client.get("/api/picture/other.jpg?p=1").status_code == 404


@pytest.mark.parametrize("zoom, fov, v_pan", [(1.0, 180.0, 0.0), (0.4, 200.0, 90.0),
                                               (2.5, 150.0, -30.0)])
def test_pictures_have_the_pixels_of_rvm_color(session, zoom, fov, v_pan):
    """The console's own remap (a BGR copy of the fisheye, shared ray planes) gives the
    pixels of the pipeline's ``rvm_color``, exactly; twice (the second from the ray cache)."""
    import numpy as np

    from rvmsim.console import Pictures
    from rvmsim.pipeline import rvm_color

    pictures = Pictures(session)
    params = session.start.replace(zoom=zoom, fov=fov, v_pan=v_pan)
    want = rvm_color(session.images, params, session.display)
    for _ in range(2):
        got = pictures.render_bgr(params, session.display)
        assert np.array_equal(got[:, :, ::-1], want)
    near = params.replace(fov=fov - 5.0, rad=params.rad * 1.1)  # same rays, cached
    assert np.array_equal(pictures.render_bgr(near, session.display)[:, :, ::-1],
                          rvm_color(session.images, near, session.display))


@pytest.mark.parametrize("value, low, high, want", [
    (6.0, 4.0, 8.0, 1.0), (4.0, 4.0, 8.0, 0.0), (3.0, 4.0, 8.0, -0.5), (9.0, 4.0, 8.0, -0.5),
    (15.0, 10.0, None, 0.5), (5.0, 10.0, None, -0.5), (2.5, None, 5.0, 0.5),
    (1.0, 1.0, 1.0, 1.0), (0.0, 1.0, 1.0, -1.0), (None, 1.0, 2.0, None),
    (3.0, None, None, None), (1.0, 0.0, None, 1.0)])
def test_ec_margin(value, low, high, want):
    assert ec_margin(value, low, high) == want


@pytest.mark.parametrize("body, status, words", [
    ({"params": {"zoom": 50}}, 422, ["zoom", "outside"]),
    ({"params": {"zoom": "wide"}}, 422, ["zoom", "number"]),
    ({"params": {"zoom": True}}, 422, ["zoom", "number"]),
    ({"params": {"zoom": None}}, 422, ["zoom", "number"]),
    ({"params": {"fov": -1e308}}, 422, ["fov", "outside"]),
    ({"params": {"warp": 1}}, 422, ["warp", "unknown"]),
    ({"params": [1, 2]}, 422, ["params"]),
    ({"params": {}, "annotate": "yes"}, 422, ["annotate"]),
])
def test_bad_values_get_a_json_message(session, body, status, words):
    r = _evaluate(TestClient(create_app(session), base_url=LOCAL), body)
    assert r.status_code == status
    msg = r.json()["error"]
    assert all(w in msg for w in words), msg
    assert "Traceback" not in r.text


@pytest.mark.parametrize("raw, status", [(b"{nope", 400), (b"[1]", 422), (b"nan", 400),
                                         (b"[" * 15000, 400), (b"1" * (MAX_BODY_BYTES + 1), 413)],
                         ids=["not-json", "a-list", "nan", "nested-deep", "too-long"])
def test_bad_bodies_get_a_json_message(session, raw, status):
    client = TestClient(create_app(session), base_url=LOCAL)
    if len(raw) < 20000:  # longer URLs (3 bytes a bracket) are refused by the client
        r = client.get("/api/evaluate", params={"q": raw.decode()})
        long_url = len(r.request.url.raw_path) > MAX_TARGET_BYTES
        assert r.status_code == (414 if long_url else status) and r.json()["error"]
    r = client.post("/api/save", content=raw, headers={"content-type": "application/json"})
    assert r.status_code == status and r.json()["error"]


def test_save_writes_a_select_format_file_into_the_run_folder(client, run_copy):
    r = client.post("/api/save", json={"params": {"zoom": 0.8}, "label": "../../../etc/passwd"})
    assert r.status_code == 200
    doc = r.json()
    path = run_copy / "run" / doc["file"]
    assert path.parent == run_copy / "run" / "console"
    assert re.fullmatch(r"params_\d{8}-\d{6}_etc-passwd\.yaml", path.name)
    params, output = load_params(path)
    start = open_session(run_copy / "run").start
    assert params == start.replace(zoom=0.8)
    # the run searched at its default size, the RVM image of record, where it was judged
    assert (output.width, output.height) == (1280, 720)
    assert path.read_text().startswith("# console setting")
    assert "judged_at:\n  - 1280\n  - 720" in path.read_text()
    again = client.post("/api/save", json={"params": {"zoom": 0.8}, "label": "../../../etc/passwd"})
    assert again.json()["file"] != doc["file"]  # never overwritten
    assert client.post("/api/save", json={"params": {"zoom": 0.8}, "label": 7}).status_code == 422


def test_report_writes_the_setting_into_the_run_folder(client, run_copy):
    r = client.post("/api/report", json={"params": {"zoom": 0.8}})
    assert r.status_code == 200
    path = run_copy / "run" / r.json()["file"]
    assert path.parent == run_copy / "run" / "console" and path.suffix == ".html"
    text = path.read_text()
    assert 'id="ec-table"' in text and "0.8" in text and "<script" not in text


def test_a_token_is_required_once_set(session):
    app = create_app(session, token=TOKEN)
    anyone = TestClient(app, base_url="http://192.0.2.1:8765")
    for path in ("/", "/api/session", "/static/console.js", "/api/fisheye.jpg"):
        r = anyone.get(path)
        assert r.status_code == 403 and "token" in r.json()["error"], path
    assert _evaluate(anyone, {}).status_code == 403
    assert anyone.post("/api/save", json={}).status_code == 403
    assert anyone.get("/api/session", headers={TOKEN_HEADER: TOKEN + "x"}).status_code == 403
    assert anyone.get("/api/session", headers={TOKEN_HEADER: TOKEN}).status_code == 200
    page = anyone.get(f"/?token={TOKEN}")
    assert page.status_code == 200 and "rvm_token" in page.headers["set-cookie"]
    assert anyone.get("/api/fisheye.jpg").status_code == 200  # the cookie it was given


def test_without_a_token_only_loopback_host_names_are_answered(session):
    app = create_app(session)
    assert TestClient(app, base_url="http://127.0.0.1:8765").get("/").status_code == 200
    assert TestClient(app, base_url="http://localhost:8765").get("/").status_code == 200
    assert TestClient(app, base_url="http://[::1]:8765").get("/").status_code == 200
    rebound = TestClient(app, base_url="http://attacker.example:8765")
    assert rebound.get("/api/session").status_code == 403


def test_page_and_assets_are_local_and_set_as_text(session):
    client = TestClient(create_app(session), base_url=LOCAL)
    page = client.get("/")
    assert page.status_code == 200
    assert "script-src 'self'" in page.headers["content-security-policy"]
    for name in ("console.js", "console.css"):
        r = client.get(f"/static/{name}")
        assert r.status_code == 200 and len(r.content) > 500
    assert client.get("/static/../app.py").status_code == 404
    for f in STATIC.iterdir():  # no CDN, no remote anything
        text = f.read_text()
        assert not re.search(r"(https?:)?//[a-z0-9.-]+\.[a-z]{2,}/", text), f.name
    js = (STATIC / "console.js").read_text()
    assert "innerHTML" not in js and "insertAdjacentHTML" not in js and "eval(" not in js


def test_evaluate_setting_draws_annotations_only_when_asked(session):
    plain = evaluate_setting(session, IspParams(), annotate=False)
    drawn = evaluate_setting(session, IspParams(), annotate=True)
    assert plain.annotated_jpeg is None and drawn.annotated_jpeg
    assert plain.ec.as_dict() == drawn.ec.as_dict()
