"""The ``ekf`` estimator: an extended Kalman filter on the plant's own nonlinear model, named in YAML.

Independent references: the linear Kalman filter on the exact (matrix-exponential) discretisation of a linear
model written as f and h, and a scipy ``solve_ivp`` truth of a swinging pendulum.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.integrate import solve_ivp

import netsim
from netsim.control.kalman import KalmanFilter
from netsim.control.model_ekf import ModelEKF, rk4_transition
from netsim.errors import ConfigError, SimulationError
from netsim.scenario import check_scenario
from netsim.scenario.problems import ScenarioError
from netsim.scenario.safe_yaml import load_file

H = 0.01
A = np.array([[0.0, 1.0], [-4.0, -0.4]])  # a lightly damped oscillator
B = np.array([[0.0], [1.0]])
Q = np.diag([1e-6, 1e-4])
R = np.array([[1e-4]])


def linear_f(t, x, u, p):
    return A @ x + B @ u


def linear_h(t, x, u, p):
    return np.array([x[0], x[1]])


def test_on_a_linear_model_the_ekf_equals_the_kalman_filter_on_the_exact_discretisation():
    M = np.zeros((3, 3))
    M[:2, :2], M[:2, 2:] = A * H, B * H
    E = sla.expm(M)  # exact ZOH: an independent discretisation
    kf = KalmanFilter(E[:2, :2], E[:2, 2:], np.array([[1.0, 0.0]]), Q, R, x0=[0.2, 0.0])
    ekf = ModelEKF(linear_f, linear_h, None, 2, 1, [0], H, Q, R, x0=[0.2, 0.0], substeps=20)
    rng = np.random.default_rng(2)
    for k in range(200):
        y = rng.normal(0.0, 0.3, 1)
        if k % 7:
            kf.correct(y)
            ekf.correct(y)
        u = [np.cos(0.03 * k)]
        kf.predict(u)
        ekf.predict(u)
    # RK4 with 20 steps of 0.5 ms: local error ~ (4 * 5e-4)^5 / 120 per step, far below these tolerances
    np.testing.assert_allclose(ekf.x_hat, kf.x_hat, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(ekf.P, kf.P, rtol=1e-7, atol=1e-12)


def test_rk4_transition_is_fourth_order():
    phi1 = rk4_transition(linear_f, None, 0.2, 1)
    phi2 = rk4_transition(linear_f, None, 0.2, 2)
    x, u = np.array([1.0, 0.0]), np.zeros(1)
    exact = sla.expm(A * 0.2) @ x
    e1, e2 = np.linalg.norm(phi1(x, u) - exact), np.linalg.norm(phi2(x, u) - exact)
    assert 2**4 * 0.7 < e1 / e2 < 2**5 * 1.3  # halving the step divides the error by about 2^4 (global order 4)


G_L, DAMP = 9.81 / 0.5, 0.1  # a 0.5 m pendulum, light damping


def pendulum_f(t, x, u, p):
    return np.array([x[1], -G_L * np.sin(x[0]) - DAMP * x[1] + u[0]])


def pendulum_h(t, x, u, p):
    return np.array([x[0]])


def test_on_a_large_swing_the_ekf_tracks_the_velocity_the_linearised_kalman_filter_misses():
    # truth: a 1.4 rad swing, angle measured with 0.01 rad noise every 10 ms, by scipy's solve_ivp (tight tolerances)
    steps = 300
    t = np.arange(steps) * H
    sol = solve_ivp(lambda tt, x: pendulum_f(tt, x, [0.0], None), (0, t[-1]), [1.4, 0.0], t_eval=t,
                    rtol=1e-10, atol=1e-12)
    rng = np.random.default_rng(4)
    ys = sol.y[0] + rng.normal(0.0, 0.01, steps)
    Rm = np.array([[1e-4]])
    Qm = np.diag([1e-8, 1e-6])
    ekf = ModelEKF(pendulum_f, pendulum_h, None, 2, 1, [0], H, Qm, Rm, x0=[1.3, 0.0], P0=np.diag([0.01, 0.1]))
    A_lin = np.array([[0.0, 1.0], [-G_L, -DAMP]])  # the linearisation at the bottom
    Ad = sla.expm(A_lin * H)
    kf = KalmanFilter(Ad, np.zeros((2, 1)), np.array([[1.0, 0.0]]), Qm, Rm, x0=[1.3, 0.0], P0=np.diag([0.01, 0.1]))
    err_ekf, err_kf = [], []
    for k in range(steps):
        ekf.correct(ys[k:k + 1])
        kf.correct(ys[k:k + 1])
        err_ekf.append(ekf.x_hat[1] - sol.y[1, k])
        err_kf.append(kf.x_hat[1] - sol.y[1, k])
        ekf.predict([0.0])
        kf.predict([0.0])
    rms_ekf = np.sqrt(np.mean(np.square(err_ekf[100:])))
    rms_kf = np.sqrt(np.mean(np.square(err_kf[100:])))
    # measured ordering (this test's own runs): the EKF's velocity error is several times smaller
    assert rms_ekf < rms_kf / 3, (rms_ekf, rms_kf)


def test_a_model_that_fails_is_named():
    def bad_h(t, x, u, p):
        return np.array([x[0], x[1], 0.0])[:1] / 0.0 if x[0] > 5 else np.array([x[0]])

    with pytest.raises(ConfigError, match="the model's f raised ZeroDivisionError"):
        ModelEKF(lambda t, x, u, p: 1 / 0, pendulum_h, None, 2, 1, [0], H, Qm_ := np.eye(2), 1.0)
    ekf = ModelEKF(pendulum_f, bad_h, None, 2, 1, [0], H, np.eye(2) * 1e-6, 1e-4, x0=[0.0, 0.0])
    ekf.x = np.array([6.0, 0.0])
    with np.errstate(divide="ignore", invalid="ignore"), pytest.raises(SimulationError, match="NaN or infinite"):
        ekf.correct([6.0])
    assert Qm_.shape == (2, 2)


# --- from YAML -------------------------------------------------------------------------------------------------
PENDULUM = Path(__file__).resolve().parents[2] / "scenarios" / "pendulum_lqr.yaml"


def _pendulum_with(estimator: dict) -> dict:
    raw = copy.deepcopy(load_file(PENDULUM)[0])
    raw["duration"] = "1.5 s"
    raw["nodes"]["rip"]["tasks"][0]["params"]["estimator"] = estimator
    return raw


def test_the_pendulum_balances_with_an_ekf_on_its_own_nonlinear_model():
    # Q: the input disturbance (0.05 V held 1 ms) is small; R: the encoder quantisation variance (8.86e-4 rad)^2
    ekf = {"type": "ekf", "Q": [1e-8, 1e-4, 1e-8, 1e-4], "R": 7.8e-7, "P0": [0.01, 0.1, 0.1, 1.0]}
    result = netsim.run(_pendulum_with(ekf))
    m = result.metrics
    # two encoders, each fused on its own, at the 301 samples of 0 to 1.5 s (both ends included)
    assert m["control.rip.control.fused"] == 602
    s = result.signals
    late = s[s["time_s"] > 0.5]
    assert float(np.abs(late["alpha"]).max()) < 0.05  # balanced: upright within 3 degrees after 0.5 s


def test_ekf_on_a_plant_without_a_nonlinear_model_is_refused_by_validate_and_run_with_its_path():
    raw = {
        "name": "servo_ekf", "duration": "0.1 s",
        "plant": {"type": "ss", "A": A.tolist(), "B": B.ravel().tolist(), "C": [[1, 0]], "inputs": ["u"],
                  "outputs": ["y"]},
        "io": {"y": {"type": "adc", "output": "y"}, "u": {"type": "dac", "input": "u"}},
        "nodes": {"c": {"policy": "dm", "tasks": [{"name": "loop", "program": "state_feedback", "period": "10 ms", "params": {
            "measurements": [{"channel": "y"}], "estimator": {"type": "ekf", "Q": [0, 0.01], "R": 1e-6},
            "law": {"type": "lqr", "Q": [1, 0], "R": 0.1}, "output_channel": "u"}}]}},
    }
    problems = [p for p in check_scenario(raw) if p.is_error]
    assert len(problems) == 1
    assert problems[0].path == "nodes.c.tasks[0].params.estimator" and "use 'kalman'" in problems[0].message
    with pytest.raises(ScenarioError, match="use 'kalman'"):
        netsim.run(raw)
