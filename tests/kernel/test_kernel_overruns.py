"""WCET and deadline overrun handlers, killing jobs, context-switch accounting."""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.kernel import Kernel
from netsim.timebase import MS, US


def body_of(*durations):
    def body(job):
        for d in durations:
            yield job.execute(d)

    return body


def test_wcet_handler_fires_when_budget_is_exhausted_and_job_continues():
    # Budget 2 ms, demand 3 ms in three 1 ms pieces, released at 1 ms, alone: overrun at 3 ms, finish at 4 ms.
    fired = []
    env = SimEnv()
    k = Kernel(env, "n")

    def on_wcet(job):
        fired.append((job.now, job.data.task_name, job.data.cpu_time))
        yield job.execute(0)

    k.create_handler("wcet_h", on_wcet)
    k.create_task("t", body_of(1 * MS, 1 * MS, 1 * MS), period=10 * MS, offset=1 * MS, priority=1, wcet=2 * MS,
                  wcet_handler="wcet_h")
    env.run(5 * MS)
    assert fired == [(3 * MS, "t", 2 * MS)]
    rec = k.job_records[0]
    assert rec.finish == 4 * MS and not rec.killed


def test_wcet_budget_counts_execution_only_not_preemption():
    # L: budget 2 ms, demand 3 ms from 0; H runs 1-2 ms: L has executed 2 ms at t = 3 ms -> overrun then.
    fired = []
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("L", body_of(3 * MS), period=20 * MS, priority=2, wcet=2 * MS,
                  wcet_handler=lambda job: fired.append(job.now))
    k.create_task("H", body_of(1 * MS), period=20 * MS, offset=1 * MS, priority=1)
    env.run(10 * MS)
    assert fired == [3 * MS]
    assert next(r for r in k.job_records if r.task == "L").finish == 4 * MS


def test_job_using_exactly_its_budget_does_not_overrun():
    fired = []
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("t", body_of(1 * MS, 1 * MS), period=10 * MS, priority=1, wcet=2 * MS,
                  wcet_handler=lambda job: fired.append(job.now))
    env.run(5 * MS)
    assert fired == []
    assert k.job_records[0].finish == 2 * MS


def test_deadline_handler_fires_at_the_deadline_and_can_kill_freeing_the_cpu():
    # T: 3 ms demand, deadline 2.5 ms, killed by its deadline handler at 2.5 ms; L (lower) starts then.
    env = SimEnv()
    k = Kernel(env, "n")
    at = []

    def on_miss(job):
        at.append(job.now)
        yield job.kill(job.data)

    k.create_handler("miss", on_miss)
    k.create_task("T", body_of(3 * MS), period=10 * MS, deadline=2500 * US, priority=1, deadline_handler="miss")
    k.create_task("L", body_of(1 * MS), period=10 * MS, priority=2)
    env.run(5 * MS)
    assert at == [2500 * US]
    rec = {r.task: r for r in k.job_records}
    assert rec["T"].killed and rec["T"].finish == 2500 * US and rec["T"].cpu_time == 2500 * US
    assert rec["T"].deadline_met is False and rec["T"].response is None  # killed: never completed, a miss
    assert rec["L"].start == 2500 * US and rec["L"].finish == 3500 * US


def test_deadline_handler_does_not_fire_when_job_finishes_exactly_at_deadline():
    fired = []
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("T", body_of(2500 * US), period=10 * MS, deadline=2500 * US, priority=1,
                  deadline_handler=lambda job: fired.append(job.now))
    env.run(5 * MS)
    assert fired == []
    assert k.job_records[0].deadline_met is True


def test_deadline_miss_without_kill_lets_job_continue():
    fired = []
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("T", body_of(3 * MS), period=10 * MS, deadline=2 * MS, priority=1,
                  deadline_handler=lambda job: fired.append(job.now))
    env.run(5 * MS)
    assert fired == [2 * MS]
    rec = k.job_records[0]
    assert rec.finish == 3 * MS and rec.deadline_met is False and not rec.killed


def test_kill_job_from_outside_frees_cpu_and_starts_next_queued_job():
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_task("T", body_of(5 * MS), priority=1)
    first = k.create_job("T", data=1)
    k.create_job("T", data=2)

    def killer():
        yield env.timeout(2 * MS)
        k.kill_job(first)

    env.process(killer())
    env.run(10 * MS)
    recs = sorted(k.job_records, key=lambda r: r.job_id)
    assert (recs[0].killed, recs[0].finish, recs[0].cpu_time) == (True, 2 * MS, 2 * MS)
    assert (recs[1].start, recs[1].finish, recs[1].killed) == (2 * MS, 7 * MS, False)


def test_job_can_kill_itself():
    after = []
    env = SimEnv()
    k = Kernel(env, "n")

    def body(job):
        yield job.execute(1 * MS)
        yield job.kill()
        after.append("not reached")

    k.create_task("T", body, period=10 * MS, priority=1)
    env.run(5 * MS)
    assert after == []
    assert k.job_records[0].killed and k.job_records[0].finish == 1 * MS


def test_context_switch_cost_is_charged_at_release_preemption_and_resumption():
    # cs = 100 us. T2 (prio 2, 3 ms) from 0, T1 (prio 1, 1 ms) at 1 ms. By hand: T2 cs 0-0.1, runs 0.1-1.0;
    # T1 cs 1.0-1.1, runs 1.1-2.1 (finish); T2 cs 2.1-2.2, runs 2.2-4.3 (finish).
    env = SimEnv()
    k = Kernel(env, "n", context_switch=100 * US)
    k.create_task("T2", body_of(3 * MS), period=50 * MS, priority=2)
    k.create_task("T1", body_of(1 * MS), period=50 * MS, offset=1 * MS, priority=1)
    env.run(10 * MS)
    rec = {r.task: r for r in k.job_records}
    assert rec["T1"].finish == 2100 * US and rec["T1"].cpu_time == 1100 * US
    assert rec["T2"].finish == 4300 * US and rec["T2"].cpu_time == 3200 * US
    assert k.cpu_time == {"T1": 1100 * US, "T2": 3200 * US}
    assert k.switches == 3 and k.switch_time == 300 * US
    assert k.utilization(0, 4300 * US) == pytest.approx(1.0)


def test_handler_interrupting_a_task_causes_no_context_switch():
    # cs = 100 us; task 1 ms from 0; ISR 100 us at 0.5 ms: task = 0.1 (cs) + 1.0 + 0.1 (ISR) -> ends 1.2 ms.
    env = SimEnv()
    k = Kernel(env, "n", context_switch=100 * US)
    k.create_task("T", body_of(1 * MS), period=50 * MS, priority=1)

    def isr(job):
        yield job.execute(100 * US)

    k.create_handler("isr", isr)
    k.create_timer("once", "isr", start=500 * US)
    env.run(5 * MS)
    rec = k.job_records[0]
    assert rec.finish == 1200 * US and rec.cpu_time == 1100 * US and rec.preemptions == 1
    assert k.switches == 1
