"""Periodic interrupt loads accounted in closed form (Kernel.create_periodic_load).

The reference everywhere is the same node with an explicit handler of the same execution time invoked by a
periodic timer (the faithful, slow model): the load must give identical job records, CPU times and
utilization.
"""

from __future__ import annotations

import random
from typing import Any

import pytest

from netsim.analysis.rta import RTATask, response_times
from netsim.env import SimEnv
from netsim.errors import BuildError
from netsim.kernel import Kernel, PeriodicLoad
from netsim.timebase import MS, S, US


def _records(k: Kernel) -> list[tuple[Any, ...]]:
    return sorted((r.task, r.job_id, r.release, r.start, r.finish, r.response, r.deadline_met, r.preemptions,
                   r.cpu_time, r.killed) for r in k.job_records)


def _task_set(k: Kernel, log: list[tuple[str, int, int]]) -> None:
    """Five tasks with offsets off and on the tick grid, a sleep in one body, execution times that are not
    multiples of the free time per period (so segments end at every phase of the windows); the most urgent
    one is released 4 us after ticks of the grid starting at 0 (inside windows of at least 5 us), so it
    finds the CPU taken by a window and preempts the job that window interrupted."""

    def body(c: int, sleep: int | None = None):
        def run(job):
            log.append((job.task_name, job.job_id, job.now))
            yield job.execute(c)
            if sleep is not None:
                yield job.sleep(sleep)
                log.append((job.task_name, job.job_id, job.now))
                yield job.execute(c // 2 + 3)

        return run

    k.create_task("a", body(130 * US), period=1 * MS, priority=1)
    k.create_task("b", body(370 * US, sleep=55 * US + 3), period=3 * MS, offset=150 * US, priority=2)
    k.create_task("c", body(1210 * US + 1), period=7 * MS, priority=3)
    k.create_task("d", body(333 * US + 7), period=10 * MS, offset=1234 * US + 5, priority=4)
    k.create_task("z", body(21 * US), period=2 * MS + 100 * US, offset=4 * US, priority=0)


def _node(load: bool, *, period: int, execution: int, start: int = 0, policy: str = "fp",
          context_switch: int = 0, horizon: int = 2 * S) -> tuple[Kernel, list[tuple[str, int, int]]]:
    env = SimEnv(seed=1)
    k = Kernel(env, "n", policy=policy, context_switch=context_switch)
    log: list[tuple[str, int, int]] = []
    _task_set(k, log)
    if load:
        k.create_periodic_load("isr", period=period, execution=execution, start=start)
    else:
        def isr(job):
            yield job.execute(execution)

        k.create_handler("isr", isr, priority=0)
        k.create_timer("tick", "isr", period=period, start=start)
    env.run(horizon)
    return k, log


@pytest.mark.parametrize("policy,context_switch,start", [("fp", 0, 0), ("fp", 3 * US, 37 * US + 1),
                                                         ("edf", 2 * US + 1, 0)])
def test_load_gives_the_job_records_of_an_explicit_10khz_handler(policy, context_switch, start):
    # 10 kHz, 9 us per tick (9 % of the CPU), 2 simulated seconds: 20 000 handler invocations in the explicit
    # model, several tasks with preemptions by each other and by every tick.
    explicit, log_e = _node(False, period=100 * US, execution=9 * US, start=start, policy=policy,
                            context_switch=context_switch)
    analytic, log_a = _node(True, period=100 * US, execution=9 * US, start=start, policy=policy,
                            context_switch=context_switch)
    rec_e, rec_a = _records(explicit), _records(analytic)
    assert len(rec_e) > 2000
    assert rec_a == rec_e
    # the instants at which job code ran (start of each job, after each sleep) are the same
    assert sorted(log_a) == sorted(log_e)
    # the set really exercises preemptions by tasks and by ticks, and windows delaying starts
    assert sum(r[7] for r in rec_e) > 10_000
    assert any(r[3] != r[2] for r in rec_e)
    assert analytic.cpu_time == explicit.cpu_time
    assert analytic.switch_time == explicit.switch_time and analytic.switches == explicit.switches
    assert analytic.utilization() == pytest.approx(explicit.utilization(), abs=1e-15)
    for t0, t1 in ((0, 1 * MS), (123_457, 777_777), (1 * S + 4 * US, 2 * S)):
        assert analytic.utilization(t0, t1) == pytest.approx(explicit.utilization(t0, t1), abs=1e-15)
    # the closed form costs far fewer segments than one handler invocation per tick
    assert analytic.segments < explicit.segments / 3


def test_load_cpu_time_is_execution_times_windows_with_the_last_one_partial():
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_periodic_load("isr", period=10 * US, execution=3 * US, start=5 * US)
    env.run(1 * MS + 6 * US)
    # ticks at 5, 15, ..., 1005 us: 100 full windows up to 995 us + 3 us, and the window at 1005 us has run
    # 1 us of its 3 us at t = 1006 us
    assert k.cpu_time["isr"] == 100 * 3 * US + 1 * US
    assert k.utilization() == pytest.approx((300 + 1) / 1006)


def test_real_handler_at_ticks_is_the_window_not_extra_cpu():
    # An exact-mode sensor ISR: in the explicit model the handler runs at every tick and does its work at a few
    # of them; with the load it is invoked only at those ticks. Same stored values, same task records, same
    # CPU time of the handler.
    period, execution, horizon = 50 * US, 6 * US, 1 * S
    rnd = random.Random(4)
    work_ticks = sorted(j * period for j in range(horizon // period) if rnd.random() < 0.05)

    def node(load: bool) -> tuple[Kernel, list[int], list[tuple[str, int, int]]]:
        env = SimEnv(seed=1)
        k = Kernel(env, "n", context_switch=1 * US)
        log: list[tuple[str, int, int]] = []
        _task_set(k, log)
        stored: list[int] = []
        todo = set(work_ticks)

        def isr(job):
            if not load and job.now in todo:
                stored.append(job.now)
            elif load:
                stored.append(job.now)
            yield job.execute(execution)
            log.append(("isr-after", 0, job.now))

        k.create_handler("isr", isr, priority=0)
        if load:
            k.create_periodic_load("isr", period=period, execution=execution, handler="isr")

            def source():
                for t in work_ticks:
                    yield env.sim.timeout(t - env.sim.now)
                    k.invoke_handler("isr")

            env.sim.process(source())
        else:
            k.create_timer("tick", "isr", period=period)
        env.run(horizon)
        if not load:  # keep only the code instants of the working ticks, as the load model runs only those
            log = [e for e in log if e[0] != "isr-after" or e[2] - execution in todo]
        return k, stored, log

    explicit, stored_e, log_e = node(False)
    analytic, stored_a, log_a = node(True)
    assert stored_a == stored_e == [t for t in work_ticks if t <= horizon]
    assert _records(analytic) == _records(explicit)
    assert sorted(log_a) == sorted(log_e)
    # the handler's entry: execution x windows (20 000 windows start before 1 s; the one at 1 s has not run
    # yet at the end of the run), not more
    assert explicit.cpu_time["isr"] == (horizon // period) * execution
    assert analytic.cpu_time == explicit.cpu_time
    assert analytic.loads["isr"].real_invocations == len(stored_a)


def test_load_interference_equals_rta_for_a_1khz_control_task():
    # Issue 3: a 100 kHz ISR of 1 us under a 1 ms control task of 500 us: R = 500 + ceil(R / 10 us) * 1 us.
    # RTA with the ISR as the top-priority task; tasks released together at t = 0 (critical instant).
    env = SimEnv()
    k = Kernel(env, "ctrl")
    k.create_periodic_load("isr", period=10 * US, execution=1 * US)

    def body(c):
        def run(job):
            yield job.execute(c)

        return run

    k.create_task("control", body(500 * US), period=1 * MS, priority=1)
    k.create_task("logger", body(2 * MS), period=10 * MS, priority=2)
    env.run(100 * MS)
    rta = response_times([RTATask("isr", 1 * US, 10 * US, priority=0),
                          RTATask("control", 500 * US, 1 * MS, priority=1),
                          RTATask("logger", 2 * MS, 10 * MS, priority=2)])
    worst = {name: max(r.response for r in k.job_records if r.task == name and r.finish is not None)
             for name in ("control", "logger")}
    assert rta["control"] == 556 * US  # 500 + 56: the fixed point of R = 500 + ceil(R/10)
    assert worst == {"control": rta["control"], "logger": rta["logger"]}
    # each window inside a job's execution preempted it once: the control job spans windows at 0 (its first
    # segment starts at the end of that window), 10, ..., 550 us: 55 windows after its start
    first = next(r for r in k.job_records if r.task == "control" and r.job_id == 0)
    assert (first.start, first.finish, first.preemptions) == (1 * US, 556 * US, 55)


def _brute_finish(period: int, execution: int, start: int, a: int, demand: int) -> int:
    """Walk nanosecond by nanosecond: the CPU is free at t unless t is inside a window."""
    t, done = a, 0
    while done < demand:
        if not (t >= start and (t - start) % period < execution):
            done += 1
        t += 1
    return t


def test_closed_form_finish_and_free_time_match_a_nanosecond_walk():
    rnd = random.Random(7)
    for _ in range(300):
        period = rnd.randint(2, 40)
        execution = rnd.randint(1, period - 1)
        start = rnd.randint(0, 50)
        load = PeriodicLoad("l", period, execution, start)
        a = rnd.randint(0, 120)
        demand = rnd.randint(0, 150)
        end = load.finish(a, demand)
        assert end == _brute_finish(period, execution, start, a, demand)
        b = a + rnd.randint(0, 150)
        walk = sum(1 for t in range(a, b) if not (t >= start and (t - start) % period < execution))
        assert load.free(a, b) == walk
        assert load.ticks_in(a, b) == sum(1 for t in range(a, b) if t >= start and (t - start) % period == 0)
        inside = a >= start and (a - start) % period < execution
        assert (load.window_end(a) > 0) == inside


def test_windows_lists_the_clipped_windows():
    load = PeriodicLoad("l", 10, 3, 5)
    assert load.windows(0, 30) == [(5, 8), (15, 18), (25, 28)]
    assert load.windows(6, 26) == [(6, 8), (15, 18), (25, 26)]


@pytest.mark.parametrize("kwargs,field", [({"period": 10 * US, "execution": 10 * US}, "execution"),
                                          ({"period": 0, "execution": 1 * US}, "period"),
                                          ({"period": 10 * US, "execution": -1}, "execution")])
def test_bad_load_parameters_name_the_field(kwargs, field):
    k = Kernel(SimEnv(), "n")
    with pytest.raises(BuildError, match=field):
        k.create_periodic_load("isr", **kwargs)


def test_second_load_and_name_clashes_are_build_errors():
    env = SimEnv()
    k = Kernel(env, "n")
    k.create_periodic_load("isr", period=10 * US, execution=1 * US, handler="enc")
    with pytest.raises(BuildError, match="at most one"):
        k.create_periodic_load("isr2", period=10 * US, execution=1 * US)
    with pytest.raises(BuildError, match="unknown handler 'enc'"):
        env.run(1 * US)  # references are checked when the run starts

    k2 = Kernel(SimEnv(), "m")

    def body(job):
        yield job.execute(1)

    k2.create_handler("other", body)
    k2.create_periodic_load("other", period=10 * US, execution=1 * US)
    with pytest.raises(BuildError, match="handler 'other'"):
        k2.validate()
