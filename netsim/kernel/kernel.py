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

Where the code is
-----------------
:class:`Kernel` is assembled from one part per concern (mixins: the hot paths call each other as plain
methods, with no extra indirection):

- this module: the run-time API (releases, invocations, triggers, message delivery, kills), the event-loop
  callbacks of releases, timers, sleeps and deadlines, and ending jobs (their :class:`JobRecord`);
- :mod:`netsim.kernel.building`: creating tasks, handlers, timers, triggers and loads, wiring I/O (build time);
- :mod:`netsim.kernel.dispatch`: who holds the CPU, CPU segments, preemption, context switches, accounting;
- :mod:`netsim.kernel.interpreter`: running body code, one method per request;
- :mod:`netsim.kernel.trace`: the schedule trace, ``cpu_time``/``utilization`` and end-of-run finalisation.

A job reaches its kernel only through a :class:`~netsim.kernel.job.JobContext`.
"""

from __future__ import annotations

import logging
from collections import deque
from heapq import heappush
from typing import Any, Callable

from netsim.env import SimEnv
from netsim.errors import BuildError, SimulationError
from netsim.kernel.arrivals import Arrivals
from netsim.kernel.building import KernelBuilder
from netsim.kernel.dispatch import Dispatcher
from netsim.kernel.events import DEADLINE, NORMAL, URGENT, schedule_call
from netsim.kernel.interpreter import Interpreter
from netsim.kernel.job import Job, JobContext
from netsim.kernel.load import PeriodicLoad
from netsim.kernel.monitor import monitor_killed
from netsim.kernel.multicore import MulticoreDispatcher
from netsim.kernel.node_sync import NodeSync
from netsim.kernel.policies import Policy, resolve_policy
from netsim.kernel.records import JobRecord, deadline_verdict
from netsim.kernel.states import BLOCKED, DONE, NEW, READY
from netsim.kernel.task import Handler, Task, check_time, did_you_mean
from netsim.kernel.timers import Timer, Trigger
from netsim.kernel.trace import Tracing
from netsim.network.message import Message

__all__ = ["Kernel"]

log = logging.getLogger(__name__)

#: Rank of a periodic load's real invocation at a tick: above every handler.
_WINDOW_RANK = (-1, 0)


class Kernel(KernelBuilder, Dispatcher, Interpreter, Tracing, Arrivals):
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
    cores, multicore, migration_cost, speed, speed_levels
        Cores, ``"global"``/``"partitioned"``, migration cost (:mod:`netsim.kernel.multicore`); initial CPU
        speed (``None``: no scaling) and the speeds :meth:`set_speed` accepts (:mod:`netsim.kernel.speed`).

    Attributes
    ----------
    shared : dict
        Per-node state shared by the node's bodies.
    sync : NodeSync
        The node's named mailboxes, semaphores, events and monitors (``nodes.<n>.sync`` in a scenario).
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

    def __new__(cls, *args: Any, cores: int = 1, speed: float | None = None, **kwargs: Any) -> "Kernel":
        """A :class:`MulticoreKernel` for ``cores > 1`` or a ``speed`` (its dispatcher chosen at build time)."""
        return object.__new__(MulticoreKernel if cls is Kernel and (cores != 1 or speed is not None) else cls)

    def __init__(self, env: SimEnv, name: str, policy: "str | Policy" = "fp", context_switch: int = 0, *,
                 trace: bool = True, livelock_limit: int = 200_000, cores: int = 1, multicore: str = "global",
                 migration_cost: int = 0, speed: float | None = None,
                 speed_levels: "list[float] | None" = None) -> None:
        if not isinstance(name, str) or not name:
            raise BuildError(f"kernel name must be a non-empty string, got {name!r}")
        if cores != 1 or speed is not None:  # Kernel(...) makes a MulticoreKernel for these (see __new__)
            raise BuildError(f"node '{name}': cores and speed need a MulticoreKernel (subclass that one)")
        self.env = env
        self._sim = env.sim
        self.name = name
        self.policy = resolve_policy(policy, name)
        self.context_switch = check_time(name, "<kernel>", "context_switch", context_switch) or 0
        self.trace = bool(trace)
        self.livelock_limit = int(livelock_limit)
        self.shared: dict[str, Any] = {}
        self.sync = NodeSync(name)
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
        self._routes: dict[str, tuple] = {}  # per network: (inbox, handler, task, label); building.py _route
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
        self._ctx = JobContext(self, name, self._sim, self.shared, self.rng, self._unblock)
        self._zt_time = -1
        self._zt_count = 0
        self._zt_names: dict[str, int] = {}
        self._unfinished: list[JobRecord] = []
        self._t_end: int | None = None
        self.switches = 0
        self.switch_time = 0
        self.segments = 0
        self.halted = False  # halt(): the node stopped for good (its battery ran out, netsim.energy)
        self.servers: dict[str, Any] = {}  # CBS/TBS servers by name (netsim.kernel.servers)
        self.cores = 1  # a MulticoreKernel sets its own (netsim.kernel.multicore)
        self.speed = 1.0  # CPU speed; changed only by a kernel with speed scaling (set_speed)
        # the event loop's heap and id counter: wake-ups are call entries pushed on it (kernel.events)
        _, self._queue, self._eid = env.sim.scheduler()
        schedule_call(self._sim, 0, URGENT, self._on_start)
        env.at_end(self._finalize)

    # ================================================================= run-time API
    @property
    def now(self) -> int:
        """Current simulation time in ns."""
        return self._sim.now

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
        if self.halted:
            self._kill(job)
        self._request_dispatch_deferred()
        return job

    def invoke_handler(self, handler: str, data: Any = None, invoker: str | None = None) -> Job:
        """Raise the interrupt of ``handler`` now (queued if it is already queued or running)."""
        job = self._invoke(self._get(self.handlers, handler, "handler"), data, invoker)
        if self.halted:
            self._kill(job)
        self._request_dispatch_deferred()
        return job

    def trigger(self, name: str, data: Any = None) -> bool:
        """An edge on external trigger ``name``; returns ``False`` if ignored by its minimum inter-arrival."""
        trig = self._get(self.triggers, name, "trigger")
        if self.halted:
            return False
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
        if self.halted:
            return
        route = self._routes.get(network)
        if route is None:
            route = self._route(network)
        inbox, handler, task, label = route
        inbox.append(msg)
        if handler is not None:
            self._invoke(handler, msg, label)
        elif task is not None:
            self._release(task, msg)
        else:
            return  # no bound target: the message only waits in the inbox
        # deferred: a medium may act after deliver in the same callback (the pipeline delivers every copy of a
        # frame, CAN arbitrates after delivering), and a receiver's zero-time code must run after all of it
        self._request_dispatch_deferred()

    def kill_job(self, job: Job) -> None:
        """End ``job`` now: it frees the CPU, its record is marked killed, its task's next job may start."""
        if job._state == DONE:
            return
        if job._ctx is not self._ctx:
            job._ctx.kernel.kill_job(job)
            return
        self._kill(job)
        self._request_dispatch_deferred()

    def halt(self) -> None:
        """Stop the node for good (its battery ran out: :mod:`netsim.energy`).

        Every unfinished job is killed now (its record says killed), timers stop, and from now on no task is
        released, no trigger is accepted and received messages are ignored; a job created from program code
        is killed at once.
        """
        if self.halted:
            return
        self.halted = True
        entities: list[Handler | Task] = [*self.handlers.values(), *self.tasks.values()]
        for ent in entities:
            for job in list(ent.queue):
                self._kill(job)
            if ent.active is not None:
                self._kill(ent.active)
        for timer in self.timers.values():
            timer.active = False


    # ================================================================= releases and invocations
    def _get(self, table: dict[str, Any], name: str, what: str) -> Any:
        obj = table.get(name)
        if obj is None:
            raise SimulationError(f"node '{self.name}': no {what} '{name}'{did_you_mean(str(name), table)}")
        return obj

    def _release(self, task: Task, data: Any, nominal: int | None = None) -> Job:
        """Release a job of ``task`` now; ``nominal``: its nominal release (a jittered arrival, see
        :mod:`netsim.kernel.arrivals`), from which its release time and deadline count."""
        now = self._sim.now
        spec = task.spec
        jid = task.released
        task.released = jid + 1
        if nominal is None:
            deadline = None if spec.deadline is None else now + spec.deadline
            job = Job(self._ctx, task, jid, task.data if data is None else data, now, deadline)
        else:  # a jittered arrival: release and deadline count from the nominal release
            deadline = None if spec.deadline is None else nominal + spec.deadline
            job = Job(self._ctx, task, jid, task.data if data is None else data, nominal, deadline)
            job.arrival = now
        key = task.key
        if key is None:
            key = self.policy.key(job)
            if self.policy.static:
                task.key = key
        job._rank = job._base_rank = (1, key)
        job._np = not (spec.preemptible and self.policy.preemptive)
        job._budget = spec.wcet
        if task.server is not None:  # served by a CBS or TBS: the server ranks the job (netsim.kernel.servers)
            task.server.arrive(job)
        if task.watch_deadline and deadline is not None:  # a deadline handler or abort_on_miss
            at = deadline if nominal is None or deadline > now else now  # a jitter may pass the deadline
            heappush(self._queue, (at, DEADLINE, next(self._eid), (self._on_deadline, job)))
        if task.active is None:
            task.active = job
            self._make_ready(job, now)
        else:
            task.queue.append(job)
        return job

    def _invoke(self, handler: Handler, data: Any, invoker: str | None) -> Job:
        now = self._sim.now
        job = Job(self._ctx, handler, handler.invocations, handler.data if data is None else data, now, None, True,
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

    # ================================================================= simpy callbacks
    def _on_start(self, _ev: Any) -> None:
        self.validate()

    def _on_periodic_release(self, ev: tuple) -> None:
        task: Task = ev[1]
        if self.halted:
            return
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
        task = job._task
        if task.deadline_handler is not None or not task.spec.abort_on_miss:
            self._fire_overrun(task.deadline_handler, job, "deadline")
        if task.spec.abort_on_miss and job.finish is None:
            self._kill(job)  # abort on deadline miss: the record is killed (and so missed)
        self._request_dispatch()

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
            # a jittered job's arrival is added to its record by Arrivals._fill_arrivals (end of the run): no
            # work here for the jobs of other tasks
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
        if job._held is not None:  # it used a monitor: release what it owns, leave what it waits for
            monitor_killed(self, job)
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


    def __repr__(self) -> str:
        return (f"<Kernel {self.name} policy={self.policy.name} tasks={len(self.tasks)} "
                f"handlers={len(self.handlers)}>")


class MulticoreKernel(MulticoreDispatcher, Kernel):
    """A kernel with several cores and/or speed scaling (:mod:`netsim.kernel.multicore`); ``Kernel(...)`` makes it."""

    def __init__(self, env: SimEnv, name: str, policy: "str | Policy" = "fp", context_switch: int = 0, *,
                 trace: bool = True, livelock_limit: int = 200_000, **cpu: Any) -> None:
        super().__init__(env, name, policy, context_switch, trace=trace, livelock_limit=livelock_limit)
        self._setup_cpu(**cpu)
