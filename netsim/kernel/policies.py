"""Scheduling policies: which ready task job gets the CPU.

A policy maps each task job to a *key*; the smaller key is more urgent. The kernel compares keys when a
job becomes ready; equal keys are served first come, first served and never preempt each other.
Interrupt handlers are outside the policy: every handler beats every task.

Built-in policies (registered under kind ``"policy"``):

========== ==============================================================================
``fp``     fixed priority: key = the task's ``priority`` (required)
``rm``     rate monotonic: key = period (sporadic: min gap; aperiodic last); D <= T
``dm``     deadline monotonic: key = relative deadline (tasks without one last); D <= T
``edf``    earliest deadline first: key = absolute deadline of the job (none: last)
``np_fp``  ``fp`` without preemption between tasks (handlers still preempt)
``np_edf`` ``edf`` without preemption between tasks
``tt``     time-triggered: a static schedule table (:mod:`netsim.kernel.timetable`) activates
           tasks at their slots; the latest activation runs first, other tasks in the gaps
========== ==============================================================================

Custom policies subclass :class:`Policy` and override :meth:`Policy.key` (and optionally
:meth:`Policy.check` and :attr:`Policy.preemptive`); pass an instance to ``Kernel(policy=...)`` or name
it as ``"module:Class"``.

A key is a job's *own* urgency. While a job owns a monitor (:mod:`netsim.kernel.monitor`) the dispatcher orders it by
its *effective* urgency instead: the most urgent of its own and those of the jobs waiting for its monitors
(priority inheritance; under ``edf`` that is the earliest waiting deadline), or the monitor's ceiling (the
immediate ceiling protocol, static policies only: ``fp``, ``rm``, ``dm``, ``np_fp``). Policies need not do
anything for it: the effective urgency is a rank the monitor sets on the job, compared like any other key.

Every policy name is resolved by :func:`find_policy` (the kernel, ``netsim validate`` and the scenario
builder alike); :func:`resolve_policy` turns its result into the instance a kernel uses.
"""

from __future__ import annotations

import abc
import difflib
import math
from typing import TYPE_CHECKING, Any, ClassVar

from netsim.errors import BuildError, ConfigError
from netsim.kernel.task import CheckedTask, task_error
from netsim.registry import entries, lookup, register
from netsim.timebase import format_time

if TYPE_CHECKING:  # pragma: no cover
    from netsim.kernel.job import Job

__all__ = [
    "Policy",
    "FixedPriority",
    "RateMonotonic",
    "DeadlineMonotonic",
    "EarliestDeadlineFirst",
    "NonPreemptiveFixedPriority",
    "NonPreemptiveEDF",
    "TimeTriggered",
    "BUILTIN_POLICIES",
    "find_policy",
    "is_builtin_policy",
    "resolve_policy",
]


class Policy(abc.ABC):
    """Interface of a scheduling policy.

    Attributes
    ----------
    name : str
        Short name used in messages.
    preemptive : bool
        ``False``: a started task job keeps the CPU until it finishes or blocks (handlers still preempt).
    static : bool
        ``True`` when the key depends only on the task (computed once per task, faster).
    """

    name: ClassVar[str] = "custom"
    preemptive: ClassVar[bool] = True
    static: ClassVar[bool] = False

    def check(self, node: str, spec: CheckedTask) -> None:
        """Reject a task this policy cannot schedule (raise via :func:`~netsim.kernel.task.task_error`)."""

    @abc.abstractmethod
    def key(self, job: "Job") -> Any:
        """Urgency of ``job`` (smaller = more urgent); called when the job is released.

        ``job.spec`` is the task's :class:`TaskSpec`; ``job.release`` and ``job.deadline`` (absolute) are set.
        """

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


@register("policy", "fp", "fixed priority: the task's `priority` (lower = more urgent)")
class FixedPriority(Policy):
    """Fixed priority given explicitly per task (TrueTime's ``prioFP``)."""

    name = "fp"
    static = True

    def check(self, node: str, spec: CheckedTask) -> None:
        if spec.priority is None:
            raise task_error(node, spec.name, "priority",
                             f"is required under policy '{self.name}'; add e.g. 'priority: 1' (lower is more "
                             "urgent) or use policy 'rm', 'dm' or 'edf'")

    def key(self, job: "Job") -> Any:
        return job.spec.priority


class _Constrained(Policy):
    """Shared check: relative deadline must not exceed the period (the policy's optimality assumption)."""

    def check(self, node: str, spec: CheckedTask) -> None:
        period = spec.period if spec.period is not None else spec.min_interarrival  # sporadic: the minimum gap
        if period is not None and spec.deadline is not None and spec.deadline > period:
            what = "period" if spec.period is not None else "min_interarrival"
            raise task_error(
                node, spec.name, "deadline",
                f"{format_time(spec.deadline)} exceeds the {what} {format_time(period)}, which policy "
                f"'{self.name}' does not allow; shorten the deadline or use policy 'fp' or 'edf'",
            )


@register("policy", "rm", "rate monotonic: shorter period = more urgent")
class RateMonotonic(_Constrained):
    """Rate monotonic: priority by period; aperiodic tasks rank below every periodic one."""

    name = "rm"
    static = True

    def key(self, job: "Job") -> Any:
        spec = job.spec
        period = spec.period if spec.period is not None else spec.min_interarrival  # sporadic: the minimum gap
        return math.inf if period is None else period


@register("policy", "dm", "deadline monotonic: shorter relative deadline = more urgent")
class DeadlineMonotonic(_Constrained):
    """Deadline monotonic: priority by relative deadline; tasks without a deadline rank last."""

    name = "dm"
    static = True

    def key(self, job: "Job") -> Any:
        deadline = job.spec.deadline
        return math.inf if deadline is None else deadline


@register("policy", "edf", "earliest deadline first: earlier absolute deadline = more urgent")
class EarliestDeadlineFirst(Policy):
    """Earliest deadline first on the absolute deadline of each job."""

    name = "edf"

    def key(self, job: "Job") -> Any:
        return math.inf if job.deadline is None else job.deadline


@register("policy", "np_fp", "non-preemptive fixed priority (handlers still preempt)")
class NonPreemptiveFixedPriority(FixedPriority):
    """Fixed priority where a started task job runs until it finishes or blocks."""

    name = "np_fp"
    preemptive = False


@register("policy", "np_edf", "non-preemptive EDF (handlers still preempt)")
class NonPreemptiveEDF(EarliestDeadlineFirst):
    """EDF where a started task job runs until it finishes or blocks."""

    name = "np_edf"
    preemptive = False


@register("policy", "tt", "time-triggered: the node's static schedule table activates tasks at their slots")
class TimeTriggered(Policy):
    """Time-triggered dispatch (TrueTime's time-triggered dispatcher, OSEKtime): a
    :class:`~netsim.kernel.timetable.Timetable` activates its tasks at their slot starts.

    Among the jobs of slotted tasks the latest activation is the most urgent (OSEKtime's stack order: a job that
    overruns its slot is preempted by the next slot's activation and resumes after it); jobs of other tasks
    (released by messages, program code or their own period) run in the gaps, first come first served.

    Attributes
    ----------
    slotted : frozenset[str]
        The tasks the node's table activates (set by :func:`~netsim.kernel.timetable.create_timetable`).
    """

    name = "tt"
    slotted: frozenset[str] = frozenset()

    def key(self, job: "Job") -> Any:
        if job.task_name in self.slotted:
            return (0, -job.release)
        return (1, job.release)


#: The built-in policies by name (resolved without loading every plugin of the registry).
BUILTIN_POLICIES: dict[str, type[Policy]] = {
    cls.name: cls
    for cls in (FixedPriority, RateMonotonic, DeadlineMonotonic, EarliestDeadlineFirst,
                NonPreemptiveFixedPriority, NonPreemptiveEDF, TimeTriggered)
}


def is_builtin_policy(name: Any) -> bool:
    """True when ``name`` is one of the kernel's own policies (``fp``, ``rm``, ``dm``, ``edf``, ``np_fp``,
    ``np_edf``, ``tt``): resolving it runs no code from outside netsim."""
    return isinstance(name, str) and name in BUILTIN_POLICIES


def find_policy(name: str) -> "type[Policy] | Policy":
    """The policy class (or registered instance) called ``name``, without instantiating it.

    The one place a policy name is looked up: the kernel (:func:`resolve_policy`), ``netsim validate`` and
    the scenario builder all resolve names here. Built-in names first, then the registry (kind
    ``"policy"``: plugins and ``"module:Class"`` paths).

    Raises
    ------
    ConfigError
        When the name is unknown (with a "did you mean" or the list of known policies), its path cannot be
        loaded, or it names something that is not a :class:`Policy`.
    """
    if not isinstance(name, str):
        raise ConfigError(f"policy must be a name such as 'fp', 'rm', 'dm' or 'edf', got {name!r}")
    if name in BUILTIN_POLICIES:
        return BUILTIN_POLICIES[name]
    try:
        obj = lookup("policy", name)
    except ConfigError as exc:
        if ":" in name:
            raise
        known = sorted({*BUILTIN_POLICIES, *(e.name for e in entries("policy"))})
        close = difflib.get_close_matches(name, known, n=1, cutoff=0.4)
        hint = f"; did you mean '{close[0]}'?" if close else f" (known: {', '.join(known)})"
        raise ConfigError(f"unknown policy '{name}'{hint}") from exc
    if not (isinstance(obj, Policy) or (isinstance(obj, type) and issubclass(obj, Policy))):
        raise ConfigError(f"'{name}' is not a scheduling Policy (got {obj!r}); `netsim list policies` shows them")
    return obj


def resolve_policy(policy: "str | type[Policy] | Policy", node: str) -> Policy:
    """A :class:`Policy` instance from a name (see :func:`find_policy`), a Policy class or an instance.

    Raises
    ------
    BuildError
        Naming the node, when the policy cannot be found.
    """
    if isinstance(policy, Policy):
        return policy
    if isinstance(policy, type) and issubclass(policy, Policy):
        return policy()
    try:
        obj = find_policy(policy)
    except ConfigError as exc:
        where = "scheduling policy: " if isinstance(policy, str) and ":" in policy else ""
        raise BuildError(f"node '{node}': {where}{exc.message}") from None
    return obj() if isinstance(obj, type) else obj
