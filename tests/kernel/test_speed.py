"""CPU speed scaling (netsim.kernel.speed): execution stretched by the speed, exact over a change mid-segment.

Every expected time is worked out by hand in the comment next to it (ms = 1_000_000 ns).
"""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import BuildError, SimulationError
from netsim.kernel import Kernel
from netsim.timebase import MS


def _one_job(speed: float, work: int) -> Kernel:
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", speed=speed)

    def body(job):
        yield job.execute(work)

    k.create_task("t", body, priority=1)
    k.create_job("t")
    env.run(20 * MS)
    return k


def test_a_4_ms_job_at_half_speed_finishes_at_8_ms():
    # w / s = 4 ms / 0.5 = 8 ms; its CPU time is the wall time it held the CPU
    rec = _one_job(0.5, 4 * MS).job_records[0]
    assert rec.finish == 8 * MS and rec.cpu_time == 8 * MS


def test_a_segment_length_is_rounded_up_to_whole_ns():
    # 0.3 is 3/10: 1_000_001 ns of work take ceil(1_000_001 * 10 / 3) = ceil(3_333_336.67) = 3_333_337 ns
    assert _one_job(0.3, 1_000_001).job_records[0].finish == 3_333_337


def test_a_speed_change_mid_segment_charges_the_work_done_and_replans_the_rest():
    # A 4 ms job starts at speed 0.5 at t = 0. A handler at t = 2 ms sets speed 1: in [0, 2] ms the job did
    # 2 * 0.5 = 1 ms of work, 3 ms are left, done at speed 1 by 2 + 3 = 5 ms (the handler takes no time).
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", speed=0.5)

    def body(job):
        yield job.execute(4 * MS)

    def governor(job):
        yield job.set_speed(1.0)

    k.create_task("t", body, priority=1)
    k.create_handler("gov", governor)
    k.create_timer("at2", "gov", start=2 * MS)
    k.create_job("t")
    env.run(20 * MS)
    rec = k.job_records[0]
    assert rec.finish == 5 * MS and rec.cpu_time == 5 * MS and rec.preemptions == 1
    assert k.speed == 1.0
    assert k.busy_by_speed() == {0.5: 2 * MS, 1.0: 3 * MS}


def test_a_job_that_changes_the_speed_between_its_executes():
    # execute(2 ms) at 0.5 takes 4 ms; set_speed(1); execute(2 ms) takes 2 ms: finish at 6 ms
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", speed=0.5, speed_levels=[0.5, 1.0])

    def body(job):
        yield job.execute(2 * MS)
        yield job.set_speed(1.0)
        yield job.execute(2 * MS)

    k.create_task("t", body, priority=1)
    k.create_job("t")
    env.run(20 * MS)
    assert k.job_records[0].finish == 6 * MS


def test_speed_is_refused_outside_its_range_and_its_levels():
    with pytest.raises(BuildError, match=r"outside \(0, 1\]"):
        Kernel(SimEnv(), "cpu", speed=1.5)
    with pytest.raises(BuildError, match="not one of speed_levels"):
        Kernel(SimEnv(), "cpu", speed=0.7, speed_levels=[0.5, 1.0])
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp", speed=1.0, speed_levels=[0.5, 1.0])

    def body(job):
        yield job.set_speed(0.25)

    k.create_task("t", body, priority=1)
    k.create_job("t")
    with pytest.raises(SimulationError, match="not one of speed_levels"):
        env.run(MS)


def test_set_speed_on_a_node_without_speed_scaling_says_what_to_add():
    env = SimEnv()
    k = Kernel(env, "cpu", policy="fp")

    def body(job):
        yield job.set_speed(0.5)

    k.create_task("t", body, priority=1)
    k.create_job("t")
    with pytest.raises(SimulationError, match=r"nodes\.cpu\.speed"):
        env.run(MS)
