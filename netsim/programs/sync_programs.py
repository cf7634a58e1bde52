"""Programs that use the node's named mailboxes, semaphores, events and monitors (``nodes.<n>.sync``).

``mailbox_sampler``
    ``y = analog_in(channel)``; ``execute``; ``post`` ``y`` to ``mailbox`` (blocking while it is full, or dropping
    the sample with ``blocking: false``).
``mailbox_controller``
    ``y = fetch(mailbox)`` (blocking until a sample is there); inside ``monitor`` (if given) read the reference,
    compute the PID output and ``execute``; then ``analog_out(output_channel, u)``.
``critical_section``
    a load that shares resources: optionally ``wait`` for ``wait_event``; ``execute(before)``; ``enter(monitor)``
    and/or ``take(semaphore)``; ``execute(inside)`` (default: the task's ``execution``); ``give``/``exit``;
    ``execute(after)``; optionally ``notify`` ``notify_event`` (every waiter).

Each declares its :class:`SyncTiming` (``timing(params, execution_ns, node)``) for ``netsim analyze``: its
execution time, its critical sections (for the RTA blocking term) and the objects it may block on (a task
that suspends has no RTA bound of its own).

Their name parameters are typed :data:`~netsim.kernel.node_sync.MailboxName` (and ``MonitorName`` ...), so
``netsim validate`` checks each against the node's declarations; a plugin program does the same by typing its
own parameters so.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generator

from netsim.control.pid import PID, PIDParams
from netsim.kernel.node_sync import EventName, MailboxName, MonitorName, SemaphoreName
from netsim.programs.basic import ProgramContext
from netsim.registry import register
from netsim.units import StrictModel, Time

if TYPE_CHECKING:
    from netsim.kernel.job import Job

__all__ = ["SyncTiming", "MailboxSampler", "MailboxController", "CriticalSectionProgram"]

Body = Generator[Any, Any, None]


@dataclass(frozen=True)
class SyncTiming:
    """What the response-time analysis needs of a program that uses sync objects.

    Attributes
    ----------
    wcet : int | None
        Worst-case execution time of a job (ns); ``None``: unknown (an unbounded ``execution``).
    sections : dict[str, int]
        Monitor name -> longest execution inside it (ns).
    suspends_on : tuple[str, ...]
        The mailboxes, semaphores or events a job may block on (self-suspension: no RTA bound of its own).
    """

    wcet: int | None
    sections: dict[str, int] = field(default_factory=dict)
    suspends_on: tuple[str, ...] = ()


def _capacity(node: Any, mailbox: str) -> int | None:
    sync = getattr(node, "sync", None)
    decl = None if sync is None else sync.mailboxes.get(mailbox)
    return None if decl is None else decl.capacity


@register("program", "mailbox_sampler", "analog_in(channel), execute, post the sample to `mailbox` (nodes.<n>.sync)")
class MailboxSampler:
    """Producer: sample, execute, post to a mailbox of the node."""

    class Params(StrictModel):
        channel: str
        mailbox: MailboxName
        blocking: bool = True
        record_as: str | None = None

    @staticmethod
    def timing(params: Any, execution: int | None, node: Any) -> SyncTiming:
        """The task's execution; it blocks only on a bounded mailbox with ``blocking: true``."""
        full = params.blocking and _capacity(node, params.mailbox) is not None
        return SyncTiming(execution, {},
                          (f"mailbox '{params.mailbox}' (post while full)",) if full else ())

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx
        self.p = params
        self.mailbox = ctx.kernel.sync.mailbox(params.mailbox)
        #: Samples dropped because the mailbox was full (``blocking: false``).
        self.dropped = 0

    def __call__(self, job: Job) -> Body:
        p = self.p
        y = float((yield job.analog_in(p.channel)))
        if p.record_as:
            self.ctx.record(p.record_as, y, job.now)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        if p.blocking:
            yield job.post(self.mailbox, y)
        elif not (yield job.try_post(self.mailbox, y)):
            self.dropped += 1


class _MailboxControllerParams(PIDParams):
    mailbox: MailboxName
    output_channel: str
    reference: str | None = None
    monitor: MonitorName | None = None
    record_as: str | None = None


@register("program", "mailbox_controller",
          "fetch y from `mailbox`, PID inside `monitor` (optional), analog_out(output_channel)")
class MailboxController:
    """Consumer: a PID controller fed by a mailbox, computing inside a monitor."""

    Params = _MailboxControllerParams

    @staticmethod
    def timing(params: Any, execution: int | None, node: Any) -> SyncTiming:
        """The task's execution, all of it inside the monitor; it blocks on the mailbox until a sample is there."""
        sections = {params.monitor: execution or 0} if params.monitor is not None and execution is not None else {}
        return SyncTiming(execution, sections, (f"mailbox '{params.mailbox}' (fetch while empty)",))

    def __init__(self, ctx: ProgramContext, params: _MailboxControllerParams) -> None:
        self.ctx = ctx
        self.p = params
        self.pid = PID.from_params(params, ctx.period)
        self.ref = ctx.signal(params.reference) if params.reference else (lambda t: 0.0)
        self.mailbox = ctx.kernel.sync.mailbox(params.mailbox)
        self.monitor = None if params.monitor is None else ctx.kernel.sync.monitor(params.monitor)

    def __call__(self, job: Job) -> Body:
        p = self.p
        y = float((yield job.fetch(self.mailbox)))
        if self.monitor is not None:
            yield job.enter(self.monitor)
        u = self.pid.step(self.ref(job.now), y)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        if self.monitor is not None:
            yield job.exit(self.monitor)
        yield job.analog_out(p.output_channel, u)
        if p.record_as:
            self.ctx.record(p.record_as, u, job.now)


@register("program", "critical_section",
          "execute before, inside `monitor`/`semaphore`, after; optional wait_event / notify_event")
class CriticalSectionProgram:
    """A load that shares a resource: the piece of it inside the monitor (or semaphore) is the critical section."""

    class Params(StrictModel):
        monitor: MonitorName | None = None
        semaphore: SemaphoreName | None = None
        wait_event: EventName | None = None
        notify_event: EventName | None = None
        before: Time = 0
        inside: Time | None = None
        after: Time = 0

    @staticmethod
    def timing(params: Any, execution: int | None, node: Any) -> SyncTiming:
        """``before + inside + after``; ``inside`` is a section of the monitor (and a wait on the semaphore)."""
        inside = execution if params.inside is None else int(params.inside)
        waits = tuple(f"{what} '{name}'" for what, name in (("semaphore", params.semaphore),
                                                               ("event", params.wait_event)) if name is not None)
        if inside is None:
            return SyncTiming(None, {}, waits)
        sections = {params.monitor: inside} if params.monitor is not None else {}
        return SyncTiming(int(params.before) + inside + int(params.after), sections, waits)

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.p = params
        sync = ctx.kernel.sync
        self.monitor = None if params.monitor is None else sync.monitor(params.monitor)
        self.semaphore = None if params.semaphore is None else sync.semaphore(params.semaphore)
        self.wait_event = None if params.wait_event is None else sync.event(params.wait_event)
        self.notify_event = None if params.notify_event is None else sync.event(params.notify_event)
        self.inside = ctx.execution if params.inside is None else params.inside

    def __call__(self, job: Job) -> Body:
        p = self.p
        if self.wait_event is not None:
            yield job.wait(self.wait_event)
        if p.before:
            yield job.execute(p.before)
        if self.monitor is not None:
            yield job.enter(self.monitor)
        if self.semaphore is not None:
            yield job.take(self.semaphore)
        if self.inside is not None:
            yield job.execute(self.inside)
        if self.semaphore is not None:
            yield job.give(self.semaphore)
        if self.monitor is not None:
            yield job.exit(self.monitor)
        if p.after:
            yield job.execute(p.after)
        if self.notify_event is not None:
            yield job.notify(self.notify_event, all=True)
