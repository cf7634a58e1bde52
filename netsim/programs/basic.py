"""Generic task and handler programs that scenario files name (registry kind ``"program"``).

A program is a class with a nested ``Params`` (:class:`~netsim.units.StrictModel`) for its YAML ``params:``;
the builder constructs it once per task/handler as ``Program(ctx, params)`` and the kernel calls the instance
once per job: ``instance(job)`` returns the job's generator. The numerics live in plain objects (here the
:class:`~netsim.control.pid.PID`); a program only adds the kernel requests around them (``analog_in``,
``execute``, ``send`` ...), in the order TrueTime's example code functions use:

``sampler``
    ``y = analog_in(channel)``; ``execute``; send ``y`` to ``to`` on ``network`` (or store it in the node's
    ``shared[key]`` without a network); optional ``after_send`` execution.
``controller``
    take the newest measurement (from the node inbox on ``input_network``/``network``, from ``shared[key]``, or
    ``analog_in(channel)``), read the reference signal, compute the PID/PD output, ``execute``, then send it to
    ``to`` on ``network`` or write ``output_channel``.
``actuator``
    take the newest control value from the inbox, ``execute``, ``analog_out(channel, u)``; with ``report:`` it
    then sends ``{value: u, t_ns: the instant it wrote the DAC}`` back (tag ``applied``), for a
    ``state_feedback`` estimator's ``applied_input`` (the input the plant really holds, issue 26).
``interference``
    dummy frames of ``bits`` on ``network``: per job with probability ``share`` (TrueTime's bandwidth share)
    or, with ``rate`` set, a Poisson stream from a single long-running job.
``periodic_controller``
    one-node loop: ``analog_in``, PID, ``execute``, ``analog_out`` (TrueTime's ``pid_code1``).

Message payloads are floats; messages carry ``tag`` (``"y"``/``"u"`` by default) for the messages table.

Destinations: a program that sends on ``network`` needs ``to``, the receiving node's name, or ``to: all``
(:data:`BROADCAST`) for every other node on the network. Leaving ``to`` out is an error (it used to broadcast
silently, releasing every node that consumes that network's messages).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Annotated, Any, Callable, ClassVar, Generator

from pydantic import BeforeValidator, Field, ValidationInfo, field_validator, model_validator

from netsim.control.pid import PID, PIDParams
from netsim.kernel.requests import ANALOG_IN, RECEIVE_NEWEST, Request
from netsim.registry import register
from netsim.units import QuietDefaultsModel, StrictModel, Time

if TYPE_CHECKING:
    from netsim.env import SimEnv
    from netsim.kernel.job import Job
    from netsim.kernel.kernel import Kernel
    from netsim.scenario.schema import Scenario

__all__ = [
    "BROADCAST",
    "ProgramContext",
    "Sampler",
    "Controller",
    "Actuator",
    "ActuatorReport",
    "Interference",
    "PeriodicController",
]

log = logging.getLogger(__name__)

#: The ``to:`` value that sends a message to every other node on the network.
BROADCAST = "all"


def _destination_given(to: str | None, info: ValidationInfo) -> str | None:
    """A sender on ``network`` names its destination (``to``): a node, or ``all`` to broadcast.

    Runs as the ``to`` field's validator (also when ``to`` is left out), so the error's path is ``params.to``.
    """
    network = info.data.get("network")
    if network is not None and to is None:
        raise ValueError(f"'to' is missing: name the node that receives on '{network}', or write "
                         f"'to: {BROADCAST}' to broadcast to every node on it")
    return to


def _destination_name(to: Any) -> Any:
    """``to`` is a node's name or ``all``: refuse a mapping or list with that hint (not a bare type error)."""
    if isinstance(to, (dict, list, tuple)):
        kind = "a mapping" if isinstance(to, dict) else "a list"
        raise ValueError(f"'to' is {kind}; write one node's name (e.g. 'to: actuator') or 'to: {BROADCAST}'")
    return to


#: ``to`` of a program that sends on ``network`` (declared after ``network``): required with a network.
Destination = Annotated[str | None, BeforeValidator(_destination_name), Field(default=None, validate_default=True)]


def _destination(to: str | None) -> str | None:
    """The kernel's destination for ``to`` (``None`` broadcasts)."""
    return None if to == BROADCAST else to


@dataclass
class ProgramContext:
    """What a program gets to know about where it runs.

    Attributes
    ----------
    env : netsim.env.SimEnv
    kernel : netsim.kernel.Kernel
        The node the program runs on.
    node, task : str
        Node name and task/handler name.
    execution : ExecTime | None
        The task's ``execution:`` from YAML (programs pass it to ``job.execute``).
    signals : dict
        Scenario signals (references, disturbances) by name: ``t_ns -> float``.
    scenario : Scenario | None
        The validated scenario (read-only).
    period : int | None
        The task's period in ns (``None`` for aperiodic tasks and handlers).
    spec : Any
        The task's or handler's own validated YAML entry.
    dry_run : bool
        True when ``netsim validate``'s dry run builds the program (:mod:`netsim.build.dry_run`): it never runs,
        so what it makes for the run (a control design) is left for the run's program to take.
    """

    env: SimEnv
    kernel: Kernel
    node: str
    task: str
    execution: Any
    signals: dict[str, Callable[[int], float]] = field(default_factory=dict)
    scenario: Scenario | None = None
    period: int | None = None
    spec: Any = None
    dry_run: bool = False

    def record(self, name: str, value: Any, t_ns: int | None = None) -> None:
        """Record a signal sample (see :meth:`netsim.env.SimEnv.record`)."""
        if type(value) is float:  # the common case, without the array conversion of Recorder.record
            rec = self.env.recorder
            if rec.enabled is None or name in rec.enabled or rec.wants(name):
                times = rec.times.get(name)
                if times is not None:
                    times.append(int(self.env.sim.now if t_ns is None else t_ns))
                    rec.values[name].append(value)
                    return
            else:
                return
        self.env.record(name, value, t_ns)

    @cached_property
    def execute_request(self) -> Any:
        """``job.execute(self.execution)`` built once (requests are immutable), or ``None`` without an
        execution time: for programs that yield it at every job."""
        from netsim.kernel.requests import EXECUTE, Request

        return None if self.execution is None else Request(EXECUTE, self.execution)

    def signal(self, name: str) -> Callable[[int], float]:
        """The scenario signal ``name``."""
        try:
            return self.signals[name]
        except KeyError:
            from netsim.errors import BuildError

            raise BuildError(
                f"task '{self.node}.{self.task}' refers to signal '{name}', which the scenario does not define "
                f"(known: {', '.join(sorted(self.signals)) or 'none'})"
            ) from None


Body = Generator[Any, Any, None]


def _newest(job: Job, network: str) -> Generator[Any, Any, Any]:
    """Drain the node's inbox on ``network``; return the newest message (or ``None``): one request,
    ``job.receive_newest`` (the programs below yield it directly)."""
    return (yield job.receive_newest(network))


def _value(msg: Any) -> float:
    payload = msg.payload
    if isinstance(payload, dict):
        payload = payload.get("value")
    return float(payload)


@register("program", "idle", "execute the task's execution time and nothing else (a CPU load, an ISR whose effect is not modelled)")
class Idle:
    """A program that only uses the CPU: background load tasks, or interrupt handlers kept for their timing."""

    class Params(StrictModel):
        pass

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx

    def __call__(self, job: Job) -> Body:
        if self.ctx.execution is not None:
            yield self.ctx.execute_request


@register("program", "sampler", "analog_in(channel), execute, send to `to` on `network` (or post to shared[key])")
class Sampler:
    """Time-driven sensor: sample, execute, send."""

    class Params(StrictModel):
        channel: str
        network: str | None = None
        to: Destination
        bits: int = Field(80, ge=1, le=10**9)
        priority: int = 0
        tag: str = "y"
        key: str = "y"
        after_send: Time = 0
        record_as: str | None = None

        @field_validator("to")
        @classmethod
        def _to(cls, to: str | None, info: ValidationInfo) -> str | None:
            return _destination_given(to, info)

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx
        self.p = params
        self._ain = Request(ANALOG_IN, params.channel)  # job.analog_in(channel), built once

    def __call__(self, job: Job) -> Body:
        p = self.p
        y = yield self._ain
        if p.record_as:
            self.ctx.record(p.record_as, y, job.now)
        if self.ctx.execution is not None:
            yield self.ctx.execute_request
        if p.network is not None:
            yield job.send(p.network, _destination(p.to), float(y), p.bits, priority=p.priority, tag=p.tag)
        else:
            job.shared[p.key] = float(y)
        if p.after_send:
            yield job.execute(p.after_send)


class _ControllerParams(PIDParams):
    reference: str | None = None
    channel: str | None = None
    input_network: str | None = None
    network: str | None = None
    to: Destination
    output_channel: str | None = None
    key: str = "y"
    bits: int = Field(80, ge=1, le=10**9)
    priority: int = 0
    tag: str = "u"
    record_as: str | None = None

    @field_validator("to")
    @classmethod
    def _to(cls, to: str | None, info: ValidationInfo) -> str | None:
        return _destination_given(to, info)

    @model_validator(mode="after")
    def _output(self) -> "_ControllerParams":
        if self.network is None and self.output_channel is None:
            raise ValueError("give 'network' (and 'to') to send the control signal, or 'output_channel' to write it")
        if self.network is not None and self.output_channel is not None:
            raise ValueError("give either 'network' or 'output_channel' for the control signal, not both")
        return self


@register("program", "controller", "PID/PD on a received or sampled measurement; output sent or written")
class Controller:
    """Event- or time-driven PID/PD controller node program."""

    Params = _ControllerParams

    def __init__(self, ctx: ProgramContext, params: _ControllerParams) -> None:
        self.ctx = ctx
        self.p = params
        self.pid = PID.from_params(params, ctx.period)
        self.ref = ctx.signal(params.reference) if params.reference else (lambda t: 0.0)
        self.y_last = 0.0
        # measurement source: explicit channel, else inbox of input_network / network, else shared[key]
        self.in_net = params.input_network or (params.network if params.channel is None else None)
        # the measurement request, built once: job.analog_in(channel) or job.receive_newest(in_net)
        self._measure_request = (Request(ANALOG_IN, params.channel) if params.channel is not None
                                 else Request(RECEIVE_NEWEST, self.in_net) if self.in_net is not None else None)

    def _measurement(self, job: Job, answer: Any) -> float:
        """The measurement from the answer to the measurement request (``None``: shared[key])."""
        p = self.p
        if p.channel is not None:
            return float(answer)
        if self.in_net is not None:
            if answer is None:
                log.warning("%s.%s: no measurement in the inbox at t=%d ns; reusing the last one",
                            self.ctx.node, self.ctx.task, job.now)
                return self.y_last
            return _value(answer)
        return float(job.shared.get(p.key, self.y_last))

    def __call__(self, job: Job) -> Body:
        p = self.p
        req = self._measure_request
        y = self._measurement(job, None if req is None else (yield req))
        self.y_last = y
        r = self.ref(job.now)
        u = self.pid.step(r, y)
        if self.ctx.execution is not None:
            yield self.ctx.execute_request
        if p.output_channel is not None:
            yield job.analog_out(p.output_channel, u)
        else:  # Params requires a network when there is no output_channel
            yield job.send(p.network, _destination(p.to), u, p.bits, priority=p.priority, tag=p.tag)  # type: ignore[arg-type]
        if p.record_as:
            self.ctx.record(p.record_as, u, job.now)


class ActuatorReport(StrictModel):
    """Where the actuator reports each input it applies (a ``{value, t_ns}`` message, ``t_ns`` the instant it
    wrote the DAC), for a ``state_feedback`` estimator's ``applied_input``."""

    network: str = Field(description="the network the report is sent on (the actuator's node must be on it)")
    to: str = Field(description="the node the report goes to (the controller)")
    tag: str = Field("applied", description="tag of the report message")
    bits: int = Field(64, ge=1, le=10**9, description="size of the report message in bits")
    priority: int = Field(0, description="priority of the report message on the network (medium-specific)")


@register("program", "actuator", "take the newest control value from `network`, execute, analog_out(channel)")
class Actuator:
    """Event-driven actuator: receive, execute, write the DAC."""

    class Params(QuietDefaultsModel):
        #: 'report' (issue 26) is left out while unset: resolved scenarios stay as they were
        _QUIET_DEFAULTS: ClassVar[dict[str, Any]] = {"report": None}

        network: str = Field(description="the network the control messages arrive on (the newest one is applied)")
        channel: str = Field(description="the DAC channel of the scenario's io the value is written to")
        record_as: str | None = Field(None, description="record the applied value under this name, at the "
                                                        "instant it is written")
        report: ActuatorReport | None = Field(None, description="send back {value, t_ns} of each applied input "
                                                                 "(default: none)")

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx
        self.p = params
        self._rx = Request(RECEIVE_NEWEST, params.network)  # job.receive_newest(network), built once

    def __call__(self, job: Job) -> Body:
        msg = yield self._rx
        if self.ctx.execution is not None:
            yield self.ctx.execute_request
        if msg is None:
            log.warning("%s.%s: released without a control message at t=%d ns", self.ctx.node, self.ctx.task, job.now)
            return
        u = _value(msg)
        yield job.analog_out(self.p.channel, u)
        if self.p.record_as:
            self.ctx.record(self.p.record_as, u, job.now)
        rep = self.p.report
        if rep is not None:
            yield job.send(rep.network, rep.to, {"value": u, "t_ns": int(job.now)}, rep.bits, priority=rep.priority,
                           tag=rep.tag)


@register("program", "interference", "dummy frames of `bits` on `network`: per job with probability, or at a rate")
class Interference:
    """Interfering traffic (TrueTime's interference node).

    ``netsim validate`` warns when its frames reach a node that consumes messages of that network (a task or
    handler released ``on_message``): TrueTime's interference node sends to itself.
    """

    #: Marks a source of interfering traffic for ``netsim validate``.
    interference_source = True

    class Params(StrictModel):
        network: str
        to: Destination
        bits: int = Field(80, ge=1, le=10**9)
        priority: int = 0
        share: float = Field(1.0, ge=0, le=1)
        rate: float | None = Field(None, gt=0)
        tag: str = "interference"

        @field_validator("to")
        @classmethod
        def _to(cls, to: str | None, info: ValidationInfo) -> str | None:
            return _destination_given(to, info)

        @model_validator(mode="after")
        def _check(self) -> "Interference.Params":
            if not 0.0 <= self.share <= 1.0:
                raise ValueError(f"share is a probability in [0, 1], got {self.share}")
            if self.rate is not None and not self.rate > 0:
                raise ValueError(f"rate (frames per second) must be positive, got {self.rate}")
            return self

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx
        self.p = params
        self.rng = ctx.env.rng(f"program.{ctx.node}.{ctx.task}")

    def __call__(self, job: Job) -> Body:
        p = self.p
        if p.rate is None:
            yield job.receive_newest(p.network)  # discard frames addressed to this node
            if p.share >= 1.0 or self.rng.random() < p.share:
                yield job.send(p.network, _destination(p.to), 0.0, p.bits, priority=p.priority, tag=p.tag)
            if self.ctx.execution is not None:
                yield self.ctx.execute_request
            return
        from netsim.timebase import from_seconds

        while True:
            gap = max(1, from_seconds(float(self.rng.exponential(1.0 / p.rate))))
            yield job.sleep(gap)
            yield job.receive_newest(p.network)
            yield job.send(p.network, _destination(p.to), 0.0, p.bits, priority=p.priority, tag=p.tag)


class _PeriodicControllerParams(PIDParams):
    channel: str
    output_channel: str
    reference: str | None = None
    record_as: str | None = None


@register("program", "periodic_controller", "analog_in, PID, execute, analog_out on one node (TrueTime pid_code1)")
class PeriodicController:
    """Single-node periodic PID loop."""

    Params = _PeriodicControllerParams

    def __init__(self, ctx: ProgramContext, params: _PeriodicControllerParams) -> None:
        self.ctx = ctx
        self.p = params
        self.pid = PID.from_params(params, ctx.period)
        self.ref = ctx.signal(params.reference) if params.reference else (lambda t: 0.0)

    def __call__(self, job: Job) -> Body:
        p = self.p
        r = self.ref(job.now)
        y = yield job.analog_in(p.channel)
        u = self.pid.step(r, float(y))
        if self.ctx.execution is not None:
            yield self.ctx.execute_request
        yield job.analog_out(p.output_channel, u)
        if p.record_as:
            self.ctx.record(p.record_as, u, job.now)
