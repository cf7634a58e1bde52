"""Release jitter, sporadic tasks, abort on deadline miss and run-time task parameters (issue 20).

Every expected time is computed in the test: jitters and gaps from the task's own random stream
(``env.rng("kernel.<node>.release.<task>")``, drawn in the kernel's order), schedules by hand.
"""

from __future__ import annotations

import pytest

from netsim.env import SimEnv
from netsim.errors import BuildError, SimulationError
from netsim.kernel import ExecTime, Kernel
from netsim.kernel.task import TaskSpec
from netsim.timebase import MS


def _body(c: int):
    def body(job):
        yield job.execute(c)
    return body


def _records(k: Kernel, task: str) -> list:
    return sorted((r for r in k.job_records if r.task == task), key=lambda r: r.job_id)


def test_jittered_arrivals_follow_the_tasks_own_stream_and_count_from_the_nominal_release():
    env = SimEnv(seed=7)
    k = Kernel(env, "n", policy="fp")
    k.add_task(TaskSpec("a", period=10 * MS, priority=1, release_jitter=ExecTime.uniform(0, 3 * MS)), _body(MS))
    env.run(100 * MS)
    rng = SimEnv(seed=7).rng("kernel.n.release.a")  # the same stream, drawn as the kernel does (one per release)
    expected = [int(rng.integers(0, 3 * MS + 1)) for _ in range(10)]
    recs = _records(k, "a")
    assert [r.release for r in recs] == [i * 10 * MS for i in range(10)]  # nominal releases
    assert [r.arrival - r.release for r in recs] == expected
    assert [r.release_jitter for r in recs] == expected
    for r in recs:  # alone on the CPU: starts at its arrival, runs 1 ms
        assert r.start == r.arrival and r.finish == r.arrival + MS
        assert r.response == r.finish - r.release  # from the nominal release (what RTA bounds by J + w)
        assert r.response_from_arrival == MS
        assert r.deadline == r.release + 10 * MS


def test_jitter_of_one_task_changes_no_draw_of_another():
    def run(jitter_b: bool) -> list[int]:
        env = SimEnv(seed=3)
        k = Kernel(env, "n", policy="fp")
        k.add_task(TaskSpec("a", period=10 * MS, priority=1, release_jitter=ExecTime.uniform(0, 2 * MS)), _body(MS))
        k.add_task(TaskSpec("b", period=7 * MS, priority=2,
                            release_jitter=ExecTime.uniform(0, MS) if jitter_b else None), _body(MS))
        env.run(60 * MS)
        return [r.arrival for r in _records(k, "a")]

    assert run(False) == run(True)


def test_a_task_without_jitter_has_no_arrival():
    env = SimEnv(seed=1)
    k = Kernel(env, "n", policy="fp")
    k.add_task(TaskSpec("a", period=10 * MS, priority=1), _body(MS))
    env.run(25 * MS)
    assert [r.arrival for r in k.job_records] == [None] * 3
    assert [(r.release_jitter, r.response_from_arrival) for r in k.job_records] == [(None, None)] * 3


def test_sporadic_arrivals_are_the_minimum_plus_the_drawn_extra_gap():
    env = SimEnv(seed=11)
    k = Kernel(env, "n", policy="fp")
    k.add_task(TaskSpec("s", min_interarrival=7 * MS, offset=2 * MS, priority=1,
                        extra_interarrival=ExecTime.exponential(3 * MS)), _body(MS))
    env.run(200 * MS)
    rng = SimEnv(seed=11).rng("kernel.n.release.s")
    releases = [2 * MS]
    while True:
        nxt = releases[-1] + 7 * MS + int(round(float(rng.exponential(float(3 * MS)))))
        if nxt > 200 * MS:
            break
        releases.append(nxt)
    recs = _records(k, "s")
    assert [r.release for r in recs] == releases
    assert all(b - a >= 7 * MS for a, b in zip(releases, releases[1:]))
    assert {r.deadline - r.release for r in recs} == {7 * MS}  # the deadline defaults to the minimum gap
    assert all(r.arrival is None for r in recs)


def test_sporadic_without_extra_is_periodic_at_the_minimum():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="dm")
    k.add_task(TaskSpec("s", min_interarrival=5 * MS), _body(MS))
    env.run(20 * MS)
    assert [r.release for r in _records(k, "s")] == [0, 5 * MS, 10 * MS, 15 * MS, 20 * MS]


def test_abort_on_miss_kills_the_job_at_its_deadline_after_its_handler():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")
    seen = []
    # a: C = 3 ms, D = 2 ms, T = 5 ms: every job is killed at release + 2 ms; b (lower priority) then runs
    k.add_task(TaskSpec("a", period=5 * MS, deadline=2 * MS, priority=1, abort_on_miss=True,
                        deadline_handler=lambda job: seen.append((job.job_id, job.now, job.done))), _body(3 * MS))
    k.add_task(TaskSpec("b", period=10 * MS, priority=2), _body(MS))
    env.run(10 * MS)
    a = _records(k, "a")
    assert [(r.release, r.finish, r.killed, r.deadline_met, r.response) for r in a[:2]] == [
        (0, 2 * MS, True, False, None), (5 * MS, 7 * MS, True, False, None)]
    assert [r.cpu_time for r in a[:2]] == [2 * MS, 2 * MS]
    assert seen[:2] == [(0, 2 * MS, False), (1, 7 * MS, False)]  # the handler sees the job before it is killed
    b = _records(k, "b")[0]
    assert (b.start, b.finish) == (2 * MS, 3 * MS)


def test_a_job_finishing_at_its_deadline_is_not_aborted():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")
    k.add_task(TaskSpec("a", period=5 * MS, deadline=2 * MS, priority=1, abort_on_miss=True), _body(2 * MS))
    env.run(4 * MS)
    r = _records(k, "a")[0]
    assert (r.finish, r.killed, r.deadline_met) == (2 * MS, False, True)


def test_set_period_moves_the_next_release_to_one_new_period_after_the_last():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")
    k.add_task(TaskSpec("a", period=10 * MS, priority=1), _body(MS))
    k.add_task(TaskSpec("late", period=100 * MS, offset=5 * MS, priority=2, deadline=100 * MS),
               _body(MS))
    env.run(12 * MS)  # a released at 0 and 10 ms; next planned at 20 ms
    k.set_period("a", 4 * MS)
    env.run(30 * MS)
    assert [r.release for r in _records(k, "a")] == [t * MS for t in (0, 10, 14, 18, 22, 26, 30)]


def test_set_period_is_in_effect_at_once_and_before_the_first_release():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="rm")
    k.add_task(TaskSpec("a", period=10 * MS, offset=5 * MS), _body(MS))
    env.run(1 * MS)
    k.set_period("a", 3 * MS)  # the first release stays at the offset
    env.run(12 * MS)
    recs = _records(k, "a")
    assert [r.release for r in recs] == [5 * MS, 8 * MS, 11 * MS]
    assert {r.deadline - r.release for r in recs} == {3 * MS}  # the implicit deadline follows the period
    env2 = SimEnv(seed=0)
    k2 = Kernel(env2, "n", policy="fp")
    k2.add_task(TaskSpec("a", period=10 * MS, priority=1), _body(MS))
    env2.run(9 * MS)
    now = k2.now
    k2.set_period("a", 2 * MS)  # one new period after the last release (0) has passed: released now
    env2.run(12 * MS)
    assert [r.release for r in _records(k2, "a")] == [0, now, now + 2 * MS]


def test_set_priority_re_dispatches_at_once():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")
    k.add_task(TaskSpec("a", priority=1), _body(5 * MS))
    k.add_task(TaskSpec("b", priority=2), _body(MS))

    def raise_b(job):
        job.kernel.set_priority("b", 0)
        return
        yield

    k.create_handler("h", raise_b)
    k.create_timer("t", "h", start=2 * MS)
    k.create_job("a")
    k.create_job("b")
    env.run(10 * MS)
    a, b = _records(k, "a")[0], _records(k, "b")[0]
    # a runs 0-2 ms, b (now more urgent) preempts it at 2 ms and runs 2-3 ms, a resumes and ends at 6 ms
    assert (b.start, b.finish) == (2 * MS, 3 * MS)
    assert (a.finish, a.preemptions) == (6 * MS, 1)
    assert k.tasks["b"].spec.priority == 0


def test_set_priority_from_the_running_job_yields_the_cpu():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")

    def humble(job):
        yield job.execute(MS)
        job.kernel.set_priority("a", 5)
        yield job.execute(MS)

    k.add_task(TaskSpec("a", priority=1), humble)
    k.add_task(TaskSpec("b", priority=2), _body(MS))
    k.create_job("a")
    k.create_job("b")
    env.run(10 * MS)
    a, b = _records(k, "a")[0], _records(k, "b")[0]
    assert (b.start, b.finish, a.finish) == (MS, 2 * MS, 3 * MS)


def test_set_deadline_applies_to_later_jobs():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="edf")
    k.add_task(TaskSpec("a", period=10 * MS), _body(MS))
    env.run(5 * MS)
    k.set_deadline("a", 4 * MS)
    env.run(20 * MS)
    assert [r.deadline - r.release for r in _records(k, "a")] == [10 * MS, 4 * MS, 4 * MS]


@pytest.mark.parametrize("call, message", [
    (lambda k: k.set_period("s", MS), "not periodic"),
    (lambda k: k.set_period("a", 0), "positive"),
    (lambda k: k.set_priority("a", "high"), "must be a number"),
    (lambda k: k.set_deadline("nope", MS), "no task 'nope'"),
])
def test_run_time_changes_refuse_bad_values(call, message):
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")
    k.add_task(TaskSpec("a", period=10 * MS, priority=1), _body(MS))
    k.add_task(TaskSpec("s", priority=1), _body(MS))
    with pytest.raises(SimulationError, match=message):
        call(k)


@pytest.mark.parametrize("fields, field", [
    ({"release_jitter": ExecTime.constant(MS)}, "release_jitter"),  # aperiodic
    ({"period": 10 * MS, "min_interarrival": 5 * MS}, "min_interarrival"),
    ({"extra_interarrival": ExecTime.constant(MS)}, "extra_interarrival"),
    ({"abort_on_miss": True}, "abort_on_miss"),  # aperiodic without a deadline
    ({"period": 10 * MS, "release_jitter": -1}, "release_jitter"),
    ({"min_interarrival": 0}, "min_interarrival"),
])
def test_task_spec_refuses_inconsistent_arrival_fields(fields, field):
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")
    with pytest.raises(BuildError) as info:
        k.add_task(TaskSpec("a", priority=1, **fields), _body(MS))
    assert info.value.field == field


def test_a_new_priority_holds_for_later_jobs_of_a_periodic_task():
    env = SimEnv(seed=0)
    k = Kernel(env, "n", policy="fp")
    k.add_task(TaskSpec("a", period=10 * MS, priority=1), _body(2 * MS))
    k.add_task(TaskSpec("b", period=10 * MS, priority=2), _body(2 * MS))
    env.run(5 * MS)  # a ran first (0-2 ms), then b (2-4 ms)
    k.set_priority("a", 3)  # from now on b is the more urgent
    env.run(25 * MS)
    a, b = _records(k, "a"), _records(k, "b")
    assert [(r.start, r.finish) for r in a] == [(0, 2 * MS), (12 * MS, 14 * MS), (22 * MS, 24 * MS)]
    assert [(r.start, r.finish) for r in b] == [(2 * MS, 4 * MS), (10 * MS, 12 * MS), (20 * MS, 22 * MS)]
