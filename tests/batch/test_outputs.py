"""batch.outputs: the design-point table (columns from the sweep's criteria), sweep.csv,
sweep.json and the sweep page, from the locally run sweep."""

from __future__ import annotations

import json

import cv2

from rvmsim.batch import YIELD_COLUMNS, csv_text, sweep_table
from rvmsim.report import write_sweep_outputs
from rvmsim.isp import IspParams


def test_table_columns_follow_the_axes_and_the_criteria(local_run):
    spec, res = local_run
    header, rows = sweep_table(spec, res.points, res.results)
    ec_ids = spec.criteria().ids
    n_axes = len(spec.axes)
    assert header[:1 + n_axes + 5] == ["point", "camera_height_m", "pitch_deg", "verdict",
                                       "ec_score", "passed", "limiting_ec", "reason"]
    assert header[1 + n_axes + 5:1 + n_axes + 5 + len(ec_ids)] == [f"ec_{e}" for e in ec_ids]
    yields_at = 1 + n_axes + 5 + len(ec_ids)
    assert header[yields_at:yields_at + len(YIELD_COLUMNS)] == list(YIELD_COLUMNS)
    assert header[-2:] == ["evaluations", "error"]
    assert len(header) == (1 + n_axes + 5 + len(ec_ids) + len(YIELD_COLUMNS)
                           + len(IspParams.names()) + 2)
    assert [r[0] for r in rows] == list(range(6))
    for p, row in zip(res.points, rows):
        r = res.results[p.key]
        assert len(row) == len(header)
        assert row[header.index("ec_score")] == r["score"]
        assert row[header.index("verdict")] == r["verdict"]
        assert r["verdict"] in ("pass", "not found", "infeasible")
        assert (r["verdict"] == "pass") == r["passed"]
        assert (row[header.index("reason")] is None) == (r["verdict"] != "infeasible")
        for e in ec_ids:
            assert row[header.index(f"ec_{e}")] == ("pass" if r["ecs"][e]["passed"] else "FAIL")
    # A point not run (or failed) has only its axis values and the reason.
    missing = {k: r for k, r in res.results.items() if k != res.points[0].key}
    _, rows2 = sweep_table(spec, res.points, missing)
    assert rows2[0][-1] == "not run"
    assert rows2[0][1 + n_axes:-1] == [None] * (len(header) - n_axes - 2)
    assert rows2[1:] == rows[1:]


def test_csv_cells():
    text = csv_text(["a", "b", "c"], [[0.1, None, "x"], [1, True, 2.5]])
    assert text == "a,b,c\n0.1,,x\n1,True,2.5\n"


def test_written_outputs(local_run):
    spec, res = local_run
    written = write_sweep_outputs(res)
    names = {p.name for p in written}
    assert {"sweep.csv", "sweep.json", "feasibility.png", "sweep.html"} <= names
    img = cv2.imread(str(res.out_dir / "feasibility.png"))
    assert img is not None and img.std() > 10
    csv_lines = (res.out_dir / "sweep.csv").read_text().splitlines()
    assert len(csv_lines) == 7
    doc = json.loads((res.out_dir / "sweep.json").read_text())
    assert [p["index"] for p in doc["points"]] == list(range(6))
    assert doc["points"][0]["values"] == dict(res.points[0].values)
    html = (res.out_dir / "sweep.html").read_text()
    assert html.count("data:image/png;base64,") >= 1 and "Feasibility map" in html
    # Point numbers 0 and 1 are not coloured as pass/fail (1 == True in Python).
    assert '<tr><td class="">0</td>' in html and '<tr><td class="">1</td>' in html
    n_ec = len(spec.criteria().ids)
    n_pass = sum(r["verdict"] == "pass" for r in res.results.values())
    assert html.count('class="fail">FAIL</td>') + html.count('class="pass">pass</td>') == \
        6 * n_ec + n_pass  # the EC cells and the passing verdicts
    assert html.count('<td class="fail">not found</td>') + \
        html.count('<td class="off">infeasible</td>') == 6 - n_pass
