"""Bandwidth servers on an EDF node: the constant bandwidth server (CBS) and the total bandwidth server (TBS).

TrueTime's ``ttCreateCBS``/``ttAttachCBS``/``ttSetCBSParameters`` and ``ttCreateTBS``/``ttAttachTBS``. A server
serves the jobs of the tasks attached to it; the node's EDF scheduler ranks each served job by the *server's*
deadline instead of the job's own (the job's own deadline, if any, is still what its record is judged by).
Servers need ``policy: edf``.

Constant bandwidth server (Abeni & Buttazzo, 1998)
--------------------------------------------------
Budget ``Qs`` and period ``Ts`` (bandwidth ``Qs/Ts``); state: the budget left ``c`` and the deadline ``d``
(both 0 at first).

- **Arrival.** A job of an attached task arriving at ``r`` while the server is idle (no unfinished job of its
  tasks) checks ``c >= (d - r) * Qs / Ts`` (computed as ``c * Ts >= (d - r) * Qs``, in integers): if it holds,
  ``c = Qs`` and ``d = r + Ts``; otherwise ``c`` and ``d`` are kept. A job arriving while the server is busy
  takes the current ``d``.
- **Budget.** Every ns of execution of a served job (context switches excluded, as for a task's ``wcet``)
  takes one ns of ``c``; a served job's segment never runs past ``c``.
- **Exhaustion.** When ``c`` reaches 0 with work left: a *soft* server sets ``c = Qs`` and ``d = d + Ts`` at once
  (every served job is re-ranked by the postponed deadline, so the running one may be preempted); a *hard*
  server sets ``d = d + Ts`` and suspends its jobs until the old ``d`` (the replenishment time), when
  ``c = Qs`` (TrueTime's hard CBS). If the old ``d`` has already passed, a hard server replenishes at once.
- **Run time.** :meth:`ConstantBandwidthServer.set_parameters` (``ttSetCBSParameters``) sets ``Qs`` and ``Ts``;
  as in TrueTime the current ``c`` and ``d`` are kept, the new values apply from the next replenishment or
  arrival reset. :attr:`ConstantBandwidthServer.budget_left` (``ttGetCBSBudget``) is ``c`` now, counting the
  segment under way.

Total bandwidth server (Spuri & Buttazzo, 1996)
-----------------------------------------------
Utilisation ``Us``. A job arriving at ``r_k`` gets the deadline ``d_k = max(r_k, d_{k-1}) + C_k / Us``
(rounded up to the ns), where ``C_k`` is its task's ``wcet`` (required) and ``d_{k-1}`` the deadline the
server gave last (0 at first). There is no budget: the task's ``wcet`` stays its per-job budget.

Every server keeps an :attr:`Server.events` log of what it did (arrival resets, replenishments, throttling,
TBS deadlines) for checks and plots.

Limits: one server per task; a task is attached before its first release; ``kernel.set_deadline`` on a served
task re-ranks its jobs by their own deadlines until the server next re-ranks them.
"""

from __future__ import annotations

import math
from fractions import Fraction
from heapq import heapify, heappush
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple

from netsim.errors import BuildError, SimulationError
from netsim.kernel.events import NORMAL
from netsim.kernel.monitor import refresh_rank
from netsim.kernel.states import BLOCKED, READY
from netsim.kernel.task import did_you_mean
from netsim.registry import register
from netsim.timebase import format_time

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.job import Job
    from netsim.kernel.kernel import Kernel
    from netsim.kernel.task import Task

__all__ = ["Server", "ServerEvent", "ConstantBandwidthServer", "TotalBandwidthServer", "create_cbs", "create_tbs",
           "attach_server", "SERVER_TYPES"]

#: The server types a scenario names (``nodes.<n>.servers[].type``) and what each is.
SERVER_TYPES = {
    "cbs": "constant bandwidth server (Abeni & Buttazzo): budget per period, soft or hard",
    "tbs": "total bandwidth server (Spuri & Buttazzo): d_k = max(r_k, d_k-1) + wcet / utilization",
}


class ServerEvent(NamedTuple):
    """One entry of a server's log: at ``t`` the server did ``what`` (``reset``: arrival rule, ``replenish``,
    ``throttle``, ``deadline``: a TBS deadline given), leaving budget ``budget`` and deadline ``deadline``;
    ``task``/``job_id`` name the job concerned."""

    t: int
    what: str
    task: str
    job_id: int
    budget: int
    deadline: int


class Server:
    """What CBS and TBS share: a name, the node's kernel, the attached tasks and the log.

    Attributes
    ----------
    name : str
    tasks : list[Task]
        The attached tasks.
    deadline : int
        The current server deadline (ns, absolute).
    events : list[ServerEvent]
    """

    kind: ClassVar[str] = ""

    def __init__(self, kernel: Kernel, name: str) -> None:
        self.kernel = kernel
        self.name = name
        self.tasks: list[Task] = []
        self.deadline = 0
        self.events: list[ServerEvent] = []

    @property
    def utilization(self) -> Fraction:
        """The share of the CPU the server reserves."""
        raise NotImplementedError

    def arrive(self, job: Job) -> None:  # pragma: no cover - overridden
        """A job of an attached task was released now (called by the kernel's release)."""
        raise NotImplementedError

    def _rank(self, job: Job) -> None:
        """Rank ``job`` by the server deadline (monitors and a started non-preemptible job keep their lent rank)."""
        rank = (1, self.deadline)
        if job._held is not None:
            job._own_rank = rank
            refresh_rank(job)
            return
        lent = job._rank != job._base_rank
        job._base_rank = rank
        if not lent:
            job._rank = rank

    def _log(self, what: str, job: Job | None, budget: int) -> None:
        self.events.append(ServerEvent(self.kernel.now, what, "" if job is None else job.task_name,
                                       -1 if job is None else job.job_id, budget, self.deadline))

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.name} on {self.kernel.name}: tasks {[t.name for t in self.tasks]}>"


@register("server", "cbs", "constant bandwidth server (Abeni & Buttazzo): budget per period, soft or hard; "
          "nodes.<n>.servers")
class ConstantBandwidthServer(Server):
    """A constant bandwidth server (see the module notes). Made by :func:`create_cbs`.

    Attributes
    ----------
    budget, period : int
        ``Qs`` and ``Ts`` (ns).
    hard : bool
        Suspend the served jobs until the replenishment time when the budget runs out.
    replenishments, throttles : int
        Times the budget ran out (each is a replenishment), and of those the times a hard server suspended.
    """

    kind = "cbs"

    def __init__(self, kernel: Kernel, name: str, budget: int, period: int, hard: bool = False) -> None:
        super().__init__(kernel, name)
        self.budget = budget
        self.period = period
        self.hard = bool(hard)
        self.c = 0
        self.throttled = False
        self.replenishments = 0
        self.throttles = 0
        self._waiting: list[Job] = []

    @property
    def utilization(self) -> Fraction:
        return Fraction(self.budget, self.period)

    @property
    def budget_left(self) -> int:
        """The budget left now (TrueTime's ``ttGetCBSBudget``), counting the served segment under way."""
        if self.throttled:
            return 0
        kernel = self.kernel
        job = kernel._seg_job
        if job is None or job._server is not self or job._pre_left:
            return self.c
        now = kernel.now
        used = now - job._seg_start if kernel._load is None else kernel._load_progress(job, now)[0]
        return self.c - used

    def set_parameters(self, budget: int, period: int) -> None:
        """Set ``Qs`` and ``Ts`` (TrueTime's ``ttSetCBSParameters``): used from the next replenishment or arrival
        reset on; the budget left and the deadline now are kept.

        Raises
        ------
        SimulationError
            For a budget or period that is not a positive int of ns, or a budget above the period.
        """
        for what, value in (("budget", budget), ("period", period)):
            if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
                raise SimulationError(f"node '{self.kernel.name}', server '{self.name}': the {what} must be a "
                                      f"positive integer number of ns, got {value!r}")
        if budget > period:
            raise SimulationError(f"node '{self.kernel.name}', server '{self.name}': budget {format_time(budget)} "
                                  f"exceeds the period {format_time(period)} (a bandwidth above 1)")
        others = sum((s.utilization for s in self.kernel.servers.values() if s is not self), Fraction(0))
        if others + Fraction(budget, period) > 1:
            raise SimulationError(f"node '{self.kernel.name}', server '{self.name}': budget/period "
                                  f"{budget / period:.3f} with the node's other servers ({float(others):.3f}) "
                                  "exceeds the CPU (1)")
        self.budget = budget
        self.period = period

    # ----------------------------------------------------------------- kernel hooks
    def arrive(self, job: Job) -> None:
        now = self.kernel.now
        job._server = self
        for task in self.tasks:
            if task.active is not None:  # busy: the job takes the current deadline
                break
        else:  # idle: Abeni & Buttazzo's arrival rule, c >= (d - r) Qs / Ts in integers
            if self.c * self.period >= (self.deadline - now) * self.budget:
                self.c = self.budget
                self.deadline = now + self.period
                self._log("reset", job, self.c)
        self._rank(job)

    def held(self, job: Job) -> bool:
        """``job`` is about to get the CPU: True if it must wait for a hard server's replenishment (it is then
        suspended), else False with its budget set to the server's."""
        if self.throttled:
            self._suspend(job)
            return True
        job._budget = self.c
        return False

    def charged(self, job: Job) -> None:
        """``job``'s budget was charged (the kernel's CPU accounting): the server's budget is the job's."""
        self.c = job._budget  # type: ignore[assignment]

    def exhausted(self, job: Job) -> None:
        """The running served ``job`` has work left and no budget (called by the dispatcher)."""
        kernel = self.kernel
        now = kernel.now
        if self.throttled:  # woke while the server waits for its replenishment
            self._suspend(job)
            return
        self.replenishments += 1
        old = self.deadline
        self.deadline = old + self.period
        if not self.hard or old <= now:
            self.c = job._budget = self.budget
            self._log("replenish", job, self.c)
        else:
            self.c = job._budget = 0
            self.throttled = True
            self.throttles += 1
            self._log("throttle", job, 0)
            heappush(kernel._queue, (old, NORMAL, next(kernel._eid), (self._on_replenish, None)))
            self._suspend(job)
        self._rerank()

    # ----------------------------------------------------------------- helpers
    def _suspend(self, job: Job) -> None:
        self.kernel._block(job, self, self.kernel.now)
        self._waiting.append(job)

    def _rerank(self) -> None:
        """Rank every unfinished job of the attached tasks by the server deadline; re-sort the ready queue."""
        for task in self.tasks:
            if task.active is not None:
                self._rank(task.active)
            for job in task.queue:
                self._rank(job)
        ready = self.kernel._ready
        ready[:] = [(j._rank, seq, j) for _, seq, j in ready if j._state == READY]
        heapify(ready)

    def _on_replenish(self, _ev: Any) -> None:
        kernel = self.kernel
        if kernel.halted:
            return
        self.throttled = False
        self.c = self.budget
        waiting, self._waiting = self._waiting, []
        self._log("replenish", None, self.c)
        now = kernel.now
        for job in waiting:
            if job._state == BLOCKED and job._blocked_on is self:
                job._blocked_on = None
                kernel._make_ready(job, now)
        kernel._request_dispatch()


@register("server", "tbs", "total bandwidth server (Spuri & Buttazzo): d_k = max(r_k, d_k-1) + wcet / Us; "
          "nodes.<n>.servers")
class TotalBandwidthServer(Server):
    """A total bandwidth server (see the module notes). Made by :func:`create_tbs`.

    Attributes
    ----------
    share : Fraction
        ``Us``, exact (from the decimal text of the number given).
    """

    kind = "tbs"

    def __init__(self, kernel: Kernel, name: str, utilization: Fraction) -> None:
        super().__init__(kernel, name)
        self.share = utilization

    @property
    def utilization(self) -> Fraction:
        return self.share

    def arrive(self, job: Job) -> None:
        wcet = job._task.spec.wcet
        share = self.share
        # d_k = max(r_k, d_k-1) + C_k / Us, rounded up to the ns
        self.deadline = max(self.kernel.now, self.deadline) + -(-wcet * share.denominator // share.numerator)  # integers
        self._rank(job)
        self._log("deadline", job, 0)


# --------------------------------------------------------------------------------------------- build
def _check_node(kernel: Kernel, name: str) -> None:
    if not isinstance(name, str) or not name:
        raise BuildError(f"node '{kernel.name}': a server name must be a non-empty string, got {name!r}")
    from netsim.kernel.dispatch import Dispatcher

    if type(kernel)._dispatch is not Dispatcher._dispatch:  # a multicore or speed-scaling kernel
        raise BuildError(f"node '{kernel.name}': server '{name}' needs a single-core node without speed scaling "
                         "(the servers' budget accounting is the single-core dispatcher's)")
    if kernel.policy.name != "edf":
        raise BuildError(f"node '{kernel.name}': server '{name}' needs policy 'edf' (a server's deadline ranks its "
                         f"jobs among the node's EDF jobs); the node's policy is '{kernel.policy.name}'")
    if name in kernel.servers:
        raise BuildError(f"node '{kernel.name}': server '{name}' is defined twice; give each server its own name")


def _check_total(kernel: Kernel, name: str, share: Fraction) -> None:
    total = sum((s.utilization for s in kernel.servers.values()), Fraction(0)) + share
    if total > 1:
        raise BuildError(f"node '{kernel.name}': server '{name}' brings the node's servers to a utilisation of "
                         f"{float(total):.3f}, above the CPU (1); lower a budget or utilization")


def create_cbs(kernel: Kernel, name: str, budget: int, period: int, *, hard: bool = False) -> ConstantBandwidthServer:
    """A constant bandwidth server of budget ``Qs = budget`` per period ``Ts = period`` (ns) on ``kernel``
    (TrueTime's ``ttCreateCBS(name, Qs, Ts, type)``, ``hard`` for type 1).

    Raises
    ------
    BuildError
        For a node whose policy is not ``edf``, a name already used, a budget or period that is not positive,
        a budget above the period, or servers whose utilisations add up to more than 1.
    """
    _check_node(kernel, name)
    for what, value in (("budget", budget), ("period", period)):
        if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
            raise BuildError(f"node '{kernel.name}', server '{name}': the {what} must be a positive integer number "
                             f"of ns, got {value!r}")
    if budget > period:
        raise BuildError(f"node '{kernel.name}', server '{name}': budget {format_time(budget)} exceeds the period "
                         f"{format_time(period)} (utilisation {budget / period:.3f} > 1); lower the budget")
    _check_total(kernel, name, Fraction(budget, period))
    server = ConstantBandwidthServer(kernel, name, budget, period, hard)
    kernel.servers[name] = server
    return server


def create_tbs(kernel: Kernel, name: str, utilization: float | Fraction) -> TotalBandwidthServer:
    """A total bandwidth server of utilisation ``Us`` on ``kernel`` (TrueTime's ``ttCreateTBS(name, Us)``).

    Raises
    ------
    BuildError
        As :func:`create_cbs`, and for a utilisation outside (0, 1].
    """
    _check_node(kernel, name)
    if isinstance(utilization, bool) or not isinstance(utilization, (int, float, Fraction)):
        raise BuildError(f"node '{kernel.name}', server '{name}': utilization must be a number in (0, 1], got "
                         f"{utilization!r}")
    share = utilization if isinstance(utilization, Fraction) else Fraction(str(utilization))
    if not 0 < share <= 1:
        raise BuildError(f"node '{kernel.name}', server '{name}': utilization {float(share):g} is outside (0, 1]")
    _check_total(kernel, name, share)
    server = TotalBandwidthServer(kernel, name, share)
    kernel.servers[name] = server
    return server


def attach_server(kernel: Kernel, task: str, server: str) -> None:
    """Serve ``task``'s jobs by ``server`` (TrueTime's ``ttAttachCBS``/``ttAttachTBS``), before its first release.

    Raises
    ------
    BuildError
        For an unknown task or server, a task already served or already released, a CBS task with a ``wcet``
        (the server's budget is its budget) or a TBS task without one (its deadlines need it).
    """
    node = kernel.name
    t = kernel.tasks.get(task)
    if t is None:
        raise BuildError(f"node '{node}': no task '{task}' to attach to server '{server}'"
                         f"{did_you_mean(str(task), kernel.tasks)}")
    srv = kernel.servers.get(server)
    if srv is None:
        raise BuildError(f"node '{node}', task '{task}': unknown server '{server}'"
                         f"{did_you_mean(str(server), kernel.servers)}; declare it under the node's 'servers'")
    if t.server is not None:
        raise BuildError(f"node '{node}', task '{task}': already served by '{t.server.name}'")
    if t.released:
        raise BuildError(f"node '{node}', task '{task}': attach it to server '{server}' before its first release")
    if srv.kind == "cbs" and t.spec.wcet is not None:
        raise BuildError(f"node '{node}', task '{task}': a task served by CBS '{server}' has the server's budget; "
                         "drop its 'wcet'")
    if srv.kind == "tbs" and t.spec.wcet is None:
        raise BuildError(f"node '{node}', task '{task}': a task served by TBS '{server}' needs a 'wcet' (its jobs' "
                         "deadlines are max(r, d) + wcet / utilization)")
    t.server = srv
    srv.tasks.append(t)
