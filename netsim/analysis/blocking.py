"""The blocking term ``B_i`` of fixed-priority response-time analysis for tasks sharing monitors.

A job of task ``i`` can be blocked by a less urgent task that holds a monitor whose *ceiling* (the most urgent
priority among the tasks that use it) is at least as urgent as ``i``: directly (``i`` uses the monitor) or by
push-through (the holder inherits, or runs at the ceiling, above ``i``). ``lp(i)`` is the set of tasks less
urgent than ``i``; ``cs(j, k)`` the longest critical section of task ``j`` on monitor ``k``; only monitors with
``ceil(k)`` at least as urgent as ``i`` count. Critical sections are assumed not nested (Buttazzo, *Hard
Real-Time Computing Systems*, 3rd ed., sections 7.6-7.8):

- **priority inheritance** (``"inherit"``, Sha, Rajkumar & Lehoczky 1990): ``i`` is blocked at most once per
  less urgent task and at most once per monitor, so
  ``B_i = min( sum_{j in lp(i)} max_k cs(j, k),  sum_k max_{j in lp(i)} cs(j, k) )``;
- **priority ceiling** (``"ceiling"``: the immediate ceiling protocol of :mod:`netsim.kernel.monitor`, with the
  same bound as the original PCP): ``i`` is blocked at most once, for one critical section:
  ``B_i = max_{j in lp(i), k} cs(j, k)``.

Give the results to :class:`~netsim.analysis.rta.RTATask` as ``blocking``.

Examples
--------
>>> ms = 1_000_000
>>> prio = {"H": 1, "M": 2, "L": 3}
>>> cs = [CriticalSection("L", "res", 4 * ms), CriticalSection("H", "res", 1 * ms)]
>>> {k: v // ms for k, v in blocking_terms(prio, cs, "inherit").items()}
{'H': 4, 'M': 4, 'L': 0}
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Mapping

from netsim.errors import ConfigError

__all__ = ["CriticalSection", "blocking_terms"]


@dataclass(frozen=True)
class CriticalSection:
    """The longest critical section of one task on one monitor.

    Attributes
    ----------
    task, monitor
        Task and monitor names.
    length
        Worst-case execution time inside the monitor (integer ns).
    """

    task: str
    monitor: str
    length: int


def blocking_terms(priorities: Mapping[str, Any], sections: Iterable[CriticalSection],
                   protocol: str = "inherit") -> dict[str, int]:
    """``B_i`` of every task under ``protocol`` (``"inherit"`` or ``"ceiling"``).

    Parameters
    ----------
    priorities
        Every task's priority (smaller is more urgent: an ``fp`` priority, an ``rm`` period, a ``dm``
        deadline); tasks without critical sections are included so they get their push-through blocking.
    sections
        The critical sections (one per task and monitor; the longest if a task has several on one monitor).
    protocol
        ``"inherit"`` (priority inheritance) or ``"ceiling"`` (immediate / original priority ceiling).

    Returns
    -------
    dict[str, int]
        Task name -> worst-case blocking (ns), in the order of ``priorities``.

    Raises
    ------
    ConfigError
        For an unknown protocol, a section of a task missing from ``priorities``, or a negative length.
    """
    if protocol not in ("inherit", "ceiling"):
        raise ConfigError(f"blocking_terms: protocol must be 'inherit' or 'ceiling', got {protocol!r} (without "
                          "inheritance the blocking is not bounded by the critical sections)")
    cs: dict[tuple[str, str], int] = {}
    for s in sections:
        if s.task not in priorities:
            raise ConfigError(f"blocking_terms: critical section of '{s.task}' on '{s.monitor}', but '{s.task}' "
                              f"has no priority (known: {', '.join(priorities) or 'none'})")
        if s.length < 0:
            raise ConfigError(f"blocking_terms: critical section of '{s.task}' on '{s.monitor}' has negative "
                              f"length {s.length}")
        key = (s.task, s.monitor)
        cs[key] = max(cs.get(key, 0), s.length)
    ceiling: dict[str, Any] = {}
    for (task, mon) in cs:
        p = priorities[task]
        ceiling[mon] = p if mon not in ceiling else min(ceiling[mon], p)
    out: dict[str, int] = {}
    for task, p in priorities.items():
        # critical sections of less urgent tasks on monitors whose ceiling is at least as urgent as `task`
        relevant = {(j, k): c for (j, k), c in cs.items() if priorities[j] > p and ceiling[k] <= p}
        if not relevant:
            out[task] = 0
        elif protocol == "ceiling":
            out[task] = max(relevant.values())
        else:
            per_task: dict[str, int] = {}
            per_mon: dict[str, int] = {}
            for (j, k), c in relevant.items():
                per_task[j] = max(per_task.get(j, 0), c)
                per_mon[k] = max(per_mon.get(k, 0), c)
            out[task] = min(sum(per_task.values()), sum(per_mon.values()))
    return out
