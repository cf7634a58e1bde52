"""Load a scenario from YAML (or a dict), validate it completely, and report every problem at once.

Loading goes one way: **text -> raw tree -> overrides and seed applied to the raw tree -> one validation -> a
frozen** :class:`~netsim.scenario.schema.Scenario`, which ``build`` turns into runtime objects. Nothing goes back
from a Scenario to raw data except on purpose (:func:`raw_copy`, when a caller overrides a loaded scenario).

The file is read by :func:`netsim.scenario.safe_yaml.load_text` (PyYAML with libyaml's C parser: fast, keeps no
positions). Every problem is reported as ``file:line: path: message``; the lines are looked up only when there
is a problem to place (:class:`LineIndex` parses the text a second time, keeping positions, on first use).
Validation runs in three layers that all run even when an earlier one finds problems: the base schema
(:mod:`netsim.scenario.schema`, once), every plugin's own ``Params`` model, and the cross references
(:mod:`netsim.scenario.validate`); a scenario that passes them then goes through build's own kernel and network
checks (:mod:`netsim.build.dry_run`: the run's own build on a dry-run environment, once; loaded for a run, the
scenario leaves those checks to the run's one build, :class:`~netsim.build.dry_run.RunCheck`). A scenario
with ``baseline: {overrides: ...}`` has its baseline validated the same way, once, while it loads;
:meth:`Scenario.baseline_scenario` returns it.

A mapping from Python is made plain first (:mod:`netsim.scenario.python_values`: numpy arrays and scalars as lists
and numbers, python-control systems as the plant or model forms), so validation, the resolved scenario and the hash
see what the same scenario written in YAML gives. Overrides (``--set``, ``overrides=``, ``baseline.overrides``)
are written by :mod:`netsim.scenario.overrides`, which also refuses one that a preset-like field's siblings, given
in the scenario, would hide.

Top-level keys starting with ``x-`` are ignored, so a file can hold YAML anchors for repeated entries::

    x-task: &task {program: sampler, priority: 1, execution: 0.5 ms}
    nodes:
      a: {tasks: [{<<: *task, name: s1, period: 10 ms}]}

Why this module is long: loading is one pass over one raw tree (read, overrides, plugin files, the validation
layers, the baseline, shadowed presets, and what a run's build is left to check), and every step reports through
the same line index; kept together, the order of the steps reads in one place.

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
import json
import logging
import os
from pathlib import Path
from typing import Any, Mapping, Sequence

from pydantic import ValidationError

from netsim.errors import ConfigError
from netsim.scenario.messages import problems_from_validation_error, shorten_problem
from netsim.scenario.paths import PathPart, get_path, parse_path
from netsim.scenario.overrides import apply_overrides, shadowed_overrides
from netsim.scenario.problems import ERROR, Problem, ScenarioError, sort_problems
from netsim.scenario.python_values import plain_values
from netsim.scenario.schema import Scenario

__all__ = [
    "LineIndex",
    "read_yaml",
    "load_scenario",
    "check_scenario",
    "resolved_dict",
    "raw_copy",
    "dump_resolved",
    "scenario_hash",
    "shadow_verdict",
]

log = logging.getLogger(__name__)

#: Top-level keys starting with this are ignored: a place for YAML anchors shared by several entries.
EXTENSION_PREFIX = "x-"

Source = str | os.PathLike[str] | Mapping[str, Any] | Scenario


class LineIndex:
    """Lines (1-based) of the keys and list items of a YAML document, addressable by path parts.

    Made from the document's text, it parses the text (again, keeping positions) the first time a line is asked
    for: loading a valid scenario never pays for positions.
    """

    def __init__(self, text: str | None = None) -> None:
        self._text = text
        self._lines: dict[tuple[PathPart, ...], int] | None = None if text is not None else {}

    def _table(self) -> dict[tuple[PathPart, ...], int]:
        if self._lines is None:
            from netsim.scenario.safe_yaml import YamlRefused, line_table

            try:
                self._lines = line_table(self._text or "")
            except YamlRefused:  # cannot happen for a text that loaded; no lines rather than a crash
                self._lines = {}
            self._lines.setdefault((), 1)
        return self._lines

    def add(self, parts: tuple[PathPart, ...], line: int) -> None:
        """Record that the value at ``parts`` starts on ``line``."""
        self._table().setdefault(parts, line)

    def line_of(self, path: str | Sequence[PathPart]) -> int | None:
        """The line of ``path``, or of its nearest existing ancestor (None for an empty index)."""
        try:
            parts = tuple(parse_path(path)) if path else ()
        except ConfigError:
            return None
        lines = self._table()
        while parts:
            if parts in lines:
                return lines[parts]
            parts = parts[:-1]
        return lines.get((), None)


def read_yaml(path: str | os.PathLike[str]) -> tuple[Any, LineIndex]:
    """Read a YAML file into plain Python data and the (lazy) line index of its keys.

    Raises
    ------
    ScenarioError
        For a missing or unreadable file, a file refused by :mod:`netsim.scenario.safe_yaml` (size, nesting,
        aliases, tags, duplicate keys) or a YAML syntax error, with its line.
    """
    from netsim.scenario.messages import path_at_line
    from netsim.scenario.safe_yaml import YamlRefused, load_file

    name = os.fspath(path)
    try:
        data, text = load_file(name)
    except FileNotFoundError:
        raise ScenarioError([Problem("", f"file not found: {name}", None, name)]) from None
    except YamlRefused as exc:  # placed by line; the key or item on that line gives the path (a duplicate key)
        where = path_at_line(name, exc.line) if exc.line is not None and not exc.syntax else ""
        raise ScenarioError([Problem(where, exc.message, exc.line, name)]) from None
    return data, LineIndex(text)


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


def _raw_tree(source: Source, overrides: Mapping[str, Any] | None
              ) -> tuple[Any, str | None, LineIndex, list[Problem]]:
    """The raw tree of ``source`` (a private copy), its file, its line index and the problems reading it."""
    if isinstance(source, Scenario):
        return raw_copy(source), source.source, LineIndex(), []
    if isinstance(source, Mapping):  # numpy values and python-control systems as the YAML forms, once
        raw, problems = plain_values(dict(source))
        return raw, None, LineIndex(), problems
    if isinstance(source, (str, os.PathLike)):
        file = os.fspath(source)
        try:
            raw, index = read_yaml(file)
        except ScenarioError as exc:
            return None, file, LineIndex(), exc.problems
        return raw, file, index, []
    return None, None, LineIndex(), [Problem("", f"expected a scenario file path or mapping, got "
                                                 f"{type(source).__name__}")]


def _validate(raw: dict[str, Any], line_of: Any, build: bool = True) -> tuple[list[Problem], Scenario | None]:
    """The one validation of a raw tree: schema, plugin parameters and cross references, then build's checks
    (with ``build`` False they are left to the run's one build: :class:`~netsim.build.dry_run.RunCheck`).

    Returns the problems (with paths, no lines) and the scenario when there is no error.
    """
    from netsim.scenario.validate import check_raw

    problems: list[Problem] = []
    scenario: Scenario | None = None
    try:
        scenario = Scenario.model_validate(raw)
    except ValidationError as exc:
        problems += problems_from_validation_error(exc, model=Scenario)
    more, validated = check_raw(raw, line_of, scenario)  # duplicate names quote the line of the first definition
    problems += more
    if scenario is None or any(p.severity == ERROR for p in problems):
        return problems, None
    for path, spec in scenario.plugin_specs():
        if path in validated:
            spec.attach_validated(validated[path])
    scenario._raw = raw
    if not build:
        return problems, scenario
    from netsim.build.dry_run import build_problems

    problems += build_problems(scenario)  # the run's build on a dry-run environment, nothing simulated
    if any(p.severity == ERROR for p in problems):
        return problems, None
    return problems, scenario


def _baseline(raw: dict[str, Any], main_valid: bool, build: bool = True
              ) -> tuple[list[Problem], list[Problem], Scenario | None]:
    """The baseline of ``raw`` (``baseline.overrides`` applied, no baseline), validated once.

    Returns the errors to report at ``baseline.overrides``, the baseline's warnings, and the baseline scenario.
    When the scenario itself has errors, only the schema errors at the overridden paths are reported (the
    others are the scenario's own, already reported).
    """
    baseline = raw.get("baseline")
    if not isinstance(baseline, dict) or not isinstance(baseline.get("overrides"), dict):
        return [], [], None
    where = "baseline.overrides"
    base_raw = copy.deepcopy(raw)
    base_raw["baseline"] = None
    applied, refused = apply_overrides(base_raw, {str(k): v for k, v in baseline["overrides"].items()})
    errors = [Problem(where, f"override '{p.path}': {p.message.removeprefix('cannot apply override: ')}")
              for p in refused]
    keys: list[list[PathPart]] = [list(a.parts) for a in applied]
    if not keys:
        return errors, [], None
    if not main_valid:
        try:
            Scenario.model_validate(base_raw)
        except ValidationError as exc:
            for p in problems_from_validation_error(exc, model=Scenario):
                try:
                    parts = parse_path(p.path)
                except ConfigError:
                    continue
                if any(parts[: len(k)] == k for k in keys):
                    errors.append(Problem(where, f"override gives {p.path}: {p.message}"))
        return errors, [], None
    problems, scenario = _validate(base_raw, None, build)
    if scenario is not None:  # an override of a preset the scenario spells out (issue 26)
        hidden, changed = shadowed_overrides(base_raw, scenario, applied)
        if changed:
            problems, scenario = _validate(base_raw, None, build)
        errors += [Problem(where, f"'{p.path}': {p.message}") for p in hidden]
    from netsim.build.dry_run import override_gives

    errors += [override_gives(p) for p in problems if p.severity == ERROR]
    warnings = [p for p in problems if p.severity != ERROR]
    return errors, warnings, None if errors else scenario


def _gather(source: Source, overrides: Mapping[str, Any] | None, allow_plugins: bool | None = None,
            build: bool = True) -> tuple[list[Problem], Scenario | None, list[Problem]]:
    """:func:`_gather_all` with the caller's permission and the scenario file's folder known to plugin parameters
    that name code files (:func:`netsim.trust.validating`: an FMU plant)."""
    from netsim.trust import validating

    file = os.fspath(source) if isinstance(source, (str, os.PathLike)) else None
    with validating(allow_plugins, Path(file).resolve().parent if file else None):
        return _gather_all(source, overrides, allow_plugins, build)


def _gather_all(source: Source, overrides: Mapping[str, Any] | None, allow_plugins: bool | None = None,
                build: bool = True) -> tuple[list[Problem], Scenario | None, list[Problem]]:
    """Every problem of ``source`` (located), the scenario when there is no error, and its baseline's warnings.

    ``build`` False: the build's checks are left to the run (:class:`~netsim.build.dry_run.RunCheck`, with the
    baseline's warnings not yet compared with the scenario's).
    """
    if isinstance(source, Scenario) and not overrides:
        return [], source, []
    raw, file, index, read_problems = _raw_tree(source, overrides)

    def done(problems: list[Problem]) -> list[Problem]:
        located = [shorten_problem(p.located(index.line_of(p.path), file)) for p in problems]
        return sort_problems(located)

    if read_problems:
        return read_problems, None, []
    if raw is None:
        return done([Problem("", "the file is empty; a scenario needs at least 'name' and 'duration'", 1)]), None, []
    if not isinstance(raw, dict):
        kind = "a list" if isinstance(raw, list) else repr(raw)[:80]
        return done([Problem("", f"the top level must be a mapping (name: ..., duration: ...), got {kind}", 1)]), None, []

    for key in [k for k in raw if isinstance(k, str) and k.startswith(EXTENSION_PREFIX)]:
        del raw[key]  # a place for YAML anchors (``x-defaults: &task {...}``), ignored
    applied, problems = apply_overrides(raw, overrides)
    refused = _plugin_files(raw, file, allow_plugins)  # before any plugin name is looked up
    problems += refused
    if any(_NOT_ALLOWED in p.message for p in refused):
        # the names the file registers are unknown until it runs: listing them as unknown would only be noise
        return done(problems), None, []

    found, scenario = _validate(raw, index.line_of, build)
    if scenario is not None and applied:  # an override of a preset the file spells out (issue 26)
        hidden, changed = shadowed_overrides(raw, scenario, applied)
        if changed:  # siblings that spelled out the old preset were removed: the new one fills them
            found, scenario = _validate(raw, index.line_of, build)
        found += hidden
        if hidden:
            scenario = None
    problems += found
    valid = scenario is not None and not any(p.severity == ERROR for p in problems)
    base_errors, base_warnings, base_scenario = _baseline(raw, valid, build)
    problems += base_errors
    if not build and valid and not base_errors and scenario is not None:
        from netsim.build.dry_run import RunCheck

        scenario._run_check = RunCheck(list(problems), index, file, base_warnings)
    said = {(p.path, p.message) for p in problems}
    base_warnings = [p for p in base_warnings if (p.path, p.message) not in said]  # not twice in the log
    if not valid or base_errors:
        return done(problems), None, []
    assert scenario is not None
    scenario._source = file
    scenario._baseline = base_scenario
    return done(problems), scenario, base_warnings


def shadow_verdict(base: dict[str, Any], values: Mapping[str, Any]) -> tuple[list[tuple[PathPart, ...]],
                                                                            list[Problem]] | None:
    """What the shadow check does to ``values`` written as overrides into (a copy of) ``base``: the paths of the
    siblings it removes and its problems; None when the overridden scenario does not validate (nothing to check).

    A sweep (:meth:`netsim.sweep.spec.Sweep.point_raw`) runs this once per distinct preset level and applies the
    verdict to every point with that level.
    """
    raw = copy.deepcopy(base)
    applied, refused = apply_overrides(raw, values)
    if refused:
        return None
    _, scenario = _validate(raw, None)
    if scenario is None:
        return None
    before = copy.deepcopy(raw)
    problems, changed = shadowed_overrides(raw, scenario, applied)
    removed: list[tuple[PathPart, ...]] = []
    if changed:
        for item in applied:
            old, new = _at(before, item.parts[:-1]), _at(raw, item.parts[:-1])
            if isinstance(old, dict) and isinstance(new, dict):
                removed += [(*item.parts[:-1], k) for k in old if k not in new]
    return removed, problems


def _at(raw: Any, parts: tuple[PathPart, ...]) -> Any:
    try:
        return get_path(raw, list(parts)) if parts else raw
    except ConfigError:  # a path the override did not reach: no siblings there were removed
        return None


def raw_copy(scenario: Scenario) -> dict[str, Any]:
    """A copy of the raw data ``scenario`` was validated from (its resolved dict if it was built directly).

    Overrides are applied to this, so that derived defaults follow them (a task's deadline defaults to its
    period: overriding the period of a loaded scenario moves the default deadline too).
    """
    if isinstance(scenario._raw, dict):
        return copy.deepcopy(scenario._raw)
    return resolved_dict(scenario)


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
    problems, _, _ = _gather(source, overrides, allow_plugins)
    return problems


def load_scenario(source: Source, overrides: Mapping[str, Any] | None = None, *,
                  allow_plugins: bool | None = None, for_run: bool = False) -> Scenario:
    """Load and validate a scenario (and its baseline, if it has one); warnings are logged.

    Parameters
    ----------
    source : str, os.PathLike, Mapping or Scenario
        Path of a YAML file, a raw mapping (copied, never modified), or a :class:`Scenario` (returned as is
        unless ``overrides`` are given).
    overrides : Mapping[str, Any], optional
        ``{"dotted.path": value}`` applied to the raw data before the one validation
        (``{"networks.can.bitrate": "1 Mbit/s", "seed": 3}``).
    allow_plugins : bool, optional
        Whether the plugin files the scenario's ``plugins:`` names may run (None: the user's settings,
        :func:`netsim.trust.plugins_allowed`; a scenario naming a file that is not allowed does not load).
    for_run : bool, optional
        True to run it (``netsim run``, :func:`netsim.runner.run`): no dry run; the run's one build, before the run
        folder, reports the build's problems as loading would and logs the warnings
        (:class:`~netsim.build.dry_run.RunCheck`). A Scenario given as ``source`` without ``overrides`` is returned
        as it is.

    Returns
    -------
    Scenario
        The validated scenario (frozen), ready for :func:`netsim.run`.

    Raises
    ------
    ScenarioError
        Listing every problem (with path, line and file) when there is at least one error.

    Examples
    --------
    >>> import netsim
    >>> scenario = netsim.load_scenario("scenarios/dc_servo_can.yaml", {"seed": 3})   # doctest: +SKIP
    >>> scenario.seed, scenario.name                                                  # doctest: +SKIP
    (3, 'dc_servo_can')
    """
    problems, scenario, base_warnings = _gather(source, overrides, allow_plugins, build=not for_run)
    if scenario is None:
        raise ScenarioError(problems or [Problem("", "invalid scenario")])
    if scenario._run_check is not None:  # logged by the run, with its build's warnings
        return scenario
    for p in [*problems, *base_warnings]:
        log.warning("%s", p.describe(tag=False))
    return scenario


# --------------------------------------------------------------------------------------------- resolved form
def resolved_dict(scenario: Scenario) -> dict[str, Any]:
    """Plain data of ``scenario`` with every default filled in and times as text (``"10 ms"``).

    The same as :meth:`Scenario.resolved_dict`: network and signal parameters are written inline
    (``{type: can, nodes: [...], bitrate: ...}``), as in scenario files, so the result loads back into an equal
    scenario.
    """
    return scenario.resolved_dict()


def dump_resolved(scenario: Scenario) -> str:
    """The resolved scenario (:func:`resolved_dict`) as YAML text, keys in schema order, that loads back into an
    equal scenario (:func:`netsim.scenario.safe_yaml.dump_text`)."""
    from netsim.scenario.safe_yaml import dump_text

    return dump_text(resolved_dict(scenario), width=100)


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
