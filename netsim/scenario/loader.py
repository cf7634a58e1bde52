"""Load a scenario from YAML (or a dict), validate it completely, and report every problem at once.

The file is read with ruamel.yaml's round-trip loader, which keeps the line of every key and list item, so
each problem is reported as ``file:line: path: message``. Validation runs in three layers that all run even
when an earlier one finds problems: the base schema (:mod:`netsim.scenario.schema`), every plugin's own
``Params`` model, and the cross references (:mod:`netsim.scenario.validate`); a scenario that passes them
then goes through build's own kernel and network checks (:mod:`netsim.scenario.static_build`).

Top-level keys starting with ``x-`` are ignored, so a file can hold YAML anchors for repeated entries::

    x-task: &task {program: sampler, priority: 1, execution: 0.5 ms}
    nodes:
      a: {tasks: [{<<: *task, name: s1, period: 10 ms}]}

Examples
--------
>>> sc = load_scenario({"name": "idle", "duration": "1 s"})
>>> sc.duration
1000000000
>>> check_scenario({"name": "idle", "duration": "1 sec"})[0].message
"unknown unit 'sec'; did you mean 's'?"
"""

from __future__ import annotations

import copy
import hashlib
import io
import json
import logging
import os
from pathlib import Path
from typing import Any, Mapping, Sequence

from pydantic import BaseModel, ValidationError

from netsim.errors import ConfigError
from netsim.scenario.messages import problems_from_validation_error, shorten_problem
from netsim.scenario.paths import PathPart, parse_path, set_path
from netsim.scenario.problems import ERROR, Problem, ScenarioError, sort_problems
from netsim.scenario.schema import PluginSpec, Scenario

__all__ = [
    "LineIndex",
    "read_yaml",
    "load_scenario",
    "check_scenario",
    "resolved_dict",
    "raw_copy",
    "dump_resolved",
    "scenario_hash",
]

log = logging.getLogger(__name__)

#: Top-level keys starting with this are ignored: a place for YAML anchors shared by several entries.
EXTENSION_PREFIX = "x-"

Source = str | os.PathLike[str] | Mapping[str, Any] | Scenario


class LineIndex:
    """Lines (1-based) of the keys and list items of a YAML document, addressable by path parts."""

    def __init__(self) -> None:
        self._lines: dict[tuple[PathPart, ...], int] = {}

    def add(self, parts: tuple[PathPart, ...], line: int) -> None:
        """Record that the value at ``parts`` starts on ``line``."""
        self._lines.setdefault(parts, line)

    def line_of(self, path: str | Sequence[PathPart]) -> int | None:
        """The line of ``path``, or of its nearest existing ancestor (None for an empty index)."""
        try:
            parts = tuple(parse_path(path)) if path else ()
        except ConfigError:
            return None
        while parts:
            if parts in self._lines:
                return self._lines[parts]
            parts = parts[:-1]
        return self._lines.get((), None)


def _to_plain(node: Any, parts: tuple[PathPart, ...], index: LineIndex) -> Any:
    """Plain Python (dict/list/str/int/float/bool/None) from ruamel nodes, recording lines on the way."""
    from ruamel.yaml.comments import CommentedMap, CommentedSeq

    if isinstance(node, dict):
        out: dict[Any, Any] = {}
        for key, value in node.items():
            plain_key = _scalar(key)
            if isinstance(node, CommentedMap):
                try:
                    index.add((*parts, plain_key), node.lc.key(key)[0] + 1)
                except (KeyError, TypeError, AttributeError):
                    pass
            out[plain_key] = _to_plain(value, (*parts, plain_key), index)
        return out
    if isinstance(node, (list, tuple)):
        items = []
        for i, value in enumerate(node):
            if isinstance(node, CommentedSeq):
                try:
                    index.add((*parts, i), node.lc.item(i)[0] + 1)
                except (KeyError, TypeError, AttributeError, IndexError):
                    pass
            items.append(_to_plain(value, (*parts, i), index))
        return items
    return _scalar(node)


def _scalar(value: Any) -> Any:
    if value is None or type(value) in (str, int, float, bool):
        return value
    if isinstance(value, bool):
        return bool(value)
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return float(value)
    if isinstance(value, str):
        return str(value)
    return value


def read_yaml(path: str | os.PathLike[str]) -> tuple[Any, LineIndex]:
    """Read a YAML file into plain Python data and the line index of its keys.

    Raises
    ------
    ScenarioError
        For a missing or unreadable file, or a YAML syntax error (with its line).
    """
    from ruamel.yaml import YAML
    from ruamel.yaml.error import MarkedYAMLError, YAMLError

    from netsim.scenario.safe_yaml import YamlRefused, check_events, check_flow_depth, needs_event_check, read_text
    from netsim.scenario.limits import round_trip_constructor

    name = os.fspath(path)
    try:
        text = read_text(name)
    except FileNotFoundError:
        raise ScenarioError([Problem("", f"file not found: {name}", None, name)]) from None
    except YamlRefused as exc:
        raise ScenarioError([Problem("", exc.message, exc.line, name)]) from None
    yaml = YAML(typ="rt", pure=True)
    yaml.Constructor = round_trip_constructor()  # a 5000-digit integer is refused at its path (limits.py)
    try:
        check_flow_depth(text)
        if needs_event_check(text):
            check_events(yaml.parse(io.StringIO(text)))  # depth, tags, alias expansion: before anything is built
        data = yaml.load(io.StringIO(text))
    except YamlRefused as exc:
        raise ScenarioError([Problem("", exc.message, exc.line, name)]) from None
    except MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        what = exc.problem or "syntax error"
        context = f" ({exc.context})" if exc.context else ""
        if "'\\t'" in what or "\t" in what:
            what, context = "a tab character where YAML expects indentation", "; indent with spaces, not tabs"
        raise ScenarioError([Problem("", f"YAML syntax error: {what}{context}", line, name)]) from None
    except YAMLError as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ScenarioError([Problem("", f"YAML error: {first[:200]}", None, name)]) from None
    except (ValueError, TypeError, AttributeError, RecursionError) as exc:  # a value ruamel cannot construct
        raise ScenarioError([Problem("", f"YAML value cannot be read ({type(exc).__name__}: {str(exc)[:120]}); "
                                     "remove any '!!' tag and write plain values", None, name)]) from None
    index = LineIndex()
    index.add((), 1)
    return _to_plain(data, (), index), index


def _plain_copy(data: Any) -> Any:
    return _to_plain(copy.deepcopy(data), (), LineIndex())


_NOT_ALLOWED = "this scenario loads code from"


def _plugin_files(raw: dict[str, Any], file: str | None, allow: bool | None) -> list[Problem]:
    """Run the plugin files ``raw["plugins"]`` names, if the user allows it; the problems otherwise.

    Each entry is resolved relative to the scenario file (the current folder for a mapping) and written back
    as an absolute path, so a baseline or a sweep point loaded from the raw data finds the same file. A file
    this process already ran (the user allowed it before) is not asked about again.
    """
    from netsim import registry
    from netsim.trust import plugins_allowed

    entries = raw.get("plugins")
    if not isinstance(entries, list):
        return []  # absent, or a wrong type the schema reports
    base = Path(file).parent if file else Path.cwd()
    problems: list[Problem] = []
    resolved: list[Any] = []
    for i, entry in enumerate(entries):
        if not isinstance(entry, str) or not entry.strip():
            resolved.append(entry)
            if isinstance(entry, str):
                problems.append(Problem(f"plugins[{i}]", "empty plugin file name; write the path of a .py file"))
            continue
        where = f"plugins[{i}]"
        try:
            path = (base / entry).resolve()
            exists = path.is_file()
        except (OSError, ValueError) as exc:  # a name too long for the file system, a NUL byte
            resolved.append(entry)
            problems.append(Problem(where, f"cannot use this plugin file name ({exc.__class__.__name__}); write "
                                    "the path of a .py file"))
            continue
        resolved.append(str(path))
        if path.suffix != ".py":
            problems.append(Problem(where, f"a plugin file is a Python file ending in .py, not '{entry[:80]}'"))
        elif not exists:
            problems.append(Problem(where, f"plugin file not found: {path}; fix the path (relative to the "
                                    "scenario file)"))
        elif registry.plugin_file_loaded(path) or plugins_allowed(allow):
            try:
                registry.load_plugin_file(path)
            except ConfigError as exc:
                problems.append(Problem(where, exc.message))
        else:
            problems.append(Problem(where, f"{_NOT_ALLOWED} {path}; rerun with --allow-plugins if you trust it "
                                    "(Python: allow_plugins=True)"))
    raw["plugins"] = resolved
    return problems


def _gather(source: Source, overrides: Mapping[str, Any] | None,
            allow_plugins: bool | None = None) -> tuple[list[Problem], Scenario | None]:
    """Every problem of ``source`` (located) and the scenario when there is no error."""
    file: str | None = None
    index = LineIndex()
    if isinstance(source, Scenario):
        if not overrides:
            return [], source
        raw: Any = raw_copy(source)
        file = source.source
    elif isinstance(source, Mapping):
        raw = _plain_copy(dict(source))
    elif isinstance(source, (str, os.PathLike)):
        file = os.fspath(source)
        try:
            raw, index = read_yaml(file)
        except ScenarioError as exc:
            return exc.problems, None
    else:
        return [Problem("", f"expected a scenario file path or mapping, got {type(source).__name__}")], None

    def done(problems: list[Problem]) -> list[Problem]:
        located = [shorten_problem(p.located(index.line_of(p.path), file)) for p in problems]
        return sort_problems(located)

    if raw is None:
        return done([Problem("", "the file is empty; a scenario needs at least 'name' and 'duration'", 1)]), None
    if not isinstance(raw, dict):
        kind = "a list" if isinstance(raw, list) else repr(raw)
        return done([Problem("", f"the top level must be a mapping (name: ..., duration: ...), got {kind}", 1)]), None

    for key in [k for k in raw if isinstance(k, str) and k.startswith(EXTENSION_PREFIX)]:
        del raw[key]  # a place for YAML anchors (``x-defaults: &task {...}``), ignored
    problems: list[Problem] = []
    for key, value in (overrides or {}).items():
        try:
            set_path(raw, key, _plain_copy(value))
        except ConfigError as exc:
            problems.append(Problem(key, f"cannot apply override: {exc.message}"))
    refused = _plugin_files(raw, file, allow_plugins)  # before any plugin name is looked up
    problems += refused
    if any(_NOT_ALLOWED in p.message for p in refused):
        # the names the file registers are unknown until it runs: listing them as unknown would only be noise
        return done(problems), None

    scenario: Scenario | None = None
    try:
        scenario = Scenario.model_validate(raw)
    except ValidationError as exc:
        problems += problems_from_validation_error(exc, model=Scenario)

    from netsim.scenario.validate import check_raw

    more, validated = check_raw(raw, index.line_of)  # duplicate names quote the line of the first definition
    problems += more
    if scenario is not None and not any(p.severity == ERROR for p in problems):
        _attach(scenario, validated)
        scenario._source = file
        scenario._raw = raw
        from netsim.scenario.static_build import build_problems

        problems += build_problems(scenario)  # what build checks with its runtime objects, nothing simulated
        if any(p.severity == ERROR for p in problems):
            scenario = None
    elif any(p.severity == ERROR for p in problems):
        scenario = None
    return done(problems), scenario


def raw_copy(scenario: Scenario) -> dict[str, Any]:
    """A copy of the raw data ``scenario`` was validated from (its resolved dict if it was built directly).

    Overrides are applied to this, so that derived defaults follow them (a task's deadline defaults to its
    period: overriding the period of a loaded scenario moves the default deadline too).
    """
    if isinstance(scenario._raw, dict):
        return copy.deepcopy(scenario._raw)
    return resolved_dict(scenario)


def _attach(scenario: Scenario, validated: Mapping[str, Any]) -> None:
    for path, spec in scenario.plugin_specs():
        if path in validated:
            spec.attach_validated(validated[path])


def check_scenario(source: Source, overrides: Mapping[str, Any] | None = None, *,
                   allow_plugins: bool | None = None) -> list[Problem]:
    """Every problem (errors and warnings) in a scenario file or dict; never raises for user mistakes.

    Parameters
    ----------
    source
        Path of a YAML file, a raw mapping, or a :class:`Scenario`.
    overrides
        ``{"dotted.path": value}`` applied to the raw data before validation.
    allow_plugins
        Whether the plugin files the scenario's ``plugins:`` names may run (None: the user's settings,
        :func:`netsim.trust.plugins_allowed`). Refused files are error problems.

    Returns
    -------
    list[Problem]
        Sorted by line; empty when the scenario is valid and clean.
    """
    problems, _ = _gather(source, overrides, allow_plugins)
    return problems


def load_scenario(source: Source, overrides: Mapping[str, Any] | None = None, *,
                  allow_plugins: bool | None = None) -> Scenario:
    """Load and validate a scenario; warnings are logged.

    Parameters
    ----------
    source
        Path of a YAML file, a raw mapping (copied, never modified), or a :class:`Scenario` (returned as is
        unless ``overrides`` are given).
    overrides
        ``{"dotted.path": value}`` applied before validation (``{"networks.can.bitrate": "1 Mbit/s"}``).
    allow_plugins
        Whether the plugin files the scenario's ``plugins:`` names may run (None: the user's settings,
        :func:`netsim.trust.plugins_allowed`; a scenario naming a file that is not allowed does not load).

    Raises
    ------
    ScenarioError
        Listing every problem (with path, line and file) when there is at least one error.
    """
    problems, scenario = _gather(source, overrides, allow_plugins)
    if scenario is None:
        raise ScenarioError(problems or [Problem("", "invalid scenario")])
    for p in problems:
        log.warning("%s", p.describe(tag=False))
    return scenario


# --------------------------------------------------------------------------------------------- resolved form
def _params_json(spec: PluginSpec) -> dict[str, Any]:
    validated = spec._validated
    if isinstance(validated, BaseModel):
        try:
            return validated.model_dump(mode="json")
        except Exception:  # a Params model with values JSON cannot hold: keep what the user wrote
            log.debug("cannot serialize validated params of %s", spec.plugin_name(), exc_info=True)
    elif isinstance(validated, dict):
        return _plain_copy(validated)
    return _plain_copy(spec.raw_params())


def resolved_dict(scenario: Scenario) -> dict[str, Any]:
    """Plain data of ``scenario`` with every default filled in and times as text (``"10 ms"``).

    Network and signal parameters are written inline (``{type: can, nodes: [...], bitrate: ...}``), as in
    scenario files, so the result loads back into an equal scenario.
    """
    data = scenario.model_dump(mode="json")
    if not data.get("plugins"):
        data.pop("plugins", None)  # most scenarios have none: their resolved form (and hash) stays as it was
    for path, spec in scenario.plugin_specs():
        params = _params_json(spec)
        parts = parse_path(path)
        if parts[0] == "networks":
            params.pop("nodes", None)
            data["networks"][parts[1]] = {"type": spec.plugin_name(), "nodes": list(spec.nodes), **params}  # type: ignore[attr-defined]
        elif parts[0] == "signals":
            data["signals"][parts[1]] = {"type": spec.plugin_name(), **params}
        else:
            node: Any = data
            for part in parts:
                node = node[part]
            node["params"] = params
    return data


def dump_resolved(scenario: Scenario) -> str:
    """The resolved scenario (:func:`resolved_dict`) as YAML text, keys in schema order."""
    from ruamel.yaml import YAML

    yaml = YAML(typ="rt", pure=True)
    yaml.default_flow_style = False
    yaml.width = 100
    yaml.representer.add_representer(
        type(None), lambda rep, _: rep.represent_scalar("tag:yaml.org,2002:null", "null")
    )
    buf = io.StringIO()
    yaml.dump(resolved_dict(scenario), buf)
    return buf.getvalue()


def scenario_hash(raw_or_scenario: Source) -> str:
    """SHA-256 (hex) of the canonical JSON of the resolved scenario, without its ``output`` section.

    Two files that differ only in formatting, comments, key order, defaults written out or time spelling
    (``"0.01 s"`` vs ``"10 ms"``) hash the same; any change that can alter results changes the hash.

    Raises
    ------
    ScenarioError
        When ``raw_or_scenario`` is not a valid scenario.
    """
    scenario = raw_or_scenario if isinstance(raw_or_scenario, Scenario) else load_scenario(raw_or_scenario)
    data = resolved_dict(scenario)
    data.pop("output", None)
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()
