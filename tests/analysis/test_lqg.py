"""netsim.analysis.lqg: segment integrals by quadrature, closed forms (no delay = Riccati LQG cost, one-period
delay = an augmented discrete Lyapunov equation), a hand-computed scalar loop, and Monte-Carlo in netsim."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.linalg import expm, solve_discrete_are, solve_discrete_lyapunov

import netsim
from netsim.analysis.lqg import (
    SampledLoop,
    TimingDistribution,
    lqg_cost,
    pid_controller,
    segment_matrices,
    transient_cost,
)
from netsim.errors import ConfigError

A = np.array([[0.0, 1.0], [0.0, -1.0]])
B = np.array([[0.0], [1.0]])
Q1 = np.diag([1.0, 0.1])
Q2 = np.array([[0.01]])
R1 = np.diag([0.0, 1.0])


def _quad_matrix(fn, lo: float, hi: float, shape: tuple[int, int]) -> np.ndarray:
    return np.array([[quad(lambda t: fn(t)[i, k], lo, hi, epsabs=1e-13, epsrel=1e-11)[0] for k in range(shape[1])]
                     for i in range(shape[0])])


def _sampled_by_quadrature(h: float) -> dict[str, np.ndarray | float]:
    """Phi, Gamma, the sampled cost (Q1d, Q12, Q2d), the noise covariance R1d and the intra-sample noise cost,
    all by numerical quadrature of the defining integrals (independent of lqg's block exponentials)."""
    n, m = B.shape
    Ab = np.block([[A, B], [np.zeros((m, n + m))]])
    Qb = np.block([[Q1, np.zeros((n, m))], [np.zeros((m, n)), Q2]])
    Qd = _quad_matrix(lambda t: expm(Ab.T * t) @ Qb @ expm(Ab * t), 0.0, h, (n + m, n + m))
    W = lambda s: _quad_matrix(lambda t: expm(A * t) @ R1 @ expm(A.T * t), 0.0, s, (n, n))  # noqa: E731
    jn = quad(lambda s: float(np.trace(Q1 @ W(s))), 0.0, h, epsabs=1e-13)[0]
    E = expm(Ab * h)
    return {"Phi": E[:n, :n], "Gam": E[:n, n:], "Q1d": Qd[:n, :n], "Q12": Qd[:n, n:], "Q2d": Qd[n:, n:],
            "R1d": W(h), "jn": jn}


def test_segment_matrices_equal_their_integrals_by_quadrature() -> None:
    s = 0.07
    Phi, W, Q, j = segment_matrices(A, B, Q1, Q2, R1, s)
    d = _sampled_by_quadrature(s)
    assert np.allclose(Phi[:2, :2], d["Phi"], atol=1e-12) and np.allclose(Phi[:2, 2:], d["Gam"], atol=1e-12)
    assert np.allclose(W[:2, :2], d["R1d"], atol=1e-12) and np.allclose(W[2:, :], 0.0)
    assert np.allclose(Q, np.block([[d["Q1d"], d["Q12"]], [d["Q12"].T, d["Q2d"]]]), atol=1e-12)
    assert j == pytest.approx(d["jn"], rel=1e-8)


def test_scalar_integrator_by_hand() -> None:
    # dx = u dt + dv (intensity 1), u = -2 x(kh) with h = 0.1, no delay: x_{k+1} = 0.8 x_k + w, Var w = h, so
    # E x_k^2 = 0.1 / (1 - 0.64); per period int_0^h (1 - 2t)^2 dt * E x_k^2 + int_0^h t dt.
    loop = SampledLoop(A=[[0.0]], B=[[1.0]], C=[[1.0]], Dc=[[-2.0]], period_s=0.1, Q1=[[1.0]], Q2=[[0.0]], R1=[[1.0]])
    var = 0.1 / (1 - 0.64)
    per_period = (1 - 0.8**3) / 6 * var + 0.1**2 / 2
    r = lqg_cost(loop)
    assert r.covariance[0, 0] == pytest.approx(var, rel=1e-12)
    assert r.cost == pytest.approx(per_period / 0.1, rel=1e-12)
    assert r.spectral_radius == pytest.approx(0.64, rel=1e-12)


def test_no_delay_with_the_sampled_lqr_gain_costs_the_riccati_value() -> None:
    # Astrom & Wittenmark ch. 11: with x_{k+1} = Phi x + Gam u + w and the sampled cost (Q1d, Q12, Q2d), the
    # optimal stationary cost per period is tr(S R1d) + the intra-sample noise cost, S the DARE solution.
    h = 0.05
    d = _sampled_by_quadrature(h)
    S = solve_discrete_are(d["Phi"], d["Gam"], d["Q1d"], d["Q2d"], s=d["Q12"])
    L = np.linalg.solve(d["Q2d"] + d["Gam"].T @ S @ d["Gam"], d["Gam"].T @ S @ d["Phi"] + d["Q12"].T)
    expected = (np.trace(S @ d["R1d"]) + d["jn"]) / h
    loop = SampledLoop(A=A, B=B, C=np.eye(2), Dc=-L, period_s=h, Q1=Q1, Q2=Q2, R1=R1)
    assert lqg_cost(loop).cost == pytest.approx(expected, rel=1e-8)
    # and the gain is optimal: any other gain costs more
    for dL in ([[0.3, 0.0]], [[0.0, -0.2]]):
        other = SampledLoop(A=A, B=B, C=np.eye(2), Dc=-(L + np.array(dL)), period_s=h, Q1=Q1, Q2=Q2, R1=R1)
        assert lqg_cost(other).cost > expected


def test_a_delay_of_one_period_equals_the_augmented_lyapunov_solution() -> None:
    # u_k = -K x_k reaches the plant at t_{k+1}: xi_k = [x_k; u_{k-1}], xi_{k+1} = [[Phi, Gam], [-K, 0]] xi_k +
    # [w; 0]; the period cost is xi' [[Q1d, Q12], [Q12', Q2d]] xi + jn (the held input during period k is u_{k-1}).
    h = 0.05
    K = np.array([[4.0, 1.2]])
    d = _sampled_by_quadrature(h)
    F = np.block([[d["Phi"], d["Gam"]], [-K, np.zeros((1, 1))]])
    Wn = np.zeros((3, 3))
    Wn[:2, :2] = d["R1d"]
    P = solve_discrete_lyapunov(F, Wn)
    Qxi = np.block([[d["Q1d"], d["Q12"]], [d["Q12"].T, d["Q2d"]]])
    expected = (np.trace(Qxi @ P) + d["jn"]) / h
    loop = SampledLoop(A=A, B=B, C=np.eye(2), Dc=-K, period_s=h, Q1=Q1, Q2=Q2, R1=R1)
    assert lqg_cost(loop, delay=h).cost == pytest.approx(expected, rel=1e-8)
    assert lqg_cost(loop, delay=0.0).cost < expected  # the delay costs


def test_a_constant_offset_is_no_jitter_and_jitter_costs() -> None:
    loop = SampledLoop(A=A, B=B, C=np.eye(2), Dc=[[-10.0, -4.0]], period_s=0.1, Q1=Q1, Q2=Q2, R1=R1)
    base = lqg_cost(loop, delay=0.02).cost
    assert lqg_cost(loop, delay=0.02, offset=TimingDistribution.constant(0.03)).cost == pytest.approx(base, rel=1e-10)
    jittered = lqg_cost(loop, delay=0.02, offset=TimingDistribution.uniform(0.0, 0.04, 5)).cost
    assert jittered > base * 1.01


def test_measurement_noise_and_a_dynamic_controller() -> None:
    # PID (netsim.control.pid form) on the servo: with measurement noise the cost grows by exactly the noise's
    # share, which is linear in R2 (the loop is linear): J(R2) = J(0) + R2 * (J(1) - J(0)).
    Ac, Bc, Cc, Dc = pid_controller(K=2.0, Ti=2.0, Td=0.3, N=10.0, h=0.05)
    mk = lambda r2: SampledLoop(A=A, B=B, C=[[1.0, 0.0]], Ac=Ac, Bc=Bc, Cc=Cc, Dc=Dc, period_s=0.05,  # noqa: E731
                                Q1=Q1, Q2=Q2, R1=R1, R2=[[r2]])
    j0, j1, j3 = (lqg_cost(mk(r2), delay=0.01).cost for r2 in (0.0, 1e-4, 3e-4))
    assert np.isfinite(j0) and j1 > j0
    assert j3 == pytest.approx(j0 + 3 * (j1 - j0), rel=1e-9)


def test_pid_state_space_reproduces_netsims_pid() -> None:
    from netsim.control.pid import PID

    Ac, Bc, Cc, Dc = pid_controller(K=0.96, Ti=0.12, Td=0.049, N=10.0, h=0.006)
    pid = PID(0.96, 0.12, 0.049, 10.0, 0.5, 0.006)
    ys = np.sin(np.arange(30) * 0.7) + 0.1 * np.arange(30)
    xc = np.array([0.0, 0.0, ys[0]])  # netsim's PID takes y(k-1) = y(0) at the first step
    for y in ys:
        u = float((Cc @ xc + Dc @ [y])[0])
        assert u == pytest.approx(pid.step(0.0, y), abs=1e-12)
        xc = Ac @ xc + Bc @ [y]


def test_unstable_loop_costs_infinity_and_bad_timing_is_refused() -> None:
    loop = SampledLoop(A=A, B=B, C=np.eye(2), Dc=[[-400.0, -40.0]], period_s=0.1, Q1=Q1, Q2=Q2, R1=R1)
    r = lqg_cost(loop, delay=0.05)
    assert r.cost == float("inf") and r.spectral_radius > 1
    with pytest.raises(ConfigError, match="reaches past the earliest next sample"):
        lqg_cost(loop, delay=0.09, offset=TimingDistribution((0.0, 0.02), (1, 1)))
    with pytest.raises(ConfigError, match="Dc must be 1 x 2"):
        SampledLoop(A=A, B=B, C=np.eye(2), Dc=[[1.0]], period_s=0.1, Q1=Q1, Q2=Q2)


def test_monte_carlo_in_netsim_converges_to_the_analytic_cost() -> None:
    # The servo-like plant with process noise, state feedback u = -K x run as a netsim task whose execution time
    # (hence the sample-to-actuation delay) is 10, 50 or 90 ms at random each period of 100 ms. The simulated
    # time-average cost, with a 95 % batch-means confidence interval, must contain the analytic value, and must
    # exclude the analytic value without delay (0.058: the delay matters by 30 %). Seed 3 measures 0.0755 +- 0.0060
    # against the analytic 0.0766.
    h, K = 0.1, [[10.0, 4.0]]
    scenario = {
        "name": "lqg_mc", "seed": 3, "duration": "300 s",
        "plant": {"type": "ss", "A": A.tolist(), "B": B.tolist(), "C": [[1, 0], [0, 1]], "outputs": ["p", "v"],
                  "inputs": ["u"], "process_noise": [0, 1.0], "record_grid": "5 ms"},
        "io": {"p_m": {"type": "adc", "output": "p"}, "v_m": {"type": "adc", "output": "v"},
               "u": {"type": "dac", "input": "u"}},
        "nodes": {"cpu": {"policy": "fp", "tasks": [{
            "name": "ctl", "program": "state_feedback", "period": "100 ms", "priority": 1,
            "execution": {"dist": "empirical", "values": ["10 ms", "50 ms", "90 ms"]},
            "params": {"measurements": [{"channel": "p_m", "outputs": ["p"]}, {"channel": "v_m", "outputs": ["v"]}],
                       "estimator": {"type": "none"}, "law": {"type": "state_feedback", "K": K},
                       "output_channel": "u", "record_as": "u"}}]}},
        "record": ["p", "v", "u"],
    }
    res = netsim.run(scenario)
    assert res.status == "ok"
    s = res.signals
    t = s["time_s"].to_numpy()
    inst = Q1[0, 0] * s["p"].to_numpy() ** 2 + Q1[1, 1] * s["v"].to_numpy() ** 2 \
        + Q2[0, 0] * np.nan_to_num(s["u"].to_numpy()) ** 2
    dt = np.diff(t)
    per_step = inst[:-1] * dt
    batches = 30
    size = len(per_step) // batches
    means = per_step[: batches * size].reshape(batches, size).sum(axis=1) / dt[: batches * size].reshape(batches, size).sum(axis=1)
    mean, half = means.mean(), 2.045 * means.std(ddof=1) / np.sqrt(batches)  # t(0.975, 29) = 2.045
    loop = SampledLoop(A=A, B=B, C=np.eye(2), Dc=-np.array(K), period_s=h, Q1=Q1, Q2=Q2, R1=R1)
    delays = TimingDistribution.empirical((res.jobs["finish_s"] - res.jobs["release_s"]).dropna())
    assert delays.values == pytest.approx((0.01, 0.05, 0.09))
    analytic = lqg_cost(loop, delay=TimingDistribution((0.01, 0.05, 0.09), (1, 1, 1))).cost
    assert abs(mean - analytic) < half, (mean, half, analytic)
    assert abs(mean - lqg_cost(loop).cost) > half


def _servo_pid_ise_by_fine_simulation(T: float, h: float, delay: float) -> float:
    """ISE of r - y for TrueTime's servo 1000/(s(s+1)) under netsim's PID (K 0.96, Ti 0.12, Td 0.049, N 10,
    b 0.5), square reference +-1 of period 1 s, sampled every h, output after `delay`: exact ZOH steps of 10 us
    and the trapezoidal rule (an independent time-stepping computation)."""
    from netsim.control.pid import PID

    dt = 1e-5
    Ad = expm(np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 1000.0], [0.0, 0.0, 0.0]]) * dt)
    pid = PID(0.96, 0.12, 0.049, 10.0, 0.5, h)
    per, dl = int(round(h / dt)), int(round(delay / dt))
    x, u, pending, ise = np.zeros(2), 0.0, 0.0, 0.0
    r = lambda t: 1.0 if (t % 1.0) < 0.5 - 1e-12 else -1.0  # noqa: E731
    for i in range(int(round(T / dt))):
        t = i * dt
        if i % per == 0:
            pending = pid.step(r(t), x[0])
        if i % per == dl:
            u = pending
        e0 = r(t) - x[0]
        x = (Ad @ np.r_[x, u])[:2]
        e1 = r(t) - x[0]  # r is constant on [t, t + dt): its jumps are at multiples of dt
        ise += 0.5 * (e0 * e0 + e1 * e1) * dt
    return ise


def test_transient_cost_of_a_pid_step_response_with_reference_jumps() -> None:
    h, delay, T = 0.004, 0.002, 0.7
    Aa = np.zeros((3, 3))
    Aa[:2, :2] = A
    Ba = np.array([[0.0], [1000.0], [0.0]])
    e = np.array([[1.0, 0.0, -1.0]])  # r - y with the reference as the third state
    Ac, Bc, Cc, Dc = pid_controller(0.96, 0.12, 0.049, 10.0, h, b=0.5)
    loop = SampledLoop(A=Aa, B=Ba, C=[[0, 0, 1.0], [1.0, 0, 0]], Ac=Ac, Bc=Bc, Cc=Cc, Dc=Dc, period_s=h,
                       Q1=e.T @ e, Q2=[[0.0]])
    flip = np.diag([1.0, 1.0, -1.0])
    analytic = transient_cost(loop, T, [0.0, 0.0, 1.0], delay=delay, jumps=[(0.5, flip)])
    assert analytic == pytest.approx(_servo_pid_ise_by_fine_simulation(T, h, delay), rel=1e-6)
    # one offset value with its own delay list is the plain delay
    assert transient_cost(loop, T, [0.0, 0.0, 1.0], delay=[TimingDistribution.constant(delay)],
                          jumps=[(0.5, flip)]) == pytest.approx(analytic, rel=1e-12)
    # a late sample with a long delay would act after the next sample: refused, naming what to change
    with pytest.raises(ConfigError, match="reaches past the earliest next sample"):
        transient_cost(loop, T, [0.0, 0.0, 1.0], offset=TimingDistribution((0.0, 0.002), (1, 1)),
                       delay=[TimingDistribution.constant(0.003), TimingDistribution.constant(0.003)])
