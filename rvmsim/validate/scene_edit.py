"""A scene file rewritten with the corrected mount pose (in memory:
:func:`rvmsim.pose.scene_with_mount`).

The file is rewritten line by line, not re-dumped, so that its comments and layout stay:
only the ``camera.mount`` values change.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path

from .._io import KeyPath, key_lines, read_text
from ..errors import SceneError
from ..scene import Scene, load_scene
from ..pose import PoseCorrection

__all__ = ["write_corrected_scene"]

_MOUNT_KEYS = ("position", "yaw_deg", "pitch_deg", "roll_deg")
#: ``key: value  # comment`` on one line; groups: head, value, comment (with its leading
#: blanks), the comment alone, the line end.
_VALUE_LINE = r"^([ \t]*{key}[ \t]*:[ \t]*)([^#\r\n]*?)([ \t]*(#[^\r\n]*)?)(\r?\n)?$"
#: One number of a block-style list: ``- 0.02``.
_BLOCK_ITEM = r"^[ \t]*-[ \t]*[-+.\deE]+[ \t]*(#.*)?\r?\n?$"


def write_corrected_scene(scene_file: str | Path, correction: PoseCorrection,
                          out_file: str | Path) -> Path:
    """Copy ``scene_file`` to ``out_file`` with the corrected mount pose.

    Only the ``camera.mount`` values change; comments and layout stay.  The position is
    written as ``[x, y, z]`` with 4 decimals (m), the angles with 3 (degrees); a block-style
    position list becomes a flow list, and missing angle keys are added after the position.
    Mesh paths stay valid when ``out_file`` is in another folder only if they are absolute,
    so the file is checked by loading it again.  A ``load_state`` stays as it is: without a
    ``pivot_m`` of its own its body then pitches about the corrected mount position (the
    body shifts by about the pitch in radians times the position correction: 0.26 mm at
    1.5° and 10 mm).

    Raises
    ------
    SceneError
        When the mount cannot be rewritten in place, the copy cannot be written, or it does
        not load.
    """
    scene_file, out_file = Path(scene_file), Path(out_file)
    text = read_text(scene_file, SceneError)
    new_text = _rewrite_mount(text, _mount_values(correction), str(scene_file))
    try:
        out_file.parent.mkdir(parents=True, exist_ok=True)
        out_file.write_text(new_text)
    except OSError as err:
        raise SceneError(str(out_file), "", f"cannot write scene ({err.strerror or err})") from None
    load_scene(out_file)
    return out_file


def _mount_values(correction: PoseCorrection) -> dict[str, str]:
    """The mount values as YAML text, by key."""
    return {
        "position": "[{:.4f}, {:.4f}, {:.4f}]".format(*correction.position_m),
        "yaw_deg": f"{correction.yaw_deg:.3f}",
        "pitch_deg": f"{correction.pitch_deg:.3f}",
        "roll_deg": f"{correction.roll_deg:.3f}",
    }


def _rewrite_mount(text: str, values: dict[str, str], source: str) -> str:
    """``text`` (a scene YAML document from ``source``) with ``camera.mount`` set to
    ``values``; keys it lacks are inserted after ``position``."""
    lines = text.splitlines(keepends=True)
    where = key_lines(text)
    pos_line = where.get(("camera", "mount", "position"))
    if pos_line is None:
        raise SceneError(source, "camera.mount.position", "not found")
    indent = re.match(r"\s*", lines[pos_line - 1])
    inserts = []
    drop: set[int] = set()
    for key in _MOUNT_KEYS:
        ln = where.get(("camera", "mount", key))
        if ln is None:
            inserts.append(f"{indent.group(0) if indent else ''}{key}: {values[key]}\n")
            continue
        new_line, dropped = _rewrite_value(lines, ln, key, values[key], where, source)
        lines[ln - 1] = new_line
        drop.update(dropped)
    if inserts:
        lines[pos_line:pos_line] = inserts
        drop = {i + len(inserts) if i >= pos_line else i for i in drop}
    return "".join(ln for i, ln in enumerate(lines) if i not in drop)


def _rewrite_value(lines: list[str], ln: int, key: str, value: str,
                   where: Mapping[KeyPath, int], source: str) -> tuple[str, set[int]]:
    """Line ``ln`` (1-based) with ``key``'s value replaced by ``value``, and the 0-based
    indices of the block-list item lines to drop (the position as ``- x`` lines)."""
    mt = re.match(_VALUE_LINE.format(key=key), lines[ln - 1])
    drop: set[int] = set()
    ok = mt is not None
    if mt is not None and key == "position" and "]" not in mt.group(2):
        # A block list (one "- x" line per item) becomes one flow list.
        items = [where.get(("camera", "mount", "position", i)) for i in range(3)]
        item_lines = [i for i in items if i is not None]
        ok = mt.group(2) == "" and len(item_lines) == 3 and all(
            re.match(_BLOCK_ITEM, lines[i - 1]) for i in item_lines)
        if ok:
            drop.update(i - 1 for i in item_lines)
    if mt is None or not ok:
        raise SceneError(source, f"camera.mount.{key}", "cannot rewrite this value in place "
                         "(write it as a plain number, the position as [x, y, z])", ln)
    head = mt.group(1) if mt.group(1).endswith((" ", "\t")) else mt.group(1) + " "
    return head + value + (mt.group(3) or "") + (mt.group(5) or "\n"), drop
