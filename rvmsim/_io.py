"""File helpers: user YAML read safely and within limits (validation errors as one-line
messages), the image-size limit every image a user file asks for is held to, PNG writing.

Limits (``docs/errors.md``): a YAML file is at most :data:`MAX_YAML_BYTES` long, nests at most
:data:`MAX_YAML_DEPTH` deep, and its aliases add at most :data:`MAX_YAML_ALIAS_NODES` nodes
when expanded (a "billion laughs" file is refused while it is composed, before anything is
built from it).  An image (sensor, RVM output, capture) has at most
:func:`max_image_pixels` pixels: :data:`DEFAULT_MAX_IMAGE_PIXELS`, raised by the environment
variable ``RVMSIM_MAX_IMAGE_PIXELS``.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import imageio.v3 as iio
import numpy as np
import yaml
from pydantic import ValidationError

from .errors import InputFileError, RvmsimError
from .storage import write_problem

__all__ = ["KeyPath", "read_text", "parse_yaml", "parse_yaml_mapping", "key_lines",
           "input_error_from_validation", "line_of", "write_png", "make_output_folder",
           "MAX_YAML_BYTES", "MAX_YAML_DEPTH", "MAX_YAML_ALIAS_NODES",
           "DEFAULT_MAX_IMAGE_PIXELS", "MAX_IMAGE_SIDE_PX", "max_image_pixels",
           "image_size_problem", "env_limit", "safe_load_limited", "yaml_problem"]

#: Longest YAML file read (bytes): a scene, criteria, params, tuning or sweep file is a few KiB.
MAX_YAML_BYTES = 4 * 1024**2
#: Deepest nesting of mappings and sequences in a YAML file (a scene needs about 6).
MAX_YAML_DEPTH = 64
#: Most nodes the aliases (``*name``) of a YAML file may add when expanded.
MAX_YAML_ALIAS_NODES = 10_000
#: Most pixels of an image (sensor, RVM output, capture) unless ``RVMSIM_MAX_IMAGE_PIXELS``
#: says otherwise: 5 × 10⁷ px (a 8192 × 6144 sensor; rendering one needs several GiB).
DEFAULT_MAX_IMAGE_PIXELS = 50_000_000
#: Longest image side, px (the renderer's cube faces and OpenCV's remap stay within it).
MAX_IMAGE_SIDE_PX = 16384

#: A key's path in a YAML document, from the root: mapping keys (their text) and list
#: indices, as :func:`key_lines` and pydantic's error locations give them.
KeyPath = tuple[str | int, ...]


def env_limit(name: str, default: int) -> int:
    """The positive integer limit in environment variable ``name``, else ``default``.

    Raises
    ------
    RvmsimError
        The variable is set but not a positive integer.
    """
    raw = os.environ.get(name, "").strip().replace("_", "")
    if not raw:
        return default
    if not raw.isdigit() or int(raw) < 1:
        raise RvmsimError(f"environment variable {name}={os.environ[name]!r}: "
                          "must be a positive integer")
    return int(raw)


def max_image_pixels() -> int:
    """Most pixels of an image: ``RVMSIM_MAX_IMAGE_PIXELS`` or
    :data:`DEFAULT_MAX_IMAGE_PIXELS`."""
    return env_limit("RVMSIM_MAX_IMAGE_PIXELS", DEFAULT_MAX_IMAGE_PIXELS)


def image_size_problem(width: int, height: int, *, min_side: int = 1) -> str | None:
    """Why a ``width`` × ``height`` px image cannot be made (one line), or None when it can:
    each side in [``min_side``, :data:`MAX_IMAGE_SIDE_PX`] and at most
    :func:`max_image_pixels` pixels."""
    if not (min_side <= width <= MAX_IMAGE_SIDE_PX and min_side <= height <= MAX_IMAGE_SIDE_PX):
        return (f"image sides must be {min_side}..{MAX_IMAGE_SIDE_PX} px, "
                f"got {_short(width)}x{_short(height)}")
    limit = max_image_pixels()
    if width * height > limit:
        return (f"{width}x{height} = {width * height} px is over the limit of {limit} px "
                "(raise it with the environment variable RVMSIM_MAX_IMAGE_PIXELS)")
    return None


def _short(n: int) -> str:
    """``n`` for a message, a huge integer shortened (a 400-digit number is not read)."""
    text = str(n)
    return text if len(text) <= 12 else f"{text[:6]}…({len(text)} digits)"


def read_text(path: Path, error: type[InputFileError] = InputFileError, *,
              what: str = "file", max_bytes: int = MAX_YAML_BYTES) -> str:
    """The text of a user file; ``error`` (an :class:`InputFileError`) naming the file when it
    cannot be read or is longer than ``max_bytes`` (``what`` names the kind of file in the
    message: "params file not found")."""
    try:
        with path.open("rb") as f:
            data = f.read(max_bytes + 1)
    except FileNotFoundError:
        raise error(str(path), "", f"{what} not found") from None
    except OSError as err:
        raise error(str(path), "", f"cannot read {what} ({err.strerror or err})") from None
    if len(data) > max_bytes:
        raise error(str(path), "", f"{what} is over the limit of {max_bytes} bytes")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise error(str(path), "", f"cannot read {what} ({err})") from None


class _YamlLimitError(yaml.composer.ComposerError):
    """A YAML document over one of the YAML limits."""


class _LimitedLoader(yaml.SafeLoader):
    """The safe loader, refusing (as a :class:`_YamlLimitError`, with its mark) while it
    composes: a document nested deeper than :data:`MAX_YAML_DEPTH`, aliases that expand to
    more than :data:`MAX_YAML_ALIAS_NODES` nodes, and an alias inside its own anchor (a
    recursive document)."""

    def __init__(self, stream: str):
        super().__init__(stream)
        self._open_anchors: list[str | None] = []
        self._alias_nodes = 0
        self._sizes: dict[int, int] = {}

    def compose_node(self, parent: yaml.Node | None, index: object) -> yaml.Node | None:
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            if event.anchor in self._open_anchors:
                raise _YamlLimitError(None, None, f"alias *{event.anchor} is inside its own "
                                      "anchor (a recursive document)", event.start_mark)
            node = super().compose_node(parent, index)
            self._alias_nodes += self._size(node)
            if self._alias_nodes > MAX_YAML_ALIAS_NODES:
                raise _YamlLimitError(None, None, "aliases expand to more than "
                                      f"{MAX_YAML_ALIAS_NODES} nodes", event.start_mark)
            return node
        if len(self._open_anchors) >= MAX_YAML_DEPTH:
            raise _YamlLimitError(None, None, f"nested more than {MAX_YAML_DEPTH} levels deep",
                                  event.start_mark)
        self._open_anchors.append(getattr(event, "anchor", None))
        try:
            return super().compose_node(parent, index)
        finally:
            self._open_anchors.pop()

    def _size(self, node: yaml.Node) -> int:
        """Nodes of ``node`` with its aliases expanded (memoized: linear in the document)."""
        known = self._sizes.get(id(node))
        if known is not None:
            return known
        if isinstance(node, yaml.MappingNode):
            n = 1 + sum(self._size(k) + self._size(v) for k, v in node.value)
        elif isinstance(node, yaml.SequenceNode):
            n = 1 + sum(self._size(v) for v in node.value)
        else:
            n = 1
        self._sizes[id(node)] = n
        return n


def safe_load_limited(text: str) -> Any:
    """``yaml.safe_load`` within the YAML limits (depth, aliases; see the module docstring).

    Raises
    ------
    yaml.YAMLError
        Bad YAML, or a document over a limit (see :func:`yaml_problem`).
    """
    return yaml.load(text, Loader=_LimitedLoader)  # noqa: S506 - a SafeLoader subclass


def yaml_problem(err: yaml.YAMLError) -> tuple[str, int | None]:
    """(one-line message, 1-based line or None) of a YAML error from
    :func:`safe_load_limited`: "malformed YAML: …" or "over the YAML limits: …"."""
    mark = getattr(err, "problem_mark", None)
    line = mark.line + 1 if mark is not None else None
    problem = getattr(err, "problem", None) or (str(err).splitlines() or [type(err).__name__])[0]
    what = "over the YAML limits" if isinstance(err, _YamlLimitError) else "malformed YAML"
    return f"{what}: {problem}", line


def parse_yaml(text: str, source: str, error: type[InputFileError] = InputFileError) -> Any:
    """``yaml.safe_load`` within the YAML limits, with a one-line ``error`` (file and line) on
    bad YAML or a document over a limit."""
    try:
        return safe_load_limited(text)
    except yaml.YAMLError as err:
        message, line = yaml_problem(err)
        raise error(source, "", message, line) from None


def parse_yaml_mapping(text: str, source: str, error: type[InputFileError], what: str, *,
                       empty_ok: bool = False) -> dict[Any, Any]:
    """:func:`parse_yaml` for a file that must hold a mapping: ``error`` saying "``what``
    must be a YAML mapping" otherwise (an empty document is ``{}`` with ``empty_ok``)."""
    data = parse_yaml(text, source, error)
    if data is None and empty_ok:
        return {}
    if not isinstance(data, dict):
        raise error(source, "", f"{what} must be a YAML mapping")
    return data


def key_lines(text: str) -> dict[KeyPath, int]:
    """Map each key path in a YAML document to its 1-based line (best effort; empty for a
    document that :func:`parse_yaml` refuses)."""
    lines: dict[KeyPath, int] = {}
    try:
        root = yaml.compose(text, Loader=_LimitedLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError:
        return lines  # no line is known; the parse error itself is parse_yaml's to report

    def walk(node: yaml.Node, path: KeyPath) -> None:
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
    lines: Mapping[KeyPath, int],
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
        got = repr(e["input"])
        msg = f"{msg} (got {got if len(got) <= 60 else got[:40] + f'…, {len(got)} characters'})"
    return error(source, key, msg, line_of(lines, loc))


def line_of(lines: Mapping[KeyPath, int], path: KeyPath) -> int | None:
    """The line (from :func:`key_lines`) of the longest prefix of the key ``path`` that the
    document has: the key itself, else the nearest enclosing key; None if none is known."""
    for n in range(len(path), 0, -1):
        if path[:n] in lines:
            return lines[path[:n]]
    return None


def make_output_folder(path: str | Path) -> Path:
    """``path`` as a folder, created with its parents when missing.

    Raises
    ------
    RvmsimError
        One line naming the folder that cannot be created.
    """
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RvmsimError(f"{out}: {write_problem(err, 'cannot create output folder')}") from None
    return out


def write_png(path: str | Path, image: np.ndarray) -> Path:
    """Write ``image`` ((H, W) or (H, W, 3) uint8) as PNG, creating the folder.

    The file appears whole or not at all: it is written beside ``path`` under a temporary
    name and renamed over it, so a reader (another process sharing the render cache, a
    browser polling a picture) never sees half a file."""

    path = Path(path)
    # a name of this writer's own (processes and threads may write one path at once); made
    # by the writer, so the file gets the usual permissions
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        iio.imwrite(tmp, np.ascontiguousarray(image), extension=".png")
        os.replace(tmp, path)
    except OSError as err:
        raise RvmsimError(f"{path}: {write_problem(err, 'cannot write image')}") from None
    finally:
        tmp.unlink(missing_ok=True)  # a failed write leaves nothing behind
    return path
