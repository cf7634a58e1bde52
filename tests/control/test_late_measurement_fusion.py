"""Measurements one sample late (issue 26 follow-up): estimators without history re-filter one step, and a sample
taken before the controller's first one (offset over half a period) is stale, not a duplicate of the next."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

import netsim
from netsim.control.luenberger import LuenbergerObserver
from netsim.control.parts import DirectState

A_C = np.array([[0.0, 1.0], [0.0, -1.0]])  # the DC servo 1000 / (s (s + 1)), states [theta, omega]
B_C = np.array([[0.0], [1000.0]])
C = np.array([[1.0, 0.0]])
R_LQR = 0.1
POLES = [0.5, 0.6]
KEY = "control.controller.control."


def _zoh(h: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact transition over ``h`` s with the input held (scipy's expm of the augmented matrix)."""
    M = np.zeros((3, 3))
    M[:2, :2], M[:2, 2:] = A_C * h, B_C * h
    E = sla.expm(M)
    return E[:2, :2], E[:2, 2:]


def _ackermann(A: np.ndarray, Cf: np.ndarray, poles: list[float]) -> np.ndarray:
    """Observer gain placing eig(A - L Cf) at ``poles`` by Ackermann's formula, written out (one output)."""
    n = A.shape[0]
    coeffs = np.poly(poles)
    phi = sum(c * np.linalg.matrix_power(A, n - i) for i, c in enumerate(coeffs))
    O = np.vstack([Cf @ np.linalg.matrix_power(A, i) for i in range(n)])
    return phi @ np.linalg.solve(O, np.eye(n)[:, -1:])


def _loop(estimator: dict, offset: str) -> netsim.RunResult:
    """Sensor sampling theta at 10 k ms, sent over an ideal network to a 10 ms controller released at ``offset``,
    which writes u to the DAC itself; r = 0.5 rad, plant x0 = [1, 0], no noise."""
    plant = {"type": "ss", "A": A_C.tolist(), "B": B_C.ravel().tolist(), "C": C.tolist(), "inputs": ["u"],
             "outputs": ["theta"], "x0": [1.0, 0.0]}
    raw = {
        "name": "late_fusion", "seed": 1, "duration": "0.3 s", "plant": plant,
        "io": {"ym": {"type": "adc", "output": "theta"}, "u": {"type": "dac", "input": "u"}},
        "signals": {"r": {"type": "constant", "value": 0.5}},
        "nodes": {
            "sensor": {"policy": "dm", "tasks": [{"name": "sample", "program": "sensor", "period": "10 ms",
                                                  "params": {"channels": ["ym"], "network": "net",
                                                             "to": "controller", "tag": "y"}}]},
            "controller": {"policy": "dm", "tasks": [{
                "name": "control", "program": "state_feedback", "period": "10 ms", "offset": offset,
                "params": {"measurements": [{"network": "net", "sender": "sensor", "tag": "y"}],
                           "estimator": estimator, "law": {"type": "lqr", "Q": [1.0, 0.0], "R": R_LQR},
                           "reference": "r", "output_channel": "u", "record_as": "u_cmd"}}]},
        },
        "networks": {"net": {"type": "ideal", "nodes": ["sensor", "controller"]}},
        "record": ["u_cmd"],
    }
    return netsim.run(raw)


@pytest.mark.parametrize("form", ["current", "predictor"])
def test_luenberger_fuses_a_sample_taken_six_ms_before_the_controller_one_step_late(form: str) -> None:
    # before this change: 29 of 30 measurements stale, the loop ran on predictions only
    res = _loop({"type": "luenberger", "poles": POLES, "form": form}, "6 ms")
    m = res.metrics
    assert m[KEY + "steps"] == 30
    assert m[KEY + "fused"] == 29 and m[KEY + "stale"] == 1  # the t = 0 sample is before the first (see below)
    u_run = res.signals["u_cmd"].dropna().to_numpy()

    # independent computation: the design by scipy (ZOH by expm, LQR from the DARE, the observer gain by
    # Ackermann's formula), the plant stepped exactly between the sensor's samples (10 k ms) and the
    # controller's (10 k + 6 ms); y sampled at 10 k ms is the measurement of controller sample k - 1 and is
    # fused at sample k as the observer would have fused it in time at k - 1 (the re-filter is exact)
    h = 0.01
    Ad, Bd = _zoh(h)
    A4, B4 = _zoh(0.004)
    A6, B6 = _zoh(0.006)
    P = sla.solve_discrete_are(Ad, Bd, np.diag([1.0, 0.0]), np.array([[R_LQR]]))
    K = np.linalg.solve(R_LQR + Bd.T @ P @ Bd, Bd.T @ P @ Ad)
    NxNu = np.linalg.solve(np.block([[Ad - np.eye(2), Bd], [C, np.zeros((1, 1))]]), np.array([0.0, 0.0, 1.0]))
    Fr = NxNu[2] + K @ NxNu[:2]
    L = _ackermann(Ad, C @ Ad if form == "current" else C, POLES)
    x = A6 @ np.array([1.0, 0.0])  # the plant at the first controller sample (6 ms, u = 0 until then)
    xh = np.zeros(2)  # the observer's estimate at sample k (its x_bar: no measurement of sample k ever comes)
    u_ref = []
    for k in range(30):
        u = float(Fr[0] * 0.5 - (K @ xh)[0])
        u_ref.append(u)
        x = A4 @ x + B4.ravel() * u  # to the sensor's sample at 10 (k + 1) ms
        y = float((C @ x)[0])  # the measurement of controller sample k, fused at k + 1
        x = A6 @ x + B6.ravel() * u
        if form == "current":  # x_hat[k] = x_bar[k] + L e, then predicted
            xh = Ad @ (xh + L.ravel() * (y - float((C @ xh)[0]))) + Bd.ravel() * u
        else:  # x_hat[k+1] = A x_hat[k] + B u[k] + L e[k]
            xh = Ad @ xh + Bd.ravel() * u + L.ravel() * (y - float((C @ xh)[0]))
    assert abs(u_ref[-1]) < 0.05 < abs(u_ref[0])  # the loop closes: a transient that settles
    np.testing.assert_allclose(u_run, u_ref, rtol=1e-7, atol=1e-10)


def test_an_offset_over_half_a_period_makes_the_first_sample_stale_not_the_next_a_duplicate() -> None:
    # controller samples at 6 + 10 k ms; the sensor's sample at t = 0 is nearest to the sample at -4 ms,
    # which does not exist (it used to be clamped to sample 0, and the sample at 10 ms, nearest to sample 0,
    # then counted as a duplicate)
    m = _loop({"type": "kalman", "Q": [0.0, 0.01], "R": 1e-6, "history": 3}, "6 ms").metrics
    assert m[KEY + "duplicates"] == 0
    assert m[KEY + "stale"] == 1
    assert m[KEY + "fused"] == 29  # 30 samples at 10 ... 300 ms minus the one taken at 300 ms, read after the end


def test_a_sample_four_ms_before_is_still_fused_at_the_current_sample() -> None:
    m = _loop({"type": "luenberger", "poles": POLES}, "4 ms").metrics
    assert m[KEY + "stale"] == 0 and m[KEY + "fused"] == 30 and m[KEY + "prediction_only"] == 0


@pytest.mark.parametrize("form", ["current", "predictor"])
def test_luenberger_late_correction_equals_fusing_in_time(form: str) -> None:
    A = np.array([[1.0, 0.1], [0.0, 0.9]])
    B = np.array([[0.005], [0.1]])
    L = _ackermann(A, C @ A if form == "current" else C, POLES)
    late = LuenbergerObserver(A, B, C, POLES, form=form, x0=[0.3, -0.2])
    late.predict([1.0])
    late.predict([-0.5])  # sample 2; sample 1 fused nothing yet
    assert late.correct_previous([0.7])
    assert not late.correct_previous([0.7])  # once per sample
    # the observer equations written out, with y[1] = 0.7 fused at sample 1
    x1 = A @ np.array([0.3, -0.2]) + B.ravel() * 1.0
    if form == "current":
        x2 = A @ (x1 + L.ravel() * (0.7 - x1[0])) + B.ravel() * -0.5
    else:
        x2 = A @ x1 + B.ravel() * -0.5 + L.ravel() * (0.7 - x1[0])
    np.testing.assert_allclose(late.x_hat, x2, rtol=1e-12)


def test_late_correction_is_refused_when_the_previous_sample_had_a_measurement() -> None:
    obs = LuenbergerObserver(np.array([[1.0, 0.1], [0.0, 0.9]]), None, C, POLES)
    assert not obs.correct_previous([1.0])  # no previous sample
    obs.correct([1.0])
    obs.predict()
    before = obs.x_hat.copy()
    assert not obs.correct_previous([2.0])
    np.testing.assert_array_equal(obs.x_hat, before)


def test_direct_state_late_measurement_is_predicted_one_step() -> None:
    A = np.array([[1.0, 0.1], [0.0, 0.9]])
    B = np.array([[0.005], [0.1]])
    Cs = np.array([[2.0, 0.0], [0.0, 1.0]])
    est = DirectState(A, B, Cs)
    est.predict([0.4])
    assert est.correct_previous([1.0, -1.0])
    np.testing.assert_allclose(est.x_hat, A @ np.array([0.5, -1.0]) + B.ravel() * 0.4, rtol=1e-12)


def test_luenberger_form_defaults_to_current_as_in_yaml() -> None:
    from netsim.control.parts import LuenbergerPart

    assert LuenbergerObserver(np.array([[1.0, 0.1], [0.0, 0.9]]), None, C, POLES).form == LuenbergerPart.Params.model_fields["form"].default == "current"


def test_first_measurement_one_sample_late_starts_the_estimate_at_its_own_sample() -> None:
    # x0_hat: first_measurement with the first measurement one sample late: the estimate at sample 2 is the one
    # the observer would hold had it started at sample 1 from y[1] (x = x_prior + pinv(C) (y - C x_prior)),
    # fused it there and predicted with u[1]
    A = np.array([[1.0, 0.1], [0.0, 0.9]])
    B = np.array([[0.005], [0.1]])
    obs = LuenbergerObserver(A, B, C, POLES, x0=[0.3, -0.2])
    obs.predict([1.0])
    obs.predict([-0.5])
    obs.start_previous([0.7])
    assert obs.correct_previous([0.7])
    x1 = A @ np.array([0.3, -0.2]) + B.ravel() * 1.0
    xs = x1 + np.linalg.pinv(C) @ (np.array([0.7]) - C @ x1)  # C xs = 0.7: the correction after it is zero
    np.testing.assert_allclose(obs.x_hat, A @ xs + B.ravel() * -0.5, rtol=1e-12)
