"""Release jitter, sporadic arrivals and task parameters changed at run time (TrueTime's ``ttSetPeriod``,
``ttSetPriority``, ``ttSetDeadline``).

:class:`Arrivals` is a part of :class:`~netsim.kernel.kernel.Kernel` (a mixin). A periodic task without jitter
keeps the kernel's plain release callback (``Kernel._on_periodic_release``): the features here add no work
to tasks that do not use them.

Semantics
---------
- **Release jitter** (``TaskSpec.release_jitter``): at each nominal release ``r_k`` of a periodic or sporadic
  task one jitter ``J_k >= 0`` is drawn from the task's own stream ``kernel.<node>.release.<task>`` (one
  scenario seed fixes every draw, and adding jitter to one task changes no other draw); the job arrives at
  ``r_k + J_k``. Its ``release`` and absolute deadline count from ``r_k`` (so ``response = finish - r_k``,
  what response-time analysis bounds by ``J + w``); ``job.arrival`` and the record's ``arrival`` hold
  ``r_k + J_k``. A zero draw releases the job at ``r_k`` itself, exactly as without jitter. Jobs keep their
  arrival order (``job_id``); a jitter longer than the period can reorder them.
- **Sporadic tasks** (``TaskSpec.min_interarrival``): the first nominal arrival is at ``offset``; each next
  one ``min_interarrival`` plus a draw of ``extra_interarrival`` (``0`` without it) after the previous one.
- **Run-time parameters**: :meth:`Arrivals.set_period`, :meth:`Arrivals.set_priority` and
  :meth:`Arrivals.set_deadline` change a task's description (``task.spec`` is replaced, so
  ``job.spec`` and the policies see the new values). A priority change re-ranks the task's released jobs and
  re-dispatches; a deadline change applies to jobs released afterwards. A period change follows the task's
  ``set_period`` rule (:attr:`~netsim.kernel.task.TaskSpec.set_period`, or the call's ``rule``):

  ``next_release`` (the default; TrueTime 1.5)
      the release already scheduled moves to one new period after the task's last nominal release (at once
      if that instant has passed).
  ``keep_armed`` (TrueTime 2.0's ``ttSetPeriod``)
      the release already scheduled stays where it is; the new period counts from it.

  Example: period 10 ms, releases at 0 and 10 ms, ``set_period(task, 4 ms)`` at 12 ms. ``next_release``: the
  next releases are at 14 ms (10 + 4), 18, 22 ms; ``keep_armed``: at 20 ms (already armed), 24, 28 ms. Before
  the task's first release both keep the first release at its offset.
"""

from __future__ import annotations

from collections.abc import Callable
from heapq import heapify, heappush
from typing import TYPE_CHECKING, Any

from netsim.errors import BuildError, SimulationError
from netsim.kernel.events import NORMAL
from netsim.kernel.monitor import refresh_rank
from netsim.kernel.states import READY
from netsim.kernel.task import SET_PERIOD_RULES, check_time

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.job import Job
    from netsim.kernel.task import Task

__all__ = ["Arrivals"]


def _noop(_ev: Any) -> None:
    """The callback of a cancelled release entry (its place in the heap is kept, so no re-heapify)."""


class Arrivals:
    """Jittered and sporadic releases and run-time task parameters (mixed into :class:`Kernel`)."""

    #: ``(task, job_id) -> arrival`` of the jittered jobs (None until the first one)
    _arrivals: "dict[tuple[str, int], int] | None" = None

    # provided by Kernel
    name: str
    env: Any
    halted: bool
    job_records: Any
    policy: Any
    tasks: dict[str, Task]
    _sim: Any
    _queue: list[Any]
    _eid: Any
    _ready: list[Any]
    _running: Job | None
    _get: Callable[..., Any]
    _release: Callable[..., Job]
    _request_dispatch: Callable[[], None]
    _request_dispatch_deferred: Callable[[], None]
    _on_periodic_release: Callable[[Any], None]

    # ================================================================= build
    def _schedule_first_release(self, task: Task) -> None:
        """Push the first self-release of ``task`` (periodic or sporadic) at its offset from now."""
        spec = task.spec
        now = self._sim.now
        task.first_release = now + spec.offset
        if spec.release_jitter is None and spec.min_interarrival is None:
            callback = self._on_periodic_release  # the plain path: no draw, nothing extra per release
        else:
            task.rng = self.env.rng(f"kernel.{self.name}.release.{spec.name}")
            callback = self._on_timed_release
        heappush(self._queue, (now + spec.offset, NORMAL, next(self._eid), (callback, task)))

    # ================================================================= event-loop callbacks
    def _on_timed_release(self, ev: tuple) -> None:
        """A nominal release of a jittered periodic task or of a sporadic task."""
        task: Task = ev[1]
        if self.halted:  # the node stopped (its battery ran out): no more releases
            return
        spec = task.spec
        now = self._sim.now
        if spec.period is not None:
            gap = spec.period
        else:
            extra = spec.extra_interarrival
            assert spec.min_interarrival is not None  # no period: a sporadic task, which has one (TaskSpec.checked)
            gap = spec.min_interarrival + (0 if extra is None else extra.draw(task.rng))
        heappush(self._queue, (now + gap, NORMAL, next(self._eid), (self._on_timed_release, task)))
        jitter = spec.release_jitter
        delay = 0 if jitter is None else jitter.draw(task.rng)
        if delay <= 0:
            if jitter is None:
                self._release(task, None)
            else:
                self._arrived(self._release(task, None, now))
            self._request_dispatch()
        else:
            heappush(self._queue, (now + delay, NORMAL, next(self._eid), (self._on_jittered_arrival, (task, now))))

    def _on_jittered_arrival(self, ev: tuple) -> None:
        if self.halted:
            return
        task, nominal = ev[1]
        self._arrived(self._release(task, None, nominal))
        self._request_dispatch()

    def _arrived(self, job: "Job") -> None:
        """Keep a jittered job's arrival for its record (filled in when the run ends: no work for other jobs)."""
        if self._arrivals is None:
            self._arrivals = {}
        self._arrivals[(job.task_name, job.job_id)] = job.arrival  # type: ignore[assignment]

    def _fill_arrivals(self) -> None:
        """Set ``arrival`` on the records of the jittered jobs (called by ``_finalize`` at the end of a run)."""
        arrivals = self._arrivals
        records = self.job_records
        if not arrivals or not isinstance(records, list):  # a JobSummary keeps no per-job records
            return
        for rec in records:
            if rec.arrival is None:
                got = arrivals.get((rec.task, rec.job_id))
                if got is not None:
                    rec.arrival = got

    # ================================================================= run-time parameters
    def set_period(self, task: str, period: int, rule: str | None = None) -> None:
        """Change the period of periodic task ``task`` (TrueTime's ``ttSetPeriod``).

        ``rule`` (default: the task's ``set_period``, see the module notes): with ``"next_release"`` the next
        release comes ``period`` after the task's last nominal release (now, if that has passed); with
        ``"keep_armed"`` the release already scheduled stays and the ones after it are ``period`` apart. Before
        the first release, the first release stays at the offset. A relative deadline equal to the old period
        (an implicit deadline) follows the new period; another deadline is kept.

        Raises
        ------
        SimulationError
            For an unknown task, a task that is not periodic, or a period that is not a positive int of ns.
        """
        t = self._get(self.tasks, task, "task")
        spec = t.spec
        if spec.period is None:
            raise SimulationError(f"node '{self.name}': set_period('{task}'): the task is not periodic (only a "
                                  "periodic task's period can change)")
        new = _checked(self.name, task, "period", period)
        rule = spec.set_period if rule is None else rule
        if rule not in SET_PERIOD_RULES:
            raise SimulationError(f"node '{self.name}': set_period('{task}'): rule must be one of "
                                  f"{', '.join(SET_PERIOD_RULES)}, got {rule!r}")
        old = spec.period
        deadline = new if spec.deadline == old else spec.deadline
        self._replace_spec(t, period=new, deadline=deadline)
        if rule == "keep_armed":  # the armed release reads the new period when it schedules the next one
            self._rekey(t)
            return
        now = self._sim.now
        entry = self._cancel_release(t)
        if entry is not None:
            when, callback = entry
            if when != t.first_release:  # after the first release: one new period after the last nominal one
                when = max(now, when - old + new)
            heappush(self._queue, (when, NORMAL, next(self._eid), (callback, t)))
        self._rekey(t)

    def set_priority(self, task: str, priority: float) -> None:
        """Change the priority of ``task`` (TrueTime's ``ttSetPriority``; lower is more urgent).

        Under a policy that ranks by priority (``fp``, ``np_fp``) the task's released jobs are re-ranked at
        once and the CPU is re-dispatched (a job that is now less urgent than a ready one is preempted).

        Raises
        ------
        SimulationError
            For an unknown task or a priority that is not a number.
        """
        t = self._get(self.tasks, task, "task")
        if isinstance(priority, bool) or not isinstance(priority, (int, float)):
            raise SimulationError(f"node '{self.name}': set_priority('{task}'): the priority must be a number "
                                  f"(lower = more urgent), got {priority!r}")
        self._replace_spec(t, priority=priority)
        self._rekey(t)

    def set_deadline(self, task: str, deadline: int) -> None:
        """Change the relative deadline of ``task`` for the jobs released from now on (``ttSetDeadline``).

        Raises
        ------
        SimulationError
            For an unknown task or a deadline that is not a positive int of ns.
        """
        t = self._get(self.tasks, task, "task")
        self._replace_spec(t, deadline=_checked(self.name, task, "deadline", deadline))
        self._rekey(t)

    # ================================================================= helpers
    def _replace_spec(self, task: Task, **changes: Any) -> None:
        spec = task.spec.replaced(**changes)
        try:
            self.policy.check(self.name, spec)
        except BuildError as exc:  # a policy refuses at build time; here it is a run-time error
            raise SimulationError(f"node '{self.name}': changing {', '.join(changes)} of task '{task.name}': "
                                  f"{exc}") from None
        task.spec = spec

    def _cancel_release(self, task: Task) -> tuple[int, Any] | None:
        """Disable ``task``'s pending release entry; ``(time, callback)`` it had, or None if there is none.

        The entry keeps its place in the heap with a no-op callback (so the heap needs no re-ordering); a scan
        of the heap is paid only by the rare parameter change, never by releases.
        """
        queue = self._queue
        ours = (self._on_periodic_release, self._on_timed_release)
        for i, entry in enumerate(queue):
            item = entry[3]
            if type(item) is tuple and len(item) == 2 and item[1] is task and item[0] in ours:
                queue[i] = (entry[0], entry[1], entry[2], (_noop, None))
                return entry[0], item[0]
        return None

    def _rekey(self, task: Task) -> None:
        """Recompute the policy key of ``task`` and of its released jobs; re-dispatch if a rank changed."""
        policy = self.policy
        task.key = None
        jobs = ([task.active] if task.active is not None else []) + list(task.queue)
        changed = False
        key = None
        for job in jobs:
            key = policy.key(job)
            rank = (1, key)
            if rank == job._base_rank:
                continue
            changed = True
            if job._held is not None:  # a monitor user: its own rank changes, monitors may lend a higher one
                job._own_rank = rank
                refresh_rank(job)
                continue
            lent = job._rank != job._base_rank  # a started non-preemptible job keeps its rank
            job._base_rank = rank
            if not lent:
                job._rank = rank
        if jobs and policy.static:
            task.key = key  # the task's own key (a job's rank may be lent by a monitor)
        if changed:
            ready = self._ready
            ready[:] = [(j._rank, seq, j) for _, seq, j in ready if j._state == READY]
            heapify(ready)
            self._request_dispatch_deferred()


def _checked(node: str, task: str, field: str, value: Any) -> int:
    try:
        ns = check_time(node, task, field, value, positive=True)
    except BuildError as exc:  # at run time it is a SimulationError
        raise SimulationError(str(exc)) from None
    assert ns is not None
    return ns

