"""Limits every scenario must keep, checked on the raw data: numbers, names, lists, and the run's size.

These checks walk the raw scenario (plain dicts from YAML) and report with YAML paths, so they reach numbers
the schema keeps untyped (plugin parameters, matrices, ``x0``) as well as typed fields.

What is checked
---------------
- Every number is finite and ``|x| <=`` :data:`netsim.units.NUMBER_LIMIT` (1e15); NaN and inf are refused
  (``seed`` is exempt from the magnitude limit: it is an identifier, not a quantity).
- Names (the keys of ``nodes``, ``networks``, ``signals``, ``io``, and task and
  handler ``name`` fields) are at most :data:`NAME_MAX` characters (they become file and column names).
- ``nodes``, when given, names at least one node; a node whose ``tasks`` is written as an empty list and that
  has no handlers is refused, a node with neither key is a warning (it runs nothing); task and handler names are
  unique per node (the message names the first definition, with its line when the caller gives a line lookup).
- A task with neither ``period`` nor ``release`` (nor ``min_interarrival``) is refused: a deleted ``period``
  used to leave an aperiodic task that never runs while the run said ``ok``. A task released only by a
  plugin's program or a trigger says so with ``release: aperiodic``.
- The memory the run would keep (recorded samples, jobs and messages rows) above the memory budget is an error
  (:mod:`netsim.scenario.memory`).
- The expected number of events (:func:`expected_events`: ``duration / period`` summed over periodic tasks,
  timer handlers, polling encoders and the plant's ``record_grid``) above :data:`EVENTS_WARN` is a warning
  with the estimate.

Time fields beyond :data:`netsim.timebase.MAX_TIME` are refused where they are parsed (:mod:`netsim.units`).

Integers written with more digits than Python converts from text (``sys.get_int_max_str_digits()``, 4300 by
default) cannot be read exactly: the loader reads them as :func:`long_integer_placeholder` (the sign, and 4300
digits), far beyond the number limit, so they are refused here with their path and line like any other
too-large number (before: a message naming only the file). ``seed`` is an identifier, not a
quantity: it is exempt from the number limit but must stay below :data:`SEED_LIMIT`.
"""

from __future__ import annotations

import math
import re
from typing import Any, Callable, Final, Iterator, Mapping

from netsim.scenario.memory import memory_problem
from netsim.scenario.paths import PathPart, format_path
from netsim.scenario.problems import WARNING, Problem
from netsim.scenario.safe_yaml import long_integer_placeholder  # what the loader reads for a 5000-digit integer
from netsim.scenario.schema import MAX_NAME_LENGTH
from netsim.timebase import TimeParseError, parse_time
from netsim.units import NUMBER_LIMIT

__all__ = ["NAME_MAX", "EVENTS_WARN", "SEED_LIMIT", "LineOf", "limit_problems", "expected_events",
           "long_integer_placeholder"]

#: Longest name (node, task, handler, network, signal, io channel; the schema limits the scenario's own name to
#: the same), in characters.
NAME_MAX: Final[int] = MAX_NAME_LENGTH
#: Expected event count above which validate warns (about a minute of simulation at 1e5 events/s and more).
EVENTS_WARN: Final[float] = 1e7
#: ``seed`` is below this (numpy's seed sequences take any size, but 128 bits is their pool's entropy).
SEED_LIMIT: Final[int] = 2**128
#: Sections whose keys are names.
NAMED_SECTIONS: Final[tuple[str, ...]] = ("nodes", "networks", "signals", "io")
#: Top-level keys whose contents are not checked here (free text; overrides are checked as they are applied;
#: the output section belongs to the output rules).
SKIPPED: Final[tuple[str, ...]] = ("description", "baseline", "output")

#: ``line_of(path)``: the line of a YAML path, or None.
LineOf = Callable[[str], "int | None"]


_PATH_KEY = re.compile(r"[^.\[\]\s]+")  # a key a dotted path can name (netsim.scenario.paths)


def _numbers(node: Any, parts: tuple[PathPart, ...],
             inside: str = "") -> Iterator[tuple[tuple[PathPart, ...], float | int, str]]:
    """``(path, number, inside)`` for every number under ``node``. Below a key no path can name (a mobility
    waypoint's time ``8 s`` has a space), the path stops at that key's mapping and ``inside`` says where
    the number is from there (``'8 s'[0]``), so the problem keeps a path with a line."""
    if isinstance(node, dict):
        for key, value in node.items():
            if isinstance(key, str) and len(key) > NAME_MAX:
                continue  # reported as a name; its path would be unreadable
            key = key if isinstance(key, (str, int)) else str(key)
            if inside or (isinstance(key, str) and not _PATH_KEY.fullmatch(key)):
                yield from _numbers(value, parts, f"{inside}['{key}']" if inside else f"'{key}'")
            else:
                yield from _numbers(value, (*parts, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from (_numbers(value, parts, f"{inside}[{i}]") if inside else _numbers(value, (*parts, i)))
    elif isinstance(node, (int, float)) and not isinstance(node, bool):
        yield parts, node, inside


def _digits(value: int) -> str:
    """How many digits ``value`` has, in words, without converting a huge integer to text."""
    if abs(value) < 10**4000:
        return f"{len(str(abs(value)))} digits"
    return "over 4000 digits"


def _number_problem(value: float | int) -> str | None:
    if isinstance(value, float) and math.isnan(value):
        return f"NaN is not a usable number; write a finite number between -{NUMBER_LIMIT:g} and {NUMBER_LIMIT:g}"
    if isinstance(value, float) and math.isinf(value):
        return (f"{'-' if value < 0 else ''}infinity is not a usable number; write a finite number between "
                f"-{NUMBER_LIMIT:g} and {NUMBER_LIMIT:g} (leave the key out for 'no limit' where that is allowed)")
    if abs(value) > NUMBER_LIMIT:
        shown = f"{value:.3g}" if isinstance(value, float) else f"an integer of {_digits(value)}"
        return f"{shown} is beyond netsim's limit for numbers (|x| <= {NUMBER_LIMIT:g}); write a smaller value"
    return None


def _short(name: str) -> str:
    return name if len(name) <= 40 else f"{name[:37]}..."


def _d(x: Any) -> dict[Any, Any]:
    return x if isinstance(x, dict) else {}


def _l(x: Any) -> list[Any]:
    return x if isinstance(x, list) else []


def _name_problems(raw: dict[str, Any]) -> Iterator[Problem]:
    def too_long(name: Any, what: str) -> str | None:
        if isinstance(name, str) and len(name) > NAME_MAX:
            return (f"{what} '{_short(name)}' has {len(name)} characters; names are at most {NAME_MAX} "
                    "characters (they become file and column names): use a shorter name")
        return None

    for section in NAMED_SECTIONS:
        for key in _d(raw.get(section)):
            msg = too_long(key, f"{section} name")
            if msg:
                yield Problem(section, msg)  # the parent: the key itself would make an unreadable path
    for node_name, node in _d(raw.get("nodes")).items():
        if not isinstance(node_name, str) or len(node_name) > NAME_MAX:
            continue
        for kind in ("tasks", "handlers"):
            for i, item in enumerate(_l(_d(node).get(kind))):
                msg = too_long(_d(item).get("name"), kind[:-1] + " name")
                if msg:
                    yield Problem(format_path(["nodes", node_name, kind, i, "name"]), msg)


def _structure_problems(raw: dict[str, Any], line_of: LineOf | None) -> Iterator[Problem]:
    nodes = raw.get("nodes")
    if "nodes" in raw and (nodes is None or nodes == {} or nodes == []):
        yield Problem("nodes", "'nodes' is empty; a scenario needs at least one node with a task or a handler "
                               "(add one, e.g. 'nodes: {cpu: {tasks: [...]}}')")
    for node_name, node in _d(nodes).items():
        if not isinstance(node, dict) or not isinstance(node_name, str) or len(node_name) > NAME_MAX:
            continue
        if not _l(node.get("tasks")) and not _l(node.get("handlers")) and \
                all(isinstance(node.get(k), (list, type(None))) for k in ("tasks", "handlers")):
            if isinstance(node.get("tasks"), list):  # written 'tasks: []': something was meant
                yield Problem(format_path(["nodes", node_name, "tasks"]),
                              f"node '{node_name}' has an empty 'tasks' list and no handlers; add a task (or a "
                              "handler), or remove the node")
            else:
                yield Problem(format_path(["nodes", node_name]),
                              f"node '{node_name}' runs no task and no handler (messages sent to it are dropped); "
                              "add a task or a handler if it should do something", severity=WARNING)
        slotted = [_d(s).get("task") for s in _l(_d(node.get("timetable")).get("slots"))]  # a tt table releases them
        for i, task in enumerate(_l(node.get("tasks"))):
            if (isinstance(task, dict) and task.get("period") is None and task.get("release") is None
                    and task.get("min_interarrival") is None  # a sporadic task releases itself
                    and not (isinstance(task.get("name"), str) and task.get("name") in slotted)):
                yield Problem(format_path(["nodes", node_name, "tasks", i]),
                              f"task '{_short(str(task.get('name')))}' has no period and no release, so "
                              "nothing would ever release it; add e.g. 'period: 10 ms' or "
                              "'release: on_message:<network>', or write 'release: aperiodic' if only a "
                              "plugin's program or a trigger releases it")
        first: dict[str, str] = {}
        for kind in ("tasks", "handlers"):
            for i, item in enumerate(_l(node.get(kind))):
                name = _d(item).get("name")
                if not isinstance(name, str):
                    continue
                at = format_path(["nodes", node_name, kind, i])
                if name in first:
                    line = line_of(first[name]) if line_of is not None else None
                    where = f"{first[name]}" + (f", line {line}" if line is not None else "")
                    yield Problem(f"{at}.name", f"duplicate name '{_short(name)}' on node '{node_name}': first "
                                                f"defined at {where}; task and handler names must be unique per "
                                                "node: rename one")
                else:
                    first[name] = at


def _ns(value: Any) -> int | None:
    try:
        return parse_time(value) if value is not None else None
    except (TimeParseError, TypeError):
        return None


def expected_events(raw: dict[str, Any], tasks: Mapping[tuple[str, int], Any] | None = None
                    ) -> tuple[float, list[tuple[str, float]]]:
    """An estimate of the events a run of ``raw`` simulates, and its largest contributions.

    ``duration / period`` summed over periodic tasks, timer-triggered handlers, polling encoders' ``tick`` and
    the plant's ``record_grid``; networks, messages and program-internal timers add more, so this is a lower bound.
    ``tasks`` maps ``(node, index)`` to a task's validated :class:`~netsim.scenario.schema.TaskSpec`
    (:func:`netsim.scenario.validate.check_raw` passes them): its period is read there, not parsed again.

    Returns
    -------
    total
        The estimate (0 when the duration cannot be read).
    parts
        ``(path, count)`` per contribution, largest first.
    """
    duration = _ns(raw.get("duration"))
    if not duration:
        return 0.0, []
    parts: list[tuple[str, float]] = []

    def add(path: list[PathPart], period: Any, parsed: bool = False) -> None:
        p = period if parsed else _ns(period)
        if p:
            parts.append((format_path(path), duration / p))

    plant = _d(raw.get("plant"))
    if "record_grid" in plant:
        add(["plant", "record_grid"], plant.get("record_grid"))
    for name, channel in _d(raw.get("io")).items():
        if _d(channel).get("type") == "encoder" and _d(channel).get("mode") == "polling":
            add(["io", str(name), "tick"], _d(channel).get("tick"))  # exact mode accounts ticks in closed form
    for node_name, node in _d(raw.get("nodes")).items():
        for i, task in enumerate(_l(_d(node).get("tasks"))):
            model = tasks.get((str(node_name), i)) if tasks is not None else None
            if model is not None:  # validated: its times are integer ns already
                if model.release_kind == "periodic":
                    add(["nodes", str(node_name), "tasks", i, "period"], model.period, parsed=True)
                elif model.release_kind == "sporadic":
                    add(["nodes", str(node_name), "tasks", i, "min_interarrival"], model.min_interarrival, parsed=True)
                continue
            task = _d(task)
            if task.get("release", "periodic") == "periodic":
                add(["nodes", str(node_name), "tasks", i, "period"], task.get("period"))
            elif task.get("release") == "sporadic":  # at most one job per min_interarrival
                add(["nodes", str(node_name), "tasks", i, "min_interarrival"], task.get("min_interarrival"))
        for i, handler in enumerate(_l(_d(node).get("handlers"))):
            timer = _d(_d(_d(handler).get("trigger")).get("timer"))
            if timer.get("period") is not None:
                add(["nodes", str(node_name), "handlers", i, "trigger", "timer", "period"], timer.get("period"))
    parts.sort(key=lambda p: -p[1])
    return float(sum(c for _, c in parts)), parts


def limit_problems(raw: dict[str, Any], line_of: LineOf | None = None,
                   tasks: Mapping[tuple[str, int], Any] | None = None) -> list[Problem]:
    """Every limit ``raw`` breaks (see the module docstring); ``line_of`` adds lines to cross references;
    ``tasks``: the validated tasks (:func:`expected_events`)."""
    problems: list[Problem] = []
    for key, value in raw.items():
        if key in SKIPPED:
            continue
        for parts, number, inside in _numbers(value, (key,)):
            if parts == ("seed",) and isinstance(number, int):
                if number >= SEED_LIMIT:
                    problems.append(Problem("seed", f"the seed is an integer of {_digits(number)}; write an integer "
                                                    f"between 0 and 2^128 - 1 ({SEED_LIMIT - 1:.4g})",
                                            supersedes=True))
                continue  # a negative seed is the schema's (seed >= 0)
            msg = _number_problem(number)
            if msg and inside:
                msg = f"at {inside}: {msg}"
            if msg:  # the value is unusable: other messages about it would only repeat that
                problems.append(Problem(format_path(list(parts)), msg, supersedes=True))
    problems += _name_problems(raw)
    problems += _structure_problems(raw, line_of)
    total, heaviest = expected_events(raw, tasks)
    if total > EVENTS_WARN:
        top = ", ".join(f"{path}: {count:.3g}" for path, count in heaviest[:3])
        problems.append(Problem("duration", f"this run simulates at least {total:.3g} events (duration / period "
                                            f"summed: {top}); it may take very long: shorten 'duration' or lengthen "
                                            "those periods if that was not meant", severity=WARNING))
    memory = memory_problem(raw, tasks)  # what the run would keep in memory, against the budget (issue 31)
    if memory is not None:
        problems.append(memory)
    return problems

