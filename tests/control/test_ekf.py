"""Extended Kalman filter: equals the linear Kalman filter on a linear model; several sources; user errors."""

import numpy as np
import pytest

from netsim.control.ekf import ExtendedKalmanFilter, MeasurementSource, numerical_jacobian
from netsim.control.kalman import KalmanFilter
from netsim.errors import ConfigError, SimulationError

H = 0.05
A = np.array([[1.0, H, 0.0], [0.0, 1.0, H], [0.0, -0.3, 0.8]])
B = np.array([[0.0], [0.0], [H]])
C = np.array([[1.0, 0.0, 0.0]])
Cv = np.array([[0.0, 1.0, 0.0]])
Q = np.diag([1e-5, 1e-4, 1e-3])
R = np.array([[0.02]])
Rv = np.array([[0.05]])


def f_lin(x, u):
    return A @ x + B @ u


def test_numerical_jacobian_of_a_linear_map_is_its_matrix():
    x = np.array([3.0, -200.0, 0.01])
    np.testing.assert_allclose(numerical_jacobian(lambda z: A @ z, x, 3), A, atol=1e-9)


@pytest.mark.parametrize("given_jacobians", [False, True])
def test_ekf_on_a_linear_model_equals_the_kalman_filter(given_jacobians):
    rng = np.random.default_rng(7)
    kw = dict(F=lambda x, u: A) if given_jacobians else {}
    src = MeasurementSource(lambda x: C @ x, R, (lambda x: C) if given_jacobians else None)
    ekf = ExtendedKalmanFilter(f_lin, {"pos": src}, Q, x0=[0.1, 0.0, -0.2], P0=np.eye(3), **kw)
    kf = KalmanFilter(A, B, C, Q, R, x0=[0.1, 0.0, -0.2], P0=np.eye(3))
    tol = 1e-12 if given_jacobians else 1e-8  # finite differences of a linear map: rounding only
    for k in range(150):
        if k % 7 != 3:  # some samples without measurement: prediction only
            y = rng.normal(size=1)
            assert ekf.correct(y) is True
            kf.correct(y)
        np.testing.assert_allclose(ekf.x_hat, kf.x_hat, rtol=tol, atol=tol)
        np.testing.assert_allclose(ekf.P, kf.P, rtol=tol, atol=tol)
        u = rng.normal(size=1)
        ekf.predict(u)
        kf.predict(u)


def test_two_sources_at_one_sample_equal_the_joint_update():
    # sequential updates with independent noises equal one update with the stacked measurement (linear case)
    ekf = ExtendedKalmanFilter(
        f_lin, {"pos": {"h": lambda x: C @ x, "R": R}, "vel": {"h": lambda x: Cv @ x, "R": Rv}}, Q, x0=np.zeros(3)
    )
    P = np.eye(3)
    y = np.array([0.4, -0.3])
    ekf.correct(y[:1], "pos")
    ekf.correct(y[1:], "vel")
    Cs = np.vstack([C, Cv])
    Rs = np.diag([R[0, 0], Rv[0, 0]])
    K = P @ Cs.T @ np.linalg.inv(Cs @ P @ Cs.T + Rs)
    np.testing.assert_allclose(ekf.x_hat, K @ y, atol=1e-8)
    np.testing.assert_allclose(ekf.P, P - K @ Cs @ P, atol=1e-8)


def test_sources_with_their_own_rates_and_absences():
    # position at every sample, velocity every 5th, one velocity lost: the EKF equals a KF that switches C
    rng = np.random.default_rng(11)
    ekf = ExtendedKalmanFilter(f_lin, {"pos": {"h": lambda x: C @ x, "R": R}, "vel": {"h": lambda x: Cv @ x, "R": Rv}},
                               Q, x0=np.zeros(3))  # fmt: skip
    x, P = np.zeros(3), np.eye(3)
    for k in range(60):
        yp, yv = rng.normal(size=1), rng.normal(size=1)
        ekf.correct(yp, "pos")
        assert ekf.correct(yp, "pos") is False  # never fused twice
        for Cm, Rm, y in [(C, R, yp)] + ([(Cv, Rv, yv)] if k % 5 == 0 and k != 20 else []):
            K = P @ Cm.T @ np.linalg.inv(Cm @ P @ Cm.T + Rm)
            x, P = x + K @ (y - Cm @ x), (np.eye(3) - K @ Cm) @ P
        if k % 5 == 0 and k != 20:
            ekf.correct(yv, "vel")
        np.testing.assert_allclose(ekf.x_hat, x, atol=1e-7)
        ekf.predict([0.0])
        x, P = A @ x, A @ P @ A.T + Q
    assert ekf.duplicates == 60


def test_nonlinear_pendulum_estimate_converges():
    # pendulum, angle measured through sin: the EKF tracks the true state from a wrong start
    g_l, h = 9.81, 0.01

    def f(x, u):
        return np.array([x[0] + h * x[1], x[1] + h * (-g_l * np.sin(x[0]) - 0.2 * x[1] + u[0])])

    ekf = ExtendedKalmanFilter(f, {"s": {"h": lambda x: np.array([np.sin(x[0])]), "R": 1e-4}},
                               np.diag([1e-8, 1e-6]), x0=[0.0, 0.0], P0=np.eye(2))  # fmt: skip
    rng = np.random.default_rng(2)
    x = np.array([0.5, 0.0])
    for _ in range(1500):
        ekf.correct(np.sin(x[0]) + 1e-2 * rng.standard_normal())
        ekf.predict([0.0])
        x = f(x, [0.0])
    # the pendulum has decayed to about 0.5 e^{-0.1 t}, t = 15 s: amplitude 0.11; the estimate within a few %
    assert abs(ekf.x_hat[0] - x[0]) < 0.01
    assert abs(ekf.x_hat[1] - x[1]) < 0.03


def test_user_function_errors_at_construction_name_the_function():
    src = {"pos": {"h": lambda x: C @ x, "R": R}}

    def boom(x, u):
        raise ZeroDivisionError("boom")

    with pytest.raises(ConfigError, match=r"^f raised ZeroDivisionError: boom \(at x0 and u = 0\)"):
        ExtendedKalmanFilter(boom, src, Q, x0=np.zeros(3))
    with pytest.raises(ConfigError, match=r"f must return 3 values, returned shape \(2,\)"):
        ExtendedKalmanFilter(lambda x, u: x[:2], src, Q, x0=np.zeros(3))
    with pytest.raises(ConfigError, match=r"sources\.pos\.H must return 1x3 values"):
        ExtendedKalmanFilter(
            f_lin, {"pos": {"h": lambda x: C @ x, "R": R, "H": lambda x: np.eye(3)}}, Q, x0=np.zeros(3)
        )
    with pytest.raises(ConfigError, match=r"sources\.pos\.R must be positive definite"):
        ExtendedKalmanFilter(f_lin, {"pos": {"h": lambda x: C @ x, "R": 0.0}}, Q, x0=np.zeros(3))
    with pytest.raises(ConfigError, match=r"sources\.pos: unknown key\(s\) \['r'\]"):
        ExtendedKalmanFilter(f_lin, {"pos": {"h": lambda x: C @ x, "r": 1.0}}, Q, x0=np.zeros(3))
    with pytest.raises(ConfigError, match=r"sources\.pos\.h returned NaN"):
        ExtendedKalmanFilter(f_lin, {"pos": {"h": lambda x: np.array([np.nan]), "R": R}}, Q, x0=np.zeros(3))


def test_user_function_errors_during_a_run_name_the_function_and_sample():
    def h(x):
        if abs(x[0]) > 1.0:
            raise ValueError("out of the sensor's range")
        return C @ x

    ekf = ExtendedKalmanFilter(f_lin, {"pos": {"h": h, "R": R}}, Q, x0=np.zeros(3))
    ekf.correct([0.0])
    ekf.predict([0.0])
    ekf.x = np.array([2.0, 0.0, 0.0])
    with pytest.raises(
        SimulationError, match=r"sources\.pos\.h raised ValueError: out of the sensor's range \(at sample 1\)"
    ):
        ekf.correct([0.0])
    with pytest.raises(SimulationError, match="unknown measurement source 'gps'"):
        ekf.correct([0.0], "gps")
