"""The simulated real-time kernel of one node (TrueTime's kernel block, with generator bodies).

Semantics
---------
- **Bodies and segments.** A task body is a generator; the code between two yields runs atomically, in
  zero time, while the job holds the CPU. ``execute`` requests consume preemptible CPU time;
  ``sleep``/``sleep_until`` and blocking mailbox/semaphore/event requests give up the CPU. Zero-time
  requests (``analog_in``, ``send``, ``try_fetch`` ...) are answered without a simpy round trip.
- **End of a segment.** When an ``execute`` ends at ``t`` the job's following code runs at ``t``, before
  anything released at ``t`` can take the CPU (so a job whose last ``execute`` ends at ``t`` finishes at
  ``t``, as response-time analysis assumes). The job may then be preempted before its next ``execute``.
- **Releases before dispatch.** Every release at an instant (periodic releases, timers, triggers,
  message arrivals, wake-ups) is processed before the CPU is given away at that instant: the dispatch
  runs as a simpy event of lower priority than every ordinary event of the instant. Ties among ready
  jobs of equal urgency go to the one that became ready first (FIFO); equal urgency never preempts.
  A preempted job keeps its place (it resumes before equals that arrived while it ran).
- **Interrupt handlers** rank above every task; among themselves by ``priority``. An invocation that
  arrives while the handler is queued or running is queued with its data and time stamp, never lost.
  A handler's ``latency`` is CPU time spent at each invocation before its code runs (ISR entry).
- **Context switches** (TrueTime's "context switch overhead"): each time a task job is put on the CPU
  after a different task job, or after the CPU was idle, it first runs ``context_switch`` ns of kernel
  code, charged to that job (its ``cpu_time``, its task's ``cpu_time``, the schedule trace as
  "running", and ``Kernel.switch_time``). This happens after a release (the new job starts, possibly
  preempting), after a preemption (the preempting job starts, and later the preempted one resumes) and
  after a finish or a block (the next job starts or resumes). Handlers borrow the CPU without a context
  switch: a task resumed after a handler pays nothing (it continues an interrupted switch if one was
  under way). A switch cut short by a more urgent task is started again in full on resumption.
- **Budgets and deadlines.** ``wcet`` is a budget of execution time (context switches excluded) per job;
  the instant it is exhausted with work left, ``wcet_handler`` fires. ``deadline_handler`` fires at the
  absolute deadline if the job has not finished. Neither kills the job; a handler can (``kill_job``).
- **Periodic loads** (:meth:`create_periodic_load`): a fast periodic ISR accounted in closed form; tasks
  and other handlers get the CPU only outside its windows, with the same results as an explicit top-priority
  handler and timer (see that method for the exact rules).
- **Livelock.** More than ``livelock_limit`` zero-time activities (requests and job resumptions) at one
  instant raise :class:`~netsim.errors.LivelockError` naming the tasks and handlers involved.
"""

from __future__ import annotations

import logging
from collections import deque
from heapq import heappop, heappush
from types import GeneratorType
from typing import Any, Callable

from netsim.env import SimEnv
from netsim.errors import BuildError, LivelockError, SimulationError
from netsim.kernel import requests as rq
from netsim.kernel.building import KernelBuilder
from netsim.kernel.events import DEADLINE, DISPATCH, NORMAL, URGENT, schedule_call
from netsim.kernel.exectime import ExecTime
from netsim.kernel.job import Job
from netsim.kernel.load import PeriodicLoad
from netsim.kernel.policies import Policy, resolve_policy
from netsim.kernel.records import JobRecord, busy_time, deadline_verdict
from netsim.kernel.requests import Request
from netsim.kernel.states import BLOCKED, DONE, NEW, READY, RUNNING
from netsim.kernel.task import Handler, Task, check_time, did_you_mean
from netsim.kernel.timers import Timer, Trigger
from netsim.network.message import Message

__all__ = ["Kernel"]

log = logging.getLogger(__name__)

_EXECUTE, _SLEEP_UNTIL, _SLEEP = rq.EXECUTE, rq.SLEEP_UNTIL, rq.SLEEP
#: Rank of a started non-preemptible task job: below every handler (level 0), above every task (level 1).
_NP_RANK = (0.5, 0)
#: Rank of a periodic load's real invocation at a tick: above every handler.
_WINDOW_RANK = (-1, 0)


class Kernel(KernelBuilder):
    """A simulated real-time computer: tasks, interrupt handlers, a scheduler and I/O.

    Parameters
    ----------
    env
        The simulation environment.
    name
        Node name (sender name of its messages; part of its random stream names).
    policy
        ``"fp"``, ``"rm"``, ``"dm"``, ``"edf"``, ``"np_fp"``, ``"np_edf"``, ``"module:Class"`` or a
        :class:`~netsim.kernel.policies.Policy`.
    context_switch
        Context-switch overhead in ns (see the module notes for where it is charged).
    trace
        Keep the schedule trace (``Kernel.schedule``); turning it off saves time in long runs.
    livelock_limit
        Zero-time activities allowed at one instant before a :class:`LivelockError`.

    Attributes
    ----------
    shared : dict
        Per-node state shared by the node's bodies.
    job_records : list[JobRecord]
        One record per finished or killed task job (plus, after the run, one per unfinished job).
    schedule : list[tuple[str, str, int, int]]
        ``(task, state, t0, t1)`` intervals, state in ``"running"``, ``"ready"``, ``"blocked"``.
    switches, switch_time : int
        Number of context switches and CPU time spent in them.
    segments : int
        Number of CPU segments dispatched (execution pieces, context switches, ISR latencies).
    loads : dict[str, PeriodicLoad]
        Periodic interrupt loads accounted in closed form (:meth:`create_periodic_load`).
    """

    def __init__(self, env: SimEnv, name: str, policy: "str | Policy" = "fp", context_switch: int = 0, *,
                 trace: bool = True, livelock_limit: int = 200_000) -> None:
        if not isinstance(name, str) or not name:
            raise BuildError(f"kernel name must be a non-empty string, got {name!r}")
        self.env = env
        self._sim = env.sim
        self.name = name
        self.policy = resolve_policy(policy, name)
        self.context_switch = check_time(name, "<kernel>", "context_switch", context_switch) or 0
        self.trace = bool(trace)
        self.livelock_limit = int(livelock_limit)
        self.shared: dict[str, Any] = {}
        self.job_records: list[JobRecord] = []
        self.schedule: list[tuple[str, str, int, int]] = []
        self.tasks: dict[str, Task] = {}
        self.handlers: dict[str, Handler] = {}
        self.timers: dict[str, Timer] = {}
        self.triggers: dict[str, Trigger] = {}
        self.loads: dict[str, PeriodicLoad] = {}
        self._load: PeriodicLoad | None = None
        self._win_wake = -1  # end of the window for which a dispatch is scheduled
        self.networks: dict[str, Any] = {}
        self._inboxes: dict[str, deque[Message]] = {}
        self._bindings: dict[str, str] = {}
        self._net_labels: dict[str, str] = {}  # invoker label of each network's receptions
        self._ain: dict[str, Callable[[int], Any]] = {}
        self._aout: dict[str, Callable[[int, Any], None]] = {}
        self._ready: list[tuple[Any, int, Job]] = []
        self._seq = 0
        self._running: Job | None = None
        self._seg_job: Job | None = None  # the running job while one of its segments is under way
        self._last_task_job: Job | None = None
        self._busy = False
        self._dispatch_pending = False
        self._exec_rng = env.rng(f"kernel.{name}.exec")
        self.rng = env.rng(f"kernel.{name}.rng")
        self._zt_time = -1
        self._zt_count = 0
        self._zt_names: dict[str, int] = {}
        self._unfinished: list[JobRecord] = []
        self._t_end: int | None = None
        self.switches = 0
        self.switch_time = 0
        self.segments = 0
        # the event loop's heap and id counter: wake-ups are call entries pushed on it (kernel.events)
        _, self._queue, self._eid = env.sim.scheduler()
        schedule_call(self._sim, 0, URGENT, self._on_start)
        env.at_end(self._finalize)

    # ================================================================= run-time API
    @property
    def now(self) -> int:
        """Current simulation time in ns."""
        return self._sim.now  # type: ignore[no-any-return]

    @property
    def running(self) -> str | None:
        """Name of the task or handler holding the CPU (``None``: idle)."""
        return None if self._running is None else self._running.task_name

    def inbox(self, network: str) -> deque[Message]:
        """The node's queue of received, not yet read messages of ``network``."""
        return self._inboxes.setdefault(network, deque())

    def create_job(self, task: str, data: Any = None) -> Job:
        """Release a job of ``task`` now (queued FIFO behind an unfinished job of the same task)."""
        job = self._release(self._get(self.tasks, task, "task"), data)
        self._request_dispatch_deferred()
        return job

    def invoke_handler(self, handler: str, data: Any = None, invoker: str | None = None) -> Job:
        """Raise the interrupt of ``handler`` now (queued if it is already queued or running)."""
        job = self._invoke(self._get(self.handlers, handler, "handler"), data, invoker)
        self._request_dispatch_deferred()
        return job

    def trigger(self, name: str, data: Any = None) -> bool:
        """An edge on external trigger ``name``; returns ``False`` if ignored by its minimum inter-arrival."""
        trig = self._get(self.triggers, name, "trigger")
        now = self._sim.now
        if trig.last is not None and now - trig.last < trig.min_interarrival:
            trig.ignored += 1
            return False
        trig.last = now
        trig.accepted += 1
        self._invoke(self._get(self.handlers, trig.handler, "handler"), data, f"trigger:{name}")
        self._request_dispatch_deferred()
        return True

    def deliver(self, network: str, msg: Message) -> None:
        """Receiver protocol: ``msg`` arrived on ``network`` now (queued, then the bound target is run)."""
        inbox = self._inboxes.get(network)
        if inbox is None:
            inbox = self._inboxes[network] = deque()
        inbox.append(msg)
        target = self._bindings.get(network)
        if target is None:
            return
        handler = self.handlers.get(target)
        if handler is not None:
            label = self._net_labels.get(network)
            if label is None:
                label = self._net_labels[network] = f"network:{network}"
            self._invoke(handler, msg, label)
        else:
            self._release(self._get(self.tasks, target, "task"), msg)
        self._request_dispatch_deferred()

    def kill_job(self, job: Job) -> None:
        """End ``job`` now: it frees the CPU, its record is marked killed, its task's next job may start."""
        if job._state == DONE:
            return
        if job._kernel is not self:
            job._kernel.kill_job(job)
            return
        self._kill(job)
        self._request_dispatch_deferred()

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
        """Now, except right after ``env.run(T)``: the simpy clock then stands at T + 1 ns, the run covered T."""
        now: int = self._sim.now
        if self._t_end is not None and now == self._t_end + 1:
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

    # ================================================================= releases and invocations
    def _get(self, table: dict[str, Any], name: str, what: str) -> Any:
        obj = table.get(name)
        if obj is None:
            raise SimulationError(f"node '{self.name}': no {what} '{name}'{did_you_mean(str(name), table)}")
        return obj

    def _release(self, task: Task, data: Any) -> Job:
        now = self._sim.now
        spec = task.spec
        jid = task.released
        task.released = jid + 1
        deadline = None if spec.deadline is None else now + spec.deadline
        job = Job(self, task, jid, task.data if data is None else data, now, deadline)
        key = task.key
        if key is None:
            key = self.policy.key(job)
            if self.policy.static:
                task.key = key
        job._rank = job._base_rank = (1, key)
        job._np = not (spec.preemptible and self.policy.preemptive)
        job._budget = spec.wcet
        if task.deadline_handler is not None and deadline is not None:
            heappush(self._queue, (deadline, DEADLINE, next(self._eid), (self._on_deadline, job)))
        if task.active is None:
            task.active = job
            self._make_ready(job, now)
        else:
            task.queue.append(job)
        return job

    def _invoke(self, handler: Handler, data: Any, invoker: str | None) -> Job:
        now = self._sim.now
        job = Job(self, handler, handler.invocations, handler.data if data is None else data, now, None, True,
                  invoker)
        handler.invocations += 1
        job._rank = job._base_rank = (0, handler.spec.priority)
        job._pre_left = handler.spec.latency
        load = self._load
        if load is not None and load.handler == handler.name and load.claimed != now and load.is_tick(now):
            load.claimed = now  # this invocation is the tick's window: the most urgent job of the node
            load.real_invocations += 1
            job._win_end = now + load.execution
            job._rank = job._base_rank = _WINDOW_RANK
        if handler.active is None:
            handler.active = job
            self._make_ready(job, now)
        else:
            handler.queue.append(job)
        return job

    def _make_ready(self, job: Job, now: int) -> None:
        job._state = READY
        self._seq = seq = self._seq + 1
        job._seq = seq
        heappush(self._ready, (job._rank, seq, job))
        if self.trace:
            ent = job._task
            old = ent.trace_state
            if old != "ready":  # self._trace(ent, "ready", now), inlined
                if old is not None and now > ent.trace_since:
                    self.schedule.append((ent.name, old, ent.trace_since, now))
                ent.trace_state = "ready"
                ent.trace_since = now

    def _unblock(self, job: Job, value: Any) -> None:
        """Wake a blocked job with ``value`` as the result of its request (used by sync objects)."""
        job._value = value
        job._blocked_on = None
        job._wake = None
        self._make_ready(job, self._sim.now)
        self._request_dispatch_deferred()

    def _trace(self, ent: Any, state: str | None, now: int) -> None:
        old = ent.trace_state
        if old == state:
            return
        if old is not None and now > ent.trace_since:
            self.schedule.append((ent.name, old, ent.trace_since, now))
        ent.trace_state = state
        ent.trace_since = now

    # ================================================================= simpy callbacks
    def _on_start(self, _ev: Any) -> None:
        self.validate()

    def _on_periodic_release(self, ev: tuple) -> None:
        task: Task = ev[1]
        self._release(task, None)
        heappush(self._queue, (self._sim.now + task.spec.period, NORMAL, next(self._eid),
                               (self._on_periodic_release, task)))
        self._request_dispatch()

    def _on_timer(self, ev: tuple) -> None:
        timer: Timer = ev[1]
        if not timer.active:
            return
        timer.fired += 1
        handler = self.handlers.get(timer.handler) or self._get(self.handlers, timer.handler, "handler")
        self._invoke(handler, timer.data, timer.invoker)
        if timer.period is not None:
            heappush(self._queue, (self._sim.now + timer.period, NORMAL, next(self._eid), (self._on_timer, timer)))
        else:
            timer.active = False
        self._request_dispatch()

    def _on_sleep_done(self, ev: tuple) -> None:
        job: Job = ev[1]
        if job._state != BLOCKED or job._wake is not ev:
            return
        job._wake = None
        job._blocked_on = None
        self._make_ready(job, self._sim.now)
        self._request_dispatch()

    def _on_deadline(self, ev: tuple) -> None:
        job: Job = ev[1]
        if job.finish is not None:
            return
        job.deadline_overrun = True
        self._fire_overrun(job._task.deadline_handler, job, "deadline")
        self._request_dispatch()

    def _on_segment_event(self, ev: tuple) -> None:
        job: Job = ev[1]
        if ev is not job._ev:
            return  # superseded by a nearer wake-up of the same job
        job._ev = None
        if self._seg_job is not job:
            return  # preempted, blocked or killed meanwhile: a new wake-up is armed when it runs again
        now = self._sim.now
        end = job._seg_end
        if now < end:  # the job was preempted and resumed: its segment ends later than first planned
            job._ev = ev = (self._on_segment_event, job)
            heappush(self._queue, (end, NORMAL, next(self._eid), ev))
            job._ev_time = end
            return
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
        if not job._pre_left:
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
            if (remaining and (budget is None or budget >= remaining)
                    and (not ready or not ready[0][0] < job._rank)):
                self._start_segment(job, remaining, now)
                return
        self._request_dispatch()

    def _on_deferred_dispatch(self, _ev: Any) -> None:
        self._dispatch_pending = False
        self._dispatch()

    # ================================================================= dispatcher
    def _request_dispatch(self) -> None:
        """Dispatch now if nothing else is pending at this instant, else after the instant's events."""
        if self._busy or self._dispatch_pending:
            return
        sim = self._sim
        queue = self._queue  # the event loop's heap: dispatch at once if nothing else is due now
        if not queue or queue[0][0] > sim.now:
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
                    we = load.window_end(now)
                    if we and self._held_by_window(cur, now, we):
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
                    # switch in: the job holds the CPU (a task job after another task job or idle pays a context switch)
                    cur._state = RUNNING
                    self._running = cur
                    if cur.start is None:
                        cur.start = now
                    if cur._np:
                        cur._rank = _NP_RANK  # a started non-preemptible job yields to handlers only
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

    # ================================================================= running body code
    def _advance(self, job: Job, now: int) -> None:
        """Run ``job``'s code until it asks for CPU time, blocks or ends (it holds the CPU)."""
        if now != self._zt_time:
            self._zt_time = now
            self._zt_count = 0
            if self._zt_names:
                self._zt_names.clear()
        self._zt_count += 1
        limit = self.livelock_limit - self._zt_count
        if limit < self.livelock_limit // 2:
            names = self._zt_names
            names[job.task_name] = names.get(job.task_name, 0) + 1
        gen = job._gen
        if gen is None:
            gen = job._task.body(job)
            if type(gen) is not GeneratorType:
                self._check_generator(job, gen)
            job._gen = gen
        value = job._value
        job._value = None
        send = gen.send
        n = 0
        while True:
            try:
                req = send(value)
            except StopIteration:
                self._zt_count += n
                if job._state != DONE:
                    self._finish(job, now, False)
                return
            except Exception as exc:
                exc.add_note(f"raised by '{job.task_name}' on node '{self.name}' at t={now} ns")
                raise
            n += 1
            if n > limit:
                self._livelock(job)
            if job._state == DONE:  # killed by its own code (kernel.kill_job)
                gen.close()
                self._zt_count += n
                return
            value = None
            if type(req) is not Request:
                raise SimulationError(
                    f"node '{self.name}', task '{job.task_name}' yielded {req!r}; yield a request built by the "
                    "job, e.g. `yield job.execute(1000)`")
            op = req.op
            if op == _EXECUTE:
                d = req.a
                if type(d) is not int:
                    d = d.const if type(d) is ExecTime and d.const is not None else self._duration(job, d)
                elif d < 0:
                    raise SimulationError(f"node '{self.name}', task '{job.task_name}': execute({d}) is negative")
                if d:
                    job._remaining = d
                    self._zt_count += n
                    return
            elif op == _SLEEP or op == _SLEEP_UNTIL:
                t = req.a
                if type(t) is not int:
                    t = self._time_arg(job, t, rq.OP_NAMES[op])
                if op == _SLEEP:
                    if t < 0:
                        raise SimulationError(
                            f"node '{self.name}', task '{job.task_name}': sleep({t}) is negative")
                    t += now
                if t > now:
                    job._wake = schedule_call(self._sim, t - now, NORMAL, self._on_sleep_done, job)
                    self._block(job, job._wake, now)
                    self._zt_count += n
                    return
            elif op == rq.ANALOG_IN:
                fn = self._ain.get(req.a)
                if fn is None:
                    fn = self._io(self._ain, req.a, job, "analog input")
                value = fn(now)
            elif op == rq.ANALOG_OUT:
                fn = self._aout.get(req.a)
                if fn is None:
                    fn = self._io(self._aout, req.a, job, "analog output")
                fn(now, req.b)
            elif op == rq.SEND:
                self._send(job, req)
            elif op == rq.RECEIVE:
                inbox = self._inboxes.get(req.a)
                value = inbox.popleft() if inbox else None
            elif op == rq.FETCH:
                ok, value = req.a.try_get()
                if not ok:
                    req.a._getters.append(job)
                    self._block(job, req.a, now)
                    self._zt_count += n
                    return
            elif op == rq.POST:
                if not req.a.try_put(req.b):
                    req.a._putters.append((job, req.b))
                    self._block(job, req.a, now)
                    self._zt_count += n
                    return
            elif op == rq.TRY_FETCH:
                value = req.a.try_get()[1]
            elif op == rq.TRY_POST:
                value = req.a.try_put(req.b)
            elif op == rq.TAKE:
                if not req.a.try_take():
                    req.a._waiters.append(job)
                    self._block(job, req.a, now)
                    self._zt_count += n
                    return
            elif op == rq.GIVE:
                req.a.give()
            elif op == rq.WAIT:
                req.a._waiters.append(job)
                self._block(job, req.a, now)
                self._zt_count += n
                return
            elif op == rq.NOTIFY:
                req.a.notify(req.b)
            elif op == rq.KILL:
                target = job if req.a is None else req.a
                if target is job:
                    self._zt_count += n
                    self._kill(job)
                    return
                self.kill_job(target)
            else:  # pragma: no cover - Request objects come from Job methods only
                raise SimulationError(f"unknown request {req!r}")

    def _check_generator(self, job: Job, gen: Any) -> None:
        """A body's result that is not a Python generator must at least behave like one."""
        if not (hasattr(gen, "send") and hasattr(gen, "close")):
            raise SimulationError(f"node '{self.name}': body of '{job.task_name}' returned {gen!r}, not a "
                                  "generator; the body must contain `yield job.<request>(...)`")

    def _duration(self, job: Job, d: Any) -> int:
        if isinstance(d, ExecTime):
            return d.draw(self._exec_rng, job)
        return self._time_arg(job, d, "execute")

    def _time_arg(self, job: Job, t: Any, op: str) -> int:
        if isinstance(t, ExecTime):
            return t.draw(self._exec_rng, job)
        try:
            value = int(round(t))
        except (TypeError, ValueError):
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': {op}() needs integer ns or an "
                                  f"ExecTime, got {t!r}") from None
        if value < 0 and op == "execute":
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': execute({t}) is negative")
        return value

    def _io(self, table: dict[str, Any], channel: str, job: Job, what: str) -> Any:
        fn = table.get(channel)
        if fn is None:
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': no {what} '{channel}'"
                                  f"{did_you_mean(str(channel), table)}")
        return fn

    def _send(self, job: Job, req: Request) -> None:
        net = self.networks.get(req.a)
        if net is None:
            raise SimulationError(f"node '{self.name}', task '{job.task_name}': send on network '{req.a}', which "
                                  f"is not attached to this node{did_you_mean(str(req.a), self.networks)}")
        to, payload, bits = req.b
        priority, tag = req.c
        if type(bits) is not int or bits < 0:
            if isinstance(bits, bool) or not isinstance(bits, int) or bits < 0:
                raise SimulationError(f"node '{self.name}', task '{job.task_name}': send bits must be a "
                                      f"non-negative int, got {bits!r}")
        # Message(sender, receiver, payload, bits, priority, msg_id, network, sent_ns, seq, tag): positional
        # arguments cost half as much as keywords here (one message per send)
        net.send(Message(self.name, to, payload, bits, priority, -1, "", 0, 0, tag or job.task_name))

    def _block(self, job: Job, on: Any, now: int) -> None:
        job._state = BLOCKED
        job._blocked_on = on
        job._rank = job._base_rank
        self._running = None
        if self.trace:
            self._trace(job._task, "blocked", now)

    def _livelock(self, job: Job) -> None:
        names = dict(self._zt_names)
        names[job.task_name] = names.get(job.task_name, 0) + 1
        involved = sorted(names)
        raise LivelockError(
            f"node '{self.name}': livelock at t={self._sim.now} ns: more than {self.livelock_limit} zero-time "
            f"activities at one instant by {', '.join(repr(n) for n in involved)}; give the loop an execute() "
            "or a sleep() so that time advances", involved)

    # ================================================================= ending jobs
    def _finish(self, job: Job, now: int, killed: bool) -> None:
        job._state = DONE
        job._gen = None  # break the job <-> generator-frame cycle so the job is freed at once
        job.finish = now
        job.killed = killed
        if self._running is job:
            self._running = None
        task = job._task
        if not job.is_handler:
            deadline = job.deadline
            if killed:  # never completed: no response time, and a miss (deadline_verdict)
                self.job_records.append(JobRecord(
                    task.name, self.name, job.job_id, job.release, job.start, now, None, deadline, False,
                    job.preemptions, job.cpu_time, True))
            else:  # deadline_verdict(deadline, now, False), inlined on the hot path
                self.job_records.append(JobRecord(
                    task.name, self.name, job.job_id, job.release, job.start, now, now - job.release, deadline,
                    True if deadline is None else now <= deadline, job.preemptions, job.cpu_time, False))
        if task.queue:
            nxt = task.queue.popleft()
            task.active = nxt
            self._make_ready(nxt, now)
        else:
            task.active = None
            if self.trace:
                old = task.trace_state
                if old is not None:  # self._trace(task, None, now), inlined
                    if now > task.trace_since:
                        self.schedule.append((task.name, old, task.trace_since, now))
                    task.trace_state = None
                    task.trace_since = now

    def _kill(self, job: Job) -> None:
        now = self._sim.now
        if job is self._running:
            if self._seg_job is job:
                self._seg_job = None
                if self._load is None:
                    self._charge(job, now - job._seg_start)
                else:
                    self._charge_load(job, now)
            self._running = None
        elif job._state == NEW:
            job._task.queue.remove(job)
            job._state = DONE
            job.finish = now
            job.killed = True
            if not job.is_handler:
                self.job_records.append(JobRecord(
                    job.task_name, self.name, job.job_id, job.release, None, now, None,
                    job.deadline, deadline_verdict(job.deadline, now, True), 0, 0, True))
            return
        job._wake = None
        gen = job._gen
        job._gen = None
        self._finish(job, now, True)
        if gen is not None:
            try:
                gen.close()
            except ValueError:
                pass  # the job is killing itself from its own running code: _advance closes it
            except Exception:  # noqa: BLE001 - a body's cleanup must not hide the kill
                log.exception("node %s: body of %s raised while being killed", self.name, job.task_name)

    def _finalize(self, t_end: int) -> None:
        """Close open trace intervals and add records of the jobs unfinished at ``t_end``."""
        self._t_end = t_end
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
                                job.preemptions + (windows if job is running else 0), cpu, False)
                self._unfinished.append(rec)
        self.job_records.extend(self._unfinished)
        if self.trace:
            for ent in list(self.tasks.values()) + list(self.handlers.values()):
                if ent.trace_state is not None and t_end > ent.trace_since:
                    self.schedule.append((ent.name, ent.trace_state, ent.trace_since, t_end))
                    ent.trace_since = t_end

    def __repr__(self) -> str:
        return (f"<Kernel {self.name} policy={self.policy.name} tasks={len(self.tasks)} "
                f"handlers={len(self.handlers)}>")
