"""A custom controller program: a PI controller with a saturated output and conditional integration
(the integrator stops while the output is saturated and the error would push it further: no wind-up).

A program plugin is a class registered as ``@register("program", NAME)`` with a nested pydantic ``Params``
(the task's ``params:`` in YAML). netsim builds it once per task as ``Program(ctx, params)`` and calls it once
per job: ``program(job)`` is a generator that yields the kernel's requests (``job.analog_in``,
``job.receive``, ``job.execute``, ``job.analog_out``, ``job.send``) in the order the code runs them.

This one takes the newest measurement from the node's inbox on ``network`` (the sensor sends it), computes the
PI law, spends the task's execution time, and writes the pump command to the ``output_channel`` DAC.
"""

from __future__ import annotations

from typing import Any, Generator

from pydantic import Field

from netsim.registry import register
from netsim.units import StrictModel


class PIParams(StrictModel):
    """PI controller parameters."""

    network: str = Field(description="network the measurement arrives on")
    output_channel: str = Field(description="io channel (DAC) the command is written to")
    reference: str = Field(description="scenario signal to follow")
    K: float = Field(2.0, description="proportional gain")
    Ti: float = Field(20.0, gt=0, description="integral time in s")
    u_min: float = 0.0
    u_max: float = 1.0
    record_as: str | None = Field(None, description="record the command under this name")


@register("program", "pi_antiwindup", "PI with a saturated output and conditional integration (example plugin)")
class PIAntiWindup:
    """PI control of the newest measurement (see the module docstring)."""

    Params = PIParams

    def __init__(self, ctx: Any, params: PIParams) -> None:
        self.ctx, self.p = ctx, params
        self.ref = ctx.signal(params.reference)
        self.integral = 0.0
        self.last_ns: int | None = None

    def __call__(self, job: Any) -> Generator[Any, Any, None]:
        p = self.p
        newest = None
        while True:  # drain the inbox: keep the newest measurement
            msg = yield job.receive(p.network)
            if msg is None:
                break
            newest = msg
        if newest is None:
            return
        e = self.ref(job.now) - float(newest.payload)
        h = 0.0 if self.last_ns is None else (job.now - self.last_ns) / 1e9
        self.last_ns = job.now
        u = p.K * (e + self.integral / p.Ti)
        saturated_high, saturated_low = u > p.u_max, u < p.u_min
        if not ((saturated_high and e > 0) or (saturated_low and e < 0)):
            self.integral += e * h  # integrate only when it does not drive the output further into saturation
        u = min(max(u, p.u_min), p.u_max)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        yield job.analog_out(p.output_channel, u)
        if p.record_as:
            self.ctx.record(p.record_as, u, job.now)
