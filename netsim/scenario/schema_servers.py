"""A node's bandwidth servers and time-triggered schedule table in a scenario (``nodes.<n>.servers``,
``nodes.<n>.timetable``, ``tasks[].server``).

Kept apart from :mod:`netsim.scenario.schema` (whose ``NodeSpec`` has the fields) so the feature reads in one
place: the YAML models and :func:`wire_servers`, which the kernel wiring runs for each node (so ``netsim
validate`` refuses what ``netsim run`` refuses, at the same path)::

    nodes:
      ctrl:
        policy: edf
        servers:
          - {name: cbs, type: cbs, budget: 2 ms, period: 10 ms}           # hard: true suspends on exhaustion
          - {name: tbs, type: tbs, utilization: 0.2}
        tasks:
          - {name: pid, program: periodic_controller, period: 10 ms, server: cbs, ...}
      ecu:
        policy: tt
        timetable:
          cycle: 10 ms
          overrun: continue                                              # or kill
          slots:
            - {start: 0 ms, task: sample, length: 1 ms}
            - {start: 2 ms, task: control, length: 3 ms}

The semantics are those of :mod:`netsim.kernel.servers` and :mod:`netsim.kernel.timetable`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal

from pydantic import ConfigDict, Field, StringConstraints, model_validator

from netsim.errors import BuildError
from netsim.units import Duration, StrictModel, Time

if TYPE_CHECKING:
    from netsim.kernel.kernel import Kernel

__all__ = ["ServerDecl", "SlotDecl", "TimetableSpec", "wire_servers"]

_Name = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_-]+$")]


class _Decl(StrictModel):
    model_config = ConfigDict(extra="forbid", frozen=True, validate_assignment=False)


class ServerDecl(_Decl):
    """A bandwidth server on an EDF node: ``type: cbs`` (constant bandwidth server: ``budget`` per ``period``,
    ``hard: true`` to suspend its tasks when the budget runs out) or ``type: tbs`` (total bandwidth server:
    ``utilization``; its tasks need a ``wcet``). Tasks name it with ``server:``."""

    name: _Name = Field(description="the server's name, which tasks[].server names")
    type: Literal["cbs", "tbs"] = Field(description="cbs (constant bandwidth server) or tbs (total bandwidth "
                                                    "server)")
    budget: Duration | None = Field(None, description="cbs: execution time per period (TrueTime's Qs)")
    period: Duration | None = Field(None, description="cbs: the server period (Ts)")
    utilization: float | None = Field(None, gt=0, description="tbs: the CPU share Us, in (0, 1]")
    hard: bool = Field(False, description="cbs: suspend the served tasks until the replenishment time when the "
                                          "budget runs out (false: postpone the deadline and go on)")

    @model_validator(mode="after")
    def _fields_of_type(self) -> "ServerDecl":
        if self.type == "cbs":
            if self.budget is None or self.period is None:
                raise ValueError("a cbs server needs 'budget' and 'period' (e.g. budget: 2 ms, period: 10 ms)")
            if self.utilization is not None:
                raise ValueError("a cbs server has a budget and a period, not 'utilization'; drop it")
            if self.budget > self.period:
                raise ValueError(f"budget/period = {self.budget / self.period:.3f} exceeds 1 (the whole CPU); "
                                 "lower the budget or lengthen the period")
        else:
            if self.utilization is None:
                raise ValueError("a tbs server needs 'utilization' (e.g. utilization: 0.25)")
            if self.budget is not None or self.period is not None or self.hard:
                raise ValueError("a tbs server has only 'utilization'; drop 'budget', 'period' and 'hard'")
            if self.utilization > 1:
                raise ValueError(f"utilization {self.utilization:g} exceeds 1 (the whole CPU)")
        return self


class SlotDecl(_Decl):
    """A slot of a time-triggered table: ``task`` is activated at ``start`` (from the cycle's start) every cycle
    and should finish within ``length``."""

    start: Time = Field(description="activation time from the cycle's start")
    task: _Name = Field(description="the task the slot activates (a task of the node without its own release)")
    length: Duration = Field(description="the slot's length: the job's deadline is the slot's end")


class TimetableSpec(_Decl):
    """A static schedule table (``policy: tt``): the slots repeat every ``cycle``; ``overrun`` says what happens
    to a job still running at its slot's end (``continue``: a deadline miss, it goes on; ``kill``: it is killed)."""

    cycle: Duration = Field(description="the table's period: the slots repeat every cycle")
    slots: list[SlotDecl] = Field(min_length=1, description="the slots, inside the cycle and not overlapping")
    offset: Time = Field(0, description="start of the first cycle")
    overrun: Literal["continue", "kill"] = Field("continue", description=(
        "a job still running at its slot's end: continue (a deadline miss, it goes on, preempted by the next "
        "activation) or kill (killed at the slot's end)"))


def wire_servers(kernel: Kernel, node: Any, npath: str) -> None:
    """Create ``node``'s servers and timetable on its ``kernel`` and attach the served tasks (after the tasks).

    Raises
    ------
    BuildError
        With the YAML path of what is refused: a server on a node whose policy is not edf, servers whose
        utilisations add up to more than 1, a task naming an unknown server, a table that does not fit its cycle,
        a ``tt`` node without a table.
    """
    servers = node.servers
    served = [(i, t) for i, t in enumerate(node.tasks) if t.server is not None]
    if servers or served:
        from netsim.kernel.servers import attach_server, create_cbs, create_tbs
        from netsim.registry import lookup

        for i, s in enumerate(servers):
            path = f"{npath}.servers[{i}]"
            try:
                if lookup("server", s.type).kind == "cbs":  # the registered server types (netsim list servers)
                    create_cbs(kernel, s.name, s.budget, s.period, hard=s.hard)
                else:
                    create_tbs(kernel, s.name, s.utilization)
            except BuildError as exc:
                raise BuildError(exc.message, path=path) from None
        for i, t in served:
            try:
                attach_server(kernel, t.name, t.server)
            except BuildError as exc:
                raise BuildError(exc.message, path=f"{npath}.tasks[{i}].server") from None
    table = node.timetable
    if table is not None:
        from netsim.kernel.timetable import create_timetable

        create_timetable(kernel, table.cycle, [(s.start, s.task, s.length) for s in table.slots], offset=table.offset,
                         overrun=table.overrun, path=f"{npath}.timetable")
    elif node.policy == "tt":
        raise BuildError(f"node '{kernel.name}': policy 'tt' needs a schedule table; add 'timetable: {{cycle: 10 ms, "
                         "slots: [{start: 0 ms, task: <name>, length: 2 ms}]}'", path=f"{npath}.timetable")
