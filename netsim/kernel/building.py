"""Building a kernel: creating tasks, handlers, timers and triggers, and wiring I/O and networks.

:class:`KernelBuilder` is the build-time half of :class:`~netsim.kernel.kernel.Kernel` (a mixin): every
method validates its arguments and raises a :class:`~netsim.errors.BuildError` naming the node, the task
and the field to change, before anything runs.
"""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING, Any, Callable

from netsim.errors import BuildError
from netsim.kernel.events import NORMAL, schedule_call
from netsim.kernel.load import PeriodicLoad
from netsim.kernel.task import (CheckedTask, Handler, HandlerSpec, Task, TaskSpec, check_body, check_time,
                                did_you_mean, task_error)
from netsim.kernel.timers import Timer, Trigger
from netsim.timebase import format_time

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.job import Job

__all__ = ["KernelBuilder", "task_spec"]


def task_spec(node: str, name: str, **fields: Any) -> CheckedTask:
    """``TaskSpec(name, **fields).checked(node)``: the checked description of a task, as
    :meth:`KernelBuilder.create_task` makes it (fields in integer ns; a scenario's task is checked as it is).

    Raises
    ------
    BuildError
        From :func:`~netsim.kernel.task.task_error` (with ``node``, ``task`` and ``field`` attributes).
    """
    return TaskSpec(name, **fields).checked(node)


class KernelBuilder:
    """Build-time methods of a kernel (mixed into :class:`~netsim.kernel.kernel.Kernel`)."""

    # provided by Kernel
    name: str
    policy: Any
    tasks: dict[str, Task]
    handlers: dict[str, Handler]
    timers: dict[str, Timer]
    triggers: dict[str, Trigger]
    loads: dict[str, PeriodicLoad]
    _load: PeriodicLoad | None
    segments: int
    networks: dict[str, Any]
    _sim: Any
    _inboxes: dict[str, deque[Any]]
    _bindings: dict[str, str]
    _routes: dict[str, tuple]
    _ain: dict[str, Callable[[int], Any]]
    _aout: dict[str, Callable[[int, Any], None]]
    _schedule_first_release: Callable[[Task], None]
    _on_timer: Callable[[Any], None]
    _get: Callable[..., Any]

    def create_task(self, name: str, body: Callable[[Job], Any], *, period: int | None = None, offset: int = 0,
                    deadline: int | None = None, priority: int | float | None = None, wcet: int | None = None,
                    preemptible: bool = True, data: Any = None,
                    wcet_handler: "str | Callable[[Job], Any] | None" = None,
                    deadline_handler: "str | Callable[[Job], Any] | None" = None) -> Task:
        """Create a periodic (``period`` set) or aperiodic task.

        Parameters
        ----------
        name
            Unique name on this node (tasks and handlers share one name space).
        body
            Generator function ``body(job)``, called once per job.
        period, offset, deadline
            Period and first release (ns, periodic tasks; the first release is ``offset`` after the task is
            created, normally at t = 0); relative deadline (default: the period; none for an aperiodic
            task unless given). Handler names in ``wcet_handler``/``deadline_handler``, timers and
            bindings are checked by :meth:`validate`, which runs automatically at the start of the run.
        priority
            Fixed priority (lower = more urgent), required by ``fp``.
        wcet
            Execution budget per job (ns); exceeding it fires ``wcet_handler``.
        preemptible
            ``False``: a started job is preempted only by interrupt handlers.
        data
            Default ``job.data`` for jobs released without data.
        wcet_handler, deadline_handler
            A handler name (invoked with the overrunning job as data) or a callable ``fn(job)`` run at
            the overrun instant.

        Raises
        ------
        BuildError
            Naming the task and field for an invalid value.
        """
        return self.add_task(TaskSpec(name, period=period, offset=offset, deadline=deadline, priority=priority,
                                      wcet=wcet, preemptible=preemptible, wcet_handler=wcet_handler,
                                      deadline_handler=deadline_handler), body, data)

    def add_task(self, spec: TaskSpec, body: Callable[[Job], Any], data: Any = None) -> Task:
        """Create the task ``spec`` describes (:meth:`create_task` with the description in one object).

        Raises
        ------
        BuildError
            Naming the task and field for an invalid value (:meth:`TaskSpec.checked`, then the policy's
            ``check``).
        """
        node = self.name
        name = spec.name
        if not isinstance(name, str) or not name:
            raise BuildError(f"node '{node}': task name must be a non-empty string, got {name!r}")
        if name in self.tasks or name in self.handlers:
            raise task_error(node, name, "name", "is already used by another task or handler on this node")
        check_body(node, name, body)
        checked = spec.checked(node)
        self.policy.check(node, checked)
        task = Task(checked, body, data)
        self.tasks[name] = task
        self._routes.clear()
        if checked.self_released:
            self._schedule_first_release(task)
        return task

    def create_handler(self, name: str, body: Callable[[Job], Any], *, priority: int | float = 0, latency: int = 0,
                       data: Any = None) -> Handler:
        """Create an interrupt handler.

        Parameters
        ----------
        name
            Unique name on this node.
        body
            Generator function ``body(job)``, called once per invocation; ``job.data`` is the invocation
            data (the message, the trigger data, the overrunning job) or ``data``.
        priority
            Among handlers (lower = more urgent); every handler beats every task.
        latency
            ISR entry latency: CPU time (ns) spent at each invocation before the code runs.
        """
        return self.add_handler(HandlerSpec(name, priority, latency), body, data)

    def add_handler(self, spec: HandlerSpec, body: Callable[[Job], Any], data: Any = None) -> Handler:
        """Create the interrupt handler ``spec`` describes (:meth:`create_handler` with the description in one
        object)."""
        node = self.name
        name = spec.name
        if not isinstance(name, str) or not name:
            raise BuildError(f"node '{node}': handler name must be a non-empty string, got {name!r}")
        if name in self.tasks or name in self.handlers:
            raise task_error(node, name, "name", "is already used by another task or handler on this node")
        check_body(node, name, body)
        handler = Handler(spec.checked(node), body, data)
        self.handlers[name] = handler
        self._routes.clear()
        return handler

    def create_timer(self, name: str, handler: str, *, period: int | None = None, start: int = 0,
                     data: Any = None) -> Timer:
        """A timer invoking ``handler`` at absolute time ``start``, then every ``period`` ns if given."""
        node = self.name
        if name in self.timers:
            raise task_error(node, name, "name", "is already used by another timer on this node")
        period_ns = check_time(node, name, "period", period, positive=True, allow_none=True)
        start_ns = check_time(node, name, "start", start)
        assert start_ns is not None
        now = self._sim.now
        if start_ns < now:
            raise task_error(node, name, "start", f"{format_time(start_ns)} is in the past (now {format_time(now)})")
        if not isinstance(handler, str):
            raise task_error(node, name, "handler", f"must be a handler name, got {handler!r}")
        timer = Timer(name, handler, period_ns, start_ns, data)
        self.timers[name] = timer
        schedule_call(self._sim, start_ns - now, NORMAL, self._on_timer, timer)
        return timer

    def create_periodic_load(self, name: str, *, period: int, execution: int, start: int = 0,
                             handler: str | None = None) -> PeriodicLoad:
        """A periodic interrupt load accounted in closed form: a fast ISR without one event per tick.

        It means: an interrupt handler of constant ``execution`` fires at ``t_k = start + k * period`` for
        every ``k >= 0``; between real invocations it does nothing observable except take the CPU during
        its *windows* ``[t_k, t_k + execution)``. The results (job release/start/finish/response times,
        preemption counts, CPU times, utilization) equal those of an explicit handler with that execution
        time, invoked by a timer of that period, that is more urgent than every other handler of the node
        -- at the cost of a few integer operations per segment instead of one invocation per tick.

        Semantics
        ---------
        - **CPU time taken.** A segment (execution, context switch, ISR latency) of any task or other handler
          that needs ``R`` ns from ``t`` ends at the smallest ``t'`` with ``(t' - t) - stolen(t, t') = R``
          (``stolen``: overlap with the windows); one that ends just before a window ends at the window's
          start ``t_k``, where its following code runs (as with an explicit handler, whose tick comes after
          the code of a segment ending at the same instant). A preemption at ``t''`` credits
          ``(t'' - t) - stolen(t, t'')`` of progress.
        - **Dispatch.** Inside a window nothing but the tick's real invocation (below) gets the CPU: a
          dispatch that would start, resume or switch a job is deferred to the window's end (a job that
          held the CPU is preempted at once, as the explicit handler would have done at ``t_k``). So job
          start times and the instants at which job code runs are those of the explicit model.
        - **Preemption counts.** Every window that falls inside a job's segment counts as one preemption of
          the job (as the explicit handler preempts it at each tick); a preemption by the dispatcher at the
          end of a window that already preempted the job is the same preemption, not a second one.
        - **CPU accounting.** ``cpu_time[name]`` is ``execution`` times the windows elapsed (the last one
          partially), and the windows count as busy time in :meth:`utilization`. If ``name`` is also a
          handler's name, that handler's own CPU time is added to the same entry.
        - **Schedule trace.** The windows are not listed one by one: a task's ``"running"`` interval spans
          the windows it was interrupted by (an explicit model would show it ``"ready"`` during each).
          ``kernel.loads[name].windows(t0, t1)`` lists them for a drawing.
        - **The real handler at a tick** (``handler``): an exact-mode sensor ISR is invoked only at the ticks
          where it has something to do. An invocation of ``handler`` at a tick ``t_k`` *is* that tick's
          window, not an extra one: it is made the most urgent job of the node, its code runs at ``t_k``,
          its execution inside the window is the window's CPU time (not charged again to ``handler``), and
          only execution beyond the window's end is charged as ordinary handler time. If its execution
          equals ``execution`` (the intended use) the result equals the explicit model exactly. Invocations
          at other instants, and a second invocation at the same tick, are ordinary invocations.

        Approximations (documented, not checked): the load is treated as more urgent than every handler of
        the node, so a handler with a more urgent priority is interrupted by the windows instead of
        delaying them; a real invocation at a tick that cannot start before its window ends (its handler
        still busy with an earlier invocation) runs as an ordinary invocation, its window still counted.
        At most one load per node.

        Parameters
        ----------
        name
            Name of the load (its entry in ``cpu_time``); must not be a task's name, and may be a handler's
            name only if it is ``handler``.
        period, execution
            Tick period and constant execution per tick, ns (``0 < execution < period``).
        start
            First tick (absolute time, ns).
        handler
            Optional name of the node's handler whose invocations at ticks are the windows (checked when
            the run starts).

        Raises
        ------
        BuildError
            Naming the load and the field to change.
        """
        node = self.name
        if not isinstance(name, str) or not name:
            raise BuildError(f"node '{node}': periodic load name must be a non-empty string, got {name!r}")
        if self.loads:
            other = next(iter(self.loads))
            raise task_error(node, name, "name", f"node already has the periodic load '{other}'; at most one "
                             "per node (merge them into one handler, or model the others explicitly)")
        if self.segments:
            raise task_error(node, name, "name", "periodic loads must be created before the node runs")
        period_ns = check_time(node, name, "period", period, positive=True)
        exec_ns = check_time(node, name, "execution", execution, positive=True)
        start_ns = check_time(node, name, "start", start)
        assert period_ns is not None and exec_ns is not None and start_ns is not None
        if exec_ns >= period_ns:
            raise task_error(node, name, "execution", f"{format_time(exec_ns)} must be less than the period "
                             f"({format_time(period_ns)}); "
                             "the load would take the whole CPU")
        now = self._sim.now
        if start_ns < now:
            raise task_error(node, name, "start", f"{format_time(start_ns)} is in the past (now {format_time(now)})")
        if handler is not None and not isinstance(handler, str):
            raise task_error(node, name, "handler", f"must be a handler name or None, got {handler!r}")
        load = PeriodicLoad(name, period_ns, exec_ns, start_ns, handler)
        self.loads[name] = load
        self._load = load
        return load

    def cancel_timer(self, name: str) -> None:
        """Stop timer ``name`` (pending expiries are discarded)."""
        self._get(self.timers, name, "timer").active = False

    def create_trigger(self, name: str, handler: str, *, min_interarrival: int = 0) -> Trigger:
        """An external interrupt input ``name`` invoking ``handler``; edges closer than ``min_interarrival``
        ns to the last accepted one are ignored (counted in ``Trigger.ignored``)."""
        node = self.name
        if name in self.triggers:
            raise task_error(node, name, "name", "is already used by another trigger on this node")
        mia = check_time(node, name, "min_interarrival", min_interarrival)
        assert mia is not None
        if not isinstance(handler, str):
            raise task_error(node, name, "handler", f"must be a handler name, got {handler!r}")
        trig = Trigger(name, handler, mia)
        self.triggers[name] = trig
        return trig

    def bind_receive(self, network: str, target: str) -> None:
        """On each message arriving on ``network``: queue it in ``inbox(network)``, then invoke the handler
        ``target`` or release a job of the task ``target`` (the message is also the job's ``data``)."""
        if network in self._bindings:
            raise BuildError(f"node '{self.name}': network '{network}' is already bound to "
                             f"'{self._bindings[network]}'")
        if not isinstance(target, str):
            raise BuildError(f"node '{self.name}': bind_receive target must be a task or handler name, "
                             f"got {target!r}")
        self._bindings[network] = target
        self._inboxes.setdefault(network, deque())
        self._routes.clear()

    def _route(self, network: str) -> tuple[deque[Any], Handler | None, Task | None, str]:
        """Where a message arriving on ``network`` goes, looked up once and kept by ``deliver`` until a binding,
        task or handler is added: its inbox, the bound handler or task (``None``, ``None``: unbound), and the
        invoker label of a handler's jobs."""
        inbox = self._inboxes.get(network)
        if inbox is None:
            inbox = self._inboxes[network] = deque()
        target = self._bindings.get(network)
        handler = None if target is None else self.handlers.get(target)
        task = None if target is None or handler is not None else self._get(self.tasks, target, "task")
        route = self._routes[network] = (inbox, handler, task, f"network:{network}")
        return route

    def attach_network(self, net: Any) -> None:
        """Make ``net`` (with ``.name`` and ``.send(msg)``) available to ``job.send``."""
        self.networks[net.name] = net
        self._inboxes.setdefault(net.name, deque())

    def attach_analog_in(self, channel: str, read: Callable[[int], Any]) -> None:
        """Analog input ``channel``: ``read(t_ns)`` returns the value seen by ``job.analog_in``."""
        self._ain[channel] = read

    def attach_analog_out(self, channel: str, write: Callable[[int, Any], None]) -> None:
        """Analog output ``channel``: ``job.analog_out`` calls ``write(t_ns, value)``."""
        self._aout[channel] = write

    def validate(self) -> None:
        """Check every reference to a handler or task by name (called automatically at time 0).

        Raises
        ------
        BuildError
            Naming the referring timer, trigger, task or binding, with a suggestion.
        """
        handlers = self.handlers
        for timer in self.timers.values():
            if timer.handler not in handlers:
                raise task_error(self.name, timer.name, "handler",
                                 f"unknown handler '{timer.handler}'{did_you_mean(timer.handler, handlers)}")
        for trig in self.triggers.values():
            if trig.handler not in handlers:
                raise task_error(self.name, trig.name, "handler",
                                 f"unknown handler '{trig.handler}'{did_you_mean(trig.handler, handlers)}")
        for task in self.tasks.values():
            for field, ref in (("wcet_handler", task.wcet_handler), ("deadline_handler", task.deadline_handler)):
                if isinstance(ref, str) and ref not in handlers:
                    raise task_error(self.name, task.name, field,
                                     f"unknown handler '{ref}'{did_you_mean(ref, handlers)}")
        for load in self.loads.values():
            if load.name in self.tasks:
                raise task_error(self.name, load.name, "name", "is the name of a task; give the load its own "
                                 "name (or its handler's)")
            if load.name in handlers and load.name != load.handler:
                raise task_error(self.name, load.name, "name", f"is the name of handler '{load.name}' but the "
                                 "load's handler is "
                                 f"{repr(load.handler) if load.handler else 'not set'}; set handler= or rename")
            if load.handler is not None and load.handler not in handlers:
                raise task_error(self.name, load.name, "handler",
                                 f"unknown handler '{load.handler}'{did_you_mean(load.handler, handlers)}")
        for network, target in self._bindings.items():
            if target not in handlers and target not in self.tasks:
                known = list(handlers) + list(self.tasks)
                raise BuildError(f"node '{self.name}': bind_receive('{network}', '{target}'): no task or "
                                 f"handler '{target}'{did_you_mean(target, known)}")
