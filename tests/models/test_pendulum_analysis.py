"""models/pendulum/analysis.py: the pendulum loop's expected cost under delay from netsim.analysis.lqg, checked
against independent computations (an exact discrete loop written here, and the phase-margin estimate)."""

import math

import numpy as np
import pytest
from scipy.linalg import expm, solve_discrete_lyapunov

import netsim  # noqa: F401 - pins BLAS before numpy work
from netsim.models.pendulum.analysis import analytic_cost, controller_matrices, lqg_delay_margin
from netsim.models.pendulum.design import Q_LQR, R_LQR, delay_margin, delay_spectral_radius, designs
from netsim.models.pendulum.model import DISTURBANCE_HOLD, DISTURBANCE_STD

ESTIMATORS = ("fd_raw", "fd_lowpass", "luenberger", "kalman")


@pytest.fixture(scope="module")
def d():
    return designs()


@pytest.mark.parametrize("name", ESTIMATORS)
def test_stability_at_whole_sample_delays_equals_the_exact_discrete_loop(d, name):
    # With a delay of D whole periods the sampled loop is the discrete loop with u applied D samples late
    # (design.delay_spectral_radius, built independently); the second-moment operator's radius is its square.
    for steps in (1, 2, 4, 5, 6):
        rho2 = analytic_cost(name, d, steps * d.lin.h)["spectral_radius"]
        assert math.sqrt(rho2) == pytest.approx(delay_spectral_radius(name, d, steps), abs=1e-9), steps


@pytest.mark.parametrize("name", ["fd_raw", "kalman"])  # the report checks all four (delay.csv, test_pendulum_report)
def test_lqg_delay_margin_equals_phase_margin_over_crossover(d, name):
    # Each loop has one gain crossover, so a constant delay destabilises it exactly when w_c tau = PM: the two
    # independent computations (frequency response vs the spectral radius of the cost recursion) must agree.
    margin = lqg_delay_margin(name, d, step_s=0.002)
    assert margin == pytest.approx(delay_margin(name, d, n=4000)["margin_s"], abs=2e-6)


def test_stationary_cost_without_delay_equals_a_discrete_lyapunov_computation(d):
    # Kalman (current form) + LQR, zero delay: zeta[k] = [x[k], x_hat[k]],
    #   x[k+1] = A x - B K x_hat + w,   x_hat[k+1] = (I - L C)(A - B K) x_hat + L C (A x - B K x_hat + w) + L v,
    # w ~ N(0, W), W = int_0^h e^(A r) R1 e^(A' r) dr (Van Loan), v ~ N(0, Rn); cost per sample
    # tr(Q Sxx) + R K Shh K'.
    A, B, C, L, K = d.lin.Ad, d.lin.Bd, d.lin.C, d.K_kal, d.K_lqr
    Ac = d.lin.A
    R1 = d.lin.B @ d.lin.B.T * DISTURBANCE_STD**2 * DISTURBANCE_HOLD
    M = np.zeros((8, 8))
    M[:4, :4], M[:4, 4:], M[4:, 4:] = -Ac, R1, Ac.T
    E = expm(M * d.lin.h)
    W = E[4:, 4:].T @ E[:4, 4:]
    I = np.eye(4)
    Phi = np.block([[A, -B @ K], [L @ C @ A, (I - L @ C) @ (A - B @ K) - L @ C @ B @ K]])
    Gw = np.vstack([I, L @ C])
    Gv = np.vstack([np.zeros((4, 2)), L])
    S = solve_discrete_lyapunov(Phi, Gw @ W @ Gw.T + Gv @ d.Rn @ Gv.T)
    expected = np.trace(np.diag(Q_LQR) @ S[:4, :4]) + R_LQR * (K @ S[4:, 4:] @ K.T)[0, 0]
    assert analytic_cost("kalman", d, 0.0)["per_sample"] == pytest.approx(expected, rel=1e-6)


def test_delay_line_outputs_the_input_computed_steps_ago(d):
    # the undelayed controller's output u[k] for the same measurements, against the delayed one's output
    A0, B0, C0, D0 = controller_matrices("luenberger", d, 0)
    Ac, Bc, Cc, Dc = controller_matrices("luenberger", d, 3)
    rng = np.random.default_rng(1)
    x0, x3 = np.zeros(A0.shape[0]), np.zeros(Ac.shape[0])
    computed, out = [], []
    for _ in range(8):
        y = rng.normal(size=2)
        computed.append(float((C0 @ x0 + D0 @ y)[0]))
        out.append(float((Cc @ x3 + Dc @ y)[0]))
        x0, x3 = A0 @ x0 + B0 @ y, Ac @ x3 + Bc @ y
    assert out[3:] == pytest.approx(computed[:-3], abs=1e-12)
    assert out[:3] == [0.0, 0.0, 0.0]


def test_the_cost_grows_without_bound_towards_the_margin(d):
    m = lqg_delay_margin("luenberger", d)
    costs = [analytic_cost("luenberger", d, f * m)["per_sample"] for f in (0.2, 0.9, 0.99)]
    assert costs[0] < costs[1] < costs[2] and costs[2] > 10 * costs[0]
    assert analytic_cost("luenberger", d, 1.01 * m)["J"] == math.inf
