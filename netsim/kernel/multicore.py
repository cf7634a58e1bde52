"""Multiprocessor nodes (m identical cores, global or partitioned scheduling) and CPU speed scaling.

:class:`~netsim.kernel.kernel.MulticoreKernel` is what ``Kernel(env, name, cores=m, ...)`` (or ``speed=...``)
builds: a :class:`~netsim.kernel.kernel.Kernel` whose dispatcher (:class:`MulticoreDispatcher` here, chosen at
build time) places jobs on ``m`` cores. The one-core kernel's dispatcher (:mod:`netsim.kernel.dispatch`) is not touched:
every node without ``cores``/``speed`` runs exactly as before.

Semantics (those of the one-core kernel, per core, except as said here)
-----------------------------------------------------------------------
- **Global** (``multicore: global``, the default): one ready queue; the ``m`` most urgent ready or running
  jobs run (the policy's keys: global FP, RM, DM or EDF). A job that becomes ready takes an idle core (the core
  it last ran on if that one is idle, else the lowest-numbered idle core), else preempts the least urgent
  running job if it is strictly more urgent than it (equal urgency never preempts; among equally urgent
  running jobs the one that became ready last is preempted).
- **Partitioned** (``multicore: partitioned``): each task runs only on its ``core`` (``tasks[].core``, required
  for every task); each core is scheduled as a one-core kernel over its own tasks. Interrupt handlers run on
  core 0.
- Under global scheduling, interrupt handlers compete for the cores like jobs (every handler outranks every
  task); a started non-preemptible job yields to handlers only.
- **Context switches** are per core: a task job put on a core after a different task job, or after that core
  idled, pays ``context_switch``.
- **Migration cost**: a task job placed on a core other than the one it last ran on (after a preemption, a
  sleep or a block) first runs ``migration_cost`` ns of kernel time on the new core (with the context switch
  if one is due), charged to the job like a context switch (its ``cpu_time``, ``Kernel.switch_time``).
  ``Kernel.migrations`` counts the moves (with any cost, zero included).
- **Schedule trace**: with ``m > 1`` every interval carries a fifth element, the core of a ``"running"``
  interval (``(task, "running", t0, t1, core)``; ``None`` for ``"ready"`` and ``"blocked"``), the ``core``
  column of ``schedule.csv``. With one core the trace is unchanged.
- **Speed scaling** (:mod:`netsim.kernel.speed`) applies to every core at once.
- Not available here: periodic loads in closed form (``trigger: {periodic_load: ...}``); use a timer-driven
  handler. Monitors work, with their one-processor protocols.
"""

from __future__ import annotations

from fractions import Fraction
from heapq import heapify, heappop, heappush
from typing import Any

from netsim.errors import BuildError, SimulationError
from netsim.kernel.dispatch import NP_RANK
from netsim.kernel.events import DISPATCH, NORMAL
from netsim.kernel.job import Job
from netsim.kernel.cores import MULTICORE_MODES
from netsim.kernel.load import PeriodicLoad
from netsim.kernel.speed import check_levels, speed_fraction, work_done, work_time
from netsim.kernel.states import READY, RUNNING
from netsim.kernel.task import Task, check_time, task_error

__all__ = ["MulticoreDispatcher"]


class MulticoreDispatcher:
    """CPU allocation over ``m`` cores, with speed scaling (mixed into :class:`~netsim.kernel.kernel.MulticoreKernel`).

    Attributes
    ----------
    cores : int
        Number of cores.
    multicore : str
        ``"global"`` or ``"partitioned"``.
    migration_cost : int
        Kernel time (ns) a task job pays when it resumes on another core.
    migrations : int
        How many times a task job resumed on another core than it last ran on.
    speed : float
        The current CPU speed (a fraction of the nominal clock).
    """

    # ================================================================= set-up
    def _setup_cpu(self: Any, cores: Any = 1, multicore: Any = "global", migration_cost: Any = 0, speed: Any = None,
                   speed_levels: Any = None) -> None:
        node = self.name
        if isinstance(cores, bool) or not isinstance(cores, int) or cores < 1:
            raise BuildError(f"node '{node}': cores must be a whole number >= 1, got {cores!r}")
        if multicore not in MULTICORE_MODES:
            raise BuildError(f"node '{node}': multicore must be 'global' or 'partitioned', got {multicore!r}")
        self.cores = cores
        self.multicore = multicore
        self._partitioned = multicore == "partitioned"
        self.migration_cost = check_time(node, "<kernel>", "migration_cost", migration_cost) or 0
        self._cores: list[Job | None] = [None] * cores  # the job holding each core
        self._core_last: list[Job | None] = [None] * cores  # the last task job of each core (context switches)
        self._home: dict[str, int] = {}  # partitioned: the core of each task
        self._trace_core: dict[str, int] = {}  # the core of each entity's open "running" interval
        self.migrations = 0
        where = f"node '{node}'"
        self._levels = check_levels(speed_levels, where)
        frac = speed_fraction(1 if speed is None else speed, where)
        self._check_level(frac, speed)
        self._set_frac(frac)
        self._speed_busy: dict[float, int] = {}
        self._busy_mark = 0

    def _set_frac(self: Any, frac: Fraction) -> None:
        self._frac = frac
        self._num, self._den = frac.numerator, frac.denominator
        self._unit = frac == 1
        self.speed = float(frac)

    def _check_level(self: Any, frac: Fraction, given: Any) -> None:
        if self._levels is not None and frac not in self._levels:
            levels = ", ".join(str(float(s)) for s in self._levels)
            raise BuildError(f"node '{self.name}': speed {given!r} is not one of speed_levels [{levels}]")

    def __repr__(self: Any) -> str:
        return (f"<MulticoreKernel {self.name} cores={self.cores} {self.multicore} policy={self.policy.name} "
                f"speed={self.speed} tasks={len(self.tasks)} handlers={len(self.handlers)}>")

    # ================================================================= run-time API
    @property
    def running(self: Any) -> str | None:
        """Name of the task or handler on the lowest-numbered busy core (``None``: every core idles)."""
        for job in self._cores:
            if job is not None:
                return str(job.task_name)
        return None

    @property
    def running_on(self: Any) -> list[str | None]:
        """Name of the task or handler on each core (``None``: that core idles)."""
        return [None if job is None else job.task_name for job in self._cores]

    def set_speed(self: Any, speed: float) -> None:
        """Set the CPU speed now: segments under way are charged for the work done at the old speed and their
        rest is planned at the new one (:mod:`netsim.kernel.speed`).

        Raises
        ------
        SimulationError
            For a speed outside ``(0, 1]`` or not among the node's ``speed_levels``.
        """
        try:
            frac = speed_fraction(speed, f"node '{self.name}': set_speed")
            self._check_level(frac, speed)
        except BuildError as exc:
            raise SimulationError(str(exc)) from None
        if frac == self._frac:
            return
        now = self._sim.now
        busy = sum(self.cpu_time.values())
        self._speed_busy[self.speed] = self._speed_busy.get(self.speed, 0) + busy - self._busy_mark
        self._busy_mark = busy
        for job in self._cores:
            if job is not None and job._in_seg and job._seg_work:
                self._end_segment(job, now)  # the dispatch plans the rest at the new speed
        self._set_frac(frac)
        self._request_dispatch_deferred()

    def busy_by_speed(self: Any) -> dict[float, int]:
        """Busy core-time (ns, up to now) per speed the CPU ran at."""
        out = dict(self._speed_busy)
        busy = sum(self.cpu_time.values())
        out[self.speed] = out.get(self.speed, 0) + busy - self._busy_mark
        return out

    def assign_core(self: Any, task: str, core: int) -> None:
        """Partitioned scheduling: task ``task`` runs on core ``core`` (``tasks[].core`` in a scenario)."""
        self._get(self.tasks, task, "task")
        self._home[task] = self._check_core(task, core)

    def _check_core(self: Any, task: str, core: Any) -> int:
        node = self.name
        if not self._partitioned:
            raise task_error(node, task, "core", f"is only used with partitioned scheduling; set nodes.{node}."
                             "multicore: partitioned, or remove the task's core")
        if isinstance(core, bool) or not isinstance(core, int) or not 0 <= core < self.cores:
            raise task_error(node, task, "core", f"must be a core index 0..{self.cores - 1} (the node has "
                             f"{self.cores} cores), got {core!r}")
        return core

    # ================================================================= build-time overrides
    def add_task(self: Any, spec: Any, body: Any, data: Any = None) -> Task:
        core = getattr(spec, "core", None)
        if core is not None:
            self._check_core(spec.name, core)
        task: Task = super().add_task(spec, body, data)  # type: ignore[misc]
        if core is not None:
            self._home[task.name] = core
        return task

    def create_periodic_load(self: Any, name: str, **kwargs: Any) -> PeriodicLoad:
        raise task_error(self.name, name, "trigger", "a periodic load is not available on a node with several "
                         "cores or speed scaling; raise the handler from a timer instead")

    def validate(self: Any) -> None:
        super().validate()  # type: ignore[misc]
        if self._partitioned:
            for name in self.tasks:
                if name not in self._home:
                    raise task_error(self.name, name, "core", "is required under multicore: partitioned (the "
                                     f"core the task runs on, 0..{self.cores - 1})")

    # ================================================================= segments
    def _arm(self: Any, job: Job, now: int, length: int, work: int) -> None:
        job._seg_start = now
        end = now + length
        job._seg_end = end
        job._seg_work = work
        job._in_seg = True
        self.segments += 1
        if job._ev is None or job._ev_time > end:
            job._ev = ev = (self._on_segment_event, job)
            heappush(self._queue, (end, NORMAL, next(self._eid), ev))
            job._ev_time = end

    def _end_segment(self: Any, job: Job, now: int) -> None:
        """Charge ``job``'s segment up to ``now`` (its work at the speed, or kernel time) and close it."""
        job._in_seg = False
        elapsed = now - job._seg_start
        work = job._seg_work
        if work:
            done = elapsed if self._unit else work_done(elapsed, self._num, self._den, work)
            job._remaining -= done
            if job._budget is not None:
                job._budget -= done
            job._seg_work = 0
        else:
            job._pre_left -= elapsed
            if not job.is_handler:
                self.switch_time += elapsed
        job.cpu_time += elapsed
        job._task.cpu += elapsed

    def _on_segment_event(self: Any, ev: tuple) -> None:
        job: Job = ev[1]
        if ev is not job._ev:
            return  # superseded by a nearer wake-up of the same job
        job._ev = None
        if not job._in_seg:
            return  # preempted, blocked or killed meanwhile
        now = self._sim.now
        end = job._seg_end
        if now < end:  # preempted and resumed: the segment ends later than first planned
            job._ev = ev = (self._on_segment_event, job)
            heappush(self._queue, (end, NORMAL, next(self._eid), ev))
            job._ev_time = end
            return
        self._end_segment(job, now)
        if not job._pre_left and not job._remaining:
            self._busy = True
            try:
                self._advance(job, now)  # the code after the segment runs at its end, on its core
            finally:
                self._busy = False
        self._request_dispatch()

    # ================================================================= dispatcher
    def _request_dispatch(self: Any) -> None:
        if self._busy or self._dispatch_pending:
            return
        queue = self._queue
        if not queue or queue[0][0] > self._sim.now or queue[0][1] > DISPATCH:
            self._dispatch()
        else:
            self._dispatch_pending = True
            heappush(queue, (self._sim.now, DISPATCH, next(self._eid), (self._on_deferred_dispatch, None)))

    def _dispatch(self: Any) -> None:
        """Place the most urgent jobs on the cores and run each until it starts a segment or leaves its core."""
        self._busy = True
        try:
            now = self._sim.now
            cores = self._cores
            while True:
                self._assign(now)
                for job in cores:
                    if job is not None and not job._in_seg:
                        break
                else:
                    break
                if job._pre_left:
                    self._arm(job, now, job._pre_left, 0)
                    continue
                remaining = job._remaining
                if remaining:
                    budget = job._budget
                    if budget is not None and budget < remaining:
                        if budget <= 0:
                            job._budget = None
                            job.wcet_overrun = True
                            self._fire_overrun(job._task.wcet_handler, job, "wcet")
                            continue
                        remaining = budget
                    length = remaining if self._unit else work_time(remaining, self._num, self._den)
                    self._arm(job, now, length, remaining)
                    continue
                self._advance(job, now)
            for c, held in enumerate(cores):
                if held is None:
                    self._core_last[c] = None  # an idle core: its next task pays a context switch
        finally:
            self._busy = False

    def _assign(self: Any, now: int) -> None:
        ready = self._ready
        while ready and ready[0][2]._state != READY:
            heappop(ready)  # killed while ready
        if not ready:
            return
        if self._partitioned:
            self._assign_partitioned(now)
            return
        cores = self._cores
        while ready:
            job = ready[0][2]
            if job._state != READY:
                heappop(ready)
                continue
            c = self._idle_core(job)
            if c < 0:  # every core is busy: the least urgent running job, the last to become ready among equals
                busy: list[Job] = cores
                c = max(range(len(busy)), key=lambda i: (busy[i]._rank, busy[i]._seq))
                worst = busy[c]
                if not job._rank < worst._rank:
                    return
                self._preempt(worst, now)
            heappop(ready)
            self._place(job, c, now)

    def _idle_core(self: Any, job: Job) -> int:
        cores = self._cores
        last = job._last_core
        if last >= 0 and cores[last] is None:
            return last
        for i, held in enumerate(cores):
            if held is None:
                return i
        return -1

    def _home_of(self: Any, job: Job) -> int:
        return 0 if job.is_handler else self._home.get(job.task_name, 0)

    def _assign_partitioned(self: Any, now: int) -> None:
        ready = self._ready
        best: dict[int, tuple] = {}
        for entry in ready:
            if entry[2]._state != READY:
                continue
            c = self._home_of(entry[2])
            b = best.get(c)
            if b is None or entry[:2] < b[:2]:
                best[c] = entry
        placed = False
        for c in sorted(best):
            job = best[c][2]
            cur = self._cores[c]
            if cur is not None:
                if not job._rank < cur._rank:
                    continue
                self._preempt(cur, now)
            self._place(job, c, now)
            placed = True
        if placed:
            ready[:] = [e for e in ready if e[2]._state == READY]
            heapify(ready)

    def _place(self: Any, job: Job, c: int, now: int) -> None:
        """Give core ``c`` to ``job`` (it pays a context switch and a migration when due)."""
        self._cores[c] = job
        job._core = c
        job._state = RUNNING
        if job.start is None:
            job.start = now
        if job._np:
            job._rank = NP_RANK  # a started non-preemptible job yields to handlers only
        if not job.is_handler:
            pre = 0
            if job._last_core >= 0 and job._last_core != c:
                self.migrations += 1
                pre = self.migration_cost
            if self._core_last[c] is not job:
                self._core_last[c] = job
                self.switches += 1
                pre += self.context_switch
            if pre:
                job._pre_left = pre
        job._last_core = c
        if self.trace:
            self._trace(job._task, "running", now)
            self._trace_core[job.task_name] = c

    def _free(self: Any, job: Job) -> None:
        self._cores[job._core] = None
        job._core = -1

    def _preempt(self: Any, job: Job, now: int) -> None:
        if job._in_seg:
            self._end_segment(job, now)
        job.preemptions += 1
        job._state = READY
        heappush(self._ready, (job._rank, job._seq, job))  # keeps its place among equals
        self._free(job)
        if self.trace:
            self._trace(job._task, "ready", now)

    # ================================================================= leaving a core
    def _block(self: Any, job: Job, on: Any, now: int) -> None:
        if job._core >= 0:
            self._free(job)
        super()._block(job, on, now)  # type: ignore[misc]

    def _finish(self: Any, job: Job, now: int, killed: bool) -> None:
        if self.trace:
            self._close(job._task, now)
        if job._core >= 0:
            self._free(job)
        super()._finish(job, now, killed)  # type: ignore[misc]

    def _make_ready(self: Any, job: Job, now: int) -> None:
        job._state = READY
        self._seq = seq = self._seq + 1
        job._seq = seq
        heappush(self._ready, (job._rank, seq, job))
        if self.trace:
            self._trace(job._task, "ready", now)

    def _kill(self: Any, job: Job) -> None:
        if job._core >= 0 and job._in_seg:
            self._end_segment(job, self._sim.now)
        super()._kill(job)  # type: ignore[misc]

    # ================================================================= trace and accounting
    def _trace(self: Any, ent: Any, state: str | None, now: int) -> None:
        if ent.trace_state != state:
            self._close(ent, now)
        super()._trace(ent, state, now)  # type: ignore[misc]

    def _close(self: Any, ent: Any, now: int) -> None:
        """With several cores, end ``ent``'s open interval at ``now`` as ``(task, state, t0, t1, core)``, the
        core of a running interval (``None`` for the other states); with one core the base trace does it."""
        state = ent.trace_state
        if self.cores > 1 and state is not None and now > ent.trace_since:
            core = self._trace_core[ent.name] if state == "running" else None
            self.schedule.append((ent.name, state, ent.trace_since, now, core))
            ent.trace_since = now

    @property
    def cpu_time(self: Any) -> dict[str, int]:
        """CPU time per task and handler (ns, context switches and migrations included), summed over cores."""
        out: dict[str, int] = super().cpu_time  # type: ignore[misc]
        now = self._clock()
        for job in self._cores:
            if job is not None and job._in_seg:
                out[job.task_name] += max(0, now - job._seg_start)
        return out

    def utilization(self: Any, t0: int = 0, t1: int | None = None) -> float:
        """Fraction of the ``m`` cores' time in ``[t0, t1]`` they were busy (``1.0``: every core all the time)."""
        if not self.trace:
            now = self._clock()
            if (t0, t1) not in ((0, None), (0, now)):
                raise SimulationError(f"node '{self.name}': utilization over a window needs trace=True")
            return sum(self.cpu_time.values()) / (now * self.cores) if now > 0 else 0.0
        now = self._clock()
        t1 = now if t1 is None else int(t1)
        if t1 <= t0:
            raise SimulationError(f"node '{self.name}': utilization window [{t0}, {t1}] ns is empty")
        spans = [(iv[2], iv[3]) for iv in self.schedule if iv[1] == "running"]
        spans += [(ent.trace_since, now) for ent in [*self.tasks.values(), *self.handlers.values()]
                  if ent.trace_state == "running"]
        busy = sum(max(0, min(b, t1) - max(a, t0)) for a, b in spans)
        return busy / ((t1 - t0) * self.cores)

    def _finalize(self: Any, t_end: int) -> None:
        stop = min(self._sim.now, t_end)
        parts = [(job, max(0, stop - job._seg_start)) for job in self._cores if job is not None and job._in_seg]
        if self.trace:
            for ent in [*self.tasks.values(), *self.handlers.values()]:
                if t_end > ent.trace_since:
                    self._close(ent, t_end)
        for job, part in parts:  # the records of the jobs on the cores count their segment up to the end
            job.cpu_time += part
        try:
            super()._finalize(t_end)  # type: ignore[misc]
        finally:
            for job, part in parts:
                job.cpu_time -= part
