"""A DVS governor program: a task that sets its node's CPU speed at each job (``job.set_speed``).

``speed_governor``
    job ``k`` sets the speed ``speeds[k mod n]`` (TrueTime's ``ttSetCPUScaling`` from a code function), then
    executes the task's execution time, if any. Give it a higher priority than the tasks it slows down or speeds
    up, so that its change comes first at an instant they share. The node needs ``nodes.<n>.speed``
    (:mod:`netsim.kernel.speed`); with ``speed_levels`` every speed must be one of them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Generator

from pydantic import Field

from netsim.errors import ConfigError
from netsim.registry import register
from netsim.units import StrictModel

if TYPE_CHECKING:
    from netsim.kernel.job import Job
    from netsim.programs.basic import ProgramContext

__all__ = ["SpeedGovernor"]


@register("program", "speed_governor", "sets the node's CPU speed at each job (DVS, ttSetCPUScaling): "
          "speeds[k mod n] for job k, then its execution")
class SpeedGovernor:
    """Set the CPU speed ``speeds[k mod n]`` at job ``k`` (see the module docstring)."""

    class Params(StrictModel):
        speeds: list[Annotated[float, Field(gt=0, le=1)]] = Field(
            min_length=1, description="the speed each job sets, in turn (fractions of the nominal clock)")

    def __init__(self, ctx: "ProgramContext", params: Params) -> None:
        self.ctx = ctx
        self.speeds = list(params.speeds)
        levels = getattr(ctx.kernel, "_levels", None)
        if not hasattr(ctx.kernel, "busy_by_speed"):
            raise ConfigError(f"speed_governor on node '{ctx.node}' needs speed scaling: give the node a speed "
                              f"(nodes.{ctx.node}.speed: 1)")
        if levels is not None:
            for s in self.speeds:
                if not any(abs(s - float(level)) < 1e-12 for level in levels):
                    raise ConfigError(f"speed {s} is not one of nodes.{ctx.node}.speed_levels "
                                      f"{[float(level) for level in levels]}")

    def __call__(self, job: "Job") -> Generator[Any, Any, None]:
        yield job.set_speed(self.speeds[job.job_id % len(self.speeds)])
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)
