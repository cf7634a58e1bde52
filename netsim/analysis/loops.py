"""A scenario's control loops and their expected cost: the ``loop`` rows of ``netsim analyze``.

A loop here is a PID (a ``periodic_controller`` task, or a ``sampler`` -> ``controller`` -> ``actuator`` chain on
a network) or a static ``state_feedback`` task (``estimator: none``, a law without integral action or limits),
on an LTI plant with plain io (ADCs and a DAC without noise, quantisation or saturation) and a square-wave
reference of bias 0 (or none).

Its cost is the expected ISE of ``r - y`` over a run, from :func:`netsim.analysis.lqg.transient_cost`: the part of
the plant the loop's input drives, the controller at the sampling instants, and the sampling offsets and
input-output delays the run measured, taken as independent from period to period (:class:`LoopTiming`).

:func:`find_loops` lists the loops of a built scenario, :func:`loop_output` names the plant output whose error the
loop is judged by, :func:`loop_cost` gives the expected ISE of one loop (or why it is outside the analysis), and
:func:`expected_ise` is the computation itself on plain matrices and measured times.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Protocol, Union

import numpy as np

from netsim.analysis.lqg import SampledLoop, TimingDistribution, pid_controller, transient_cost

if TYPE_CHECKING:
    import pandas as pd

    from netsim.io.signals import Square
    from netsim.scenario.schema import Scenario

__all__ = ["BuiltLoops", "DiscreteController", "Loop", "LoopCost", "LoopTiming", "expected_ise", "find_loops",
           "loop_cost", "loop_output", "lti_plant", "measured_timing", "subsystem"]

#: Seconds per nanosecond.
NS = 1e-9
#: Resolution (s) the measured offsets and delays are rounded to before they enter the analysis.
TIMING_RESOLUTION_S = 10e-6


class BuiltLoops(Protocol):
    """What the loop analysis reads of a built scenario (a :class:`netsim.build.builder.Simulation`): the plant
    object, the signals by name and the programs by ``node.task``."""

    plant: Any
    signals: dict[str, Callable[[int], float]]
    programs: dict[str, Any]


@dataclass(frozen=True)
class DiscreteController:
    """A loop's controller at its samples: ``xc+ = Ac xc + Bc [r; y]``, ``u = Cc xc + Dc [r; y]``.

    ``Ac``, ``Bc``, ``Cc`` are None for a static gain; ``xc0`` is the initial controller state (None: zeros).
    """

    Ac: np.ndarray | None
    Bc: np.ndarray | None
    Cc: np.ndarray | None
    Dc: np.ndarray
    xc0: list[float] | None = None


#: ``make(h, C, idx, y0)``: the controller of a loop sampled every ``h`` s that measures ``C`` (rows of the
#: measured outputs over the states ``idx`` of the plant it drives) starting from ``y0``; or why there is none.
ControllerMaker = Callable[[float, np.ndarray, np.ndarray, np.ndarray], Union[DiscreteController, str]]


@dataclass(frozen=True)
class Loop:
    """One control loop of a scenario.

    Attributes
    ----------
    name
        ``node.task`` of the controller.
    reference
        The scenario signal it tracks (None: regulation to 0).
    adcs, dac
        The io channels it measures and the one it writes.
    sample, act
        ``(node, task)`` whose job start is the sampling instant, and whose job finish is the actuation.
    controller
        Makes the controller once the sampling period and the measured part of the plant are known.
    """

    name: str
    reference: str | None
    adcs: tuple[str, ...]
    dac: str
    sample: tuple[str, str]
    act: tuple[str, str]
    controller: ControllerMaker


@dataclass(frozen=True)
class LoopCost:
    """What :func:`loop_cost` found for one loop.

    Attributes
    ----------
    cost
        The expected ISE (None: the loop is outside the analysis, ``why`` says how).
    why
        Why there is no cost ("" when there is one).
    pairs
        The number of distinct ``(offset, delay)`` pairs of the run the cost was computed with.
    """

    cost: float | None
    why: str = ""
    pairs: int = 0


@dataclass(frozen=True, eq=False)
class LoopTiming:
    """A loop's timing in a run: per period, the sampling offset from the nominal release and the delay from
    the sample to the actuation (s)."""

    period_s: float
    offsets_s: np.ndarray
    delays_s: np.ndarray

    def distributions(self) -> tuple[TimingDistribution, list[TimingDistribution]]:
        """The offsets' distribution and, per offset value, the distribution of the delays measured with it
        (both rounded to :data:`TIMING_RESOLUTION_S`)."""
        res = TIMING_RESOLUTION_S
        off = TimingDistribution.empirical(self.offsets_s, resolution_s=res)
        keys = np.round(self.offsets_s / res)
        dly = [TimingDistribution.empirical(self.delays_s[keys == round(v / res)], resolution_s=res)
               for v in off.values]
        return off, dly


def lti_plant(sim: BuiltLoops) -> Any:
    """The simulation's plant when it is LTI (it has ``A``, ``B``, ``C`` and ``D``), else None."""
    plant = sim.plant
    if plant is None or not all(hasattr(plant, k) for k in ("A", "B", "C")) or getattr(plant, "D", None) is None:
        return None
    return plant


def subsystem(A: np.ndarray, B: np.ndarray, C: np.ndarray, i_in: int, outs: list[int]) -> np.ndarray | None:
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


# --------------------------------------------------------------------------------------------- the loops
def find_loops(scenario: Scenario, sim: BuiltLoops) -> list[Loop]:
    """The PID and static state-feedback loops of ``scenario`` (built as ``sim``); none without an LTI plant."""
    if lti_plant(sim) is None:
        return []
    return [*_pid_loops(scenario), *_state_feedback_loops(scenario, sim)]


def _pid_maker(params: dict[str, Any]) -> ControllerMaker:
    """The controller maker of a PID (netsim.control.pid form, ``h`` from its params or the sampling period)."""
    from netsim.timebase import parse_time, to_seconds

    def make(h: float, Csub: np.ndarray, idx: np.ndarray, y0: np.ndarray) -> DiscreteController | str:
        given = params.get("h")
        h_ctrl = h if given is None else to_seconds(parse_time(given) if isinstance(given, str) else int(given))
        if params.get("u_min") is not None or params.get("u_max") is not None:
            return "the PID has output limits"
        Ac, Bc, Cc, Dc = pid_controller(float(params.get("K", 1.0)), params.get("Ti"), float(params.get("Td", 0.0)),
                                        float(params.get("N", 10.0)), h_ctrl, b=float(params.get("b", 1.0)))
        return DiscreteController(Ac, Bc, Cc, Dc, [0.0, 0.0, float(y0[0])])  # netsim's PID: y(k-1) = y(0) at first

    return make


def _pid_loops(scenario: Scenario) -> list[Loop]:
    """PID loops: one ``periodic_controller`` task, or a ``sampler`` -> ``controller`` -> ``actuator`` chain."""
    out = []
    for node_name, node in scenario.nodes.items():
        for t in node.tasks:
            p = t.params
            if t.program == "periodic_controller":
                adc, dac = p.get("channel"), p.get("output_channel")
                if isinstance(adc, str) and isinstance(dac, str):  # both required by the program's Params
                    out.append(Loop(f"{node_name}.{t.name}", p.get("reference"), (adc,), dac, (node_name, t.name),
                                    (node_name, t.name), _pid_maker(p)))
            elif t.program == "controller" and p.get("network") and t.release_kind == "on_message":
                net = p["network"]
                samplers = [(n, s) for n, nd in scenario.nodes.items() for s in nd.tasks
                            if s.program == "sampler" and s.params.get("network") == net
                            and s.params.get("to") == node_name and s.release_kind == "periodic"]
                acts = [(n, a) for n, nd in scenario.nodes.items() for a in nd.tasks
                        if a.program == "actuator" and a.params.get("network") == net and n == p.get("to")]
                if len(samplers) == 1 and len(acts) == 1:
                    (sn, s), (an, a) = samplers[0], acts[0]
                    adc, dac = s.params.get("channel"), a.params.get("channel")
                    if isinstance(adc, str) and isinstance(dac, str):  # both required by the programs' Params
                        out.append(Loop(f"{node_name}.{t.name}", p.get("reference"), (adc,), dac, (sn, s.name),
                                        (an, a.name), _pid_maker(p)))
    return out


def _state_feedback_loops(scenario: Scenario, sim: BuiltLoops) -> list[Loop]:
    """``state_feedback`` tasks that sample ADCs and write a DAC with ``estimator: none`` and a static law
    (``lqr`` or ``state_feedback`` without integral action or limits): ``u = Fr r - K C^-1 y``."""
    out = []
    n_plant = int(np.asarray(sim.plant.A).shape[0])
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
            out.append(Loop(f"{node_name}.{t.name}", p.get("reference"), tuple(m["channel"] for m in srcs),
                            p["output_channel"], (node_name, t.name), (node_name, t.name),
                            _static_feedback_maker(law, est, n_plant)))
    return out


def _static_feedback_maker(law: Any, est: Any, n: int) -> ControllerMaker:
    """The controller maker of a static state feedback ``u = Fr r - K C^-1 y`` (``law``, ``est``: the objects the
    program runs; ``n``: the plant's states)."""

    def make(h: float, Csub: np.ndarray, idx: np.ndarray, y0: np.ndarray) -> DiscreteController | str:
        if getattr(law, "u_min", None) is not None or getattr(law, "u_max", None) is not None:
            return "the law has input limits"
        if idx.size != n or law.K.shape[0] != 1:
            return "the analysis takes a state feedback on the whole plant with one input"
        Cinv = np.asarray(est._Cinv, float)
        Fr = np.asarray(getattr(law, "_Fr", np.zeros((1, 1))), float).sum(axis=1, keepdims=True) \
            if getattr(law, "Cr", None) is not None else np.zeros((1, 1))
        Dc = np.hstack([Fr, -law.K @ Cinv])
        return DiscreteController(None, None, None, Dc, None)

    return make


def _output_index(scenario: Scenario, plant: Any, channel: str) -> int | None:
    """The plant output an ADC or encoder channel reads (None for a DAC)."""
    io = scenario.io[channel]
    return None if io.type == "dac" else int(plant.output_index(io.output))


def loop_output(scenario: Scenario, plant: Any, loop: Loop) -> str | None:
    """The plant output ``loop`` is judged by: the output of a ``control_error`` metric against its reference
    (the output its first channel measures first), or None."""
    first = _output_index(scenario, plant, loop.adcs[0])
    prefer = plant.output_names[first] if first is not None else None
    outs = [m.params.get("output") for m in scenario.metrics
            if m.type == "control_error" and m.params.get("reference") == loop.reference]
    outs = [o for o in outs if o in plant.output_names]
    if prefer in outs:
        return prefer
    return outs[0] if outs else None


# --------------------------------------------------------------------------------------------- the cost
def measured_timing(jobs: pd.DataFrame, loop: Loop, period_s: float) -> LoopTiming | str:
    """The sampling offsets and input-output delays of ``loop`` in a run's ``jobs`` table (one pair per sample
    with a finished actuation), or why they cannot be paired."""
    sj = _jobs_of(jobs, *loop.sample).sort_values("release_s").dropna(subset=["start_s"])
    aj = _jobs_of(jobs, *loop.act).sort_values("release_s").dropna(subset=["finish_s"])
    k = min(len(sj), len(aj))
    if k == 0:
        return "no finished jobs"
    offsets = sj["start_s"].to_numpy()[:k] - sj["release_s"].to_numpy()[:k]
    delays = aj["finish_s"].to_numpy()[:k] - sj["start_s"].to_numpy()[:k]
    if np.any(delays < 0) or len(sj) - len(aj) > 1:
        return "samples and actuations do not pair one to one"
    return LoopTiming(period_s, offsets, delays)


def _jobs_of(jobs: pd.DataFrame, node: str, task: str) -> pd.DataFrame:
    return jobs[(jobs["node"] == node) & (jobs["task"] == task)]


def loop_cost(scenario: Scenario, sim: BuiltLoops, loop: Loop, output: str, jobs: pd.DataFrame,
              t_end_s: float) -> LoopCost:
    """The expected ISE of ``r - output`` of ``loop`` over ``[0, t_end_s]``, with the timing of the run's ``jobs``.

    Parameters
    ----------
    scenario, sim
        The scenario and the simulation built from it (its plant, signals and programs).
    loop
        One of :func:`find_loops`.
    output
        The plant output judged (:func:`loop_output`).
    jobs
        The run's jobs table.
    t_end_s
        The end of the run (s).
    """
    from netsim.io.signals import Square
    from netsim.timebase import to_seconds

    plant = lti_plant(sim)
    if plant is None:
        return LoopCost(None, "the plant is not LTI")
    A, B, C = np.asarray(plant.A, float), np.asarray(plant.B, float), np.asarray(plant.C, float)
    if np.any(np.asarray(plant.D) != 0) or np.any(np.asarray(getattr(plant, "Qc", 0)) != 0):
        return LoopCost(None, "the analysis of a run's ISE needs a noise-free plant without feed-through")
    sig = sim.signals.get(loop.reference) if loop.reference else None
    if loop.reference and not (isinstance(sig, Square) and sig.bias == 0.0):
        return LoopCost(None, "the analysis handles a square-wave reference with bias 0, or none")
    reference = sig if isinstance(sig, Square) else None
    dac = scenario.io[loop.dac]
    adcs = [scenario.io[ch] for ch in loop.adcs]
    plain_adcs = [io for io in adcs if io.type == "adc" and not (io.noise_std or io.quant_step or io.saturation)]
    if dac.type != "dac" or dac.saturation or len(plain_adcs) < len(adcs):
        return LoopCost(None, "the analysis needs plain ADCs and a DAC (no noise, quantisation or saturation)")
    i_in = int(plant.input_index(dac.input))
    meas_rows = [int(plant.output_index(io.output)) for io in plain_adcs]
    i_out = int(plant.output_index(output))
    idx = subsystem(A, B, C, i_in, [i_out, *meas_rows])
    if idx is None:
        return LoopCost(None, "the loop's input and outputs do not isolate a part of the plant")
    timed = scenario.nodes[loop.sample[0]].task(loop.sample[1])
    if timed.release_kind != "periodic" or not timed.period:
        return LoopCost(None, "the sampling task is not periodic")
    h = to_seconds(timed.period)
    timing = measured_timing(jobs, loop, h)
    if isinstance(timing, str):
        return LoopCost(None, timing)
    off, dly = timing.distributions()
    worst = float(np.max(timing.offsets_s + timing.delays_s))
    if worst > h + min(off.values):
        return LoopCost(None, f"output {worst * 1e3:.3g} ms after the nominal sample, past the next one "
                              f"(h = {h * 1e3:.3g} ms)")
    ns = idx.size
    Csub = C[np.ix_(np.asarray(meas_rows, dtype=int), idx)]
    x0 = np.zeros(ns)
    if getattr(plant, "x0", None) is not None:
        x0 = np.asarray(plant.x0, float)[idx]
    made = loop.controller(h, Csub, idx, Csub @ x0)
    if isinstance(made, str):
        return LoopCost(None, made)
    cost = expected_ise(A[np.ix_(idx, idx)], B[idx, i_in: i_in + 1], Csub, C[i_out: i_out + 1, idx], x0, made,
                        timing, t_end_s, reference)
    return LoopCost(cost, pairs=sum(len(d.values) for d in dly))


def expected_ise(A: np.ndarray, B: np.ndarray, C: np.ndarray, c_out: np.ndarray, x0: np.ndarray,
                 controller: DiscreteController, timing: LoopTiming, t_end_s: float,
                 reference: Square | None = None) -> float:
    """The expected ISE of ``r - c_out x`` over ``[0, t_end_s]`` of a sampled loop.

    The plant ``dx/dt = A x + B u`` (one input) starts at ``x0`` with ``u = 0`` held until the first actuation.
    Sample ``k`` is taken at ``k h + o_k``: the controller reads ``[r; C x]`` and its output ``u_k`` is applied
    ``d_k`` later and held. The pairs ``(o_k, d_k)`` are drawn independently per period from the run's
    (:meth:`LoopTiming.distributions`). The reference is a square wave of bias 0 (its sign flips at each
    breakpoint) or 0.

    Parameters
    ----------
    A, B, C, c_out
        ``n x n``, ``n x 1``, the measured rows ``p x n`` and the judged output ``1 x n``.
    x0
        Initial plant state (``n``).
    controller
        The discrete controller reading ``[r; y]`` (``1 + p`` inputs).
    timing
        The period and the measured offsets and delays.
    t_end_s
        Horizon (s).
    reference
        The reference signal, or None for ``r = 0``.
    """
    ns = A.shape[0]
    off, dly = timing.distributions()
    Aa = np.zeros((ns + 1, ns + 1))  # the reference rides along as a state with no dynamics
    Aa[:ns, :ns] = A
    Ba = np.vstack([B, [[0.0]]])
    Cm = np.zeros((1 + C.shape[0], ns + 1))  # the controller reads [r; y]
    Cm[0, ns] = 1.0
    Cm[1:, :ns] = C
    e = np.hstack([c_out, [[-1.0]]])
    loop = SampledLoop(A=Aa, B=Ba, C=Cm, Ac=controller.Ac, Bc=controller.Bc, Cc=controller.Cc, Dc=controller.Dc,
                       period_s=timing.period_s, Q1=e.T @ e, Q2=[[0.0]])
    z0 = np.append(np.asarray(x0, float), reference(0) if reference is not None else 0.0)
    flip = np.eye(ns + 1)
    flip[ns, ns] = -1.0
    jumps = [(bp * NS, flip) for bp in reference.breakpoints(0, int(t_end_s / NS))] if reference is not None else []
    return transient_cost(loop, t_end_s, z0, delay=dly, offset=off, jumps=jumps, xc0=controller.xc0)
