"""Schedulability analysis beside the simulation: fixed-priority response times and the EDF demand test.

All times are integer nanoseconds (any consistent integer unit works), so the fixed points are exact.

Fixed priority (preemptive, one CPU)
------------------------------------
Response-time analysis with blocking ``B`` and release jitter ``J`` (Joseph & Pandya; Audsley et al.;
Tindell's busy-window extension for deadlines beyond the period). For task ``i`` and the ``q``-th job of
its level-``i`` busy period (``q = 0, 1, ...``)::

    w(q) = (q + 1) C_i + B_i + sum_{j in hp(i)} ceil((w(q) + J_j) / T_j) C_j
    R(q) = w(q) + J_i - q T_i

iterating while ``R(q) > T_i`` (the next job of ``i`` still falls in the busy window);
``R_i = max_q R(q)``. ``R`` counts from the job's **nominal** release (``J_i + w``: the job may arrive up to
``J_i`` late); a sporadic task enters with ``T`` = its minimum inter-arrival time. netsim's kernel measures
``response`` the same way (``JobRecord.response``, from the nominal release; ``response_from_arrival`` is at
most ``w``). ``hp(i)`` holds the tasks with a smaller priority value and, conservatively, the
other tasks of equal priority. The iteration diverges when the level-``i`` utilization reaches 1; the
result is then ``None``.

EDF (preemptive, one CPU)
-------------------------
The processor-demand test (Baruah, Rosier & Howell): with ``dbf(t) = sum_i max(0, floor((t + J_i - D_i)/T_i)
+ 1) C_i``, a synchronous periodic task set is EDF-schedulable iff ``U <= 1`` and ``dbf(t) <= t`` at
every absolute deadline ``t`` within the first synchronous busy period. Release jitter ``J_i`` (Spuri) shortens
a task's deadline to ``D_i - J_i`` after its arrival, and the busy period grows with it
(``w = sum ceil((w + J_i) / T_i) C_i``); without jitter the test is exact, with it, sufficient.

Examples
--------
>>> ms = 1_000_000
>>> tasks = [RTATask("a", 3 * ms, 7 * ms), RTATask("b", 3 * ms, 12 * ms), RTATask("c", 5 * ms, 20 * ms)]
>>> {k: v // ms for k, v in response_times(rate_monotonic(tasks)).items()}
{'a': 3, 'b': 6, 'c': 20}
>>> edf_schedulable([RTATask("a", 2 * ms, 5 * ms), RTATask("b", 4 * ms, 7 * ms)])
True
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction

from netsim.errors import ConfigError

__all__ = [
    "RTATask",
    "busy_period",
    "deadline_monotonic",
    "edf_demand",
    "edf_schedulable",
    "fp_schedulable",
    "hyperperiod",
    "rate_monotonic",
    "response_times",
    "utilization",
]


@dataclass(frozen=True)
class RTATask:
    """A periodic (or sporadic, ``period`` = minimum inter-arrival) task for the analysis.

    Attributes
    ----------
    name
        Task name (keys of the results).
    wcet, period
        Worst-case execution time ``C`` and period ``T`` (integer ns).
    deadline
        Relative deadline ``D`` (default: ``period``).
    priority
        Lower = more urgent; ``None`` for every task means "in the given order".
    jitter
        Release jitter ``J``.
    blocking
        Worst blocking ``B`` by lower-priority tasks (non-preemptive sections, resources).
    """

    name: str
    wcet: int
    period: int
    deadline: int | None = None
    priority: float | None = None
    jitter: int = 0
    blocking: int = 0

    def __post_init__(self) -> None:
        for field in ("wcet", "period", "jitter", "blocking"):
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise ConfigError(f"task '{self.name}': {field} must be a non-negative integer, got {value!r}")
        if self.period <= 0:
            raise ConfigError(f"task '{self.name}': period must be positive, got {self.period}")
        if self.deadline is not None and (not isinstance(self.deadline, int) or self.deadline <= 0):
            raise ConfigError(f"task '{self.name}': deadline must be a positive integer, got {self.deadline!r}")

    @property
    def relative_deadline(self) -> int:
        """``deadline`` or, if unset, ``period``."""
        return self.period if self.deadline is None else self.deadline


def _ceil_div(a: int, b: int) -> int:
    return -(-a // b)


def utilization(tasks: Iterable[RTATask]) -> float:
    """Total utilization ``sum C/T``."""
    return float(sum(Fraction(t.wcet, t.period) for t in tasks))


def hyperperiod(periods: Iterable[int]) -> int:
    """Least common multiple of the periods."""
    out = 1
    for p in periods:
        out = math.lcm(out, int(p))
    return out


def rate_monotonic(tasks: Sequence[RTATask]) -> list[RTATask]:
    """Copies with priorities by period (shorter = more urgent; ties keep the given order)."""
    order = sorted(range(len(tasks)), key=lambda i: (tasks[i].period, i))
    return [replace(tasks[i], priority=rank) for rank, i in enumerate(order)]


def deadline_monotonic(tasks: Sequence[RTATask]) -> list[RTATask]:
    """Copies with priorities by relative deadline (shorter = more urgent; ties keep the given order)."""
    order = sorted(range(len(tasks)), key=lambda i: (tasks[i].relative_deadline, i))
    return [replace(tasks[i], priority=rank) for rank, i in enumerate(order)]


def _priorities(tasks: Sequence[RTATask]) -> list[float]:
    given = [t.priority for t in tasks]
    if all(p is None for p in given):
        return [float(i) for i in range(len(tasks))]
    if any(p is None for p in given):
        missing = [t.name for t in tasks if t.priority is None]
        raise ConfigError(f"tasks {missing} have no priority; give every task one or none")
    return [float(p) for p in given]  # type: ignore[arg-type]


def response_times(tasks: Sequence[RTATask], *, max_jobs: int = 100_000) -> dict[str, int | None]:
    """Worst-case response time of every task under preemptive fixed priorities.

    Parameters
    ----------
    tasks
        The task set; ``priority`` (lower = more urgent) or, if no task has one, the list order.
    max_jobs
        Safety bound on the jobs examined in one busy window.

    Returns
    -------
    dict
        Task name -> worst response time (ns) including its own jitter, or ``None`` when unbounded
        (level utilization >= 1).
    """
    prios = _priorities(tasks)
    out: dict[str, int | None] = {}
    for i, ti in enumerate(tasks):
        hp = [tasks[j] for j in range(len(tasks)) if j != i and prios[j] <= prios[i]]
        level_u = Fraction(ti.wcet, ti.period) + sum(Fraction(t.wcet, t.period) for t in hp)
        if level_u >= 1 and ti.wcet + sum(t.wcet for t in hp) > 0:
            out[ti.name] = None
            continue
        worst = 0
        w = 0
        for q in range(max_jobs):
            w = max(w, (q + 1) * ti.wcet + ti.blocking)
            while True:
                nxt = (q + 1) * ti.wcet + ti.blocking + sum(_ceil_div(w + t.jitter, t.period) * t.wcet for t in hp)
                if nxt == w:
                    break
                w = nxt
            r = w + ti.jitter - q * ti.period
            worst = max(worst, r)
            if r <= ti.period:
                break
        else:  # pragma: no cover - needs a pathological task set
            out[ti.name] = None
            continue
        out[ti.name] = worst
    return out


def fp_schedulable(tasks: Sequence[RTATask]) -> bool:
    """True when every response time is bounded and within its deadline."""
    rts = response_times(tasks)
    for t in tasks:
        r = rts[t.name]
        if r is None or r > t.relative_deadline:
            return False
    return True


def busy_period(tasks: Sequence[RTATask]) -> int | None:
    """Length of the first synchronous busy period (``None`` if the utilization exceeds 1)."""
    if utilization(tasks) > 1:
        return None
    w = sum(t.wcet for t in tasks)
    if w == 0:
        return 0
    while True:
        nxt = sum(_ceil_div(w + t.jitter, t.period) * t.wcet for t in tasks)
        if nxt == w:
            return w
        w = nxt


def edf_demand(tasks: Iterable[RTATask], t: int) -> int:
    """Processor demand ``dbf(t)``: work of the jobs arriving and due within ``[0, t]`` (a job with jitter ``J``
    is due ``D - J`` after its latest arrival)."""
    total = 0
    for task in tasks:
        d = task.relative_deadline - task.jitter
        if t >= d:
            total += ((t - d) // task.period + 1) * task.wcet
    return total


def edf_schedulable(tasks: Sequence[RTATask], bandwidth: Fraction = Fraction(0)) -> bool:
    """Processor-demand test for preemptive EDF on one CPU (exact for synchronous periodic tasks).

    Parameters
    ----------
    tasks
        The task set.
    bandwidth
        CPU share reserved by bandwidth servers (CBS ``Qs/Ts``, TBS ``Us``) beside ``tasks``: a server's jobs due
        in an interval of length ``t`` need at most ``bandwidth * t`` (Abeni & Buttazzo 1998; Spuri & Buttazzo
        1996), so the test becomes ``dbf(t) + bandwidth * t <= t``. With a bandwidth the test is sufficient; it
        checks the deadlines up to ``max(D_i - J_i, sum (T_i - D_i + J_i) U_i / (1 - U))`` (Baruah's bound), or
        one hyperperiod past the largest deadline when ``U = 1``.
    """
    if not bandwidth:
        return _edf_demand_test(tasks)
    u = sum((Fraction(t.wcet, t.period) for t in tasks), Fraction(bandwidth))
    if u > 1:
        return False
    if any(t.relative_deadline - t.jitter <= 0 for t in tasks):
        return False
    late = [t for t in tasks if t.relative_deadline - t.jitter < t.period]
    if not late:
        return True  # every deadline at or after its period: U <= 1 suffices (Liu & Layland; the servers' papers)
    d_max = max(t.relative_deadline - t.jitter for t in tasks)
    if u < 1:
        horizon = max(Fraction(d_max), sum((Fraction((t.period - t.relative_deadline + t.jitter) * t.wcet, t.period)
                                            for t in tasks), Fraction(0)) / (1 - u))
    else:
        horizon = Fraction(hyperperiod(t.period for t in tasks) + d_max)
    for task in late + [t for t in tasks if t not in late]:
        d = task.relative_deadline - task.jitter
        while d <= horizon:
            if edf_demand(tasks, d) + bandwidth * d > d:
                return False
            d += task.period
    return True


def _edf_demand_test(tasks: Sequence[RTATask]) -> bool:
    if not tasks:
        return True
    if sum(Fraction(t.wcet, t.period) for t in tasks) > 1:
        return False
    horizon = busy_period(tasks)
    assert horizon is not None
    deadlines: set[int] = set()
    for task in tasks:
        d = task.relative_deadline - task.jitter
        if d <= 0:
            return False  # a job may arrive after its deadline
        while d <= horizon:
            deadlines.add(d)
            d += task.period
    return all(edf_demand(tasks, t) <= t for t in sorted(deadlines))
