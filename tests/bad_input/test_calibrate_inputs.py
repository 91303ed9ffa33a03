"""Bad input for ``rvmsim calibrate``: no captures, missing or corrupt images, a bad
``--board``, too few usable views, bad ``--import`` files, a bad ``--write-scene`` scene.
Each is one stderr line naming the file or the option, exit 2, and the scene unchanged."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from .harness import MEMORY, Case, check_case
from .test_captures import png


def _blank_pngs(n: int):
    def setup(folder):
        import imageio.v3 as iio

        (folder / "caps").mkdir()
        for k in range(n):
            noise = np.random.default_rng(k).integers(0, 255, (48, 64), dtype=np.uint8)
            iio.imwrite(folder / "caps" / f"c{k}.png", noise)
    return setup


def _write(name: str, data: bytes | str):
    def setup(folder):
        p = folder / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(data if isinstance(data, bytes) else data.encode())
    return setup


def _both(*setups):
    def setup(folder):
        for s in setups:
            s(folder)
    return setup


GOOD_CAMERA = "camera:\n  image_size: [64, 48]\n  intrinsics: {K: [[20, 0, 32], [0, 20, 24], [0, 0, 1]]}\n  lens: {model: kannala_brandt, k: [0, 0, 0, 0]}\n"
CAL = ("calibrate", "--out", "o")

CASES = [
    Case("no-captures", CAL, ["no captures"]),
    Case("missing-capture", (*CAL, "nothere.png", "--board", "7x9:0.05"),
         ["nothere.png", "not found"]),
    Case("corrupt-capture", (*CAL, "bad.png", "--board", "7x9:0.05"), ["bad.png"],
         setup=_write("bad.png", b"\x89PNG\r\n\x1a\nnot really")),
    Case("header-bomb-capture", (*CAL, "big.png", "--board", "7x9:0.05"), ["big.png"],
         setup=_write("big.png", png(100000, 100000)), isolate=MEMORY),
    Case("empty-folder", (*CAL, "caps", "--board", "7x9:0.05"), ["caps", "no images"],
         setup=lambda f: (f / "caps").mkdir()),
    Case("no-board", (*CAL, "caps"), ["--board", "required"], setup=_blank_pngs(3)),
    Case("board-garbage", (*CAL, "caps", "--board", "seven"), ["--board", "COLSxROWS"],
         setup=_blank_pngs(3)),
    Case("board-too-small", (*CAL, "caps", "--board", "1x9:0.05"), ["--board", "2..200"],
         setup=_blank_pngs(3)),
    Case("board-zero-square", (*CAL, "caps", "--board", "7x9:0"), ["--board", "square size"],
         setup=_blank_pngs(3)),
    Case("board-nan-square", (*CAL, "caps", "--board", "7x9:nan"), ["--board"],
         setup=_blank_pngs(3)),
    Case("board-bad-scene", (*CAL, "caps", "--board", "s.yaml"), ["s.yaml"],
         setup=_both(_blank_pngs(3), _write("s.yaml", "name: [unclosed\n"))),
    Case("board-never-found", (*CAL, "caps", "--board", "7x9:0.05"), ["at least 3"],
         setup=_blank_pngs(4)),
    Case("import-missing", (*CAL, "--import", "nothere.yaml"), ["nothere.yaml"]),
    Case("import-unknown-format", (*CAL, "--import", "x.yaml"), ["x.yaml", "not a known"],
         setup=_write("x.yaml", "a: 1\n")),
    Case("import-bad-matrix", (*CAL, "--import", "x.yaml"), ["x.yaml", "camera_matrix"],
         setup=_write("x.yaml", "%YAML:1.0\n---\ncamera_matrix: [1, 2]\ndist_coeffs: [0, 0, 0, 0]\n")),
    Case("import-ocam-truncated", (*CAL, "--import", "calib_results.txt"),
         ["calib_results.txt", "OCamCalib"],
         setup=_write("calib_results.txt", "#polynomial coefficients\n\n3 -100 0 0.001\n\n2 1 2\n")),
    Case("import-ocam-singular", (*CAL, "--import", "calib_results.txt"),
         ["calib_results.txt", "invertible"],
         setup=_write("calib_results.txt", "#polynomial coefficients\n\n3 -100 0 0.001\n\n"
                      "2 1 2\n\n24 32\n\n1 1 1\n\n48 64\n")),
    Case("import-and-captures", (*CAL, "c.png", "--import", "x.yaml"), ["not both"],
         setup=_write("x.yaml", GOOD_CAMERA)),
    Case("write-scene-missing", (*CAL, "--import", "x.yaml", "--write-scene", "nothere.yaml"),
         ["nothere.yaml"], setup=_write("x.yaml", GOOD_CAMERA)),
    Case("write-scene-broken", (*CAL, "--import", "x.yaml", "--write-scene", "s/scene.yaml"),
         ["scene.yaml"], keep=("s",),
         setup=_both(_write("x.yaml", GOOD_CAMERA), _write("s/scene.yaml", "name: [oops\n"))),
    Case("write-scene-invalid", (*CAL, "--import", "x.yaml", "--write-scene", "s/scene.yaml"),
         ["scene.yaml", "camera"], keep=("s",),
         setup=_both(_write("x.yaml", GOOD_CAMERA), _write("s/scene.yaml", "name: t\n"))),
]


def _scene_board(edit):
    """The small scene with its ``test_site.board`` edited (``edit``: the board mapping
    changed in place; None: the key removed), as ``s.yaml``, and three blank captures."""
    def setup(folder):
        from .conftest import small_scene

        _blank_pngs(3)(folder)
        small_scene(folder)
        doc = yaml.safe_load((folder / "scene.yaml").read_text())
        if edit is None:
            del doc["test_site"]["board"]
        else:
            edit(doc["test_site"]["board"])
        (folder / "s.yaml").write_text(yaml.safe_dump(doc))
    return setup


def _good_then_bad(name: str, data: bytes | None):
    """Three good captures in ``caps``, then ``name`` holding ``data`` (None: a real image
    of another size)."""
    def setup(folder):
        import imageio.v3 as iio

        _blank_pngs(3)(folder)
        if data is None:
            noise = np.random.default_rng(9).integers(0, 255, (24, 32), dtype=np.uint8)
            iio.imwrite(folder / "caps" / name, noise)
        else:
            (folder / "caps" / name).write_bytes(data)
    return setup


#: Issue #30: a scene's board disabled or absent (before any capture is read), and a bad
#: capture among good ones (before any detection).
CASES += [
    Case("board-scene-disabled", (*CAL, "nothere.png", "--board", "s.yaml"),
         ["s.yaml", "test_site.board.enabled", "disabled"],
         setup=_scene_board(lambda b: b.update(enabled=False))),
    Case("board-scene-absent", (*CAL, "caps", "--board", "s.yaml"),
         ["s.yaml", "test_site.board"], setup=_scene_board(None)),
    Case("capture-empty-among-good", (*CAL, "caps", "--board", "7x9:0.05"), ["c9.png"],
         setup=_good_then_bad("c9.png", b"")),
    Case("capture-corrupt-among-good", (*CAL, "caps", "--board", "7x9:0.05"), ["c9.png"],
         setup=_good_then_bad("c9.png", b"\x89PNG\r\n\x1a\nnot really")),
    Case("capture-other-size-among-good", (*CAL, "caps", "--board", "7x9:0.05"),
         ["c9.png", "differ in size"], setup=_good_then_bad("c9.png", None)),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_calibrate_input(case, tmp_path):
    check_case(case, tmp_path)
