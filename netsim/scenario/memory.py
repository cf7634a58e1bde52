"""How much memory a run will hold, estimated before it starts, and a clean end when it runs out (issue 31).

A ``duration: 1e9 s`` scenario with a 1 ms record grid used to start and end in a traceback (or be killed) once
the samples filled the machine. :func:`memory_problem` (called by :func:`netsim.scenario.limits.limit_problems`,
so ``validate`` and ``run`` refuse alike) estimates the memory a run keeps until its end and refuses the run when
that exceeds the budget:

* recorded signals: ``duration / plant.record_grid`` samples for each name in ``record:`` (every ``io`` channel
  and ``signals`` source plus one plant output when ``record:`` is omitted), :data:`SAMPLE_BYTES` each;
* the jobs table kept in full (``output.jobs: full``, the default): ``duration / period`` rows per periodic task
  (``min_interarrival`` for a sporadic one), :data:`ROW_BYTES` each;
* the messages table kept in full: one row per job of a periodic task on a node attached to a network.

It is a lower bound, like the event estimate (messages from handlers and program timers are not counted).

The budget (:func:`memory_budget`) is half the machine's memory, or half the address-space limit
(``ulimit -v``) when that is lower; ``NETSIM_MEMORY_BUDGET`` sets it (``4 GiB``, ``512 MB``, ``0`` for no limit).

When memory runs out anyway, :func:`out_of_memory` gives the error the run ends with (one line, with the fix)
after :func:`release` dropped what the run recorded, so its folder can still be written and marked failed.
"""

from __future__ import annotations

import gc
import os
import re
import resource
from typing import Any, Final, Mapping

from netsim.errors import SimulationError
from netsim.scenario.paths import PathPart, format_path
from netsim.scenario.problems import Problem
from netsim.timebase import TimeParseError, parse_time

__all__ = ["SAMPLE_BYTES", "ROW_BYTES", "BUDGET_ENV", "memory_budget", "estimated_bytes", "memory_problem",
           "out_of_memory", "release"]

#: Bytes per recorded sample of one signal: 8 (time) + 8 (value) in typed arrays, doubled for their growth and
#: the tables built from them at the end.
SAMPLE_BYTES: Final[int] = 32
#: Bytes per row of the jobs or messages table kept in full: measured on dc_servo_can (2 s -> 40 s simulated:
#: peak RSS 107 -> 157 MB for about 94 000 more job and message rows, tables built), rounded up.
ROW_BYTES: Final[int] = 600
#: The environment variable that sets the memory budget.
BUDGET_ENV: Final[str] = "NETSIM_MEMORY_BUDGET"

_UNITS = {"": 1, "b": 1, "kb": 10**3, "mb": 10**6, "gb": 10**9, "tb": 10**12, "k": 2**10, "m": 2**20, "g": 2**30,
          "t": 2**40, "kib": 2**10, "mib": 2**20, "gib": 2**30, "tib": 2**40}
_SIZE = re.compile(r"^\s*(\d+(?:\.\d*)?)\s*([a-zA-Z]*)\s*$")
_FIX = ("shorten 'duration', use a coarser 'plant.record_grid' or fewer 'record:' signals, or keep summaries "
        "('output: {jobs: summary, messages: summary}')")


def show_bytes(n: float) -> str:
    """``n`` bytes in words (``1.5 GiB``)."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("kiB", 2**10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def _physical() -> int | None:
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # no sysconf names here: the address-space limit or 2 GiB serve
        return None


def memory_budget() -> tuple[int | None, str]:
    """The memory a run may be estimated to hold, in bytes (None: no limit), and where it comes from.

    Raises
    ------
    ValueError
        When ``NETSIM_MEMORY_BUDGET`` cannot be read (with what to write).
    """
    text = os.environ.get(BUDGET_ENV, "").strip()
    if text:
        m = _SIZE.match(text)
        if m is None or m.group(2).lower() not in _UNITS:
            raise ValueError(f"{BUDGET_ENV}={text!r} is not a size; write e.g. '4 GiB', '512 MB' or 0 (no limit)")
        value = int(float(m.group(1)) * _UNITS[m.group(2).lower()])
        return (value or None), f"{BUDGET_ENV}={text}"
    limits: list[tuple[int, str]] = []
    ram = _physical()
    if ram:
        limits.append((ram // 2, f"half of the machine's {show_bytes(ram)}"))
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft not in (resource.RLIM_INFINITY, -1) and soft > 0:
        limits.append((soft // 2, f"half of the address-space limit 'ulimit -v' of {show_bytes(soft)}"))
    if not limits:
        return 2 * 2**30, "a fixed 2 GiB"
    return min(limits)


def _ns(value: Any) -> int | None:
    try:
        return parse_time(value) if value is not None else None
    except (TimeParseError, TypeError):
        return None


def _d(x: Any) -> dict[Any, Any]:
    return x if isinstance(x, dict) else {}


def _l(x: Any) -> list[Any]:
    return x if isinstance(x, list) else []


def estimated_bytes(raw: dict[str, Any], tasks: Mapping[tuple[str, int], Any] | None = None
                    ) -> tuple[float, list[tuple[str, float]]]:
    """The memory a run of ``raw`` keeps until its end (see the module docstring), and its parts, largest first;
    ``tasks``: the validated tasks by ``(node, index)`` (their periods are read there, not parsed again)."""
    duration = _ns(raw.get("duration"))
    if not duration:
        return 0.0, []
    parts: list[tuple[str, float]] = []
    grid = _ns(_d(raw.get("plant")).get("record_grid"))
    if grid:
        record = raw.get("record")
        names = len(record) if isinstance(record, list) else len(_d(raw.get("io"))) + len(_d(raw.get("signals"))) + 1
        parts.append(("plant.record_grid", duration / grid * max(names, 1) * SAMPLE_BYTES))
    output = _d(raw.get("output"))
    jobs_full, messages_full = output.get("jobs", "full") == "full", output.get("messages", "full") == "full"
    networked = {n for net in _d(raw.get("networks")).values() for n in _l(_d(net).get("nodes"))
                 if isinstance(n, str)}
    for node_name, node in _d(raw.get("nodes")).items():
        for i, task in enumerate(_l(_d(node).get("tasks"))):
            model = tasks.get((str(node_name), i)) if tasks is not None else None
            task = _d(task)
            release = (model.release_kind if model is not None
                       else task.get("release", "periodic" if task.get("period") is not None else None))
            key = "period" if release == "periodic" else "min_interarrival" if release == "sporadic" else None
            if model is not None:
                every = getattr(model, key) if key else None
            else:
                every = _ns(task.get(key)) if key else None
            if not every:
                continue
            rows = duration / every * (jobs_full + (messages_full and node_name in networked))
            if rows:
                path: list[PathPart] = ["nodes", str(node_name), "tasks", i, key]  # type: ignore[list-item]
                parts.append((format_path(path), rows * ROW_BYTES))
    parts.sort(key=lambda p: -p[1])
    return float(sum(b for _, b in parts)), parts


def memory_problem(raw: dict[str, Any], tasks: Mapping[tuple[str, int], Any] | None = None) -> Problem | None:
    """An error at ``duration`` when the run's estimated memory exceeds the budget, else None."""
    need, parts = estimated_bytes(raw, tasks)
    if not need:
        return None
    try:
        budget, source = memory_budget()
    except ValueError as exc:
        return Problem("duration", f"{exc}")
    if budget is None or need <= budget:
        return None
    top = ", ".join(f"{path}: {show_bytes(b)}" for path, b in parts[:3])
    return Problem("duration", f"this run would keep about {show_bytes(need)} in memory ({top}), more than the "
                               f"budget of {show_bytes(budget)} ({source}); {_FIX}, or raise the budget with "
                               f"{BUDGET_ENV}=<size> if the machine has the memory")


def release(sim: Any) -> None:
    """Drop what the simulation ``sim`` recorded (signals, job and message rows, schedule) after a MemoryError, so
    the run folder can still be written (with empty tables) and marked failed."""
    recorder = getattr(getattr(sim, "env", None), "recorder", None)
    for table in (getattr(recorder, "times", None), getattr(recorder, "values", None)):
        if isinstance(table, dict):
            table.clear()
    for owner in [*getattr(sim, "kernels", {}).values(), *getattr(sim, "networks", {}).values()]:
        for name in ("job_records", "records", "schedule"):
            rows = getattr(owner, name, None)
            if isinstance(rows, list):
                rows.clear()
    gc.collect()


def out_of_memory(t_ns: int | None = None) -> SimulationError:
    """The one-line error a run that ran out of memory ends with (``t_ns``: the simulated time then)."""
    when = f" at t = {t_ns / 1e9:.9g} s" if t_ns is not None else ""
    return SimulationError(f"out of memory{when} (MemoryError); {_FIX}, or run it where more memory is free "
                           f"(the run's estimate is checked against {BUDGET_ENV}, default half the memory)")
