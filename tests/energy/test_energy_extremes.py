"""Extreme but valid energy models (h14f, issue 14's standard for issue 20's batteries): a tiny power with a
battery never overflows the next battery check, and the node keeps running."""

from __future__ import annotations

import pytest

from netsim.energy import EnergyMeter, EnergyModel
from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.timebase import MS, S


def _body(job):
    yield job.execute(2 * MS)


@pytest.mark.parametrize("busy, capacity", [("1e-300 W", "1 J"), (5e-324, "1 J"), ("1e-15 W", "1e15 J")])
def test_a_battery_that_a_tiny_power_cannot_empty_adds_no_check_and_no_overflow(busy, capacity):
    """capacity / power is beyond netsim's time range (1 J / 1e-300 W = 1e300 s; the denormal power gives an
    infinite time): the battery cannot run out in any run, so the first check schedules no other one
    (before: OverflowError converting infinity to an integer time, or a check beyond MAX_TIME)."""
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("T", _body, period=10 * MS, priority=1)
    model = EnergyModel.model_validate({"cpu": {"busy": busy}, "battery": {"capacity": capacity}})
    meter = EnergyMeter(env, "n", k, model, [])
    env.run(1 * S)
    assert meter.checks == 1 and meter.depleted_ns is None
    # releases at 0, 10, ..., 1000 ms (the run includes its end instant): 101 jobs, none killed
    assert len(k.job_records) == 101 and not any(r.killed for r in k.job_records)


def test_a_huge_power_still_empties_a_tiny_battery_at_once():
    """1e15 W busy and idle against 1e-15 J: 1e-30 s of use, below a nanosecond: depleted at the first check."""
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("T", _body, period=10 * MS, priority=1)
    model = EnergyModel.model_validate({"cpu": {"busy": 1e15, "idle": 1e15}, "battery": {"capacity": "1e-15 J"}})
    meter = EnergyMeter(env, "n", k, model, [])
    env.run(1 * S)
    assert meter.checks == 1 and meter.depleted_ns == 0
