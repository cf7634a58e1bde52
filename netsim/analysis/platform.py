"""What a node's CPU adds to the analysis: speed scaling, several cores, bandwidth servers, a schedule table.

:func:`netsim.analysis.from_scenario.node_tasks` maps a node's tasks at its slowest speed
(:func:`slowest_speed`); ``netsim analyze`` (:mod:`netsim.cli.analyze`) then picks the test the node's
scheduling calls for. The rules, each stated in the row it gives:

Speed (``nodes.<n>.speed``, :mod:`netsim.kernel.speed`)
    Execution work ``C`` (written for speed 1) takes ``ceil(C / s)`` ns at speed ``s``; context switches and a
    handler's latency do not scale. A bound holds at the slowest speed the node can run: the initial speed and
    every speed of its ``speed_governor`` tasks; a program from outside netsim may call ``set_speed``, so then
    the slowest of ``speed_levels``, and without levels no bound (any speed in (0, 1] is allowed).
Partitioned cores (``multicore: partitioned``)
    No job migrates: each core is its own uniprocessor (FP RTA or EDF demand test) over the tasks whose ``core``
    it is; handlers run on core 0, as the kernel runs them (:mod:`netsim.kernel.multicore`).
Global EDF (``multicore: global``, ``policy: edf``)
    The density test of Goossens, Funk & Baruah (2003), extended to constrained deadlines by Bertogna et al.
    (2005): with ``lambda_i = C_i / min(D_i - J_i, T_i)``, the set is schedulable on ``m`` cores if
    ``sum lambda_i <= m - (m - 1) max lambda_i`` (:func:`gfb_test`). It is only sufficient: a failed test says
    "not shown schedulable", never "not schedulable". A migration costs ``migration_cost`` at most once per
    release of another task within the job's deadline (global EDF preempts only at releases).
Global fixed priorities (``fp``, ``rm``, ``dm``)
    The response-time test of Bertogna & Cirinei (2007; sufficient): a higher-priority task ``i`` with bound
    ``R_i`` does at most ``W_i(L) = N C_i + min(C_i, L + R_i - C_i - N T_i)``, ``N = floor((L + R_i - C_i) / T_i)``,
    of work in a window ``L``; a job of ``k`` not done by ``R`` was kept out more than ``R - C_k`` while all ``m``
    cores ran such work, so ``R`` bounds ``k`` when ``C_k + floor(sum_i min(W_i(R), R - C_k + 1) / m) <= R``
    (:func:`global_fp_bounds` tries ``R = C_k``, then steps of the set's common time grain, up to ``D_k``). It
    needs constrained deadlines, no release jitter and distinct priorities; a task with no ``R <= D`` leaves every
    less urgent one without a bound. A migration costs ``migration_cost`` per release of a more urgent task within
    the job's deadline.
Servers (``nodes.<n>.servers``, :mod:`netsim.kernel.servers`)
    The tasks outside servers pass the EDF demand test with each server's bandwidth reserved
    (:func:`~netsim.analysis.rta.edf_schedulable` ``bandwidth=``): then every server deadline is met (isolation,
    Abeni & Buttazzo 1998; Spuri & Buttazzo 1996). A task alone in a CBS with ``C <= Qs`` and
    ``Ts <= T - J`` gets a fresh budget at every arrival: ``R <= J + Ts``. A task alone in a TBS with
    ``ceil(wcet / Us) <= T - J`` has every deadline ``r + ceil(wcet / Us)``: ``R <= J + ceil(wcet / Us)``
    (:func:`served_bound`).
Schedule table (``policy: tt``, :mod:`netsim.kernel.timetable`)
    A slotted job is the node's most urgent from its activation to its slot's end (slots do not overlap), so
    with ``C + 2 x context_switch <= length`` it ends in its slot: ``R <= length`` (slot end - activation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any, Sequence

from netsim.analysis.rta import RTATask

if TYPE_CHECKING:
    from netsim.scenario.schema import NodeSpec, Scenario

__all__ = ["UNBOUNDED", "Speed", "bandwidth", "gfb_test", "global_fp_bounds", "migration_charge", "served_bound",
           "slot_bound", "slowest_speed", "stretch"]


@dataclass(frozen=True)
class Speed:
    """The speed a node's bounds are computed at.

    Attributes
    ----------
    value
        The slowest speed the node can run (exact), ``None`` when none is known (then no bound).
    rule
        How it was found (for the notes; empty at speed 1 without speed scaling).
    """

    value: Fraction | None
    rule: str = ""


def _frac(x: float) -> Fraction:
    from netsim.kernel.speed import speed_fraction  # the kernel's own reading of a speed, so the two cannot drift

    return speed_fraction(x, "speed")


def slowest_speed(node: NodeSpec, scenario: Scenario | None = None) -> Speed:
    """The slowest speed ``node`` can run at (see the module notes for the rule)."""
    if node.speed is None:
        return Speed(Fraction(1))
    speeds = {_frac(node.speed)}
    for t in node.tasks:
        if t.program == "speed_governor":
            speeds |= {_frac(s) for s in t.params.get("speeds", []) if isinstance(s, (int, float))}
    foreign = _foreign_programs(scenario if scenario is not None else None, node)
    if foreign:
        if node.speed_levels is None:
            return Speed(None, f"program {foreign} may set any speed in (0, 1] (no speed_levels): no slowest speed")
        s = min(_frac(x) for x in node.speed_levels)
        return Speed(s, f"C / s at s = {float(s):g}, the slowest of speed_levels (program {foreign} may set it)")
    s = min(speeds)
    how = "its speed" if len(speeds) == 1 else "the slowest of its speed and its speed_governor speeds"
    return Speed(s, f"C / s at s = {float(s):g}, {how}")


def _foreign_programs(scenario: Scenario | None, node: NodeSpec) -> str:
    """A program from outside netsim's modules on any node (it could change this node's speed), or ``""``."""
    from netsim.registry import is_builtin

    entries = [e for n in (scenario.nodes.values() if scenario is not None else [node])
               for e in [*n.tasks, *n.handlers]]
    for e in entries:
        try:
            cls = e.plugin()
        except Exception:  # noqa: BLE001 - an unresolvable program is validate's business; assume the worst
            return str(getattr(e, "program", "?"))
        if not is_builtin(cls):
            return str(getattr(e, "program", "?"))
    return ""


def bandwidth(server: Any) -> Fraction:
    """A server declaration's CPU share: ``budget / period`` for a CBS, ``utilization`` for a TBS (exact)."""
    if server.type == "cbs":
        return Fraction(int(server.budget), int(server.period))
    return Fraction(repr(float(server.utilization))).limit_denominator(1_000_000)


def stretch(work: int, speed: Fraction) -> int:
    """Wall time (ns) of ``work`` ns of execution at ``speed``: ``ceil(work / speed)``, as the kernel plans it."""
    return -(-work * speed.denominator // speed.numerator)


def gfb_test(tasks: Sequence[RTATask], cores: int) -> tuple[bool, Fraction, Fraction]:
    """The GFB density test for global EDF on ``cores`` identical cores (sufficient only).

    Returns
    -------
    ok, total, limit
        ``total = sum C_i / min(D_i - J_i, T_i)`` and ``limit = m - (m - 1) max_i C_i / min(D_i - J_i, T_i)``
        (release jitter ``J`` shortens a job's deadline after its arrival); ``ok = total <= limit``.
    """
    if any(t.relative_deadline - t.jitter <= 0 for t in tasks):
        return False, Fraction(0), Fraction(cores)  # a job may arrive after its deadline
    dens = [Fraction(t.wcet, min(t.relative_deadline - t.jitter, t.period)) for t in tasks]
    if not dens:
        return True, Fraction(0), Fraction(cores)
    total = sum(dens, Fraction(0))
    limit = cores - (cores - 1) * max(dens)
    return total <= limit, total, limit


def global_fp_bounds(tasks: Sequence[RTATask], cores: int, migration: int = 0) -> tuple[dict[str, int | None], str]:
    """Response bounds under global preemptive fixed priorities (Bertogna & Cirinei 2007; see the module notes).

    Returns
    -------
    bounds, why
        Task name -> bound (ns) or ``None``; ``why`` is non-empty when the test does not apply at all.
    """
    if any(t.jitter or t.blocking for t in tasks):
        return {t.name: None for t in tasks}, "release jitter or blocking: the test does not apply"
    if any(t.relative_deadline > t.period for t in tasks):
        return {t.name: None for t in tasks}, "a deadline beyond its period: the test needs D <= T"
    order = sorted(tasks, key=lambda t: float(t.priority or 0))
    if len({t.priority for t in order}) < len(order):
        return {t.name: None for t in tasks}, "equal priorities: the test needs distinct ones"
    grain = 0
    for t in order:
        grain = math.gcd(grain, t.wcet, t.period, t.relative_deadline)
    out: dict[str, int | None] = {}
    done: list[tuple[RTATask, int]] = []  # more urgent tasks with their bounds
    for k in order:
        if len(done) < len(out):  # a more urgent task has no bound: neither has this one
            out[k.name] = None
            continue
        c = k.wcet + migration * sum(-(-k.relative_deadline // i.period) + 1 for i, _ in done)
        step = max(grain, -(-k.relative_deadline // 100_000), 1)
        found = None
        r = c
        while r <= k.relative_deadline:
            load = 0
            for i, ri in done:
                n = (r + ri - i.wcet) // i.period
                work = n * i.wcet + min(i.wcet, max(0, r + ri - i.wcet - n * i.period))
                load += min(work, r - c + 1)
            if c + load // cores <= r:
                found = r
                break
            r = c + (r - c) // step * step + step  # the next point of the grain
        out[k.name] = found
        if found is not None:
            done.append((RTATask(k.name, c, k.period, deadline=k.deadline, priority=k.priority), found))
    return out, ""


def migration_charge(tasks: Sequence[RTATask], cost: int) -> list[RTATask]:
    """Copies of ``tasks`` whose ``C`` includes ``cost`` per release of another task within ``D``: the most
    migrations a job can make under global EDF (a job is preempted only when another job is released)."""
    if not cost:
        return list(tasks)
    out = []
    for t in tasks:
        d = t.relative_deadline
        moves = sum(-(-d // o.period) + 1 for o in tasks if o is not t)
        out.append(RTATask(t.name, t.wcet + moves * cost, t.period, deadline=t.deadline, priority=t.priority,
                           jitter=t.jitter, blocking=t.blocking))
    return out


#: :func:`served_bound`'s value for a task whose response grows without bound.
UNBOUNDED = -1


def served_bound(item: RTATask, server: Any, shared: int, exec_ns: int | None) -> tuple[int | None, str]:
    """The response bound of a task served by ``server`` (a ``ServerDecl``) and why; ``None``: no bound computed,
    :data:`UNBOUNDED`: the response grows without bound.

    Parameters
    ----------
    item
        The task as the analysis maps it (``C`` without context switches: the server's budget counts execution).
    server
        Its server's declaration (``type``, ``budget``, ``period``, ``utilization``).
    shared
        How many tasks the server serves.
    exec_ns
        The task's ``wcet`` field (a TBS's deadlines come from it), or ``None``.
    """
    if shared > 1:
        return None, f"server '{server.name}' serves {shared} tasks: no per-task bound"
    c, gap, j = item.wcet, item.period - item.jitter, item.jitter
    if server.type == "cbs":
        q, ts = int(server.budget), int(server.period)
        if Fraction(c, item.period) > Fraction(q, ts):
            return UNBOUNDED, (f"CBS '{server.name}': task U = {c / item.period:.3g} > Qs/Ts = {q / ts:.3g}: its "
                               "backlog grows without bound")
        if c <= q and ts <= gap:
            return j + ts, (f"CBS '{server.name}' (Abeni & Buttazzo): C <= Qs and Ts <= T - J, a fresh budget at "
                            f"every arrival: R <= J + Ts")
        return None, (f"CBS '{server.name}': C = {c / 1e6:g} ms > Qs = {q / 1e6:g} ms or Ts > T - J: a job spans "
                      "several server periods; no bound computed")
    us = bandwidth(server)
    if exec_ns is None:
        return None, f"TBS '{server.name}': the task has no wcet"
    if Fraction(exec_ns, item.period) > us:
        return UNBOUNDED, (f"TBS '{server.name}': task U = {exec_ns / item.period:.3g} > Us = {float(us):g}: its "
                           "deadlines drift without bound")
    span = -(-exec_ns * us.denominator // us.numerator)
    if span <= gap:
        return j + span, (f"TBS '{server.name}' (Spuri & Buttazzo): deadline r + wcet/Us, met: "
                          f"R <= J + {span / 1e6:g} ms")
    return None, f"TBS '{server.name}': wcet/Us = {span / 1e6:g} ms > T - J: no bound computed"


def slot_bound(name: str, c: int, node: NodeSpec) -> tuple[int | None, str]:
    """A task's response bound on a ``tt`` node from its slots, or ``(None, why)`` (``c``: its execution plus
    two context switches)."""
    table = node.timetable
    slots = [s for s in table.slots if s.task == name] if table is not None else []
    if not slots:
        return None, "runs in the table's gaps (first come first served): no bound"
    if node.handlers:
        return None, "handlers preempt the table's jobs: no slot bound"
    short = min(int(s.length) for s in slots)
    longest = max(int(s.length) for s in slots)
    if c > short:
        rule = table.overrun if table is not None else "continue"
        return None, (f"C = {c / 1e6:g} ms > slot length {short / 1e6:g} ms: a job may overrun its slot "
                      f"(overrun: {rule}): no bound")
    return longest, f"TT slot: R <= slot end - activation (C = {c / 1e6:g} ms <= slot {short / 1e6:g} ms)"
