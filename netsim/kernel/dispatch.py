"""The dispatcher of a kernel: who holds the CPU, CPU segments, preemption and CPU accounting.

:class:`Dispatcher` is the part of :class:`~netsim.kernel.kernel.Kernel` (a mixin) that gives the CPU to the
most urgent ready job and runs it in *segments*: a piece of an ``execute``, a context switch or a handler's
ISR latency, each ending with one wake-up on the event loop (re-armed lazily, so a preemption costs no new
event). A dispatch requested while other events of the instant are pending runs after them, at the
:data:`~netsim.kernel.events.DISPATCH` priority, so releases come before dispatch. With a periodic load
(:meth:`~netsim.kernel.building.KernelBuilder.create_periodic_load`) segments stretch over the load's
windows and are charged in closed form.
"""

from __future__ import annotations

import logging
from heapq import heappop, heappush
from typing import TYPE_CHECKING, Any, Callable

from netsim.kernel.events import DISPATCH, NORMAL, schedule_call
from netsim.kernel.job import Job
from netsim.kernel.load import PeriodicLoad
from netsim.kernel.states import READY, RUNNING

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.task import Handler, Task

__all__ = ["Dispatcher"]

log = logging.getLogger("netsim.kernel.kernel")  # the kernel's logger, as before the split

#: Rank of a started non-preemptible task job: below every handler (level 0), above every task (level 1).
NP_RANK = (0.5, 0)


class Dispatcher:
    """CPU allocation of a kernel (mixed into :class:`~netsim.kernel.kernel.Kernel`)."""

    # provided by Kernel
    name: str
    trace: bool
    context_switch: int
    schedule: list[tuple[str, str, int, int]]
    handlers: dict[str, "Handler"]
    tasks: dict[str, "Task"]
    switches: int
    switch_time: int
    segments: int
    _sim: Any
    _queue: list[Any]
    _eid: Any
    _load: PeriodicLoad | None
    _win_wake: int
    _ready: list[tuple[Any, int, Job]]
    _running: Job | None
    _seg_job: Job | None
    _last_task_job: Job | None
    _busy: bool
    _dispatch_pending: bool
    _advance: Callable[[Job, int], None]  # Interpreter
    _get: Callable[..., Any]  # Kernel
    _invoke: Callable[..., Job]  # Kernel
    _trace: Callable[[Any, "str | None", int], None]  # Tracing

    # ================================================================= segment ends
    def _on_segment_event(self, ev: tuple) -> None:
        job: Job = ev[1]
        if ev is not job._ev:
            return  # superseded by a nearer wake-up of the same job
        job._ev = None
        if self._seg_job is not job:
            return  # preempted, blocked or killed meanwhile: a new wake-up is armed when it runs again
        sim = self._sim
        now = sim.now
        end = job._seg_end
        if now < end:  # the job was preempted and resumed: its segment ends later than first planned
            job._ev = ev = (self._on_segment_event, job)
            heappush(self._queue, (end, NORMAL, next(self._eid), ev))
            job._ev_time = end
            return
        while True:  # one segment end per turn; back-to-back segments that nothing can interrupt chain here
            self._seg_job = None
            if self._load is not None:
                self._charge_load(job, now)
            elif job._pre_left or job._budget is not None:
                self._charge(job, now - job._seg_start)
            else:  # the common case, inlined: an execute segment without budget ran to its end
                elapsed = now - job._seg_start
                job._remaining -= elapsed
                job.cpu_time += elapsed
                job._task.cpu += elapsed
            if job._pre_left:
                break
            if not job._remaining:
                self._busy = True
                try:
                    self._advance(job, now)  # the code after the segment runs at its end, on the CPU
                finally:
                    self._busy = False
                if self._running is not job:
                    self._request_dispatch()
                    return
            remaining = job._remaining
            budget = job._budget
            ready = self._ready
            # fast path: the job keeps the CPU for its next segment unless a ready job beats it (starting
            # a segment runs no code, so doing it before other events of this instant changes nothing)
            if not (remaining and (budget is None or budget >= remaining)
                    and (not ready or not ready[0][0] < job._rank)):
                break
            if self._load is None:
                end = now + remaining
                # the segment's end would be the loop's next entry (nothing due before it, nothing of this
                # priority at it): go there now instead of pushing and popping it (issue 19)
                if sim.advance_if_next(end, NORMAL):
                    job._seg_start = now
                    job._seg_end = end
                    self._seg_job = job
                    self.segments += 1
                    now = end
                    continue
            self._start_segment(job, remaining, now)
            return
        self._request_dispatch()

    def _on_deferred_dispatch(self, _ev: Any) -> None:
        self._dispatch_pending = False
        self._dispatch()

    # ================================================================= dispatcher
    def _request_dispatch(self) -> None:
        """Dispatch now if a dispatch entry pushed now would be the loop's next entry, else push one.

        Called last by the kernel's own callbacks (segment ends, releases, timers, sleeps, deadlines), so
        dispatching at once is what the loop would do next when nothing due now comes before the
        ``DISPATCH`` row: entries of the later rows of the instant (air, arbitration, deadline checks, the
        plant's record samples) wait for the dispatch anyway (issue 19: a task released with a record sample
        at the same instant needs no dispatch entry).
        """
        if self._busy or self._dispatch_pending:
            return
        sim = self._sim
        queue = self._queue  # the event loop's heap: its head is the next entry (time, priority, ...)
        if not queue or queue[0][0] > sim.now or queue[0][1] > DISPATCH:
            if not self._ready and self._running is None and self._load is None:
                self._last_task_job = None  # what _dispatch does when nothing is ready: the CPU idles
                return
            self._dispatch()
        else:
            self._dispatch_pending = True
            heappush(queue, (sim.now, DISPATCH, next(self._eid), (self._on_deferred_dispatch, None)))

    def _request_dispatch_deferred(self) -> None:
        """Dispatch after every event of this instant (entry points called from outside the kernel)."""
        if self._busy or self._dispatch_pending:
            return
        self._dispatch_pending = True
        heappush(self._queue, (self._sim.now, DISPATCH, next(self._eid), (self._on_deferred_dispatch, None)))

    def _dispatch(self) -> None:
        """Give the CPU to the most urgent job and run it until it starts a segment or the CPU idles."""
        self._busy = True
        try:
            now = self._sim.now
            ready = self._ready
            load = self._load
            while True:
                while ready and ready[0][2]._state != READY:
                    heappop(ready)  # killed while ready
                cur = self._running
                if load is not None:
                    d = now - load.start  # we = load.window_end(now), inlined (one dispatch per job)
                    if d >= 0:
                        d %= load.period
                        if d < load.execution and self._held_by_window(cur, now, now - d + load.execution):
                            return
                if cur is not None:
                    if ready and ready[0][0] < cur._rank:
                        self._preempt(cur, now)
                        cur = None
                    elif self._seg_job is cur:
                        return  # keeps running its segment
                if cur is None:
                    if not ready:
                        self._last_task_job = None  # idle: the next task pays a context switch
                        return
                    cur = heappop(ready)[2]
                    if cur._server is not None and cur._server.held(cur):
                        continue  # a hard CBS out of budget keeps its job until the replenishment (servers)
                    # switch in: the job holds the CPU (a task job after another task job or idle pays a context switch)
                    cur._state = RUNNING
                    self._running = cur
                    if cur.start is None:
                        cur.start = now
                    if cur._np:
                        cur._rank = NP_RANK  # a started non-preemptible job yields to handlers only
                    if not cur.is_handler and self._last_task_job is not cur:
                        self._last_task_job = cur
                        self.switches += 1
                        if self.context_switch:
                            cur._pre_left = self.context_switch
                    if self.trace:
                        ent = cur._task
                        old = ent.trace_state
                        if old != "running":  # self._trace(ent, "running", now), inlined
                            if old is not None and now > ent.trace_since:
                                self.schedule.append((ent.name, old, ent.trace_since, now))
                            ent.trace_state = "running"
                            ent.trace_since = now
                if cur._pre_left:
                    self._start_segment(cur, cur._pre_left, now)
                    return
                remaining = cur._remaining
                if remaining:
                    budget = cur._budget
                    if budget is not None and budget < remaining:
                        if budget <= 0:
                            if cur._server is not None:  # a CBS's budget ran out (netsim.kernel.servers)
                                cur._server.exhausted(cur)
                                continue
                            cur._budget = None
                            cur.wcet_overrun = True
                            self._fire_overrun(cur._task.wcet_handler, cur, "wcet")
                            continue
                        remaining = budget
                    self._start_segment(cur, remaining, now)
                    return
                self._advance(cur, now)
        finally:
            self._busy = False

    def _held_by_window(self, cur: Job | None, now: int, we: int) -> bool:
        """Inside a load window ending at ``we``: True if the CPU stays with the window until then.

        Only the tick's real invocation may take or keep the CPU; a job that holds it without a segment, or
        that a ready job beats, is preempted now (the window's interrupt), and a dispatch is scheduled at
        the window's end. A job in a segment keeps it (the segment's end already accounts for the window).
        """
        ready = self._ready
        if (cur is not None and cur._win_end > now) or (ready and ready[0][2]._win_end > now):
            return False
        if cur is not None:
            if self._seg_job is cur and not (ready and ready[0][0] < cur._rank):
                return True
            self._preempt(cur, now)
        if self._win_wake != we:
            self._win_wake = we
            schedule_call(self._sim, we - now, DISPATCH, self._on_window_end)
        return True

    def _on_window_end(self, _ev: Any) -> None:
        self._win_wake = -1
        if not self._busy:
            self._dispatch()

    def _start_segment(self, job: Job, length: int, now: int) -> None:
        job._seg_start = now
        load = self._load
        if load is None:
            end = now + length
        else:
            we = job._win_end
            if we > now:  # the tick's real invocation: the window is its own time
                end = now + length if now + length <= we else load.finish(we, length - (we - now))
            else:
                end = load.finish(now, length)
            length = end - now
        job._seg_end = end
        self._seg_job = job
        self.segments += 1
        # One wake-up per job, re-armed lazily: a preempted job keeps its pending wake-up, which re-arms
        # itself for the later end when it fires early, so a preemption costs no new simpy event.
        if job._ev is None or job._ev_time > end:
            job._ev = ev = (self._on_segment_event, job)
            heappush(self._queue, (end, NORMAL, next(self._eid), ev))
            job._ev_time = end

    def _charge(self, job: Job, elapsed: int) -> None:
        if job._pre_left:
            job._pre_left -= elapsed
            if not job.is_handler:
                self.switch_time += elapsed
        else:
            job._remaining -= elapsed
            if job._budget is not None:
                job._budget -= elapsed
                if job._server is not None:  # a constant bandwidth server's budget (netsim.kernel.servers)
                    job._server.charged(job)
        job.cpu_time += elapsed
        job._task.cpu += elapsed

    def _load_progress(self, job: Job, now: int) -> tuple[int, int]:
        """``(progress, charged)`` of ``job``'s current segment up to ``now`` under the periodic load."""
        load = self._load
        assert load is not None
        a = job._seg_start
        we = job._win_end
        if we > a:  # the tick's real invocation: its time inside the window is the window's CPU time
            if now <= we:
                return now - a, 0
            beyond = load.free(we, now)
            return (we - a) + beyond, beyond
        progress = load.free(a, now)
        return progress, progress

    def _charge_load(self, job: Job, now: int) -> None:
        """Charge ``job``'s segment up to ``now`` under the load; each window inside it preempted the job."""
        progress, charged = self._load_progress(job, now)
        self._charge(job, progress)
        if charged != progress:
            job.cpu_time -= progress - charged
            job._task.cpu -= progress - charged
        if job._win_end <= job._seg_start:
            job.preemptions += self._load.ticks_in(job._seg_start, now)  # type: ignore[union-attr]

    def _preempt(self, job: Job, now: int) -> None:
        same = False
        if self._seg_job is job:
            self._seg_job = None
            if self._load is None:
                self._charge(job, now - job._seg_start)
            else:  # at the end of a window that already preempted the job: one preemption, not two
                same = job._win_end <= job._seg_start and self._load.preempted_until(job._seg_start, now)
                self._charge_load(job, now)
        if not same:
            job.preemptions += 1
        job._state = READY
        heappush(self._ready, (job._rank, job._seq, job))  # keeps its place among equals
        self._running = None
        if self.trace and job._task.trace_state != "ready":
            self._trace(job._task, "ready", now)

    def _fire_overrun(self, ref: Any, job: Job, kind: str) -> None:
        if ref is None:
            log.debug("node %s: %s overrun of %s#%d at %d ns", self.name, kind, job.task_name, job.job_id,
                      self._sim.now)
            return
        if isinstance(ref, str):
            self._invoke(self._get(self.handlers, ref, "handler"), job, f"{kind}:{job.task_name}")
        else:
            busy, self._busy = self._busy, True
            try:
                ref(job)
            finally:
                self._busy = busy

