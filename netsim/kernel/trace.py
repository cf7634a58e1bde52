"""The schedule trace, CPU accounting queries and the end-of-run finalisation of a kernel.

:class:`Tracing` is the part of :class:`~netsim.kernel.kernel.Kernel` (a mixin) that keeps the schedule
trace (``Kernel.schedule``: ``(task, state, t0, t1)`` intervals, state ``"running"``, ``"ready"`` or
``"blocked"``), answers :attr:`~Tracing.cpu_time` and :meth:`~Tracing.utilization` at any time, and at the end
of the run (:meth:`~Tracing._finalize`, registered with ``env.at_end``) closes the open trace intervals and
adds a :class:`~netsim.kernel.records.JobRecord` for every unfinished job. The hot paths of the kernel
inline :meth:`~Tracing._trace` where they change a state (each place says so).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

from netsim.errors import SimulationError
from netsim.kernel.load import PeriodicLoad
from netsim.kernel.records import JobRecord, busy_time, deadline_verdict

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.job import Job
    from netsim.kernel.task import Handler, Task

__all__ = ["Tracing"]


class Tracing:
    """Trace, accounting and finalisation of a kernel (mixed into :class:`~netsim.kernel.kernel.Kernel`)."""

    # provided by Kernel
    name: str
    trace: bool
    schedule: list[tuple[str, str, int, int]]
    job_records: list[JobRecord]
    _arrivals: Any  # Arrivals
    _fill_arrivals: Any
    tasks: dict[str, "Task"]
    handlers: dict[str, "Handler"]
    _sim: Any
    _load: PeriodicLoad | None
    _running: "Job | None"
    _seg_job: "Job | None"
    _unfinished: list[JobRecord]
    _t_end: int | None
    _load_progress: Callable[["Job", int], tuple[int, int]]  # provided by Dispatcher

    @property
    def cpu_time(self) -> dict[str, int]:
        """CPU time per task and handler (ns, context switches included), up to now."""
        out = {t.name: t.cpu for t in self.tasks.values()}
        out.update({h.name: h.cpu for h in self.handlers.values()})
        job = self._running
        load = self._load
        if job is not None and self._seg_job is job:
            if load is None:
                out[job.task_name] += max(0, self._clock() - job._seg_start)
            else:
                out[job.task_name] += max(0, self._load_progress(job, self._clock())[1])
        if load is not None:
            out[load.name] = out.get(load.name, 0) + load.stolen_until(self._clock())
        return out

    def _clock(self) -> int:
        """Now, except once the run has ended at T: then T. After ``env.run(T)`` the simpy clock stands at T + 1 ns;
        after netsim's own loop (``run_events``) at the last entry it processed, which may be before T."""
        now: int = self._sim.now
        if self._t_end is not None and now <= self._t_end + 1:
            return self._t_end
        return now

    def utilization(self, t0: int = 0, t1: int | None = None) -> float:
        """Fraction of ``[t0, t1]`` (default: up to now) the CPU was busy (tasks, handlers, switches)."""
        now = self._clock()
        t1 = now if t1 is None else int(t1)
        if t1 <= t0:
            raise SimulationError(f"node '{self.name}': utilization window [{t0}, {t1}] ns is empty")
        if not self.trace:
            if t0 != 0 or t1 != now:
                raise SimulationError(f"node '{self.name}': utilization over a window needs trace=True")
            return min(1.0, sum(self.cpu_time.values()) / t1)
        load = self._load
        if load is None:
            busy = busy_time(self.schedule, t0, t1)
        else:  # running intervals span the windows that interrupted them: count those as the load's
            busy = load.stolen(t0, t1)
            for _, state, a, b in self.schedule:
                if state == "running" and b > t0 and a < t1:
                    busy += load.free(max(a, t0), min(b, t1))
        for ent in list(self.tasks.values()) + list(self.handlers.values()):
            if ent.trace_state == "running":
                lo, hi = max(ent.trace_since, t0), min(now, t1)  # open interval of the running entity
                if hi > lo:
                    busy += hi - lo if load is None else load.free(lo, hi)
        return busy / (t1 - t0)


    def _trace(self, ent: Any, state: str | None, now: int) -> None:
        old = ent.trace_state
        if old == state:
            return
        if old is not None and now > ent.trace_since:
            self.schedule.append((ent.name, old, ent.trace_since, now))
        ent.trace_state = state
        ent.trace_since = now


    def _finalize(self, t_end: int) -> None:
        """Close open trace intervals and add records of the jobs unfinished at ``t_end``."""
        self._t_end = t_end
        if self._arrivals:
            self._fill_arrivals()
        if self._unfinished:
            stale = {id(r) for r in self._unfinished}
            self.job_records[:] = [r for r in self.job_records if id(r) not in stale]
        self._unfinished = []
        running, partial, windows = self._running, 0, 0
        stop = min(self._sim.now, t_end)  # the simpy clock may stand at t_end + 1 ns after env.run(t_end)
        if running is not None and self._seg_job is running:
            if self._load is None:
                partial = stop - running._seg_start
            else:
                partial = self._load_progress(running, stop)[1]
                if running._win_end <= running._seg_start:
                    windows = self._load.ticks_in(running._seg_start, stop)
        for task in self.tasks.values():
            jobs = ([task.active] if task.active is not None else []) + list(task.queue)
            for job in jobs:
                cpu = job.cpu_time + (partial if job is running else 0)
                rec = JobRecord(task.name, self.name, job.job_id, job.release, job.start, None, None, job.deadline,
                                deadline_verdict(job.deadline, None, False, t_end),
                                job.preemptions + (windows if job is running else 0), cpu, False, job.arrival)
                self._unfinished.append(rec)
        self.job_records.extend(self._unfinished)
        if self.trace:
            for ent in list(self.tasks.values()) + list(self.handlers.values()):
                if ent.trace_state is not None and t_end > ent.trace_since:
                    self.schedule.append((ent.name, ent.trace_state, ent.trace_since, t_end))
                    ent.trace_since = t_end

