"""``netsim analyze``'s control-loop rows: per PID or state-feedback loop on an LTI plant, the expected ISE from
:func:`netsim.analysis.lqg.transient_cost` (fed the sampling offsets and input-output delays the run measured) vs
the run's ``<y>.ISE`` metric. Split from :mod:`netsim.cli.analyze`, which adds these rows to its table.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from netsim.cli.analyze_table import NS
from netsim.cli.analyze_table import jobs_of as _jobs_of
from netsim.cli.analyze_table import row as _row

__all__ = ["loop_rows"]


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
    rows = np.array(outs, dtype=int)
    if others.size and (np.any(A[np.ix_(idx, others)] != 0) or np.any(C[np.ix_(rows, others)] != 0)):
        return None
    if B.shape[1] > 1 and np.any(np.delete(B, i_in, axis=1)[idx, :] != 0):
        return None
    return idx


def loop_rows(scenario: Any, sim: Any, jobs: pd.DataFrame, result: Any) -> list[dict]:
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
