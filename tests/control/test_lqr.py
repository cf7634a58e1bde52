"""LQR and state feedback: gain against the Riccati equation, feed-forward, integral action, tracking."""

import numpy as np
import pytest
import scipy.linalg as sla

from netsim.control.lqr import LQR, StateFeedback, trajectory_feedforward
from netsim.errors import ConfigError

H = 0.02
# DC servo 1000/(s(s+1)) sampled at 20 ms (ZOH), exact matrix exponential
_Ac = np.array([[0.0, 1.0], [0.0, -1.0]])
_Bc = np.array([[0.0], [1000.0]])
_M = sla.expm(np.block([[_Ac, _Bc], [np.zeros((1, 3))]]) * H)
A, B = _M[:2, :2], _M[:2, 2:]
C = np.array([[1.0, 0.0]])
Q = np.diag([1.0, 0.01])
R = np.array([[1e-3]])


def test_gain_equals_dlqr_and_the_riccati_equation():
    import control

    lqr = LQR(A, B, Q, R)
    K, S, _ = control.dlqr(A, B, Q, R)
    np.testing.assert_allclose(lqr.K, K, rtol=1e-12)
    # independent: scipy's DARE solution and K = (R + B'PB)^-1 B'PA
    P = sla.solve_discrete_are(A, B, Q, R)
    np.testing.assert_allclose(lqr.P, P, rtol=1e-9)
    np.testing.assert_allclose(lqr.K, np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A), rtol=1e-9)


def test_output_reference_is_reached_with_feedforward():
    lqr = LQR(A, B, Q, R, Cr=C)
    x = np.zeros(2)
    for _ in range(400):
        x = A @ x + B @ lqr.step(x, 0.7)
    np.testing.assert_allclose(C @ x, [0.7], atol=1e-10)
    lqr0 = LQR(A, B, Q, R, Cr=C, feedforward=False)
    np.testing.assert_allclose(lqr0.step(np.array([0.3, 0.1]), 5.0), -lqr0.K @ np.array([0.3, 0.1]), rtol=1e-15)


def test_integral_action_removes_a_constant_input_disturbance():
    d = np.array([0.05])  # constant load on the input
    errs = {}
    for integral in (False, True):
        lqr = LQR(A, B, Q, R, Cr=C, integral=integral, Qi=[[0.5]])
        x = np.zeros(2)
        for _ in range(3000):
            x = A @ x + B @ (lqr.step(x, 1.0) + d)
        errs[integral] = (C @ x)[0] - 1.0
    # without integral action: the servo integrates, so at rest K1 (r - y) + d = 0 (Nx = [1, 0], Nu = 0):
    # y - r = d / K1
    k1 = LQR(A, B, Q, R, Cr=C).K[0, 0]
    assert errs[False] == pytest.approx(d[0] / k1, rel=1e-6)
    assert abs(errs[True]) < 1e-9


def test_integral_action_does_not_wind_up_when_saturated():
    lqr = LQR(A, B, Q, R, Cr=C, integral=True, u_max=0.01, u_min=-0.01)
    assert lqr.Ki[0, 0] < 0  # u = ... - Ki z: a positive error raises u
    x = np.zeros(2)
    frozen = 0
    for _ in range(600):
        z = lqr.z.copy()
        e = 1.0 - (C @ x)[0]
        u = lqr.step(x, 1.0)
        assert -0.01 <= u[0] <= 0.01
        if u[0] == 0.01 and e > 0:  # at the upper limit, integrating would push further up
            np.testing.assert_array_equal(lqr.z, z)
            frozen += 1
        x = A @ x + B @ u
    assert frozen > 5  # the start saturates
    assert abs((C @ x)[0] - 1.0) < 1e-6


def test_feasible_trajectory_is_tracked_exactly_and_errors_decay_with_a_minus_bk():
    rng = np.random.default_rng(4)
    U = rng.normal(size=(50, 1)) * 0.01
    X = [np.array([0.2, -0.1])]
    for u in U:
        X.append(A @ X[-1] + B @ u)
    X = np.array(X)
    Uff = trajectory_feedforward(A, B, X)
    np.testing.assert_allclose(Uff, U, atol=1e-12)
    lqr = LQR(A, B, Q, R)
    e0 = np.array([0.05, 0.3])
    x = X[0] + e0
    Acl = A - B @ lqr.K
    for k in range(50):
        np.testing.assert_allclose(x - X[k], np.linalg.matrix_power(Acl, k) @ e0, atol=1e-12)
        x = A @ x + B @ lqr.step(x, np.concatenate([X[k], Uff[k]]))


def test_state_feedback_with_a_given_gain():
    K = np.array([[10.0, 0.5]])
    sf = StateFeedback(A, B, K, u_min=-1, u_max=1)
    np.testing.assert_allclose(sf.step([0.01, 0.0], np.zeros(2)), [-0.1])
    np.testing.assert_allclose(sf.step([1.0, 0.0], np.zeros(2)), [-1.0])  # saturated
    np.testing.assert_allclose(sf.step([0.01, 0.0], 0.0), [-0.1])  # one number: regulation to 0


def test_unstabilisable_pair_names_the_mode():
    A2 = np.diag([1.1, 0.5])
    B2 = np.array([[0.0], [1.0]])
    with pytest.raises(ConfigError, match=r"not stabilisable: the mode\(s\) at eigenvalue 1\.1"):
        LQR(A2, B2, np.eye(2), 1.0)


def test_integrator_on_a_plant_with_a_zero_at_one_is_refused():
    # y = x2 - x1 with x1 and x2 both integrating the same input: the transfer function is 0, zero at z = 1
    A2 = np.eye(2) * 0.5
    B2 = np.array([[1.0], [1.0]])
    with pytest.raises(ConfigError, match=r"integral: the pair .* augmented .* not stabilisable"):
        LQR(A2, B2, np.eye(2), 1.0, Cr=[[1.0, -1.0]], integral=True)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        (dict(R=[[0.0]]), "R must be positive definite"),
        (dict(Q=np.diag([1.0, -1.0])), "Q must be positive semidefinite"),
        (dict(B=[[1.0, 0.0, 0.0]]), "B must be 2xany"),
        (dict(A=np.ones((2, 3))), "A must be square"),
        (dict(Cr=[[1.0, 0.0, 0.0]]), "Cr must be anyx2"),
        (dict(integral=True), "integral action needs Cr"),
        (dict(u_min=1.0, u_max=0.0), "u_min"),
    ],
)
def test_bad_input_is_refused_naming_the_parameter(kw, match):
    args = dict(A=A, B=B, Q=Q, R=R)
    for k in list(kw):
        if k in args:
            args[k] = kw.pop(k)
    with pytest.raises(ConfigError, match=match):
        LQR(args["A"], args["B"], args["Q"], args["R"], **kw)
