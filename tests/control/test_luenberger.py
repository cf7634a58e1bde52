"""Luenberger observer: the error eigenvalues of both forms equal the requested poles.

The error matrix is measured, not read from the object: the observer is run one sample on the true plant
started at each unit vector (estimate zero, no input), and the columns of the map error[0] -> error[1] are
the measured errors. Its eigenvalues must equal the requested poles.
"""

import numpy as np
import pytest

from netsim.control.luenberger import LuenbergerObserver
from netsim.errors import ConfigError

# a 3-state plant, one output (acker) and two outputs (place)
A3 = np.array([[1.0, 0.1, 0.0], [0.0, 0.95, 0.1], [0.0, -0.2, 0.9]])
B3 = np.array([[0.0], [0.0], [0.1]])
C_one = np.array([[1.0, 0.0, 0.0]])
C_two = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def measured_error_matrix(obs: LuenbergerObserver) -> np.ndarray:
    """Columns: the error after one sample when the error before it is a unit vector.

    Predictor form: error of x_hat (prior = the estimate). Current form: error of the prediction x_bar
    (x - x_bar propagates with A (I - L C), similar to (I - L C) A: same eigenvalues).
    """
    n = obs.n
    M = np.zeros((n, n))
    for i in range(n):
        x = np.eye(n)[i]
        obs.reset(x0=np.zeros(n))
        obs.correct(obs.C @ x)
        obs.predict(np.zeros(obs.m))
        x_next = A3 @ x
        M[:, i] = x_next - obs.x_hat
    return M


@pytest.mark.parametrize("form", ["predictor", "current"])
@pytest.mark.parametrize(
    ("C", "poles"),
    [
        (C_one, [0.5, 0.6, 0.7]),
        (C_one, [0.3 + 0.2j, 0.3 - 0.2j, 0.1]),
        (C_one, [0.4, 0.4, 0.4]),  # repeated: acker handles it for one output
        (C_two, [0.2, 0.5 + 0.1j, 0.5 - 0.1j]),
    ],
)
def test_error_eigenvalues_equal_requested_poles(form, C, poles):
    obs = LuenbergerObserver(A3, B3, C, poles, form=form)
    M = measured_error_matrix(obs)
    got = np.sort_complex(np.linalg.eigvals(M))
    # triple poles are sensitive (a perturbation eps moves them by eps^(1/3)): looser tolerance there
    tol = 1e-4 if len(set(poles)) == 1 else 1e-8
    np.testing.assert_allclose(got, np.sort_complex(np.array(poles, complex)), atol=tol)
    np.testing.assert_allclose(M, A3 @ (np.eye(3) - obs.L @ C) if form == "current" else obs.error_matrix, atol=1e-12)


def test_predictor_uses_the_previous_measurement_and_current_form_this_one():
    pred = LuenbergerObserver(A3, B3, C_one, [0.5, 0.6, 0.7], form="predictor")
    curr = LuenbergerObserver(A3, B3, C_one, [0.5, 0.6, 0.7], form="current")
    pred.correct([2.0])
    curr.correct([2.0])
    np.testing.assert_array_equal(pred.x_hat, np.zeros(3))  # y[k] only enters the next prediction
    np.testing.assert_allclose(curr.x_hat, curr.L @ np.array([2.0]))  # x_bar = 0 corrected by L y
    pred.predict([0.0])
    np.testing.assert_allclose(pred.x_hat, pred.L @ np.array([2.0]))


def test_estimate_converges_on_a_driven_plant():
    obs = LuenbergerObserver(A3, B3, C_one, [0.3, 0.4, 0.5], form="current", x0=[1.0, -1.0, 0.5])
    x = np.zeros(3)
    for k in range(80):
        u = np.array([np.cos(0.3 * k)])
        obs.correct(C_one @ x)
        err = np.linalg.norm(x - obs.x_hat)
        obs.predict(u)
        x = A3 @ x + B3 @ u
    # slowest pole 0.5: the error falls like 0.5^k (about 1e-24 at k = 79, times a modest transient gain)
    assert err < 1e-9


@pytest.mark.parametrize(
    ("poles", "match"),
    [
        ([0.5, 0.6, 1.0], r"poles must lie strictly inside the unit circle.*1 \(\|p\| >= 1\)"),
        ([0.5, -1.2, 0.1], r"-1\.2"),
        ([0.5, 0.6], "poles must list 3 poles"),
        ([0.5 + 0.1j, 0.5, 0.1], "needs its conjugate"),
    ],
)
def test_bad_poles_are_refused(poles, match):
    with pytest.raises(ConfigError, match=match):
        LuenbergerObserver(A3, B3, C_one, poles)


def test_unobservable_mode_is_named():
    A = np.diag([0.9, 0.7, 0.5])
    with pytest.raises(ConfigError, match=r"not observable.*0\.7"):
        LuenbergerObserver(A, None, [[1.0, 0.0, 1.0]], [0.1, 0.2, 0.3])


def test_current_form_needs_a_nonsingular_direction():
    A = np.array([[0.0, 1.0], [0.0, 0.0]])  # C A loses the first state: (A, C A) is not observable
    LuenbergerObserver(A, None, [[1.0, 0.0]], [0.1, 0.2], form="predictor")
    with pytest.raises(ConfigError, match="use the predictor form"):
        LuenbergerObserver(A, None, [[1.0, 0.0]], [0.1, 0.2], form="current")
