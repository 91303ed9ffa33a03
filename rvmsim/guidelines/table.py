"""The guideline table a camera ECU loads: every line's display points, per steering angle,
in fixed point (format ``RVMG`` version 1, documented in docs/guidelines.md).

Layout (little-endian; offsets in bytes):

=======  ==========  ==============================================================
offset   type        field
=======  ==========  ==============================================================
0        char[4]     magic ``RVMG``
4        u16         version (1)
6        u16         fraction bits F: a coordinate is ``round(px · 2^F)``
8        u16, u16    RVM image width, height, px
12       u16         static lines S
14       u16         steering angles A
16       u16         trajectory lines per angle T
18       u16         lines N = S + A·T
20       u32         points P (pen-ups included)
24       u32         CRC-32 of every byte after the header
28       u32         reserved (0)
32       i16[A]      steering-wheel angles, 0.1° (positive toward +X)
…        12 B × N    line directory: u32 first point, u16 point count, u8 kind (0 mark,
                     1 width, 2 trajectory), u8 R, G, B, u16 angle index (0xFFFF: static)
…        i16[2] × P  points (u, v); (−32768, −32768) lifts the pen between a line's pieces
=======  ==========  ==============================================================

Static lines come first, then per angle its T trajectory lines (−X side, +X side).  F is the
largest number of fraction bits (at most 4, 1/16 px) that holds the image size.

Convention
----------
Display px of the RVM image of record, pixel centres at integer coordinates.
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass

import numpy as np

from .overlay import GuidelineSet
from .project import DisplayLine

__all__ = ["TABLE_MAGIC", "TABLE_VERSION", "PEN_UP", "KINDS", "TableLine", "GuidelineTable",
           "table_bytes", "read_table"]

TABLE_MAGIC = b"RVMG"
TABLE_VERSION = 1
PEN_UP = -32768
KINDS = ("mark", "width", "trajectory")
_HEADER = struct.Struct("<4sHHHHHHHHIII")
_LINE = struct.Struct("<IHBBBBH")
_STATIC = 0xFFFF


@dataclass(frozen=True, eq=False)
class TableLine:
    """One line read from a table: kind, colour (RGB 0–255), steering angle (None: static)
    and its pieces, each (M, 2) float64 display px."""

    kind: str
    color: tuple[int, int, int]
    steering_deg: float | None
    pieces: tuple[np.ndarray, ...]


@dataclass(frozen=True, eq=False)
class GuidelineTable:
    """A table read back (:func:`read_table`)."""

    width: int
    height: int
    fraction_bits: int
    steering_deg: tuple[float, ...]
    lines: tuple[TableLine, ...]


def _fraction_bits(width: int, height: int) -> int:
    for bits in range(4, -1, -1):
        if (max(width, height) + 1) * (1 << bits) < 32767:
            return bits
    return 0


def _points(line: DisplayLine, scale: int, width: int, height: int) -> np.ndarray:
    parts = []
    for k, piece in enumerate(line.pieces):
        if k:
            parts.append(np.array([[PEN_UP, PEN_UP]]))
        uv = np.clip(piece.uv_px, -0.5, [width - 0.5, height - 0.5])
        parts.append(np.rint(uv * scale))
    return (np.concatenate(parts) if parts else np.empty((0, 2))).astype("<i2")


def table_bytes(gset: GuidelineSet) -> bytes:
    """The ``RVMG`` table of a guideline set (see the module docstring)."""
    out = gset.view.output
    bits = _fraction_bits(out.width, out.height)
    scale = 1 << bits
    per_angle = len(gset.trajectories[0]) if gset.trajectories else 0
    lines: list[tuple[DisplayLine, int]] = [(l, _STATIC) for l in gset.static]
    for a, group in enumerate(gset.trajectories):
        lines += [(l, a) for l in group]
    directory, blocks, first = [], [], 0
    for line, angle in lines:
        pts = _points(line, scale, out.width, out.height)
        r, g, b = (int(round(c * 255)) for c in line.color)
        directory.append(_LINE.pack(first, len(pts), KINDS.index(line.kind), r, g, b, angle))
        blocks.append(pts.tobytes())
        first += len(pts)
    angles = np.rint(np.asarray(gset.steering_deg, np.float64) * 10).astype("<i2")
    body = angles.tobytes() + b"".join(directory) + b"".join(blocks)
    header = _HEADER.pack(TABLE_MAGIC, TABLE_VERSION, bits, out.width, out.height,
                          len(gset.static), len(gset.steering_deg), per_angle, len(lines),
                          first, zlib.crc32(body), 0)
    return header + body


def read_table(data: bytes) -> GuidelineTable:
    """Read an ``RVMG`` table.

    Raises
    ------
    ValueError
        Not a version-1 table, a bad checksum, or sizes that do not add up.
    """
    if len(data) < _HEADER.size:
        raise ValueError("too short for a guideline table")
    (magic, version, bits, width, height, n_static, n_angles, per_angle, n_lines, n_points,
     crc, _) = _HEADER.unpack_from(data)
    if magic != TABLE_MAGIC or version != TABLE_VERSION:
        raise ValueError("not an RVMG version 1 guideline table")
    body = data[_HEADER.size:]
    if zlib.crc32(body) != crc:
        raise ValueError("checksum mismatch")
    need = 2 * n_angles + _LINE.size * n_lines + 4 * n_points
    if len(body) != need or n_lines != n_static + n_angles * per_angle:
        raise ValueError("sizes in the header do not match the table")
    angles = np.frombuffer(body, "<i2", n_angles).astype(np.float64) / 10.0
    at = 2 * n_angles
    pts_all = np.frombuffer(body, "<i2", 2 * n_points, at + _LINE.size * n_lines).reshape(-1, 2)
    lines = []
    for i in range(n_lines):
        first, count, kind, r, g, b, angle = _LINE.unpack_from(body, at + i * _LINE.size)
        pts = pts_all[first:first + count]
        pen = np.flatnonzero(pts[:, 0] == PEN_UP)
        parts = [part[part[:, 0] != PEN_UP] for part in np.split(pts, pen)]
        pieces = tuple(part.astype(np.float64) / (1 << bits) for part in parts if len(part))
        lines.append(TableLine(KINDS[kind], (r, g, b),
                               None if angle == _STATIC else float(angles[angle]), pieces))
    return GuidelineTable(width, height, bits, tuple(angles.tolist()), tuple(lines))
