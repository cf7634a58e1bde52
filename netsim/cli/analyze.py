"""``netsim analyze``: what analysis predicts beside what a run measured.

For one scenario and its run, one row per checked item:

``task``
    The fixed-priority response-time bound (:mod:`netsim.analysis.rta`; policies ``fp``, ``rm``, ``dm``) or the
    non-preemptive one (``np_fp``, the CAN recurrence of :mod:`netsim.analysis.can` with one-tick arbitration)
    vs the worst simulated response (release to finish). Execution times count at their largest value (the
    ``wcet`` field, else the upper end of the ``execution`` distribution, plus a sampler's ``after_send``), with
    two context switches per job. A task released by messages or by program code has no period: it is taken
    as sporadic with the shortest gap between its releases in the run (said in the note).
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
from netsim.cli.analyze_sync import NodeSyncAnalysis

__all__ = ["COLUMNS", "analyze_run"]

COLUMNS = ["kind", "name", "analysis", "simulated", "unit", "verdict", "note"]
NS = 1e-9


def _row(kind: str, name: str, analysis: Any, simulated: Any, unit: str, verdict: str, note: str = "") -> dict:
    return {"kind": kind, "name": name, "analysis": analysis, "simulated": simulated, "unit": unit,
            "verdict": verdict, "note": note}


def _wcet_ns(task: Any) -> int | None:
    """Largest execution time of a scenario task (ns), ``None`` when unbounded or unknown."""
    if getattr(task, "wcet", None) is not None:
        base = int(task.wcet)
    else:
        ex = task.execution
        if ex is None:
            base = 0
        elif isinstance(ex, int):
            base = int(ex)
        elif getattr(ex, "dist", "") == "constant":
            base = int(ex.value)
        elif getattr(ex, "dist", "") == "uniform":
            base = int(ex.high)
        elif getattr(ex, "dist", "") == "empirical":
            base = int(max(ex.values))
        elif getattr(ex, "dist", "") == "normal" and getattr(ex, "max", None) is not None:
            base = int(ex.max)
        else:
            return None
    after = task.params.get("after_send") if getattr(task, "program", "") == "sampler" else None
    if after:
        from netsim.timebase import parse_time

        base += int(parse_time(after)) if isinstance(after, str) else int(after)
    return base


def _jobs_of(jobs: pd.DataFrame, node: str, task: str) -> pd.DataFrame:
    return jobs[(jobs["node"] == node) & (jobs["task"] == task)]


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
            items.append(RTATask(t.name, c + 2 * cs, period, deadline=deadline, priority=prio))
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
            msgs = [CanMessage(it.name, int(it.priority), it.period, max(it.wcet, 1), deadline_ns=it.relative_deadline)
                    for it in items]
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


def _ms(x: float) -> float:
    return float("nan") if x is None or (isinstance(x, float) and math.isnan(x)) else float(x) * 1e3


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


# --------------------------------------------------------------------------------------------- control loops
def _subsystem(A: np.ndarray, B: np.ndarray, C: np.ndarray, i_in: int, outs: list[int]) -> np.ndarray | None:
    """States of the part of the plant that input ``i_in`` drives, if no other input reaches it and the outputs
    ``outs`` read only it; else None."""
    n = A.shape[0]
    reach = set(np.flatnonzero(B[:, i_in]).tolist())
    frontier = list(reach)
    while frontier:
        j = frontier.pop()
        for i in np.flatnonzero(A[:, j]).tolist():
            if i not in reach:
                reach.add(i)
                frontier.append(i)
    idx = np.array(sorted(reach), dtype=int)
    others = np.setdiff1d(np.arange(n), idx)
    if idx.size == 0:
        return None
    if others.size and (np.any(A[np.ix_(idx, others)] != 0) or np.any(C[np.ix_(outs, others)] != 0)):
        return None
    if B.shape[1] > 1 and np.any(np.delete(B, i_in, axis=1)[idx, :] != 0):
        return None
    return idx


def _loop_rows(scenario: Any, sim: Any, jobs: pd.DataFrame, result: Any) -> list[dict]:
    plant = sim.plant
    if plant is None or not all(hasattr(plant, k) for k in ("A", "B", "C")) or getattr(plant, "D", None) is None:
        return []
    raw = getattr(result, "metrics", None)
    metrics = {} if raw is None else dict(raw)
    t_end = float(result.signals["time_s"].max()) if len(result.signals) else 0.0
    rows: list[dict] = []
    for cand in [*_pid_chains(scenario), *_state_feedback_loops(scenario, sim)]:
        row = _loop_row(scenario, sim, jobs, plant, metrics, t_end, cand)
        if row is not None:
            rows.append(row)
    return rows


def _metric_output(scenario: Any, plant: Any, ref: str | None, prefer: str | None) -> str | None:
    """The plant output of a ``control_error`` metric against ``ref`` (``prefer`` first)."""
    outs = [m.params.get("output") for m in scenario.metrics
            if m.type == "control_error" and m.params.get("reference") == ref]
    outs = [o for o in outs if o in plant.output_names]
    if prefer in outs:
        return prefer
    return outs[0] if outs else None


def _loop_row(scenario: Any, sim: Any, jobs: pd.DataFrame, plant: Any, metrics: dict, t_end: float,
              cand: dict) -> dict | None:
    """The ``loop`` row of one candidate loop (see :func:`_pid_chains`, :func:`_state_feedback_loops`)."""
    from netsim.analysis.lqg import SampledLoop, TimingDistribution, transient_cost
    from netsim.timebase import to_seconds

    A, B, C = np.asarray(plant.A, float), np.asarray(plant.B, float), np.asarray(plant.C, float)
    name, ref = cand["name"], cand["reference"]
    io_in = scenario.io[cand["dac"]]
    i_in = plant.input_index(io_in.input)
    meas_rows = [plant.output_index(scenario.io[ch].output) for ch in cand["adcs"]]
    y_name = _metric_output(scenario, plant, ref, plant.output_names[meas_rows[0]])
    metric = metrics.get(f"{y_name}.ISE") if y_name else None
    if metric is None:
        return None

    def na(why: str) -> dict:
        return _row("loop", name, "n/a", float(metric), "ISE", "n/a", why)

    if np.any(np.asarray(plant.D) != 0) or np.any(np.asarray(getattr(plant, "Qc", 0)) != 0):
        return na("the analysis of a run's ISE needs a noise-free plant without feed-through")
    sig = sim.signals.get(ref) if ref else None
    if ref and (type(sig).__name__ != "Square" or getattr(sig, "bias", 1.0) != 0.0):
        return na("the analysis handles a square-wave reference with bias 0, or none")
    adcs = [scenario.io[ch] for ch in cand["adcs"]]
    if io_in.type != "dac" or io_in.saturation or any(
            io.type != "adc" or io.noise_std or io.quant_step or io.saturation for io in adcs):
        return na("the analysis needs plain ADCs and a DAC (no noise, quantisation or saturation)")
    i_out = plant.output_index(y_name)
    idx = _subsystem(A, B, C, i_in, [i_out, *meas_rows])
    if idx is None:
        return na("the loop's input and outputs do not isolate a part of the plant")
    timed = scenario.nodes[cand["sample"][0]].task(cand["sample"][1])
    if timed.release_kind != "periodic" or not timed.period:
        return na("the sampling task is not periodic")
    h = to_seconds(timed.period)
    sj = _jobs_of(jobs, *cand["sample"]).sort_values("release_s").dropna(subset=["start_s"])
    aj = _jobs_of(jobs, *cand["act"]).sort_values("release_s").dropna(subset=["finish_s"])
    k = min(len(sj), len(aj))
    if k == 0:
        return na("no finished jobs")
    offsets = sj["start_s"].to_numpy()[:k] - sj["release_s"].to_numpy()[:k]
    delays = aj["finish_s"].to_numpy()[:k] - sj["start_s"].to_numpy()[:k]
    if np.any(delays < 0) or len(sj) - len(aj) > 1:
        return na("samples and actuations do not pair one to one")
    res = 10e-6
    off = TimingDistribution.empirical(offsets, resolution_s=res)
    keys = np.round(offsets / res)
    dly = [TimingDistribution.empirical(delays[keys == round(v / res)], resolution_s=res) for v in off.values]
    worst = float(np.max(offsets + delays))
    if worst > h + min(off.values):
        return na(f"output {worst * 1e3:.3g} ms after the nominal sample, past the next one (h = {h * 1e3:.3g} ms)")
    ns = idx.size
    Csub = C[np.ix_(meas_rows, idx)]
    x0 = np.zeros(ns + 1)
    if getattr(plant, "x0", None) is not None:
        x0[:ns] = np.asarray(plant.x0, float)[idx]
    x0[ns] = sig(0) if sig is not None else 0.0
    made = cand["controller"](h, Csub, idx, Csub @ x0[:ns])
    if isinstance(made, str):
        return na(made)
    Ac, Bc, Cc, Dc, xc0 = made
    Aa = np.zeros((ns + 1, ns + 1))
    Aa[:ns, :ns] = A[np.ix_(idx, idx)]
    Ba = np.vstack([B[idx, i_in : i_in + 1], [[0.0]]])
    Cm = np.zeros((1 + len(meas_rows), ns + 1))  # the controller reads [r; y]
    Cm[0, ns] = 1.0
    Cm[1:, :ns] = Csub
    e = np.hstack([C[i_out : i_out + 1, idx], [[-1.0]]])
    loop = SampledLoop(A=Aa, B=Ba, C=Cm, Ac=Ac, Bc=Bc, Cc=Cc, Dc=Dc, period_s=h, Q1=e.T @ e, Q2=[[0.0]])
    flip = np.eye(ns + 1)
    flip[ns, ns] = -1.0
    jumps = [(bp * NS, flip) for bp in sig.breakpoints(0, int(t_end / NS))] if sig is not None else []
    cost = transient_cost(loop, t_end, x0, delay=dly, offset=off, jumps=jumps, xc0=xc0)
    rel = (float(metric) - cost) / cost if cost else float("nan")
    return _row("loop", name, cost, float(metric), "ISE", f"{rel * 100:+.1f} %",
                f"E[ISE] of {ref or 0}-{y_name}, 0-{t_end:.3g} s, {sum(len(d.values) for d in dly)} (offset, delay) "
                "pairs of the run")


def _pid_controller_of(params: dict) -> Any:
    """The candidate's controller maker for a PID (netsim.control.pid form, ``h`` from its params or the
    sampling period)."""
    from netsim.analysis.lqg import pid_controller
    from netsim.timebase import parse_time, to_seconds

    def make(h: float, Csub: np.ndarray, idx: np.ndarray, y0: np.ndarray) -> Any:
        given = params.get("h")
        h_ctrl = h if given is None else to_seconds(parse_time(given) if isinstance(given, str) else int(given))
        if params.get("u_min") is not None or params.get("u_max") is not None:
            return "the PID has output limits"
        Ac, Bc, Cc, Dc = pid_controller(float(params.get("K", 1.0)), params.get("Ti"), float(params.get("Td", 0.0)),
                                        float(params.get("N", 10.0)), h_ctrl, b=float(params.get("b", 1.0)))
        return Ac, Bc, Cc, Dc, [0.0, 0.0, float(y0[0])]  # netsim's PID takes y(k-1) = y(0) at its first step

    return make


def _pid_chains(scenario: Any) -> list[dict]:
    """PID loops: one ``periodic_controller`` task, or a ``sampler`` -> ``controller`` -> ``actuator`` chain."""
    out = []
    for node_name, node in scenario.nodes.items():
        for t in node.tasks:
            p = t.params
            if t.program == "periodic_controller":
                out.append({"name": f"{node_name}.{t.name}", "reference": p.get("reference"),
                            "adcs": [p.get("channel")], "dac": p.get("output_channel"),
                            "sample": (node_name, t.name), "act": (node_name, t.name),
                            "controller": _pid_controller_of(p)})
            elif t.program == "controller" and p.get("network") and t.release_kind == "on_message":
                net = p["network"]
                samplers = [(n, s) for n, nd in scenario.nodes.items() for s in nd.tasks
                            if s.program == "sampler" and s.params.get("network") == net
                            and s.params.get("to") == node_name and s.release_kind == "periodic"]
                acts = [(n, a) for n, nd in scenario.nodes.items() for a in nd.tasks
                        if a.program == "actuator" and a.params.get("network") == net and n == p.get("to")]
                if len(samplers) == 1 and len(acts) == 1:
                    (sn, s), (an, a) = samplers[0], acts[0]
                    out.append({"name": f"{node_name}.{t.name}", "reference": p.get("reference"),
                                "adcs": [s.params.get("channel")], "dac": a.params.get("channel"),
                                "sample": (sn, s.name), "act": (an, a.name), "controller": _pid_controller_of(p)})
    return out


def _state_feedback_loops(scenario: Any, sim: Any) -> list[dict]:
    """``state_feedback`` tasks that sample ADCs and write a DAC with ``estimator: none`` and a static law
    (``lqr`` or ``state_feedback`` without integral action or limits): ``u = Fr r - K C^-1 y``."""
    out = []
    for node_name, node in scenario.nodes.items():
        for t in node.tasks:
            p = t.params
            if t.program != "state_feedback" or not p.get("output_channel"):
                continue
            srcs = p.get("measurements") or []
            if not srcs or any(not isinstance(m, dict) or not m.get("channel") for m in srcs):
                continue
            prog = sim.programs.get(f"{node_name}.{t.name}")
            law = getattr(prog, "law", None)
            est = getattr(prog, "estimator", None)
            if (p.get("estimator") or {}).get("type") != "none" or not hasattr(law, "K") or \
                    getattr(law, "Ki", None) is not None:
                continue

            def make(h: float, Csub: np.ndarray, idx: np.ndarray, y0: np.ndarray, law: Any = law, est: Any = est,
                     n: int = int(np.asarray(sim.plant.A).shape[0])) -> Any:
                if getattr(law, "u_min", None) is not None or getattr(law, "u_max", None) is not None:
                    return "the law has input limits"
                if idx.size != n or law.K.shape[0] != 1:
                    return "the analysis takes a state feedback on the whole plant with one input"
                Cinv = np.asarray(est._Cinv, float)
                Fr = np.asarray(getattr(law, "_Fr", np.zeros((1, 1))), float).sum(axis=1, keepdims=True) \
                    if getattr(law, "Cr", None) is not None else np.zeros((1, 1))
                Dc = np.hstack([Fr, -law.K @ Cinv])
                return None, None, None, Dc, None

            out.append({"name": f"{node_name}.{t.name}", "reference": p.get("reference"),
                        "adcs": [m["channel"] for m in srcs], "dac": p["output_channel"],
                        "sample": (node_name, t.name), "act": (node_name, t.name), "controller": make})
    return out


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
    rows += _loop_rows(scenario, sim, jobs, result)
    return pd.DataFrame(rows, columns=COLUMNS)
