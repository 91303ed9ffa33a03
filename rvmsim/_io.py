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

import json
import os
import re
import uuid
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any

import imageio.v3 as iio
import numpy as np
import yaml
from pydantic import AfterValidator, BaseModel, ConfigDict, ValidationError

from .errors import InputFileError, RvmsimError
from .storage import write_problem

__all__ = ["KeyPath", "read_text", "parse_yaml", "parse_yaml_mapping", "key_lines",
           "input_error_from_validation", "line_of", "write_png", "make_output_folder",
           "MAX_YAML_BYTES", "MAX_YAML_DEPTH", "MAX_YAML_ALIAS_NODES",
           "DEFAULT_MAX_IMAGE_PIXELS", "MAX_IMAGE_SIDE_PX", "max_image_pixels",
           "image_size_problem", "env_limit", "safe_load_limited", "yaml_problem",
           "MAX_JSON_BYTES", "MAX_JSON_DEPTH", "json_depth", "parse_json", "read_json_file",
           "path_problem", "FilePathText", "validate_document", "key_path_text", "ReadModel"]

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

#: Longest JSON file read back (bytes), unless ``RVMSIM_MAX_JSON_BYTES`` says otherwise: a
#: robustness.json of 10,000 samples is about 60 MiB.
MAX_JSON_BYTES = 512 * 1024**2
#: Deepest nesting of objects and arrays in a JSON file read back, unless
#: ``RVMSIM_MAX_JSON_DEPTH`` says otherwise (a robustness.json needs about 6).
MAX_JSON_DEPTH = 64

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


def _read_bytes(path: Path, error: type[InputFileError], what: str, max_bytes: int) -> bytes:
    """At most ``max_bytes`` + 1 bytes of ``path`` (one more tells the caller it is over);
    ``error`` naming the file when it is missing or cannot be read."""
    try:
        with path.open("rb") as f:
            return f.read(max_bytes + 1)
    except FileNotFoundError:
        raise error(str(path), "", f"{what} not found") from None
    except (OSError, ValueError) as err:  # ValueError: a path the system cannot take
        raise error(str(path), "", f"cannot read {what} "
                    f"({getattr(err, 'strerror', None) or err})") from None


def read_text(path: Path, error: type[InputFileError] = InputFileError, *,
              what: str = "file", max_bytes: int = MAX_YAML_BYTES) -> str:
    """The text of a user file; ``error`` (an :class:`InputFileError`) naming the file when it
    cannot be read or is longer than ``max_bytes`` (``what`` names the kind of file in the
    message: "params file not found")."""
    data = _read_bytes(path, error, what, max_bytes)
    if len(data) > max_bytes:
        raise error(str(path), "", f"{what} is over the limit of {max_bytes} bytes")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise error(str(path), "", f"cannot read {what} ({err})") from None


#: A JSON string (its escapes included), blanked out before brackets are counted.
_JSON_STRING = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)
#: Every byte but the four brackets (deleted before they are counted).
_NOT_BRACKETS = bytes(b for b in range(256) if b not in b"[]{}")


def json_depth(data: bytes) -> int:
    """How deep the objects and arrays of the JSON text ``data`` nest (0: a bare value),
    counted from its brackets outside strings, without parsing it (so a document nested
    deeper than Python's recursion limit is measured, not crashed on)."""
    brackets = _JSON_STRING.sub(b"", data).translate(None, _NOT_BRACKETS)
    codes = np.frombuffer(brackets, dtype=np.uint8)
    steps = np.where((codes == ord("[")) | (codes == ord("{")), 1, -1).astype(np.int32)
    return int(np.cumsum(steps).max(initial=0))


def parse_json(data: bytes | str, source: str, error: type[InputFileError] = InputFileError,
               *, what: str = "file") -> Any:
    """The JSON document ``data`` (the text of ``source``) within the JSON limits: at most
    ``RVMSIM_MAX_JSON_BYTES`` (:data:`MAX_JSON_BYTES`) long and nested at most
    ``RVMSIM_MAX_JSON_DEPTH`` (:data:`MAX_JSON_DEPTH`) deep.

    Raises
    ------
    InputFileError
        ``error``, one line naming ``source``: over a limit, not UTF-8, or not valid JSON
        (with its line).
    """
    raw = data.encode("utf-8", "surrogatepass") if isinstance(data, str) else data
    max_bytes = env_limit("RVMSIM_MAX_JSON_BYTES", MAX_JSON_BYTES)
    if len(raw) > max_bytes:
        raise error(source, "", f"{what} is over the limit of {max_bytes} bytes (raise it with "
                    "the environment variable RVMSIM_MAX_JSON_BYTES)")
    max_depth = env_limit("RVMSIM_MAX_JSON_DEPTH", MAX_JSON_DEPTH)
    if json_depth(raw) > max_depth:
        raise error(source, "", f"over the JSON limits: nested more than {max_depth} levels "
                    "deep (raise it with the environment variable RVMSIM_MAX_JSON_DEPTH)")
    try:
        return json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as err:
        raise error(source, "", f"cannot read {what} ({err})") from None
    except json.JSONDecodeError as err:
        raise error(source, "", f"not valid JSON (line {err.lineno}: {err.msg})") from None
    except RecursionError:  # within the depth limit but past the interpreter's stack
        raise error(source, "", "over the JSON limits: nested too deep to read") from None


def read_json_file(path: Path, error: type[InputFileError] = InputFileError, *,
                   what: str = "file") -> Any:
    """The JSON document in ``path`` (a file rvmsim wrote and reads back, or a user's JSON
    file), read within the JSON limits (:func:`parse_json`).

    Raises
    ------
    InputFileError
        ``error``, one line naming the file: not found, unreadable, over a limit, not JSON.
    """
    data = _read_bytes(path, error, what, env_limit("RVMSIM_MAX_JSON_BYTES", MAX_JSON_BYTES))
    return parse_json(data, str(path), error, what=what)


def path_problem(text: str) -> str | None:
    """Why ``text`` (a path named in a file) cannot be a path on this system, one line, or
    None when it can: it holds a NUL byte, which no operating system takes."""
    if "\x00" in text:
        return "a path cannot hold a NUL byte"
    return None


def _checked_path_text(text: str) -> str:
    problem = path_problem(text)
    if problem is not None:
        raise ValueError(problem)
    return text


#: A path named in a file (pydantic): text the operating system can take (:func:`path_problem`).
FilePathText = Annotated[str, AfterValidator(_checked_path_text)]


class ReadModel(BaseModel):
    """Base of the schemas a file rvmsim wrote is checked against when it is read back:
    the keys and types its readers use, strictly (a number is not taken from text), other
    keys allowed (a file of an older or newer rvmsim reads as before)."""

    model_config = ConfigDict(strict=True, extra="allow", frozen=True)


#: What a value of the wrong type is said to be "not", by pydantic's error type.
_NOT_A = {"float_type": "not a number", "float_parsing": "not a number",
          "int_type": "not a whole number", "int_parsing": "not a whole number",
          "int_from_float": "not a whole number", "string_type": "not text",
          "bool_type": "not true or false", "bool_parsing": "not true or false",
          "list_type": "not a list", "tuple_type": "not a list", "dict_type": "not an object",
          "model_type": "not an object", "model_attributes_type": "not an object",
          "finite_number": "not a finite number", "missing": "missing",
          "too_short": "too few items", "too_long": "too many items",
          "none_required": "not null"}


def key_path_text(path: KeyPath) -> str:
    """A key path as a person reads it: ``ecs[2].failure_rate`` (``[3]`` alone for an item
    of a top-level list)."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def validate_document(model: type[BaseModel], doc: Any, source: str,
                      error: type[InputFileError] = InputFileError) -> Any:
    """``doc`` (a JSON document read back) checked against ``model``; returns ``doc`` as it
    is (its readers keep using the plain document; the model says what they may assume).

    Raises
    ------
    InputFileError
        ``error``, one line naming ``source`` and the key of the first problem
        (``robustness.json: ecs[2].failure_rate: not a number (got 'lots')``).
    """
    try:
        model.model_validate(doc)
    except ValidationError as err:
        first = err.errors(include_url=False)[0]
        # the error of a union names each member's type; the key is the value's own
        loc = tuple(p for p in first["loc"] if isinstance(p, int) or not (
            isinstance(p, str) and (p in _NOT_A_MEMBERS or "[" in p)))
        kind = first["type"]
        message = _NOT_A.get(kind) or first["msg"].removeprefix("Value error, ")
        if kind != "missing":
            got = repr(first.get("input"))
            message += f" (got {got if len(got) <= 40 else got[:30] + '…'})"
        if not loc:  # the document is not of the file's kind at all
            need = [f.alias or name for name, f in getattr(model, "model_fields", {}).items()
                    if f.is_required()]
            raise error(source, "", f"{message}; expected an object with "
                        f"{', '.join(need)}" if need else message) from None
        raise error(source, key_path_text(loc), message) from None
    return doc


#: Tags pydantic puts into the error location of a union's members (not keys).
_NOT_A_MEMBERS = frozenset({"float", "int", "str", "bool", "list", "dict", "none",
                            "list[float]", "list[str]", "list[int]", "tuple"})


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
