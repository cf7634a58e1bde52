"""CPU energy under speed scaling and on several cores: the integral of the stated power law, by hand."""

from __future__ import annotations

import pytest

from netsim.energy.meter import EnergyMeter
from netsim.energy.params import EnergyModel
from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.timebase import MS

# busy 50 mW at full speed, of which static 10 mW; idle 2 mW; exponent 3 (the default):
#   P_busy(0.5) = 0.010 + 0.040 * 0.5**3 = 0.015 W,  P_busy(1) = 0.050 W
MODEL = {"cpu": {"busy": 0.05, "idle": 0.002, "static": 0.01}}


def _meter(env: SimEnv, k: Kernel) -> EnergyMeter:
    return EnergyMeter(env, k.name, k, EnergyModel.model_validate(MODEL), [])


def _body(work: int):
    def body(job):
        yield job.execute(work)
    return body


def test_energy_of_a_half_speed_job_is_the_power_law_times_its_time():
    # a 4 ms job at speed 0.5 is busy [0, 8] ms, then idle to 10 ms:
    #   E = 0.015 W * 8 ms + 0.002 W * 2 ms = 1.2e-4 + 4e-6 = 1.24e-4 J
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", speed=0.5)
    k.create_task("t", _body(4 * MS), priority=1)
    k.create_job("t")
    meter = _meter(env, k)
    env.run(10 * MS)
    assert meter.energy(10 * MS) == pytest.approx(1.24e-4, rel=1e-12)


def test_energy_across_a_speed_change_sums_each_speed_s_busy_time():
    # 4 ms job at 0.5 from 0; speed 1 at 2 ms: busy at 0.5 for 2 ms, at 1 for 3 ms (finish 5 ms), idle 5 ms:
    #   E = 0.015 * 2e-3 + 0.050 * 3e-3 + 0.002 * 5e-3 = 3e-5 + 1.5e-4 + 1e-5 = 1.9e-4 J
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", speed=0.5)

    def governor(job):
        yield job.set_speed(1.0)

    k.create_task("t", _body(4 * MS), priority=1)
    k.create_handler("gov", governor)
    k.create_timer("at2", "gov", start=2 * MS)
    k.create_job("t")
    meter = _meter(env, k)
    env.run(10 * MS)
    assert meter.energy(10 * MS) == pytest.approx(1.9e-4, rel=1e-12)


def test_two_cores_idle_and_busy_each_at_the_per_core_powers():
    # two 3 ms jobs on two cores at speed 1, 10 ms: 6 core-ms busy, 14 core-ms idle:
    #   E = 0.050 * 6e-3 + 0.002 * 14e-3 = 3e-4 + 2.8e-5 = 3.28e-4 J
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", cores=2)
    k.create_task("a", _body(3 * MS), priority=1)
    k.create_task("b", _body(3 * MS), priority=2)
    k.create_job("a")
    k.create_job("b")
    meter = _meter(env, k)
    env.run(10 * MS)
    assert meter.energy(10 * MS) == pytest.approx(3.28e-4, rel=1e-12)


def test_static_power_above_busy_is_refused():
    with pytest.raises(ValueError, match="static"):
        EnergyModel.model_validate({"cpu": {"busy": 0.01, "static": 0.02}})
