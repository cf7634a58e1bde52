"""Response-time analysis and the EDF processor-demand test against hand-computed examples."""

from __future__ import annotations

import pytest

from netsim.analysis.rta import (RTATask, busy_period, deadline_monotonic, edf_demand, edf_schedulable,
                                 fp_schedulable, hyperperiod, rate_monotonic, response_times, utilization)
from netsim.errors import ConfigError


def test_textbook_rate_monotonic_set_3_6_20():
    # (3,7), (3,12), (5,20): R1 = 3; R2 = 3 + ceil(6/7)*3 = 6; R3 = 5 + ceil(R/7)*3 + ceil(R/12)*3 -> 20
    # (R = 20: ceil(20/7) = 3 -> 9, ceil(20/12) = 2 -> 6; 5 + 9 + 6 = 20).
    tasks = rate_monotonic([RTATask("c", 5, 20), RTATask("a", 3, 7), RTATask("b", 3, 12)])
    assert response_times(tasks) == {"c": 20, "a": 3, "b": 6}
    assert fp_schedulable(tasks)


def test_rm_miss_of_second_task():
    # (2,5), (4,7): R2 = 4 + ceil(R/5)*2 -> 6 -> 8 (ceil(8/5) = 2), 8 > 7.
    tasks = rate_monotonic([RTATask("t1", 2, 5), RTATask("t2", 4, 7)])
    assert response_times(tasks)["t2"] == 8
    assert not fp_schedulable(tasks)


def test_release_jitter_of_higher_priority_task_adds_interference():
    # hp: C=1, T=4, J=2; lp: C=2, T=10. w = 2 + ceil((w + 2)/4) -> 2, 3, 4, 4: R = 4.
    # Without jitter: w = 2 + ceil(w/4) -> 3.
    hp = RTATask("hp", 1, 4, jitter=2, priority=0)
    lp = RTATask("lp", 2, 10, priority=1)
    assert response_times([hp, lp])["lp"] == 4
    assert response_times([RTATask("hp", 1, 4, priority=0), lp])["lp"] == 3
    # the task's own jitter adds to its response: R_hp = J + C = 3
    assert response_times([hp, lp])["hp"] == 3


def test_blocking_term_adds_to_the_busy_window():
    # lp with B = 1: w = 3 + ceil(w/4) -> 3, 4, 4: R = 4.
    tasks = [RTATask("hp", 1, 4, priority=0), RTATask("lp", 2, 10, blocking=1, priority=1)]
    assert response_times(tasks)["lp"] == 4


def test_deadline_beyond_period_uses_several_jobs_of_the_busy_window():
    # t1 (3, 5), t2 (3, 8, D=16): q=0: w = 3 + 3 ceil(w/5) -> 9, R = 9 > 8 so q=1: w = 6 + 3 ceil(w/5) -> 15,
    # R = 15 - 8 = 7 <= 8: stop. Worst = 9 (hand schedule in tests/kernel/test_kernel_scheduling.py).
    tasks = [RTATask("t1", 3, 5, priority=1), RTATask("t2", 3, 8, deadline=16, priority=2)]
    assert response_times(tasks) == {"t1": 3, "t2": 9}


def test_overloaded_level_is_unbounded():
    tasks = [RTATask("a", 3, 5, priority=0), RTATask("b", 3, 6, priority=1)]
    assert response_times(tasks)["b"] is None
    assert not fp_schedulable(tasks)


def test_equal_priorities_interfere_conservatively():
    tasks = [RTATask("a", 1, 10, priority=1), RTATask("b", 2, 10, priority=1)]
    assert response_times(tasks) == {"a": 3, "b": 3}


def test_deadline_monotonic_assignment():
    tasks = deadline_monotonic([RTATask("a", 1, 10, deadline=3), RTATask("b", 1, 5)])
    assert [t.priority for t in tasks] == [0, 1]


def test_edf_processor_demand():
    # (2,5),(4,7): U = 0.971 <= 1 with implicit deadlines: schedulable.
    assert edf_schedulable([RTATask("a", 2, 5), RTATask("b", 4, 7)])
    # U > 1
    assert not edf_schedulable([RTATask("a", 3, 5), RTATask("b", 4, 7)])
    # constrained: (C=2, T=5, D=2), (C=2, T=5, D=3): dbf(3) = 2 + 2 = 4 > 3.
    tasks = [RTATask("a", 2, 5, deadline=2), RTATask("b", 2, 5, deadline=3)]
    assert edf_demand(tasks, 2) == 2 and edf_demand(tasks, 3) == 4
    assert not edf_schedulable(tasks)
    assert edf_schedulable([RTATask("a", 1, 5, deadline=2), RTATask("b", 1, 5, deadline=3)])


def test_helpers():
    assert hyperperiod([7, 12, 20]) == 420
    assert utilization([RTATask("a", 1, 4), RTATask("b", 1, 2)]) == pytest.approx(0.75)
    # synchronous busy period of (2,5),(4,7): w = 6 -> 2*2 + 4 = 8 -> 2*2 + 2*4 = 12 -> 3*2 + 2*4 = 14 -> 14
    assert busy_period([RTATask("a", 2, 5), RTATask("b", 4, 7)]) == 14


def test_bad_tasks_are_rejected():
    with pytest.raises(ConfigError, match="period"):
        RTATask("x", 1, 0)
    with pytest.raises(ConfigError, match="wcet"):
        RTATask("x", -1, 5)
    with pytest.raises(ConfigError, match="no priority"):
        response_times([RTATask("a", 1, 5, priority=1), RTATask("b", 1, 5)])
