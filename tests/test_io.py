"""rvmsim._io: the YAML limits (size, depth, alias expansion, recursion), the image-size
limit and its environment variable."""

from __future__ import annotations

import pytest

from rvmsim._io import (MAX_YAML_ALIAS_NODES, MAX_YAML_BYTES, MAX_YAML_DEPTH,
                        image_size_problem, key_lines, max_image_pixels, parse_yaml, read_text)
from rvmsim.errors import RvmsimError, SceneError


def _nested(depth: int) -> str:
    return "[" * depth + "]" * depth


def test_nesting_up_to_the_limit_loads_and_beyond_is_refused():
    # The document root counts as one level: depth - 1 sequences inside a mapping value.
    assert parse_yaml("a: " + _nested(MAX_YAML_DEPTH - 2), "f.yaml") is not None
    with pytest.raises(SceneError, match="nested more than") as err:
        parse_yaml("a: " + _nested(5000), "f.yaml", SceneError)
    assert err.value.line == 1 and "\n" not in str(err.value)
    assert key_lines("a: " + _nested(5000)) == {}


def test_aliases_within_the_budget_load_and_a_billion_laughs_is_refused():
    ok = "base: &b {x: 1, y: [1, 2]}\none: *b\ntwo: *b\n"
    assert parse_yaml(ok, "f.yaml") == {"base": {"x": 1, "y": [1, 2]}, "one": {"x": 1, "y": [1, 2]},
                                        "two": {"x": 1, "y": [1, 2]}}
    assert key_lines(ok)[("two",)] == 3
    laughs = "l0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"l{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]\n" for i in range(1, 9))
    with pytest.raises(SceneError, match=f"more than {MAX_YAML_ALIAS_NODES} nodes"):
        parse_yaml(laughs, "f.yaml", SceneError)
    assert key_lines(laughs) == {}


def test_a_recursive_alias_is_refused():
    with pytest.raises(SceneError, match="inside its own anchor"):
        parse_yaml("a: &s [1, *s]\n", "f.yaml", SceneError)


def test_a_file_over_the_size_limit_is_refused_before_it_is_read_whole(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_bytes(b"a: 1\n" + b"#" * MAX_YAML_BYTES)
    with pytest.raises(SceneError, match=f"over the limit of {MAX_YAML_BYTES} bytes"):
        read_text(path, SceneError)
    path.write_text("a: 1\n")
    assert read_text(path, SceneError) == "a: 1\n"
    assert read_text(path, SceneError, max_bytes=5) == "a: 1\n"
    with pytest.raises(SceneError, match="over the limit of 4 bytes"):
        read_text(path, SceneError, max_bytes=4)


def test_image_size_limit_and_its_environment_variable(monkeypatch):
    monkeypatch.delenv("RVMSIM_MAX_IMAGE_PIXELS", raising=False)
    assert image_size_problem(1280, 960) is None
    assert "16384" in (image_size_problem(100000, 100000) or "")
    assert "digits" in (image_size_problem(10**400, 10) or "")
    assert "RVMSIM_MAX_IMAGE_PIXELS" in (image_size_problem(8000, 8000) or "")
    assert "16.." in (image_size_problem(8, 8, min_side=16) or "")
    monkeypatch.setenv("RVMSIM_MAX_IMAGE_PIXELS", "70_000_000")
    assert max_image_pixels() == 70_000_000 and image_size_problem(8000, 8000) is None
    monkeypatch.setenv("RVMSIM_MAX_IMAGE_PIXELS", "lots")
    with pytest.raises(RvmsimError, match="RVMSIM_MAX_IMAGE_PIXELS"):
        max_image_pixels()


def test_write_png_replaces_a_file_whole_or_not_at_all(tmp_path):
    """A reader (another worker sharing the render cache) never sees half a PNG: the image
    is written under a temporary name and renamed; a write that fails leaves the old file
    and no temporary file."""
    import imageio.v3 as iio
    import numpy as np

    from rvmsim._io import write_png

    path = tmp_path / "cache" / "fisheye_labels.png"
    old = np.arange(48, dtype=np.uint8).reshape(6, 8)
    write_png(path, old)
    before = path.read_bytes()
    with pytest.raises(TypeError):
        write_png(path, np.zeros((6, 8), np.complex128))  # cannot be encoded
    assert path.read_bytes() == before
    assert sorted(p.name for p in path.parent.iterdir()) == ["fisheye_labels.png"]
    inode = path.stat().st_ino
    held = path.open("rb")  # a reader in the middle of the old file keeps reading it whole
    new = old[::-1].copy()
    write_png(path, new)
    assert path.stat().st_ino != inode  # a new file renamed over the old, not rewritten
    assert held.read() == before
    held.close()
    assert np.array_equal(iio.imread(path), new)
    assert sorted(p.name for p in path.parent.iterdir()) == ["fisheye_labels.png"]
    assert oct(path.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask
