"""Task/handler programs of the event-triggered multi-rate loop (registry kind ``"program"``).

``et_sensor`` (a periodic handler, timer period ``T``)
    ``y = analog_in(channel)``; ``execute``; evaluate the sensor trigger (time-triggered, PET eq (6),
    optionally OR the safety condition eq (7) / the reference-change condition eq (8)); if it fires, send
    ``{"k": k, "y": y}`` to ``to`` on ``network`` (tag ``y``).
``et_controller`` (a task released by message arrival, or periodic with ``step_on: every_period``)
    ``step_on: arrival`` (default): for each received sample: the control side (:class:`~netsim.control.cascade.ControlSide`: NUMRE,
    MRCI, DOB, built by a registered kind ``"controller"`` design such as ``hdd_et``); ``execute`` (the
    algorithm's CPU time); if eq (22) holds, send the packet ``{"k": k, "values": [u_k .. u_k+h]}``
    (tag ``u``, ``header_bits + bits_per_value * (h + 1)`` bits).
    ``step_on: every_period`` (the other reading of Case 2, no estimator only): the task is released every
    ``T`` (``release: periodic``, an ``offset`` after the sensor); it takes the messages that arrived (the
    last one wins), steps the controller on the last received measurement and checks eq (22) at every
    period. Before the first measurement it does nothing. Both readings count transmissions the same way
    (messages by tag); the controller's job count (jobs table) differs: every arrival vs every period.

    Which reading is the paper's: the text of section 3.2.4 ("the control signal ... is generated when
    beta_k = 1 (i.e. when a measurement is received by the control side)") and eq (28)'s
    ``Cc = Uc (1 - CS)`` (controller computation proportional to the *sensor* utilization) describe a
    controller that runs at arrivals: ``arrival`` is the default.
``playout_actuator`` (two handlers sharing the node's ``shared[key]`` buffer)
    ``mode: receive`` (on message): take the packet into the :class:`~netsim.control.packets.PlayoutBuffer`,
    ``execute``, ``analog_out`` the value for the current period; ``mode: tick`` (timer ``T``):
    ``analog_out`` the buffer's value for the period (current action, then the future ones, then the last
    one held). The tick also records ``record_past_end`` (default ``u_past_end``): 1 for a period played
    past the end of a packet that carries future actions (``h >= 1`` and ``j - k > h``: the paper's
    ``h >= N_max`` is violated), 0 otherwise (a packet of the current action only, ``h = 0``, is held by
    design and counts 0). The ``et_control`` metric sums it (``et.played_past_packet``).

The fast-period index is ``k = (now - offset) // period``. The requests a program yields at every job with the
same arguments (``analog_in``, ``receive``, ``execute``) are built once (requests are immutable values).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any, Generator, Literal

from pydantic import Field, model_validator

from netsim.control.cascade import CascadeActions
from netsim.control.controller_trigger import ControllerTrigger
from netsim.control.packets import ControlPacket, PlayoutBuffer
from netsim.control.triggers import (AnyOf, MaxIntervalTrigger, MixedTrigger, ReferenceChangeTrigger, SendOnDelta,
                                     SensorTrigger, TimeTriggered)
from netsim.errors import BuildError, ConfigError
from netsim.kernel import requests as rq
from netsim.kernel.requests import Request
from netsim.registry import lookup, register
from netsim.units import Duration, StrictModel, Time

if TYPE_CHECKING:
    from netsim.programs.basic import ProgramContext
    from netsim.kernel.job import Job

__all__ = ["EtSensor", "EtController", "PlayoutActuator"]

log = logging.getLogger(__name__)

Body = Generator[Any, Any, None]


@register("program", "et_sensor", "sensor handler at T: analog_in, execute, PET/TT trigger (eqs 6-8), send")
class EtSensor:
    """Sensor handler evaluating the sampling trigger every period."""

    class Params(StrictModel):
        channel: str
        network: str
        to: str | None
        period: Duration
        offset: Time = 0
        trigger: Literal["time", "pet", "send_on_delta"] = "pet"
        sigma_s: float = Field(0.0, ge=0)
        delta_s: float = Field(0.0, ge=0)
        norm: Literal["squared", "2"] = "squared"
        k_max: int | None = Field(None, ge=1, description="safety condition eq (7): send at least every k_max periods")
        reference: str | None = None
        reference_k_max: int | None = Field(None, ge=0, description="eq (8): send k_max periods after a reference change")
        bits: int = Field(64, ge=1)
        priority: int = 0
        tag: str = "y"
        record_as: str | None = "y_meas"

    @staticmethod
    def canonical_params(params: dict) -> dict:
        """``params`` (resolved YAML form) with the parameters the trigger mode ignores set to their defaults.

        ``trigger: time`` uses none of ``sigma_s``, ``delta_s``, ``norm``; ``send_on_delta`` uses ``delta_s``
        only. Runs whose parameters differ only there behave identically (the runner's baseline cache).
        """
        mode = params.get("trigger", "pet")
        inert = {"time": ("sigma_s", "delta_s", "norm"), "send_on_delta": ("sigma_s", "norm")}.get(mode, ())
        defaults = {"sigma_s": 0.0, "delta_s": 0.0, "norm": "squared"}
        for key in inert:
            if key in params:
                params[key] = defaults[key]
        return params

    def __init__(self, ctx: ProgramContext, params: "EtSensor.Params") -> None:
        self.ctx = ctx
        self.p = p = params
        base: SensorTrigger
        if p.trigger == "time":
            base = TimeTriggered()
        elif p.trigger == "pet":
            base = MixedTrigger(p.sigma_s, p.delta_s, p.norm)
        else:
            base = SendOnDelta(p.delta_s)
        members: list[SensorTrigger] = [base]
        if p.k_max is not None:
            members.append(MaxIntervalTrigger(p.k_max))
        if p.reference_k_max is not None:
            if p.reference is None:
                raise BuildError(f"{ctx.node}.{ctx.task}: reference_k_max (eq 8) needs `reference`")
            members.append(ReferenceChangeTrigger(p.reference_k_max))
        self.trigger = base if len(members) == 1 else AnyOf(members)
        self.ref = ctx.signal(p.reference) if p.reference else None
        self._read = Request(rq.ANALOG_IN, p.channel)  # job.analog_in(p.channel)
        self._exec = ctx.execute_request  # job.execute(ctx.execution), built once

    def __call__(self, job: Job) -> Body:
        p = self.p
        now = job.now
        k = (now - p.offset) // p.period
        y = float((yield self._read))
        if p.record_as:
            self.ctx.record(p.record_as, y, now)
        if self._exec is not None:
            yield self._exec
        r = self.ref(job.now) if self.ref is not None else None
        if self.trigger.should_send(k, y, r):
            yield job.send(p.network, p.to, {"k": k, "y": y}, p.bits, priority=p.priority, tag=p.tag)


@register("program", "et_controller",
          "control side on message arrival: NUMRE + MRCI (+DOB), execute, controller ET eq (22), send packet")
class EtController:
    """Controller task: one control-side update per received sample."""

    class Params(StrictModel):
        network: str
        to: str | None
        period: Duration
        offset: Time = 0
        reference: str
        design: str = Field(description="registered kind 'controller' design, e.g. hdd_et")
        design_params: dict = Field(default_factory=dict)
        controller_et: bool = True
        sigma_c: float = Field(0.0, ge=0)
        delta_c: float = Field(0.0, ge=0)
        norm: Literal["squared", "2"] = "squared"
        bits_per_value: int = Field(32, ge=1)
        header_bits: int = Field(0, ge=0)
        priority: int = 0
        tag: str = "u"
        record: bool = True
        step_on: Literal["arrival", "every_period"] = Field(
            "arrival", description="arrival: step at each received measurement (section 3.2.4, eq 28; default); "
            "every_period: a periodic task stepping every T on the last received measurement (no estimator)")

        def nested_params(self) -> list[tuple[str, Any, dict]]:
            """``(field, Params model or None, raw)`` of parameters a plugin named here validates itself: the
            ``design``'s own ``Params`` (when it declares one) checks ``design_params`` at validate, not at build."""
            try:
                factory = lookup("controller", self.design)
            except ConfigError:
                return []  # build reports the unknown design
            return [("design_params", getattr(factory, "Params", None), self.design_params)]

    @staticmethod
    def canonical_params(params: dict) -> dict:
        """``params`` with eq (22)'s thresholds and norm set to defaults when ``controller_et`` is off.

        A disabled :class:`ControllerTrigger` sends every packet whatever its thresholds (they are only checked
        to be finite numbers >= 0, so only such values are reset). Used by the runner's baseline cache.
        """
        if params.get("controller_et", True) is False:
            for key, default in (("sigma_c", 0.0), ("delta_c", 0.0)):
                v = params.get(key)
                if isinstance(v, (int, float)) and not isinstance(v, bool) and 0 <= v < float("inf"):
                    params[key] = default
            if params.get("norm") in ("squared", "2"):
                params["norm"] = "squared"
        return params

    def __init__(self, ctx: ProgramContext, params: "EtController.Params") -> None:
        self.ctx = ctx
        self.p = p = params
        factory = lookup("controller", p.design)
        r_t = ctx.signal(p.reference)
        T, off = int(p.period), int(p.offset)
        trig = ControllerTrigger(p.sigma_c, p.delta_c, p.norm, enabled=p.controller_et)
        self.side = factory(p.design_params, reference=lambda k: float(r_t(off + k * T)), trigger=trig)
        if p.step_on == "every_period" and self.side.est is not None:
            raise BuildError(f"{ctx.node}.{ctx.task}: step_on: every_period is the no-estimator reading of Case 2; "
                             "with a NUMRE (design_params.estimator) use step_on: arrival")
        self._receive = Request(rq.RECEIVE, p.network)  # job.receive(p.network)
        self._exec = ctx.execute_request  # job.execute(ctx.execution), built once
        self._last: tuple[int, float] | None = None  # every_period: last received (k, y)
        ctx.env.at_end(self._finish)

    def _finish(self, t_end: int) -> None:
        side = self.side
        if side.horizon_violations:
            log.warning("%s.%s: h=%d < N_max=%d (%d arrivals beyond the horizon): raise h (design_params.h)",
                        self.ctx.node, self.ctx.task, side.h, side.N_max, side.horizon_violations)
        self.ctx.record("numre_h_violations", float(side.horizon_violations), t_end)
        self.ctx.record("numre_N_max", float(side.N_max), t_end)

    def __call__(self, job: Job) -> Body:
        if self.p.step_on == "every_period":
            yield from self._every_period(job)
            return
        while True:
            msg = yield self._receive
            if msg is None:
                return
            payload = msg.payload
            k, y = int(payload["k"]), float(payload["y"])
            yield from self._decide(job, self.side.on_measurement(k, y))

    def _every_period(self, job: Job) -> Body:
        p = self.p
        while True:
            msg = yield self._receive
            if msg is None:
                break
            self._last = (int(msg.payload["k"]), float(msg.payload["y"]))
        if self._last is None:
            return
        k = (job.now - p.offset) // p.period
        k_y, y = self._last
        yield from self._decide(job, self.side.on_period(k, y, k_y))

    def _decide(self, job: Job, dec: Any) -> Body:
        """Record the decision, execute, and send the packet when eq (22) lets it go."""
        p = self.p
        if p.record:
            record = self.ctx.record
            now = job.now
            record("N", float(dec.N), now)
            record("y_hat", dec.y_hat, now)
            record("d_hat", dec.d_hat, now)
            record("u_hat", dec.packet.values[0], now)
        if self._exec is not None:
            yield self._exec
        if dec.send:
            pkt = dec.packet
            yield job.send(p.network, p.to, {"k": pkt.k, "values": pkt.values},
                           pkt.bits(p.bits_per_value, p.header_bits), priority=p.priority, tag=p.tag)


@register("program", "playout_actuator", "actuator: playout buffer of h-step packets; receive (on message) or tick (timer T)")
class PlayoutActuator:
    """Actuator handler: ``mode: receive`` takes packets, ``mode: tick`` plays one value per period."""

    class Params(StrictModel):
        mode: Literal["receive", "tick"]
        channel: str
        period: Duration
        offset: Time = 0
        network: str | None = None
        key: str = "playout"
        u0: float = 0.0
        record_as: str | None = "u"
        record_past_end: str | None = Field("u_past_end", description="tick mode: signal set to 1 for a period "
                                            "played past the end of an h >= 1 packet (0 otherwise)")

        @model_validator(mode="after")
        def _receive_needs_a_network(self) -> "PlayoutActuator.Params":
            # checked here so that validate refuses it, not only build (issue 14 B: validate said valid, run failed)
            if self.mode == "receive" and not self.network:
                raise ValueError("mode 'receive' needs 'network': add the network its packets arrive on")
            return self

    def __init__(self, ctx: ProgramContext, params: "PlayoutActuator.Params") -> None:
        self.ctx = ctx
        self.p = params
        if params.mode == "receive" and not params.network:
            raise BuildError(f"{ctx.node}.{ctx.task}: playout_actuator in mode 'receive' needs `network`")
        shared = ctx.kernel.shared
        if params.key not in shared:
            shared[params.key] = PlayoutBuffer(params.u0)
        self.buf: PlayoutBuffer = shared[params.key]
        self._receive = None if params.network is None else Request(rq.RECEIVE, params.network)
        self._exec = ctx.execute_request  # job.execute(ctx.execution), built once

    def __call__(self, job: Job) -> Body:
        p = self.p
        if p.mode == "receive":
            got = False
            while True:
                msg = yield self._receive  # job.receive(p.network)
                if msg is None:
                    break
                pl = msg.payload
                values = pl["values"]
                if not isinstance(values, (tuple, CascadeActions)):
                    values = tuple(values)  # a lazy cascade stays lazy: only the values played are computed
                got = self.buf.receive(ControlPacket(int(pl["k"]), values)) or got
            if not got:
                return
        if self._exec is not None:
            yield self._exec
        now = job.now
        j = (now - p.offset) // p.period
        buf = self.buf
        u = buf.value(j)
        yield job.analog_out(p.channel, u)
        if p.record_as:
            self.ctx.record(p.record_as, u, now)
        if p.mode == "tick" and p.record_past_end:
            pkt = buf.packet
            past = pkt is not None and pkt.horizon > 0 and j - pkt.k > pkt.horizon
            self.ctx.record(p.record_past_end, 1.0 if past else 0.0, now)
