"""Read YAML (scenario, sweep and run-folder files, ``--set`` values) as untrusted data, with one library.

Every YAML text netsim reads goes through :func:`load_text` (files through :func:`load_file`): PyYAML's safe
loader, with libyaml's C parser when it is installed (``yaml.CSafeLoader``, about 15x faster than a pure-Python
parser on a scenario), the plain ``SafeLoader`` otherwise. Scalars are read as YAML 1.2's core schema says
(``1e-5`` is a number, ``yes``/``no``/``on``/``off`` and ``1:30`` are text, ``010`` is ten, ``0o10`` eight), and
nothing but plain values, lists and mappings is ever built. Positions are not kept while loading: when there is
a problem to report, :func:`line_table` parses the text again, keeping the line of every key and list item.

A scenario may come from anyone (issue 14), so before anything is built, :func:`read_text` and
:func:`check_events` refuse, each with a one-line message that says what to change and never echoes the file:

* anything but a regular file (a directory, a FIFO, ``/dev/zero``, a socket), and files over
  :data:`MAX_FILE_BYTES`; the file is opened without blocking and checked on the open descriptor;
* NUL bytes and text that is not UTF-8 (with the line of the first bad byte);
* nesting deeper than :data:`MAX_DEPTH` (the composer recurses);
* tags other than YAML's plain core types (``!!python/object``, ``!!binary``, ``!custom``, ...), and a
  ``!!int`` / ``!!float`` tag on a value that is not such a number;
* an alias inside its own anchor (a recursive merge key ``&a {<<: *a}``);
* aliases that expand to more than :data:`MAX_VALUES` values or :data:`MAX_CHARS` characters of text
  ("billion laughs": nine lines that expand to 10^9 values, or one 1 MB string aliased 1000 times).

While building, a mapping that holds a key twice is refused with the lines of both (a merge key ``<<: *a``
brings keys in without that check: keys written in the mapping override them).

The limit checks walk the parser's event stream once (no tree is built): the expanded size of every anchor is
counted as its events go by, so an alias costs one addition, never an expansion.
"""

from __future__ import annotations

import os
import re
import stat
from dataclasses import dataclass
from typing import Any, Iterable

import yaml
from yaml.constructor import ConstructorError, SafeConstructor
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode
from yaml.resolver import BaseResolver

__all__ = ["MAX_FILE_BYTES", "MAX_DEPTH", "MAX_VALUES", "MAX_CHARS", "YamlRefused", "ScenarioLoader", "read_text",
           "load_text", "load_file", "line_table", "dump_text", "check_flow_depth", "needs_event_check", "check_events"]

#: Largest scenario file read (bytes). The shipped scenarios are under 20 kB.
MAX_FILE_BYTES = 2 * 1024 * 1024
#: Deepest nesting of mappings and lists (the shipped scenarios nest at most 8 deep).
MAX_DEPTH = 64
#: Most values (scalars, mappings, lists) a document may hold once its aliases are expanded.
MAX_VALUES = 200_000
#: Most characters of scalar text a document may hold once its aliases are expanded.
MAX_CHARS = 8 * 1024 * 1024

_CORE = "tag:yaml.org,2002:"
_ALLOWED_TAGS = {None, "!", *(_CORE + t for t in ("str", "int", "float", "bool", "null", "seq", "map"))}
_INT = re.compile(r"^[-+]?(0|[1-9][0-9_]*|0o[0-7_]+|0x[0-9a-fA-F_]+|0b[01_]+|0[0-7_]+)$")
_FLOAT = re.compile(r"^[-+]?(\.[0-9]+|[0-9][0-9_]*(\.[0-9_]*)?)([eE][-+]?[0-9]+)?$|^[-+]?\.(inf|Inf|INF)$|^\.(nan|NaN|NAN)$")


class YamlRefused(Exception):
    """A text refused before or while parsing: ``message`` (one line) and the 1-based ``line`` (or None).

    ``syntax`` is True when the text is not valid YAML (rather than valid YAML that is refused).
    """

    def __init__(self, message: str, line: int | None = None, *, syntax: bool = False) -> None:
        super().__init__(message)
        self.message = message
        self.line = line
        self.syntax = syntax


def _kind(mode: int) -> str | None:
    """What a non-regular file is, in words (None for a regular file)."""
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def read_text(name: str) -> str:
    """The UTF-8 text of the regular file ``name`` (at most :data:`MAX_FILE_BYTES`).

    Raises
    ------
    FileNotFoundError
        When ``name`` does not exist.
    YamlRefused
        For anything but a regular UTF-8 text file of acceptable size, and for NUL bytes.
    """
    try:
        fd = os.open(name, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise
    except IsADirectoryError:
        raise YamlRefused("this is a directory, not a scenario file; pass the path of a .yaml file") from None
    except OSError as exc:
        raise YamlRefused(f"cannot open the file ({exc.strerror}); check its path and permissions") from None
    try:
        kind = _kind(os.fstat(fd).st_mode)
        if kind is not None:
            raise YamlRefused(f"this is {kind}, not a scenario file; pass the path of a .yaml file")
        with os.fdopen(os.dup(fd), "rb") as fh:
            data = fh.read(MAX_FILE_BYTES + 1)
    finally:
        os.close(fd)
    if len(data) > MAX_FILE_BYTES:
        raise YamlRefused(f"the file is larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB; a scenario file is a "
                          "few kB of YAML (put large data, e.g. measured execution times, in fewer values)")
    nul = data.find(b"\x00")
    if nul >= 0:
        raise YamlRefused("the file contains a NUL byte (is it a binary file?); a scenario is UTF-8 text",
                          data.count(b"\n", 0, nul) + 1)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise YamlRefused(f"the file is not UTF-8 text (byte 0x{data[exc.start]:02x} cannot be decoded); "
                          "save it as UTF-8", data.count(b"\n", 0, exc.start) + 1) from None


_BRACKETS = re.compile(r"[\[\]{}]")


def check_flow_depth(text: str) -> None:
    """Refuse text whose ``[``/``{`` brackets open more than :data:`MAX_DEPTH` levels.

    A pure-Python scanner takes time quadratic in the depth of nested flow collections (2 s for 1000 levels)
    before it yields the first event, and the composer recurses, so this cheap count runs first. Brackets inside quoted text count too: a real
    scenario never comes near the limit.

    Raises
    ------
    YamlRefused
        With the line of the bracket that went past the limit.
    """
    depth = 0
    for m in _BRACKETS.finditer(text):
        if m.group() in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                raise YamlRefused(f"the data nests more than {MAX_DEPTH} levels deep (counting '[' and '{{'); a "
                                  "scenario nests a few levels (flatten the structure)",
                                  text.count("\n", 0, m.start()) + 1)
        elif depth:
            depth -= 1


_INDENT = re.compile(r"^[ ]+", re.MULTILINE)


def needs_event_check(text: str) -> bool:
    """False when :func:`check_events` cannot find anything in ``text`` (then the second parse is skipped).

    Without ``&`` there is no anchor, so no alias expands; without ``!`` there is no tag; and when no line is
    indented more than :data:`MAX_DEPTH` spaces, block nesting is at most ``2 * (MAX_DEPTH + 1)`` levels (a
    nested block is indented deeper, except a list directly under its key), far below what the composer
    can recurse, with flow nesting bounded by :func:`check_flow_depth`. Most scenario files take this path.
    """
    if "&" in text or "!" in text:
        return True
    return max((len(m.group()) for m in _INDENT.finditer(text)), default=0) > MAX_DEPTH


@dataclass
class _Open:
    """A mapping or list whose events are still coming: its anchor and expanded size so far."""

    anchor: str | None
    values: int = 1
    chars: int = 0


def _line(event: Any) -> int | None:
    mark = getattr(event, "start_mark", None)
    return None if mark is None else mark.line + 1


def _short(text: str, limit: int = 30) -> str:
    return text if len(text) <= limit else text[:limit] + "..."


def _check_tag(event: Any) -> None:
    tag = getattr(event, "tag", None)
    if tag in _ALLOWED_TAGS:
        if tag == _CORE + "int" and not _INT.match(event.value):
            raise YamlRefused(f"'{_short(event.value)}' is not an integer but is tagged !!int; remove the tag or "
                              "write an integer", _line(event))
        if tag == _CORE + "float" and not _FLOAT.match(event.value) and not _INT.match(event.value):
            raise YamlRefused(f"'{_short(event.value)}' is not a number but is tagged !!float; remove the tag or "
                              "write a number", _line(event))
        return
    shown = "!!" + tag[len(_CORE):] if tag.startswith(_CORE) else tag
    raise YamlRefused(f"the tag '{_short(shown, 60)}' is not allowed in a scenario (only plain values, lists and "
                      "mappings are); remove the tag", _line(event))


def check_events(events: Iterable[Any]) -> None:
    """Refuse a YAML event stream that nests too deep, uses a forbidden tag or expands aliases too far.

    Parameters
    ----------
    events
        PyYAML parse events (``yaml.parse(text, Loader=ScenarioLoader)``); consumed until the first problem.

    Raises
    ------
    YamlRefused
        With the line of the offending event. YAML syntax errors are left to the caller (the parser raises
        them while the events are produced).
    """
    anchors: dict[str, tuple[int, int]] = {}
    stack: list[_Open] = [_Open(None, 0, 0)]  # the document level
    total_values = total_chars = 0  # the expanded size of everything seen so far (the sum over the stack)
    for event in events:
        name = type(event).__name__
        if name in ("MappingStartEvent", "SequenceStartEvent"):
            _check_tag(event)
            stack.append(_Open(event.anchor))
            total_values += 1
            if len(stack) - 1 > MAX_DEPTH:
                raise YamlRefused(f"the data nests more than {MAX_DEPTH} levels deep; a scenario nests a few "
                                  "levels (flatten the structure)", _line(event))
            continue
        if name in ("MappingEndEvent", "SequenceEndEvent"):
            done = stack.pop()
            if done.anchor is not None:
                anchors[done.anchor] = (done.values, done.chars)
            stack[-1].values += done.values
            stack[-1].chars += done.chars
            continue
        if name == "ScalarEvent":
            _check_tag(event)
            values, chars = 1, len(event.value)
            if event.anchor is not None:
                anchors[event.anchor] = (values, chars)
        elif name == "AliasEvent":
            if any(o.anchor == event.anchor for o in stack):
                raise YamlRefused(f"the alias '*{_short(event.anchor)}' is used inside its own anchor "
                                  f"'&{_short(event.anchor)}' (a recursive reference); refer to a finished "
                                  "anchor", _line(event))
            values, chars = anchors.get(event.anchor, (1, 0))  # an undefined alias: the parser reports it
        else:
            continue
        stack[-1].values += values
        stack[-1].chars += chars
        total_values += values
        total_chars += chars
        if total_values > MAX_VALUES or total_chars > MAX_CHARS:
            what = (f"{MAX_VALUES} values" if total_values > MAX_VALUES
                    else f"{MAX_CHARS // (1024 * 1024)} MiB of text")
            raise YamlRefused(f"the document holds more than {what} once its aliases are expanded (an alias "
                              "bomb?); use fewer aliases or fewer values", _line(event))


# --------------------------------------------------------------------------------------------- the loader
_BOOL_1_2 = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_NULL_1_2 = re.compile(r"^(?:~|null|Null|NULL|)$")
_INT_1_2 = re.compile(r"^[-+]?(?:0b[01_]+|0o?[0-7_]+|[0-9_]*[0-9][0-9_]*|0x[0-9a-fA-F_]+)$")
_FLOAT_1_2 = re.compile(r"""^(?:[-+]?[0-9][0-9_]*\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                              |[-+]?[0-9][0-9_]*[eE][-+]?[0-9]+
                              |[-+]?\.[0-9_]+(?:[eE][-+][0-9]+)?
                              |[-+]?\.(?:inf|Inf|INF)
                              |\.(?:nan|NaN|NAN))$""", re.X)
_DIGITS = "0123456789"


class _CoreResolver(BaseResolver):
    """Plain scalars as YAML 1.2's core schema reads them (as the scenario files were always read).

    ``true``/``false`` (three spellings each), ``null``/``~``/empty, decimal, ``0o`` octal, ``0x`` hex and ``0b``
    binary integers (``_`` allowed between digits), decimal floats with an optional exponent (``1e-5``),
    ``.inf`` and ``.nan``; dates (``2001-12-14``) and the merge key ``<<`` as YAML 1.1 reads them. Everything
    else is text: ``yes``, ``on``, ``1:30``, ``nan``.
    """


_CoreResolver.add_implicit_resolver(_CORE + "bool", _BOOL_1_2, list("tTfF"))
_CoreResolver.add_implicit_resolver(_CORE + "null", _NULL_1_2, ["~", "n", "N", ""])
_CoreResolver.add_implicit_resolver(_CORE + "int", _INT_1_2, list("-+_" + _DIGITS))
_CoreResolver.add_implicit_resolver(_CORE + "float", _FLOAT_1_2, list("-+." + _DIGITS))
for _first, _resolvers in yaml.resolver.Resolver.yaml_implicit_resolvers.items():  # dates and '<<': as PyYAML
    for _tag, _regexp in _resolvers:
        if _tag in (_CORE + "timestamp", _CORE + "merge"):
            _CoreResolver.add_implicit_resolver(_tag, _regexp, [_first])


def _short_key(key: Any) -> str:
    return _short(str(key), 40)


class _SafeConstructor(SafeConstructor):
    """PyYAML's safe constructor with YAML 1.2 integers and duplicate keys refused."""

    def construct_yaml_int(self, node: ScalarNode) -> int:
        text = str(self.construct_scalar(node)).replace("_", "")
        sign = -1 if text[:1] == "-" else 1
        text = text.lstrip("+-")
        base = {"0b": 2, "0o": 8, "0x": 16}.get(text[:2], 10)
        digits = text[2:] if base != 10 else text
        try:
            return sign * int(digits, base)
        except ValueError:
            if not (base == 10 and digits.isdigit()):
                raise
            # more digits than Python reads from text (4300): a placeholder far beyond the number limit, which
            # the scenario's limit checks refuse at its path and line
            from netsim.scenario.limits import long_integer_placeholder

            return long_integer_placeholder(sign < 0)

    def construct_mapping(self, node: MappingNode, deep: bool = False) -> dict[Any, Any]:
        """The mapping of ``node``: its own keys in written order, then the keys its merge keys bring in.

        Keys written in the mapping win over merged ones, and among ``<<: [*a, *b]`` the first mapping wins.
        """
        if not isinstance(node, MappingNode):
            raise ConstructorError(None, None, f"expected a mapping node, but found {node.id}", node.start_mark)
        return {key: self.construct_object(value, deep=deep) for key, value in self._pairs(node)}

    def _pairs(self, node: MappingNode) -> list[tuple[Any, Node]]:
        """``(key, value node)`` of a mapping with its merge keys resolved (nothing is changed in the tree)."""
        cache: dict[Node, list[tuple[Any, Node]]] = self.__dict__.setdefault("_merged", {})
        if node in cache:
            return cache[node]
        own: list[tuple[Any, Node]] = []
        merged: list[list[tuple[Any, Node]]] = []
        lines: dict[Any, int] = {}
        for key_node, value_node in node.value:
            line = key_node.start_mark.line + 1
            if key_node.tag == _CORE + "merge":
                key: Any = "<<"
                subs = value_node.value if isinstance(value_node, SequenceNode) else [value_node]
                for sub in subs:
                    if not isinstance(sub, MappingNode):
                        raise ConstructorError("while constructing a mapping", node.start_mark,
                                               f"expected a mapping or list of mappings for merging, but found "
                                               f"{sub.id}", sub.start_mark)
                    merged.append(self._pairs(sub))
            else:
                key = self.construct_object(key_node, deep=True)
                try:
                    hash(key)
                except TypeError:
                    raise ConstructorError("while constructing a mapping", node.start_mark, "found unhashable key",
                                           key_node.start_mark) from None
                own.append((key, value_node))
            if key in lines:
                raise YamlRefused(f"duplicate key '{_short_key(key)}' (first on line {lines[key]}); a mapping holds "
                                  "each key once: remove or rename one", line)
            lines[key] = line
        seen = {key for key, _ in own}
        for pairs in merged:
            for key, value_node in pairs:
                if key not in seen:
                    seen.add(key)
                    own.append((key, value_node))
        cache[node] = own
        return own


_SafeConstructor.add_constructor(_CORE + "int", _SafeConstructor.construct_yaml_int)

try:  # libyaml's parser when PyYAML was built with it
    from yaml.cyaml import CParser as _Parser

    def _parser_init(self: Any, stream: str) -> None:
        _Parser.__init__(self, stream)

    _PARSERS: tuple[type, ...] = (_Parser,)
except ImportError:  # pragma: no cover - PyYAML without libyaml
    from yaml.composer import Composer
    from yaml.parser import Parser
    from yaml.reader import Reader
    from yaml.scanner import Scanner

    def _parser_init(self: Any, stream: str) -> None:
        Reader.__init__(self, stream)
        Scanner.__init__(self)
        Parser.__init__(self)
        Composer.__init__(self)

    _PARSERS = (Reader, Scanner, Parser, Composer)


class ScenarioLoader(*_PARSERS, _SafeConstructor, _CoreResolver):  # type: ignore[misc]
    """The one YAML loader of netsim: libyaml's C parser if available, safe constructor, YAML 1.2 scalars."""

    def __init__(self, stream: str) -> None:
        _parser_init(self, stream)
        _SafeConstructor.__init__(self)
        _CoreResolver.__init__(self)


def _syntax_refusal(exc: yaml.YAMLError, text: str) -> YamlRefused:
    """A one-line refusal for a YAML syntax error in ``text``, with its line."""
    if isinstance(exc, yaml.MarkedYAMLError):
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        what = exc.problem or "syntax error"
        context = f" ({exc.context})" if exc.context else ""
        rows = text.splitlines() if mark is not None else []
        row = rows[mark.line] if mark is not None and mark.line < len(rows) else ""
        column = mark.column if mark is not None else 0
        if "\t" in what or "\t" in row[: len(row) - len(row.lstrip())] or row[column: column + 1] == "\t":
            what, context = "a tab character where YAML expects indentation", "; indent with spaces, not tabs"
        elif exc.context and exc.context.startswith("found duplicate anchor") and exc.context_mark is not None:
            what, context = (f"an anchor is defined twice (first on line {exc.context_mark.line + 1})",
                             "; give each anchor its own name")
        return YamlRefused(f"YAML syntax error: {what}{context}", line, syntax=True)
    first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    return YamlRefused(f"YAML error: {first[:200]}", None, syntax=True)


def load_text(text: str) -> Any:
    """Plain data (dicts, lists, str, int, float, bool, None, dates) from YAML ``text``, within the limits.

    Raises
    ------
    YamlRefused
        For text beyond a limit (see the module docstring), a forbidden tag, a duplicate key, a YAML syntax
        error (``syntax=True``) or a value that cannot be built; always one line, with the line when known.
    """
    try:
        check_flow_depth(text)
        if needs_event_check(text):
            check_events(yaml.parse(text, Loader=ScenarioLoader))  # depth, tags, aliases: before anything is built
        return yaml.load(text, Loader=ScenarioLoader)
    except YamlRefused:
        raise
    except ConstructorError as exc:  # e.g. an unhashable key ({[a, b]: 1})
        mark = exc.problem_mark or exc.context_mark
        raise YamlRefused(f"YAML value cannot be read: {exc.problem}; write plain values, lists and mappings",
                          mark.line + 1 if mark is not None else None) from None
    except yaml.YAMLError as exc:
        raise _syntax_refusal(exc, text) from None
    except (ValueError, TypeError, AttributeError, IndexError, OverflowError, RecursionError) as exc:
        raise YamlRefused(f"YAML value cannot be read ({type(exc).__name__}: {str(exc)[:120]}); remove any '!!' tag "
                          "and write plain values") from None


def load_file(name: str | os.PathLike[str]) -> tuple[Any, str]:
    """The data of the YAML file ``name`` and its text (kept for :func:`line_table` when a problem needs a line).

    Raises
    ------
    FileNotFoundError
        When ``name`` does not exist.
    YamlRefused
        As :func:`read_text` and :func:`load_text` do.
    """
    text = read_text(os.fspath(name))
    return load_text(text), text


def line_table(text: str) -> dict[tuple[Any, ...], int]:
    """The 1-based line of every key and list item of the YAML ``text`` (valid: :func:`load_text` read it).

    Keys are path parts: ``("nodes", "cpu", "tasks", 0)`` is the first task of node ``cpu``. A mapping key gives
    its own line, a list item the line where its value starts; keys a merge key ``<<`` brings in are left out
    (their path's nearest ancestor then gives the line). The text is parsed again, this time keeping positions:
    call this only when there is a problem to place.
    """
    loader = ScenarioLoader(text)
    try:
        root = loader.get_single_node()
        lines: dict[tuple[Any, ...], int] = {}
        if root is not None:
            _walk(loader, root, (), lines, [0])
        return lines
    finally:
        loader.dispose()


def _walk(loader: ScenarioLoader, node: Node, parts: tuple[Any, ...], lines: dict[tuple[Any, ...], int],
          count: list[int]) -> None:
    count[0] += 1
    if count[0] > MAX_VALUES:  # aliases were counted by check_events; this only bounds the walk once more
        return
    if isinstance(node, MappingNode):
        for key_node, value_node in node.value:
            if key_node.tag == _CORE + "merge":
                continue
            key = loader.construct_object(key_node, deep=True)
            try:
                hash(key)
            except TypeError:
                continue
            lines.setdefault((*parts, key), key_node.start_mark.line + 1)
            _walk(loader, value_node, (*parts, key), lines, count)
    elif isinstance(node, SequenceNode):
        for i, item in enumerate(node.value):
            lines.setdefault((*parts, i), item.start_mark.line + 1)
            _walk(loader, item, (*parts, i), lines, count)


# --------------------------------------------------------------------------------------------- writing
class _Dumper(getattr(yaml, "CSafeDumper", yaml.SafeDumper)):  # type: ignore[misc]
    """PyYAML's safe dumper (libyaml's emitter when available) that quotes every text YAML 1.1 *or* 1.2 would
    read as something else (``'1e-5'``, ``'0o10'`` as well as ``'yes'``), so :func:`load_text` reads back
    exactly what was written."""


for _tag, _regexp, _firsts in ((_CORE + "float", _FLOAT_1_2, "-+." + _DIGITS), (_CORE + "int", _INT_1_2, "-+_" + _DIGITS)):
    _Dumper.add_implicit_resolver(_tag, _regexp, list(_firsts))


def dump_text(data: Any, width: int = 80) -> str:
    """``data`` (plain dicts, lists and scalars) as block-style YAML text, keys in their order, unicode kept;
    lines longer than ``width`` are folded where YAML allows."""
    return yaml.dump(data, Dumper=_Dumper, sort_keys=False, allow_unicode=True, default_flow_style=False,
                     width=width)
