"""Typed records the kernel keeps for the results tables: one :class:`JobRecord` per task job.

The schedule trace is a plain list of ``(task, state, t0, t1)`` tuples (``state`` in ``"running"``,
``"ready"``, ``"blocked"``); :func:`busy_time` sums the CPU-busy part of it over a window.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

__all__ = ["JobRecord", "busy_time"]


@dataclass(slots=True)
class JobRecord:
    """What happened to one job (all times in integer ns).

    Attributes
    ----------
    task, node
        Task and kernel (node) names.
    job_id
        Index of the job within its task.
    release, start, finish
        Release time; first time on the CPU (``None`` if it never ran); finish or kill time (``None`` if
        still unfinished when the run ended).
    response
        ``finish - release`` (``None`` if unfinished).
    deadline
        Absolute deadline (``None``: the task has none).
    deadline_met
        ``finish <= deadline``; ``True`` without a deadline; for a job unfinished at the end of the run,
        ``False`` if its deadline had passed, else ``None``. A killed job counts as a miss if it was killed
        after its deadline.
    preemptions
        Times the job lost the CPU to a more urgent job or handler.
    cpu_time
        CPU time consumed, including the context switches charged to it.
    killed
        Ended by ``kill`` rather than by returning.
    """

    task: str
    node: str
    job_id: int
    release: int
    start: int | None
    finish: int | None
    response: int | None
    deadline: int | None
    deadline_met: bool | None
    preemptions: int
    cpu_time: int
    killed: bool


def busy_time(intervals: Iterable[tuple[str, str, int, int]], t0: int, t1: int) -> int:
    """Total length of the ``"running"`` intervals inside ``[t0, t1]``."""
    total = 0
    for _, state, a, b in intervals:
        if state != "running":
            continue
        lo = a if a > t0 else t0
        hi = b if b < t1 else t1
        if hi > lo:
            total += hi - lo
    return total
