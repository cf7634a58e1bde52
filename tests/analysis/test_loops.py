"""netsim.analysis.loops: the expected ISE of a PID loop against independent computations (a closed form, and an
exact enumeration of every timing path), and the loops it finds in a scenario."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from netsim.analysis.loops import (
    DiscreteController,
    LoopTiming,
    expected_ise,
    find_loops,
    loop_cost,
    loop_output,
    measured_timing,
)
from netsim.analysis.lqg import pid_controller
from netsim.io.signals import Square

ROOT = Path(__file__).resolve().parents[2]
MS = 1e-3
INTEGRATOR = (np.zeros((1, 1)), np.ones((1, 1)), np.ones((1, 1)))  # dx/dt = u, y = x


def _pid(K: float, Ti: float | None, Td: float, N: float, h: float, b: float, y0: float) -> DiscreteController:
    Ac, Bc, Cc, Dc = pid_controller(K, Ti, Td, N, h, b=b)
    return DiscreteController(Ac, Bc, Cc, Dc, [0.0, 0.0, y0])  # netsim's PID starts with y(k-1) = y(0)


def test_a_proportional_loop_without_delay_costs_the_geometric_sum() -> None:
    # By hand: u = -K x(kh) held over [kh, (k+1)h) gives x(kh + t) = x_k (1 - K t) and x_{k+1} = q x_k with
    # q = 1 - K h; int_0^h x_k^2 (1 - K t)^2 dt = x_k^2 c with c = h - K h^2 + K^2 h^3 / 3; over n periods,
    # ISE = x0^2 c (1 - q^(2n)) / (1 - q^2).
    K, h, x0, n = 20.0, 10 * MS, 0.5, 8
    q = 1 - K * h
    c = h - K * h**2 + K**2 * h**3 / 3
    by_hand = x0**2 * c * (1 - q ** (2 * n)) / (1 - q**2)
    timing = LoopTiming(h, np.array([0.0]), np.array([0.0]))
    cost = expected_ise(*INTEGRATOR, np.ones((1, 1)), np.array([x0]), _pid(K, None, 0.0, 10.0, h, 1.0, x0),
                        timing, n * h)
    assert cost == pytest.approx(by_hand, rel=1e-9)


def _square(t: float, period: float) -> float:
    """The reference: +1 on the first half of each period, -1 on the second (netsim's square, duty 0.5)."""
    return 1.0 if (t % period) < period / 2 else -1.0


def _ise_by_enumeration(K: float, Ti: float, Td: float, N: float, b: float, h: float, x0: float,
                        pairs: list[tuple[float, float]], T: float, r_period: float) -> float:
    """E[ISE] of r - x for the integrator under netsim's PID (the equations of netsim.control.pid's docstring,
    written out here), averaged over every sequence of (offset, delay) pairs, each period drawing one of
    ``pairs`` with equal probability. Between events x is linear in t, so each piece integrates exactly:
    int_0^L (c - u s)^2 ds = c^2 L - c u L^2 + u^2 L^3 / 3."""
    ad = Td / (Td + N * h)
    bd = K * N * ad
    ki = K * h / Ti
    n = math.ceil(T / h)
    jumps = [j * r_period / 2 for j in range(1, int(2 * T / r_period) + 1) if j * r_period / 2 < T]
    total = 0.0
    for path in itertools.product(pairs, repeat=n):
        events = [(k * h + o, 0, k) for k, (o, _) in enumerate(path)]  # 0: sample
        events += [(k * h + o + d, 1, k) for k, (o, d) in enumerate(path)]  # 1: actuation
        events += [(t, 2, -1) for t in jumps]  # 2: the reference flips (never at a sample or an actuation)
        events = sorted(e for e in events if e[0] < T) + [(T, 3, -1)]
        x, u, t_now, ise = x0, 0.0, 0.0, 0.0
        I, D, y_prev = 0.0, 0.0, x0
        pending: dict[int, float] = {}
        for t, kind, k in events:
            L = t - t_now
            c = _square(t_now, r_period) - x
            ise += c * c * L - c * u * L * L + u * u * L**3 / 3
            x += u * L
            t_now = t
            if kind == 0:
                r, y = _square(t, r_period), x
                D = ad * D - bd * (y - y_prev)
                pending[k] = K * (b * r - y) + I + D
                I += ki * (r - y)
                y_prev = y
            elif kind == 1:
                u = pending[k]
        total += ise
    return total / len(pairs) ** n


def test_a_pid_loop_with_jitter_and_a_square_reference_equals_the_enumeration_of_its_timing_paths() -> None:
    # A PID (integral and filtered derivative, set-point weight 0.7) on dx/dt = u, 6 periods of 10 ms; each
    # period samples 0 or 1 ms late and actuates 2 or 4 ms after its sample, the four pairs equally likely and
    # independent (as measured: each offset seen with each delay once). The reference is a square wave of period
    # 46 ms, so its flips at 23 and 46 ms fall between samples and actuations. 4^6 = 4096 paths, each exact.
    K, Ti, Td, N, b, h, x0, T, rp = 20.0, 0.05, 0.005, 10.0, 0.7, 10 * MS, 0.3, 60 * MS, 46 * MS
    pairs = [(0.0, 2 * MS), (0.0, 4 * MS), (1 * MS, 2 * MS), (1 * MS, 4 * MS)]
    timing = LoopTiming(h, np.array([o for o, _ in pairs]), np.array([d for _, d in pairs]))
    reference = Square(Square.Params(amplitude=1.0, period="46 ms"))
    cost = expected_ise(*INTEGRATOR, np.ones((1, 1)), np.array([x0]), _pid(K, Ti, Td, N, h, b, x0), timing, T,
                        reference)
    assert cost == pytest.approx(_ise_by_enumeration(K, Ti, Td, N, b, h, x0, pairs, T, rp), rel=1e-9)
    # the timing matters: with every sample on time and acted on at once, the cost is another number
    prompt = LoopTiming(h, np.array([0.0]), np.array([0.0]))
    assert expected_ise(*INTEGRATOR, np.ones((1, 1)), np.array([x0]), _pid(K, Ti, Td, N, h, b, x0), prompt, T,
                        reference) == pytest.approx(
        _ise_by_enumeration(K, Ti, Td, N, b, h, x0, [(0.0, 0.0)], T, rp), rel=1e-9)


def test_the_loops_of_a_networked_servo_and_their_cost_from_its_run() -> None:
    import netsim
    from netsim.scenario import build, load_scenario

    scenario = load_scenario(ROOT / "scenarios" / "dc_servo_can.yaml")
    sim = build(scenario)
    loops = find_loops(scenario, sim)
    # the sampler -> controller -> actuator chain of the scenario file, named after its controller task
    assert [(lp.name, lp.reference, lp.adcs, lp.dac, lp.sample, lp.act) for lp in loops] == [
        ("controller.control", "r", ("y",), "u", ("sensor", "sample"), ("actuator", "actuate"))]
    assert loop_output(scenario, sim.plant, loops[0]) == "y"
    result = netsim.run(scenario)
    timing = measured_timing(result.jobs, loops[0], 10 * MS)
    assert not isinstance(timing, str)
    # each sample starts at its release and its actuation ends 0.5 ms (sample) + 1 ms (the frame) + 0.5 ms
    # (control) + 1 ms (frame) + 0.5 ms (actuate) = 3.5 ms later (the scenario's execution times, 80-bit frames
    # at 80 kbit/s; the sensor's 0.4 ms after sending delays nothing)
    assert np.allclose(timing.offsets_s, 0.0)
    assert np.allclose(timing.delays_s, 3.5 * MS)
    found = loop_cost(scenario, sim, loops[0], "y", result.jobs, float(result.signals["time_s"].max()))
    assert found.cost is not None and found.pairs == 1
    # the run's ISE holds y on its record grid: within 3 % of the expectation (test_analyze_command)
    assert float(result.metrics["y.ISE"]) == pytest.approx(found.cost, rel=0.03)
