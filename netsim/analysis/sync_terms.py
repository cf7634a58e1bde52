"""The analysis of tasks that use a node's sync objects: execution times, blocking terms, self-suspension.

A program that uses monitors, mailboxes, semaphores or events declares its timing (``Program.timing(params,
execution_ns, node)`` returning a :class:`~netsim.programs.sync_programs.SyncTiming`): the execution time of a
job, its critical sections and what it may block on. From them:

- each task's RTA gets the blocking term ``B_i`` of :func:`netsim.analysis.blocking.blocking_terms` from the
  node's monitors (``inherit`` and ``ceiling`` monitors separately, their terms added, which is safe);
- a task that may block on a mailbox, semaphore or event (self-suspension) gets no bound of its own; for the
  tasks below it, its release jitter is taken as ``D - C`` (its execution can fall anywhere in its deadline
  window, which covers the deferred execution a suspension causes, as long as it meets its deadlines);
- a monitor without inheritance (``none``) leaves the tasks it can block without a bound (priority inversion).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

from netsim.analysis.blocking import CriticalSection, blocking_terms
from netsim.analysis.rta import RTATask

if TYPE_CHECKING:
    from netsim.scenario.schema import NodeSpec, TaskSpec

__all__ = ["program_timing", "with_blocking", "NodeSyncAnalysis"]


def program_timing(task: TaskSpec, execution: int | None, node: NodeSpec) -> Any:
    """The :class:`SyncTiming` of a scenario task whose program declares ``timing``, else ``None``."""
    try:
        cls = task.plugin()
    except Exception:  # noqa: BLE001 - an unknown program was refused by validate already
        return None
    timing = getattr(cls, "timing", None)
    if not callable(timing):
        return None
    return timing(task.validated_params(), execution, node)


class NodeSyncAnalysis:
    """What one node's sync objects change in its tasks' analysis (used by :mod:`netsim.analysis.from_scenario`).

    Parameters
    ----------
    node
        The scenario node.
    """

    def __init__(self, node: NodeSpec) -> None:
        self.node = node
        self.sections: dict[str, dict[str, int]] = {}
        self.suspends: dict[str, str] = {}
        self.notes: dict[str, str] = {}
        self.unbounded: dict[str, str] = {}

    def timing(self, task: TaskSpec, execution: int | None) -> int | None:
        """The task's execution time for the RTA; records its critical sections and what it may block on."""
        timing = program_timing(task, execution, self.node)
        if timing is None:
            return execution
        self.sections[task.name] = dict(timing.sections)
        if timing.suspends_on:
            self.suspends[task.name] = ", ".join(timing.suspends_on)
        return timing.wcet

    def apply(self, items: list[RTATask], skipped: list[tuple[str, str]]
              ) -> tuple[list[RTATask], list[tuple[str, str]]]:
        """The RTA tasks with their blocking terms and suspension jitter (:func:`with_blocking`), and ``skipped``
        with the tasks that get no bound of their own (:meth:`no_bound` says why)."""
        items, self.notes, self.unbounded = with_blocking(items, self.node, self.sections, self.suspends)
        names = {it.name for it in items}
        return items, skipped + [(t.name, why) for t in self.node.tasks
                                 if t.name in names and (why := self.no_bound(t.name))]

    def note(self, name: str) -> str:
        """``"; B = ... ms (inherit)"`` for a task with a blocking term, else ``""``."""
        return f"; {self.notes[name]}" if name in self.notes else ""

    def no_bound(self, name: str) -> str | None:
        """Why task ``name`` gets no bound (a monitor without inheritance, or it suspends), else ``None``."""
        if name in self.unbounded:
            return self.unbounded[name]
        if name in self.suspends:
            return f"blocks on {self.suspends[name]}: self-suspending, no RTA bound"
        return None


def with_blocking(items: list[RTATask], node: NodeSpec, sections: dict[str, dict[str, int]],
                  suspends: dict[str, str]) -> tuple[list[RTATask], dict[str, str], dict[str, str]]:
    """The RTA tasks with their blocking terms and suspension jitter.

    Parameters
    ----------
    items
        The node's RTA tasks (handlers and loads included, at their top priorities).
    node
        The scenario node (its ``sync.monitors`` give each monitor's protocol).
    sections
        Task -> {monitor -> longest section (ns)}.
    suspends
        Task -> what it may block on.

    Returns
    -------
    items, notes, unbounded
        The tasks with ``blocking`` (and ``jitter`` for suspending ones) set; a note per task with a blocking
        term; the tasks a monitor without inheritance can block (why).
    """
    monitors = {} if node.sync is None else node.sync.monitors
    prio = {it.name: it.priority for it in items}
    groups: dict[str, list[CriticalSection]] = {"inherit": [], "ceiling": [], "none": []}
    for task, secs in sections.items():
        if task not in prio:
            continue
        for mon, length in secs.items():
            protocol = monitors[mon].protocol if mon in monitors else "inherit"
            groups[protocol].append(CriticalSection(task, mon, int(length)))
    blocking = {name: 0 for name in prio}
    used = []
    for protocol in ("inherit", "ceiling"):
        if groups[protocol]:
            used.append(protocol)
            for name, b in blocking_terms(prio, groups[protocol], protocol).items():
                blocking[name] += b
    unbounded: dict[str, str] = {}
    if groups["none"]:  # who can be blocked: the same tasks the inheritance bound would count
        for name, b in blocking_terms(prio, groups["none"], "inherit").items():
            if b:
                mons = sorted({s.monitor for s in groups["none"]})
                unbounded[name] = (f"monitor {', '.join(repr(m) for m in mons)} without inheritance (protocol none): "
                                   "blocking unbounded")
    notes = {name: f"B = {b / 1e6:g} ms ({' + '.join(used)})" for name, b in blocking.items() if b}
    out = []
    for it in items:
        it = replace(it, blocking=it.blocking + blocking.get(it.name, 0))
        if it.name in suspends:
            it = replace(it, jitter=max(it.jitter, it.relative_deadline - it.wcet))
        out.append(it)
    return out, notes, unbounded
