"""Typed records the kernel keeps for the results tables: one :class:`JobRecord` per task job.

The schedule trace is a plain list of ``(task, state, t0, t1)`` tuples (``state`` in ``"running"``,
``"ready"``, ``"blocked"``); :func:`busy_time` sums the CPU-busy part of it over a window.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

__all__ = ["ARRIVAL_COLUMNS", "OUTCOMES", "JobRecord", "busy_time", "deadline_verdict", "has_arrivals", "job_outcome"]

#: The values of :func:`job_outcome` (the ``outcome`` column of ``jobs.csv``).
OUTCOMES = ("met", "missed", "killed", "pending", "done")


def deadline_verdict(deadline: int | None, finish: int | None, killed: bool, t_end: int | None = None) -> bool | None:
    """Whether a job met its deadline: the one rule every table of a run uses.

    Parameters
    ----------
    deadline
        Absolute deadline in ns (``None``: the task has none).
    finish
        Time the job finished or was killed (``None``: still unfinished when the run ended at ``t_end``).
    killed
        The job was killed or aborted: it never completed, so it missed (whatever the time of the kill).
    t_end
        End of the run in ns, for unfinished jobs. Every event at ``t_end`` has been processed when the run
        ends, so a job due at ``t_end`` or earlier that has not finished has missed its deadline.

    Returns
    -------
    bool or None
        True: met (finished at or before the deadline, or finished with no deadline). False: missed
        (finished late, killed, or unfinished with its deadline at or before ``t_end``). None: pending (unfinished
        and not yet due at the end of the run, or unfinished without a deadline): neither met nor missed.
    """
    if killed:
        return False
    if finish is not None:
        return True if deadline is None else finish <= deadline
    if deadline is None or t_end is None or deadline > t_end:
        return None
    return False


def job_outcome(deadline: float | None, killed: bool, met: bool | None) -> str:
    """The label of a job for the tables: ``met``, ``missed``, ``killed``, ``pending`` or ``done``.

    ``met`` is :func:`deadline_verdict`'s value; ``done``: finished, and the task has no deadline. NaN counts
    as missing for ``deadline`` and ``met`` (values read back from a CSV).
    """
    if killed:
        return "killed"
    if met is None or met != met:  # None or NaN/NA: pending
        return "pending"
    if not met:
        return "missed"
    return "done" if deadline is None or deadline != deadline else "met"


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
        ``finish - release`` (``None`` if unfinished, killed or aborted: such a job never completed).
    deadline
        Absolute deadline (``None``: the task has none).
    deadline_met
        :func:`deadline_verdict`: ``finish <= deadline``; ``True`` without a deadline; ``False`` for a killed
        job; for a job unfinished at the end of the run, ``False`` if its deadline was at or before the end,
        else ``None`` (pending).
    preemptions
        Times the job lost the CPU to a more urgent job or handler.
    cpu_time
        CPU time consumed, including the context switches charged to it.
    killed
        Ended by ``kill`` rather than by returning.
    arrival
        The actual arrival of a job of a task with release jitter (``release`` is its nominal release, and
        ``response`` counts from it), set when the run ends (``env.run``); ``None`` for every other job (it
        arrived at ``release``).
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
    arrival: int | None = None

    @property
    def release_jitter(self) -> int | None:
        """``arrival - release``: how late the job arrived after its nominal release (``None`` without jitter)."""
        return None if self.arrival is None else self.arrival - self.release

    @property
    def response_from_arrival(self) -> int | None:
        """``finish - arrival`` (``None`` without jitter, or when the job has no ``response``)."""
        if self.arrival is None or self.response is None or self.finish is None:
            return None
        return self.finish - self.arrival


#: The jobs table's columns for release jitter, ``(column, JobRecord attribute)``, all times: empty for jobs of
#: tasks without jitter, and left out of the tables of runs without any (:func:`has_arrivals`).
ARRIVAL_COLUMNS: tuple[tuple[str, str], ...] = (("arrival_s", "arrival"), ("release_jitter_s", "release_jitter"),
                                                ("response_from_arrival_s", "response_from_arrival"))


def has_arrivals(records: Iterable[Any]) -> bool:
    """True when a job of ``records`` has an ``arrival`` (its task has release jitter)."""
    return any(getattr(r, "arrival", None) is not None for r in records)


def busy_time(intervals: Iterable[tuple[str, str, int, int]], t0: int, t1: int) -> int:
    """Total length of the ``"running"`` intervals inside ``[t0, t1]``."""
    total = 0
    for _, state, a, b in intervals:
        if state != "running":
            continue
        lo = max(t0, a)
        hi = min(t1, b)
        if hi > lo:
            total += hi - lo
    return total
