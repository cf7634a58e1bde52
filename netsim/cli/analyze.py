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

A simulated value above its bound is flagged ``EXCEEDS``: a bug in the simulator or in the analysis.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from netsim.analysis.can import CanMessage, can_analysis
from netsim.analysis.from_scenario import interface_delay, message_period, node_tasks, response_bounds
from netsim.analysis.rta import edf_schedulable, utilization
from netsim.cli.analyze_loops import loop_rows
from netsim.cli.analyze_table import COLUMNS, NS
from netsim.cli.analyze_table import jobs_of as _jobs_of
from netsim.cli.analyze_table import ms as _ms
from netsim.cli.analyze_table import row as _row

if TYPE_CHECKING:
    from netsim.results import RunResult
    from netsim.scenario import Simulation  # the builder's, as netsim.scenario names it
    from netsim.scenario.schema import Scenario

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
        policy = node.policy
        kernel = sim.kernels.get(node_name)
        def min_gap(name: str, n: str = node_name) -> int | None:
            return _min_gap_ns(_jobs_of(jobs, n, name)["release_s"])

        mapped = node_tasks(node, dict(getattr(kernel, "loads", {}) or {}), min_gap)
        items, notes, skipped, sync = mapped.items, mapped.notes, mapped.skipped, mapped.sync
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
        rts = response_bounds(policy, items)
        how = mapped.how
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
