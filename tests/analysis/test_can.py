"""CAN worst-case response-time analysis against hand-worked examples."""

import pytest

from netsim.analysis.can import CanMessage, can_analysis, can_response_times
from netsim.timebase import MS, US


def test_davis_counterexample_second_instance_is_worst():
    # Davis, Burns, Bril, Lukkien (2007), the example that refuted the original CAN analysis: three
    # messages of C = 1 ms, periods 2.5 / 3.5 / 3.5 ms. The lowest one's first instance answers in 3 ms,
    # but the second (queued at 3.5 ms) waits for A (at 2.5 and 5 ms) and B: it ends at 7 ms -> R = 3.5 ms.
    # Worked by hand: busy period 7 ms, Q = 2, w(0) = 2 ms -> R(0) = 3 ms, w(1) = 6 ms -> R(1) = 3.5 ms.
    msgs = [
        CanMessage("A", 1, 2500 * US, 1 * MS),
        CanMessage("B", 2, 3500 * US, 1 * MS),
        CanMessage("C", 3, 3500 * US, 1 * MS),
    ]
    res = {r.name: r for r in can_analysis(msgs)}
    assert res["C"].busy_period_ns == 7 * MS
    assert res["C"].instances == 2
    assert res["C"].response_ns == 3500 * US
    assert res["A"].response_ns == 2 * MS  # blocked by one 1 ms frame, then its own 1 ms
    assert res["B"].response_ns == 3 * MS  # blocking 1 + A 1 + own 1
    assert all(r.schedulable for r in res.values())


def test_blocking_by_longest_lower_priority_frame():
    # m1 (1 ms), m2 (1.2 ms), m3 (1.35 ms) with periods 5/7/10 ms and a 1.5 ms lowest-priority frame.
    # By hand: R1 = 1.5 + 1 = 2.5 ms; R2 = 1.5 + 1 + 1.2 = 3.7 ms; R3 = 1.5 + 1 + 1.2 + 1.35 = 5.05 ms;
    # the lowest one is never blocked: it waits for one instance of each other (w = 3.55 ms) -> 5.05 ms.
    msgs = [
        CanMessage("m1", 1, 5 * MS, 1000 * US),
        CanMessage("m2", 2, 7 * MS, 1200 * US),
        CanMessage("m3", 3, 10 * MS, 1350 * US),
        CanMessage("low", 9, 50 * MS, 1500 * US),
    ]
    r = can_response_times(msgs)
    assert r == {"m1": 2500 * US, "m2": 3700 * US, "m3": 5050 * US, "low": 5050 * US}


def test_overload_gives_no_bound_and_jitter_adds():
    over = [CanMessage("a", 1, 1 * MS, 600 * US), CanMessage("b", 2, 1 * MS, 600 * US)]
    res = {r.name: r for r in can_analysis(over)}
    assert res["a"].response_ns is not None
    assert res["b"].response_ns is None and not res["b"].schedulable
    # a jitter of 0.3 ms on the only message adds exactly 0.3 ms to its response (R = J + C)
    assert can_response_times([CanMessage("j", 1, 10 * MS, 1 * MS, jitter_ns=300 * US)]) == {"j": 1300 * US}


def test_bad_message_set_is_rejected():
    with pytest.raises(ValueError, match="unique"):
        can_analysis([CanMessage("x", 1, MS, MS), CanMessage("x", 2, MS, MS)])
    with pytest.raises(ValueError, match="period"):
        can_analysis([CanMessage("x", 1, 0, MS)])
