"""Checking the browser's values."""

from __future__ import annotations

import pytest

from rvmsim.console import ConsoleInputError, parse_label, parse_params
from rvmsim.console.inputs import MAX_LABEL, parse_flag
from rvmsim.isp import IspParams


def test_params_keep_the_base_where_not_given():
    base = IspParams(zoom=0.7)
    p = parse_params({"fov": 170, "rad": 600.5}, base)
    assert p == base.replace(fov=170.0, rad=600.5)


@pytest.mark.parametrize("doc, key", [
    ({"zoom": 10.5}, "zoom"), ({"zoom": float("nan")}, "zoom"), ({"zoom": "1"}, "zoom"),
    ({"zoom": False}, "zoom"), ({"zoom": 10 ** 400}, "zoom"), ({"Zoom": 1}, "Zoom"),
    ({1: 1}, "1"), (["zoom"], "params"),
])
def test_bad_params_name_their_key(doc, key):
    with pytest.raises(ConsoleInputError) as err:
        parse_params(doc, IspParams())
    assert err.value.key == key and err.value.status == 422
    assert str(err.value).startswith(key)


@pytest.mark.parametrize("raw, clean", [
    (None, ""), ("", ""), ("rank 3 wider", "rank-3-wider"), ("../../x", "x"),
    ("a/b\\c\x00d", "a-b-c-d"), ("Ünïcode ok", "n-code-ok"), ("x" * 99, "x" * MAX_LABEL),
])
def test_labels_are_safe_file_name_parts(raw, clean):
    assert parse_label(raw) == clean


def test_labels_and_flags_of_other_types_are_refused():
    with pytest.raises(ConsoleInputError, match="label"):
        parse_label(["x"])
    assert parse_flag(None, "annotate") is False and parse_flag(True, "annotate") is True
    with pytest.raises(ConsoleInputError, match="annotate"):
        parse_flag(1, "annotate")
