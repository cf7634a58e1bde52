"""The control conventions of docs/control-conventions.md, each checked against the code.

Every estimator and law is built through the public path (a scenario dict built by ``netsim.scenario.build``,
or a full ``netsim.run``) and stepped; the expected values are the equations of the conventions page computed
here independently with numpy/scipy (matrix exponential, scipy's DARE, a bounded least-squares QP, Runge-Kutta
written out), never taken from the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla

import netsim
from netsim.scenario import build, load_scenario
from netsim.scenario.problems import ScenarioError

H = 0.01  # controller period of every scenario here, s
A_C = np.array([[0.0, 1.0], [0.0, -1.0]])  # DC servo 1000 / (s (s + 1)), states [theta, omega]
B_C = np.array([[0.0], [1000.0]])
C_SERVO = np.array([[1.0, 0.0]])
SERVO_NUM, SERVO_DEN = [1000.0], [1.0, 1.0, 0.0]
TASK = "nodes.c.tasks[0].params"


# ----------------------------------------------------------------------------------------------- helpers
def _zoh(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """ZOH discretisation by scipy's matrix exponential of the augmented matrix."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A * h, B * h
    E = sla.expm(M)
    return E[:n, :n], E[:n, n:]


def _dlqr(A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``u = -K x`` minimising ``sum x'Qx + u'Ru``: scipy's DARE, K = (R + B'PB)^-1 B'PA."""
    P = sla.solve_discrete_are(A, B, Q, R)
    return np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A), P


def _equilibrium(A: np.ndarray, B: np.ndarray, Cr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Nx, Nu) with x_s = Nx r, u_s = Nu r: (A - I) x_s + B u_s = 0, Cr x_s = r."""
    n, m = B.shape
    q = Cr.shape[0]
    sol = np.linalg.solve(np.block([[A - np.eye(n), B], [Cr, np.zeros((q, m))]]),
                          np.vstack([np.zeros((n, q)), np.eye(q)]))
    return sol[:n], sol[n:]


def _servo_plant(kind: str = "ss") -> dict:
    if kind == "tf":
        return {"type": "tf", "num": SERVO_NUM, "den": SERVO_DEN, "inputs": ["u"], "outputs": ["theta"]}
    return {"type": "ss", "A": A_C.tolist(), "B": B_C.ravel().tolist(), "C": C_SERVO.tolist(), "inputs": ["u"],
            "outputs": ["theta"], "x0": [1.0, 0.0]}


def _scenario(params: dict, *, plant: dict | None = None, channels: tuple[str, ...] = ("theta",),
              noise: float = 0.0, duration: str = "0.3 s", reference: float | None = 0.5) -> dict:
    """One node running ``state_feedback`` at 10 ms on ADC channels, writing u to a DAC."""
    plant = plant or _servo_plant()
    params = {"estimator": {"type": "kalman", "Q": 1e-3, "R": 1e-4}, **params}
    io = {f"y_{o}": {"type": "adc", "output": o, "noise_std": noise} for o in channels}
    io["u"] = {"type": "dac", "input": plant.get("inputs", ["u"])[0]}
    task_params = {"measurements": [{"channel": f"y_{o}"} for o in channels], "output_channel": "u",
                   "record_as": "u_cmd", "record_estimate": "xh", **params}
    raw = {"name": "conventions", "seed": 4, "duration": duration, "plant": plant, "io": io,
           "nodes": {"c": {"policy": "dm", "tasks": [{"name": "control", "program": "state_feedback",
                                                        "period": "10 ms", "params": task_params}]}},
           "record": ["u_cmd", "xh", "r"]}
    if reference is not None:
        raw["signals"] = {"r": {"type": "constant", "value": reference}}
        task_params["reference"] = "r"
    return raw


def _program(raw: dict):
    """The built state_feedback program (its design, estimator and law) of a scenario dict."""
    return build(raw).programs["c.control"]


# ----------------------------------------------------------------------------------------------- the model
def test_design_model_is_the_zoh_discretisation_at_the_task_period() -> None:
    prog = _program(_scenario({"law": {"type": "lqr", "Q": [1, 0], "R": 0.1}}))
    Ad, Bd = _zoh(A_C, B_C, H)
    np.testing.assert_allclose(prog.design.A, Ad, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(prog.design.B, Bd, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(prog.design.C, C_SERVO)
    assert prog.design.period_s == H


def test_tf_plant_states_are_python_controls_tf2ss_realisation() -> None:
    import control

    prog = _program(_scenario({"law": {"type": "lqr", "Q": 1, "R": 0.1}}, plant=_servo_plant("tf")))
    real = control.tf2ss(SERVO_NUM, SERVO_DEN)  # what the page tells users to call to see the state order
    Ad, Bd = _zoh(np.asarray(real.A), np.asarray(real.B), H)
    np.testing.assert_allclose(prog.design.A, Ad, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(prog.design.B, Bd, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(prog.design.C, np.asarray(real.C), rtol=1e-12, atol=1e-14)


# ----------------------------------------------------------------------------------------------- estimators
def test_kalman_is_the_current_form_time_varying_filter() -> None:
    Qn, Rn, P0, x0 = np.diag([1e-4, 1e-2]), np.array([[1e-3]]), np.diag([2.0, 3.0]), np.array([0.3, -0.2])
    prog = _program(_scenario({"estimator": {"type": "kalman", "Q": [1e-4, 1e-2], "R": 1e-3, "P0": [2, 3],
                                             "x0": x0.tolist()},
                               "law": {"type": "lqr", "Q": [1, 0], "R": 0.1}}))
    est = prog.estimator
    Ad, Bd = _zoh(A_C, B_C, H)
    rng = np.random.default_rng(1)
    x, P = x0.copy(), P0.copy()  # x[0|-1], P[0|-1]
    for k in range(6):
        y, u = rng.normal(size=1), rng.normal(size=1)
        if k != 3:  # sample 3 has no measurement: prediction only
            K = P @ C_SERVO.T @ np.linalg.inv(C_SERVO @ P @ C_SERVO.T + Rn)
            x = x + K @ (y - C_SERVO @ x)  # x[k|k]
            P = (np.eye(2) - K @ C_SERVO) @ P
            est.correct(y)
        np.testing.assert_allclose(est.x_hat, x, rtol=1e-9, atol=1e-12)  # the law is fed x[k|k]
        x, P = Ad @ x + Bd @ u, Ad @ P @ Ad.T + Qn  # x[k+1|k], P[k+1|k]
        est.predict(u)
        np.testing.assert_allclose(est.P, P, rtol=1e-9, atol=1e-14)


def test_steady_state_kalman_uses_the_gain_of_the_filter_dare() -> None:
    prog = _program(_scenario({"estimator": {"type": "steady_state_kalman", "Q": [1e-4, 1e-2], "R": 1e-3},
                               "law": {"type": "lqr", "Q": [1, 0], "R": 0.1}}))
    Ad, Bd = _zoh(A_C, B_C, H)
    M = sla.solve_discrete_are(Ad.T, C_SERVO.T, np.diag([1e-4, 1e-2]), np.array([[1e-3]]))  # prior covariance
    K = M @ C_SERVO.T / (C_SERVO @ M @ C_SERVO.T + 1e-3)
    est = prog.estimator
    x = np.zeros(2)
    for y, u in ((0.1, 0.2), (0.3, -0.1), (0.2, 0.0)):
        x = x + (K * (y - C_SERVO @ x)).ravel()
        est.correct([y])
        np.testing.assert_allclose(est.x_hat, x, rtol=1e-9, atol=1e-13)
        x = Ad @ x + Bd.ravel() * u
        est.predict([u])


@pytest.mark.parametrize("form", ["current", "predictor"])
def test_luenberger_places_the_error_poles_and_steps_as_stated(form: str) -> None:
    from scipy.signal import place_poles

    poles = [0.5, 0.6]
    prog = _program(_scenario({"estimator": {"type": "luenberger", "poles": poles, "form": form},
                               "law": {"type": "lqr", "Q": [1, 0], "R": 0.1}}))
    est = prog.estimator
    Ad, Bd = _zoh(A_C, B_C, H)
    Cf = C_SERVO @ Ad if form == "current" else C_SERVO  # current: eig((I - L C) A) = eig(A - L C A)
    L = place_poles(Ad.T, Cf.T, poles).gain_matrix.T  # one output: the gain is unique
    np.testing.assert_allclose(est.L, L, rtol=1e-8)
    E = (np.eye(2) - L @ C_SERVO) @ Ad if form == "current" else Ad - L @ C_SERVO
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(E).real), poles, atol=1e-10)
    x = np.zeros(2)
    for y, u in ((0.1, 0.2), (0.3, -0.1), (0.2, 0.0)):
        est.correct([y])
        if form == "current":
            x = x + (L * (y - C_SERVO @ x)).ravel()  # x_hat[k] = x_bar[k] + L (y[k] - C x_bar[k])
            np.testing.assert_allclose(est.x_hat, x, rtol=1e-12, atol=1e-14)
            x = Ad @ x + Bd.ravel() * u  # x_bar[k+1]
        else:
            np.testing.assert_allclose(est.x_hat, x, rtol=1e-12, atol=1e-14)  # y[k] not used yet
            x = Ad @ x + Bd.ravel() * u + (L * (y - C_SERVO @ x)).ravel()
        est.predict([u])


def test_no_estimator_inverts_c_and_predicts_a_missing_sample() -> None:
    C = np.array([[2.0, 0.0], [1.0, 1.0]])
    plant = {"type": "ss", "A": A_C.tolist(), "B": B_C.ravel().tolist(), "C": C.tolist(), "inputs": ["u"],
             "outputs": ["a", "b"]}
    prog = _program(_scenario({"estimator": {"type": "none"}, "law": {"type": "lqr", "Q": 1, "R": 0.1}},
                              plant=plant, channels=("a", "b"), reference=None))
    est = prog.estimator
    y = np.array([0.4, 0.5])
    est.correct(y)
    np.testing.assert_allclose(est.x_hat, np.linalg.solve(C, y), rtol=1e-14)
    Ad, Bd = _zoh(A_C, B_C, H)
    est.predict([0.3])
    np.testing.assert_allclose(est.x_hat, Ad @ np.linalg.solve(C, y) + Bd.ravel() * 0.3, rtol=1e-12)


def _rk4(f, x: np.ndarray, u: np.ndarray, h: float, steps: int) -> np.ndarray:
    dt = h / steps
    for _ in range(steps):
        k1 = f(x, u)
        k2 = f(x + dt / 2 * k1, u)
        k3 = f(x + dt / 2 * k2, u)
        k4 = f(x + dt * k3, u)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


def test_ekf_predicts_with_rk4_over_the_period_and_corrects_at_the_prior() -> None:
    from netsim.models.pendulum.model import PendulumParams, dynamics

    plant = {"type": "furuta_pendulum", "params": {"disturbance_std": 0.0}, "x0": [0.0, 0.0, 0.1, 0.0]}
    Qn, Rn = np.diag([1e-6, 1e-4, 1e-6, 1e-4]), np.diag([1e-6, 2e-6])
    prog = _program(_scenario({"estimator": {"type": "ekf", "Q": np.diag(Qn).tolist(), "R": [1e-6, 2e-6],
                                             "x0": [0.0, 0.0, 0.05, 0.0], "substeps": 3},
                               "law": {"type": "lqr", "Q": [5, 0, 20, 0], "R": 1}},
                              plant=plant, channels=("theta", "alpha"), reference=None))
    est = prog.estimator
    p = PendulumParams(disturbance_std=0.0)

    def f(x, u):
        return dynamics(0.0, x, u, p)

    Hm = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])  # y = [theta, alpha]: h is linear
    x, P = np.array([0.0, 0.0, 0.05, 0.0]), np.eye(4)
    for y, u in (([0.01, 0.08], [0.5]), ([0.02, 0.1], [-0.3])):
        y, u = np.array(y), np.array(u)
        K = P @ Hm.T @ np.linalg.inv(Hm @ P @ Hm.T + Rn)
        x, P = x + K @ (y - Hm @ x), (np.eye(4) - K @ Hm) @ P
        est.correct(y)
        # (the filter differentiates h numerically: its H is exact to about 1e-11)
        np.testing.assert_allclose(est.x_hat, x, rtol=1e-8, atol=1e-10)
        F = np.empty((4, 4))  # d phi / dx at x[k|k], central differences with our own step
        for i in range(4):
            d = np.zeros(4)
            d[i] = 1e-6
            F[:, i] = (_rk4(f, x + d, u, H, 3) - _rk4(f, x - d, u, H, 3)) / 2e-6
        x, P = _rk4(f, x, u, H, 3), F @ P @ F.T + Qn
        est.predict(u)
        np.testing.assert_allclose(est.x_hat, x, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(est.P, P, rtol=1e-6, atol=1e-12)


def test_fd_velocity_cutoff_is_in_hertz() -> None:
    fc = 20.0
    prog = _program(_scenario({"estimator": {"type": "pendulum_fd", "cutoff_hz": fc},
                               "law": {"type": "lqr", "Q": [5, 0, 20, 0], "R": 1}},
                              plant={"type": "furuta_pendulum", "params": {"disturbance_std": 0.0}},
                              channels=("theta", "alpha"), reference=None))
    est = prog.estimator
    a = math.exp(-2 * math.pi * fc * H)  # first-order low-pass 1 / (1 + s / (2 pi fc)), exact at the period
    p = [0.0, 0.01, 0.03, 0.04, 0.04]
    v = 0.0  # the first sample has no difference: velocity 0
    for k, pk in enumerate(p):
        est.correct([pk, -pk])
        if k:
            v = a * v + (1 - a) * (pk - p[k - 1]) / H
        np.testing.assert_allclose(est.x_hat, [pk, v, -pk, -v], rtol=1e-12, atol=1e-15)
        est.predict([0.0])


# ----------------------------------------------------------------------------------------------- laws
def test_state_feedback_law_is_feedforward_minus_k_x_hat() -> None:
    K = np.array([[2.0, 0.05]])
    prog = _program(_scenario({"law": {"type": "state_feedback", "K": K.tolist()}}))
    Ad, Bd = _zoh(A_C, B_C, H)
    Nx, Nu = _equilibrium(Ad, Bd, C_SERVO)
    x, r = np.array([0.2, -0.1]), 0.5
    np.testing.assert_allclose(prog.law.step(x, r), Nu @ [r] - K @ (x - Nx @ [r]), rtol=1e-12)
    # without a reference the law regulates the state to zero: u = -K x
    reg = _program(_scenario({"law": {"type": "state_feedback", "K": K.tolist()}}, reference=None))
    np.testing.assert_allclose(reg.law.step(x, 0.0), -K @ x, rtol=1e-12)


def test_tracked_picks_the_plant_outputs_the_reference_applies_to() -> None:
    A, B = np.array([[-1.0, 0.5], [0.0, -2.0]]), np.array([[0.0], [1.0]])  # stable: every output has a steady state
    C = np.eye(2)
    plant = {"type": "ss", "A": A.tolist(), "B": B.ravel().tolist(), "C": C.tolist(), "inputs": ["u"],
             "outputs": ["p", "q"]}
    law = {"type": "lqr", "Q": [1, 0.01], "R": 0.1}
    first = _program(_scenario({"law": law}, plant=plant, channels=("q", "p")))
    np.testing.assert_array_equal(first.design.Cr, C[[1]])  # default: the first measured output (q here)
    # tracked names plant outputs (names or indices), measured or not
    prog = _program(_scenario({"law": law, "tracked": ["q"]}, plant=plant, channels=("p",)))
    np.testing.assert_array_equal(prog.design.Cr, C[[1]])
    Ad, Bd = _zoh(A, B, H)
    K, _ = _dlqr(Ad, Bd, np.diag([1, 0.01]), np.array([[0.1]]))
    Nx, Nu = _equilibrium(Ad, Bd, C[[1]])
    x = np.array([0.3, 0.2])
    np.testing.assert_allclose(prog.law.step(x, 2.0), Nu @ [2.0] - K @ (x - Nx @ [2.0]), rtol=1e-10)
    np.testing.assert_allclose(C[[1]] @ Nx @ [2.0], [2.0], rtol=1e-12)  # the steady state holds q = r


def test_lqr_gain_is_the_discrete_riccati_gain() -> None:
    prog = _program(_scenario({"law": {"type": "lqr", "Q": [1, 0.01], "R": 0.1}}))
    Ad, Bd = _zoh(A_C, B_C, H)
    K, P = _dlqr(Ad, Bd, np.diag([1, 0.01]), np.array([[0.1]]))
    np.testing.assert_allclose(prog.law.K, K, rtol=1e-9)
    np.testing.assert_allclose(prog.law.P, P, rtol=1e-9)


def test_integral_action_integrates_r_minus_cr_x_hat_not_r_minus_y() -> None:
    """A whole run: every recorded u[k] equals Fr r - K x_hat[k|k] - Ki z[k], z[k] = sum_{j<k} (r - Cr x_hat[j|j])."""
    Qi, r = 5.0, 0.5
    raw = _scenario({"estimator": {"type": "kalman", "Q": [0, 0.01], "R": 1e-4},
                     "law": {"type": "lqr", "Q": [1, 0], "R": 0.1, "integral": True, "Qi": Qi}},
                    noise=0.01, reference=r)
    raw["plant"]["record_grid"] = "10 ms"  # the plant's true angle at the sample instants
    raw["record"].append("theta")
    s = netsim.run(raw).signals
    at = s["u_cmd"].notna().to_numpy()
    u = s["u_cmd"].to_numpy()[at]
    xh = s[["xh[0]", "xh[1]"]].to_numpy()[at]
    theta = s["theta"].to_numpy()[at]
    assert len(u) == 31  # jobs at 0, 10, ..., 300 ms
    Ad, Bd = _zoh(A_C, B_C, H)
    # design on the model augmented with z[k+1] = z[k] + r - Cr x[k]; u = -[K Ki] [x; z]
    Aa = np.block([[Ad, np.zeros((2, 1))], [-C_SERVO, np.eye(1)]])
    Ba = np.vstack([Bd, [[0.0]]])
    Ka, _ = _dlqr(Aa, Ba, np.diag([1.0, 0.0, Qi]), np.array([[0.1]]))
    K, Ki = Ka[:, :2], Ka[:, 2:]
    Nx, Nu = _equilibrium(Ad, Bd, C_SERVO)
    Fr = Nu + K @ Nx
    z = np.cumsum(np.concatenate([[0.0], r - xh[:-1] @ C_SERVO.ravel()]))  # z[k], errors of the estimate
    expected = (Fr * r).ravel() - xh @ K.ravel() - Ki.ravel() * z
    np.testing.assert_allclose(u, expected, rtol=1e-8, atol=1e-9)
    # the check tells the two conventions apart: integrating the output's error instead would not match
    z_y = np.cumsum(np.concatenate([[0.0], r - theta[:-1]]))
    assert np.max(np.abs((Fr * r).ravel() - xh @ K.ravel() - Ki.ravel() * z_y - u)) > 1e-3


def _box_qp(Hm: np.ndarray, g: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """argmin 1/2 U'HU + g'U on a box, as bounded least squares: ||L'U + L^-1 g||^2 with H = L L'."""
    from scipy.optimize import lsq_linear

    L = np.linalg.cholesky(Hm)
    res = lsq_linear(L.T, -np.linalg.solve(L, g), bounds=(lo, hi), method="bvls", tol=1e-14)
    return res.x


def _mpc_cost(U, x0, Ad, Bd, Q, R, P, xs, us):
    x, J = x0, 0.0
    for u in U:
        J += (x - xs) @ Q @ (x - xs) + R * (u - us) ** 2
        x = Ad @ x + Bd.ravel() * u
    return J + (x - xs) @ P @ (x - xs)


@pytest.mark.parametrize("x0", [[1.0, 0.0], [0.52, 0.001]])
def test_mpc_first_move_solves_the_stated_problem(x0: list[float]) -> None:
    """u_0 of min sum (x_k - x_s)'Q(x_k - x_s) + R (u_k - u_s)^2 + (x_N - x_s)'P(x_N - x_s), |u_k| <= 0.3, x_0 = x_hat,
    P from the DARE, (x_s, u_s) the equilibrium of r; the QP is formed here by evaluating the cost."""
    N, Q, R, r = 8, np.diag([1.0, 0.01]), 0.1, 0.5
    prog = _program(_scenario({"law": {"type": "mpc", "horizon": N, "Q": [1, 0.01], "R": R, "u_min": -0.3,
                                       "u_max": 0.3}}))
    Ad, Bd = _zoh(A_C, B_C, H)
    K, P = _dlqr(Ad, Bd, Q, np.array([[R]]))
    Nx, Nu = _equilibrium(Ad, Bd, C_SERVO)
    xs, us = (Nx * r).ravel(), float(Nu[0, 0] * r)
    x0 = np.array(x0)

    def J(U):
        return _mpc_cost(U, x0, Ad, Bd, Q, R, P, xs, us)

    E = np.eye(N)
    J0 = J(np.zeros(N))
    g = np.array([(J(E[i]) - J(-E[i])) / 2 for i in range(N)])  # exact for a quadratic
    Hm = np.array([[J(E[i] + E[j]) - J(E[i]) - J(E[j]) + J0 for j in range(N)] for i in range(N)])
    U = _box_qp(0.5 * (Hm + Hm.T), g, -0.3, 0.3)
    u = prog.law.step(x0, r)
    assert u[0] == pytest.approx(U[0], abs=1e-7)
    if x0[0] == 1.0:  # the limit is active: the case tests the constrained solve
        assert np.isclose(np.abs(U), 0.3, atol=1e-9).any() and abs(U[0] - (us - (K @ (x0 - xs))[0])) > 1e-3
    else:  # the unconstrained optimum is inside the box: it is the LQR law (terminal weight = DARE)
        assert np.all(np.abs(U) < 0.3)
        assert u[0] == pytest.approx(us - (K @ (x0 - xs))[0], abs=1e-9)


def test_mpc_falls_back_to_the_clipped_lqr_law_when_infeasible() -> None:
    prog = _program(_scenario({"law": {"type": "mpc", "horizon": 5, "Q": [1, 0.01], "R": 0.1, "u_min": -0.5,
                                       "u_max": 0.5, "x_max": [None, 1.0]}}, reference=None))
    Ad, Bd = _zoh(A_C, B_C, H)
    K, _ = _dlqr(Ad, Bd, np.diag([1.0, 0.01]), np.array([[0.1]]))
    x = np.array([0.0, 50.0])  # far above omega <= 1: no input in the box brings it back in one sample
    u = prog.law.step(x, 0.0)
    assert prog.law.fallbacks == 1
    assert u[0] == pytest.approx(float(np.clip(-(K @ x)[0], -0.5, 0.5)))


def test_pid_law_steps_as_the_stated_discretisation() -> None:
    Kp, Ti, Td, N, b = 2.0, 0.5, 0.05, 10.0, 0.7
    prog = _program(_scenario({"law": {"type": "pid", "K": Kp, "Ti": Ti, "Td": Td,
                                                                     "N": N, "b": b}}))
    ad = Td / (Td + N * H)
    bd, bi = Kp * N * ad, Kp * H / Ti
    I = D = 0.0
    y_old = None
    for y, r in ((0.1, 0.5), (0.2, 0.5), (0.35, 0.4)):
        D = ad * D - bd * (y - (y if y_old is None else y_old))
        u = Kp * (b * r - y) + I + D
        assert prog.law.step([y], r) == pytest.approx(u, rel=1e-12)
        I += bi * (r - y)
        y_old = y


# ----------------------------------------------------------------------------------------------- Qy
def test_qy_on_a_tf_plant_gives_the_gain_of_q_equal_c_qy_c() -> None:
    import control

    Qy, R = 3.0, 0.1
    tf_prog = _program(_scenario({"law": {"type": "lqr", "Qy": Qy, "R": R}}, plant=_servo_plant("tf")))
    real = control.tf2ss(SERVO_NUM, SERVO_DEN)
    A, B, C = (np.asarray(M, dtype=float) for M in (real.A, real.B, real.C))
    ss_plant = {"type": "ss", "A": A.tolist(), "B": B.tolist(), "C": C.tolist(), "inputs": ["u"],
                "outputs": ["theta"]}
    ss_prog = _program(_scenario({"law": {"type": "lqr", "Q": (C.T @ C * Qy).tolist(), "R": R}}, plant=ss_plant))
    np.testing.assert_allclose(tf_prog.law.K, ss_prog.law.K, rtol=1e-9)
    Ad, Bd = _zoh(A, B, H)
    K, _ = _dlqr(Ad, Bd, C.T * Qy @ C, np.array([[R]]))
    np.testing.assert_allclose(tf_prog.law.K, K, rtol=1e-8)
    # an output weight does not depend on the realisation: the physical [theta, omega] states give the same
    # closed-loop eigenvalues
    phys = _program(_scenario({"law": {"type": "lqr", "Qy": Qy, "R": R}}))
    Ap, Bp = _zoh(A_C, B_C, H)
    eig_tf = np.sort_complex(np.linalg.eigvals(Ad - Bd @ tf_prog.law.K))
    eig_phys = np.sort_complex(np.linalg.eigvals(Ap - Bp @ phys.law.K))
    np.testing.assert_allclose(eig_tf, eig_phys, rtol=1e-8)


def test_qy_adds_to_q_in_the_mpc_stage_and_terminal_weights() -> None:
    prog = _program(_scenario({"law": {"type": "mpc", "horizon": 5, "Q": [0.5, 0.01], "Qy": 2.0, "R": 0.1}}))
    Ad, Bd = _zoh(A_C, B_C, H)
    Qt = np.diag([0.5, 0.01]) + 2.0 * C_SERVO.T @ C_SERVO
    np.testing.assert_allclose(prog.law.Q, Qt, rtol=1e-14)
    K, P = _dlqr(Ad, Bd, Qt, np.array([[0.1]]))
    np.testing.assert_allclose(prog.law.P, P, rtol=1e-8)
    np.testing.assert_allclose(prog.law.K, K, rtol=1e-8)


@pytest.mark.parametrize(("law", "where", "words"), [
    ({"type": "lqr", "Qy": [1, 2], "R": 0.1}, f"{TASK}.law.Qy", "must have 1 entries"),
    ({"type": "mpc", "horizon": 5, "Qy": [[1, 0], [0, 1]], "R": 0.1}, f"{TASK}.law.Qy", "1x1"),
    ({"type": "lqr", "R": 0.1}, f"{TASK}.law", "Qy"),
])
def test_a_wrong_output_weight_is_refused_at_its_yaml_path(law: dict, where: str, words: str) -> None:
    with pytest.raises(ScenarioError) as err:
        load_scenario(_scenario({"law": law}, plant=_servo_plant("tf")))
    problems = [(p.path, p.message) for p in err.value.problems]
    assert any(p.startswith(where) and words in m for p, m in problems), problems


def test_qy_from_python_needs_c_and_a_weight() -> None:
    from netsim.control.lqr import LQR
    from netsim.errors import ConfigError

    Ad, Bd = _zoh(A_C, B_C, H)
    law = LQR(Ad, Bd, None, 0.1, Qy=[[4.0]], C=C_SERVO)
    np.testing.assert_allclose(law.K, _dlqr(Ad, Bd, 4.0 * C_SERVO.T @ C_SERVO, np.array([[0.1]]))[0], rtol=1e-8)
    with pytest.raises(ConfigError, match="Qy: an output weight needs the output matrix C"):
        LQR(Ad, Bd, None, 0.1, Qy=1.0)
    with pytest.raises(ConfigError, match="give a state weight Q, an output weight Qy"):
        LQR(Ad, Bd, None, 0.1)


# ----------------------------------------------------------------------------------------------- fuse_at
def _fuse_run(fuse_at: str, controller_offset: str) -> np.ndarray:
    """Sensor sampling at 10 k ms, the controller at 10 k ms + offset, an ideal network (no delay)."""
    raw = _scenario({"estimator": {"type": "kalman", "Q": [0, 0.01], "R": 1e-4, "history": 5},
                     "law": {"type": "lqr", "Q": [1, 0], "R": 0.1}, "fuse_at": fuse_at,
                     "measurements": [{"network": "net", "sender": "s", "tag": "y"}]}, noise=0.01)
    raw["nodes"]["c"]["tasks"][0]["offset"] = controller_offset
    raw["nodes"]["s"] = {"policy": "dm", "tasks": [{"name": "sample", "program": "sensor", "period": "10 ms",
                                    "params": {"channels": ["y_theta"], "network": "net", "to": "c", "tag": "y"}}]}
    raw["networks"] = {"net": {"type": "ideal", "nodes": ["s", "c"]}}
    s = netsim.run(raw).signals
    return s["u_cmd"].dropna().to_numpy()


def test_fuse_at_changes_nothing_for_a_sample_nearer_the_current_control_sample() -> None:
    # 4 ms before the controller's sample (< half a period): the nearest controller sample is the current one,
    # the sample index the message is fused at is the same under both settings
    np.testing.assert_array_equal(_fuse_run("sample_time", "4 ms"), _fuse_run("arrival", "4 ms"))
    # 6 ms before (> half a period): sample_time attributes it to the previous controller sample and the
    # Kalman filter re-filters from there; arrival fuses it as a measurement of the current one
    assert not np.allclose(_fuse_run("sample_time", "6 ms"), _fuse_run("arrival", "6 ms"))


# ----------------------------------------------------------------------------------------------- models
def test_pendulum_arm_inertia_is_taken_about_the_motor_axis_as_mr_lr2_over_12() -> None:
    from netsim.models.pendulum.model import PendulumParams, dynamics

    p = PendulumParams()
    Jr = 0.095 * 0.085**2 / 12  # arm: mr Lr^2 / 12, used as the inertia about the motor axis
    J0 = 0.024 * 0.129**2 / 3  # pendulum about its pivot: mp Lp^2 / 12 + mp (Lp / 2)^2
    assert p.Jr == pytest.approx(Jr, rel=1e-14) and p.J0 == pytest.approx(J0, rel=1e-14)
    # upright and at rest, 1 V: tau = km u / Rm; [Jr + mp Lr^2, mp l Lr; mp l Lr, J0] [th''; a''] = [tau; 0]
    tau = 0.042 / 8.4
    M = np.array([[Jr + 0.024 * 0.085**2, 0.024 * 0.0645 * 0.085], [0.024 * 0.0645 * 0.085, J0]])
    acc = np.linalg.solve(M, [tau, 0.0])
    dx = dynamics(0.0, np.zeros(4), [1.0], p)
    np.testing.assert_allclose(dx[[1, 3]], acc, rtol=1e-12)
    assert acc[1] < 0  # a positive arm acceleration tips the pendulum to negative alpha (reaction)


def test_two_wheel_cart_wheel_speeds_map_to_forward_speed_and_left_turn() -> None:
    from netsim.models.unicycle.model import HALF_WHEELBASE, WHEEL_RADIUS, arc, wheels_to_body

    r, a = WHEEL_RADIUS, HALF_WHEELBASE
    v, w = wheels_to_body(4.0, 6.0)  # rad/s, left then right
    assert v == pytest.approx(r / 2 * 10.0) and w == pytest.approx(r / (2 * a) * 2.0)
    assert w > 0  # the right wheel faster: the cart turns left (theta counter-clockwise)
    pose = arc(np.array([0.0, 0.0, 0.0]), v, w, 0.5)
    R = v / w  # exact circle of radius v / w around (0, R)
    np.testing.assert_allclose(pose, [R * math.sin(w * 0.5), R * (1 - math.cos(w * 0.5)), w * 0.5], rtol=1e-12)


# ----------------------------------------------------------------------------------------------- descriptions
def _models_in(tp, seen: set) -> list:
    from typing import get_args

    from pydantic import BaseModel

    out = []
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        if tp not in seen:
            seen.add(tp)
            out.append(tp)
            for f in tp.model_fields.values():
                out += _models_in(f.annotation, seen)
        return out
    for arg in get_args(tp):
        out += _models_in(arg, seen)
    return out


def _undescribed() -> list[str]:
    from netsim import registry
    from netsim.programs.feedback_design import part_params

    roots = []
    for kind in ("estimator", "controller"):
        for entry in registry.entries(kind):
            if entry.obj.__module__.startswith("netsim.") and not entry.obj.__module__.startswith("netsim.models"):  # the toolbox (models/ are studies, not toolbox)
                roots.append((f"{kind} {entry.name}", part_params(kind, entry.name)))
    roots.append(("program state_feedback", registry.lookup("program", "state_feedback").Params))
    missing = []
    for label, root in roots:
        for model in _models_in(root, set()):
            for name, field in model.model_fields.items():
                if not (field.description or "").strip():
                    where = label if model is root else f"{label} ({model.__name__})"
                    missing.append(f"{where}: {name}")
    return missing


def test_every_toolbox_parameter_has_a_description() -> None:
    missing = _undescribed()
    assert not missing, "parameters without a description:\n" + "\n".join(missing)
