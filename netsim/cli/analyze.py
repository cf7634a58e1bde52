"""``netsim analyze``: what analysis predicts beside what a run measured.

For one scenario and its run, one row per checked item:

``task``
    The fixed-priority response-time bound (:mod:`netsim.analysis.rta`; policies ``fp``, ``rm``, ``dm``) or the
    non-preemptive one (``np_fp``, the CAN recurrence of :mod:`netsim.analysis.can` with one-tick arbitration)
    vs the worst simulated response (release to finish). Execution times count at their largest value (the
    ``wcet`` field, else the upper end of the ``execution`` distribution, plus a sampler's ``after_send``), with
    two context switches per job. A task released by messages or by program code has no period: it is taken
    as sporadic with the shortest gap between its releases in the run (said in the note); a ``sporadic`` task
    with its ``min_interarrival``. A task with ``release_jitter`` enters with ``J`` = the jitter's largest value:
    the bound is ``R = J + w`` from the nominal release, as the simulated ``response_s`` (the note says so).
``node``
    Under ``edf``/``np_edf``: the processor-demand test (schedulable or not) vs the deadline misses of the run.
``message``
    Per CAN message stream (network, sender, priority): the worst-case response time (Davis et al.) plus the
    interface delays vs the worst simulated latency (queued to delivered). The period is the sending task's
    (its queuing jitter: its response bound minus its execution), or for an event-driven sender the shortest
    gap between its messages in the run; the transmission time is the frame's on the bus.
``loop``
    A PID loop (``periodic_controller``, or a ``sampler`` / ``controller`` / ``actuator`` chain) on an LTI
    plant with a square-wave reference: the expected ISE of ``r - y`` over the run from
    :func:`netsim.analysis.lqg.transient_cost`, fed the sampling offsets and input-output delays the run
    measured (taken as independent from period to period), vs the run's ``<y>.ISE``.

A simulated value above its bound is flagged ``EXCEEDS``: a bug in the simulator or in the analysis.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from netsim.analysis.can import CanMessage, can_analysis
from netsim.analysis.rta import RTATask, edf_schedulable, response_times, utilization
from netsim.cli.analyze_loops import loop_rows
from netsim.cli.analyze_sync import NodeSyncAnalysis
from netsim.cli.analyze_table import COLUMNS, NS
from netsim.cli.analyze_table import jobs_of as _jobs_of
from netsim.cli.analyze_table import ms as _ms
from netsim.cli.analyze_table import row as _row

__all__ = ["COLUMNS", "analyze_run"]

def _wcet_ns(task: Any) -> int | None:
    """Largest execution time of a scenario task (ns), ``None`` when unbounded or unknown."""
    if getattr(task, "wcet", None) is not None:
        base = int(task.wcet)
    else:
        ex = task.execution_time()
        bound = 0 if ex is None else ex.upper_bound()
        if bound is None:
            return None
        base = int(bound)
    after = task.params.get("after_send") if getattr(task, "program", "") == "sampler" else None
    if after:
        from netsim.timebase import parse_time

        base += int(parse_time(after)) if isinstance(after, str) else int(after)
    return base


def _min_gap_ns(times_s: pd.Series) -> int | None:
    t = np.sort(times_s.dropna().to_numpy(dtype=float))
    if t.size < 2:
        return None
    gap = float(np.min(np.diff(t)))
    return int(round(gap / NS)) if gap > 0 else None


def _task_rows(scenario: Any, sim: Any, jobs: pd.DataFrame) -> tuple[list[dict], dict[tuple[str, str], tuple[int, int]]]:
    """Rows for tasks and EDF nodes; also ``(node, task) -> (response bound, wcet)`` for the message jitter."""
    rows: list[dict] = []
    bounds: dict[tuple[str, str], tuple[int, int]] = {}
    for node_name, node in scenario.nodes.items():
        policy = node.policy
        cs = int(node.context_switch)
        items: list[RTATask] = []
        notes: dict[str, str] = {}
        skipped: list[tuple[str, str]] = []
        sync = NodeSyncAnalysis(node)  # monitors, mailboxes ...: blocking terms, self-suspension
        kernel = sim.kernels.get(node_name)
        loads = dict(getattr(kernel, "loads", {}) or {})
        for load in loads.values():  # periodic ISR loads, from the scenario or created by programs at build
            items.append(RTATask(load.name, int(load.execution), int(load.period), priority=-1_000_000))
        covered = set(loads) | {load.handler for load in loads.values() if load.handler}
        blind: list[str] = []
        for h in node.handlers:
            if h.name in covered:
                continue
            trig = h.trigger
            period = None
            timer = getattr(trig, "timer", None) if trig is not None else None
            if timer is not None and timer.period:
                period = int(timer.period)
            if period is None:
                period = _min_gap_ns(_jobs_of(jobs, node_name, h.name)["release_s"])
            c = _wcet_ns(h)
            if period is None or c is None:
                blind.append(h.name)
                continue
            items.append(RTATask(h.name, c + int(h.latency or 0), period, priority=-1_000_000))
        how = "non-preemptive FP RTA" if policy == "np_fp" else f"{policy.upper()} RTA"
        retimed = {name: t.name for t in node.tasks if t.program == "feedback_scheduler"
                   for name in t.params.get("tasks", []) if isinstance(name, str)}
        for t in node.tasks:
            c = sync.timing(t, _wcet_ns(t))
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
                notes[t.name] = f"sporadic: T = min_interarrival ({_ms(period * NS):g} ms)"
            jitter = 0 if t.release_jitter is None else t.release_jitter.upper_bound()
            if jitter is None:
                skipped.append((t.name, "release jitter unbounded (exponential, or normal without max): no bound"))
                continue
            if jitter:
                notes[t.name] = (f"{notes.get(t.name, how)}; R = J + w from the nominal release "
                                 f"(J = {_ms(jitter * NS):g} ms; response_from_arrival_s <= w)")
            if t.name in retimed:  # kernel.set_period at run time: the analysis knows the nominal periods only
                notes[t.name] = f"{notes.get(t.name, how)}; at the nominal period (set at run time by {retimed[t.name]})"
            if period is None:
                period = _min_gap_ns(_jobs_of(jobs, node_name, t.name)["release_s"])
                notes[t.name] = f"{t.release_kind}: sporadic, T = shortest gap in the run"
                if period is None:
                    skipped.append((t.name, "fewer than two releases in the run: no period to analyse"))
                    continue
            deadline = int(t.deadline) if t.deadline else period
            if policy == "fp" or policy == "np_fp":
                prio = float(t.priority if t.priority is not None else 0)
            elif policy == "rm":
                prio = float(period)
            else:
                prio = float(deadline)
            items.append(RTATask(t.name, c + 2 * cs, period, deadline=deadline, priority=prio, jitter=jitter))
        items, skipped = sync.apply(items, skipped)
        task_names = {t.name for t in node.tasks}
        if policy in ("edf", "np_edf"):
            tasks = [it for it in items if it.name in task_names]
            ok = edf_schedulable(tasks) if policy == "edf" else None
            misses = int(sum(((jobs["node"] == node_name) & (jobs["outcome"].isin(["missed", "killed"]))).tolist()))
            u = utilization(items)
            if ok is None:
                rows.append(_row("node", node_name, "n/a", misses, "misses", "n/a", "non-preemptive EDF: no test"))
            else:
                verdict = "EXCEEDS" if ok and misses else "ok"
                rows.append(_row("node", node_name, "schedulable" if ok else "not schedulable", misses, "misses",
                                 verdict, f"EDF demand test, U = {u:.3g}"))
            for t in node.tasks:
                worst = _jobs_of(jobs, node_name, t.name)["response_s"].max()
                rows.append(_row("task", f"{node_name}.{t.name}", "n/a", _ms(worst), "ms", "n/a",
                                 "EDF: no per-task bound"))
            continue
        if policy == "np_fp":
            msgs = [CanMessage(it.name, int(it.priority), it.period, max(it.wcet, 1), deadline_ns=it.relative_deadline,
                               jitter_ns=it.jitter) for it in items]
            rts = {r.name: r.response_ns for r in can_analysis(msgs, tau_ns=1)}
            how = "non-preemptive FP RTA"
        else:
            rts = response_times(items)
            how = f"{policy.upper()} RTA"
        for it in items:
            if it.name not in task_names or sync.no_bound(it.name):
                continue
            bound = rts.get(it.name)
            js = _jobs_of(jobs, node_name, it.name)
            worst = js["response_s"].max()
            unfinished = int((js["response_s"].isna() & (js["outcome"] != "pending")).sum())
            note = notes.get(it.name, how) + sync.note(it.name)
            if unfinished:
                note += f"; {unfinished} jobs unfinished"
            if bound is None:
                rows.append(_row("task", f"{node_name}.{it.name}", "unbounded", _ms(worst), "ms", "ok",
                                 note + "; load at its level >= 1"))
                continue
            bounds[(node_name, it.name)] = (bound, it.wcet)
            exceeds = (not math.isnan(worst) and worst > bound * NS + 1e-12) or (
                unfinished and _unfinished_past(js, bound))
            rows.append(_row("task", f"{node_name}.{it.name}", bound * NS * 1e3, _ms(worst), "ms",
                             "EXCEEDS" if exceeds else "ok", note))
        for name, why in skipped:
            rows.append(_row("task", f"{node_name}.{name}", "n/a", _ms(_jobs_of(jobs, node_name, name)["response_s"]
                                                                       .max()), "ms", "n/a", why))
    return rows, bounds


def _unfinished_past(js: pd.DataFrame, bound_ns: int) -> bool:
    """An unfinished job released more than the bound before the last finish seen (the run went on past it)."""
    end = js["finish_s"].max()
    rel = js.loc[js["response_s"].isna() & (js["outcome"] != "pending"), "release_s"]
    return bool(not math.isnan(end) and (rel + bound_ns * NS < end - 1e-12).any())


def _message_rows(scenario: Any, sim: Any, jobs: pd.DataFrame, messages: pd.DataFrame,
                  bounds: dict[tuple[str, str], tuple[int, int]]) -> list[dict]:
    rows: list[dict] = []
    for net_name, net in scenario.networks.items():
        if net.type != "can":
            continue
        params = sim.networks[net_name].params
        ms = messages[messages["network"] == net_name]
        if ms.empty:
            continue
        # one stream per (sender, priority); one row per sent message (a broadcast's copies share a msg_id)
        firsts = ms.sort_values("sent_s").drop_duplicates("msg_id")
        streams = []
        for (sender, prio), group in firsts.groupby(["sender", "priority"], sort=True):
            tx = (group["tx_end_s"] - group["tx_start_s"]).max()
            tx_ns = int(round(tx / NS)) if not math.isnan(tx) else None
            period, jitter, note = None, 0, ""
            senders = [t for t in scenario.nodes[sender].tasks
                       if t.params.get("network") == net_name and int(t.params.get("priority", 0)) == int(prio)]
            if len(senders) == 1 and senders[0].release_kind == "periodic" and senders[0].period:
                period = int(senders[0].period)
                b = bounds.get((sender, senders[0].name))
                if b is None:
                    note = "J = 0 (sender has no bound)"
                else:
                    jitter = b[0] - b[1]
                    note = f"T = {senders[0].name} period, J = R - C"
            else:
                period = _min_gap_ns(group["sent_s"])
                note = "event-driven: T = shortest gap in the run"
            if period is None or tx_ns is None:
                continue
            streams.append((f"{sender}/p{int(prio)}", sender, int(prio), period, tx_ns, jitter, note, group))
        results = {r.name: r for r in can_analysis(
            [CanMessage(n, p, T, c, jitter_ns=j) for n, _, p, T, c, j, _, _ in streams], tau_ns=1)}
        for name, sender, _, _, _, _, note, group in streams:
            delays = ms[ms["msg_id"].isin(group["msg_id"]) & ~ms["dropped"]]
            pre = _interface_delay(params, sender, "pre_delay")
            post = max([_interface_delay(params, r, "post_delay") for r in delays["receiver"].unique()]
                       or [int(params.post_delay)])
            worst = delays["delay_s"].max()
            r = results[name].response_ns
            if r is None:
                rows.append(_row("message", f"{net_name}.{name}", "unbounded", _ms(worst), "ms", "ok",
                                 note + "; bus load at its level >= 1"))
                continue
            bound = (r + pre + post) * NS
            exceeds = not math.isnan(worst) and worst > bound + 1e-12
            rows.append(_row("message", f"{net_name}.{name}", bound * 1e3, _ms(worst), "ms",
                             "EXCEEDS" if exceeds else "ok", "CAN RTA; " + note))
    return rows


def _interface_delay(params: Any, node: str, which: str) -> int:
    """A node's ``pre_delay`` or ``post_delay`` on a network: its own override, else the network's."""
    own = getattr(params.node_delays.get(node), which, None) if node in params.node_delays else None
    return int(own) if own is not None else int(getattr(params, which))


def analyze_run(scenario: Any, result: Any) -> pd.DataFrame:
    """The comparison table of ``scenario`` and its run ``result`` (columns :data:`COLUMNS`).

    Parameters
    ----------
    scenario
        The validated :class:`~netsim.scenario.Scenario` that was run.
    result
        Its :class:`~netsim.results.RunResult`.
    """
    from netsim.scenario import build

    sim = build(scenario)
    jobs = result.jobs
    rows, bounds = _task_rows(scenario, sim, jobs)
    rows += _message_rows(scenario, sim, jobs, result.messages, bounds)
    rows += loop_rows(scenario, sim, jobs, result)
    return pd.DataFrame(rows, columns=COLUMNS)
