"""The limits of reading untrusted YAML: what is refused before anything is built (issue 14).

A scenario may come from anyone, so before the YAML loader (:mod:`netsim.scenario.safe_yaml`) builds anything,
:func:`read_text` and :func:`check_events` refuse, each with a one-line message that says what to change and
never echoes the file:

* anything but a regular file (a directory, a FIFO, ``/dev/zero``, a socket), and files over
  :data:`MAX_FILE_BYTES`; the file is opened without blocking and checked on the open descriptor;
* NUL bytes and text that is not UTF-8 (with the line of the first bad byte);
* nesting deeper than :data:`MAX_DEPTH` (the composer recurses);
* tags other than YAML's plain core types (``!!python/object``, ``!!binary``, ``!custom``, ...), and a
  ``!!int`` / ``!!float`` tag on a value that is not such a number;
* an alias inside its own anchor (a recursive merge key ``&a {<<: *a}``);
* aliases that expand to more than :data:`MAX_VALUES` values or :data:`MAX_CHARS` characters of text
  ("billion laughs": nine lines that expand to 10^9 values, or one 1 MB string aliased 1000 times);
* a run of more than :data:`MAX_DIGITS` digits (:func:`check_long_numbers`, one linear pass over the text before
  the parser sees it): no usable number has that many, and converting or matching such a scalar cost time
  quadratic in its length (a 20000-digit number took 6 s to load, tens of thousands over 30 s).

The checks walk the parser's event stream once (no tree is built): the expanded size of every anchor is counted
as its events go by, so an alias costs one addition, never an expansion.
"""

from __future__ import annotations

import os
import re
import stat
from dataclasses import dataclass
from typing import Any, Iterable

__all__ = ["MAX_FILE_BYTES", "MAX_DEPTH", "MAX_VALUES", "MAX_CHARS", "MAX_DIGITS", "YamlRefused", "read_text",
           "check_flow_depth", "check_long_numbers", "needs_event_check", "check_events"]

#: Largest scenario file read (bytes). The shipped scenarios are under 20 kB.
MAX_FILE_BYTES = 2 * 1024 * 1024
#: Deepest nesting of mappings and lists (the shipped scenarios nest at most 8 deep).
MAX_DEPTH = 64
#: Most values (scalars, mappings, lists) a document may hold once its aliases are expanded.
MAX_VALUES = 200_000
#: Most characters of scalar text a document may hold once its aliases are expanded.
MAX_CHARS = 8 * 1024 * 1024
#: Most digits (``_`` separators counted) written in a row. Numbers are at most 1e15 in size (``NUMBER_LIMIT``),
#: so a real one has a few dozen digits; Python itself reads integers of at most 4300 digits from text (longer
#: ones reach the number-limit check through ``safe_yaml.long_integer_placeholder``).
MAX_DIGITS = 10_000

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


_NOT_DIGITS = re.compile(r"[^0-9_]+")
_DIGIT_RUN = re.compile(r"[0-9_]+")


def check_long_numbers(text: str) -> None:
    """Refuse text with more than :data:`MAX_DIGITS` digits in a row, in time linear in its length.

    Runs before the YAML parser (whose scalar resolution and number conversion are slower than linear on such a
    scalar), on the raw text, so it also refuses such a run inside quoted text.

    Raises
    ------
    YamlRefused
        With the line where the run starts.
    """
    if len(text) <= MAX_DIGITS or max(map(len, _NOT_DIGITS.split(text)), default=0) <= MAX_DIGITS:
        return
    for m in _DIGIT_RUN.finditer(text):  # only on the error path: find where the run is
        if m.end() - m.start() > MAX_DIGITS:
            raise YamlRefused(f"a number written with {m.end() - m.start()} digits (at most {MAX_DIGITS} are read; "
                              "netsim's numbers are at most 1e15 in size): write a smaller value",
                              text.count("\n", 0, m.start()) + 1)


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
    if tag is None or tag in _ALLOWED_TAGS:
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
