"""A scenario's tasks, handlers and CAN message streams as the analysis' types (:class:`RTATask`, :class:`CanMessage`).

The one place that maps a validated scenario to the analysis: ``netsim analyze`` (:mod:`netsim.cli.analyze`)
compares what it gives with a run and prints the table. What the scenario does not say (the period of a task
released by messages or by program code, the transmission time of a frame) comes from the run through the
callbacks the caller passes.

Mapping rules
-------------
- Execution times count at their largest value: the ``wcet`` field, else the ``execution`` distribution's
  :meth:`~netsim.distributions.Distribution.upper_bound`, plus a sampler's ``after_send``; two context switches
  per job. A task whose execution or release jitter is unbounded gets no bound (said in ``skipped``).
- On a node with speed scaling, execution times (not context switches or ISR latencies) count at the slowest speed
  the node can run, ``ceil(C / s)`` (:func:`netsim.analysis.platform.slowest_speed` gives ``s`` and the rule).
- Periodic ISR loads and handlers enter above every task (priority ``-1e6``); a handler's period is its timer's,
  else the shortest gap between its runs.
- A ``periodic`` task enters with its period, a ``sporadic`` one with its ``min_interarrival``, any other with the
  shortest gap between its releases in the run. ``release_jitter`` enters as ``J`` = its largest value.
- Priorities: ``fp``/``np_fp`` the task's, ``rm`` the period, ``dm``/``edf`` the deadline.
- Tasks using a node's sync objects get their blocking terms (:mod:`netsim.analysis.sync_terms`).
- A CAN message stream (sender, priority) has its single periodic sending task's period and the jitter
  ``R - C`` of that task's bound, else the shortest gap between its messages (event-driven).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Callable

from netsim.analysis.can import CanMessage, can_analysis
from netsim.analysis.platform import Speed, stretch
from netsim.analysis.rta import RTATask, response_times
from netsim.analysis.sync_terms import NodeSyncAnalysis
from netsim.timebase import parse_time

if TYPE_CHECKING:
    from netsim.scenario.schema import HandlerSpec, NodeSpec, TaskSpec

__all__ = ["ISR_PRIORITY", "NodeTasks", "interface_delay", "message_period", "node_tasks", "response_bounds",
           "wcet_ns"]

#: The priority handlers and ISR loads enter the analysis with (above every task).
ISR_PRIORITY = -1_000_000


def wcet_ns(entry: TaskSpec | HandlerSpec) -> int | None:
    """Largest execution time of a scenario task or handler (ns), ``None`` when unbounded."""
    wcet = getattr(entry, "wcet", None)  # a task's own bound (a handler has none)
    if wcet is not None:
        base = int(wcet)
    else:
        ex = entry.execution_time()
        bound = 0 if ex is None else ex.upper_bound()
        if bound is None:
            return None
        base = int(bound)
    after = entry.params.get("after_send") if getattr(entry, "program", "") == "sampler" else None
    if after:
        base += int(parse_time(after)) if isinstance(after, str) else int(after)
    return base


@dataclass
class NodeTasks:
    """One node's tasks for the analysis.

    Attributes
    ----------
    items
        ISR loads, handlers and tasks as :class:`RTATask` (blocking terms included).
    sync
        The node's sync analysis (blocking notes, tasks without a bound of their own).
    notes
        Task -> how it was mapped, where that differs from the plain RTA.
    skipped
        ``(task, why)`` for the tasks that get no bound.
    how
        The analysis the node's policy calls for (``"FP RTA"``, ``"non-preemptive FP RTA"`` ...).
    """

    items: list[RTATask]
    sync: NodeSyncAnalysis
    notes: dict[str, str] = field(default_factory=dict)
    skipped: list[tuple[str, str]] = field(default_factory=list)
    how: str = ""


def node_tasks(node: NodeSpec, loads: dict[str, Any], min_gap: Callable[[str], int | None],
               speed: Speed | None = None) -> NodeTasks:
    """The analysis' view of one scenario node.

    Parameters
    ----------
    node
        The scenario's :class:`~netsim.scenario.schema.NodeSpec`.
    loads
        The node kernel's periodic loads by name (from the scenario or created by programs at build).
    min_gap
        ``min_gap(name)``: the shortest gap (ns) between the releases of a task or handler in the run, or None.
    speed
        The speed to map execution times at (:func:`netsim.analysis.platform.slowest_speed`; default 1): each
        ``C`` becomes ``ceil(C / s)``, context switches and handler latencies unchanged.
    """
    policy = node.policy
    cs = int(node.context_switch)
    items: list[RTATask] = []
    notes: dict[str, str] = {}
    skipped: list[tuple[str, str]] = []
    sync = NodeSyncAnalysis(node)  # monitors, mailboxes ...: blocking terms, self-suspension
    s = speed.value if speed is not None else Fraction(1)
    scaled = s is not None and s != 1
    def at_speed(c: int | None) -> int | None:
        return None if c is None or s is None else stretch(c, s)

    for load in loads.values():  # periodic ISR loads
        items.append(RTATask(load.name, int(load.execution), int(load.period), priority=ISR_PRIORITY))
    covered = set(loads) | {load.handler for load in loads.values() if load.handler}
    blind: list[str] = []
    for h in node.handlers:
        if h.name in covered:
            continue
        timer = getattr(h.trigger, "timer", None) if h.trigger is not None else None
        period = int(timer.period) if timer is not None and timer.period else min_gap(h.name)
        c = at_speed(wcet_ns(h))
        if period is None or c is None:
            blind.append(h.name)
            continue
        items.append(RTATask(h.name, c + int(h.latency or 0), period, priority=ISR_PRIORITY))
    how = "non-preemptive FP RTA" if policy == "np_fp" else f"{policy.upper()} RTA"
    retimed = {name: t.name for t in node.tasks if t.program == "feedback_scheduler"
               for name in t.params.get("tasks", []) if isinstance(name, str)}
    for t in node.tasks:
        c = at_speed(sync.timing(t, wcet_ns(t)))
        if speed is not None and speed.value is None:
            skipped.append((t.name, speed.rule))
            continue
        if scaled and node.sync is not None:
            skipped.append((t.name, "sync objects on a node with speed scaling: blocking terms are not scaled"))
            continue
        if blind:
            skipped.append((t.name, f"handler {', '.join(blind)}: no period or execution time to analyse"))
            continue
        if c is None:
            skipped.append((t.name, "execution time unbounded (normal without max)"))
            continue
        if t.params.get("solve_time"):
            skipped.append((t.name, "execution includes the solver's time (solve_time): no bound known"))
            continue
        period = int(t.period) if t.release_kind == "periodic" and t.period else None
        if t.release_kind == "sporadic" and t.min_interarrival:
            period = int(t.min_interarrival)
            notes[t.name] = f"sporadic: T = min_interarrival ({period / 1e6:g} ms)"
        jitter = 0 if t.release_jitter is None else t.release_jitter.upper_bound()
        if jitter is None:
            skipped.append((t.name, "release jitter unbounded (exponential, or normal without max): no bound"))
            continue
        if jitter:
            notes[t.name] = (f"{notes.get(t.name, how)}; R = J + w from the nominal release "
                             f"(J = {jitter / 1e6:g} ms; response_from_arrival_s <= w)")
        if t.name in retimed:  # kernel.set_period at run time: the analysis knows the nominal periods only
            notes[t.name] = f"{notes.get(t.name, how)}; at the nominal period (set at run time by {retimed[t.name]})"
        if period is None:
            period = min_gap(t.name)
            notes[t.name] = f"{t.release_kind}: sporadic, T = shortest gap in the run"
            if period is None:
                skipped.append((t.name, "fewer than two releases in the run: no period to analyse"))
                continue
        if speed is not None and speed.rule:
            notes[t.name] = f"{notes.get(t.name, how)}; {speed.rule}"
        deadline = int(t.deadline) if t.deadline else period
        if policy in ("fp", "np_fp"):
            prio = float(t.priority if t.priority is not None else 0)
        elif policy == "rm":
            prio = float(period)
        else:
            prio = float(deadline)
        items.append(RTATask(t.name, c + 2 * cs, period, deadline=deadline, priority=prio, jitter=jitter))
    items, skipped = sync.apply(items, skipped)
    return NodeTasks(items, sync, notes=notes, skipped=skipped, how=how)


def response_bounds(policy: str, items: list[RTATask]) -> dict[str, int | None]:
    """Each task's response-time bound (ns; None: unbounded) under ``policy``: the fixed-priority RTA, or for
    ``np_fp`` the non-preemptive recurrence of CAN (:mod:`netsim.analysis.can`, one-tick arbitration)."""
    if policy == "np_fp":
        msgs = [CanMessage(it.name, int(it.priority or 0), it.period, max(it.wcet, 1),
                           deadline_ns=it.relative_deadline, jitter_ns=it.jitter) for it in items]
        return {r.name: r.response_ns for r in can_analysis(msgs, tau_ns=1)}
    return response_times(items)


def message_period(node: NodeSpec, network: str, priority: int, bounds: dict[tuple[str, str], tuple[int, int]],
                   node_name: str) -> tuple[int | None, int, str]:
    """``(period, jitter, note)`` of a CAN message stream from its sending task on ``node``.

    The stream's single periodic sender (a task whose ``params`` name the network and the priority) gives the
    period, and the jitter ``R - C`` of its response bound (``bounds``: ``(node, task) -> (R, C)``); without one,
    the period is None (the caller takes the shortest gap of the run: event-driven).
    """
    senders = [t for t in node.tasks
               if t.params.get("network") == network and int(t.params.get("priority", 0)) == int(priority)]
    if len(senders) == 1 and senders[0].release_kind == "periodic" and senders[0].period:
        b = bounds.get((node_name, senders[0].name))
        if b is None:
            return int(senders[0].period), 0, "J = 0 (sender has no bound)"
        return int(senders[0].period), b[0] - b[1], f"T = {senders[0].name} period, J = R - C"
    return None, 0, "event-driven: T = shortest gap in the run"


def interface_delay(params: Any, node: str, which: str) -> int:
    """A node's ``pre_delay`` or ``post_delay`` on a network: its own override, else the network's."""
    own = getattr(params.node_delays.get(node), which, None) if node in params.node_delays else None
    return int(own) if own is not None else int(getattr(params, which))
