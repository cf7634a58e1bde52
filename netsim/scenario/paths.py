"""Dotted paths into raw scenario dictionaries: ``nodes.sensor.tasks[0].params.bits``.

The same syntax names a value in ``netsim run --set``, in sweep factors and in every validation message.
A path is a chain of mapping keys separated by dots, each optionally followed by list indices in brackets:
``networks.can.bitrate``, ``plant.x0[1]``, ``metrics[0].params.reference``. Keys are scenario names
(``[A-Za-z0-9_-]+``); indices are non-negative integers.

Examples
--------
>>> raw = {"nodes": {"sensor": {"tasks": [{"name": "sample", "period": "10 ms"}]}}}
>>> get_path(raw, "nodes.sensor.tasks[0].period")
'10 ms'
>>> set_path(raw, "nodes.sensor.tasks[0].period", "5 ms")
>>> raw["nodes"]["sensor"]["tasks"][0]["period"]
'5 ms'
>>> format_path(["nodes", "sensor", "tasks", 0, "period"])
'nodes.sensor.tasks[0].period'
"""

from __future__ import annotations

import copy
import difflib
import re
from typing import Any, Iterable, Sequence

from netsim.errors import ConfigError

__all__ = [
    "PathPart",
    "parse_path",
    "format_path",
    "get_path",
    "set_path",
    "parse_override",
    "parse_value",
    "plain_copy",
    "did_you_mean",
]

PathPart = str | int

_SHOWN = 60  # a name longer than this is cut in messages
_LISTED = 30  # at most this many known names are listed

_KEY = re.compile(r"[^.\[\]\s]+")
_INDEX = re.compile(r"\[\s*([^\]]*?)\s*\]")


def did_you_mean(word: str, candidates: Iterable[str], *, what: str = "") -> str:
    """A hint naming the closest candidate (``"; did you mean 'period'?"``) or listing the known ones.

    Parameters
    ----------
    word
        The unknown word.
    candidates
        The valid words.
    what
        Plural noun for the list form (``"keys"`` gives ``" (known keys: a, b)"``); empty gives ``""``
        when nothing is close.
    """
    names = sorted({str(c) for c in candidates})
    close = difflib.get_close_matches(str(word)[:_SHOWN], [n for n in names if len(n) <= _SHOWN], n=1, cutoff=0.6)
    if close:
        return f"; did you mean '{close[0]}'?"
    if what:
        shown = [n if len(n) <= _SHOWN else f"{n[:_SHOWN - 3]}... ({len(n)} characters)" for n in names[:_LISTED]]
        more = f" and {len(names) - _LISTED} more" if len(names) > _LISTED else ""
        return f" (known {what}: {', '.join(shown)}{more})" if names else f" (there are no {what}: define one first, or remove this reference)"
    return ""


def parse_path(path: str | Sequence[PathPart]) -> list[PathPart]:
    """Split ``"a.b[1].c"`` into ``["a", "b", 1, "c"]`` (a list of parts is returned unchanged).

    A bracket holding something other than an integer (``tasks[sample]``) is kept as a string part so that
    :func:`get_path` can suggest the index of the item with that ``name``.

    Raises
    ------
    ConfigError
        For an empty path or malformed brackets/dots.
    """
    if not isinstance(path, str):
        return list(path)
    text = path.strip()
    if not text:
        raise ConfigError("empty path; write e.g. 'networks.can.bitrate'")
    parts: list[PathPart] = []
    pos = 0
    expect_key = True
    while pos < len(text):
        if expect_key:
            m = _KEY.match(text, pos)
            if m is None:
                raise ConfigError(f"malformed path '{path}' at character {pos + 1}; write e.g. 'nodes.ctrl.tasks[0].period'")
            parts.append(m.group(0))
            pos = m.end()
            expect_key = False
            continue
        ch = text[pos]
        if ch == "[":
            m = _INDEX.match(text, pos)
            if m is None:
                raise ConfigError(f"malformed path '{path}': unclosed '['")
            inner = m.group(1)
            if re.fullmatch(r"\d+", inner):
                parts.append(int(inner))
            elif inner:
                parts.append(f"[{inner}]")
            else:
                raise ConfigError(f"malformed path '{path}': empty index '[]'")
            pos = m.end()
        elif ch == ".":
            pos += 1
            expect_key = True
            if pos >= len(text):
                raise ConfigError(f"malformed path '{path}': ends with '.'")
        else:
            raise ConfigError(f"malformed path '{path}' at character {pos + 1}")
    return parts


def format_path(parts: Sequence[PathPart]) -> str:
    """Join path parts into the dotted form (integers become ``[i]``)."""
    out = ""
    for part in parts:
        if isinstance(part, int):
            out += f"[{part}]"
        elif isinstance(part, str) and part.startswith("[") and part.endswith("]"):
            out += part
        else:
            out += f".{part}" if out else str(part)
    return out


def _index_hint(seq: list[Any], label: str, prefix: Sequence[PathPart]) -> str:
    """Suggest the integer index for ``[name]`` on a list of named items (tasks, handlers)."""
    name = label[1:-1].strip().strip("'\"")
    names = [item.get("name") for item in seq if isinstance(item, dict)]
    for i, item_name in enumerate(names):
        if item_name == name:
            return f"list items are addressed by index; did you mean '{format_path([*prefix, i])}' (the item named '{name}')?"
    known = [n for n in names if isinstance(n, str)]
    hint = did_you_mean(name, known, what="names") if known else ""
    return f"list items are addressed by index (0..{len(seq) - 1}), and no item is named '{name}'{hint}"


def _step(node: Any, part: PathPart, done: list[PathPart], path: str) -> Any:
    where = format_path(done) or "the top level"
    if isinstance(node, dict):
        if isinstance(part, int):
            raise ConfigError(f"'{where}' is a mapping, not a list; use a key instead of [{part}]", path)
        if part not in node:
            hint = did_you_mean(part, [k for k in node if isinstance(k, str)], what="keys")
            raise ConfigError(f"no key '{part}' in '{where}'{hint}", path)
        return node[part]
    if isinstance(node, list):
        if isinstance(part, str) and part.startswith("["):
            raise ConfigError(_index_hint(node, part, done), path)
        if not isinstance(part, int):
            raise ConfigError(f"'{where}' is a list; address its items by index, e.g. '{format_path([*done, 0])}'", path)
        if part >= len(node):
            raise ConfigError(f"index {part} out of range: '{where}' has {len(node)} item(s)", path)
        return node[part]
    raise ConfigError(f"'{where}' is a value ({node!r}), it has no '{format_path([part])}'", path)


def get_path(d: Any, path: str | Sequence[PathPart]) -> Any:
    """The value at ``path`` in nested dicts/lists ``d``.

    Raises
    ------
    ConfigError
        When a key does not exist (with the closest existing key), an index is out of range, or a list item
        is addressed by name (with the index to use instead).
    """
    parts = parse_path(path)
    text = path if isinstance(path, str) else format_path(parts)
    node = d
    done: list[PathPart] = []
    for part in parts:
        node = _step(node, part, done, text)
        done.append(part)
    return node


def set_path(d: Any, path: str | Sequence[PathPart], value: Any) -> None:
    """Set the value at ``path`` in nested dicts/lists ``d`` (in place).

    A missing last key is created (so a sweep can set a parameter that the file leaves at its default).
    A missing intermediate mapping key is created as an empty mapping, unless an existing key is close to it,
    which is taken as a typo and reported with a "did you mean". List items are never created.

    Raises
    ------
    ConfigError
        For a likely misspelt key, an index out of range, a name used as an index, or a path that goes
        through a plain value.
    """
    parts = parse_path(path)
    text = path if isinstance(path, str) else format_path(parts)
    node = d
    done: list[PathPart] = []
    for i, part in enumerate(parts):
        if i == len(parts) - 1:
            if isinstance(node, dict) and isinstance(part, str) and not part.startswith("["):
                node[part] = value
            else:
                _step(node, part, done, text)  # raises unless this is a valid list index
                node[part] = value
            return
        if isinstance(node, dict) and isinstance(part, str) and not part.startswith("[") and part not in node:
            where = format_path(done) or "the top level"
            hint = did_you_mean(part, [k for k in node if isinstance(k, str)])
            if hint:
                raise ConfigError(f"no key '{part}' in '{where}'{hint}", text)
            if isinstance(parts[i + 1], int):
                raise ConfigError(f"'{format_path([*done, part])}' does not exist, so it has no item [{parts[i + 1]}]; "
                                  "fix the path", text)
            node[part] = {}
        node = _step(node, part, done, text)
        done.append(part)


def parse_value(text: str) -> Any:
    """Read an override value as a YAML scalar or flow collection (as a scenario file reads it).

    ``"1 Mbit/s"`` stays a string, ``"0.5"`` and ``"1e-5"`` become floats, ``"[1, 0]"`` a list, ``"{a: 1}"`` a
    mapping, ``"null"`` None, ``"true"`` True.

    Raises
    ------
    ConfigError
        When the text is not valid YAML flow syntax (or is refused as a scenario file would be: a tag, ...).
    """
    from netsim.scenario.safe_yaml import YamlRefused, load_text

    try:
        return load_text(text)
    except YamlRefused as exc:
        problem = exc.message.removeprefix("YAML syntax error: ")
        raise ConfigError(f"cannot read {text[:80]!r} as a YAML value: {problem}") from None


def plain_copy(data: Any) -> Any:
    """A deep copy of ``data`` made of plain dicts, lists and scalars (tuples become lists).

    Scenario data given from Python (a mapping, override values) is copied so, never shared: validation and
    overrides then work on data that nobody else holds. A numpy array becomes its ``tolist()`` (a number, a list
    or a list of rows) and a numpy scalar the Python value it holds (python-control systems:
    :func:`netsim.scenario.python_values.plain_values`).
    """
    if isinstance(data, dict):
        return {_scalar(k): plain_copy(v) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [plain_copy(v) for v in data]
    return _scalar(data)


def _readable(value: int) -> int:
    """``value``, or the YAML reader's placeholder when it has more digits than Python turns into text.

    A 5000-digit integer from Python then gets the same message, at its path, as one read from a file; as it is,
    a message that shows it would raise ``ValueError`` (issue 14 B).
    """
    if value.bit_length() < 14_000:  # fewer than 4215 digits: always readable
        return value
    from netsim.scenario.safe_yaml import long_integer_placeholder

    placeholder = long_integer_placeholder(value < 0)
    return placeholder if abs(value) > abs(placeholder) else value


def _scalar(value: Any) -> Any:
    """``value`` as the plain type it is a subclass of (a ``numpy.float64`` becomes a ``float``), a numpy value as
    the Python data its ``tolist()`` gives."""
    kind = type(value)
    if value is None or kind in (str, float, bool):
        return value
    if kind is int:
        return _readable(value)
    if kind.__module__ == "numpy" and hasattr(value, "tolist"):  # ndarray (any shape), np.float32, np.bool_ ...
        return plain_copy(value.tolist())
    for plain in (bool, int, float, str):
        if isinstance(value, plain):
            return plain(value)
    return copy.deepcopy(value)  # a date, or something the schema will refuse: still not shared


def parse_override(item: str) -> tuple[str, Any]:
    """Split a ``key.path=value`` override (as given to ``netsim run --set``) into path and YAML value.

    Raises
    ------
    ConfigError
        When there is no ``=`` or the path is malformed.
    """
    key, sep, text = item.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ConfigError(f"cannot read override {item!r}; write key.path=value, e.g. networks.can.bitrate='1 Mbit/s'")
    parse_path(key)
    return key, parse_value(text) if text.strip() else None
