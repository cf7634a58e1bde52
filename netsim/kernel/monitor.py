"""Monitors (mutual exclusion with priority inheritance or a priority ceiling), TrueTime's ``ttEnterMonitor``.

A task body brackets a critical section with ``yield job.enter(mon)`` ... ``yield job.exit(mon)``. One job at a
time owns a monitor; a job that enters a monitor owned by another blocks until it is handed the monitor.
Waiters are served most urgent first (equal urgency: first come, first served); the owner's exit hands the
monitor directly to that waiter, which becomes ready as the new owner.

Protocols (``Monitor(protocol=...)``)
-------------------------------------
``"inherit"`` (default, TrueTime's monitors): the **priority inheritance protocol** (Sha, Rajkumar & Lehoczky
    1990). While a job waits for a monitor, the owner runs at the waiter's urgency if that is higher than its
    own, transitively along a chain of owners blocked on other monitors. Urgency is the job's rank in the ready
    queue, so this is the inherited *priority* under ``fp``/``rm``/``dm`` and the inherited *absolute
    deadline* under ``edf`` (the owner is scheduled as if it had the waiter's deadline).
``"ceiling"``: the **immediate priority ceiling protocol** (ICPP; "highest locker", POSIX
    ``PTHREAD_PRIO_PROTECT``, Ada's ``Ceiling_Locking``), not the original PCP of Sha et al. with its
    system-ceiling entry test. The monitor's ceiling is the most urgent priority of the tasks that use it
    (``users``) or an explicit ``ceiling`` (a policy key: an ``fp`` priority, an ``rm`` period, a ``dm``
    deadline). A job runs at the ceiling from the instant it enters until it exits, so on one CPU a job that
    does not suspend inside a critical section never finds a monitor taken, and each job is blocked at most
    once, for at most one critical section of a lower-priority task (the same bound as the original PCP).
    It needs a static policy (``fp``, ``rm``, ``dm``, ``np_fp``); under ``edf`` use ``"inherit"``.
``"none"``: a plain mutex without inheritance (to show priority inversion).

How the urgency changes
-----------------------
The dispatcher orders jobs by ``job._rank`` (:mod:`netsim.kernel.dispatch`); ``job._base_rank`` is what
``_rank`` returns to after a non-preemptible stretch. While a job uses monitors, both hold its *effective*
rank (its own, raised by inheritance or a ceiling) and ``job._own_rank`` keeps its own; ``job._held`` lists the
monitors it owns (``None`` for a job that never touched a monitor, so jobs of scenarios without monitors carry
no extra state and the dispatcher's hot paths are unchanged). A ready job whose rank changes is re-queued.

A job killed while it owns monitors releases them (the next waiter gets each); a job killed while waiting is
removed from the waiters and the owner's inherited urgency recomputed. A job that ends normally while it
still owns a monitor is an error, reported when another job next enters that monitor.
"""

from __future__ import annotations

from heapq import heapify
from typing import TYPE_CHECKING, Any

from netsim.errors import SimulationError
from netsim.kernel.states import BLOCKED, DONE, READY

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.job import Job

if TYPE_CHECKING:
    from netsim.kernel.kernel import Kernel

__all__ = ["Monitor", "PROTOCOLS", "refresh_rank", "monitor_killed"]

#: :data:`netsim.kernel.dispatch.NP_RANK`, the rank of a started non-preemptible job (not imported: the
#: dispatcher imports :mod:`netsim.kernel.job`, which imports this module; a test checks they are equal).
_NP_RANK = (0.5, 0)

#: The protocols a monitor can follow.
PROTOCOLS = ("inherit", "ceiling", "none")


class _SpecOnly:
    """What a static policy's ``key`` reads of a job: its task's spec."""

    __slots__ = ("spec",)

    def __init__(self, spec: Any) -> None:
        self.spec = spec


class Monitor:
    """A monitor: one owner at a time, waiters served most urgent first.

    Parameters
    ----------
    name
        Label used in error messages.
    protocol
        ``"inherit"`` (priority inheritance), ``"ceiling"`` (immediate priority ceiling) or ``"none"``.
    ceiling
        For ``"ceiling"``: the ceiling as a policy key (e.g. the most urgent ``fp`` priority of the users).
    users
        For ``"ceiling"`` without ``ceiling``: the names of the tasks that enter the monitor (the ceiling is
        the most urgent of their keys, computed at the first entry).

    Attributes
    ----------
    owner : Job | None
        The job holding the monitor.
    entries, contended : int
        How many times the monitor was taken, and how many of those entries had to wait.
    """

    def __init__(self, name: str = "", protocol: str = "inherit", ceiling: Any = None,
                 users: "tuple[str, ...] | list[str]" = ()) -> None:
        if protocol not in PROTOCOLS:
            raise SimulationError(f"monitor '{name}': protocol must be one of {', '.join(PROTOCOLS)}, got "
                                  f"{protocol!r}")
        if protocol == "ceiling" and ceiling is None and not users:
            raise SimulationError(f"monitor '{name}': protocol 'ceiling' needs 'users' (the tasks that enter it) "
                                  "or an explicit 'ceiling'")
        self.name = name
        self.protocol = protocol
        self.ceiling = ceiling
        self.users = tuple(users)
        self.owner: Job | None = None
        self.entries = 0
        self.contended = 0
        self._waiters: list[Job] = []
        self._ceiling_rank: Any = None

    # ----------------------------------------------------------------- requests (called by the interpreter)
    def enter(self, job: "Job", kernel: Kernel) -> bool:
        """``job`` (running) asks for the monitor: True when it owns it now, False when it must block."""
        if job.is_handler:
            raise SimulationError(f"node '{kernel.name}', handler '{job.task_name}': enter(monitor "
                                  f"'{self.name}'): interrupt handlers cannot wait for a monitor; enter it from a "
                                  "task")
        if job._held is None:
            job._held = []
            job._own_rank = job._base_rank
        owner = self.owner
        if owner is None:
            self._take(job, kernel)
            return True
        if owner is job:
            raise SimulationError(f"node '{kernel.name}', task '{job.task_name}': enter(monitor '{self.name}') "
                                  "while already holding it (monitors are not re-entrant)")
        if owner._state == DONE:
            raise SimulationError(f"node '{kernel.name}': job {owner.task_name}#{owner.job_id} ended while "
                                  f"holding monitor '{self.name}'; its body must exit the monitor before it ends")
        self._waiters.append(job)
        self.contended += 1
        if self.protocol != "none":
            _inherit(owner, job._base_rank)
        return False

    def exit(self, job: "Job", kernel: Kernel) -> None:
        """``job`` (running) leaves the monitor: the most urgent waiter becomes the owner."""
        if self.owner is not job:
            holder = "nobody" if self.owner is None else f"'{self.owner.task_name}'"
            raise SimulationError(f"node '{kernel.name}', task '{job.task_name}': exit(monitor '{self.name}') "
                                  f"without holding it (held by {holder})")
        self._release(job)
        refresh_rank(job)

    # ----------------------------------------------------------------- internals
    def _take(self, job: "Job", kernel: Kernel) -> None:
        self.owner = job
        self.entries += 1
        job._held.append(self)  # type: ignore[union-attr]
        if self.protocol == "ceiling":
            ceiling = self._ceiling_rank
            if ceiling is None:
                ceiling = self._ceiling_rank = self._resolve_ceiling(kernel)
            if job._own_rank < ceiling:
                raise SimulationError(
                    f"node '{kernel.name}', task '{job.task_name}': enters monitor '{self.name}' but is more "
                    f"urgent than its ceiling {ceiling[1]!r}; add '{job.task_name}' to the monitor's users")
            _raise(job, ceiling)

    def _release(self, job: "Job") -> None:
        """``job`` gives up the monitor; hand it to the most urgent live waiter."""
        job._held.remove(self)  # type: ignore[union-attr]
        self.owner = None
        waiters = self._waiters
        best = None
        for w in waiters:
            if w._state == BLOCKED and w._blocked_on is self and (best is None or w._base_rank < best._base_rank):
                best = w
        if best is None:
            waiters.clear()
            return
        waiters.remove(best)
        waiters[:] = [w for w in waiters if w._state == BLOCKED and w._blocked_on is self]
        kernel = best._ctx.kernel
        self._take(best, kernel)
        if self.protocol != "none":
            for w in waiters:  # those still waiting now wait for the new owner
                _inherit(best, w._base_rank)
        best._rank = best._base_rank
        best._ctx.unblock(best, None)

    def _resolve_ceiling(self, kernel: Kernel) -> tuple[int, Any]:
        if self.ceiling is not None:
            return (1, self.ceiling)
        policy = kernel.policy
        if not policy.static:
            raise SimulationError(f"node '{kernel.name}': monitor '{self.name}' uses protocol 'ceiling', which needs "
                                  f"a static-priority policy (fp, rm, dm, np_fp), not '{policy.name}'; use "
                                  "protocol 'inherit' (the owner then inherits the waiter's deadline)")
        keys = []
        for user in self.users:
            task = kernel.tasks.get(user)
            if task is None:
                from netsim.kernel.task import did_you_mean
                raise SimulationError(f"node '{kernel.name}': monitor '{self.name}': user '{user}' is not a task of "
                                      f"the node{did_you_mean(user, kernel.tasks)}")
            keys.append(policy.key(_SpecOnly(task.spec)))
        return (1, min(keys))

    def __repr__(self) -> str:
        owner = None if self.owner is None else self.owner.task_name
        return f"Monitor({self.name!r}, protocol={self.protocol!r}, owner={owner!r})"


def _raise(job: "Job", rank: Any) -> None:
    """Raise ``job``'s effective rank to ``rank`` if that is more urgent (re-queue it if ready)."""
    if rank < job._base_rank:
        job._base_rank = rank
        if rank < job._rank:
            job._rank = rank
            if job._state == READY:
                _requeue(job)


def _inherit(owner: "Job", rank: Any) -> None:
    """The owner (and the owners it waits for, transitively) inherit ``rank``."""
    seen = 0
    while owner is not None and rank < owner._base_rank and seen < 1000:
        _raise(owner, rank)
        on = owner._blocked_on
        if owner._state != BLOCKED or type(on) is not Monitor or on.protocol == "none":
            return
        owner = on.owner  # type: ignore[assignment]
        seen += 1


def _requeue(job: "Job") -> None:
    """Put a ready job's queue entry at its new rank."""
    ready = job._ctx.kernel._ready
    for i, entry in enumerate(ready):
        if entry[2] is job:
            ready[i] = (job._rank, entry[1], job)
            heapify(ready)
            return


def refresh_rank(job: "Job") -> None:
    """Recompute ``job``'s effective rank from its own and the monitors it holds (after an exit, a kill of a
    waiter, or a run-time change of its own priority: set ``job._own_rank`` first)."""
    if job._held is None:
        return
    eff = job._own_rank
    for mon in job._held:
        if mon.protocol == "ceiling" and mon._ceiling_rank is not None and mon._ceiling_rank < eff:
            eff = mon._ceiling_rank
        if mon.protocol != "none":
            for w in mon._waiters:
                if w._state == BLOCKED and w._blocked_on is mon and w._base_rank < eff:
                    eff = w._base_rank
    job._base_rank = eff
    if job._rank != _NP_RANK:  # a started non-preemptible job keeps its rank until it blocks or ends
        changed = job._rank != eff
        job._rank = eff
        if changed and job._state == READY:
            _requeue(job)


def monitor_killed(kernel: Kernel, job: "Job") -> None:
    """``job`` is being killed: release the monitors it owns and leave the waiters of the one it waits for."""
    on = job._blocked_on
    if job._state == BLOCKED and type(on) is Monitor:
        if job in on._waiters:
            on._waiters.remove(job)
        job._blocked_on = None
        owner = on.owner
        while owner is not None:  # the chain of owners may lose what they inherited from this job
            refresh_rank(owner)
            nxt = owner._blocked_on
            owner = nxt.owner if owner._state == BLOCKED and type(nxt) is Monitor else None
    if job._held:
        for mon in list(job._held):
            mon._release(job)
