"""Process noise: the exact (Van Loan) discrete covariance and its use in propagation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad_vec
from scipy.linalg import expm

from netsim.env import SimEnv
from netsim.plant import LTIPlant
from netsim.plant.lti import van_loan, zoh_transition
from netsim.timebase import MS, S


def _qd_by_quadrature(A: np.ndarray, Qc: np.ndarray, h: float) -> np.ndarray:
    """Independent reference: Qd = int_0^h e^{As} Qc e^{A's} ds by adaptive quadrature."""
    val, _ = quad_vec(lambda s: expm(A * s) @ Qc @ expm(A.T * s), 0.0, h, epsabs=1e-14, epsrel=1e-12)
    return val


@pytest.mark.parametrize("h", [1e-3, 0.05, 2.0])
def test_van_loan_matches_quadrature_including_long_steps(h):
    # h = 2 s with poles up to 50 rad/s (|A| h ~ 100) exercises the scaled-and-doubled path.
    A = np.array([[0.0, 1.0, 0.0], [-4.0, -0.4, 1.0], [0.0, 0.0, -50.0]])
    B = np.array([[0.0], [1.0], [0.5]])
    Qc = np.diag([0.0, 0.3, 2.0])
    Ad, Bd, Qd = van_loan(A, B, Qc, h)
    Ad_ref, Bd_ref = zoh_transition(A, B, h)
    np.testing.assert_allclose(Ad, Ad_ref, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(Bd, Bd_ref, rtol=1e-10, atol=1e-13)
    ref = _qd_by_quadrature(A, Qc, h)
    np.testing.assert_allclose(Qd, ref, rtol=1e-8, atol=1e-12 * np.abs(ref).max())


def test_sample_covariance_of_propagated_steps_matches_van_loan():
    A = np.array([[0.0, 1.0], [-25.0, -1.0]])
    Qc = np.array([[0.1, 0.0], [0.0, 2.0]])
    h = 10 * MS
    env = SimEnv(seed=42)
    plant = LTIPlant(A, [0.0, 1.0], [1.0, 0.0], None, process_noise=Qc, name="osc")
    plant.bind(env)
    plant.set_input(0, 0.7, 0)
    N = 100_000
    Ad, Bd = zoh_transition(A, np.array([[0.0], [1.0]]), h / S)  # independent of the plant's cache
    xs = np.empty((N + 1, 2))
    xs[0] = plant.state(0)
    for k in range(1, N + 1):
        plant.advance_to(k * h)
        xs[k] = plant.state()
    w = xs[1:] - xs[:-1] @ Ad.T - 0.7 * Bd[:, 0]  # the noise added in each step
    S_hat = w.T @ w / N  # the noise has zero mean: no mean subtracted
    Sigma = _qd_by_quadrature(A, Qc, h / S)
    # Each entry of a Gaussian sample covariance has variance (Sigma_ij^2 + Sigma_ii Sigma_jj) / N; we
    # accept 5 standard deviations (a false alarm probability below 1e-5 for the three entries).
    tol = 5.0 * np.sqrt((Sigma**2 + np.outer(np.diag(Sigma), np.diag(Sigma))) / N)
    assert np.all(np.abs(S_hat - Sigma) <= tol), (S_hat, Sigma, tol)
    assert np.abs(w.mean(axis=0)).max() < 5.0 * np.sqrt(np.diag(Sigma).max() / N)


def test_noise_is_reproducible_from_the_seed_and_named_stream():
    def run(seed: int) -> np.ndarray:
        env = SimEnv(seed=seed)
        plant = LTIPlant([[-1.0]], [[1.0]], [[1.0]], None, process_noise=[1.0], name="p")
        plant.bind(env)
        return np.array([plant.output(k * MS)[0] for k in range(1, 50)])

    np.testing.assert_array_equal(run(1), run(1))
    assert not np.array_equal(run(1), run(2))


def test_noisy_continuous_disturbance_model_has_its_stationary_variance():
    # d = xd, xd' = -a xd + w with intensity q: stationary variance q / (2a). The plant x' = 0*x + 0*d only
    # carries it; we read xd from the augmented state at spaced instants (nearly independent samples).
    from netsim.plant import LTIDisturbance

    a, q = 50.0, 3.0
    env = SimEnv(seed=7)
    plant = LTIPlant([[-1.0]], [[0.0]], [[1.0]], None, name="p")
    plant.add_disturbance(0, LTIDisturbance([[-a]], [1.0], [1.0], noise_cov=q))
    plant.bind(env)
    N = 20_000
    samples = np.empty(N)
    for k in range(1, N + 1):
        plant.advance_to(k * 100 * MS)  # 100 ms = 5 time constants apart
        samples[k - 1] = plant.augmented_state[1]
    var = q / (2 * a)
    # sample variance of N independent Gaussians has relative standard deviation sqrt(2/N) = 1 %; 5 sigma.
    assert samples.var() == pytest.approx(var, rel=5 * np.sqrt(2 / N))
