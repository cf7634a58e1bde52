"""Task and handler programs of the cart node (registry kind ``program``).

``cart_encoder_isr`` (an interrupt handler)
    The encoder ISR of section VI-A. It drops ``q`` low bits of the encoder channel (the paper's software
    emulation of a coarser encoder) and keeps, in the node's ``shared[key]``, the count and the direction
    and time stamp of the last edge. With the channel in ``mode: polling`` the handler needs a timer
    trigger at the ISR period and runs every tick (the real CPU load of a 100 kHz ISR); with ``mode: exact``
    it has no trigger and is invoked only at the ticks that see an edge (identical stored values, a small
    fraction of the jobs). In exact mode the CPU time of the runs at every other tick is accounted in closed
    form (``isr_load: true``, the default): the program registers a periodic load on its node
    (:meth:`netsim.kernel.Kernel.create_periodic_load`) with the encoder's tick and the handler's
    ``latency + execution``, whose windows are the ISR runs; its invocations at edge ticks are those windows.
    The controller's response times, the CPU utilization and ``cpu_time`` of the ISR are then those of the
    polling ISR (same job records). ``isr_load: false`` leaves out the every-tick load (only the edge runs
    take CPU time), as the model did before.
``cart_controller`` (a periodic task)
    At each release: read the ISR's values (zero time, at the start of the job), step the controller
    (time update to the event, measurement update, time update for the rest of the step, control law),
    ``execute`` the task's execution time, then ``analog_out`` of ``uV``. The reference steps back to zero
    when the measured position passes ``stop_at`` (the paper's 1 m run). Records ``cart.accel`` (the
    commanded acceleration u = Ku uV in m/s^2; ``cart.u`` would collide with the plant's own input record),
    ``cart.uV``, ``cart.v_hat``, ``cart.u_bias_hat``, ``cart.vref`` and once ``cart.tfilter``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Generator, Literal

from pydantic import Field

from netsim.models.cart.controllers import KU, make_controller
from netsim.models.cart.encoding import Quantizer, check_q
from netsim.errors import BuildError
from netsim.registry import register
from netsim.units import StrictModel

if TYPE_CHECKING:
    from netsim.programs.basic import ProgramContext
    from netsim.kernel.job import Job

__all__ = ["CartEncoderIsr", "CartControllerProgram"]

Body = Generator[Any, Any, None]


def _encoder_channel(ctx: ProgramContext, name: str) -> Any:
    enc = ctx.env.components.get(f"io.{name}")
    if enc is None or not hasattr(enc, "tick_ns"):
        raise BuildError(f"'{name}' is not an encoder io channel; add io.{name} with type: encoder")
    return enc


@register("program", "cart_encoder_isr", "cart encoder ISR: drop q bits, store count/direction/stamp of the last edge")
class CartEncoderIsr:
    """The 100 kHz encoder ISR (polling: timer-triggered every tick; exact: invoked at edges only)."""

    class Params(StrictModel):
        encoder_channel: str = "enc"
        q: int = Field(0, description="low bits dropped in software (0..16; the paper mostly uses 6)")
        key: str = "enc"
        record: bool = True
        isr_load: bool = Field(True, description="exact mode: account the ISR's CPU time at every tick (periodic "
                               "load of latency + execution per tick); false: only the edge runs take CPU")

    def __init__(self, ctx: ProgramContext, params: "CartEncoderIsr.Params") -> None:
        from netsim.io import Encoder

        self.ctx = ctx
        self.p = params
        q = check_q(params.q)
        base = _encoder_channel(ctx, params.encoder_channel)
        self.plant = base.plant
        self.output = base.output
        self.delta = base.delta * 2**q
        self.mode = base.mode
        trigger = getattr(ctx.spec, "trigger", None)
        has_timer = trigger is not None and getattr(trigger, "timer", None) is not None
        if self.mode == "polling" and not has_timer:
            raise BuildError(f"handler '{ctx.task}': a polling encoder needs trigger: {{timer: {{period: "
                             f"{base.tick_ns / 1000:g} us}}}} on the ISR")
        if self.mode == "exact" and trigger is not None:
            raise BuildError(f"handler '{ctx.task}': with an exact encoder the ISR is invoked at edges; remove "
                             f"its trigger (or use mode: polling on io.{params.encoder_channel})")
        count = math.floor(self.plant.output_value(self.output, ctx.env.now) / self.delta)
        self.state = {"count": count, "direction": 0, "stamp": -1, "delta": self.delta, "q": q, "edges": 0}
        ctx.kernel.shared[params.key] = self.state
        if params.record:
            ctx.record("cart.count", count, ctx.env.now)
        if self.mode == "exact":
            self.encoder = Encoder(self.plant, self.output, step=base.delta, q=q, tick_ns=base.tick_ns,
                                   mode="exact", offset_ns=base.offset_ns, name=f"{ctx.node}.{ctx.task}")
            kernel, task = ctx.kernel, ctx.task
            if params.isr_load:
                self._register_load(ctx, base)
            self.encoder.start(ctx.env, lambda c, d, s: kernel.invoke_handler(task, data=(c, d, s)))

    @staticmethod
    def _register_load(ctx: ProgramContext, base: Any) -> None:
        """The ISR's runs at every tick as a periodic load of ``latency + execution`` (exact mode)."""
        ex = ctx.execution
        if ex is not None and ex.const is None:
            raise BuildError(f"handler '{ctx.task}': isr_load needs a constant execution time (got {ex!r}); give "
                             "a constant, or use mode: polling with a timer trigger, or isr_load: false")
        latency = int(getattr(ctx.spec, "latency", 0) or 0)
        per_tick = latency + (0 if ex is None else int(ex.const))
        if per_tick <= 0:
            return  # an ISR that takes no time: nothing to account
        if per_tick >= base.tick_ns:
            raise BuildError(f"handler '{ctx.task}': latency + execution ({per_tick} ns) must be less than the "
                             f"encoder tick ({base.tick_ns} ns)")
        ctx.kernel.create_periodic_load(ctx.task, period=base.tick_ns, execution=per_tick, start=base.offset_ns,
                                        handler=ctx.task)

    def _store(self, count: int, direction: int, stamp: int) -> None:
        st = self.state
        st["count"], st["direction"], st["stamp"] = count, direction, stamp
        st["edges"] += 1
        if self.p.record:
            self.ctx.record("cart.count", count, stamp)

    def __call__(self, job: Job) -> Body:
        if self.mode == "exact":
            c, d, s = job.data
            self._store(c, d, s)
        else:
            now = job.now
            c = math.floor(self.plant.output_value(self.output, now) / self.delta)
            old = self.state["count"]
            if c != old:
                self._store(c, 1 if c > old else -1, now)
        if self.ctx.execution is not None:
            yield self.ctx.execute_request  # job.execute(self.ctx.execution), built once


@register("program", "cart_controller", "cart velocity controller: event estimator or PI at 1 kHz, uV to the DAC")
class CartControllerProgram:
    """One of the five controllers of the paper, run as a periodic task."""

    class Params(StrictModel):
        controller: Literal["pure_pi", "observer_pi", "basic_event", "position_prediction", "full_event"]
        wc: float = Field(gt=0, description="crossover frequency in rad/s")
        vref: float = Field(0.8, description="velocity reference step in m/s")
        stop_at: float | None = Field(1.0, description="reference back to 0 once the measured position passes this (m)")
        output_channel: str = "u"
        key: str = "enc"
        ku: float = Field(KU, gt=0)
        r: float = Field(3.0, gt=1)
        observer_variant: Literal["ti4", "ti2"] = "ti4"
        ti_floor: float | None = Field(3.0 / 80.0, description="lower bound of the reduced Ti (s); null: none")

    def __init__(self, ctx: ProgramContext, params: "CartControllerProgram.Params") -> None:
        self.ctx = ctx
        self.p = params
        if ctx.period is None:
            raise BuildError(f"task '{ctx.task}': cart_controller must be periodic (give it a period)")
        st = ctx.kernel.shared.get(params.key)
        if st is None:
            raise BuildError(f"task '{ctx.task}': no encoder ISR stores shared['{params.key}'] on node "
                             f"'{ctx.node}'; add a cart_encoder_isr handler (handlers are built before tasks?)")
        self.enc = st
        self.ctrl = make_controller(params.controller, params.wc, Quantizer(st["delta"], "floor"), ctx.period,
                                    ku=params.ku, r=params.r, observer_variant=params.observer_variant,
                                    ti_floor=params.ti_floor)
        self.stopped = False
        ctx.record("cart.tfilter", self.ctrl.tuning.Tfilter, ctx.env.now)
        ctx.record("cart.vref", params.vref, ctx.env.now)

    def __call__(self, job: Job) -> Body:
        st, p = self.enc, self.p
        now = job.now
        if not self.stopped and p.stop_at is not None and st["count"] * st["delta"] >= p.stop_at:
            self.stopped = True
            self.ctx.record("cart.vref", 0.0, now)
        vref = 0.0 if self.stopped else p.vref
        uv = self.ctrl.update(now, st["count"], st["direction"], st["stamp"], vref)
        rec = self.ctx.record
        rec("cart.v_hat", self.ctrl.v_hat, now)
        rec("cart.u_bias_hat", self.ctrl.u_bias_hat, now)
        if self.ctx.execution is not None:
            yield self.ctx.execute_request  # job.execute(self.ctx.execution), built once
        yield job.analog_out(p.output_channel, uv)
        rec("cart.uV", uv, job.now)
        rec("cart.accel", self.ctrl.u, job.now)
