"""Budgets set at run time: a scheduler task that adapts a constant bandwidth server's budget to what its tasks
use (the adaptive-reservation idea of Abeni & Buttazzo's CBS feedback studies, with TrueTime's
``ttSetCBSParameters``).

``budget_scheduler``
    A periodic task (give it a short deadline, so that under EDF it runs first at its releases) that, at each
    job, measures the CPU time
    ``used`` the tasks of CBS ``server`` got since its last job, over the window ``w`` since then, and
    sets the server's budget for the bandwidth they need::

        b = used / w                        (the bandwidth they used)
        b' = b * (1 + step)   if the server ran out of budget in the window (they wanted more than they got)
        b' = b * (1 + margin) otherwise (a little room above what they used)
        Qs = clamp(round(b' * Ts), min_budget, max_budget)       (Ts: the server's period, kept)

    and never more than the node's other servers leave of the CPU. The new budget applies from the server's next
    replenishment or arrival (:meth:`~netsim.kernel.servers.ConstantBandwidthServer.set_parameters`). It records
    the budget it set, in ms, as ``record_as`` (default ``budget_ms``).
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING, Any, Generator

from pydantic import Field, model_validator

from netsim.errors import ConfigError, SimulationError
from netsim.registry import register
from netsim.units import Duration, StrictModel

if TYPE_CHECKING:
    from netsim.kernel.job import Job
    from netsim.programs.basic import ProgramContext

__all__ = ["BudgetScheduler"]

Body = Generator[Any, Any, None]


@register("program", "budget_scheduler", "sets a CBS's budget at run time from what its tasks use (ttSetCBSParameters)")
class BudgetScheduler:
    """Adapts the budget of one constant bandwidth server of its node (see the module notes)."""

    class Params(StrictModel):
        server: str = Field(min_length=1, description="the node's CBS (nodes.<n>.servers) whose budget it sets")
        margin: float = Field(0.2, ge=0, description="room above the used bandwidth when the budget sufficed")
        step: float = Field(0.5, gt=0, description="relative increase when the server ran out of budget")
        min_budget: Duration = Field(100_000, description="the smallest budget it sets")
        max_budget: Duration | None = Field(None, description="the largest budget it sets (default: the period)")
        record_as: str | None = "budget_ms"

        @model_validator(mode="after")
        def _bounds(self) -> "BudgetScheduler.Params":
            if self.max_budget is not None and self.max_budget < self.min_budget:
                raise ValueError("max_budget must not be below min_budget")
            return self

    def __init__(self, ctx: ProgramContext, params: Params) -> None:
        self.ctx = ctx
        self.p = params
        self.t_last: int | None = None
        self.cpu_last = 0
        self.exhausted_last = 0
        self.budgets: list[tuple[int, int]] = []  # (time, budget set)
        self._check_server()

    def _check_server(self) -> None:
        """Refuse, at ``nodes.<n>.tasks[i].params.server``, a server the node does not declare as a cbs: the
        build checks it (so ``netsim validate`` refuses what the run would), not the first job."""
        scenario = self.ctx.scenario
        node = scenario.nodes.get(self.ctx.node) if scenario is not None else None
        if node is None:  # built outside a scenario (a kernel made in Python): the first job checks
            return
        index = next((i for i, t in enumerate(node.tasks) if t.name == self.ctx.task), None)
        path = None if index is None else f"nodes.{self.ctx.node}.tasks[{index}].params.server"
        kinds = {s.name: s.type for s in node.servers}
        kind = kinds.get(self.p.server)
        if kind == "cbs":
            return
        cbs = ", ".join(name for name, k in kinds.items() if k == "cbs") or "none yet: add one"
        what = (f"node '{self.ctx.node}' has no server '{self.p.server}'" if kind is None
                else f"server '{self.p.server}' is a {kind}, not a cbs")
        raise ConfigError(f"{what}; name a cbs of nodes.{self.ctx.node}.servers ({cbs})", path=path)

    def _server(self) -> Any:
        srv = self.ctx.kernel.servers.get(self.p.server)
        if srv is None or srv.kind != "cbs":
            what = "no server" if srv is None else f"a {srv.kind}, not a cbs"
            raise SimulationError(f"budget_scheduler '{self.ctx.node}.{self.ctx.task}': params.server "
                                  f"'{self.p.server}' is {what}; name a cbs of nodes.{self.ctx.node}.servers")
        return srv

    def __call__(self, job: Job) -> Body:
        srv = self._server()
        p = self.p
        now = job.now
        cpu = sum(t.cpu for t in srv.tasks)
        exhausted = srv.replenishments
        t0, used, ran_out = self.t_last, cpu - self.cpu_last, exhausted > self.exhausted_last
        self.t_last, self.cpu_last, self.exhausted_last = now, cpu, exhausted
        if t0 is not None and now > t0:
            want = Fraction(used, now - t0) * Fraction(1 + (p.step if ran_out else p.margin)).limit_denominator(10**6)
            others = sum((s.utilization for s in job.kernel.servers.values() if s is not srv), Fraction(0))
            cap = min(p.max_budget or srv.period, srv.period, int((1 - others) * srv.period))
            budget = max(p.min_budget, min(cap, round(want * srv.period)))
            srv.set_parameters(budget, srv.period)
            self.budgets.append((now, budget))
            if p.record_as:
                self.ctx.record(p.record_as, budget / 1e6, now)
        if self.ctx.execution is not None:
            yield job.execute(self.ctx.execution)

    def metrics(self) -> dict[str, float]:
        """``budget_ms``: the last budget it set (NaN before its second job)."""
        return {"budget_ms": self.budgets[-1][1] / 1e6 if self.budgets else float("nan")}
