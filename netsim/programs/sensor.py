"""The ``sensor`` program: sample ADC channels and send the values with their sample time."""

from __future__ import annotations

from collections.abc import Generator
from typing import TYPE_CHECKING, Any

import numpy as np
from pydantic import Field, ValidationInfo, field_validator

from netsim.programs.basic import (
    Destination,
    ProgramContext,
    _destination,
    _destination_given,
)
from netsim.registry import register
from netsim.units import StrictModel, Time

if TYPE_CHECKING:
    from netsim.kernel.job import Job

__all__ = ["Sensor"]

Body = Generator[Any, Any, None]


@register("program", "sensor", "analog_in(channels), execute, send {value, t_ns: sample time} to `to` on `network`")
class Sensor:
    """Time-driven sensor whose messages carry their sample time (for ``state_feedback``'s ``fuse_at``)."""

    class Params(StrictModel):
        channels: list[str] = Field(min_length=1)
        network: str
        to: Destination
        bits: int = Field(80, ge=1, le=10**9)
        priority: int = 0
        tag: str = "y"
        after_send: Time = 0
        record_as: str | None = None

        @field_validator("to")
        @classmethod
        def _to(cls, to: str | None, info: ValidationInfo) -> str | None:
            return _destination_given(to, info)

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx
        self.p = params

    def __call__(self, job: Job) -> Body:
        p = self.p
        t = job.now
        ys = []
        for ch in p.channels:
            ys.append(float((yield job.analog_in(ch))))
        if p.record_as:
            self.ctx.record(p.record_as, ys[0] if len(ys) == 1 else np.array(ys), t)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
        value: Any = ys[0] if len(ys) == 1 else ys
        yield job.send(p.network, _destination(p.to), {"value": value, "t_ns": int(t)}, p.bits,
                       priority=p.priority, tag=p.tag)
        if p.after_send:
            yield job.execute(p.after_send)
