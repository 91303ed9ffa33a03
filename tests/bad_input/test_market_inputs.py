"""Bad market names, site files and `sites:` keys (`--markets`, `render --site`, a scene's
`sites`): one stderr line naming the option or the file and key, exit status 2, no
traceback, nothing stored changed."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from .conftest import SMALL_SCENE, small_scene
from .harness import Case, check_case

S = SMALL_SCENE
NEW = ("--out", "new", "--no-progress", "--workers", "1")
GOOD_ROW = {"name": "r", "z": 1.0, "x": [0.0], "diameter": 0.3, "height": 0.8}


def _site(text: str | dict, name: str = "site.yaml"):
    """A setup writing the small scene and a site file ``name`` (a dict is dumped)."""
    def setup(folder: Path) -> None:
        small_scene(folder)
        (folder / name).write_text(text if isinstance(text, str) else yaml.safe_dump(text))
    return setup


def _site_doc(**row: object) -> dict:
    return {"name": "mine", "rows": [{**GOOD_ROW, **row}]}


def _scene(edit: dict):
    def setup(folder: Path) -> None:
        small_scene(folder, edit)
    return setup


def _criteria(folder: Path) -> None:
    small_scene(folder)
    (folder / "crit.yaml").write_text("ecs: [3-2]\n")


SITE_FILE_CASES = [
    ("malformed", "rows: [\n", ("site.yaml",)),
    ("unknown-key", _site_doc(colour=1), ("site.yaml", "rows.0.colour")),
    ("negative-diameter", _site_doc(diameter=-0.3), ("site.yaml", "rows.0.diameter")),
    ("band-too-high", _site_doc(marking={"top_band": 0.8}), ("site.yaml", "rows.0")),
    ("bad-lateral-key", _site_doc(x=[0.0, {"of_width": 0.5, "mm": 1}]),
     ("site.yaml", "rows.0.x.1.mm")),
    ("vertical-stripe", _site_doc(marking={"vertical_stripe": 0.15}), ("site.yaml", "rows")),
    ("repeated-rows", {"name": "mine", "rows": [GOOD_ROW, GOOD_ROW]}, ("site.yaml", "rows")),
    ("too-many-objects", {"name": "mine", "rows": [
        {**GOOD_ROW, "name": f"r{k}", "x": [-1.0, 0.0, 1.0]} for k in range(7)]},
     ("site.yaml", "rows", "18")),
    ("bad-name", {"name": "my site", "rows": [GOOD_ROW]}, ("site.yaml", "name")),
    ("no-rows", {"name": "mine"}, ("site.yaml", "rows")),
    ("not-a-mapping", "- 1\n- 2\n", ("site.yaml",)),
]

CASES = [
    Case("markets-unknown", ("tune", S, "--markets", "fmvss111-full,eu", *NEW),
         ("--markets", "'eu'", "unknown market")),
    Case("markets-repeated", ("tune", S, "--markets", "unr158,unr158", *NEW),
         ("--markets", "unr158", "twice")),
    Case("markets-empty-entry", ("tune", S, "--markets", ",unr158", *NEW), ("--markets",)),
    Case("markets-half-pair", ("tune", S, "--markets", "unr158:", *NEW),
         ("--markets", "SITE:CRITERIA")),
    Case("markets-missing-site-file", ("tune", S, "--markets", "gone.yaml:unr158", *NEW),
         ("--markets", "gone.yaml", "no such file")),
    Case("markets-unknown-criteria", ("tune", S, "--markets", "unr158:nosuch", *NEW),
         ("nosuch",)),
    Case("markets-with-criteria", ("tune", S, "--markets", "unr158", "--criteria", "crit.yaml",
                                   *NEW), ("--criteria", "--markets"), setup=_criteria),
    Case("markets-with-robust", ("tune", S, "--markets", "unr158", "--robust", *NEW),
         ("--markets", "--robust")),
    Case("markets-resume", ("tune", "--resume", "run", "--markets", "unr158", "--no-progress"),
         ("--resume", "--markets")),
    Case("markets-no-vehicle", ("tune", S, "--markets", "unr158", *NEW),
         ("scene.yaml", "vehicle"), setup=_scene({"vehicle": None})),
    Case("evaluate-markets-unknown", ("evaluate", S, "--markets", "mars", "--out", "ev"),
         ("--markets", "'mars'")),
    Case("evaluate-markets-with-criteria", ("evaluate", S, "--markets", "unr158", "--criteria",
                                            "crit.yaml", "--out", "ev"),
         ("--criteria", "--markets"), setup=_criteria),
    Case("render-site-unknown", ("render", S, "--site", "mars", "--out", "r"),
         ("site", "'mars'", "unknown")),
    Case("scene-sites-unknown", ("render", S, "--out", "r"), ("scene.yaml", "sites.1", "mars"),
         setup=_scene({"sites": ["fmvss111", "mars"]})),
    Case("scene-sites-missing-file", ("render", S, "--out", "r"),
         ("scene.yaml", "sites.0", "gone.yaml", "not found"),
         setup=_scene({"sites": ["gone.yaml"]})),
    Case("scene-sites-twice", ("render", S, "--out", "r"), ("scene.yaml", "sites.1", "twice"),
         setup=_scene({"sites": ["unr158", "unr158"]})),
    *[Case(f"site-file-{cid}", ("render", S, "--site", "site.yaml", "--out", "r"), names,
           setup=_site(text)) for cid, text, names in SITE_FILE_CASES],
    *[Case(f"market-site-file-{cid}", ("tune", S, "--markets", "site.yaml:unr158", *NEW), names,
           setup=_site(text)) for cid, text, names in SITE_FILE_CASES[:3]],
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_market_or_site_input_is_one_line(case, case_dir):
    check_case(case, case_dir)
    assert not (case_dir / "new").exists()  # refused before anything is written
