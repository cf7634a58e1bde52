"""The event estimators against hand-computed update sequences on scripted encoder events.

Every expected number below is worked out by hand from the paper's equations (9)-(11) and section VI-B,
with the round numbers K = 10 1/s, Ti = 0.1 s, Tfilter = 10 ms (or 2 ms), step 1 mm.
"""

import pytest

from netsim.models.cart.controllers import make_controller
from netsim.models.cart.encoding import Quantizer
from netsim.models.cart.estimators import BasicEventEstimator, FullEventEstimator, PositionPredictionEstimator
from netsim.models.cart.tuning import Tuning
from netsim.errors import ConfigError

MS = 1_000_000
Q = Quantizer(1e-3)  # count c means p in [c - 0.5, c + 0.5) mm
TN = Tuning(wc=10.0, K=10.0, Ti=0.1, Tfilter=0.01, beta=1.0)  # K/Ti = 100


def test_quantizer_follows_eq1_round_convention():
    assert Q.count(0.00049) == 0 and Q.count(0.00051) == 1 and Q.count(-0.00051) == -1
    assert Q.interval(2) == pytest.approx((0.0015, 0.0025))
    assert Q.edge_position(2, +1) == pytest.approx(0.0015)  # came up from 1
    assert Q.edge_position(2, -1) == pytest.approx(0.0025)  # came down from 3
    assert Quantizer.from_bits(6).delta == pytest.approx(3.2e-3)  # paper: q = 6 emulates 3.2 mm


@pytest.mark.parametrize("q", [-1, 17, 2.5])
def test_q_outside_0_to_16_is_a_config_error(q):
    with pytest.raises(ConfigError, match="q"):
        Quantizer.from_bits(q)


def test_basic_event_estimator_hand_sequence():
    est = BasicEventEstimator(TN, Q)
    # step 1 ms: no edge. No time update; bias integrates -h vref: 100 * (0 - 0.001 * 0.5) = -0.05
    est.update(1 * MS, 0, 1, -1, u=3.0, vref=0.5)
    s = est.state
    assert (s.p_hat, s.v_hat) == (0.0, 0.0)
    assert s.u_bias_hat == pytest.approx(-0.05)
    # step 2 ms: edge into count 1 at 1.6 ms -> p_hat = 0.5 mm, v_hat = 0.5 mm / 1.6 ms = 0.3125 m/s
    est.update(2 * MS, 1, 1, 1_600_000, u=3.0, vref=0.5)
    assert s.p_hat == pytest.approx(0.0005)
    assert s.v_hat == pytest.approx(0.3125)
    # bias: -0.05 + 100 * (0.0005 - 0 - 0.0005) = -0.05
    assert s.u_bias_hat == pytest.approx(-0.05)
    # step 3 ms: same stamp -> no event, estimates unchanged, bias -0.05 - 0.05 = -0.1
    est.update(3 * MS, 1, 1, 1_600_000, u=3.0, vref=0.5)
    assert s.v_hat == pytest.approx(0.3125) and s.u_bias_hat == pytest.approx(-0.1)
    # step 4 ms: edge into 2 at 3.1 ms: v_hat = 1 mm / 1.5 ms (no lower limit on dt)
    est.update(4 * MS, 2, 1, 3_100_000, u=3.0, vref=0.5)
    assert s.v_hat == pytest.approx(0.001 / 0.0015)
    assert s.u_bias_hat == pytest.approx(-0.1 + 100 * (0.001 - 0.0005))


def test_position_prediction_hand_sequence():
    est = PositionPredictionEstimator(TN, Q)
    s = est.state
    s.v_hat = 0.4  # pretend a previous estimate
    # step 1 ms: p_hat = 0.4 mm (inside [-0.5, 0.5) mm), bias 100 * (0.0004 - 0.001 * 0.4) = 0
    est.update(1 * MS, 0, 1, -1, u=0.0, vref=0.4)
    assert s.p_hat == pytest.approx(0.0004) and s.u_bias_hat == pytest.approx(0.0)
    # step 2 ms: p_hat would reach 0.8 mm > 0.5 mm: bound update at 2 ms, dt since last event (t = 0) is
    # 2 ms < Tfilter -> 10 ms: dp = 0.5 - 0.8 = -0.3 mm, v_hat = 0.4 - 0.0003/0.01 = 0.37
    est.update(2 * MS, 0, 1, -1, u=0.0, vref=0.4)
    assert s.p_hat == pytest.approx(0.0005)
    assert s.v_hat == pytest.approx(0.37)
    # bias: 100 * ((0.0005 - 0.0004) - 0.0004) = -0.03
    assert s.u_bias_hat == pytest.approx(-0.03)
    # step 3 ms: edge into 1 at 2.5 ms. Predict to 2.5 ms: 0.5 + 0.37*0.5 = 0.685 mm; edge at 0.5 mm:
    # dp = -0.185 mm, dt = 2.5 ms -> Tf: v_hat = 0.37 - 0.0185 = 0.3515; then 0.5 ms more:
    # p_hat = 0.5 + 0.3515 * 0.5 = 0.67575 mm
    est.update(3 * MS, 1, 1, 2_500_000, u=0.0, vref=0.4)
    assert s.v_hat == pytest.approx(0.3515)
    assert s.p_hat == pytest.approx(0.00067575)
    assert s.t_event == pytest.approx(0.0025)
    assert s.u_bias_hat == pytest.approx(-0.03 + 100 * (0.00067575 - 0.0005 - 0.0004))


def test_full_event_hand_sequence_eqs_9_to_11():
    est = FullEventEstimator(TN, Q)
    s = est.state
    # step 1 ms, u = 2 over [0, 1 ms], no edge: eq 9 -> p = 0.5*2*1e-6 = 1e-6, v = 2e-3; bias unchanged
    est.update(1 * MS, 0, 1, -1, u=2.0, vref=0.8)
    assert s.p_hat == pytest.approx(1e-6) and s.v_hat == pytest.approx(2e-3) and s.u_bias_hat == 0.0
    # step 2 ms, edge into 1 at 1.5 ms. Time update 0.5 ms: p = 1e-6 + 2e-3*5e-4 + 0.5*2*2.5e-7 = 2.25e-6,
    # v = 3e-3. Measurement (eq 10, dt = 1.5 ms -> Tf = 10 ms): dp = 5e-4 - 2.25e-6 = 4.9775e-4,
    # v = 3e-3 + 0.049775 = 0.052775; eq 11: bias = 100 * 4.9775e-4 = 0.049775.
    # Time update 0.5 ms with a = u + bias = 2.049775.
    est.update(2 * MS, 1, 1, 1_500_000, u=2.0, vref=0.8)
    a = 2.0 + 0.049775
    assert s.u_bias_hat == pytest.approx(0.049775)
    assert s.v_hat == pytest.approx(0.052775 + a * 5e-4)
    assert s.p_hat == pytest.approx(5e-4 + 0.052775 * 5e-4 + 0.5 * a * 2.5e-7)


def test_full_event_lti_mode_timeout_switches_dt_to_tfilter():
    # Tfilter = 2 ms -> timeout 2 Tfilter = 4 ms. A stuck cart (count 0, p_hat starting at the upper bound
    # 0.5 mm with v_hat = 0.1 m/s) under u = 10 m/s^2: the prediction leaves [-0.5, 0.5] mm in every step,
    # so constraints are active from the 1 ms step on and the streak has lasted 4 ms at the 5 ms step.
    tn = Tuning(wc=10.0, K=10.0, Ti=0.1, Tfilter=0.002, beta=1.0)
    est = FullEventEstimator(tn, Q, trace=True)
    s = est.state
    s.p_hat, s.v_hat = 0.0005, 0.1
    for k in range(1, 9):
        est.update(k * MS, 0, 1, -1, u=10.0, vref=0.0)
    assert [h[0] for h in s.history] == ["bound"] * 8
    used = [h[3] for h in s.history]
    # steps 1..4 ms: dt = max(time since the last event (t = 0), Tfilter) = 2, 2, 3, 4 ms; then LTI mode: 2 ms
    assert used == pytest.approx([0.002, 0.002, 0.003, 0.004, 0.002, 0.002, 0.002, 0.002])
    # the first update by hand: p = 0.5 + 0.1 + 0.5*10*1e-3 mm = 0.605 mm -> dp = -0.105 mm,
    # v = 0.1 + 0.01 - 0.000105/0.002 = 0.0575, bias = 100 * dp = -0.0105
    est2 = FullEventEstimator(tn, Q)
    est2.state.p_hat, est2.state.v_hat = 0.0005, 0.1
    est2.update(1 * MS, 0, 1, -1, u=10.0, vref=0.0)
    assert est2.state.p_hat == pytest.approx(0.0005)
    assert est2.state.v_hat == pytest.approx(0.0575)
    assert est2.state.u_bias_hat == pytest.approx(-0.0105)


def test_position_prediction_has_no_lti_timeout():
    tn = Tuning(wc=10.0, K=10.0, Ti=0.1, Tfilter=0.002, beta=1.0)
    est = PositionPredictionEstimator(tn, Q, trace=True)
    est.state.p_hat, est.state.v_hat = 0.0005, 0.1
    for k in range(1, 9):
        est.update(k * MS, 0, 1, -1, u=0.0, vref=0.0)
    used = [h[3] for h in est.state.history]
    # dt = max(t, Tf) throughout: the long time since the last event keeps the gain low
    assert used == pytest.approx([max(k * 1e-3, 0.002) for k in range(1, len(used) + 1)])
    assert len(used) >= 3


def test_control_law_and_saturation():
    ctrl = make_controller("full_event", 40.0, Q)
    tn = ctrl.tuning
    assert tn.beta == 1.0 and tn.K == 40.0
    # at rest, all estimates zero: u = K beta vref = 40 * 0.8 = 32 m/s^2 > Ku = 25.5 -> uV = 1
    assert ctrl.update(0, 0, 1, -1, 0.8) == 1.0
    assert ctrl.u == pytest.approx(25.5)
    pi = make_controller("pure_pi", 10.0, Q)
    # u = K (0.5 vref) = 10 * 0.5 * 0.8 = 4 -> uV = 4/25.5
    assert pi.update(0, 0, 1, -1, 0.8) == pytest.approx(4.0 / 25.5)
