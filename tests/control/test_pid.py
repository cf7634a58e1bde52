"""Discrete PID: the difference equations of TrueTime's pidcalc, written out independently here."""

import numpy as np
import pytest

from netsim.control.pid import PID, PIDParams
from netsim.registry import lookup


def reference_pid(K, Ti, Td, N, b, h, r, ys):
    """Independent transcription of Astrom & Wittenmark's discrete PID (TrueTime's pidcalc)."""
    I = D = 0.0
    yold = ys[0]
    us = []
    for y in ys:
        P = K * (b * r - y)
        D = Td / (N * h + Td) * D + N * K * Td / (N * h + Td) * (yold - y)
        us.append(P + I + D)
        I = I + K * h / Ti * (r - y)
        yold = y
    return np.array(us)


def test_pid_matches_truetime_difference_equations():
    # TrueTime servo example parameters (examples/servo/servo_init.m): K=0.96, Ti=0.12, Td=0.049, beta=0.5, N=10, h=6 ms
    pid = PID(0.96, 0.12, 0.049, 10.0, 0.5, 0.006)
    rng = np.random.default_rng(1)
    ys = rng.normal(size=50)
    got = np.array([pid.step(1.0, y) for y in ys])
    want = reference_pid(0.96, 0.12, 0.049, 10.0, 0.5, 0.006, 1.0, ys)
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)


def test_pd_without_integral_has_no_steady_integration():
    pd_ = PID(1.0, None, 0.04, 100.0, 1.0, 0.010)
    # constant error: P = 1, derivative zero after the first sample, no integral growth
    us = [pd_.step(1.0, 0.0) for _ in range(10)]
    assert us == [1.0] * 10


def test_integral_accumulates_k_h_over_ti_per_sample():
    pid = PID(2.0, 0.5, 0.0, 10.0, 1.0, 0.1)
    us = [pid.step(1.0, 0.0) for _ in range(4)]
    # u(k) = K*e + k*K*h/Ti*e = 2 + 0.4 k
    assert us == pytest.approx([2.0, 2.4, 2.8, 3.2])


def test_saturation_clamps_and_stops_windup():
    pid = PID(2.0, 0.5, 0.0, 10.0, 1.0, 0.1, u_min=-1.0, u_max=1.0)
    for _ in range(100):
        assert pid.step(1.0, 0.0) == 1.0
    # the integral did not wind up, so a reversed error gives an immediate negative output
    assert pid.step(0.0, 1.0) == -1.0
    assert pid.I == 0.0


def test_params_model_parses_h_and_rejects_bad_values():
    p = PIDParams(K=1.0, Ti=0.12, h="6 ms")
    assert p.h == 6_000_000
    assert PID.from_params(p).h == pytest.approx(0.006)
    assert PID.from_params(PIDParams(K=1.0), h_ns=4_000_000).h == pytest.approx(0.004)
    with pytest.raises(ValueError):
        PIDParams(K=1.0, Ti=-1.0)
    with pytest.raises(ValueError):
        PID.from_params(PIDParams(K=1.0))


def test_pid_is_registered_as_a_controller():
    assert lookup("controller", "pid") is PID
