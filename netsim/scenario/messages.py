"""Turn pydantic validation errors into :class:`~netsim.scenario.problems.Problem` records a user can act on.

Each error keeps its YAML path (internal union tags dropped) and gets a short message in the user's terms:
``unknown key 'perod'; did you mean 'period'?``, ``expected an integer, got 'abc'``, ``missing required
key 'duration'``. Messages from our own validators (units, ranges) pass through unchanged.
"""

from __future__ import annotations

import re
import types
import typing
from typing import Any, Sequence

from pydantic import BaseModel, ValidationError

from netsim.scenario.paths import PathPart, did_you_mean, format_path
from netsim.scenario.problems import Problem, shorten
from netsim.scenario.schema import EXEC_DISTS, IO_TYPES, TAG_MARK
from netsim.scenario.schema_task import TIME_DISTS

__all__ = ["problems_from_validation_error", "show_value", "shorten", "shorten_problem", "path_at_line"]


def shorten_problem(problem: Problem) -> Problem:
    """``problem`` with its path and message shortened (:func:`shorten`); the same object when nothing is cut.

    Every :class:`Problem` is shortened when it is made, so this returns ``problem`` itself; kept for callers.
    """
    path, message = shorten(problem.path), shorten(problem.message)
    if path is problem.path and message is problem.message:
        return problem
    from dataclasses import replace

    return replace(problem, path=path, message=message)


_UNIONS = (typing.Union, types.UnionType)

_TYPE_WORDS = {
    "int": "an integer",
    "float": "a number",
    "bool": "true or false",
    "string": "a text string",
    "str": "a text string",
    "list": "a list",
    "tuple": "a list",
    "dict": "a mapping (key: value)",
    "model": "a mapping (key: value)",
    "model_attributes": "a mapping (key: value)",
    "set": "a list",
}


def show_value(value: Any, limit: int = 60) -> str:
    """A short rendering of a user value for a message (``'abc'``, ``3``, ``a mapping``)."""
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**60:
        return "an integer of over 60 digits"  # repr of a huge integer is slow, and refused beyond 4300 digits
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _unwrap(tp: Any) -> Any:
    while typing.get_origin(tp) is typing.Annotated:
        tp = typing.get_args(tp)[0]
    return tp


def _tag_of(tp: Any) -> str | None:
    if typing.get_origin(tp) is typing.Annotated:
        for meta in typing.get_args(tp)[1:]:
            tag = getattr(meta, "tag", None)
            if isinstance(tag, str):
                return tag
    return None


def _members(tp: Any) -> list[Any]:
    """The members of a (nested, possibly Annotated) union, each with its own annotations kept."""
    inner = _unwrap(tp)
    if typing.get_origin(inner) in _UNIONS:
        out: list[Any] = []
        for member in typing.get_args(inner):
            out += _members(member) if typing.get_origin(_unwrap(member)) in _UNIONS else [member]
        return out
    return [tp]


def _child(tp: Any, part: PathPart, next_tag: str | None) -> Any:
    """The type found at ``part`` inside values of type ``tp`` (None when unknown)."""
    tp = _unwrap(tp)
    origin = typing.get_origin(tp)
    if origin in _UNIONS:
        members = [m for m in typing.get_args(tp) if m is not type(None)]
        if next_tag is not None:
            members = [m for m in members if _tag_of(m) == next_tag] or members
        for member in members:
            found = _child(member, part, None)
            if found is not None:
                return found
        return None
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        field = tp.model_fields.get(str(part))
        return field.annotation if field is not None else None
    if origin in (list, tuple, set) and isinstance(part, int):
        args = typing.get_args(tp)
        return args[0] if args else None
    if origin is dict and isinstance(part, str):
        args = typing.get_args(tp)
        return args[1] if len(args) == 2 else None
    return None


def _model_at(root: type[BaseModel] | None, loc: Sequence[Any]) -> type[BaseModel] | None:
    """The pydantic model class validating the value at ``loc`` (tags included), if it can be found."""
    if root is None:
        return None
    tp: Any = root
    parts = list(loc)
    i = 0
    while i < len(parts):
        part = parts[i]
        if isinstance(part, str) and part.startswith(TAG_MARK):
            tagged = [m for m in _members(tp) if _tag_of(m) == part]
            tp = tagged[0] if tagged else tp
            i += 1
            continue
        nxt = parts[i + 1] if i + 1 < len(parts) else None
        next_tag = nxt if isinstance(nxt, str) and nxt.startswith(TAG_MARK) else None
        tp = _child(tp, part, next_tag)
        if tp is None:
            return None
        i += 1
    tp = _unwrap(tp)
    origin = typing.get_origin(tp)
    if origin in _UNIONS:
        models = [_unwrap(m) for m in typing.get_args(tp)]
        models = [m for m in models if isinstance(m, type) and issubclass(m, BaseModel)]
        return models[0] if len(models) == 1 else None
    return tp if isinstance(tp, type) and issubclass(tp, BaseModel) else None


def _field_names(model: type[BaseModel]) -> list[str]:
    return [f.alias or name for name, f in model.model_fields.items()]


def _clean_loc(loc: Sequence[Any]) -> list[PathPart]:
    out: list[PathPart] = []
    for part in loc:
        if isinstance(part, str) and (part.startswith(TAG_MARK) or part == "[key]"):
            continue
        out.append(part)
    return out


def _expected_values(expected: str) -> list[str]:
    return re.findall(r"'([^']*)'", expected)


def _message(err: dict[str, Any], root: type[BaseModel] | None) -> tuple[list[PathPart], str]:
    kind = err["type"]
    loc = list(err.get("loc", ()))
    value = err.get("input")
    path = _clean_loc(loc)
    ctx = err.get("ctx") or {}
    msg = str(err.get("msg", ""))

    if kind == "extra_forbidden":
        key = str(loc[-1]) if loc else "?"
        model = _model_at(root, loc[:-1])
        hint = did_you_mean(key, _field_names(model), what="keys") if model is not None else ""
        return path, f"unknown key '{key}'{hint}"
    if kind == "missing":
        key = str(loc[-1]) if loc else "?"
        return path, f"missing required key '{key}'; add '{key}: ...' there"
    if loc and loc[-1] == "[key]":
        if kind == "string_pattern_mismatch":
            return path, f"invalid name {show_value(value)}: use only letters, digits, '_' and '-'"
        return path, f"invalid name {show_value(value)}: names are text of letters, digits, '_' and '-'"
    if kind == "string_pattern_mismatch":
        return path, f"invalid name {show_value(value)}: use only letters, digits, '_' and '-'"
    if kind == "io_type":
        if isinstance(value, dict):
            t = value.get("type")
            if t is None:
                return path, f"missing required key 'type' (one of {', '.join(IO_TYPES)})"
            return [*path, "type"], f"unknown io channel type {show_value(t)}{did_you_mean(str(t), IO_TYPES, what='types')}"
        return path, f"expected a mapping such as {{type: adc, output: 0}}, got {show_value(value)}"
    if kind == "execution_spec":
        if isinstance(value, dict):
            d = value.get("dist")
            if d is None:
                return path, f"missing required key 'dist' (one of {', '.join(EXEC_DISTS)})"
            return [*path, "dist"], f"unknown distribution {show_value(d)}{did_you_mean(str(d), EXEC_DISTS, what='distributions')}"
        return path, f"expected a time such as '0.5 ms' or {{dist: uniform, low: .., high: ..}}, got {show_value(value)}"
    if kind == "time_distribution":  # netsim.scenario.schema_task.TimeDistribution (release_jitter, ...)
        if not isinstance(value, dict):
            return path, (f"expected a time such as '1 ms' or {{dist: uniform, low: .., high: ..}}, got "
                          f"{show_value(value)}")
        d = value.get("dist")
        if d is None:
            return path, (f"missing required key 'dist' (one of {', '.join(TIME_DISTS)}), or write a time such "
                          "as '1 ms'")
        hint = did_you_mean(str(d), TIME_DISTS, what="distributions")
        return [*path, "dist"], f"unknown distribution {show_value(d)}{hint}"
    if kind == "literal_error":
        options = _expected_values(str(ctx.get("expected", "")))
        hint = did_you_mean(str(value), options) if isinstance(value, str) else ""
        return path, f"must be {ctx.get('expected', 'one of the allowed values')}, got {show_value(value)}{hint}"
    if kind in ("value_error", "assertion_error"):
        text = re.sub(r"^(Value|Assertion) error, ", "", msg)
        return path, text
    m = re.fullmatch(r"(\w+?)_(type|parsing|from_float)", kind)
    if m and m.group(1) in _TYPE_WORDS:
        word = _TYPE_WORDS[m.group(1)]
        if m.group(2) == "from_float":
            return path, f"expected {word}, got {show_value(value)} (a number with a fractional part)"
        return path, f"expected {word}, got {show_value(value)}"
    if kind == "int_from_float":
        return path, f"expected an integer, got {show_value(value)}"
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        return path, f"{msg[0].lower() + msg[1:]}, got {show_value(value)}"
    if kind == "too_short" and ctx.get("actual_length") == 0:
        key = f"'{loc[-1]}'" if loc and isinstance(loc[-1], str) else "the list"
        least = ctx.get("min_length", 1)
        return path, f"{key} is empty; give at least {least} entr{'y' if least == 1 else 'ies'}"
    if kind in ("too_short", "too_long", "string_too_short"):
        return path, msg[0].lower() + msg[1:]
    return path, msg[0].lower() + msg[1:] if msg else kind


def problems_from_validation_error(
    exc: ValidationError,
    *,
    prefix: Sequence[PathPart] = (),
    model: type[BaseModel] | None = None,
    severity: str = "error",
) -> list[Problem]:
    """One :class:`Problem` per pydantic error, with paths prefixed by ``prefix``.

    Parameters
    ----------
    exc
        The validation error.
    prefix
        Path of the validated value inside the scenario (``["nodes", "s", "tasks", 0, "params"]``).
    model
        The model class that was validated (used to suggest key names); defaults to ``exc.title``'s class
        when not given (then no suggestions).
    """
    problems = []
    for err in exc.errors(include_url=False):
        parts, message = _message(dict(err), model)
        problems.append(Problem(format_path([*prefix, *parts]), message, severity=severity))
    return problems


def path_at_line(name: str, line: int) -> str:
    """The YAML path of the first key or list item that starts on ``line`` of the file ``name``; "" if none.

    For refusals the YAML reader can place only by line (a duplicate key, a forbidden tag, a recursive alias):
    the file is read again within :mod:`netsim.scenario.yaml_limits`' bounds and composed into nodes, never
    built, and every node is visited once (an alias is not followed twice), so an alias bomb costs no more
    than its text. A text that does not even compose has no path.
    """
    from yaml.nodes import MappingNode, ScalarNode, SequenceNode

    from netsim.scenario.safe_yaml import ScenarioLoader
    from netsim.scenario.yaml_limits import read_text

    try:
        loader = ScenarioLoader(read_text(name))
        try:
            root = loader.get_single_node()
        finally:
            loader.dispose()
    except Exception:  # noqa: BLE001 - whatever stops the composer, the problem keeps its line and no path
        return ""
    stack: list[tuple[Any, tuple[PathPart, ...]]] = [(root, ())]
    seen: set[int] = set()
    while stack:  # depth first, in document order
        node, parts = stack.pop()
        if node is None or id(node) in seen:
            continue
        seen.add(id(node))
        children: list[tuple[Any, tuple[PathPart, ...]]] = []
        if isinstance(node, MappingNode):
            for key, value in node.value:
                at = (*parts, key.value if isinstance(key, ScalarNode) else "?")
                if key.start_mark.line + 1 == line:
                    return format_path(list(at))
                children.append((value, at))
        elif isinstance(node, SequenceNode):
            for i, item in enumerate(node.value):
                at = (*parts, i)
                if item.start_mark.line + 1 == line:
                    return format_path(list(at))
                children.append((item, at))
        stack.extend(reversed(children))
    return ""
