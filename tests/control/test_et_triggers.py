"""Sensor triggers (eqs 6-8) and the controller condition (eq 22) against hand-computed sequences."""

import pytest

from netsim.control import (
    AnyOf,
    ControllerTrigger,
    MaxIntervalTrigger,
    MixedTrigger,
    ReferenceChangeTrigger,
    SendOnDelta,
    TimeTriggered,
)
from netsim.errors import ConfigError


def _run(trig, ys, rs=None):
    rs = rs or [None] * len(ys)
    return [trig.should_send(k, y, r) for k, (y, r) in enumerate(zip(ys, rs))]


def test_pet_squared_fires_when_squared_change_exceeds_mixed_threshold():
    # hand: ybar=1.0; k1 0.0025 <= 0.01*1.1025+0.001; k2 0.04 > 0.0154 -> send (ybar=1.2);
    # k3 0; k4 0.0025 <= 0.016625; k5 (1.2-1.4)^2=0.04 > 0.01*1.96+0.001=0.0206
    trig = MixedTrigger(sigma=0.01, delta=0.001)
    assert _run(trig, [1.0, 1.05, 1.2, 1.2, 1.25, 1.4]) == [True, False, True, False, False, True]


def test_pet_plain_norm_reading_uses_absolute_differences():
    # |1 - 1.05| = 0.05 > 0.01*1.05 + 0.001 = 0.0115
    trig = MixedTrigger(sigma=0.01, delta=0.001, norm="2")
    assert _run(trig, [1.0, 1.05]) == [True, True]


def test_pet_compares_with_last_sent_value_not_previous_sample():
    # drift of 0.02 per step: each step alone 0.0004 <= 0.001, but vs the last sent value
    # the squared change reaches (0.04)^2 = 0.0016 > 0.001 at k=2
    trig = MixedTrigger(sigma=0.0, delta=0.001)
    assert _run(trig, [0.0, 0.02, 0.04, 0.06, 0.08]) == [True, False, True, False, True]


def test_safety_condition_sends_every_kmax_periods_and_restarts_after_pet_send():
    assert _run(MaxIntervalTrigger(3), [0.0] * 8) == [True, False, False, True, False, False, True, False]
    # PET fires at k=2 (jump), the safety timer restarts there: next safety send at k=5
    combo = AnyOf([MixedTrigger(0.0, 0.5), MaxIntervalTrigger(3)])
    ys = [0.0, 0.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0]
    assert _run(combo, ys) == [True, False, True, False, False, True, False, False]


def test_reference_change_condition_fires_kmax_after_the_change():
    rs = [0, 0, 0, 0, 1, 1, 1, 1, 1]
    assert _run(ReferenceChangeTrigger(2), [0.0] * 9, rs) == [False] * 6 + [True, False, False]


def test_time_triggered_and_send_on_delta():
    assert _run(TimeTriggered(2), [0.0] * 5) == [True, False, True, False, True]
    assert _run(SendOnDelta(0.1), [0.0, 0.05, 0.11, 0.15, 0.22]) == [True, False, True, False, True]


@pytest.mark.parametrize("bad", [dict(sigma=-1.0, delta=0.1), dict(sigma=0.1, delta=-1e-9)])
def test_negative_thresholds_are_refused(bad):
    with pytest.raises(ConfigError, match="must be a finite number >= 0"):
        MixedTrigger(**bad)
    with pytest.raises(ConfigError, match="sigma_c|delta_c"):
        ControllerTrigger(**bad)


def test_controller_condition_compares_with_first_value_of_last_sent_packet():
    # ubar=1 ; 1.12: 0.0144 <= 0.02 ; 1.24: vs ubar=1 -> 0.0576 > 0.02 (vs 1.12 it would not fire)
    trig = ControllerTrigger(sigma=0.0, delta=0.02)
    assert [trig.should_send(u) for u in (1.0, 1.12, 1.24, 1.3)] == [True, False, True, False]


def test_disabled_controller_condition_always_sends():
    trig = ControllerTrigger(enabled=False)
    assert all(trig.should_send(1.0) for _ in range(3))
