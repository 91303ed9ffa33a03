"""Criteria files: overrides, switched-off ECs, selections, plugins and one-line errors."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from rvmsim.criteria import (
    EC_IDS,
    criteria_from_text,
    default_criteria,
    evaluate,
    load_criteria,
    score_batch,
    values_array,
)
from rvmsim.errors import CriteriaError

from .views import rvm

EXAMPLE = Path(__file__).with_name("ec_plugin_example.py")


def test_customer_file_overrides_and_switches_off(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(
        "name: OEM X\nupper_region_fraction: 0.4\ncriteria:\n"
        "  2-1: {range: [5, 9], tolerance: 1.0}\n"
        "  4-1: {enabled: false}\n"
    )
    c = load_criteria(path)
    assert c.name == "OEM X" and c.upper_region_fraction == 0.4
    assert c.items["2-1"].low == 5 and c.items["2-1"].sigmoid.c2 == pytest.approx(4.5)
    assert c.items["3-2"] == default_criteria().items["3-2"]
    labels = rvm("a")
    on, off = evaluate(labels, default_criteria()), evaluate(labels, c)
    assert not off["4-1"].enabled
    expected = np.prod([i.score for i in off.items if i.enabled])
    assert off.score == pytest.approx(expected)
    assert on["4-1"].enabled


@pytest.mark.parametrize("text, words", [
    ("criteria:\n  5-1: {}\n", "unknown EC '5-1'"),
    ("criteria:\n  2-1: {range: [8, 4]}\n", "low <= high"),
    ("criteria:\n  2-1: {tolerance: 1}\n", "needs a range"),
    ("criteria:\n  2-1: {sigmoid: {c1: -1}}\n", "greater than or equal to 0"),
    ("criteria:\n  2-1: {colour: red}\n", "unknown key"),
    ("criteria: [\n", "malformed YAML"),
])
def test_bad_criteria_file(tmp_path, text, words):
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(CriteriaError) as info:
        load_criteria(path)
    assert words in str(info.value) and str(path) in str(info.value)
    assert "\n" not in str(info.value)




# ---------------------------------------------------------------------------- selections
#: The bundled default file as shipped before the EC registry (every EC spelled out): such
#: files keep loading with the same meaning.
OLD_DEFAULT = """
name: paper defaults (Lee et al., RVM ISP tuning)
upper_region_fraction: 0.5
edge_columns: 4
criteria:
  "1-1": {range: [1, 1]}
  "1-2": {range: [10, null], sigmoid: {c1: 0.5, c2: 10, c3: 0, c4: .inf}}
  "1-3": {range: [15, null], sigmoid: {c1: 0.43, c2: 15, c3: 0, c4: .inf}}
  "1-4": {range: [0.1, null], sigmoid: {c1: 23.1, c2: 0.1, c3: 0, c4: .inf}}
  "2-1": {range: [4, 8], sigmoid: {c1: 3.0, c2: 4, c3: 3.0, c4: 8}}
  "2-2": {range: [8, 16], sigmoid: {c1: 2.69, c2: 8, c3: 2.69, c4: 16}}
  "2-3": {range: [null, 5], sigmoid: {c1: 0, c2: -.inf, c3: 1.17, c4: 5}}
  "2-4": {range: [1, 1]}
  "3-1": {range: [null, 5], sigmoid: {c1: 0, c2: -.inf, c3: 0.937, c4: 5}}
  "3-2": {range: [45, 55], sigmoid: {c1: 1.0, c2: 45, c3: 1.0, c4: 55}}
  "4-1": {range: [0.9, 1.1], sigmoid: {c1: 42.4, c2: 0.9, c3: 42.4, c4: 1.1}}
"""


def test_the_old_full_default_file_means_the_same(tmp_path):
    path = tmp_path / "old.yaml"
    path.write_text(OLD_DEFAULT)
    old, new = load_criteria(path), default_criteria()
    assert old.ids == new.ids == EC_IDS
    assert old.items == new.items and old.name == new.name
    assert criteria_from_text(OLD_DEFAULT).items == new.items


def test_a_file_selects_some_ecs_in_its_order(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text('ecs: ["4-1", "2-1", 1-3]\ncriteria:\n  2-1: {range: [5, 9], tolerance: 1}\n')
    c = load_criteria(path)
    assert c.ids == ("4-1", "2-1", "1-3")
    assert c.items["4-1"] == default_criteria().items["4-1"] and c.items["2-1"].low == 5
    labels = rvm("a")
    full, some = evaluate(labels), evaluate(labels, c)
    assert [i.id for i in some.items] == list(c.ids)
    for i in some.items:
        assert i.value == full[i.id].value
    assert some.score == pytest.approx(np.prod([i.score for i in some.items]))
    b = score_batch(values_array(some.measurements, c.ids)[None], c)
    assert b.ids == c.ids and b.score[0] == pytest.approx(some.score)


def test_plugin_ecs_join_the_default_selection(tmp_path):
    folder = tmp_path / "oem"
    folder.mkdir()
    shutil.copy(EXAMPLE, folder / "board_ec.py")
    path = folder / "c.yaml"
    path.write_text("plugins: [board_ec.py]\ncriteria:\n  acme-board-centred: {range: [null, 2], "
                    "tolerance: 1}\n  4-1: {enabled: false}\n")
    c = load_criteria(path)
    assert c.ids == EC_IDS + ("acme-board-centred",)
    assert c.items["acme-board-centred"].high == 2 and not c.items["4-1"].enabled
    # a text with a relative plugin path resolves it against base_dir
    same = criteria_from_text(path.read_text(), "oem criteria", base_dir=folder)
    assert same.items == c.items and same.ids == c.ids
    r = evaluate(rvm("a"), c)
    assert r["acme-board-centred"].value is not None and r["4-1"].value is not None
    assert r.score == pytest.approx(np.prod([i.score for i in r.items if i.enabled]))


@pytest.mark.parametrize("text, key, line, words", [
    ("ecs: [1-1, 5-1]\n", "ecs.1", 2, "unknown EC '5-1' (known: 1-1, 1-2"),
    ("ecs:\n  - 1-1\n  - 1-1\n", "ecs.1", 4, "EC '1-1' is selected twice"),
    ("ecs: [1-1]\ncriteria:\n  2-1: {enabled: false}\n", "criteria.2-1", 4,
     "EC '2-1' is not selected (add it to ecs)"),
    ("ecs: []\n", "ecs", 2, "no EC selected"),
    ("plugins: ok.py\n", "plugins", 2, "valid list"),
])
def test_bad_selection_is_one_line(tmp_path, text, key, line, words):
    path = tmp_path / "c.yaml"
    path.write_text("name: x\n" + text)
    with pytest.raises(CriteriaError) as info:
        load_criteria(path)
    assert info.value.key == key and words in info.value.message, str(info.value)
    assert info.value.line == line and "\n" not in str(info.value)


@pytest.mark.parametrize("text, key", [
    ("criteria: {2-1: {range: [.nan, 9]}}\n", "criteria.2-1.range.0"),
    ("criteria: {2-1: {sigmoid: {c2: .nan}}}\n", "criteria.2-1.sigmoid.c2"),
    ("criteria: {2-1: {range: [5, 9], tolerance: .inf}}\n", "criteria.2-1.tolerance"),
])
def test_nan_thresholds_are_refused_but_open_ends_stay(text, key):
    with pytest.raises(CriteriaError) as err:
        criteria_from_text(text, "c.yaml")
    assert err.value.key == key
    open_end = criteria_from_text("criteria: {2-1: {range: [5, .inf]}}\n", "c.yaml")
    assert open_end.items["2-1"].high == float("inf")
