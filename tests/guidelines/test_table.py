"""The RVMG ECU table: its documented layout read byte by byte, and the reader."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from rvmsim.guidelines import compute_guidelines, guideline_view
from rvmsim.guidelines.table import read_table, table_bytes
from rvmsim.isp import IspParams, OutputSpec
from tests.conftest import bundled_scene


def _set(zoom: float = 1.0):
    scene = bundled_scene("c")
    view = guideline_view(scene, IspParams(zoom=zoom), OutputSpec())
    return compute_guidelines(scene, view, (-200.0, 0.0, 350.5))


def test_the_layout_is_as_documented() -> None:
    gset = _set(zoom=1.6)  # some lines leave the picture and come back: pen-ups
    data = table_bytes(gset)
    magic, version, bits, w, h, n_static, n_angles, per_angle, n_lines, n_points, crc, res = \
        struct.unpack_from("<4sHHHHHHHHIII", data)
    assert (magic, version, w, h, res) == (b"RVMG", 1, 1280, 720, 0)
    assert bits == 4  # 1280 px fit with 1/16 px
    assert n_static == len(gset.static) and n_angles == 3 and per_angle == 2
    assert n_lines == n_static + 3 * 2
    assert crc == zlib.crc32(data[32:])
    angles = struct.unpack_from("<3h", data, 32)
    assert angles == (-2000, 0, 3505)  # 0.1°
    at = 32 + 2 * n_angles
    points_at = at + 12 * n_lines
    assert len(data) == points_at + 4 * n_points
    lines = gset.lines()
    for i, line in enumerate(lines):
        first, count, kind, r, g, b, angle = struct.unpack_from("<IHBBBBH", data, at + 12 * i)
        assert kind == ("mark", "width", "trajectory").index(line.kind)
        assert (r, g, b) == tuple(round(c * 255) for c in line.color)
        assert angle == (0xFFFF if line.steering_deg is None
                         else gset.steering_deg.index(line.steering_deg))
        pts = np.frombuffer(data, "<i2", 2 * count, points_at + 4 * first).reshape(-1, 2)
        expected = []
        for k, piece in enumerate(line.pieces):
            if k:
                expected.append([[-32768, -32768]])
            expected.append(np.rint(np.clip(piece.uv_px, -0.5, [1279.5, 719.5]) * 16))
        want = np.concatenate(expected) if expected else np.empty((0, 2))
        np.testing.assert_array_equal(pts, want)


def test_the_reader_gives_the_lines_back_to_a_thirty_second_of_a_pixel() -> None:
    gset = _set()
    table = read_table(table_bytes(gset))
    assert table.steering_deg == (-200.0, 0.0, 350.5)
    assert len(table.lines) == len(gset.lines())
    for got, line in zip(table.lines, gset.lines()):
        assert got.kind == line.kind and got.steering_deg == line.steering_deg
        assert len(got.pieces) == len(line.pieces)
        for a, b in zip(got.pieces, line.pieces):
            assert np.abs(a - b.uv_px).max() <= 1 / 32 + 1e-9


def test_a_damaged_table_is_refused() -> None:
    data = bytearray(table_bytes(_set()))
    data[40] ^= 0xFF
    with pytest.raises(ValueError, match="checksum"):
        read_table(bytes(data))
    with pytest.raises(ValueError, match="RVMG"):
        read_table(b"XXXX" + bytes(data[4:]))
    with pytest.raises(ValueError):
        read_table(bytes(data[:20]))
