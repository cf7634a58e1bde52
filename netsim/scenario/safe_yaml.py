"""Read YAML (scenario, sweep and run-folder files, ``--set`` values) as untrusted data, with one library.

Every YAML text netsim reads goes through :func:`load_text` (files through :func:`load_file`): PyYAML's safe
loader, with libyaml's C parser when it is installed (``yaml.CSafeLoader``'s parser, about 15x faster than a
pure-Python parser on a scenario), the pure-Python one otherwise. Scalars are read as YAML 1.2's core schema says
(``1e-5`` is a number, ``yes``/``no``/``on``/``off`` and ``1:30`` are text, ``010`` is ten, ``0o10`` eight), and
nothing but plain values, lists and mappings is ever built. Positions are not kept while loading: when there is
a problem to report, :func:`line_table` parses the text again, keeping the line of every key and list item.

Before anything is built, the limits of :mod:`netsim.scenario.yaml_limits` apply (regular files only, size,
over-long numbers, nesting depth, tags, alias expansion; its names are available here too). While building, a mapping that holds
a key twice is refused with the lines of both (a merge key ``<<: *a`` brings keys in without that check: keys
written in the mapping override them, and among ``<<: [*a, *b]`` the first mapping wins).
"""

from __future__ import annotations

import os
import re
import sys
from typing import Any

import yaml
from yaml.constructor import ConstructorError, SafeConstructor
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode
from yaml.resolver import BaseResolver

from netsim.scenario.yaml_limits import (
    MAX_CHARS,
    MAX_DEPTH,
    MAX_FILE_BYTES,
    MAX_VALUES,
    YamlRefused,
    check_events,
    check_flow_depth,
    check_long_numbers,
    needs_event_check,
    read_text,
)

__all__ = ["MAX_FILE_BYTES", "MAX_DEPTH", "MAX_VALUES", "MAX_CHARS", "YamlRefused", "ScenarioLoader", "read_text",
           "load_text", "load_file", "line_table", "dump_text", "long_integer_placeholder", "check_flow_depth",
           "needs_event_check", "check_events"]

_CORE = "tag:yaml.org,2002:"


def _short(text: str, limit: int = 30) -> str:
    return text if len(text) <= limit else text[:limit] + "..."


# --------------------------------------------------------------------------------------------- the loader
_BOOL_1_2 = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_NULL_1_2 = re.compile(r"^(?:~|null|Null|NULL|)$")
# '_*[0-9]' rather than '[0-9_]*[0-9]': the same texts, without backtracking quadratic in a long digit run
_INT_1_2 = re.compile(r"^[-+]?(?:0b[01_]+|0o?[0-7_]+|_*[0-9][0-9_]*|0x[0-9a-fA-F_]+)$")
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


# (types-PyYAML expects the constructor of a Loader class; this constructor is the loader's mixin)
_SafeConstructor.add_constructor(_CORE + "int", _SafeConstructor.construct_yaml_int)  # type: ignore[type-var]


def long_integer_placeholder(negative: bool) -> int:
    """What the loader reads for an integer with more digits than Python converts from text (4300 by default).

    ``-/+ 10 ** (limit - 1)``: the written sign, and the most digits Python turns back into text, far beyond
    :data:`netsim.units.NUMBER_LIMIT`, so :func:`netsim.scenario.limits.limit_problems` refuses it at its YAML
    path and line ("an integer of over 4000 digits ...; write a smaller value"). The same value as
    :func:`netsim.scenario.limits.long_integer_placeholder` (defined here too: this module imports no checker).
    """
    limit = sys.get_int_max_str_digits()
    return (-1 if negative else 1) * 10 ** ((limit if limit > 0 else 4300) - 1)

try:  # libyaml's parser when PyYAML was built with it
    from yaml._yaml import CParser as _Parser  # what yaml.cyaml re-exports

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
        check_long_numbers(text)
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
