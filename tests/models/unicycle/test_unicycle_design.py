"""The 2WD cart study's EKF and LQR (models/unicycle/design.py, reference.py): structure, stability, coverage."""

from __future__ import annotations

import math

import numpy as np
import pytest

import netsim  # noqa: F401  (pins BLAS before numpy work)
from netsim.models.unicycle.design import LQR_Q, LQR_R, PHASES, Trajectory, cart_frame_error, error_model, lqr_gain
from netsim.models.unicycle.model import P0, Q_REPORT, R_REPORT, TS, XI0_HAT, arc
from netsim.models.unicycle.reference import simulate


@pytest.mark.parametrize("v_ref", [0.03, 0.02, 0.015, -0.05])
def test_lqr_gain_has_the_structure_of_eq27_and_matches_full_dlqr(v_ref):
    import control

    K = lqr_gain(v_ref)
    assert K[0, 1] == 0.0 and K[0, 2] == 0.0 and K[1, 0] == 0.0  # exactly zero (assembled from the blocks)
    assert K[0, 0] != 0.0 and K[1, 1] != 0.0 and K[1, 2] != 0.0
    A, B = error_model(v_ref)
    Kfull, _, _ = control.dlqr(A, B, LQR_Q, LQR_R)
    # the full 3-state Riccati solution (an independent computation) gives the same gain to its own accuracy
    assert np.allclose(K, Kfull, rtol=1e-6, atol=1e-9)
    assert np.all(np.abs(np.linalg.eigvals(A - B @ K)) < 1.0)


def test_printed_sign_of_eq26_gives_an_unstable_loop_on_the_derived_model():
    # designed on A_d[1,2] = -Ts v_ref (printed), applied to the derived error model (+Ts v_ref)
    A, B = error_model(0.03)
    Kp = lqr_gain(0.03, a_sign="printed")
    assert max(abs(np.linalg.eigvals(A - B @ Kp))) > 1.0
    assert Kp[1, 1] == pytest.approx(-lqr_gain(0.03)[1, 1])  # only the sign of k22 flips


def test_derived_error_model_matches_the_nonlinear_error_dynamics():
    # one step of the true motion of cart and reference, error rotated into the cart frame (eq 24), against A e + B u
    v_ref, ts = 0.03, TS
    ref0 = np.array([0.0, 0.0, 0.0])
    cart0 = np.array([-2e-3, 1e-3, -0.05])  # behind, left, heading 0.05 rad right of the reference
    e0 = cart_frame_error(ref0, cart0)
    du = np.array([1e-3, -2e-3])  # inputs relative to the reference's (v_ref, 0)
    cart1 = arc(cart0, v_ref + du[0], du[1], ts)
    ref1 = arc(ref0, v_ref, 0.0, ts)
    e1 = cart_frame_error(ref1, cart1)
    A, B = error_model(v_ref, ts)
    # linear prediction up to second-order terms (Ts v e3^2 / 2 and Ts w e2: below 1e-6 here)
    assert np.allclose(e1, A @ e0 + B @ du, atol=1e-6)
    # the printed sign misses the lateral error by 2 Ts v_ref e3 = 3e-5
    Ap, _ = error_model(v_ref, ts, "printed")
    assert abs((Ap @ e0 + B @ du)[1] - e1[1]) > 2e-5


def test_initial_band_widths_are_sqrt_diag_P0():
    from netsim.models.unicycle.design import Phase

    # sensors off at the first sample: the band at sample 0 is the prior's, sqrt(diag(P0)) (eq 21)
    o = simulate(3, phases=(Phase(1.0, 0.03, 0.0, False, False), Phase(1.0, 0.03, 0.0, True, True)))
    assert np.array_equal(np.sqrt(np.diagonal(o["P"][0])), np.sqrt(np.diag(P0)))
    # sigma x = 3.2 cm, sigma theta = 5 degrees: the report's reading of its P0
    assert np.sqrt(P0[0, 0]) == pytest.approx(0.0316, abs=1e-4)
    assert math.degrees(np.sqrt(P0[2, 2])) == pytest.approx(5.0, abs=0.01)
    # with both sensors on at sample 0 the first corrections can only narrow the bands
    o = simulate(3, phases=PHASES)
    assert np.all(np.sqrt(np.diagonal(o["P"][0])) < np.sqrt(np.diag(P0)))


def test_det_P_grows_monotonically_in_the_blackout():
    o = simulate(5)
    det = np.linalg.det(o["P"])
    blackout = slice(401, 600)  # samples 4.01 .. 5.99 s: no sensor
    assert np.all(np.diff(det[blackout]) > 0)


def _coverage(runs, **kw):
    fr = []
    for s in range(runs):
        o = simulate(2000 + s, **kw)
        sd = np.sqrt(np.diagonal(o["P"], axis1=1, axis2=2))
        fr.append(np.mean(np.abs(o["truth"] - o["xhat"]) <= 1.96 * sd))
    fr = np.array(fr)
    return fr.mean(), 3.0 * fr.std(ddof=1) / math.sqrt(runs)


def test_95_percent_bands_cover_95_percent_when_Q_and_R_match_the_truth():
    mean, tol = _coverage(30)
    assert abs(mean - 0.95) <= max(tol, 0.01), (mean, tol)


def test_overconfident_filter_fails_the_coverage_check():
    # R 25x too small in the filter: the bands are too narrow (the check above can fail)
    mean, tol = _coverage(10, R_filter=R_REPORT / 25, Q_filter=Q_REPORT / 25, P0_=P0 / 25)
    assert mean < 0.95 - max(tol, 0.01)


def test_lqr_without_feedforward_lags_by_v_over_k11():
    # straight line, no noise: the steady longitudinal error is the one that commands v_ref: e1 = v_ref / (-k11)
    from netsim.models.unicycle.design import Phase

    ph = (Phase(10.0, 0.03, 0.0, True, True),)
    o = simulate(1, phases=ph, law="lqr", Q_true=np.zeros((3, 3)), R_true=np.zeros(2), P0_=P0 * 1e-12)
    K = lqr_gain(0.03)
    e = np.array([cart_frame_error(r, x) for r, x in zip(o["ref"], o["truth"])])
    assert e[-1, 0] == pytest.approx(0.03 / -K[0, 0], rel=1e-3)
    with_ff = simulate(1, phases=ph, law="lqr_ff", Q_true=np.zeros((3, 3)), R_true=np.zeros(2), P0_=P0 * 1e-12)
    assert np.abs(with_ff["ref"][-1] - with_ff["truth"][-1]).max() < 1e-4


def test_trajectory_ends_where_the_arcs_say():
    tr = Trajectory()
    R = 0.02 / (math.pi / 4)
    assert np.allclose(tr.poses[-1], XI0_HAT + [0.12 + R, R + 0.06, math.pi / 2], atol=1e-12)


def test_qr_ordering_is_measured_rougher_with_5Q_smoother_with_5R():
    # the report's section 3.2.5: more Q -> more noise in the estimates, more R -> smoother. Measured with common
    # random numbers (the same 8 seeds, the truth's noise unchanged) as the RMS second difference of y_hat in the
    # straight part, where the reference's is zero
    def rough(fq, fr):
        vals = []
        for s in range(8):
            o = simulate(300 + s, Q_filter=fq * Q_REPORT, R_filter=fr * R_REPORT)
            vals.append(np.diff(o["xhat"][:400, 1], n=2))
        return float(np.sqrt(np.mean(np.square(vals))))

    base, more_q, more_r = rough(1, 1), rough(5, 1), rough(1, 5)
    assert more_q > base > more_r
    assert more_r < 0.7 * base  # 5R lets much less noise through (measured: about 0.4x)
