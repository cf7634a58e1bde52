"""NUMRE: K(N) against a brute-force fast-rate Kalman run, correction and cascade prediction."""

import numpy as np
import pytest

from netsim.control import Numre, lifted_noise_cov
from netsim.errors import ConfigError

A = np.array([[1.0, 0.1, 0.0], [0.0, 0.9, 0.2], [0.0, 0.0, 0.95]])
B = np.array([[0.0], [0.1], [0.0]])
Bw = np.array([[0.0], [0.05], [1.0]])
C = np.array([[1.0, 0.0, 0.0]])
W = np.array([[0.3]])
V = np.array([[0.01]])


def _brute_force_gain(N, cycles=400):
    """Fast-rate Kalman filter: predict every period, correct every N periods, until the gain settles."""
    P = np.eye(3)
    Q = Bw @ W @ Bw.T
    K = None
    for _ in range(cycles):
        for _ in range(N):
            P = A @ P @ A.T + Q
        S = C @ P @ C.T + V
        K = P @ C.T @ np.linalg.inv(S)
        P = (np.eye(3) - K @ C) @ P
    return K


@pytest.mark.parametrize("N", [1, 2, 5, 9])
def test_gain_of_multiplicity_n_equals_brute_force_kalman_over_n_steps(N):
    f = Numre(A, B, C, Bw, W, V, h=10)
    assert f.gain(N) == pytest.approx(_brute_force_gain(N), rel=1e-7, abs=1e-10)


def test_gains_are_cached_per_multiplicity():
    f = Numre(A, B, C, Bw, W, V, h=10)
    assert f.gain(3) is f.gain(3)


def test_lifted_noise_cov_white_is_sum_of_propagated_covariances():
    We = lifted_noise_cov(A, Bw, W, 2)
    Q = Bw @ W @ Bw.T
    assert We == pytest.approx(Q + A @ Q @ A.T)  # c=1 term then c=0 term of eq (13), white w
    held = lifted_noise_cov(A, Bw, W, 2, form="held")
    S = Bw + A @ Bw
    assert held == pytest.approx(S @ W @ S.T)  # eq (13) as printed


def test_correction_and_cascade_prediction_follow_eqs_11_and_14():
    f = Numre(A, B, C, Bw, W, V, Cbar=np.array([[0.0, 0.0, 1.0]]), h=3)
    xp = np.array([1.0, 0.0, 0.5])
    xc = f.correct(xp, 2.0, 2)
    assert xc == pytest.approx(xp + f.gain(2)[:, 0] * (2.0 - 1.0))
    traj = f.predict(xc, [0.1, 0.2])
    assert traj[2] == pytest.approx(A @ (A @ xc + B[:, 0] * 0.1) + B[:, 0] * 0.2)
    assert f.outputs(traj[1]) == pytest.approx((traj[1][0], traj[1][2]))


def test_bad_inputs_are_reported():
    with pytest.raises(ConfigError, match="positive definite"):
        Numre(A, B, C, Bw, W, [[0.0]], h=2)
    with pytest.raises(ConfigError, match="horizon"):
        Numre(A, B, C, Bw, W, V, h=-1)
    assert not Numre(A, B, C, Bw, W, V, h=2).check_horizon(3)
