"""KalmanFilter: steady-state gain, time-varying recursion, prediction-only steps, delayed measurements.

Independent references: python-control's ``dlqe`` (slycot's Riccati solver) for the steady state, and the
textbook recursion written out here (covariance update ``P - K C P``, not the Joseph form the filter uses).
"""

import numpy as np
import pytest

from netsim.control.kalman import KalmanFilter
from netsim.errors import ConfigError, SimulationError

H = 0.1
A = np.array([[1.0, H], [0.0, 1.0]])  # double integrator sampled at 0.1 s (ZOH)
B = np.array([[H * H / 2], [H]])
C = np.array([[1.0, 0.0]])
Q = np.array([[1e-4, 0.0], [0.0, 1e-3]])
R = np.array([[0.01]])


def simulate(steps, seed, x0=(0.0, 1.0)):
    """True states, inputs and measurements of the noisy double integrator."""
    rng = np.random.default_rng(seed)
    x = np.array(x0, dtype=float)
    xs, us, ys = [], [], []
    Lq = np.linalg.cholesky(Q)
    for k in range(steps):
        u = np.array([np.sin(0.05 * k)])
        xs.append(x.copy())
        ys.append(C @ x + np.sqrt(R[0, 0]) * rng.standard_normal(1))
        us.append(u)
        x = A @ x + B @ u + Lq @ rng.standard_normal(2)
    return np.array(xs), np.array(us), np.array(ys)


def textbook_filter(ys, us, x0, P0, present):
    """Kalman filter, textbook form: K = P C'(C P C' + R)^-1, x += K(y - Cx), P -= K C P; then predict."""
    x, P = np.array(x0, float), np.array(P0, float)
    out = []
    for k in range(len(us)):
        if present[k]:
            S = C @ P @ C.T + R
            K = P @ C.T @ np.linalg.inv(S)
            x = x + K @ (ys[k] - C @ x)
            P = P - K @ C @ P
        out.append((x.copy(), P.copy()))
        x = A @ x + B @ us[k]
        P = A @ P @ A.T + Q
    return out


def test_steady_state_gain_equals_dlqe_riccati_solution():
    import control

    kf = KalmanFilter(A, B, C, Q, R, steady_state=True)
    # python-control's dlqe is the predictor-form estimator: L = A M C'(C M C' + R)^-1 with M its P
    L, M, _ = control.dlqe(A, np.eye(2), C, Q, R)
    np.testing.assert_allclose(kf.M_ss, M, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(A @ kf.K_ss, L, rtol=1e-10, atol=1e-14)
    # filter gain from that M, written out here
    K = M @ C.T @ np.linalg.inv(C @ M @ C.T + R)
    np.testing.assert_allclose(kf.gain, K, rtol=1e-10, atol=1e-14)


def test_time_varying_gain_converges_to_the_steady_state_gain():
    tv = KalmanFilter(A, B, C, Q, R, P0=np.diag([10.0, 10.0]))
    ss = KalmanFilter(A, B, C, Q, R, steady_state=True)
    first = tv.gain.copy()
    for _ in range(3000):
        tv.correct(0.0)
        tv.predict(0.0)
    np.testing.assert_allclose(tv.gain, ss.K_ss, rtol=1e-9)
    np.testing.assert_allclose(tv.P, ss.M_ss, rtol=1e-9)
    assert np.max(np.abs(first - ss.K_ss)) > 1e-2  # the recursion did move (P0 far from the steady state)


def test_time_varying_filter_equals_the_textbook_recursion_with_missing_measurements():
    xs, us, ys = simulate(200, seed=3)
    present = np.ones(200, bool)
    present[[5, 6, 7, 50, 120, 121]] = False
    kf = KalmanFilter(A, B, C, Q, R, x0=[0.5, 0.0], P0=np.eye(2))
    ref = textbook_filter(ys, us, [0.5, 0.0], np.eye(2), present)
    for k in range(200):
        if present[k]:
            assert kf.correct(ys[k]) is True
        np.testing.assert_allclose(kf.x_hat, ref[k][0], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(kf.P, ref[k][1], rtol=1e-9, atol=1e-14)
        kf.predict(us[k])


@pytest.mark.parametrize("steady", [False, True])
def test_prediction_only_step_equals_model_propagation(steady):
    kf = KalmanFilter(A, B, C, Q, R, x0=[1.0, -2.0], P0=np.diag([0.3, 0.2]), steady_state=steady)
    x, P = kf.x_hat.copy(), kf.P.copy()
    kf.predict([0.7])
    np.testing.assert_array_equal(kf.x_hat, A @ x + B @ np.array([0.7]))
    if not steady:
        np.testing.assert_allclose(kf.P, A @ P @ A.T + Q, rtol=1e-15, atol=0)


def test_delayed_measurement_fused_at_its_sample_equals_the_on_time_filter():
    xs, us, ys = simulate(120, seed=5)
    on_time = KalmanFilter(A, B, C, Q, R, history=0)
    late = KalmanFilter(A, B, C, Q, R, history=4)
    delay = {k: (k % 4) for k in range(120)}  # delays of 0..3 samples
    arrivals: dict[int, list[int]] = {}
    for k, d in delay.items():
        arrivals.setdefault(k + d, []).append(k)
    for k in range(120):
        on_time.correct(ys[k])
        for ks in arrivals.get(k, []):
            assert late.correct(ys[ks], k=ks) is True
        # every measurement taken up to k - 3 is in: from then on the two agree
        if k >= 3 and all(ks + delay[ks] <= k for ks in range(k + 1)):
            np.testing.assert_allclose(late.x_hat, on_time.x_hat, rtol=1e-10, atol=1e-12)
            np.testing.assert_allclose(late.P, on_time.P, rtol=1e-10, atol=1e-14)
        on_time.predict(us[k])
        late.predict(us[k])
    # the last three arrivals fall after the end; everything that arrived was fused once
    assert late.fused == sum(1 for k in range(120) if k + delay[k] < 120)


def test_delayed_measurement_fused_at_sample_time_beats_fusing_at_arrival():
    # offline experiment: every measurement arrives 3 samples after it was taken (network delay 0.3 s)
    d = 3
    err_sample, err_arrival = [], []
    for seed in range(20):
        xs, us, ys = simulate(300, seed=100 + seed)
        at_sample = KalmanFilter(A, B, C, Q, R, history=d)
        at_arrival = KalmanFilter(A, B, C, Q, R)
        for k in range(300):
            if k >= d:
                at_sample.correct(ys[k - d], k=k - d)
                at_arrival.correct(ys[k - d])  # treated as if taken now
            if k >= 50:
                err_sample.append(at_sample.x_hat - xs[k])
                err_arrival.append(at_arrival.x_hat - xs[k])
            at_sample.predict(us[k])
            at_arrival.predict(us[k])
    rms_sample = np.sqrt(np.mean(np.square(err_sample), axis=0))
    rms_arrival = np.sqrt(np.mean(np.square(err_arrival), axis=0))
    # measured on this model (seeds 100..119): position RMS 0.072 at the sample time vs 1.05 at arrival,
    # velocity 0.109 vs 0.243; the bounds leave room for other seeds' noise
    assert rms_sample[0] < 0.2 * rms_arrival[0]
    assert rms_sample[1] < 0.6 * rms_arrival[1]


def test_duplicate_and_stale_measurements_are_never_fused_twice():
    kf = KalmanFilter(A, B, C, Q, R, history=2)
    assert kf.correct(1.0) is True
    x = kf.x_hat.copy()
    assert kf.correct(1.0) is False  # same sample again
    np.testing.assert_array_equal(kf.x_hat, x)
    for _ in range(3):
        kf.predict(0.0)
    assert kf.k == 3
    assert kf.correct(5.0, k=0) is False  # 3 samples back, history is 2: stale
    assert kf.correct(5.0, k=1) is True  # 2 samples back: fused at sample 1
    x = kf.x_hat.copy()
    assert kf.correct(5.0, k=1) is False  # duplicate of a delayed one
    np.testing.assert_array_equal(kf.x_hat, x)
    assert (kf.fused, kf.duplicates, kf.stale) == (2, 2, 1)
    with pytest.raises(SimulationError, match="future"):
        kf.correct(0.0, k=7)


def test_undetectable_pair_is_refused_naming_the_mode():
    A2 = np.diag([1.2, 0.5])  # the unstable mode at 1.2 is not measured
    with pytest.raises(ConfigError, match=r"not detectable.*1\.2"):
        KalmanFilter(A2, None, [[0.0, 1.0]], np.eye(2), 1.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(A=[[1.0, 0.1]]), "A must be square"),
        (dict(C=[[1.0, 0.0, 0.0]]), "C must be anyx2"),
        (dict(R=[[0.0]]), "R must be positive definite"),
        (dict(Q=[[1.0, 0.0], [0.0, -1.0]]), "Q must be positive semidefinite"),
        (dict(Q=[[1.0, 0.5], [0.0, 1.0]]), "Q must be symmetric"),
        (dict(B=[[1.0], [0.0], [0.0]]), "B must be 2xany"),
    ],
)
def test_bad_matrices_are_refused_naming_the_parameter(kwargs, match):
    args = dict(A=A, B=B, C=C, Q=Q, R=R) | kwargs
    with pytest.raises(ConfigError, match=match):
        KalmanFilter(args["A"], args["B"], args["C"], args["Q"], args["R"])


# --- partial measurements (two sensors with their own rates) ------------------------------------------------
C2 = np.array([[1.0, 0.0], [0.0, 1.0]])  # position and velocity sensors
R2 = np.diag([0.01, 0.04])  # independent: no cross-covariance


def _joint_update(x, P, y, Cm, Rm):
    """One textbook correction with the measured rows ``Cm`` and their covariance ``Rm`` (written out here)."""
    S = Cm @ P @ Cm.T + Rm
    K = P @ Cm.T @ np.linalg.inv(S)
    return x + K @ (y - Cm @ x), P - K @ Cm @ P


def test_fusing_two_independent_parts_one_after_the_other_equals_fusing_them_together():
    kf = KalmanFilter(A, B, C2, Q, R2, x0=[0.3, -0.2], P0=np.diag([1.0, 2.0]))
    assert kf.correct([0.5], rows=[0]) and kf.correct([0.1], rows=[1])
    x_ref, P_ref = _joint_update(np.array([0.3, -0.2]), np.diag([1.0, 2.0]), np.array([0.5, 0.1]), C2, R2)
    np.testing.assert_allclose(kf.x_hat, x_ref, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(kf.P, P_ref, rtol=1e-10, atol=1e-14)


def test_a_part_uses_only_its_rows_of_c_and_its_block_of_r():
    kf = KalmanFilter(A, B, C2, Q, R2, x0=[0.0, 0.0], P0=np.eye(2))
    kf.correct([0.2], rows=[1])
    x_ref, P_ref = _joint_update(np.zeros(2), np.eye(2), np.array([0.2]), C2[[1]], R2[[1]][:, [1]])
    np.testing.assert_allclose(kf.x_hat, x_ref, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(kf.P, P_ref, rtol=1e-12, atol=1e-15)


def test_a_late_part_fused_at_its_sample_equals_the_on_time_filter():
    # on time: position at every sample, velocity at even samples; late: each velocity part arrives 3 samples late
    rng = np.random.default_rng(7)
    ys = rng.standard_normal((40, 2))
    on_time = KalmanFilter(A, B, C2, Q, R2, history=5)
    late = KalmanFilter(A, B, C2, Q, R2, history=5)
    for k in range(40):
        u = [np.sin(0.1 * k)]
        on_time.correct(ys[k, :1], rows=[0])
        late.correct(ys[k, :1], rows=[0])
        if k % 2 == 0:
            on_time.correct(ys[k, 1:], rows=[1])
        if k >= 3 and (k - 3) % 2 == 0:
            assert late.correct(ys[k - 3, 1:], k - 3, rows=[1])
        on_time.predict(u)
        late.predict(u)
    # the last two on-time velocity parts (samples 38, 36 + 3 > 39 for 38) have not reached the late filter yet:
    # compare with an on-time filter that skipped the velocity of sample 38 instead
    ref = KalmanFilter(A, B, C2, Q, R2, history=5)
    for k in range(40):
        ref.correct(ys[k, :1], rows=[0])
        if k % 2 == 0 and k + 3 <= 39:
            ref.correct(ys[k, 1:], rows=[1])
        ref.predict([np.sin(0.1 * k)])
    np.testing.assert_allclose(late.x_hat, ref.x_hat, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(late.P, ref.P, rtol=1e-9, atol=1e-12)


def test_each_row_is_fused_once_per_sample_and_other_rows_still_count():
    kf = KalmanFilter(A, B, C2, Q, R2)
    assert kf.correct([1.0], rows=[0])
    assert not kf.correct([1.0], rows=[0])  # the same row again: a duplicate
    assert not kf.correct([1.0, 2.0])  # the whole measurement overlaps row 0
    assert kf.correct([2.0], rows=[1])  # the other row is new
    assert (kf.fused, kf.duplicates) == (2, 2)


def test_the_steady_state_filter_refuses_a_part_and_says_what_to_use():
    kf = KalmanFilter(A, B, C2, Q, R2, steady_state=True)
    assert not kf.fuses_partial
    with pytest.raises(SimulationError, match="steady_state: false"):
        kf.correct([1.0], rows=[0])
    assert kf.correct([1.0, 2.0], rows=[0, 1])  # every row, in order: the whole measurement


def test_independent_rows_sees_cross_covariance_between_sources():
    assert KalmanFilter(A, B, C2, Q, R2).independent_rows([[0], [1]])
    assert not KalmanFilter(A, B, C2, Q, np.array([[0.01, 0.005], [0.005, 0.04]])).independent_rows([[0], [1]])
