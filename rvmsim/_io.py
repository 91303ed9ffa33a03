"""File helpers: user YAML read safely (validation errors as one-line messages), PNG writing."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from pydantic import ValidationError

from .errors import InputFileError, RvmsimError

__all__ = ["read_text", "parse_yaml", "key_lines", "input_error_from_validation", "line_of",
           "write_png"]


def read_text(path: Path, error: type[InputFileError] = InputFileError, *,
              what: str = "file") -> str:
    """The text of a user file; ``error`` (an :class:`InputFileError`) naming the file when it
    cannot be read (``what`` names the kind of file in the message: "params file not found")."""
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(str(path), "", f"{what} not found") from None
    except (OSError, UnicodeDecodeError) as err:
        raise error(str(path), "", f"cannot read {what} ({err})") from None


def parse_yaml(text: str, source: str, error: type[InputFileError] = InputFileError) -> Any:
    """``yaml.safe_load`` with a one-line ``error`` (file and line) on bad YAML."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        line = mark.line + 1 if mark is not None else None
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise error(source, "", f"malformed YAML: {problem}", line) from None


def key_lines(text: str) -> dict[tuple[Any, ...], int]:
    """Map each key path in a YAML document to its 1-based line (best effort)."""
    lines: dict[tuple[Any, ...], int] = {}
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return lines  # no line is known; the parse error itself is parse_yaml's to report

    def walk(node: Any, path: tuple[Any, ...]) -> None:
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                key = k.value
                lines[path + (key,)] = k.start_mark.line + 1
                walk(v, path + (key,))
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                lines[path + (i,)] = v.start_mark.line + 1
                walk(v, path + (i,))

    if root is not None:
        walk(root, ())
    return lines


def input_error_from_validation(
    err: ValidationError,
    source: str,
    lines: dict[tuple[Any, ...], int],
    error: type[InputFileError],
    tags: frozenset[str] = frozenset(),
) -> InputFileError:
    """The first pydantic error as ``FILE:LINE: dotted.key: message``.

    ``tags`` are discriminator tags pydantic puts into error locations; they are dropped.
    """
    e = err.errors(include_url=False)[0]
    loc = tuple(p for p in e["loc"] if not (isinstance(p, str) and p in tags))
    key = ".".join(str(p) for p in loc)
    kind = e["type"]
    msg = e["msg"]
    if kind == "extra_forbidden":
        msg = "unknown key"
    elif kind == "missing":
        msg = "missing required key"
    elif msg.startswith("Value error, "):
        msg = msg[len("Value error, ") :]
    if kind not in ("extra_forbidden", "missing") and "input" in e and not isinstance(
        e["input"], dict
    ):
        msg = f"{msg} (got {e['input']!r})"
    return error(source, key, msg, line_of(lines, loc))


def line_of(lines: Mapping[tuple[Any, ...], int], path: tuple[Any, ...]) -> int | None:
    """The line (from :func:`key_lines`) of the longest prefix of the key ``path`` that the
    document has: the key itself, else the nearest enclosing key; None if none is known."""
    for n in range(len(path), 0, -1):
        if path[:n] in lines:
            return lines[path[:n]]
    return None


def write_png(path: str | Path, image: np.ndarray) -> Path:
    """Write ``image`` ((H, W) or (H, W, 3) uint8) as PNG, creating the folder."""
    import imageio.v3 as iio

    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        iio.imwrite(path, np.ascontiguousarray(image), extension=".png")
    except OSError as err:
        raise RvmsimError(f"{path}: cannot write image ({err.strerror or err})") from None
    return path
