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
    plant with a square-wave reference: the expected ISE of ``r - y`` over the run
    (:mod:`netsim.analysis.loops`, from :func:`netsim.analysis.lqg.transient_cost`), fed the sampling offsets and
    input-output delays the run measured (taken as independent from period to period), vs the run's ``<y>.ISE``.

A node's CPU changes the test (:mod:`netsim.analysis.platform`, each rule stated in the row's note): execution
times at the slowest speed the node can run (speed scaling); each core of a partitioned node on its own (node rows
``<node>.core<k>``); the GFB density test for global EDF (``not shown schedulable`` when it fails: it is only
sufficient) and the Bertogna-Cirinei response bounds under global fixed priorities; the demand test with the
servers' bandwidth reserved and a served task's CBS/TBS bound; a time-triggered task's slot
(``R <= slot end - activation``).

A simulated value above its bound is flagged ``EXCEEDS``: a bug in the simulator or in the analysis.
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from netsim.analysis.can import CanMessage, can_analysis
from netsim.analysis.from_scenario import NodeTasks, interface_delay, message_period, node_tasks, response_bounds
from netsim.analysis.platform import (UNBOUNDED, bandwidth, gfb_test, global_fp_bounds, migration_charge, served_bound,
                                      slot_bound, slowest_speed)
from netsim.analysis.rta import RTATask, edf_schedulable, utilization
from netsim.cli.analyze_loops import loop_rows
from netsim.cli.analyze_table import COLUMNS, NS
from netsim.cli.analyze_table import jobs_of as _jobs_of
from netsim.cli.analyze_table import ms as _ms
from netsim.cli.analyze_table import row as _row

if TYPE_CHECKING:
    from netsim.results import RunResult
    from netsim.scenario import Simulation  # the builder's, as netsim.scenario names it
    from netsim.scenario.schema import NodeSpec, Scenario

__all__ = ["COLUMNS", "analyze_run"]

def _min_gap_ns(times_s: pd.Series) -> int | None:
    t = np.sort(times_s.dropna().to_numpy(dtype=float))
    if t.size < 2:
        return None
    gap = float(np.min(np.diff(t)))
    return int(round(gap / NS)) if gap > 0 else None


def _task_rows(scenario: Scenario, sim: Simulation,
               jobs: pd.DataFrame) -> tuple[list[dict], dict[tuple[str, str], tuple[int, int]]]:
    """Rows for tasks and EDF nodes; also ``(node, task) -> (response bound, wcet)`` for the message jitter."""
    rows: list[dict] = []
    bounds: dict[tuple[str, str], tuple[int, int]] = {}
    for node_name, node in scenario.nodes.items():
        kernel = sim.kernels.get(node_name)
        def min_gap(name: str, n: str = node_name) -> int | None:
            return _min_gap_ns(_jobs_of(jobs, n, name)["release_s"])

        mapped = node_tasks(node, dict(getattr(kernel, "loads", {}) or {}), min_gap, slowest_speed(node, scenario))
        cores, mode = node.cores or 1, node.multicore or "global"
        if cores > 1 and mode == "partitioned":  # each core its own uniprocessor; handlers on core 0
            home = {t.name: t.core or 0 for t in node.tasks}
            for k in range(cores):
                group = [it for it in mapped.items if home.get(it.name, 0) == k]
                names = {t.name for t in node.tasks if home[t.name] == k}
                rows += _uniprocessor_rows(node_name, node, f"{node_name}.core{k}", group, names, mapped, jobs,
                                           bounds, f" (partitioned: core {k})")
            rows += _skipped_rows(node_name, node, mapped, jobs)
        elif cores > 1:
            rows += _global_rows(node_name, node, mapped, jobs, bounds)
        elif node.servers:
            rows += _server_rows(node_name, node, mapped, jobs)
        elif node.policy == "tt":
            rows += _table_rows(node_name, node, mapped, jobs, bounds)
        else:
            rows += _uniprocessor_rows(node_name, node, node_name, mapped.items, {t.name for t in node.tasks},
                                       mapped, jobs, bounds, "")
            rows += _skipped_rows(node_name, node, mapped, jobs)
    return rows, bounds


def _misses(jobs: pd.DataFrame, node: str, tasks: set[str] | None = None) -> int:
    mine = (jobs["node"] == node) & jobs["outcome"].isin(["missed", "killed"])
    if tasks is not None:
        mine &= jobs["task"].isin(sorted(tasks))
    return int(sum(mine.tolist()))


def _worst(jobs: pd.DataFrame, node: str, task: str) -> float:
    return _ms(_jobs_of(jobs, node, task)["response_s"].max())


def _uniprocessor_rows(node_name: str, node: NodeSpec, label: str, items: list[RTATask], task_names: set[str],
                       mapped: NodeTasks, jobs: pd.DataFrame, bounds: dict[tuple[str, str], tuple[int, int]],
                       where: str) -> list[dict]:
    """One CPU (a node, or one core of a partitioned node): the EDF node row and per-task rows, or the FP rows."""
    rows: list[dict] = []
    policy, notes, sync = node.policy, mapped.notes, mapped.sync
    if policy in ("edf", "np_edf"):
        tasks = [it for it in items if it.name in task_names]
        ok = edf_schedulable(tasks) if policy == "edf" else None
        misses = _misses(jobs, node_name, None if label == node_name else task_names)
        u = utilization(items)
        if ok is None:
            rows.append(_row("node", label, "n/a", misses, "misses", "n/a", "non-preemptive EDF: no test" + where))
        else:
            verdict = "EXCEEDS" if ok and misses else "ok"
            rows.append(_row("node", label, "schedulable" if ok else "not schedulable", misses, "misses",
                             verdict, f"EDF demand test, U = {u:.3g}" + where))
        for t in node.tasks:
            if t.name in task_names:
                rows.append(_row("task", f"{node_name}.{t.name}", "n/a", _worst(jobs, node_name, t.name), "ms", "n/a",
                                 "EDF: no per-task bound"))
        return rows
    rts = response_bounds(policy, items)
    for it in items:
        if it.name not in task_names or sync.no_bound(it.name):
            continue
        note = notes.get(it.name, mapped.how) + sync.note(it.name) + where
        rows.append(_bound_row(node_name, it.name, rts.get(it.name), it.wcet, note, jobs, bounds))
    return rows


def _bound_row(node_name: str, name: str, bound: int | None, wcet: int, note: str, jobs: pd.DataFrame,
               bounds: dict[tuple[str, str], tuple[int, int]]) -> dict:
    """A task's bound (ns; None: unbounded) beside its worst simulated response."""
    js = _jobs_of(jobs, node_name, name)
    worst = js["response_s"].max()
    unfinished = int((js["response_s"].isna() & (js["outcome"] != "pending")).sum())
    if unfinished:
        note += f"; {unfinished} jobs unfinished"
    if bound is None:
        return _row("task", f"{node_name}.{name}", "unbounded", _ms(worst), "ms", "ok",
                    note + "; load at its level >= 1")
    bounds[(node_name, name)] = (bound, wcet)
    exceeds = (not math.isnan(worst) and worst > bound * NS + 1e-12) or (unfinished and _unfinished_past(js, bound))
    return _row("task", f"{node_name}.{name}", bound * NS * 1e3, _ms(worst), "ms", "EXCEEDS" if exceeds else "ok", note)


def _skipped_rows(node_name: str, node: NodeSpec, mapped: NodeTasks, jobs: pd.DataFrame) -> list[dict]:
    if node.policy in ("edf", "np_edf"):
        return []  # the EDF rows name every task
    return [_row("task", f"{node_name}.{name}", "n/a", _worst(jobs, node_name, name), "ms", "n/a", why)
            for name, why in mapped.skipped]


def _global_rows(node_name: str, node: NodeSpec, mapped: NodeTasks, jobs: pd.DataFrame,
                 bounds: dict[tuple[str, str], tuple[int, int]]) -> list[dict]:
    """A node with several cores under global scheduling: the GFB test for EDF, the Bertogna-Cirinei response
    bounds for fixed priorities, else no bound (why)."""
    m, names = node.cores or 1, {t.name for t in node.tasks}
    tasks = [it for it in mapped.items if it.name in names]
    skipped = dict(mapped.skipped)
    cost = int(node.migration_cost or 0)
    extra = f"; C + {cost / 1e6:g} ms per release of a{{}} task within D (migrations)" if cost else ""
    if node.policy in ("fp", "rm", "dm") and not skipped:
        found, why = global_fp_bounds(mapped.items, m, cost)
        rows = []
        for t in node.tasks:
            it = next(i for i in mapped.items if i.name == t.name)
            bound = found.get(t.name)
            if bound is None:
                rows.append(_row("task", f"{node_name}.{t.name}", "n/a", _worst(jobs, node_name, t.name), "ms", "n/a",
                                 f"global {node.policy.upper()} on {m} cores: "
                                 f"{why or 'the Bertogna-Cirinei test finds no R <= D'}"))
            else:
                note = (f"global {node.policy.upper()} on {m} cores, Bertogna & Cirinei 2007 RTA (sufficient)"
                        + extra.format(" more urgent"))
                rows.append(_bound_row(node_name, t.name, bound, it.wcet, note, jobs, bounds))
        return rows
    misses = _misses(jobs, node_name)
    why = ""
    if node.policy != "edf":
        why = (f"global {node.policy.upper()} on {m} cores: no test (the one-core analysis does not hold on several "
               "cores)")
    elif node.handlers:
        why = "handlers outrank every task on a global node: the GFB test does not apply"
    elif skipped:
        why = f"tasks without a bound ({', '.join(sorted(skipped))}): no test"
    if why:
        rows = [_row("node", node_name, "n/a", misses, "misses", "n/a", why)]
    else:
        ok, total, limit = gfb_test(migration_charge(tasks, cost), m)
        rows = [_row("node", node_name, "schedulable" if ok else "not shown schedulable", misses, "misses",
                     "EXCEEDS" if ok and misses else "ok",
                     f"global EDF on {m} cores, GFB test (Goossens, Funk & Baruah 2003; sufficient only): "
                     f"sum C/min(D,T) = {float(total):.3g} {'<=' if ok else '>'} m - (m-1) max = "
                     f"{float(limit):.3g}{extra.format('nother')}")]
    for t in node.tasks:
        rows.append(_row("task", f"{node_name}.{t.name}", "n/a", _worst(jobs, node_name, t.name), "ms", "n/a",
                         skipped.get(t.name, f"global {node.policy.upper()}: no per-task bound")))
    return rows


def _server_rows(node_name: str, node: NodeSpec, mapped: NodeTasks, jobs: pd.DataFrame) -> list[dict]:
    """An EDF node with bandwidth servers: the demand test of the tasks outside servers with the servers'
    bandwidth reserved, and each served task's bound (:func:`~netsim.analysis.platform.served_bound`)."""
    decl = {s.name: s for s in node.servers}
    reserved = sum((bandwidth(s) for s in node.servers), Fraction(0))
    served = {t.name: t.server for t in node.tasks if t.server is not None}
    free = {t.name for t in node.tasks} - set(served)
    by_name = {it.name: it for it in mapped.items}
    tasks = [by_name[n] for n in sorted(free) if n in by_name]
    skipped = dict(mapped.skipped)
    misses = _misses(jobs, node_name, free)
    cs = int(node.context_switch)
    if node.policy != "edf" or any(n in skipped for n in free) or cs:
        why = ("context switches are outside the servers' budgets: no test" if cs else
               "tasks outside servers without a bound: no test" if node.policy == "edf" else "servers need edf")
        rows = [_row("node", node_name, "n/a", misses, "misses", "n/a", why)]
        ok = False
    else:
        ok = edf_schedulable(tasks, bandwidth=reserved)
        u = utilization(tasks) + float(reserved)
        rows = [_row("node", node_name, "schedulable" if ok else "not schedulable", misses, "misses",
                     "EXCEEDS" if ok and misses else "ok",
                     f"EDF demand test of the tasks outside servers, servers' bandwidth {float(reserved):.3g} "
                     f"reserved, U = {u:.3g} (misses: tasks outside servers)")]
    for t in node.tasks:
        worst = _worst(jobs, node_name, t.name)
        if t.name in free:
            rows.append(_row("task", f"{node_name}.{t.name}", "n/a", worst, "ms", "n/a", "EDF: no per-task bound"))
            continue
        it = by_name.get(t.name)
        if it is None or t.name in skipped:
            rows.append(_row("task", f"{node_name}.{t.name}", "n/a", worst, "ms", "n/a", skipped.get(t.name, "")))
            continue
        shared = sum(1 for v in served.values() if v == t.server)
        bound, why = served_bound(it, decl[str(t.server)], shared, None if t.wcet is None else int(t.wcet))
        if bound is not None and bound != UNBOUNDED and not ok:
            bound, why = None, "the node's demand test with the servers fails: no server guarantee"
        if bound == UNBOUNDED:
            rows.append(_row("task", f"{node_name}.{t.name}", "unbounded", worst, "ms", "ok", why))
        elif bound is None:
            rows.append(_row("task", f"{node_name}.{t.name}", "n/a", worst, "ms", "n/a", why))
        else:
            rows.append(_bound_row(node_name, t.name, bound, it.wcet, why, jobs, {}))
    return rows


def _table_rows(node_name: str, node: NodeSpec, mapped: NodeTasks, jobs: pd.DataFrame,
                bounds: dict[tuple[str, str], tuple[int, int]]) -> list[dict]:
    """A ``tt`` node: each slotted task's bound from its slots (:func:`~netsim.analysis.platform.slot_bound`)."""
    rows: list[dict] = []
    by_name = {it.name: it for it in mapped.items}
    skipped = dict(mapped.skipped)
    for t in node.tasks:
        it = by_name.get(t.name)
        if it is None:
            rows.append(_row("task", f"{node_name}.{t.name}", "n/a", _worst(jobs, node_name, t.name), "ms", "n/a",
                             skipped.get(t.name, "")))
            continue
        bound, why = slot_bound(t.name, it.wcet, node)
        if bound is None:
            rows.append(_row("task", f"{node_name}.{t.name}", "n/a", _worst(jobs, node_name, t.name), "ms", "n/a", why))
        else:
            rows.append(_bound_row(node_name, t.name, bound, it.wcet, why, jobs, bounds))
    return rows


def _unfinished_past(js: pd.DataFrame, bound_ns: int) -> bool:
    """An unfinished job released more than the bound before the last finish seen (the run went on past it)."""
    end = js["finish_s"].max()
    rel = js.loc[js["response_s"].isna() & (js["outcome"] != "pending"), "release_s"]
    return bool(not math.isnan(end) and (rel + bound_ns * NS < end - 1e-12).any())


def _message_rows(scenario: Scenario, sim: Simulation, jobs: pd.DataFrame, messages: pd.DataFrame,
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
        for _, group in firsts.groupby(["sender", "priority"], sort=True):
            sender, prio = str(group["sender"].iloc[0]), int(group["priority"].iloc[0])
            tx = (group["tx_end_s"] - group["tx_start_s"]).max()
            tx_ns = int(round(tx / NS)) if not math.isnan(tx) else None
            period, jitter, note = message_period(scenario.nodes[sender], net_name, prio, bounds, sender)
            if period is None:
                period = _min_gap_ns(group["sent_s"])
            if period is None or tx_ns is None:
                continue
            streams.append((f"{sender}/p{prio}", sender, prio, period, tx_ns, jitter, note, group))
        results = {r.name: r for r in can_analysis(
            [CanMessage(n, p, T, c, jitter_ns=j) for n, _, p, T, c, j, _, _ in streams], tau_ns=1)}
        for name, sender, _, _, _, _, note, group in streams:
            delays = ms[ms["msg_id"].isin(group["msg_id"]) & ~ms["dropped"]]
            pre = interface_delay(params, sender, "pre_delay")
            post = max([interface_delay(params, r, "post_delay") for r in delays["receiver"].unique()]
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


def analyze_run(scenario: Scenario, result: RunResult) -> pd.DataFrame:
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
