"""The shared interface: any estimator feeds any state-feedback law; PID behind step(y, r)."""

import numpy as np
import pytest
import scipy.linalg as sla

from netsim.control.baselines import FiniteDifferenceVelocity
from netsim.control.ekf import ExtendedKalmanFilter
from netsim.control.interface import ControlLaw, OutputFeedback, StateEstimator, sample_index
from netsim.control.kalman import KalmanFilter
from netsim.control.lqr import LQR, StateFeedback
from netsim.control.luenberger import LuenbergerObserver
from netsim.control.mpc import LinearMPC
from netsim.control.pid import PID

H = 0.01
_Ac = np.array([[0.0, 1.0], [0.0, -1.0]])
_Bc = np.array([[0.0], [1000.0]])
_M = sla.expm(np.block([[_Ac, _Bc], [np.zeros((1, 3))]]) * H)
A, B = _M[:2, :2], _M[:2, 2:]  # DC servo 1000/(s(s+1)) at 10 ms
C = np.array([[1.0, 0.0]])
Qw, Rv = np.diag([1e-8, 1e-4]), np.array([[1e-6]])


def estimators():
    return {
        "kalman": KalmanFilter(A, B, C, Qw, Rv),
        "kalman_ss": KalmanFilter(A, B, C, Qw, Rv, steady_state=True),
        "luenberger_pred": LuenbergerObserver(A, B, C, [0.5, 0.6], form="predictor"),
        "luenberger_curr": LuenbergerObserver(A, B, C, [0.5, 0.6], form="current"),
        "ekf": ExtendedKalmanFilter(
            lambda x, u: A @ x + B @ u, {"y": {"h": lambda x: C @ x, "R": Rv}}, Qw, np.zeros(2)
        ),
        "finite_difference": FiniteDifferenceVelocity(H, cutoff_hz=30.0),
    }


def laws():
    return {
        "lqr": LQR(A, B, np.diag([1.0, 1e-4]), 1.0, Cr=C),
        "lqr_integral": LQR(A, B, np.diag([1.0, 1e-4]), 1.0, Cr=C, integral=True, Qi=1e-4),
        "mpc": LinearMPC(A, B, np.diag([1.0, 1e-4]), 1e-3, 15, Cr=C, u_min=-0.05, u_max=0.05),
    }


def test_every_part_satisfies_its_protocol():
    for est in estimators().values():
        assert isinstance(est, StateEstimator)
    for law in laws().values():
        assert isinstance(law, ControlLaw)
    assert isinstance(PID(1.0).as_law(), ControlLaw)
    assert isinstance(OutputFeedback(KalmanFilter(A, B, C, Qw, Rv), StateFeedback(A, B, [[1.0, 0.0]])), ControlLaw)


@pytest.mark.parametrize("law_name", ["lqr", "lqr_integral", "mpc"])
@pytest.mark.parametrize("est_name", list(estimators()))
def test_any_estimator_feeds_any_state_feedback_law(est_name, law_name):
    loop = OutputFeedback(estimators()[est_name], laws()[law_name])
    rng = np.random.default_rng(1)
    x = np.zeros(2)
    for k in range(400):
        y = C @ x + 1e-3 * rng.standard_normal(1)
        u = loop.step(None if k % 10 == 9 else y, 0.5)  # every 10th measurement lost
        x = A @ x + B @ np.atleast_1d(u)
    assert abs(x[0] - 0.5) < 0.02, f"{est_name} + {law_name} ended at {x[0]:.4f}"


def test_output_feedback_is_correct_law_predict_in_that_order():
    kf_a, kf_b = KalmanFilter(A, B, C, Qw, Rv), KalmanFilter(A, B, C, Qw, Rv)
    law_a, law_b = LQR(A, B, np.eye(2), 1e-3, Cr=C), LQR(A, B, np.eye(2), 1e-3, Cr=C)
    loop = OutputFeedback(kf_a, law_a)
    for y in [0.1, 0.2, None, 0.25]:
        u = loop.step(None if y is None else [y], 1.0)
        if y is not None:
            kf_b.correct([y])
        u_b = law_b.step(kf_b.x_hat, 1.0)
        kf_b.predict(u_b)
        np.testing.assert_array_equal(u, u_b)
        np.testing.assert_array_equal(kf_a.x_hat, kf_b.x_hat)


def test_pid_law_gives_the_same_results_as_pid_step():
    a = PID(0.96, 0.12, 0.049, 10.0, 0.5, 0.006, u_min=-1, u_max=1)
    b = PID(0.96, 0.12, 0.049, 10.0, 0.5, 0.006, u_min=-1, u_max=1)
    law = b.as_law()
    rng = np.random.default_rng(3)
    for _ in range(100):
        y, r = rng.normal(), rng.normal()
        assert law.step(np.array([y]), r) == a.step(r, y)
    law.reset()
    assert b.I == 0.0 and b.y_old is None


def test_sample_index_maps_sample_times_to_the_nearest_sample():
    assert sample_index(30_000_000, 10_000_000) == 3
    assert sample_index(34_999_999, 10_000_000) == 3
    assert sample_index(35_000_000, 10_000_000) == 4  # half-way rounds up
    assert sample_index(1_005_000_000, 10_000_000, start_ns=1_000_000_000) == 1
    with pytest.raises(ValueError, match="before the first sample"):
        sample_index(0, 10_000_000, start_ns=1_000_000_000)
